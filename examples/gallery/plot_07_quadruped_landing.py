"""
A quadruped landing on its toes, its legs' couplings held
==========================================================

dm_control's quadruped (``tests/models/dm_control/quadruped.xml``, committed unchanged)
dropped 0.3 m while rolling, so that one side's toes land first (``tests/models/
quadruped_drop.xml``). Each leg's joints are coupled by a tendon equality, which MuJoCo keeps
softly: by the landings the couplings drift by up to 0.9 m/s, so the
default reference (``equality="pin"``, exact to round-off) refuses them and says so. Here
the impact imposes them (``equality="fasten"``), as MuJoCo imposes them every step.
"""

import matplotlib.pyplot as plt

from carnot.io.rollout_report import format_report
from carnot.plot_rollout import plot_audit
from carnot.rollout import RigidSettings, audit_model

report = audit_model("../../tests/models/quadruped_drop.xml", keyframe="drop", duration=1.0,
                     rigid=RigidSettings(equality="fasten"))  # fmt: skip
print(format_report(report).split("\n\nStep ledger")[0])
print("largest per-step residual of the ledger (J):", report.steps.max_abs_residual)
plot_audit(report)
plt.show()

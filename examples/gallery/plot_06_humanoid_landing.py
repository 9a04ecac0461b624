"""
A humanoid landing: MuJoCo's soft feet against the rigid law
=============================================================

dm_control's humanoid (``tests/models/dm_control/humanoid.xml``, committed unchanged with
its Apache-2.0 licence) dropped from its own pose, tipping forward: ``tests/models/
humanoid_drop.xml`` adds the keyframe. :func:`carnot.rollout.audit_model` runs 1 s of
MuJoCo (200 steps of 5 ms), splits every step's energy exactly and, for each landing, solves
the rigid impact (Newton, e = 0) from the same pre-impact state in MuJoCo's own coordinates,
mass matrix and contact set. Its contacts are frictionless (``condim`` 1), so the rigid
reference only stops the approach; MuJoCo's soft contacts and joint damping take more.
"""

import matplotlib.pyplot as plt

from carnot.io.rollout_report import format_report
from carnot.plot_rollout import plot_audit
from carnot.rollout import RigidSettings, audit_model

report = audit_model("../../tests/models/humanoid_drop.xml", keyframe="drop", duration=1.0,
                     rigid=RigidSettings())  # fmt: skip
print(format_report(report).split("\n\nStep ledger")[0])
print("largest per-step residual of the ledger (J):", report.steps.max_abs_residual)
plot_audit(report)
plt.show()

"""Draw the audit page's real robot, docs/audit-humanoid.png, and print its table: dm_control's
humanoid (tests/models/dm_control/, committed) dropped from its own pose, tipping forward, 1 s
of MuJoCo audited with the default reference (Newton, e = 0), as
``carnot audit tests/models/humanoid_drop.xml --keyframe drop --duration 1 --plot OUT`` does.

Run from the repository root: ``.venv/bin/python docs/audit_figure.py``.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from carnot.io.rollout_report import format_report  # noqa: E402
from carnot.plot_rollout import plot_audit  # noqa: E402
from carnot.rollout import RigidSettings, audit_model  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

report = audit_model(ROOT / "tests" / "models" / "humanoid_drop.xml", keyframe="drop",
                     duration=1.0, rigid=RigidSettings())  # fmt: skip
plot_audit(report, ROOT / "docs" / "audit-humanoid.png")
print(format_report(report))

"""Where a MuJoCo rollout's energy went, impact by impact (``carnot audit``, issue 17).

* :class:`EnergyAudit`: an exact per-step energy audit of a MuJoCo rollout, fed step by step
  from the user's own loop (``audit.observe()`` after each ``mj_step``), with the impact
  episodes of each contact pair and carnot's rigid reference for each;
* :func:`audit_model` runs the rollout itself from an MJCF file (and a keyframe);
  :func:`audit_recording` replays a recorded one (``qpos``/``qvel`` in an ``.npz`` file).

Everything here needs the optional extra ``carnot[mujoco]``.
"""

from carnot.rollout.audit import AuditReport, EnergyAudit, Episode, RigidSettings, StepLedger
from carnot.rollout.run import audit_model, audit_recording, load_recording

__all__ = [
    "AuditReport",
    "EnergyAudit",
    "Episode",
    "RigidSettings",
    "StepLedger",
    "audit_model",
    "audit_recording",
    "load_recording",
]

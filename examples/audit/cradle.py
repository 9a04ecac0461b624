"""Newton's cradle in MuJoCo against carnot's three multiple-impact laws.

MuJoCo runs ``newtons_cradle.xml`` (ball 1 strikes four balls at rest, soft contacts); carnot
audits the rollout and, from the state just before the first impact, solves the rigid impact
of all four contacts (e = 1) with each law: simultaneous (generalized Newton), sequential
(pairwise, Newton's textbook answer: only the last ball leaves) and dispersion (Liu, Zhao and
Brogliato 2008). Prints the velocities after, side by side.

    .venv/bin/python examples/audit/cradle.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from carnot.rollout import RigidSettings, audit_model

MODEL = Path(__file__).parent / "newtons_cradle.xml"


def main() -> None:
    rows = {}
    for law in ("simultaneous", "sequential", "dispersion"):
        report = audit_model(MODEL, keyframe="strike", duration=0.03,
                             rigid=RigidSettings(restitution=1.0, multiple_impact=law))  # fmt: skip
        first = report.episodes[0]
        rows[law] = first.rigid.system.velocity_after
        mujoco_after = report.episodes[-1].qvel_after
    steps = report.steps
    print(
        f"MuJoCo: {len(report.episodes)} episodes, energy {steps.energy[0]:.4f} J -> "
        f"{steps.energy[-1]:.4f} J, max |residual| of a step {steps.max_abs_residual:.1e} J"
    )
    for e in report.episodes:
        print(
            f"  {'/'.join(e.pair)}: {e.start * 1e3:.2f}-{e.end * 1e3:.2f} ms, the pair's "
            f"work {e.contact_work:+.4f} J, e = {e.effective_restitution:.3f}"
        )
    print("velocities after (m/s)    ball1   ball2   ball3   ball4   ball5")
    print("MuJoCo (soft)          " + "".join(f"{v:8.3f}" for v in mujoco_after))
    for law, velocity in rows.items():
        energy = 0.5 * 0.2 * float(np.sum(velocity**2))
        print(f"rigid {law:<17}" + "".join(f"{v:8.3f}" for v in velocity)
              + f"   E'' = {energy:.4f} J")  # fmt: skip


if __name__ == "__main__":
    main()

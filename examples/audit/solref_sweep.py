"""A ball dropped on a plane at several MuJoCo ``solref`` settings: the effective restitution
MuJoCo produces against the rigid law's target e = 0.5, and the energy each impact removes
(``carnot audit``'s Python API inside our own loop). Draws the figure to the path given
(docs/audit-solref.png is this figure), else to ``solref_sweep.png``.

    .venv/bin/python examples/audit/solref_sweep.py docs/audit-solref.png
"""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
from matplotlib.figure import Figure

from carnot.rollout import EnergyAudit, RigidSettings

HERE = Path(__file__).parent
TARGET = 0.5


def first_impact(timeconst: float, damping: float):
    solref = f'solref="{timeconst} {damping}"'  # on both geoms (MuJoCo mixes the two)
    xml = (HERE / "ball_drop.xml").read_text().replace('solref="0.005 0.2"', solref)
    xml = xml.replace('friction="0.3"/>', f'friction="0.3" {solref}/>', 1)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    audit = EnergyAudit(model, data, rigid=RigidSettings(restitution=TARGET))
    for _ in range(600):  # the first bounce, at 0.45 s
        mujoco.mj_step(model, data)
        audit.observe()
    return audit.finish().episodes[0]


def main(out: str) -> None:
    fig = Figure(figsize=(7.0, 4.0), layout="constrained")
    ax = fig.subplots()
    for damping in (0.2, 0.5, 1.0):
        times = [0.005, 0.01, 0.02, 0.05]
        found = [first_impact(t, damping) for t in times]
        ax.plot(times, [e.effective_restitution for e in found], "o-",
                label=f"damping ratio {damping:g}")  # fmt: skip
        for t, e in zip(times, found, strict=True):
            print(
                f"solref = ({t:g}, {damping:g}): e = {e.effective_restitution:.3f}, MuJoCo "
                f"lost {e.energy_lost:.3f} J, rigid E_d = {e.rigid_dissipated:.3f} J"
            )
    ax.axhline(TARGET, color="k", linestyle="--", label=f"rigid law e = {TARGET}")
    ax.set_xscale("log")
    ax.set_xlabel("solref time constant [s]")
    ax.set_ylabel("MuJoCo's effective restitution")
    ax.set_title("Ball drop (h = 1 ms): MuJoCo's soft contact against a rigid e", fontsize=10)
    ax.legend(fontsize=8)
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "solref_sweep.png")

"""The cost of ``carnot audit``'s per-step audit against the MuJoCo rollout alone, for a
10-body scene (10 free spheres and boxes falling onto a plane and onto each other).

Both runs in the same process, from the same state, same number of steps; the audit run
includes every step's split and the episode tracking, and separately the rigid references
(carnot's solve per episode, at the end). Target (issue 17): audit <= 2x the rollout.

    .venv/bin/python benchmarks/bench_audit.py
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from carnot.rollout import EnergyAudit, RigidSettings

SCENE = ['<mujoco><option timestep="0.002" integrator="Euler"/><worldbody>',
         '<geom name="floor" type="plane" size="3 3 .1"/>']  # fmt: skip
for i in range(10):
    x, y, z = 0.25 * (i % 3) - 0.25, 0.25 * (i // 3 % 3) - 0.25, 0.3 + 0.3 * i
    shape = 'type="sphere" size="0.1"' if i % 2 else 'type="box" size="0.08 0.06 0.05"'
    SCENE.append(f'<body name="b{i}" pos="{x} {y} {z}"><freejoint/>'
                 f'<geom name="g{i}" {shape} mass="{0.5 + 0.1 * i}"/></body>')  # fmt: skip
SCENE.append("</worldbody></mujoco>")
STEPS = 1500


def _fresh():
    model = mujoco.MjModel.from_xml_string("".join(SCENE))
    model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)  # in both runs
    data = mujoco.MjData(model)
    data.qvel[0] = 1.0
    return model, data


def rollout() -> float:
    model, data = _fresh()
    start = time.perf_counter()
    for _ in range(STEPS):
        mujoco.mj_step(model, data)
    return time.perf_counter() - start


def audited(rigid: bool) -> tuple[float, float, int, int]:
    model, data = _fresh()
    audit = EnergyAudit(model, data, rigid=RigidSettings(restitution=0.5) if rigid else None)
    start = time.perf_counter()
    for _ in range(STEPS):
        mujoco.mj_step(model, data)
        audit.observe()
    stepped = time.perf_counter() - start
    report = audit.finish()
    total = time.perf_counter() - start
    return stepped, total, len(report.episodes), int(np.max(report.steps.time.size))


def main() -> None:
    best = {"rollout": np.inf, "audit": np.inf, "audit+finish": np.inf, "with rigid": np.inf}
    episodes = 0
    for _ in range(3):
        best["rollout"] = min(best["rollout"], rollout())
        stepped, total, episodes, _ = audited(rigid=False)
        best["audit"] = min(best["audit"], stepped)
        best["audit+finish"] = min(best["audit+finish"], total)
        best["with rigid"] = min(best["with rigid"], audited(rigid=True)[1])
    base = best["rollout"]
    print(f"10 bodies, {STEPS} Euler steps, {episodes} impact episodes (best of 3)")
    for name, seconds in best.items():
        print(f"  {name:<13} {seconds * 1e3:8.1f} ms  {seconds / STEPS * 1e6:7.1f} us/step  "
              f"ratio {seconds / base:5.2f}")  # fmt: skip
    print(f"audit / rollout = {best['audit+finish'] / base:.2f} (target <= 2)")


if __name__ == "__main__":
    main()

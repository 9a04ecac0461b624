"""The cost of ``carnot audit`` against the MuJoCo rollout itself, for a 10-body scene (10
free spheres and boxes falling onto a plane and onto each other: 1500 Euler steps of 2 ms, 25
contacts at rest, about 14 impact episodes).

In the same run: the rollout alone, and the rollout with ``audit.observe()`` after every
step, each timed step by step (``mj_step`` and ``observe`` apart). On a shared machine the
totals carry the other processes' time slices (a few ms each, landing anywhere); the means
per step without the slowest 2% do not, and are the figure to compare (the medians too, but
they leave out the slower steps of impact episodes: a fifth here). The rigid references
(one carnot solve per episode, in ``finish``) are timed too, with the default scope (the
contacts coupled to the episode's pair) and, as the baseline, the whole scene; the total
audit cost is the per-step audit plus the references. Target (issue 17): audit at most 2x
the rollout.

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


def rollout() -> np.ndarray:
    """Seconds of each ``mj_step`` alone."""
    model, data = _fresh()
    times = np.empty(STEPS)
    clock = time.perf_counter
    for k in range(STEPS):
        start = clock()
        mujoco.mj_step(model, data)
        times[k] = clock() - start
    return times


def audited(rigid: RigidSettings | None) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Seconds of each ``mj_step`` and each ``observe``, of ``finish`` (with the rigid
    references when ``rigid`` is given), and the episodes."""
    model, data = _fresh()
    audit = EnergyAudit(model, data, rigid=rigid)
    steps, observes = np.empty(STEPS), np.empty(STEPS)
    clock = time.perf_counter
    for k in range(STEPS):
        start = clock()
        mujoco.mj_step(model, data)
        middle = clock()
        audit.observe()
        steps[k], observes[k] = middle - start, clock() - middle
    start = clock()
    report = audit.finish()
    return steps, observes, clock() - start, len(report.episodes)


def _trimmed_mean(times: np.ndarray) -> float:
    """The mean of all but the slowest 2% (the impacts' slower steps are far more than 2%)."""
    return float(np.mean(np.sort(times)[: int(0.98 * times.size)]))


COUPLED = RigidSettings(restitution=0.5)
SCENE_WIDE = RigidSettings(restitution=0.5, scope="scene")


def main() -> None:
    audited(None)  # the compiled kernel loaded (or compiled) once, as in any session
    alone, with_audit, finish, coupled, scene = [], [], [], [], []
    for _ in range(3):
        alone.append(rollout())
        steps, observes, seconds, episodes = audited(None)
        with_audit.append((steps, observes))
        finish.append(seconds)
        steps, observes, seconds, _ = audited(COUPLED)
        coupled.append((float((steps + observes).sum()), seconds))
        scene.append(audited(SCENE_WIDE)[2])
    rollout_total = min(float(a.sum()) for a in alone)
    audit_total = min(float((s + o).sum()) for s, o in with_audit) + min(finish)
    step_median = float(np.median(np.concatenate(alone)))
    observe_median = float(np.median(np.concatenate([o for _, o in with_audit])))
    step_mean = _trimmed_mean(np.concatenate(alone))
    observe_mean = _trimmed_mean(np.concatenate([o for _, o in with_audit]))
    # the references alone: finish with them less finish without (the final state's energy)
    references = min(s for _, s in coupled) - min(finish)
    references_scene = min(scene) - min(finish)
    print(f"10 bodies, {STEPS} Euler steps, {episodes} impact episodes")
    print(f"  median per step: mj_step {step_median * 1e6:.1f} us, observe "
          f"{observe_median * 1e6:.1f} us -> audit / rollout = "
          f"{(step_median + observe_median) / step_median:.2f} (target <= 2)")  # fmt: skip
    print(f"  mean per step without the slowest 2% (the time slices lost to other processes): "
          f"mj_step {step_mean * 1e6:.1f} us, observe {observe_mean * 1e6:.1f} us -> "
          f"{(step_mean + observe_mean) / step_mean:.2f}")  # fmt: skip
    print(f"  totals (best of 3): rollout {rollout_total * 1e3:.1f} ms, rollout + audit "
          f"{audit_total * 1e3:.1f} ms (finish {min(finish) * 1e3:.1f} ms) -> "
          f"{audit_total / rollout_total:.2f}")  # fmt: skip
    print(f"  the rigid references (best of 3, finish with them less finish without): coupled "
          f"contacts {references * 1e3:.1f} ms ({references / episodes * 1e3:.2f} ms an "
          f"episode), the whole scene {references_scene * 1e3:.0f} ms "
          f"({references_scene / episodes * 1e3:.1f} ms an episode): "
          f"{references_scene / references:.0f}x")  # fmt: skip
    rollout_mean = step_mean * STEPS
    with_references = (step_mean + observe_mean) * STEPS + min(finish) + references
    best = min(steps_observes + seconds for steps_observes, seconds in coupled)
    print(f"  audit with the references against the rollout alone: from the trimmed means "
          f"{with_references / rollout_mean:.2f} (rollout {rollout_mean * 1e3:.1f} ms, per-step "
          f"audit {observe_mean * STEPS * 1e3:.1f} ms, references {references * 1e3:.1f} ms); "
          f"totals (best of 3) {best * 1e3:.1f} ms -> {best / rollout_total:.2f} "
          "(target <= 2)")  # fmt: skip


if __name__ == "__main__":
    main()

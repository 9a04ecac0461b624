"""The cost of ``carnot audit`` against the MuJoCo rollout itself, for a 10-body scene (10
free spheres and boxes falling onto a plane and onto each other: 1500 Euler steps of 2 ms, 25
contacts at rest, 14 impact episodes). Target (issue 17): the audit, its rigid references
included, at most 2x the rollout.

In the same run, in rounds (the best of each kept): the rollout alone; the rollout with
``audit.observe()`` after every step and ``finish()`` without references; the same with the
rigid references (one carnot solve per episode, in ``finish``, of the contacts coupled to the
episode's pair). Each is timed as a whole loop twice: by the wall clock and by this thread's
CPU time (``time.thread_time``), which leaves out the time slices the shared machine gives
to other processes (a loaded 2-core machine inflates wall-clock loops by tens of percent,
anywhere); the ratios compare like with like, and each round's own ratio (its loops ran back
to back) is given too. Apart: ``mj_step`` and ``observe`` per step, each call timed alone,
interleaved (the means without the slowest 2%).

``--against DIR`` runs the same measurement on another checkout's ``DIR/src`` (for example
main's) in alternate rounds, each round a fresh process per tree, so that both see the same
load; ``--rounds N`` (default 5).

    .venv/bin/python benchmarks/bench_audit.py --against /path/to/main
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

SCENE = Path(__file__).resolve().parent.parent / "examples" / "audit" / "ten_bodies.xml"
STEPS = 1500
CLOCKS = (time.perf_counter, time.thread_time)  # wall, this thread's CPU


def _fresh():
    model = mujoco.MjModel.from_xml_path(str(SCENE))
    model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)  # in both runs
    data = mujoco.MjData(model)
    data.qvel[0] = 1.0
    return model, data


def rollout() -> list[float]:
    """Seconds of the loop of ``mj_step`` alone: wall, CPU."""
    model, data = _fresh()
    start = [c() for c in CLOCKS]
    for _ in range(STEPS):
        mujoco.mj_step(model, data)
    return [c() - s for c, s in zip(CLOCKS, start, strict=True)]


def audited(rigid) -> dict[str, list[float] | int]:  # type: ignore[no-untyped-def]
    """Seconds (wall, CPU) of the loop of ``mj_step`` and ``observe``, and of ``finish``
    (with the rigid references when ``rigid`` is given); the episodes."""
    from carnot.rollout import EnergyAudit

    model, data = _fresh()
    audit = EnergyAudit(model, data, rigid=rigid)
    start = [c() for c in CLOCKS]
    for _ in range(STEPS):
        mujoco.mj_step(model, data)
        audit.observe()
    middle = [c() for c in CLOCKS]
    report = audit.finish()
    end = [c() for c in CLOCKS]
    return {"loop": [m - s for m, s in zip(middle, start, strict=True)],
            "finish": [e - m for e, m in zip(end, middle, strict=True)],
            "episodes": len(report.episodes)}  # fmt: skip


def observe_per_step() -> list[float]:
    """The mean wall-clock seconds of one ``mj_step`` and of one ``observe`` (each timed
    alone, interleaved: both see the same load), without the slowest 2% of each."""
    from carnot.rollout import EnergyAudit

    model, data = _fresh()
    audit = EnergyAudit(model, data)
    times = np.empty((2, STEPS))
    clock = time.perf_counter
    for k in range(STEPS):
        start = clock()
        mujoco.mj_step(model, data)
        middle = clock()
        audit.observe()
        times[:, k] = middle - start, clock() - middle
    return [float(np.mean(np.sort(t)[: int(0.98 * STEPS)])) for t in times]


def one_round() -> dict[str, object]:
    """One round: each measurement once, after a warm-up (the compiled kernels loaded)."""
    from carnot.rollout import RigidSettings

    rigid = RigidSettings(restitution=0.5)
    audited(rigid)
    plain, with_rigid = audited(None), audited(rigid)
    return {"rollout": rollout(), "loop": plain["loop"], "finish": plain["finish"],
            "loop_rigid": with_rigid["loop"], "finish_rigid": with_rigid["finish"],
            "observe": observe_per_step(), "episodes": plain["episodes"]}  # fmt: skip


def _round_in(tree: Path) -> dict[str, object]:
    """One round in a fresh process importing ``tree/src``'s carnot."""
    env = dict(os.environ, PYTHONPATH=str(tree / "src"))
    out = subprocess.run([sys.executable, __file__, "--one-round"], env=env, check=True,
                         capture_output=True, text=True).stdout  # fmt: skip
    return json.loads(out.splitlines()[-1])


def summary(name: str, rounds: list[dict]) -> None:  # type: ignore[type-arg]
    """Print the best of the rounds of each measurement, and the ratios: of the best times,
    and the best and median of each round's own (its loops ran back to back)."""

    def best(key: str, clock: int) -> float:
        return min(float(r[key][clock]) for r in rounds)

    def total(r: dict, clock: int) -> float:  # type: ignore[type-arg]
        return float(r["loop_rigid"][clock] + r["finish_rigid"][clock])

    print(f"{name}: {rounds[0]['episodes']} episodes, best of {len(rounds)} rounds")
    for clock, label in enumerate(("wall clock", "CPU time")):
        roll = best("rollout", clock)
        loop, finish = best("loop", clock), best("finish", clock)
        references = best("finish_rigid", clock) - finish
        everything = min(total(r, clock) for r in rounds)
        each = [total(r, clock) / float(r["rollout"][clock]) for r in rounds]
        print(f"  {label:10s}: rollout {roll * 1e3:5.1f} ms | rollout + observe "
              f"{loop * 1e3:5.1f} ms ({loop / roll:.2f}x) | finish {finish * 1e3:3.1f} ms | "
              f"references {references * 1e3:4.1f} ms ({references / roll:.2f}x) | all "
              f"{everything * 1e3:5.1f} ms -> {everything / roll:.2f}x; each round's own: "
              f"best {min(each):.2f}x, median {float(np.median(each)):.2f}x "
              "(target <= 2)")  # fmt: skip
    step, observe = (min(float(r["observe"][i]) for r in rounds) for i in (0, 1))
    print(f"  per step (wall clock, interleaved, mean without the slowest 2%): mj_step "
          f"{step * 1e6:.1f} us, observe {observe * 1e6:.1f} us -> "
          f"{(step + observe) / step:.2f}x")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, help="another checkout to measure alike")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--one-round", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one_round:
        print(json.dumps(one_round()))
        return
    here = Path(__file__).resolve().parent.parent
    trees = {"this tree": here}
    if args.against is not None:
        trees["against " + str(args.against)] = args.against.resolve()
    print(f"10 bodies, {STEPS} Euler steps; load {os.getloadavg()[0]:.2f} on "
          f"{os.cpu_count()} CPUs")  # fmt: skip
    rounds: dict[str, list[dict]] = {name: [] for name in trees}  # type: ignore[type-arg]
    for _ in range(args.rounds):
        for name, tree in trees.items():
            rounds[name].append(_round_in(tree))
    for name in trees:
        summary(name, rounds[name])
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()

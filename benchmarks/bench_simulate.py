"""Events per second of ``carnot simulate`` (issue 16's target: >= 10^4 in a bouncing-die or
bouncing-ball scene), against baselines measured in the same run.

Scenes (each run to a fixed number of impacts, best of ``--repeat`` runs):

* ``ball``: an elastic, frictionless ball bouncing on a floor (e = 1: no accumulation, every
  flight a closed-form root of a quadratic);
* ``die``: an elastic, frictionless cube tumbling on a floor (rotation in closed form, the
  next impact by sampled gaps refined by Brent's method);
* ``rocking``: Housner's block pivoting between impacts (the contact phases integrated).

Baselines: a hand-written NumPy loop for the same bouncing ball (closed-form flight time,
Newton's rule, the two energy routes: the floor of an event loop in Python), and
``carnot.solve_impact`` alone on that ball's impact (the solver's share of an event).

And a sweep of simulations (``carnot sweep`` on the rocking block's overturning map): one
worker against two worker processes.

Run: ``.venv/bin/python benchmarks/bench_simulate.py [--events N] [--repeat R] [--runs K]``.
"""

from __future__ import annotations

import argparse
import math
import platform
import time

import numpy as np
from timing import best_of

import carnot
from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.simulate import parse_simulation, run

G = 9.81
FLOOR = {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}}


def ball_scene(events: int) -> dict:
    t1 = math.sqrt(2 * 0.5 / G)
    return {"format": 1,
            "simulation": {"duration": t1 * (2 * events - 1) + 1e-3, "max_events": events + 5},
            "bodies": {"ball": {"mass": 0.1, "shape": "sphere", "radius": 0.05,
                                "position": [0.0, 0.55, 0.0]}, "floor": FLOOR},
            "pairs": [{"a": "ball", "b": "floor", "restitution": 1.0}]}  # fmt: skip


def die_scene(duration: float) -> dict:
    return {"format": 1, "simulation": {"duration": duration, "max_events": 10**6},
            "bodies": {"die": {"mass": 0.02, "shape": "box", "size": [0.02, 0.02, 0.02],
                               "position": [0.0, 0.3, 0.0], "velocity": [0.0, 0.0, 0.0],
                               "angular_velocity": [0.0, 0.0, 7.0]}, "floor": FLOOR},
            "pairs": [{"a": "die", "b": "floor", "restitution": 1.0}]}  # fmt: skip


def rocking_scene(duration: float) -> dict:
    b, h, th = 0.1, 0.5, 0.1
    c, s = math.cos(th), math.sin(th)
    return {"format": 1, "simulation": {"duration": duration},
            "bodies": {"block": {"mass": 1.0, "shape": "convex",
                                 "vertices": [[b, -h, 0], [b, h, 0], [-b, h, 0], [-b, -h, 0]],
                                 "position": [c * b - s * h, s * b + c * h, 0.0],
                                 "orientation": [math.cos(th / 2), 0, 0, math.sin(th / 2)]},
                       "ground": FLOOR},
            "pairs": [{"a": "block", "b": "ground", "restitution": 0.0, "friction": 2.0,
                       "tangential": "stick"}]}  # fmt: skip


def baseline_ball(events: int) -> int:
    """The same elastic ball by hand: flight time 2 v / g, Newton's rule, E_d two ways."""
    m, e, h = 0.1, 1.0, 0.5
    v = math.sqrt(2 * G * h)
    t = math.sqrt(2 * h / G)
    lost = 0.0
    normal = np.array([0.0, 1.0, 0.0])
    for _ in range(events):
        w_before = -v * normal
        w_after = -e * (w_before @ normal) * normal
        impulse = m * (w_after - w_before)
        direct = 0.5 * m * (w_before @ w_before - w_after @ w_after)
        theorem = -0.5 * impulse @ (w_before + w_after)
        lost += direct + 0 * theorem
        v = float(w_after @ normal)
        t += 2 * v / G
    return events


def sweep_of_simulations(runs: int) -> list[tuple[str, int, float]]:
    """``carnot sweep`` over the overturning map's amplitudes: one worker (the baseline) and
    two worker processes (their start included), one run per chunk."""
    import tempfile
    from pathlib import Path

    from carnot.io.scenario import read_scenario_data
    from carnot.sweep import make_plan, prepare_sweep, run_sweep

    example = Path(__file__).resolve().parent.parent / "examples" / "simulate" / \
        "rocking_overturning_map.toml"  # fmt: skip
    plan = make_plan(vary=[f"simulation.ground_pulse.amplitude=1.5:6:{runs}"])
    sweep = prepare_sweep(read_scenario_data(example), plan, str(example), ["overturned"])
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for workers in (1, 2):
            start = time.perf_counter()
            report = run_sweep(sweep, Path(tmp) / f"w{workers}.parquet", workers=workers,
                               chunk_size=1)  # fmt: skip
            out.append((f"{report.runner}", runs, time.perf_counter() - start))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--events", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--runs", type=int, default=8, help="simulations in the sweep")
    args = parser.parse_args()
    n = args.events
    print(f"carnot {carnot.__version__}, Python {platform.python_version()}, "
          f"NumPy {np.__version__}, {platform.machine()}")  # fmt: skip
    rows: list[tuple[str, int, float]] = []

    base = best_of(lambda: baseline_ball(n), args.repeat)
    rows.append(("baseline: hand-written NumPy bouncing ball", n, base))

    ball = RigidBody(name="ball", mass=0.1, inertia_com=np.eye(3) * 1e-4,
                     velocity_com=[0.0, -3.13, 0.0], position_com=[0, 0.05, 0])  # fmt: skip

    def solver_only() -> None:
        for _ in range(n):
            b = ball.with_motion([0.0, -3.13, 0.0], [0.0, 0.0, 0.0])
            solve_impact(ImpactProblem(bodies={"ball": b, "floor": FixedBody(name="floor")},
                                       contacts=[PointContact(a="ball", b="floor",
                                                              point=[0, 0, 0],
                                                              normal=[0, 1.0, 0],
                                                              restitution=1.0)]))

    rows.append(("baseline: solve_impact alone, same impact (built each time)", n,
                 best_of(solver_only, args.repeat)))  # fmt: skip

    sim = parse_simulation(ball_scene(n))
    count = len(run(sim).events)
    rows.append(("carnot simulate: elastic ball", count, best_of(lambda: run(sim),
                                                                 args.repeat)))  # fmt: skip
    # the same run with the body rebuilt and validated at every impact (before the oriented
    # template of simulate.impacts._oriented): the in-run baseline of that change
    from carnot.simulate import impacts

    cached = impacts._oriented

    def rebuilt(body, orientation):  # type: ignore[no-untyped-def]
        return cached.__wrapped__(body, orientation)

    impacts._oriented = rebuilt  # type: ignore[assignment]
    try:
        rows.append(("carnot simulate: elastic ball, body rebuilt at each impact (before)",
                     count, best_of(lambda: run(sim), args.repeat)))  # fmt: skip
    finally:
        impacts._oriented = cached
    die = parse_simulation(die_scene(20.0))
    count = len(run(die).events)
    rows.append(("carnot simulate: elastic tumbling die", count,
                 best_of(lambda: run(die), args.repeat)))  # fmt: skip
    rock = parse_simulation(rocking_scene(3.0))
    start = time.perf_counter()
    count = len(run(rock).events)
    rows.append(("carnot simulate: Housner's rocking block (contact phases)", count,
                 time.perf_counter() - start))  # fmt: skip

    sweep_rows = sweep_of_simulations(args.runs)
    print("\n| scene | events | seconds | events/s | / baseline |\n| --- | ---: | ---: | ---: "
          "| ---: |")  # fmt: skip
    base_rate = n / base
    for name, events, seconds in rows:
        rate = events / seconds
        print(f"| {name} | {events} | {seconds:.3f} | {rate:,.0f} | {rate / base_rate:.3f}x |")
    ball_rate = rows[2][1] / rows[2][2]
    per_event = 1e6 / ball_rate
    solver = 1e6 * rows[1][2] / rows[1][1]
    print(f"\nelastic ball: {per_event:.0f} us per event, of which solve_impact alone (building "
          f"and validating its problem included) {solver:.0f} us; simulate's own share (event "
          f"location, flight, states, Zeno test, the problem's bodies) {per_event - solver:.0f}"
          " us")  # fmt: skip
    target = 1e4
    print("\n| sweep of simulations (rocking block, one-sine pulses) | runs | seconds | runs/s "
          "| / one worker |\n| --- | ---: | ---: | ---: | ---: |")  # fmt: skip
    for name, runs, seconds in sweep_rows:
        print(f"| {name} | {runs} | {seconds:.2f} | {runs / seconds:.2f} | "
              f"{sweep_rows[0][2] / seconds:.2f}x |")  # fmt: skip
    print(f"\ntarget >= {target:,.0f} events/s (elastic ball): "
          f"{'MET' if ball_rate >= target else 'MISSED'} ({ball_rate:,.0f}/s); "
          f"solve_impact alone allows {rows[1][1] / rows[1][2]:,.0f}/s")


if __name__ == "__main__":
    main()

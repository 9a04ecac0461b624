"""Events per second of ``carnot simulate`` (issue 16's target: >= 10^4 in a bouncing-die
scene), against baselines measured in the same run.

Scenes (each run to a fixed number of impacts or a fixed duration, best of ``--repeat`` runs):

* ``ball``: an elastic, frictionless ball bouncing on a floor (e = 1: no accumulation, every
  flight a closed-form root of a quadratic);
* ``die``: an elastic, frictionless cube spinning about a horizontal edge axis and bouncing on
  a floor: every impact strikes the two corners of an edge at once (the law of several
  contacts, carnot's general route);
* ``die3d``: the same cube tumbling about a skew axis: one corner at a time (the short path of
  ``carnot.single``);
* ``rocking``: Housner's block pivoting between impacts (the contact phases integrated).

Each scene runs three ways in the same run: as ``carnot simulate`` runs it (the lean event
loop, ``carnot.simulate.lean``, takes flights and single-point impacts of one body on planes;
every impact's full result is built when first read); the same with every impact's result
read (``every impact's result built``); the die in 3D also by the two routes of the CLI after
it has read the file (``the events table (CLI)``, ``--json text (CLI)``: the run, every
result, the table or the section 8 JSON text; interpreter start and printing left out); and by
the general loop alone (``general loop only (before)``: ``lean.LEAN = False``, every impact a
``carnot.ImpactProblem`` through ``carnot.solve_impact``, the same events to the last bit:
``tests/test_simulate_lean.py``). The dice also run with the corner search the closed form
replaced (``sampled corner gaps (before that)``: ``events.CLOSED_FORM_CORNERS = False``, gaps
sampled 0.05 rad apart, refined by brentq).

Baselines: a hand-written NumPy loop for the same bouncing ball (closed-form flight time,
Newton's rule, the two energy routes: the floor of an event loop in Python),
``carnot.solve_impact`` alone on that ball's impact (its problem built each time), and the
arithmetic of its short path alone (``carnot.single.single_floats``, which the lean loop calls).

``--stages`` prints where an event's time goes (CPU microseconds per event by stage, the
stages timed by wrappers, so a little slower than a plain run). ``--against REV`` (may be
given several times) times the ball and dice, and the die in 3D with every result built and
by the CLI's two routes, with the package as it was at git revision ``REV`` (exported to a
temporary folder) and with this tree, each in its own process, alternating, by wall clock and
by CPU time (``time.process_time``: on a shared machine wall time swings with the load), best
of ``--rounds``.

And a sweep of simulations (``carnot sweep`` on the rocking block's overturning map): one
worker against two worker processes.

Run: ``.venv/bin/python benchmarks/bench_simulate.py [--events N] [--repeat R] [--runs K]
[--stages] [--against REV ...] [--rounds N]``.
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


def die3d_scene(duration: float) -> dict:
    """The die of :func:`die_scene` tumbling about a skew axis: one corner at a time."""
    scene = die_scene(duration)
    scene["bodies"]["die"]["angular_velocity"] = [3.0, -2.0, 7.0]
    return scene


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


def with_results(sim: object) -> int:
    """A run with every impact's full result built (:class:`carnot.ImpactResult`: what
    ``--json`` and the events table read; the lean loop builds it when first read)."""
    res = run(sim)  # type: ignore[arg-type]
    return sum(ev.impact.result is not None for ev in res.events if ev.impact is not None)


def cli_route(sim: object, as_json: bool) -> int:
    """What ``carnot simulate FILE`` (``as_json``: ``--json``) does after reading the file
    (:func:`carnot.simulate.command.run_command`, interpreter start and printing left out):
    the run, then the events table or the section 8 JSON text; its length."""
    from carnot.simulate.output import format_table, to_json

    res = run(sim)  # type: ignore[arg-type]
    return len(to_json(res) if as_json else format_table(res))


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
    parser.add_argument("--stages", action="store_true", help="where an event's time goes")
    parser.add_argument("--against", metavar="REV", action="append",
                        help="also time the package at REV (may be given several times)")
    parser.add_argument("--rounds", type=int, default=3, help="alternating rounds of --against")
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
    # (imported here: --against's probe imports this file into older trees, which lack it)
    from carnot.single import REST, UNIT_INERTIA, single_floats

    j = ball.float_state[1]

    def arithmetic_only() -> None:
        for _ in range(n):
            single_floats("frictionless", 0.1, j, (0.0, 0.05, 0.0), (0.0, -3.13, 0.0), REST,
                          1.0, UNIT_INERTIA, (0.0, 0.0, 0.0), REST, REST, 0.0,
                          (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, 0.0)  # fmt: skip

    rows.append(("baseline: its short path's arithmetic alone (single_floats)", n,
                 best_of(arithmetic_only, args.repeat)))  # fmt: skip

    from carnot.simulate import events as sim_events
    from carnot.simulate import lean

    for label, scene in (("elastic ball", ball_scene(n)),
                         ("elastic die, two corners at a time (edge on)", die_scene(100.0)),
                         ("elastic die tumbling in 3D, one corner at a time",
                          die3d_scene(100.0))):  # fmt: skip
        sim = parse_simulation(scene)
        count = len(run(sim).events)
        rows.append((f"carnot simulate: {label}", count,
                     best_of(lambda sim=sim: run(sim), args.repeat)))  # fmt: skip
        rows.append((f"carnot simulate: {label}, every impact's result built", count,
                     best_of(lambda sim=sim: with_results(sim), args.repeat)))  # fmt: skip
        if "3D" in label:
            rows.append((f"carnot simulate: {label}, the events table (CLI)", count,
                         best_of(lambda sim=sim: cli_route(sim, False), args.repeat)))
            rows.append((f"carnot simulate: {label}, --json text (CLI)", count,
                         best_of(lambda sim=sim: cli_route(sim, True), args.repeat)))
        lean.LEAN = False
        try:  # the same events (tests/test_simulate_lean.py), by the general loop alone
            rows.append((f"carnot simulate: {label}, general loop only (before)", count,
                         best_of(lambda sim=sim: run(sim), args.repeat)))  # fmt: skip
            if "die" not in label:
                continue
            sim_events.CLOSED_FORM_CORNERS = False
            # (its own count: the die's motion is chaotic, and the two searches' round-off
            # differ, so the runs part after some tens of impacts)
            before = len(run(sim).events)
            rows.append((f"carnot simulate: {label}, general loop, sampled corner gaps "
                         "(before that)", before,
                         best_of(lambda sim=sim: run(sim), args.repeat)))  # fmt: skip
        finally:
            sim_events.CLOSED_FORM_CORNERS = True
            lean.LEAN = True
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
    ball_rate = rows[3][1] / rows[3][2]  # (the elastic ball, run by the lean loop)
    per_event = 1e6 / ball_rate
    solver = 1e6 * rows[1][2] / rows[1][1]
    arithmetic = 1e6 * rows[2][2] / rows[2][1]
    print(f"\nelastic ball: {per_event:.0f} us per event; solve_impact alone on its impact "
          f"{solver:.0f} us (its problem built and validated each time), of which the short "
          f"path's arithmetic (the lean loop's call) {arithmetic:.0f} us")  # fmt: skip
    target = 1e4
    dice = {name: count / seconds for name, count, seconds in rows if "die" in name
            and "(before" not in name and "built" not in name and "CLI" not in name}
    print("\n| sweep of simulations (rocking block, one-sine pulses) | runs | seconds | runs/s "
          "| / one worker |\n| --- | ---: | ---: | ---: | ---: |")  # fmt: skip
    for name, runs, seconds in sweep_rows:
        print(f"| {name} | {runs} | {seconds:.2f} | {runs / seconds:.2f} | "
              f"{sweep_rows[0][2] / seconds:.2f}x |")  # fmt: skip
    best_die = max(dice, key=dice.__getitem__)
    print(f"\ntarget >= {target:,.0f} events/s (a bouncing die): "
          f"{'MET' if dice[best_die] >= target else 'MISSED'} ({dice[best_die]:,.0f}/s, "
          f"{best_die.removeprefix('carnot simulate: ')}); the elastic ball {ball_rate:,.0f}/s; "
          f"solve_impact alone allows {rows[1][1] / rows[1][2]:,.0f}/s, its arithmetic "
          f"{rows[2][1] / rows[2][2]:,.0f}/s")  # fmt: skip
    if args.stages:
        for name, scene in (("ball", ball_scene(n)), ("die", die_scene(100.0)),
                            ("die3d", die3d_scene(100.0))):  # fmt: skip
            stages(name, parse_simulation(scene))
    if args.against:
        against(args.against, args.rounds)


#: The stages of an event timed by :func:`stages`: (module, function) as the loops call them
#: (the general loop's, and the lean loop's: ``lean.*``).
STAGES = (("loop", "solve_at"), ("impacts", "solve_impact"), ("impacts", "geometry"),
          ("impacts", "_rigid_body"), ("impacts", "_contact"), ("impacts", "ImpactProblem"),
          ("loop", "gaps_and_speeds"), ("loop", "next_contact"), ("corners", "first_corner_impact"),
          ("corners", "corner_kinematics"), ("loop", "Flight"), ("loop", "_zeno"),
          ("loop", "_rocking"), ("loop", "trigger_levels"), ("loop", "_unsettled"),
          ("lean", "factored_floats"), ("lean", "flight_floats"), ("lean", "bounce"),
          ("lean", "on_plane"), ("lean", "sphere_gap_speed"), ("lean", "sphere_quadratic"),
          ("lean", "quadratic_first_down_root"), ("lean", "Impact"),
          ("motion", "quat_matrix"))  # fmt: skip


def stages(name: str, sim: object) -> None:
    """CPU microseconds per event spent in each stage of :data:`STAGES`, each stage's time
    including the stages it calls (``loop.solve_at`` holds ``impacts.solve_impact``, ...), and
    the rest of the loops' own work: the time outside every stage."""
    import importlib

    spent: dict[str, float] = {}
    depth = [0, 0.0]  # timed stages open now, and the time of the outermost ones
    saved = []
    for module_name, fn_name in STAGES:
        module = importlib.import_module(f"carnot.simulate.{module_name}")
        fn = getattr(module, fn_name)
        saved.append((module, fn_name, fn))

        def timed_fn(*a, _fn=fn, _key=f"{module_name}.{fn_name}", **k):  # type: ignore[no-untyped-def]
            start = time.process_time()
            depth[0] += 1
            try:
                return _fn(*a, **k)
            finally:
                depth[0] -= 1
                took = time.process_time() - start
                spent[_key] = spent.get(_key, 0.0) + took
                if depth[0] == 0:
                    depth[1] += took

        setattr(module, fn_name, timed_fn)
    try:
        run(sim)  # type: ignore[arg-type]
        spent.clear()
        depth[1] = 0.0
        start = time.process_time()
        count = len(run(sim).events)  # type: ignore[arg-type]
        total = time.process_time() - start
    finally:
        for module, fn_name, fn in saved:
            setattr(module, fn_name, fn)
    print(f"\n{name}: {count} events, {1e6 * total / count:.0f} us of CPU per event (timed "
          "stages), of which:")
    for key, value in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"  {key:<28} {1e6 * value / count:7.1f} us")
    print(f"  {'the loops themselves (the rest)':<28} {1e6 * (total - depth[1]) / count:7.1f} us")


_PROBE = """
import sys, time
sys.path.insert(0, sys.argv[1])
sys.path.insert(1, sys.argv[2])
import carnot
assert carnot.__file__.startswith(sys.argv[1])
from bench_simulate import ball_scene, die_scene, die3d_scene
from carnot.simulate import parse_simulation, run
from carnot.simulate.output import format_table, to_json

def built(sim):
    for ev in run(sim).events:
        if ev.impact is not None:
            ev.impact.result

out = []
for k, scene in enumerate((ball_scene(2000), die_scene(100.0), die3d_scene(100.0))):
    sim = parse_simulation(scene)
    count = len(run(sim).events)
    routes = [lambda: run(sim)]
    if k == 2:
        routes += [lambda: built(sim), lambda: format_table(run(sim)), lambda: to_json(run(sim))]
    for route in routes:
        wall = cpu = float("inf")
        for _ in range(3):
            start, start_cpu = time.perf_counter(), time.process_time()
            route()
            cpu = min(cpu, time.process_time() - start_cpu)
            wall = min(wall, time.perf_counter() - start)
        out.append(f"{count} {wall} {cpu}")
print(" ".join(out))
"""

#: What the probe times, in its order.
PROBED = ("elastic ball", "elastic die, edge on", "elastic die, 3D",
          "die in 3D, every result built", "die in 3D, the events table (CLI)",
          "die in 3D, --json text (CLI)")  # fmt: skip


def against(revisions: list[str], rounds: int) -> None:
    """Events per second of the ball and the dice (the die in 3D also with every result
    built, and by the CLI's two routes) with this tree and with each of ``revisions``, each
    in its own process, alternating (module docstring): wall clock and CPU time, the best of
    ``rounds`` rounds of three runs."""
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    here = Path(__file__).resolve().parent
    with tempfile.TemporaryDirectory() as tmp:
        trees = {}
        for revision in revisions:
            archive = subprocess.run(["git", "-C", str(here.parent), "archive", revision,
                                      "src"], check=True, capture_output=True).stdout
            (Path(tmp) / revision).mkdir()
            subprocess.run(["tar", "-x", "-C", str(Path(tmp) / revision)], input=archive,
                           check=True)  # fmt: skip
            trees[revision] = str(Path(tmp) / revision / "src")
        trees["now"] = str(here.parent / "src")
        best: dict[str, list[tuple[int, float, float]]] = {}
        for _ in range(rounds):
            for name, src in trees.items():
                out = subprocess.run([sys.executable, "-c", _PROBE, src, str(here)], check=True,
                                     capture_output=True, text=True).stdout.split()  # fmt: skip
                runs = [(int(out[k]), float(out[k + 1]), float(out[k + 2]))
                        for k in range(0, len(out), 3)]  # fmt: skip
                best[name] = [(a[0], min(a[1], b[1]), min(a[2], b[2])) for a, b in
                              zip(best.get(name, runs), runs, strict=True)]  # fmt: skip
    for clock, at in (("wall clock", 1), ("CPU time", 2)):
        print(f"\n--against {', '.join(revisions)}: events per second ({clock}), best of "
              f"{rounds} alternating rounds\n| scene | " + " | ".join(trees) + " | "
              + " | ".join(f"now / {r}" for r in revisions) + " |\n| --- |"
              + " ---: |" * (len(trees) + len(revisions)))  # fmt: skip
        for k, scene in enumerate(PROBED):
            rates = {name: best[name][k][0] / best[name][k][at] for name in trees}
            print(f"| {scene} | " + " | ".join(f"{rate:,.0f}" for rate in rates.values())
                  + " | " + " | ".join(f"{rates['now'] / rates[r]:.2f}x" for r in revisions)
                  + " |")  # fmt: skip


if __name__ == "__main__":
    main()

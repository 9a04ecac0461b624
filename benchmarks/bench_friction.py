"""Latency of one 3D frictional point impact whose slip direction turns (issue #4, item 6).

The headline case is a tumbling box (2 kg, 0.4 x 0.2 x 0.1 m) landing on a corner on a fixed
floor, mu = 0.3, e = 0.5: its slip direction turns by about 84 degrees during the impact, so
the impulse-space integration goes through the compiled DOP853 of laws/slip3d.py (Numba).
Measured in one run, each as the median of ``--repeat`` calls (default 300) after a warm-up
(which also loads or compiles the Numba code: that time is reported apart), so that the ratios
hold on a noisy machine:

* ``carnot.solve_impact`` on the prebuilt problem, under Newton's, Poisson's and Stronge's
  hypotheses (target: median <= 1 ms each);
* ``integrate_impact(K, w', ...)`` alone, with ``K`` and ``w'`` taken from the solved
  process: the integration without the solver's assembly and result building;
* ``slip3d.slip_phase`` alone on the box's compression phase: the compiled integrator;
* baselines: the same box with mu = 0 (frictionless Newton, through ``solve_impact``; the
  ratios are to this one) and a planar frictional impact (a rod at 40 degrees, Stronge,
  slip-reversal) through the exact piecewise-linear route.

Also printed: the integrator work per impact (``slip_phase`` calls, steps, right-hand-side
evaluations), counted in a separate, untimed pass, and Numba's one-time costs, each in a new
process: importing Numba and the first call with the compiled code cached on disk (the usual
case), and with an empty cache (``NUMBA_CACHE_DIR`` set to a new folder: the compilation).
``--no-numba`` runs the whole table with ``import numba`` failing: the plain-Python fallback.
``--profile`` prints a cProfile of the headline Stronge case as well.

Run: ``make bench`` or ``.venv/bin/python benchmarks/bench_friction.py [--repeat N]
[--no-numba] [--profile]``.
"""

from __future__ import annotations

import argparse
import cProfile
import functools
import json
import math
import os
import platform
import pstats
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import scipy
from timing import summary, timed

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.laws.friction import integrate_impact
from carnot.model import inertia

TARGET = 1e-3  # s, the median of one 3D frictional impact through the Python API
LAWS = ("newton", "poisson", "stronge")

BOX_ORIENTATION = [
    [0.76975113132, -0.537760653222, -0.343942837805],
    [0.280166499593, 0.768743731054, -0.574925915637],
    [0.573576436351, 0.346188613059, 0.742403876506],
]
ROD_AXIS = [math.cos(math.radians(40.0)), 0.0, math.sin(math.radians(40.0))]
FIRST_CALL = """
import sys, time, json
import numpy as np
start = time.perf_counter()
from carnot.laws import slip3d
imported = time.perf_counter()
slip3d.slip_phase(1.0, 0.3, -0.2, 2.0, 0.4, 3.0, 0.3, -1.0, 0.5, 0.3, 0.857, 0.514, 0, 0.0,
                  1e-9, 1.0, 1e-12, np.inf, np.empty((0, 6)))
called = time.perf_counter()
print(json.dumps([imported - start, called - imported]))
"""


def box(law: str, friction: float) -> ImpactProblem:
    """The tumbling box landing on its corner at the origin."""
    body = RigidBody(name="box", mass=2.0,
                     inertia_com=inertia.box(2.0, [0.4, 0.2, 0.1],
                                                    orientation=BOX_ORIENTATION),
                     position_com=[0.082977019052, 0.104161377242, 0.186454342401],
                     velocity_com=[0.3, -0.2, -2.0], angular_velocity=[1.0, 2.0, -1.5])  # fmt: skip
    contact = PointContact(a="box", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                           restitution=0.5, friction=friction, law=law)  # fmt: skip
    return ImpactProblem(bodies={"box": body, "floor": FixedBody(name="floor")},
                         contacts=[contact])  # fmt: skip


def rod() -> ImpactProblem:
    """A planar frictional impact: a slender rod at 40 degrees landing on its end."""
    axis = np.array(ROD_AXIS)
    body = RigidBody(name="rod", mass=1.0, inertia_com=inertia.rod(1.0, 1.0, 0.01, axis),
                     position_com=0.5 * axis, velocity_com=[0.3, 0.0, -1.0])  # fmt: skip
    contact = PointContact(a="rod", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                           restitution=0.6, friction=0.2, law="stronge")  # fmt: skip
    return ImpactProblem(bodies={"rod": body, "floor": FixedBody(name="floor")},
                         contacts=[contact])  # fmt: skip


def turn_degrees(problem: ImpactProblem) -> tuple[str, float]:
    contact = solve_impact(problem).contacts[0]
    phases = contact.process.phases if contact.process is not None else ()
    return contact.regime, math.degrees(sum(ph.turn for ph in phases))


@contextmanager
def counting_slip_phase() -> Iterator[dict[str, int]]:
    """Count the ``slip3d.slip_phase`` calls of laws/friction.py, their steps and RHS
    evaluations (friction.py looks the function up on the module at each call: patch it
    there)."""
    from carnot.laws import slip3d

    counts = {"calls": 0, "steps": 0, "nfev": 0}
    original = slip3d.slip_phase

    def counted(*args: Any) -> Any:
        out = original(*args)
        counts["calls"] += 1
        counts["steps"] += out[14]
        counts["nfev"] += out[15]
        return out

    slip3d.slip_phase = counted
    try:
        yield counts
    finally:
        slip3d.slip_phase = original


def first_call_seconds(env: dict[str, str]) -> tuple[float, float]:
    """In a new process: seconds to import slip3d (and Numba), then of its first call."""
    done = subprocess.run([sys.executable, "-c", FIRST_CALL], capture_output=True, text=True,
                          check=True, env={**os.environ, **env})  # fmt: skip
    imported, called = json.loads(done.stdout)
    return imported, called


def duration(seconds: float) -> str:
    return f"{seconds * 1e3:7.2f} ms" if seconds >= 1e-3 else f"{seconds * 1e6:7.1f} us"


def profile(problem: ImpactProblem, lines: int = 15) -> None:
    solve_impact(problem)
    profiler = cProfile.Profile()
    profiler.enable()
    for _ in range(20):
        solve_impact(problem)
    profiler.disable()
    print("\ncProfile of 20 calls of solve_impact, headline box, Stronge (cumulative time):")
    pstats.Stats(profiler).strip_dirs().sort_stats("cumulative").print_stats(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=300, help="timed calls (default 300)")
    parser.add_argument("--no-numba", action="store_true",
                        help="time the plain-Python fallback (import numba fails)")  # fmt: skip
    parser.add_argument("--profile", action="store_true", help="cProfile the Stronge case")
    args = parser.parse_args()
    repeat = max(5, args.repeat)
    if args.no_numba:
        if "carnot.laws.slip3d" in sys.modules:  # pragma: no cover - imported lazily
            raise RuntimeError("slip3d was imported before numba could be blocked")
        sys.modules["numba"] = None  # type: ignore[assignment]  # import numba: ImportError
    from carnot.laws import slip3d

    compiled = hasattr(slip3d.slip_phase, "py_func")
    load_start = os.getloadavg()

    # Numba's one-time costs, each in a new process (before the timings: they load the cache).
    one_time: dict[str, tuple[float, float]] = {}
    if compiled:
        one_time["cached"] = first_call_seconds({})
        with tempfile.TemporaryDirectory() as empty:
            one_time["compile"] = first_call_seconds({"NUMBA_CACHE_DIR": empty})

    # The cases, and checks that they are what the table says.
    problems = {law: box(law, 0.3) for law in LAWS}
    frictionless, planar = box("newton", 0.0), rod()
    processes = {}
    describe: dict[str, str] = {}
    for law, problem in problems.items():
        regime, turn = turn_degrees(problem)
        if turn < 45.0:
            raise RuntimeError(f"the headline box ({law}) should turn its slip direction: {turn}")
        process = solve_impact(problem).contacts[0].process
        assert process is not None
        processes[law] = process
        with counting_slip_phase() as counts:
            again = integrate_impact(process.k, process.w_before, friction=0.3, restitution=0.5,
                                     hypothesis=law)  # fmt: skip
        if not np.allclose(again.impulse, process.impulse, rtol=1e-12, atol=0.0):
            raise RuntimeError(f"integrate_impact disagrees with solve_impact ({law})")
        describe[law] = (f"{regime}, turn {turn:.1f} deg, {counts['calls']} slip_phase calls, "
                         f"{counts['steps']} steps, {counts['nfev']} RHS evaluations")  # fmt: skip
    regime, _ = turn_degrees(planar)
    if regime != "slip-reversal":
        raise RuntimeError(f"the planar rod should slip, stop and reverse: {regime}")
    with counting_slip_phase() as counts:
        solve_impact(planar)
    if counts["calls"]:
        raise RuntimeError("the planar rod should take the exact route, not the integrator")
    describe["rod"] = f"{regime}, exact piecewise-linear route (0 slip_phase calls)"
    describe["frictionless"] = f"{solve_impact(frictionless).contacts[0].regime}"
    # The kernel alone: the box's first phase (slip until maximum compression), in the units
    # friction.py integrates in (|w'| = 1, K_nn = 1).
    process = processes["newton"]
    speed = float(np.linalg.norm(process.w_before))
    k = process.k * (speed / float(process.k[0, 0])) / speed
    w = process.w_before / speed
    rho = math.hypot(w[1], w[2])
    kernel_args = (k[0, 0], k[0, 1], k[0, 2], k[1, 1], k[1, 2], k[2, 2], 0.3, w[0], w[1], w[2],
                   w[1] / rho, w[2] / rho, slip3d.END_COMPRESSION, 0.0, 1e-9, 1.0, 1e-12,
                   math.inf, np.empty((256, 6)))  # fmt: skip
    out = slip3d.slip_phase(*kernel_args)
    describe["kernel"] = f"code {out[0]} (END), {out[14]} steps, {out[15]} RHS evaluations"

    # The timings: the fast cases get 10 times the calls (they cost little).
    rows: list[tuple[str, tuple[float, float], bool]] = [
        ("baseline: box, mu = 0, Newton, solve_impact",
         summary(timed(lambda: solve_impact(frictionless), 10 * repeat, 200)), False),
        ("baseline: planar rod, stronge, solve_impact",
         summary(timed(lambda: solve_impact(planar), 10 * repeat, 200)), False),
    ]  # fmt: skip
    for law in LAWS:
        solve = functools.partial(solve_impact, problems[law])
        rows.append((f"3D box, {law}: solve_impact", summary(timed(solve, repeat, 20)), True))
    for law in LAWS:
        process = processes[law]

        def engine(process: Any = process, law: str = law) -> object:
            return integrate_impact(process.k, process.w_before, friction=0.3,
                                    restitution=0.5, hypothesis=law)  # fmt: skip

        rows.append((f"3D box, {law}: integrate_impact alone",
                     summary(timed(engine, repeat, 20)), False))  # fmt: skip
    kernel_repeat = 10 * repeat if compiled else repeat
    rows.append(("3D box, compression: slip3d.slip_phase alone",
                 summary(timed(lambda: slip3d.slip_phase(*kernel_args), kernel_repeat, 20)),
                 False))  # fmt: skip
    load_end = os.getloadavg()

    route = "Numba " + sys.modules["numba"].__version__ if compiled else "plain Python (no Numba)"
    print(f"{platform.platform()}; python {platform.python_version()}, numpy {np.__version__}, "
          f"scipy {scipy.__version__}; slip3d: {route}; {os.cpu_count()} cpus")  # fmt: skip
    print(f"load average {', '.join(f'{x:.2f}' for x in load_start)} at start, "
          f"{', '.join(f'{x:.2f}' for x in load_end)} at end; median of {repeat} calls "
          f"({10 * repeat} for the baselines) after a warm-up")  # fmt: skip
    print("cases:")
    for law in LAWS:
        print(f"  box, mu 0.3, e 0.5, {law + ':':<8} {describe[law]}")
    print(f"  box, mu 0:                  regime {describe['frictionless']}")
    print(f"  rod, mu 0.2, e 0.6:         {describe['rod']}")
    print(f"  box, compression only:      {describe['kernel']}")
    if one_time:
        print("Numba, once per process (new processes; not in the medians):")
        for key, label in (("cached", "compiled code cached on disk"),
                           ("compile", "empty cache: compilation")):  # fmt: skip
            imported, called = one_time[key]
            print(f"  {label + ':':<31} import {duration(imported).strip()}, first call "
                  f"{duration(called).strip()}")  # fmt: skip
    base = rows[0][1][0]
    print(f"{'one frictional point impact':<46} {'median':>10} {'IQR':>10} {'/ mu = 0':>9} "
          f"{'target':>13}")  # fmt: skip
    for name, (median, iqr), headline in rows:
        verdict = f"<= 1 ms {'PASS' if median <= TARGET else 'MISS'}" if headline else ""
        print(f"{name:<46} {duration(median)} {duration(iqr)} {median / base:>8.2f}x "
              f"{verdict:>13}")  # fmt: skip
    worst = max(median for _, (median, _), headline in rows if headline)
    verdict = "PASS" if worst <= TARGET else "MISS"
    print(f"target (issue #4): median <= 1 ms under each hypothesis: {verdict} "
          f"(slowest {duration(worst).strip()})")  # fmt: skip
    if args.profile:
        profile(problems["stronge"])


if __name__ == "__main__":
    main()

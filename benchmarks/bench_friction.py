"""Latency of one 3D frictional point impact whose slip direction turns (issue #4, item 6).

The headline case is a tumbling box (2 kg, 0.4 x 0.2 x 0.1 m) landing on a corner on a fixed
floor, mu = 0.3, e = 0.5: its slip direction turns by about 84 degrees during the impact, so
the impulse-space integration goes through SciPy's DOP853 (laws/friction.py). Measured in one
run, each as the median of ``--repeat`` calls (default 300) after a warm-up, so that the
ratios hold on a noisy machine:

* ``carnot.solve_impact`` on the prebuilt problem, under Newton's, Poisson's and Stronge's
  hypotheses (target: median <= 1 ms each);
* ``integrate_impact(K, w', ...)`` alone, with ``K`` and ``w'`` taken from the solved
  process: the integration without the solver's assembly and result building;
* baselines: the same box with mu = 0 (frictionless Newton, through ``solve_impact``; the
  ratios are to this one), a planar frictional impact (a rod at 40 degrees, Stronge,
  slip-reversal) through the exact piecewise-linear route, and one ``scipy.integrate.
  solve_ivp`` call (DOP853, rtol 1e-12) on a trivial 4-state linear ODE over [0, 1]: the cost
  floor of one integrator call.

Also printed: the integrator work per impact (``solve_ivp`` calls, steps, right-hand-side
evaluations), counted in a separate, untimed pass by wrapping ``solve_ivp``.
``--profile`` prints a cProfile of the headline Stronge case as well.

Run: ``make bench`` or ``.venv/bin/python benchmarks/bench_friction.py [--repeat N] [--profile]``.
"""

from __future__ import annotations

import argparse
import cProfile
import functools
import math
import os
import platform
import pstats
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import scipy
import scipy.integrate
from scipy.integrate import solve_ivp
from timing import summary, timed

import carnot.inertia
from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.laws.friction import integrate_impact

TARGET = 1e-3  # s, the median of one 3D frictional impact through the Python API
LAWS = ("newton", "poisson", "stronge")

BOX_ORIENTATION = [
    [0.76975113132, -0.537760653222, -0.343942837805],
    [0.280166499593, 0.768743731054, -0.574925915637],
    [0.573576436351, 0.346188613059, 0.742403876506],
]
ROD_AXIS = [math.cos(math.radians(40.0)), 0.0, math.sin(math.radians(40.0))]
ODE_MATRIX = np.array([[0.0, 1.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0],
                       [0.0, 0.0, -0.5, 2.0], [0.0, 0.0, -2.0, -0.5]])  # fmt: skip


def box(law: str, friction: float) -> ImpactProblem:
    """The tumbling box landing on its corner at the origin."""
    body = RigidBody(name="box", mass=2.0,
                     inertia_com=carnot.inertia.box(2.0, [0.4, 0.2, 0.1],
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
    body = RigidBody(name="rod", mass=1.0, inertia_com=carnot.inertia.rod(1.0, 1.0, 0.01, axis),
                     position_com=0.5 * axis, velocity_com=[0.3, 0.0, -1.0])  # fmt: skip
    contact = PointContact(a="rod", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                           restitution=0.6, friction=0.2, law="stronge")  # fmt: skip
    return ImpactProblem(bodies={"rod": body, "floor": FixedBody(name="floor")},
                         contacts=[contact])  # fmt: skip


def trivial_ode() -> Any:
    """One DOP853 call on ``y' = A y`` (4 states, linear) from 0 to 1."""
    return solve_ivp(lambda t, y: ODE_MATRIX @ y, (0.0, 1.0), [1.0, 0.0, 1.0, 0.0],
                     method="DOP853", rtol=1e-12)  # fmt: skip


def turn_degrees(problem: ImpactProblem) -> tuple[str, float]:
    contact = solve_impact(problem).contacts[0]
    phases = contact.process.phases if contact.process is not None else ()
    return contact.regime, math.degrees(sum(ph.turn for ph in phases))


@contextmanager
def counting_solve_ivp() -> Iterator[dict[str, int]]:
    """Count the ``solve_ivp`` calls of laws/friction.py, their steps and RHS evaluations
    (it imports ``scipy.integrate.solve_ivp`` when it integrates, so patch it there)."""
    counts = {"calls": 0, "steps": 0, "nfev": 0}
    original = scipy.integrate.solve_ivp

    def counted(*args: Any, **kwargs: Any) -> Any:
        sol = original(*args, **kwargs)
        counts["calls"] += 1
        counts["steps"] += len(sol.t) - 1
        counts["nfev"] += sol.nfev
        return sol

    scipy.integrate.solve_ivp = counted
    try:
        yield counts
    finally:
        scipy.integrate.solve_ivp = original


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
    parser.add_argument("--profile", action="store_true", help="cProfile the Stronge case")
    args = parser.parse_args()
    repeat = max(5, args.repeat)
    load_start = os.getloadavg()

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
        with counting_solve_ivp() as counts:
            again = integrate_impact(process.k, process.w_before, friction=0.3, restitution=0.5,
                                     hypothesis=law)  # fmt: skip
        if not np.allclose(again.impulse, process.impulse, rtol=1e-12, atol=0.0):
            raise RuntimeError(f"integrate_impact disagrees with solve_impact ({law})")
        describe[law] = (f"{regime}, turn {turn:.1f} deg, {counts['calls']} solve_ivp calls, "
                         f"{counts['steps']} steps, {counts['nfev']} RHS evaluations")  # fmt: skip
    regime, _ = turn_degrees(planar)
    if regime != "slip-reversal":
        raise RuntimeError(f"the planar rod should slip, stop and reverse: {regime}")
    with counting_solve_ivp() as counts:
        solve_impact(planar)
    if counts["calls"]:
        raise RuntimeError("the planar rod should take the exact route, not the integrator")
    describe["rod"] = f"{regime}, exact piecewise-linear route (0 solve_ivp calls)"
    describe["frictionless"] = f"{solve_impact(frictionless).contacts[0].regime}"
    ode = trivial_ode()
    describe["ode"] = f"{len(ode.t) - 1} steps, {ode.nfev} RHS evaluations"

    # The timings: the fast cases get 10 times the calls (they cost little).
    rows: list[tuple[str, tuple[float, float], bool]] = [
        ("baseline: box, mu = 0, Newton, solve_impact",
         summary(timed(lambda: solve_impact(frictionless), 10 * repeat, 200)), False),
        ("baseline: planar rod, stronge, solve_impact",
         summary(timed(lambda: solve_impact(planar), 10 * repeat, 200)), False),
        ("baseline: one solve_ivp, trivial 4-state ODE",
         summary(timed(trivial_ode, 10 * repeat, 200)), False),
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
    load_end = os.getloadavg()

    print(f"{platform.platform()}; python {platform.python_version()}, numpy {np.__version__}, "
          f"scipy {scipy.__version__}; {os.cpu_count()} cpus")  # fmt: skip
    print(f"load average {', '.join(f'{x:.2f}' for x in load_start)} at start, "
          f"{', '.join(f'{x:.2f}' for x in load_end)} at end; median of {repeat} calls "
          f"({10 * repeat} for the baselines) after a warm-up")  # fmt: skip
    print("cases:")
    for law in LAWS:
        print(f"  box, mu 0.3, e 0.5, {law + ':':<8} {describe[law]}")
    print(f"  box, mu 0:                  regime {describe['frictionless']}")
    print(f"  rod, mu 0.2, e 0.6:         {describe['rod']}")
    print(f"  trivial ODE, DOP853:        {describe['ode']}")
    base = rows[0][1][0]
    print(f"{'one frictional point impact':<46} {'median':>10} {'IQR':>10} {'/ mu = 0':>9} "
          f"{'target':>13}")  # fmt: skip
    for name, (median, iqr), headline in rows:
        verdict = f"<= 1 ms {'PASS' if median <= TARGET else 'MISS'}" if headline else ""
        print(f"{name:<46} {duration(median)} {duration(iqr)} {median / base:>8.1f}x "
              f"{verdict:>13}")  # fmt: skip
    worst = max(median for _, (median, _), headline in rows if headline)
    verdict = "PASS" if worst <= TARGET else "MISS"
    print(f"target (issue #4): median <= 1 ms under each hypothesis: {verdict} "
          f"(slowest {duration(worst).strip()})")  # fmt: skip
    if args.profile:
        profile(problems["stronge"])


if __name__ == "__main__":
    main()

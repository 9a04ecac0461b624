"""Latency of one impact with several contacts through the API (issue 14's acceptance: a
4-corner 3D frictional landing via ``carnot.solve_impact`` <= 1 ms).

The case is examples/box_lands_flat.toml: a box (2 kg, 0.4 x 0.3 x 0.2 m) landing flat on its
four corners at 1 m/s, sliding at (0.8, 0.3) m/s and spinning at 0.4 rad/s, e = 0, Coulomb
mu = 1.5 at each corner (12 contact rows): it sticks, statically indeterminate. Timed in one
run, each the median of ``--repeat`` calls after a warm-up, so that the ratios hold on a noisy
machine:

* ``solve_impact`` on the prebuilt problem (assembly, the simultaneous law, the outcome and
  the ledger), and the same landing sliding (mu = 0.2: one nonlinear solve for the 3D slip);
* the law alone on the same ``G`` and ``w'`` (``resolve_simultaneous``);
* baselines: ``numpy.linalg.solve`` on the same 12 x 12 ``G`` (regularized: an equality law's
  cost), and ``solve_impact`` of one frictionless point contact (the single-contact pipeline);
* the frictionless 4-corner landing and the 5-ball cradle under each law, for scale.

Run: ``.venv/bin/python benchmarks/bench_several.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import platform
from dataclasses import replace
from pathlib import Path

import numpy as np
from timing import summary, timed

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.io.scenario import load_scenario
from carnot.laws.multiple import ContactRows, resolve_simultaneous
from carnot.model.free_bodies import assemble

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def single_contact() -> ImpactProblem:
    """A ball on the floor: one frictionless point contact."""
    ball = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3) * 0.004,
                     position_com=[0, 0, 0.1], velocity_com=[0.3, 0.0, -2.0])  # fmt: skip
    return ImpactProblem(bodies={"ball": ball, "floor": FixedBody(name="floor")},
                         contacts=[PointContact(a="ball", b="floor", point=[0, 0, 0],
                                                normal=[0, 0, 1], restitution=0.5)])  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=400)
    args = parser.parse_args()
    box = load_scenario(EXAMPLES / "box_lands_flat.toml")
    sliding = replace(box, contacts=[replace(c, friction=0.2) for c in box.contacts])
    frictionless = replace(box, contacts=[replace(c, friction=0.0) for c in box.contacts])
    cradle = load_scenario(EXAMPLES / "newtons_cradle_5.toml")
    items = list(box.contacts)
    space = assemble(box, items, [c.rows() for c in items]).space
    g = space.delassus(np.arange(space.size))
    w = space.row_velocities(space.u_before)
    rows = [ContactRows(normal=3 * k, tangents=(3 * k + 1, 3 * k + 2), friction=1.5)
            for k in range(4)]  # fmt: skip
    ball = single_contact()

    res = solve_impact(box)
    print(f"python {platform.python_version()}, numpy {np.__version__}")
    print(f"box: regimes {[c.regime for c in res.contacts]}, flags {res.flag_codes()}, "
          f"residual {res.complementarity_residual:.1e} m/s, "
          f"|v''| {np.linalg.norm(res.bodies['box'].velocity_after):.1e} m/s")
    slide = solve_impact(sliding)
    print(f"sliding box: regimes {[c.regime for c in slide.contacts]}, "
          f"flags {slide.flag_codes()}")
    cases = [
        ("baseline: numpy.linalg.solve(G 12x12)", lambda: np.linalg.solve(g + np.eye(12), w)),
        ("baseline: solve_impact, 1 contact", lambda: solve_impact(ball)),
        ("law alone: resolve_simultaneous(G, w')", lambda: resolve_simultaneous(g, w, rows)),
        ("solve_impact: 4 corners 3D Coulomb, sticks", lambda: solve_impact(box)),
        ("solve_impact: 4 corners 3D Coulomb, slides", lambda: solve_impact(sliding)),
        ("solve_impact: 4 corners frictionless", lambda: solve_impact(frictionless)),
        ("solve_impact: 5-ball cradle, simultaneous", lambda: solve_impact(cradle)),
        ("solve_impact: 5-ball cradle, sequential",
         lambda: solve_impact(replace(cradle, multiple_impact="sequential"))),
        ("solve_impact: 5-ball cradle, dispersion",
         lambda: solve_impact(replace(cradle, multiple_impact="dispersion"))),
    ]
    results = []
    for name, fn in cases:
        repeat = max(5, args.repeat // 20) if "dispersion" in name else args.repeat
        median, iqr = summary(timed(fn, repeat, warm_up=3))
        results.append((name, median, iqr))
    base, single = results[0][1], results[1][1]
    print(f"{'case':46s} {'median':>11s} {'IQR':>10s} {'x solve':>8s} {'x 1 contact':>11s}")
    for name, median, iqr in results:
        print(f"{name:46s} {median * 1e6:8.1f} us {iqr * 1e6:7.1f} us {median / base:8.1f} "
              f"{median / single:11.2f}")
    headline = results[3][1]
    verdict = "meets" if headline <= 1e-3 else "misses"
    print(f"4-corner 3D frictional landing via solve_impact: {headline * 1e3:.3f} ms "
          f"({verdict} the 1 ms target)")


if __name__ == "__main__":
    main()

"""Many coupled contacts through ``solve_impact`` and the solvers alone (issue 33's figures).

Each case is timed in this run (best of ``--repeat``), beside the enumeration where it applies
(a cradle of up to 13 balls, one box: 2^12 and 3^4 regimes), and prints the certificate:
solver, Siconos' relative residual (evaluated apart), iterations, uniqueness.

* the N-ball cradle (frictionless, e = 0.5), through ``solve_impact`` and on its contact space
  alone (``G`` tridiagonal, sparse: the solver's own cost), N = 13, 100, 1000;
* towers of boxes landing (4 contacts a box, mu = 0.5, random velocities), 1 to 250 boxes
  (4 to 1000 contacts), and a 4 x 5 brick wall struck by a ball (75 contacts);
* a pile of spheres (mu = 0.4, e = 0.3), 40 and 300 spheres (98 and 693 contacts).

The issue's targets: 1000 coupled frictional contacts certified to 1e-10 in 2 s through
``solve_impact``; up to 50 contacts to 1e-14 in 20 ms; a 1000-ball cradle in 50 ms.
Siconos' own solver on its corpus is in ``benchmarks/siconos_peer.py``.

Run: ``.venv/bin/python benchmarks/bench_many_contacts.py [--repeat N] [--quick]``.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from scenes import cradle, pile, tower, wall  # noqa: E402

from carnot import solve_impact  # noqa: E402
from carnot.laws.multiple import ContactRows  # noqa: E402
from carnot.solvers import SolverOptions, resolve  # noqa: E402


def best(fn: Callable[[], object], repeat: int) -> tuple[float, object]:
    """The shortest of ``repeat`` calls (s) and the last answer."""
    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return min(times), out


def row(label: str, contacts: int, seconds: float, cert: object) -> None:
    c = cert
    print(f"{label:34s} {contacts:5d} {seconds * 1e3:10.2f} ms  {c.solver:9s} "  # type: ignore[attr-defined]
          f"{c.residual:8.1e} {c.iterations:6d}  unique={c.unique} "  # type: ignore[attr-defined]
          f"velocities={c.velocities_unique} converged={c.converged}")  # type: ignore[attr-defined]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="skip the largest cases")
    args = parser.parse_args()
    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}")
    print(f"{'case':34s} {'cont':>5s} {'time':>13s}  {'solver':9s} {'residual':>8s} "
          f"{'iters':>6s}")  # fmt: skip
    rep = args.repeat
    for balls in (13, 100) if args.quick else (13, 100, 1000):
        problem = cradle(balls, e=0.5)
        for solver in ("enumerate", "iterative") if balls <= 13 else ("iterative",):
            t, res = best(lambda p=problem, s=solver: solve_impact(p, solver=s), rep)
            row(f"cradle {balls}, solve_impact, {solver}", balls - 1, t, res.solver)  # type: ignore[attr-defined]
        k = balls - 1
        g = sp.diags([-np.ones(k - 1), 2 * np.ones(k), -np.ones(k - 1)], [-1, 0, 1]).tocsr()
        w = np.zeros(k)
        w[0] = -1.0
        contacts = [ContactRows(normal=i, restitution=0.5) for i in range(k)]
        t, out = best(lambda g=g, w=w, c=contacts: resolve(
            g, w, c, options=SolverOptions(name="iterative")), rep)  # fmt: skip
        row(f"cradle {balls}, contact space alone", k, t, out.certificate)  # type: ignore[attr-defined]
    rng_seed = 0
    for boxes in (1, 3, 12) if args.quick else (1, 3, 12, 50, 250):
        problem = tower(boxes, rng=np.random.default_rng(rng_seed))
        solvers = ("enumerate", "iterative") if boxes == 1 else ("auto",)
        for solver in solvers:
            t, res = best(lambda p=problem, s=solver: solve_impact(p, solver=s),
                          1 if boxes >= 50 else rep)  # fmt: skip
            row(f"tower {boxes}, {solver}", 4 * boxes, t, res.solver)  # type: ignore[attr-defined]
    problem = wall(4, 5)
    t, res = best(lambda: solve_impact(problem), rep)
    row("brick wall 4 x 5 struck by a ball", len(problem.contacts), t, res.solver)  # type: ignore[attr-defined]
    for spheres in (40,) if args.quick else (40, 300):
        problem = pile(spheres)
        t, res = best(lambda p=problem: solve_impact(p), 1 if spheres > 40 else rep)
        row(f"pile of {spheres} spheres", len(problem.contacts), t, res.solver)  # type: ignore[attr-defined]


if __name__ == "__main__":
    main()

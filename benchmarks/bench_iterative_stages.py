"""The iterative solver's later stages (issue 33): where ADMM stalls, the proximal stage, and
on small dense problems the smoothed law; the cases whose figures docs/solvers.md gives.

* the 40 tilted box landings of ``benchmarks/same_answers.py`` ("tilted sticking", mu 1.5,
  and "tilted sliding", mu 0.2; ``--n 100``'s first 40, or ``--landings``), with
  ``solver="iterative"``, and the flat ones beside ("sticking", "sliding"):
  how many converge, the iterations in all, the time of all 40, the worst residual;
* Siconos' Capsules (``tests/data/siconos``, 225 contacts);
* 100 spheres poured into a box and the pile of 300 spheres (``tests/scenes.py``).

Each case best of ``--repeat`` (the pile, the poured spheres: of ``--repeat`` too). Run it
once per revision, the other's ``src`` first on ``PYTHONPATH``, to compare in the same
minutes (``git archive REV src | tar -x -C /tmp/rev``)::

    PYTHONPATH=src .venv/bin/python benchmarks/bench_iterative_stages.py [--repeat 2]
    PYTHONPATH=/tmp/rev/src .venv/bin/python benchmarks/bench_iterative_stages.py

``--window N`` sets ``carnot.solvers.iterative.PROXIMAL_WINDOW`` (where the revision has it):
the trigger's window, to measure its trade-off (docs/solvers.md, Measured).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--window", type=int, help="PROXIMAL_WINDOW (iterations)")
    parser.add_argument("--skip-poured", action="store_true", help="skip the 100 poured spheres")
    parser.add_argument("--landings", type=int, default=40,
                        help="of each case, at most 100; 0: none")
    args = parser.parse_args()

    import carnot
    from carnot import solve_impact
    from carnot.io.siconos import read_siconos_fc
    from carnot.solvers import iterative, solve_fc3d

    if args.window is not None:
        iterative.PROXIMAL_WINDOW = args.window  # type: ignore[attr-defined]
    from bench_batch_multi import landing_problem
    from bench_many_contacts import best
    from same_answers import cases
    from scenes import pile, poured

    print(f"carnot from {Path(carnot.__file__).parent}, window "
          f"{getattr(iterative, 'PROXIMAL_WINDOW', None)}")  # fmt: skip
    solve_impact(pile(40))  # (Numba's caches loaded before any timing)
    rep = args.repeat
    names = ("tilted sticking", "tilted sliding", "sticking", "sliding")
    for name in names if args.landings > 0 else ():
        case = cases(100)[name]
        count = min(args.landings, 100)
        problems = [landing_problem(case, i) for i in range(count)]
        seconds, certs = best(lambda ps=problems: [solve_impact(p, solver="iterative").solver
                                                   for p in ps], rep)  # fmt: skip
        certs = list(certs)  # type: ignore[call-overload]
        short = [i for i, c in enumerate(certs) if not c.converged]
        print(f"{count} {name} landings: {count - len(short)} converged, "
              f"{sum(c.iterations for c in certs)} iterations in all, {seconds:.2f} s, worst "
              f"residual {max(c.residual for c in certs):.1e}, short: {short}")  # fmt: skip
    capsules = read_siconos_fc(HERE.parent / "tests" / "data" / "siconos"
                               / "Capsules-i101-404.dat")  # fmt: skip
    seconds, answer = best(lambda: solve_fc3d(capsules.delassus, capsules.q, capsules.mu), rep)
    c = answer.certificate  # type: ignore[attr-defined]
    print(f"Siconos' Capsules: {c.iterations} iterations, {seconds:.2f} s, {c.residual:.1e}")
    scenes = [("pile of 300 spheres", pile(300))]
    if not args.skip_poured:
        scenes.append(("100 poured spheres", poured(100)))
    for name, problem in scenes:
        seconds, res = best(lambda p=problem: solve_impact(p), rep)
        c = res.solver  # type: ignore[attr-defined]
        print(f"{name}: {c.iterations} iterations, {seconds:.2f} s, {c.residual:.1e}, "
              f"converged={c.converged}")  # fmt: skip


if __name__ == "__main__":
    main()

"""Every row the batch kernel decides against ``carnot.solve_impact``, on one of
``same_answers.py``'s cases (the box landings, flat or tilted): ``same_answers.py`` compares
the batch with the API on its first ``--api`` rows only, which is how two tilted sticking
landings (rows 173 and 468 of 500) where the two disagree went unseen until 2026-11-27.

Compared per row: the body's velocities after (to ``--tol`` m/s) and every contact's regime.
The rows the batch leaves to the reference law (``by_reference``) are that law's answers and
are skipped. Prints each row that differs, with both sides' regimes, and exits 1 if any.

Run: ``.venv/bin/python benchmarks/batch_vs_api.py --case "tilted sticking" [--n 500]``
(tilted sticking, 500 rows: ~4 minutes, most of it the API on the rows the kernel decides).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_batch_multi import landing_problem  # noqa: E402
from same_answers import cases  # noqa: E402

from carnot import solve_impact  # noqa: E402
from carnot.batch import BatchBodies  # noqa: E402
from carnot.batch.multi import REGIME_NAMES, multi_impacts  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="tilted sticking",
                        help="sticking, sliding, tilted sticking or tilted sliding")
    parser.add_argument("--n", type=int, default=500, help="rows (the same seeds as "
                        "same_answers.py: its first n rows)")  # fmt: skip
    parser.add_argument("--tol", type=float, default=1e-8, help="velocities, m/s")
    args = parser.parse_args()
    case = cases(args.n)[args.case]
    body, points, normals, e, mu = case
    out = multi_impacts(BatchBodies(**body), None, points, normals, e, mu)
    velocity = np.concatenate([out.velocity_a, out.angular_velocity_a], axis=1)
    rows = [i for i in range(args.n) if not out.by_reference[i]]
    differ = []
    for i in rows:
        res = solve_impact(landing_problem(case, i))
        motion = res.bodies["body"]
        api = np.concatenate([motion.velocity_after, motion.angular_velocity_after])
        api_regimes = [c.regime for c in res.contacts]
        batch_regimes = [REGIME_NAMES[int(r)] for r in out.regime[i]]
        gap = float(np.abs(api - velocity[i]).max())
        if gap > args.tol or api_regimes != batch_regimes:
            differ.append(i)
            print(f"row {i}: velocities differ by {gap:.2e} m/s; solve_impact {api_regimes} "
                  f"{[f.code for f in res.warnings]}, batch {batch_regimes}")  # fmt: skip
    print(f"{args.case}: {len(differ)} of the {len(rows)} rows the kernel decides (of "
          f"{args.n}) differ from solve_impact: {differ}")  # fmt: skip
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()

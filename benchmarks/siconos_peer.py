"""Siconos' own solver on its own corpus, beside carnot's (issue 33): errors and times.

For every 3D problem of ``tests/data/siconos`` (or those named), Siconos' nonsmooth
Gauss-Seidel (``fc3d_nsgs`` through ``fc3d_driver``, ``SICONOS_FRICTION_3D_NSGS``, its default
local solver) runs from ``r = 0`` in a subprocess of the *system* Python, where Debian's
``python3-siconos`` lives (``apt-get install python3-siconos``; never a dependency of carnot).
It reports Siconos' info, its sweeps, its own residual (``SICONOS_DPARAM_RESIDU``) and the best
time of ``--repeat`` solves (one, for a solve over a second); here,
:func:`carnot.io.siconos.fc3d_error` measures the reaction it returned, independently, and the
table says which problems reach 1e-8 and 1e-12.

Measured (python3-siconos 4.4.0 from Debian bookworm, tolerance 1e-12, at most 100000 sweeps,
two CPU cores, two runs; times vary by up to 2x between them): the 20 problems up to 27
unknowns (Rover*, FrictionContact3D_*, FC3D_Example1*, Confeti-ex13-4contact, NESpheres_10_1)
converge in 2 to 35 sweeps, 0.003 to 0.3 ms, to errors of 0 to 1.5e-14; OneObject-i1028-138
(23 contacts) in 1794 sweeps, 16 to 25 ms, 1.4e-13; Confeti-ex03 (54) in 130 sweeps, 4 to
5 ms, 4e-17. Four stop at the sweep limit: Capsules-i101-404 (225 contacts) at 4.4e-9 (16 to
23 s), BoxesStack1-i100000-32 at 1.3e-6 (2.3 to 4 s), and OneObject-i100000-499 and -316 at
1.0e-3 and 1.7e-3 (1.7 to 3 s each). So 23 of the 26 reach 1e-8 and 22 reach 1e-12.
``fc3d_error`` of Siconos' reaction equals Siconos' residual on every one (to
round-off: 5.42e-16 against 5.23e-16 on Rover9770, the largest difference).

carnot's column: :func:`carnot.solvers.solve_fc3d` (``W, q, mu, *, solver, tolerance``) on
the same problems (its answer's ``impulses``), measured by the same ``fc3d_error``.

Run: ``PYTHONPATH=src .venv/bin/python benchmarks/siconos_peer.py [--tolerance 1e-12]
[--max-iter 100000] [--repeat 3] [--json out.json] [NAME.dat ...]``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from carnot.io.siconos import FrictionContactProblem, fc3d_error, read_siconos_fc  # noqa: E402

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "siconos"

# Runs under the system Python: reads a JSON job on stdin, writes one JSON line per problem.
WORKER = r"""
import json, sys, time
import numpy as np
import siconos.numerics as sn

job = json.load(sys.stdin)
for path in job["files"]:
    best, out = None, None
    for _ in range(job["repeat"]):
        problem = sn.frictionContact_new_from_filename(path)
        m = problem.dimension * problem.numberOfContacts
        r, u = np.zeros(m), np.zeros(m)
        options = sn.SolverOptions(sn.SICONOS_FRICTION_3D_NSGS)
        options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = job["max_iter"]
        options.dparam[sn.SICONOS_DPARAM_TOL] = job["tolerance"]
        start = time.perf_counter()
        info = sn.fc3d_driver(problem, r, u, options)
        seconds = time.perf_counter() - start
        if best is None or seconds < best:
            best = seconds
            out = {
                "path": path, "info": int(info), "seconds": seconds,
                "iterations": int(options.iparam[sn.SICONOS_IPARAM_ITER_DONE]),
                "residual": float(options.dparam[sn.SICONOS_DPARAM_RESIDU]),
                "r": r.tolist(),
            }
        if seconds > 1.0:  # a slow solve is timed once
            break
    print(json.dumps(out), flush=True)
"""


def siconos_column(paths: list[Path], args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """Siconos' NSGS on each file, in one subprocess of ``args.siconos_python``."""
    job = {"files": [str(p) for p in paths], "tolerance": args.tolerance,
           "max_iter": args.max_iter, "repeat": args.repeat}  # fmt: skip
    try:
        done = subprocess.run(
            [args.siconos_python, "-c", WORKER], input=json.dumps(job), capture_output=True,
            text=True, timeout=args.timeout, check=False,
        )  # fmt: skip
    except (OSError, subprocess.TimeoutExpired) as err:
        print(f"Siconos' column is not available: {err}")
        return {}
    if done.returncode != 0:
        tail = done.stderr.strip().splitlines()[-1:] or ["(no message)"]
        print(f"Siconos' column is not available ({args.siconos_python}): {tail[0]}")
        return {}
    rows = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    return {Path(row["path"]).name: row for row in rows}


def carnot_solver() -> Any:
    """``carnot.solvers.solve_fc3d``, or None (with a line saying so) while it is missing."""
    try:
        from carnot.solvers import solve_fc3d  # type: ignore[import-not-found,unused-ignore]
    except ImportError as err:
        print(f"carnot's column is not available yet (carnot.solvers.solve_fc3d: {err})")
        return None
    return solve_fc3d


def reaction_of(answer: Any) -> np.ndarray:
    """The reaction in ``solve_fc3d``'s answer (its ``impulses``)."""
    for name in ("impulses", "reaction", "r"):
        if hasattr(answer, name):
            return np.asarray(getattr(answer, name), dtype=float)
    if isinstance(answer, tuple):
        return np.asarray(answer[0], dtype=float)
    return np.asarray(answer, dtype=float)


def carnot_row(solve: Any, problem: FrictionContactProblem, args: argparse.Namespace
               ) -> dict[str, Any]:  # fmt: skip
    best, error = float("inf"), float("nan")
    for _ in range(args.repeat):
        start = time.perf_counter()
        try:
            answer = solve(problem.delassus, problem.q, problem.mu, solver=args.carnot_solver,
                           tolerance=args.tolerance)  # fmt: skip
        except Exception as err:  # a solver that refuses a problem is a result here
            return {"failed": f"{type(err).__name__}: {err}"}
        best = min(best, time.perf_counter() - start)
        error = fc3d_error(problem.delassus, problem.q, problem.mu, reaction_of(answer))
    return {"seconds": best, "error": error}


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("files", nargs="*", help="names in tests/data/siconos (default: all 3D)")
    parser.add_argument("--tolerance", type=float, default=1e-12)
    parser.add_argument("--max-iter", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=3, help="best time of this many solves")
    parser.add_argument("--siconos-python", default="/usr/bin/python3")
    parser.add_argument("--carnot-solver", default="auto", help="solve_fc3d's solver=")
    parser.add_argument("--timeout", type=float, default=1800.0, help="for Siconos, seconds")
    parser.add_argument("--json", type=Path, help="write every row here")
    args = parser.parse_args(argv)

    paths = [DATA / name for name in args.files] or sorted(DATA.glob("*.dat"))
    problems = {p.name: read_siconos_fc(p) for p in paths}
    problems = {k: v for k, v in problems.items() if v.dimension == 3}
    problems = dict(sorted(problems.items(), key=lambda kv: (kv[1].size, kv[0])))
    paths = [DATA / name for name in problems]

    sic = siconos_column(paths, args)
    solve = carnot_solver()
    head = (f"{'problem':36s} {'nc':>4s} {'m':>4s} | {'info':>4s} {'sweeps':>7s} "
            f"{'Siconos res':>11s} {'fc3d_error':>10s} {'ms':>9s} 1e-8 1e-12")  # fmt: skip
    if solve is not None:
        head += f" | {'carnot err':>10s} {'ms':>9s}"
    print(f"Siconos NSGS from r = 0, tolerance {args.tolerance:g}, at most {args.max_iter} "
          f"sweeps, best of {args.repeat}")  # fmt: skip
    print(head)
    rows = []
    for name, problem in problems.items():
        row: dict[str, Any] = {"name": name, "nc": problem.contacts, "m": problem.size,
                               "mu": sorted(set(problem.mu.tolist()))}  # fmt: skip
        line = f"{name:36s} {problem.contacts:4d} {problem.size:4d} |"
        s = sic.get(name)
        if s is not None:
            error = fc3d_error(problem.delassus, problem.q, problem.mu, np.array(s["r"]))
            row["siconos"] = {k: s[k] for k in ("info", "iterations", "residual", "seconds")}
            row["siconos"]["fc3d_error"] = error
            line += (f" {s['info']:4d} {s['iterations']:7d} {s['residual']:11.2e} "
                     f"{error:10.2e} {1e3 * s['seconds']:9.3f} {_yes(error <= 1e-8):>4s}"
                     f" {_yes(error <= 1e-12):>5s}")  # fmt: skip
        else:
            line += f" {'(not run)':>55s}"
        if solve is not None:
            c = carnot_row(solve, problem, args)
            row["carnot"] = c
            line += (f" | {c['error']:10.2e} {1e3 * c['seconds']:9.3f}" if "error" in c
                     else f" | {c['failed']}")  # fmt: skip
        rows.append(row)
        print(line)
    if sic:
        reached = {t: [r["name"] for r in rows if r.get("siconos", {}).get("fc3d_error", 1) <= t]
                   for t in (1e-8, 1e-12)}  # fmt: skip
        for t, names in reached.items():
            print(f"Siconos reaches {t:g} on {len(names)} of {len(rows)}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

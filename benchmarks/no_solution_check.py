"""Is a ``no_solution`` answer of the simultaneous Coulomb law true? (issue 14, open.)

A second route, apart from the law's enumeration of regimes: nonsmooth Gauss-Seidel on the
De Saxce formulation of the impact (Acary and Brogliato 2008, ch. 13; the method of Siconos'
``fc3d_nsgs``): per contact, ``P = proj_K(P - rho (u^_n + mu |u_t|, u_t))`` with ``u = w' + G P``
and ``u^_n = u_n + e w'_n`` (Newton's restitution), ``K`` the exact Coulomb cone. A fixed point
is a solution of the law (P in K, the modified velocity in K's dual, the two orthogonal); the
residual printed is the fixed point's, with ``rho = 1``.

Inputs: the tilted sticking landings of ``same_answers.py`` (its cases of 100 landings: a box
on four corners, mu 1.5, normals tilted up to 0.05 rad), with ``G`` and ``w'`` as
``solve_impact`` assembles them. On 2026-11-27, of the first 25 landings 12 came back
``no_solution``; on landing 9 this route found a solution to 1.5e-13 (all four corners
slipping, every ``P_n > 0``), so that ``no_solution`` was wrong; on the others it had not
converged after 20000 sweeps (residuals 1e-7 to 1e-4): inconclusive. The law then got its
start from the smoothed law (``carnot.laws.multiple.smoothing``): of the 100 landings, 0 are
``no_solution`` now. This script stays as the second route on any that may come back.

Run: ``PYTHONPATH=src .venv/bin/python benchmarks/no_solution_check.py [--rows 25]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def proj_cone(p: np.ndarray, mu: float) -> np.ndarray:
    """The Euclidean projection of ``(P_n, P_t)`` on the cone ``|P_t| <= mu P_n``."""
    pn, pt = p[0], p[1:]
    nt = float(np.linalg.norm(pt))
    if nt <= mu * pn:
        return p.copy()
    if mu * nt <= -pn:
        return np.zeros(3)
    a = (pn + mu * nt) / (1 + mu * mu)
    return np.array([a, *(mu * a * pt / nt)])


def modified(g: np.ndarray, w: np.ndarray, e: np.ndarray, mu: np.ndarray, p: np.ndarray,
             c: int) -> np.ndarray:  # fmt: skip
    """Contact ``c``'s De Saxce velocity ``(u^_n + mu |u_t|, u_t)``."""
    sl = slice(3 * c, 3 * c + 3)
    u = w[sl] + g[sl] @ p
    return np.array([u[0] + e[c] * w[3 * c] + mu[c] * np.linalg.norm(u[1:]), u[1], u[2]])


def nsgs(g: np.ndarray, w: np.ndarray, e: np.ndarray, mu: np.ndarray,
         sweeps: int = 20000, tol: float = 1e-13) -> np.ndarray:  # fmt: skip
    """Nonsmooth Gauss-Seidel: each contact's local fixed point in turn, until ``P`` stops."""
    k = len(e)
    p = np.zeros(3 * k)
    for _ in range(sweeps):
        old = p.copy()
        for c in range(k):
            sl = slice(3 * c, 3 * c + 3)
            rho = 1.0 / float(np.max(np.linalg.eigvalsh(g[sl, sl])))
            for _ in range(50):
                new = proj_cone(p[sl] - rho * modified(g, w, e, mu, p, c), float(mu[c]))
                done = np.linalg.norm(new - p[sl]) < 1e-15 * (1 + np.linalg.norm(new))
                p[sl] = new
                if done:
                    break
        if np.linalg.norm(p - old) < tol * (1 + np.linalg.norm(p)):
            break
    return p


def main() -> None:
    from bench_batch_multi import landing_problem
    from same_answers import cases

    from carnot import solve_impact
    from carnot.batch.multi import _solve_impact_space

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", type=int, default=25)
    rows = parser.parse_args().rows
    n = max(rows, 100)  # (the cases' random draws depend on n: 100, as for the figures above)
    case = cases(n)["tilted sticking"]
    body, pts, nrm, e, mu = case
    args = [body["mass"], body["inertia_com"], body["position_com"], body["velocity_com"],
            body["angular_velocity"], np.ones(n), np.broadcast_to(np.eye(3), (n, 3, 3)),
            np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))]  # fmt: skip
    refused = wrong = 0
    for i in range(rows):
        if "no_solution" not in solve_impact(landing_problem(case, i)).flag_codes():
            continue
        refused += 1
        space = _solve_impact_space(args, i, False, pts[i], nrm[i], e[i], mu[i])
        if space is None:
            continue
        g, w = space
        p = nsgs(g, w, e[i], mu[i])
        residual = max(float(np.linalg.norm(p[3 * c:3 * c + 3] - proj_cone(
            p[3 * c:3 * c + 3] - modified(g, w, e[i], mu[i], p, c), float(mu[i][c]))))
            for c in range(len(e[i])))  # fmt: skip
        wrong += residual < 1e-9
        print(f"landing {i}: no_solution; NSGS residual {residual:.2e}, P_n "
              f"{np.round(p[0::3], 6).tolist()}")  # fmt: skip
    print(f"{refused} of {rows} landings no_solution; NSGS finds a solution (residual < 1e-9) "
          f"for {wrong} of them")  # fmt: skip


if __name__ == "__main__":
    main()

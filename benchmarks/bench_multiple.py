"""Latency of the multiple-impact laws of carnot.laws.multiple (issue 14).

The headline case is a box (2 kg, 0.4 x 0.3 x 0.2 m) landing flat on its four bottom corners,
3D Coulomb friction mu = 1.5 at each (12 contact rows), e = 0, sliding at (0.8, 0.3) m/s with
a spin of 0.4 rad/s as it lands at 1 m/s: it sticks, the normal impulses are not unique
(four corners, three equations), the velocities are. Timed, each the median of ``--repeat``
calls after a warm-up, in one run so that the ratios hold on a noisy machine:

* ``resolve_simultaneous(G, w', contacts)`` as called by default: four 3D frictional contacts
  exceed the default verification size, so the regimes are tried most likely first and the
  first that holds is returned (marked unverified);
* the same box sliding on (mu = 0.2, 3 m/s): the slip regime, one nonlinear solve;
* the frictionless landing (four normal rows), where uniqueness is a theorem (monotone LCP);
* the sticking box with ``verify=True``: every regime of the four corners tried (3^4 = 81,
  each 3D slip regime by a nonlinear solve);
* the baseline: ``numpy.linalg.solve`` of the same 12 x 12 ``G`` (what an equality law
  costs), and building ``G = W M^-1 W^T`` from M and W.

Also: the sequential and dispersion laws on a 5-ball Newton's cradle (e = 1).
The issue's target is the whole API call (assembly + law + result) <= 1 ms; this measures
the law alone, which the lead's solver wraps.

Run: ``.venv/bin/python benchmarks/bench_multiple.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import platform

import numpy as np
from timing import summary, timed

from carnot.laws.multiple import (
    ContactRows,
    resolve_dispersion,
    resolve_sequential,
    resolve_simultaneous,
)


def box() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass matrix (6 x 6), Jacobian (12 x 6) and pre-impact velocity of the landing box."""
    m, a, b, c = 2.0, 0.2, 0.15, 0.1
    mass = np.zeros((6, 6))
    mass[:3, :3] = m * np.eye(3)
    mass[3:, 3:] = m / 3.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    rows = []
    for sx in (1, -1):
        for sy in (1, -1):
            r = np.array([sx * a, sy * b, -c])
            for d in np.eye(3)[[2, 0, 1]]:  # n = z, t1 = x, t2 = y (conventions.contact_frame)
                rows.append(np.concatenate([d, np.cross(r, d)]))
    u = np.array([0.8, 0.3, -1.0, 0.0, 0.0, 0.4])
    return mass, np.array(rows), u


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=300)
    args = parser.parse_args()
    mass, jac, u = box()
    minv = np.linalg.inv(mass)
    g = jac @ minv @ jac.T
    w = jac @ u
    friction = [ContactRows(normal=3 * k, tangents=(3 * k + 1, 3 * k + 2), friction=1.5)
                for k in range(4)]
    normals = [0, 3, 6, 9]
    g_n = g[np.ix_(normals, normals)]
    w_n = w[normals]
    frictionless = [ContactRows(normal=k) for k in range(4)]
    cradle_jac = np.zeros((4, 5))
    for i in range(4):
        cradle_jac[i, i], cradle_jac[i, i + 1] = -1.0, 1.0
    g_c = cradle_jac @ cradle_jac.T
    w_c = cradle_jac @ np.array([1.0, 0, 0, 0, 0])
    cradle = [ContactRows(normal=i, restitution=1.0) for i in range(4)]

    out = resolve_simultaneous(g, w, friction)
    u2 = u + minv @ jac.T @ out.impulses
    print(f"python {platform.python_version()}, numpy {np.__version__}")
    print(f"headline answer: regimes {[c.regime for c in out.contacts]}, flags {out.flags}, "
          f"residual {out.residual:.1e} m/s, |u''| {np.linalg.norm(u2):.1e}, "
          f"verified {bool(out.extra['uniqueness_verified'])}")
    slide = [ContactRows(normal=3 * k, tangents=(3 * k + 1, 3 * k + 2), friction=0.2)
             for k in range(4)]
    u_slide = np.array([3.0, 1.0, -1.0, 0.0, 0.0, 0.0])
    w_slide = jac @ u_slide
    cases = [
        ("baseline: numpy.linalg.solve(G 12x12)", lambda: np.linalg.solve(g + np.eye(12), w)),
        ("baseline: G = W M^-1 W^T (12 rows)", lambda: jac @ minv @ jac.T),
        ("3D Coulomb, sticks (default)", lambda: resolve_simultaneous(g, w, friction)),
        ("3D Coulomb, slides (default)", lambda: resolve_simultaneous(g, w_slide, slide)),
        ("frictionless, 4 corners (verified)", lambda: resolve_simultaneous(
            g_n, w_n, frictionless)),
        ("3D Coulomb, sticks, verify=True", lambda: resolve_simultaneous(
            g, w, friction, verify=True)),
        ("sequential, 5-ball cradle", lambda: resolve_sequential(g_c, w_c, cradle)),
        ("dispersion, 5-ball cradle", lambda: resolve_dispersion(g_c, w_c, cradle)),
    ]
    results = []
    for name, fn in cases:
        slow = "verify=True" in name or "dispersion" in name
        repeat = max(5, args.repeat // 30) if slow else args.repeat
        median, iqr = summary(timed(fn, repeat, warm_up=2))
        results.append((name, median, iqr))
    base = results[0][1]
    print(f"{'case':44s} {'median':>12s} {'IQR':>10s} {'x solve':>9s}")
    for name, median, iqr in results:
        print(f"{name:44s} {median * 1e6:9.1f} us {iqr * 1e6:7.1f} us {median / base:9.1f}")


if __name__ == "__main__":
    main()

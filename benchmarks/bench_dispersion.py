"""Benchmark: the dispersion (LZB) law on chains and on a box landing flat on four corners.

Cases (the law alone, on ``G`` and ``w`` built once):

* the baseline: one contact (``G = 2``, ``w = -1``, e = 0.5): two phases, the least an impact
  under this law integrates; every other case is printed as a multiple of it;
* a five-ball cradle at e = 1, 0.5 and 0 (Hertz contacts; at e = 0 the balls end as a cluster
  that rattles in ever smaller phases until what is left is 1e-9 of the deformation scale);
* a box (2 kg, 0.4 x 0.3 x 0.2 m) landing flat on its four corners at 1 m/s, at e = 0, 0.5 and
  1, flat and with a 0.3 rad/s tilt: four contacts, three normal freedoms, ties between the
  corners' events (docs/contacts.md);
* the three-ball cradle at e = 0.2 under both reactivation rules.

Each row prints the median and IQR of the wall time, the ratio to the baseline, the number of
phases and the law's flags. Run: ``.venv/bin/python benchmarks/bench_dispersion.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import os
import platform

import numpy as np
import scipy
from timing import summary, timed

from carnot.laws.multiple import ContactRows, resolve_dispersion


def chain(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``G`` and ``w`` of ``n`` unit balls touching, the first at 1 m/s."""
    jac = np.zeros((n - 1, n))
    for i in range(n - 1):
        jac[i, i], jac[i, i + 1] = -1.0, 1.0
    u = np.zeros(n)
    u[0] = 1.0
    return jac @ jac.T, jac @ u


def box(tilt: float) -> tuple[np.ndarray, np.ndarray]:
    """``G`` (4 x 4, rank 3) and ``w`` of the box's corners, ``omega = (tilt, 0, 0)``."""
    m, (a, b, c) = 2.0, (0.4, 0.3, 0.2)
    inertia = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    minv = np.zeros((6, 6))
    minv[:3, :3] = np.eye(3) / m
    minv[3:, 3:] = np.linalg.inv(inertia)
    z = np.array([0.0, 0.0, 1.0])
    rows = [np.concatenate([z, np.cross([sx * a / 2, sy * b / 2, -c / 2], z)])
            for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]  # fmt: skip
    jac = np.array(rows)
    u = np.array([0.0, 0.0, -1.0, tilt, 0.0, 0.0])
    return jac @ minv @ jac.T, jac @ u


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    g5, w5 = chain(5)
    g3, w3 = chain(3)
    cases: list[tuple[str, object]] = [
        ("baseline: one contact, e = 0.5",
         lambda: resolve_dispersion([[2.0]], [-1.0], [ContactRows(normal=0, restitution=0.5)])),
        ("5-ball cradle, e = 1",
         lambda: resolve_dispersion(g5, w5, [ContactRows(normal=i, restitution=1.0)
                                             for i in range(4)])),
        ("5-ball cradle, e = 0.5",
         lambda: resolve_dispersion(g5, w5, [ContactRows(normal=i, restitution=0.5)
                                             for i in range(4)])),
        ("5-ball cradle, e = 0 (an inelastic collapse)",
         lambda: resolve_dispersion(g5, w5, [ContactRows(normal=i) for i in range(4)])),
    ]  # fmt: skip
    for e in (0.0, 0.5, 1.0):
        for tilt in (0.0, 0.3):
            g, w = box(tilt)
            corners = [ContactRows(normal=i, restitution=e) for i in range(4)]
            cases.append((f"box flat, e = {e}, tilt {tilt} rad/s",
                          lambda g=g, w=w, c=corners: resolve_dispersion(g, w, c)))  # fmt: skip
    for rule in ("gap", "approach"):
        cradle = [ContactRows(normal=i, restitution=0.2) for i in range(2)]
        cases.append((f"3-ball cradle, e = 0.2, reactivation {rule}",
                      lambda c=cradle, r=rule: resolve_dispersion(g3, w3, c, reactivation=r)))
    print(f"python {platform.python_version()}, numpy {np.__version__}, scipy "
          f"{scipy.__version__}, load {os.getloadavg()[0]:.2f}")  # fmt: skip
    print(f"{'case':46s} {'median':>10s} {'IQR':>9s} {'x base':>7s} {'phases':>7s}  flags")
    base = None
    for name, fn in cases:
        median, iqr = summary(timed(fn, args.repeat, warm_up=1))  # type: ignore[arg-type]
        out = fn()  # type: ignore[operator]
        base = base or median
        print(f"{name:46s} {median * 1e3:7.2f} ms {iqr * 1e3:6.2f} ms {median / base:7.1f} "
              f"{len(out.stages):7d}  {out.flags}")  # fmt: skip


if __name__ == "__main__":
    main()

"""Throughput of the multi-contact batch (carnot.batch.multi_impacts), issue 14 item 5.

Two cases, random inputs per impact (a different velocity, spin and restitution in each row):

* a planar block (3 kg, 0.5 x 2 m) landing on its two bottom corners, frictionless (two
  normal rows): target >= 1 M impacts/s;
* a box (2 kg, 0.4 x 0.3 x 0.2 m) landing flat on its four bottom corners, 3D Coulomb
  friction mu = 1.5 (12 rows: it sticks, the normal impulses not unique), and the same box
  sliding at up to 3 m/s on mu = 0.2 (the slip regime: a Newton solve for the slip angle):
  target >= 200 k impacts/s.

Baselines in the same run, as ratios: the Python loop over ``carnot.solve_impact`` on the
same impacts (what a user would write), and NumPy's batched ``numpy.linalg.solve`` of the
same ``G`` (an equality law that drops the complementarity: the cost floor of batched small
solves). Also the fraction of rows the kernel left to the reference law (``by_reference``).
Run: ``.venv/bin/python benchmarks/bench_batch_multi.py [--n N] [--loop L]``.
"""

from __future__ import annotations

import argparse
import os
import platform

import numpy as np
from timing import best_of

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies
from carnot.batch.multi import multi_impacts


def _box_inertia(m: float, size: tuple[float, float, float]) -> np.ndarray:
    a, b, c = size
    return m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


Case = tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def block(rng: np.random.Generator, n: int) -> Case:
    m, b, h = 3.0, 0.25, 1.0
    v = np.zeros((n, 3))
    v[:, 1] = rng.uniform(-2.0, -0.1, n)
    om = np.zeros((n, 3))
    om[:, 2] = rng.uniform(-3.0, 3.0, n)
    body = {"mass": np.full(n, m), "inertia_com": np.broadcast_to(
        _box_inertia(m, (2 * b, 2 * h, 0.2)), (n, 3, 3)).copy(),
        "position_com": np.tile([0.0, h, 0.0], (n, 1)), "velocity_com": v,
        "angular_velocity": om}  # fmt: skip
    points = np.broadcast_to([[-b, 0.0, 0.0], [b, 0.0, 0.0]], (n, 2, 3)).copy()
    normals = np.broadcast_to([[0.0, 1.0, 0.0]] * 2, (n, 2, 3)).copy()
    e = rng.uniform(0.0, 1.0, (n, 2))
    return body, points, normals, e, np.zeros((n, 2))


def box(rng: np.random.Generator, n: int, mu: float, slide: float) -> tuple[
        dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    m, size = 2.0, (0.4, 0.3, 0.2)
    a, b, c = (s / 2 for s in size)
    v = np.zeros((n, 3))
    v[:, :2] = rng.uniform(-slide, slide, (n, 2))
    v[:, 2] = rng.uniform(-2.0, -0.2, n)
    om = rng.uniform(-0.5, 0.5, (n, 3)) * np.array([0.2, 0.2, 1.0])
    body = {"mass": np.full(n, m),
            "inertia_com": np.broadcast_to(_box_inertia(m, size), (n, 3, 3)).copy(),
            "position_com": np.tile([0.0, 0.0, c], (n, 1)), "velocity_com": v,
            "angular_velocity": om}  # fmt: skip
    corners = [[sx * a, sy * b, 0.0] for sx in (1, -1) for sy in (1, -1)]
    points = np.broadcast_to(corners, (n, 4, 3)).copy()
    normals = np.broadcast_to([[0.0, 0.0, 1.0]] * 4, (n, 4, 3)).copy()
    e = np.repeat(rng.uniform(0.0, 1.0, (n, 1)), 4, axis=1)
    return body, points, normals, e, np.full((n, 4), mu)


def landing_problem(case: tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray,
                                np.ndarray], i: int) -> ImpactProblem:  # fmt: skip
    """Impact ``i`` of a batch ``case`` (:func:`box`'s arrays) as one ``ImpactProblem``."""
    body, points, normals, e, mu = case
    contacts = [PointContact(a="body", b="ground", point=points[i, k], normal=normals[i, k],
                             restitution=float(e[i, k]), friction=float(mu[i, k]),
                             where=f"contacts[{k}]")
                for k in range(points.shape[1])]  # fmt: skip
    rigid = RigidBody(name="body", mass=float(body["mass"][i]),
                      inertia_com=body["inertia_com"][i], position_com=body["position_com"][i],
                      velocity_com=body["velocity_com"][i],
                      angular_velocity=body["angular_velocity"][i])  # fmt: skip
    return ImpactProblem(bodies={"body": rigid, "ground": FixedBody(name="ground")},
                         contacts=contacts)  # fmt: skip


def loop(case: tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, np.ndarray],
         count: int) -> None:  # fmt: skip
    for i in range(count):
        solve_impact(landing_problem(case, i))


def delassus_of(case: tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray,
                            np.ndarray]) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """``G`` and ``w'`` of every impact (NumPy, for the batched-solve baseline)."""
    from carnot.batch.multi_kernel import assemble

    body, points, normals, _, mu = case
    tangential = np.any(mu > 0, axis=0).astype(np.int64)
    m = points.shape[1] + 2 * int(tangential.sum())
    n = len(body["mass"])
    gs = np.empty((n, m, m))
    ws = np.empty((n, m))
    for i in range(n):
        g, w, *_ = assemble(body["mass"][i], body["inertia_com"][i], body["position_com"][i],
                            body["velocity_com"][i], body["angular_velocity"][i], 1.0,
                            np.eye(3), np.zeros(3), np.zeros(3), np.zeros(3), False,
                            points[i], normals[i], tangential, m)  # fmt: skip
        gs[i] = g + 1e-9 * np.trace(g) * np.eye(m)  # regularized: G may be singular
        ws[i] = w
    return gs, ws


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000, help="impacts per batch")
    parser.add_argument("--loop", type=int, default=300, help="impacts of the Python loop")
    args = parser.parse_args()
    rng = np.random.default_rng(5)
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.1f}")  # fmt: skip
    cases = {
        "2-contact planar frictionless (block on two corners)": block(rng, args.n),
        # (smaller: one row in twelve lifts a corner while the others slip and enumerates
        # 40-57 regimes, 0.6-5 ms)
        "4-contact 3D Coulomb, sticking (box landing flat, mu 1.5)": box(rng, args.n // 100,
                                                                          1.5, 0.8),
        "4-contact 3D Coulomb, sliding (box landing flat, mu 0.2)": box(rng, args.n // 100,
                                                                        0.2, 3.0),
    }  # fmt: skip
    for name, case in cases.items():
        body, points, normals, e, mu = case
        n = len(e)
        bodies = BatchBodies(**body)
        out = multi_impacts(bodies, None, points, normals, e, mu)  # compile / warm up
        batch = best_of(lambda: multi_impacts(bodies, None, points, normals, e, mu), 3)  # noqa: B023
        count = min(args.loop, n)
        python = best_of(lambda: loop(case, count), 1) / count  # noqa: B023
        small = 20000 if mu.any() else 100000
        gs, ws = delassus_of((body_slice(body, small), points[:small], normals[:small],
                              e[:small], mu[:small]))  # fmt: skip
        numpy_solve = best_of(lambda: np.linalg.solve(gs, -ws[..., None]), 3) / small  # noqa: B023
        rate = n / batch
        print(f"\n{name}: {n} impacts")
        print(f"  batch            {rate / 1e6:8.3f} M impacts/s  ({batch * 1e9 / n:7.0f} ns each)")
        print(f"  solve_impact loop {1 / python / 1e3:7.2f} k impacts/s   "
              f"ratio {rate * python:9.0f}x")
        print(f"  numpy.linalg.solve of the same G {1 / numpy_solve / 1e6:6.3f} M/s   ratio "
              f"{rate * numpy_solve:6.2f}x")  # fmt: skip
        keep = ~out.by_reference
        sub = BatchBodies(**{k: v[keep] for k, v in body.items()})
        kernel = best_of(lambda: multi_impacts(sub, None, points[keep], normals[keep],  # noqa: B023
                                               e[keep], mu[keep]), 3)  # noqa: B023
        print(f"  the rows the kernel decides alone: {keep.sum() / kernel / 1e3:8.1f} k/s")
        print(f"  rows left to the reference law: {int(out.by_reference.sum())}; "
              f"statically indeterminate {float(out.statically_indeterminate.mean()):.2f}; "
              f"regimes {np.bincount(out.regime.ravel(), minlength=4).tolist()}")  # fmt: skip


def body_slice(body: dict[str, np.ndarray], count: int) -> dict[str, np.ndarray]:
    return {k: v[:count] for k, v in body.items()}


if __name__ == "__main__":
    main()

"""Throughput of the Coulomb batch kernels (carnot.batch.coulomb), issue #5 item 1.

In one run, so that the ratios hold on a noisy machine:

* constant slip direction, Stronge's hypothesis: random planar impacts of a body on an
  obstacle (bodies moving in the x-y plane, normal in that plane: every slip direction is
  invariant, the exact piecewise-linear solution);
* 3D slip whose direction turns, Stronge's hypothesis: random two-body 3D impacts (general
  inertia tensors) whose bodies approach (DOP853 at rtol 1e-10 in every row that slides);
* the baseline: a plain Python loop over ``carnot.solve_impact`` on the same kinds of cases.

Impacts per second of ``point_impacts`` (compiled build, all cores) for N = 10^3 ... --max-n,
the ratio to the loop, and the roofline measured in the same run (``roofline.py``): the time
of a pass that streams the same input and output bytes, and the counted operations per
second against the vectorized arithmetic rate.
Run: ``.venv/bin/python benchmarks/bench_batch_coulomb.py [--max-n N]``.
"""

from __future__ import annotations

import argparse
import os
import platform

import numpy as np
import roofline
from scipy.spatial.transform import Rotation
from timing import best_of

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies, point_impacts
from carnot.batch.pipeline import FLOAT_WIDTH, INT_WIDTH

FIELDS = ("mass", "inertia_com", "position_com", "velocity_com", "angular_velocity")
#: Impacts whose operations are counted (counting numbers in Python: ~30 ms per 3D impact).
SAMPLE = 100


def planar(rng: np.random.Generator, n: int) -> tuple[BatchBodies, None, np.ndarray, np.ndarray]:
    """Bodies in the x-y plane falling onto obstacles (normal +y, approaching)."""
    mass = 10 ** rng.uniform(-1, 1, n)
    a, b = rng.uniform(0.5, 1.0, (2, n)) * mass * 0.01
    rot = Rotation.from_euler("z", rng.uniform(0, 2 * np.pi, (n, 1))).as_matrix()
    moments = np.stack([a, b, a + b], -1)
    inertia = rot @ (moments[:, :, None] * np.eye(3)) @ np.swapaxes(rot, -1, -2)
    position = np.zeros((n, 3))
    position[:, 0], position[:, 1] = rng.uniform(-0.2, 0.2, n), rng.uniform(0.05, 0.2, n)
    velocity = np.zeros((n, 3))
    velocity[:, 0], velocity[:, 1] = rng.uniform(-3, 3, n), -rng.uniform(0.5, 5, n)
    omega = np.zeros((n, 3))
    omega[:, 2] = rng.uniform(-10, 10, n)
    body = BatchBodies(mass=mass, inertia_com=inertia, position_com=position,
                       velocity_com=velocity, angular_velocity=omega)  # fmt: skip
    normal = np.zeros((n, 3))
    normal[:, 1] = 1.0
    return body, None, np.zeros((n, 3)), normal


def spatial(rng: np.random.Generator, n: int) -> tuple[BatchBodies, BatchBodies, np.ndarray,
                                                       np.ndarray]:  # fmt: skip
    """Two bodies in general 3D motion, the normal flipped where they would separate."""
    def body() -> BatchBodies:
        mass = 10 ** rng.uniform(-1, 1, n)
        moments = rng.uniform(0.5, 1.0, (n, 3)) * mass[:, None] * 0.01
        rot = Rotation.random(n, random_state=rng).as_matrix()
        inertia = rot @ (moments[:, :, None] * np.eye(3)) @ np.swapaxes(rot, -1, -2)
        return BatchBodies(mass=mass, inertia_com=inertia,
                           position_com=rng.uniform(-1, 1, (n, 3)),
                           velocity_com=rng.uniform(-5, 5, (n, 3)),
                           angular_velocity=rng.uniform(-5, 5, (n, 3)))  # fmt: skip

    a, b = body(), body()
    point, normal = rng.uniform(-1, 1, (n, 3)), rng.normal(size=(n, 3))
    w = (a.velocity_com + np.cross(a.angular_velocity, point - a.position_com)
         - b.velocity_com - np.cross(b.angular_velocity, point - b.position_com))  # fmt: skip
    normal *= -np.sign(np.einsum("ij,ij->i", w, normal))[:, None]  # approaching: n . w < 0
    return a, b, point, normal


def loop_rate(case: tuple, mu: np.ndarray, count: int) -> float:
    a, b, point, normal = case

    def one(s: BatchBodies, k: int, name: str) -> RigidBody:
        return RigidBody(name=name, **{f: getattr(s, f)[k] for f in FIELDS})

    problems = [ImpactProblem(
        bodies={"a": one(a, k, "a"), "b": FixedBody(name="b") if b is None else one(b, k, "b")},
        contacts=[PointContact(a="a", b="b", point=point[k], normal=normal[k], restitution=0.5,
                               friction=mu[k], law="stronge")]) for k in range(count)]  # fmt: skip
    return count / best_of(lambda: [solve_impact(p) for p in problems], 3)


def coulomb(max_n: int) -> None:
    """The Coulomb kernels' throughput table (see the module docstring)."""
    rng = np.random.default_rng(7)
    print(f"{platform.platform()}; python {platform.python_version()}, numpy {np.__version__}; "
          f"{os.cpu_count()} cpus; load average {os.getloadavg()}")  # fmt: skip
    triad = roofline.triad_bandwidth()
    scalar, vector = roofline.flop_rate(), roofline.vector_flop_rate()
    print(f"roofline: STREAM triad {triad / 1e9:.1f} GB/s; compiled arithmetic {scalar / 1e9:.1f} "
          f"Gflop/s scalar, {vector / 1e9:.1f} Gflop/s vectorized (all cores)")  # fmt: skip
    bytes_out = FLOAT_WIDTH * 8 + INT_WIDTH
    for name, make in (("planar Stronge (constant direction)", planar),
                       ("3D Stronge (direction turns)", spatial)):  # fmt: skip
        small = make(rng, 300)
        mu = rng.uniform(0.05, 1.0, 300)
        loop = loop_rate(small, mu, 300)
        point_impacts(*small, 0.5, friction=mu, law="stronge")  # compile, or load the cache
        # bytes: what the kernel reads (an obstacle's arrays are broadcast: a zero stride,
        # no traffic) and writes; operations: counted on a sample of the same kind of cases
        bodies = 1 if small[1] is None else 2
        bytes_in = bodies * (1 + 9 + 3 + 3 + 3) * 8 + (3 + 3 + 1) * 8  # e: one value
        ops = roofline.count_flops_of("coulomb_stronge", *small, 0.5, mu, SAMPLE)
        print(f"\n{name}: Python loop over solve_impact {loop:,.0f} impacts/s; "
              f"{bytes_in} B in + {bytes_out} B out per impact; {ops:,.0f} operations per "
              f"impact (mean of {SAMPLE})")  # fmt: skip
        print(f"{'N':>10} {'impacts/s':>12} {'x loop':>7} {'stream/s':>12} {'of stream':>9} "
              f"{'GB/s':>5} {'Gop/s':>6} {'of vector':>9}  regimes (code: count)  load")
        n = 10**3
        while n <= max_n:
            case = make(rng, n)
            friction = rng.uniform(0.05, 1.0, n)

            def run(case: tuple = case, friction: np.ndarray = friction) -> object:
                return point_impacts(*case, 0.5, friction=friction, law="stronge")

            out = run()
            seconds = best_of(run, 5 if n <= 10**5 else 2)
            a, b, point, normal = case
            inputs = [getattr(a, f) for f in FIELDS] + [point, normal, friction]
            if b is not None:
                inputs += [getattr(b, f) for f in FIELDS]
            t_stream = roofline.stream_layout(inputs, np.empty((n, FLOAT_WIDTH)),
                                              np.empty((n, INT_WIDTH), np.int8),
                                              5 if n <= 10**5 else 2)  # fmt: skip
            regimes = dict(enumerate(np.bincount(out.regime).tolist()))
            regimes = {k: v for k, v in regimes.items() if v}
            print(f"{n:>10,} {n / seconds:>12,.0f} {n / seconds / loop:>7,.0f} "
                  f"{n / t_stream:>12,.0f} {t_stream / seconds:>9.3f} "
                  f"{n * (bytes_in + bytes_out) / seconds / 1e9:>5.1f} "
                  f"{n * ops / seconds / 1e9:>6.1f} {n * ops / seconds / vector:>9.2f}  "
                  f"{regimes}  {os.getloadavg()[0]:.2f}")  # fmt: skip
            n *= 10
    print("\nstream/s: a pass that only reads the same inputs and writes the same outputs; "
          "'of stream': its time over the kernel's (the memory floor's share); Gop/s: the "
          "counted operations (an upper bound: both sides of every select, no common "
          "subexpressions removed) per second; 'of vector': of the vectorized arithmetic roof")
    print("targets (issue #5): constant-direction Coulomb with Stronge >= 5 million/s; 3D "
          "direction-changing Coulomb >= 1 million/s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-n", type=int, default=10**7)
    coulomb(parser.parse_args().max_n)

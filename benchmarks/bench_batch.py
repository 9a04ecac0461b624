"""Throughput of the batch kernels (carnot.batch.point_impacts), first part of issue #5.

Measured in one run, so the ratios hold on a noisy machine:

* ``carnot.batch.point_impacts`` on N random two-body 3D point impacts (general inertia
  tensors), frictionless Newton and stick, for N = 10^3 ... 10^6: impacts per second;
* the baseline: a plain Python loop over ``carnot.solve_impact`` (300 impacts), per impact;
* a memory-streaming pass over the same input and output bytes (``numpy.copyto`` of the
  inputs into preallocated outputs of the same size), as the roofline the issue asks for.

Run: ``.venv/bin/python benchmarks/bench_batch.py`` (about a minute).
"""

from __future__ import annotations

import os
import platform

import numpy as np
from scipy.spatial.transform import Rotation
from timing import best_of

from carnot import ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies, point_impacts


def bodies(rng: np.random.Generator, n: int) -> BatchBodies:
    mass = 10 ** rng.uniform(-1, 1, n)
    moments = rng.uniform(0.5, 1.0, (n, 3)) * mass[:, None] * 0.01
    rot = Rotation.random(n, random_state=rng).as_matrix()
    inertia = rot @ (moments[:, :, None] * np.eye(3)) @ np.swapaxes(rot, -1, -2)
    return BatchBodies(mass=mass, inertia_com=inertia, position_com=rng.uniform(-1, 1, (n, 3)),
                       velocity_com=rng.uniform(-5, 5, (n, 3)),
                       angular_velocity=rng.uniform(-5, 5, (n, 3)))  # fmt: skip


def main() -> None:
    rng = np.random.default_rng(5)
    print(f"{platform.platform()}; python {platform.python_version()}, numpy {np.__version__}; "
          f"{os.cpu_count()} cpus; load average {os.getloadavg()[0]:.2f}")  # fmt: skip
    # the baseline: the single-impact API in a Python loop
    a1, b1 = bodies(rng, 300), bodies(rng, 300)
    point, normal = rng.uniform(-1, 1, (300, 3)), rng.normal(size=(300, 3))
    problems = [
        ImpactProblem(
            bodies={name: RigidBody(name=name, mass=s.mass[k], inertia_com=s.inertia_com[k],
                                    position_com=s.position_com[k],
                                    velocity_com=s.velocity_com[k],
                                    angular_velocity=s.angular_velocity[k])
                    for name, s in (("a", a1), ("b", b1))},
            contacts=[PointContact(a="a", b="b", point=point[k], normal=normal[k],
                                   restitution=0.5)],
        )
        for k in range(300)
    ]  # fmt: skip
    loop = best_of(lambda: [solve_impact(p) for p in problems], 3) / 300
    print(f"baseline: Python loop over carnot.solve_impact: {loop * 1e6:.0f} us per impact, "
          f"{1 / loop:,.0f} impacts/s")  # fmt: skip
    print(f"{'N':>9}  {'law':<12} {'impacts/s':>14}  {'x loop':>8}  {'stream (s)':>10}  "
          f"{'kernel / stream':>15}")  # fmt: skip
    for n in (10**3, 10**4, 10**5, 10**6):
        a, b = bodies(rng, n), bodies(rng, n)
        point, normal = rng.uniform(-1, 1, (n, 3)), rng.normal(size=(n, 3))
        e = rng.uniform(0, 1, n)
        inputs = [a.mass, a.inertia_com, a.position_com, a.velocity_com, a.angular_velocity,
                  b.mass, b.inertia_com, b.position_com, b.velocity_com, b.angular_velocity,
                  point, normal, e]  # fmt: skip
        outputs = [np.empty_like(x) for x in inputs]  # as many bytes out as in

        def stream(inputs=inputs, outputs=outputs) -> None:  # type: ignore[no-untyped-def]
            for src, dst in zip(inputs, outputs, strict=True):
                np.copyto(dst, src)

        repeat = 5 if n <= 10**5 else 2
        t_stream = best_of(stream, repeat)
        for law in ("slip", "stick"):
            t = best_of(lambda a=a, b=b, point=point, normal=normal, e=e, law=law:
                        point_impacts(a, b, point, normal, e, tangential=law), repeat)  # fmt: skip
            name = "frictionless" if law == "slip" else "stick"
            print(f"{n:>9}  {name:<12} {n / t:>14,.0f}  {loop * n / t:>8,.0f}  "
                  f"{t_stream:>10.4f}  {t / t_stream:>15.1f}")  # fmt: skip
    print("targets (issue #5, for the finished kernels): frictionless >= 15 million/s and at "
          "least half the streaming rate; stick >= 10 million/s; >= 3000x the Python loop")


if __name__ == "__main__":
    main()

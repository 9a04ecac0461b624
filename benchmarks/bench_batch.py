"""Throughput of the batch kernels (carnot.batch.point_impacts) against the roofline and the
baselines of issue #5, all measured in one run (ratios hold on a noisy machine):

* the kernels, compiled (Numba, all cores) and array-API (NumPy), on N random two-body 3D
  point impacts with general inertia tensors, frictionless and stick, N = 10^3 ... 10^7:
  impacts per second through ``point_impacts``, checks included, writing to fresh memory
  ("fresh": the operating system's page faults of the first writes included) and into the
  memory of an earlier result (``out=``);
* the roofline: STREAM triad bandwidth and the scalar and vectorized floating-point rates
  of this machine;
  bytes per impact counted from the layout (inputs read, outputs written) and floating-point
  operations per impact counted by running the formula on counting numbers; and a pure
  streaming pass over exactly the kernel's input and output arrays (its memory floor);
* the baselines: a plain Python loop over ``carnot.solve_impact`` (300 impacts), and the
  NumPy a newcomer would write (``newcomer_numpy.py``: stacks, inv, cross, einsum).

Run: ``.venv/bin/python benchmarks/bench_batch.py [--max-n 10000000]`` (about two minutes).
"""

from __future__ import annotations

import argparse
import os
import platform

import newcomer_numpy
import numpy as np
import roofline
from scipy.spatial.transform import Rotation
from timing import best_of

from carnot import ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies, point_impacts
from carnot.batch.pipeline import FLOAT_WIDTH, INT_WIDTH


def bodies(rng: np.random.Generator, n: int) -> BatchBodies:
    mass = 10 ** rng.uniform(-1, 1, n)
    moments = rng.uniform(0.5, 1.0, (n, 3)) * mass[:, None] * 0.01
    rot = Rotation.random(n, random_state=rng).as_matrix()
    inertia = rot @ (moments[:, :, None] * np.eye(3)) @ np.swapaxes(rot, -1, -2)
    return BatchBodies(mass=mass, inertia_com=inertia, position_com=rng.uniform(-1, 1, (n, 3)),
                       velocity_com=rng.uniform(-5, 5, (n, 3)),
                       angular_velocity=rng.uniform(-5, 5, (n, 3)))  # fmt: skip


def python_loop_rate(rng: np.random.Generator, count: int = 300) -> float:
    """Impacts per second of a plain Python loop over carnot.solve_impact."""
    a, b = bodies(rng, count), bodies(rng, count)
    point, normal = rng.uniform(-1, 1, (count, 3)), rng.normal(size=(count, 3))
    problems = [
        ImpactProblem(
            bodies={name: RigidBody(name=name, mass=s.mass[k], inertia_com=s.inertia_com[k],
                                    position_com=s.position_com[k],
                                    velocity_com=s.velocity_com[k],
                                    angular_velocity=s.angular_velocity[k])
                    for name, s in (("a", a), ("b", b))},
            contacts=[PointContact(a="a", b="b", point=point[k], normal=normal[k],
                                   restitution=0.5)],
        )
        for k in range(count)
    ]  # fmt: skip
    return count / best_of(lambda: [solve_impact(p) for p in problems], 3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-n", type=int, default=10**7)
    args = parser.parse_args()
    rng = np.random.default_rng(5)
    print(f"{platform.platform()}; python {platform.python_version()}, numpy {np.__version__}; "
          f"{os.cpu_count()} cpus; load average {os.getloadavg()[0]:.2f}")  # fmt: skip
    triad = roofline.triad_bandwidth()
    flops, vector = roofline.flop_rate(), roofline.vector_flop_rate()
    print(f"roofline: STREAM triad {triad / 1e9:.1f} GB/s; compiled arithmetic "
          f"{flops / 1e9:.1f} Gflop/s scalar, {vector / 1e9:.1f} Gflop/s vectorized "
          f"(all cores)")  # fmt: skip
    bytes_in = 2 * (1 + 9 + 3 + 3 + 3) * 8 + (3 + 3 + 1) * 8  # two bodies, point, normal, e
    bytes_out = FLOAT_WIDTH * 8 + INT_WIDTH
    per = {law: roofline.count_flops(law, obstacle=False) for law in ("frictionless", "stick")}
    print(f"layout: {bytes_in} B in + {bytes_out} B out = {bytes_in + bytes_out} B per impact; "
          f"flop (and compare) per impact: frictionless {per['frictionless']}, "
          f"stick {per['stick']}")  # fmt: skip
    loop = python_loop_rate(rng)
    print(f"baseline: Python loop over carnot.solve_impact: {loop:,.0f} impacts/s")
    # warm both builds (Numba compiles on first use, or loads its cache)
    for law in ("slip", "stick"):
        small = bodies(rng, 10)
        point_impacts(small, small, np.zeros((10, 3)), np.ones((10, 3)), 0.5, tangential=law)
    header = (f"{'N':>9} {'law':<12} {'fresh/s':>12} {'out=/s':>12} {'array/s':>11} "
              f"{'newcomer/s':>11} {'stream/s':>11} {'of stream':>9} {'GB/s':>6} "
              f"{'Gflop/s':>7} {'x loop':>8} {'x newcomer':>10}")  # fmt: skip
    print(header)
    n = 10**3
    while n <= args.max_n:
        a, b = bodies(rng, n), bodies(rng, n)
        point, normal = rng.uniform(-1, 1, (n, 3)), rng.normal(size=(n, 3))
        e = rng.uniform(0, 1, n)
        inputs = [a.mass, a.inertia_com, a.position_com, a.velocity_com, a.angular_velocity,
                  b.mass, b.inertia_com, b.position_com, b.velocity_com, b.angular_velocity,
                  point, normal, e]  # fmt: skip
        out_float = np.empty((n, FLOAT_WIDTH))
        out_int = np.empty((n, INT_WIDTH), dtype=np.int8)
        repeat = 7 if n <= 10**5 else 3 if n <= 10**6 else 2
        t_stream = roofline.stream_layout(inputs, out_float, out_int, repeat)
        del out_float, out_int
        for law in ("slip", "stick"):
            name = "frictionless" if law == "slip" else "stick"
            # into fresh memory (what a single call costs: the page faults of the outputs'
            # first writes included), and into the memory of an earlier result (out=)
            t = best_of(lambda a=a, b=b, point=point, normal=normal, e=e, law=law:
                        point_impacts(a, b, point, normal, e, tangential=law), repeat)  # fmt: skip
            earlier = point_impacts(a, b, point, normal, e, tangential=law)
            t_reuse = best_of(lambda a=a, b=b, point=point, normal=normal, e=e, law=law,
                              earlier=earlier: point_impacts(a, b, point, normal, e,
                                                             tangential=law, out=earlier),
                              repeat)  # fmt: skip
            del earlier
            few = 1 if n >= 10**6 else repeat
            t_array = best_of(lambda a=a, b=b, point=point, normal=normal, e=e, law=law:
                              point_impacts(a, b, point, normal, e, tangential=law,
                                            backend="array"), few)  # fmt: skip
            if n <= 10**6:
                t_new = best_of(lambda a=a, b=b, point=point, normal=normal, e=e, law=law:
                                newcomer_numpy.point_impacts(
                                    a, b, point, normal, e, stick=law == "stick"), few)  # fmt: skip
                newcomer, ratio_new = f"{n / t_new:>11,.0f}", f"{t_new / t:>10.1f}"
            else:
                newcomer, ratio_new = f"{'-':>11}", f"{'-':>10}"
            print(f"{n:>9} {name:<12} {n / t:>12,.0f} {n / t_reuse:>12,.0f} "
                  f"{n / t_array:>11,.0f} {newcomer} {n / t_stream:>11,.0f} "
                  f"{t_stream / t:>4.2f}/{t_stream / t_reuse:>4.2f} "
                  f"{n * (bytes_in + bytes_out) / t_reuse / 1e9:>6.1f} "
                  f"{n * per[name] / t_reuse / 1e9:>7.2f} "
                  f"{n / t / loop:>8,.0f} {ratio_new}")  # fmt: skip
        n *= 10
    # the newcomer's answer is the same physics: check it once, so the comparison is fair
    a, b = bodies(rng, 1000), bodies(rng, 1000)
    point, normal, e = rng.uniform(-1, 1, (1000, 3)), rng.normal(size=(1000, 3)), 0.5
    ours = point_impacts(a, b, point, normal, np.full(1000, e))
    theirs = newcomer_numpy.point_impacts(a, b, point, normal, np.full(1000, e))
    gap = np.max(np.abs(ours.impulse - theirs["impulse"]) / np.abs(ours.impulse).max())
    print(f"newcomer's impulses equal carnot.batch's to {gap:.1e} (relative)")
    print("fresh: point_impacts writing to new memory; out=: into an earlier result's memory")
    print("'of stream': the streaming pass's time over point_impacts' (fresh / out=); GB/s and "
          "Gflop/s of the out= calls; x loop and x newcomer: fresh calls")
    print("targets (issue #5): frictionless >= 15 million/s and >= half the streaming rate; "
          "stick >= 10 million/s; >= 3000x the Python loop; >= 10x the newcomer's NumPy")


if __name__ == "__main__":
    main()

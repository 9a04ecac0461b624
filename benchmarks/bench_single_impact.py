"""Latency of one frictionless two-body 3D point impact.

Measured three ways in one run, so the ratios hold on a noisy machine:

* ``baseline``: a minimal hand-written NumPy closed form (the scalar effective-mass formula),
  which is the floor for any general solver in Python;
* ``carnot.solve_impact``: the Python API on a prebuilt problem (one point contact takes the
  short path of :mod:`carnot.single`), with the momentum check read as well (it is made when
  first read), through the general route (``carnot.solve.solve_pipeline``), and with the
  construction of the problem (validation included);
* ``carnot solve FILE --json``: the command line in a fresh process, start-up included.

``--against REV`` also times the prebuilt frictionless and sticking solves of the package as it
was at git revision ``REV`` (exported to a temporary folder), each tree in its own process,
alternating, so that a redesign is compared with what it replaced in the same run (issue 13:
``--against 3cd820b``, the last commit before the contact-space seam).

Run: ``make bench`` or ``.venv/bin/python benchmarks/bench_single_impact.py [--against REV]``.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from timing import summary, timed

from carnot import ImpactProblem, PointContact, RigidBody, solve_impact

SCENARIO = """
format = 1
[bodies.a]
mass = 1.3
inertia = [[0.02, 0.001, 0.0], [0.001, 0.03, 0.002], [0.0, 0.002, 0.025]]
position = [0.0, 0.0, 0.2]
velocity = [0.4, -0.1, -2.0]
angular_velocity = [1.0, 0.5, -0.3]
[bodies.b]
mass = 2.1
inertia = [[0.05, 0.0, 0.003], [0.0, 0.04, 0.0], [0.003, 0.0, 0.06]]
position = [0.05, -0.02, -0.25]
velocity = [0.0, 0.2, 0.5]
angular_velocity = [-0.2, 0.0, 0.8]
[[contacts]]
a = "a"
b = "b"
point = [0.02, -0.01, 0.0]
normal = [0.1, 0.05, 1.0]
restitution = 0.6
"""


def build() -> ImpactProblem:
    a = RigidBody(name="a", mass=1.3,
                  inertia_com=[[0.02, 0.001, 0.0], [0.001, 0.03, 0.002], [0.0, 0.002, 0.025]],
                  position_com=[0.0, 0.0, 0.2], velocity_com=[0.4, -0.1, -2.0],
                  angular_velocity=[1.0, 0.5, -0.3])  # fmt: skip
    b = RigidBody(name="b", mass=2.1,
                  inertia_com=[[0.05, 0.0, 0.003], [0.0, 0.04, 0.0], [0.003, 0.0, 0.06]],
                  position_com=[0.05, -0.02, -0.25], velocity_com=[0.0, 0.2, 0.5],
                  angular_velocity=[-0.2, 0.0, 0.8])  # fmt: skip
    contact = PointContact(a="a", b="b", point=[0.02, -0.01, 0.0], normal=[0.1, 0.05, 1.0],
                           restitution=0.6)  # fmt: skip
    return ImpactProblem(bodies={"a": a, "b": b}, contacts=[contact])


def baseline(problem: ImpactProblem) -> tuple[np.ndarray, float]:
    """The newcomer's closed form: P = -(1 + e) n.w' / (1/m_a + 1/m_b + ...), then the ledger."""
    c = problem.contacts[0]
    a, b = problem.bodies["a"], problem.bodies["b"]
    n, p = c.normal, c.point
    ra, rb = p - a.position_com, p - b.position_com
    ja, jb = np.linalg.inv(a.inertia_com), np.linalg.inv(b.inertia_com)
    w = (a.velocity_com + np.cross(a.angular_velocity, ra)) - (
        b.velocity_com + np.cross(b.angular_velocity, rb)
    )
    ran, rbn = np.cross(ra, n), np.cross(rb, n)
    k = 1 / a.mass + 1 / b.mass + ran @ ja @ ran + rbn @ jb @ rbn
    impulse = -(1 + c.restitution) * (n @ w) / k * n
    va = a.velocity_com + impulse / a.mass
    wa = a.angular_velocity + ja @ np.cross(ra, impulse)
    vb = b.velocity_com - impulse / b.mass
    wb = b.angular_velocity - jb @ np.cross(rb, impulse)
    e_after = 0.5 * (a.mass * va @ va + wa @ a.inertia_com @ wa + b.mass * vb @ vb
                     + wb @ b.inertia_com @ wb)  # fmt: skip
    return impulse, a.kinetic_energy() + b.kinetic_energy() - e_after


def build_sticking() -> ImpactProblem:
    """The same impact with a sticking contact (three rows: normal and two tangents)."""
    p = build()
    c = p.contacts[0]
    stick = PointContact(a=c.a, b=c.b, point=c.point, normal=c.normal,
                         restitution=c.restitution, tangential="stick")  # fmt: skip
    return ImpactProblem(bodies=p.bodies, contacts=[stick])


#: Run in a fresh process with one tree of the package on its path: prints two medians (s).
_PROBE = """
import statistics, sys, time
sys.path.insert(0, sys.argv[1])
sys.path.insert(0, sys.argv[2])
from bench_single_impact import build, build_sticking
from carnot import solve_impact
for make in (build, build_sticking):
    p = make()
    for _ in range(300):
        solve_impact(p)
    samples = []
    for _ in range(3000):
        t = time.perf_counter(); solve_impact(p); samples.append(time.perf_counter() - t)
    print(statistics.median(samples))
"""


def against(revision: str, rounds: int = 3) -> None:
    """Time this tree's and ``revision``'s prebuilt solves, alternating (see the docstring)."""
    here = Path(__file__).resolve().parent
    src_now = here.parent / "src"
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", str(here.parent), "archive", revision, "src"],
                                 check=True, capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        trees = {"now": str(src_now), revision: str(Path(tmp) / "src")}
        best: dict[str, list[float]] = {name: [1.0, 1.0] for name in trees}
        for _ in range(rounds):
            for name, src in trees.items():
                out = subprocess.run([sys.executable, "-c", _PROBE, src, str(here)],
                                     check=True, capture_output=True, text=True).stdout.split()
                best[name] = [min(a, float(b)) for a, b in zip(best[name], out, strict=True)]
    print(f"\nprebuilt solve, best median of {rounds} rounds   frictionless    sticking")
    for name, (free, stick) in best.items():
        print(f"  {name:<40} {free * 1e6:>9.1f} us {stick * 1e6:>8.1f} us")
    old, now = best[revision], best["now"]
    print(f"  {'speed-up (' + revision + ' / now)':<40} {old[0] / now[0]:>11.1f}x "
          f"{old[1] / now[1]:>9.1f}x")  # fmt: skip


def main() -> None:
    from carnot.solve import solve_pipeline  # here: the --against probe imports this module

    problem = build()
    ref_impulse, ref_ed = baseline(problem)
    res = solve_impact(problem)
    assert np.allclose(res.contacts[0].impulse, ref_impulse, rtol=1e-12)
    assert abs(res.energy.dissipated - ref_ed) <= 1e-12 * res.energy.before
    sticking = build_sticking()
    for fn in (lambda: baseline(problem), lambda: solve_impact(problem)):  # warm up
        timed(fn, 200)
    n = 3000
    rows = [
        ("baseline: hand-written NumPy closed form", summary(timed(lambda: baseline(problem), n))),
        ("carnot.solve_impact (prebuilt)", summary(timed(lambda: solve_impact(problem), n))),
        ("carnot.solve_impact (prebuilt, sticking)",
         summary(timed(lambda: solve_impact(sticking), n))),
        ("carnot: build + validate + solve", summary(timed(lambda: solve_impact(build()), n))),
        # the momentum check is made when first read (ImpactResult.momentum_later)
        ("  ... solve, then read the momentum check",
         summary(timed(lambda: solve_impact(problem).momentum, n))),
        ("  ... the general route (solve_pipeline)",
         summary(timed(lambda: solve_pipeline(problem), n))),
    ]  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "impact.toml"
        path.write_text(SCENARIO)
        cmd = [sys.executable, "-m", "carnot.cli", "solve", str(path), "--json"]
        subprocess.run(cmd, check=True, capture_output=True)
        rows.append(("carnot solve FILE --json (new process)",
                     summary(timed(lambda: subprocess.run(cmd, check=True, capture_output=True),
                                   15))))  # fmt: skip
        startup = [sys.executable, "-c", "pass"]
        rows.append(("  (python -c pass, for scale)",
                     summary(timed(lambda: subprocess.run(startup, check=True), 15))))  # fmt: skip
    base = rows[0][1][0]
    print(f"python {platform.python_version()}, numpy {np.__version__}, "
          f"{os.cpu_count()} cpus, {platform.machine()}")  # fmt: skip
    print(f"{'one frictionless two-body 3D point impact':<44} {'median':>11} {'IQR':>10} "
          f"{'/ baseline':>11}")  # fmt: skip
    for name, (median, iqr) in rows:
        print(f"{name:<44} {median * 1e6:>8.1f} us {iqr * 1e6:>7.1f} us {median / base:>10.1f}x")


if __name__ == "__main__":
    main()
    if "--against" in sys.argv:
        against(sys.argv[sys.argv.index("--against") + 1])

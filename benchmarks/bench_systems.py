"""Systems in generalized coordinates (issue 15): one impact of a 30-coordinate system with 4
contacts through the API, and a batch of 10^5 states of one model.

Measured against baselines in the same run, so that the ratios hold on a noisy machine:

* one impact: ``carnot.solve_impact`` on a prebuilt SystemProblem (target <= 1 ms) against
  the bare linear algebra of the same impact in NumPy (``numpy.linalg.solve`` of ``M`` for
  ``M^-1 W^T``, then of ``G`` for the impulses: the floor of any solver in Python);
* the batch: ``carnot.batch.systems.solve_systems`` over 10^5 states of a double pendulum
  striking the floor (frictionless, sticking, and Coulomb slip under Newton's and Stronge's
  hypotheses; target >= 100 k impacts/s) against the
  single-impact API called in a loop (timed on 1,000 states, rate per impact).

Run: ``.venv/bin/python benchmarks/bench_systems.py``.
"""

from __future__ import annotations

import math
import platform
import sys
from pathlib import Path

import numpy as np
from timing import best_of, summary, timed

from carnot import solve_impact
from carnot.batch.systems import solve_systems
from carnot.model.system import System, SystemContact, SystemProblem

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from chains import Chain  # noqa: E402  (the test suite's planar chains)


def big_problem(n: int = 30, contacts: int = 4, seed: int = 0) -> SystemProblem:
    """A random well-conditioned SPD mass matrix and 4 contacts with random Jacobians, every
    contact approaching (frictionless, Newton e = 0.5)."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, n))
    mass = a @ a.T / n + np.eye(n)
    q = rng.normal(size=n)
    items = []
    for k in range(contacts):
        jac = rng.normal(size=(3, n)) / math.sqrt(n)
        normal = np.array([0.0, 0.0, 1.0])
        jac[2] -= (jac[2] @ q + 1.0) / (q @ q) * q  # n . J q' = -1: approaching
        items.append(SystemContact(jacobian=jac, normal=normal, restitution=0.5,
                                   where=f"contacts[{k}]"))  # fmt: skip
    return SystemProblem(system=System(mass_matrix=mass, velocity=q), contacts=items)


def numpy_baseline(problem: SystemProblem) -> np.ndarray:
    """The same impact in bare NumPy: W from the normals, two solves."""
    m = problem.system.mass_matrix
    q = problem.system.velocity
    w = np.array([c.normal @ c.jacobian for c in problem.contacts])
    m_inv_wt = np.linalg.solve(m, w.T)
    wq = w @ q
    lam = np.linalg.solve(w @ m_inv_wt, -1.5 * wq)
    return q + m_inv_wt @ lam


def single() -> None:
    problem = big_problem()
    result = solve_impact(problem)
    baseline = numpy_baseline(problem)
    assert np.allclose(result.system.velocity_after, baseline, rtol=1e-10, atol=1e-12)
    api, api_iqr = summary(timed(lambda: solve_impact(problem), repeat=300, warm_up=30))
    bare, bare_iqr = summary(timed(lambda: numpy_baseline(problem), repeat=300, warm_up=30))
    print("One impact, 30 coordinates, 4 contacts (median of 300, IQR)")
    print(f"  carnot.solve_impact (prebuilt problem)   {api * 1e3:8.3f} ms  "
          f"(IQR {api_iqr * 1e3:.3f})   target <= 1 ms: {'met' if api <= 1e-3 else 'NOT met'}")
    print(f"  baseline: numpy.linalg.solve of M and G  {bare * 1e3:8.3f} ms  "
          f"(IQR {bare_iqr * 1e3:.3f})")
    print(f"  ratio API / baseline                     {api / bare:8.1f}")


def batch(count: int = 100_000) -> None:
    rng = np.random.default_rng(1)
    angles = np.column_stack([rng.uniform(-1.6, -1.0, count), rng.uniform(-1.2, -0.6, count)])
    rates = np.column_stack([rng.uniform(-1.5, -0.5, count), rng.uniform(-3, -1, count)])
    chains = [Chain(masses=[1.0, 0.8], lengths=[1.0, 0.7], angles=a.tolist(), rates=r.tolist())
              for a, r in zip(angles[:1000], rates[:1000], strict=True)]  # fmt: skip
    # the model's M(q) and J(q) for every state, vectorized (the chain's formulas)
    l1, l2, m1, m2 = 1.0, 0.7, 1.0, 0.8
    t1, t2 = angles[:, 0], angles[:, 1]
    c12 = np.cos(t1 - t2)
    mass = np.empty((count, 2, 2))
    mass[:, 0, 0] = m1 * l1**2 / 3 + m2 * l1**2
    mass[:, 0, 1] = mass[:, 1, 0] = m2 * l1 * l2 / 2 * c12
    mass[:, 1, 1] = m2 * l2**2 / 3
    jac = np.zeros((count, 1, 3, 2))
    jac[:, 0, 0, 0], jac[:, 0, 1, 0] = -l1 * np.sin(t1), l1 * np.cos(t1)
    jac[:, 0, 0, 1], jac[:, 0, 1, 1] = -l2 * np.sin(t2), l2 * np.cos(t2)
    assert np.allclose(mass[0], chains[0].mass_matrix()) and np.allclose(
        jac[0, 0], chains[0].jacobian(1, 0.7)
    )
    normals = np.broadcast_to(np.array([0.0, 1.0, 0.0]), (count, 1, 3))
    print(f"\nBatch of {count:,} states of a double pendulum striking the floor (best of 5)")
    for stick in (False, True):
        seconds = best_of(lambda s=stick: solve_systems(mass, rates, jac, normals, 0.5, stick=s), 5)
        out = solve_systems(mass, rates, jac, normals, 0.5, stick=stick)
        loop = best_of(lambda s=stick: [solve_impact(SystemProblem(
            system=System(mass_matrix=c.mass_matrix(), velocity=c.velocity),
            contacts=[SystemContact(jacobian=c.jacobian(1, 0.7), normal=[0, 1, 0],
                                    restitution=0.5, tangential="stick" if s else "slip")]))
            for c in chains[:200]], 3) / 200  # fmt: skip
        rate = count / seconds
        label = "stick" if stick else "frictionless"
        print(f"  {label:<13} solve_systems {seconds:7.3f} s = {rate / 1e3:8.0f} k impacts/s"
              f"  (target >= 100 k/s: {'met' if rate >= 1e5 else 'NOT met'}); "
              f"solve_impact in a loop {1 / loop / 1e3:6.1f} k/s: x{rate * loop:,.0f}")  # fmt: skip
        gap = np.abs(out.energy_before - out.energy_after - out.dissipated_theorem)
        gap /= out.energy_before
        # near-straight pendulums (J singular) make G ill-conditioned: the theorem's
        # agreement degrades with cond(G) there, in the single path as well
        cond = np.linalg.cond(jac[:, 0, :2, :]) if stick else np.ones(count)
        worst = int(np.argmax(gap))
        print(
            f"  {'':<13} |E_d direct - theorem| / E': median {float(np.median(gap)):.1e}, "
            f"max {float(gap[worst]):.1e} (cond J there {float(cond[worst]):.1e}); "
            f"above 1e-10 in {int(np.sum(gap > 1e-10))} states, of which "
            f"{int(np.sum((gap > 1e-10) & (cond > 1e3)))} with cond J > 1e3 (nearly straight)"
        )
    # Coulomb friction with slip (the batch Coulomb law on each state's 3 x 3 K), against
    # solve_impact in a loop on the same states, in the same run
    for law in ("newton", "stronge"):
        seconds = best_of(lambda h=law: solve_systems(mass, rates, jac, normals, 0.5,
                                                      friction=0.5, law=h), 5)  # fmt: skip
        out = solve_systems(mass, rates, jac, normals, 0.5, friction=0.5, law=law)
        loop = best_of(lambda h=law: [solve_impact(SystemProblem(
            system=System(mass_matrix=c.mass_matrix(), velocity=c.velocity),
            contacts=[SystemContact(jacobian=c.jacobian(1, 0.7), normal=[0, 1, 0],
                                    restitution=0.5, friction=0.5, law=h)]))
            for c in chains[:200]], 3) / 200  # fmt: skip
        rate = count / seconds
        regimes = np.bincount(out.regime, minlength=7)
        print(f"  {'coulomb ' + law:<13} solve_systems {seconds:7.3f} s = {rate / 1e3:8.0f} k "
              f"impacts/s  (target >= 100 k/s: {'met' if rate >= 1e5 else 'NOT met'}); "
              f"solve_impact in a loop {1 / loop / 1e3:6.1f} k/s: x{rate * loop:,.0f}; "
              f"regimes (slip, slip-stick, slip-reversal) {regimes[2:5].tolist()}")  # fmt: skip


if __name__ == "__main__":
    print(
        f"{platform.python_implementation()} {platform.python_version()}, "
        f"NumPy {np.__version__}, {platform.machine()}"
    )
    single()
    batch()

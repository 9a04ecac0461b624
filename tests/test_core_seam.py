"""Issue 19's defects that live in the solver core, fixed with the contact-space seam (issue 13):
a tiny inertia beside an ordinary mass (the normal row's freedom judged on its own scale; the
rank of G decided on the equilibrated operator), a grazing sticking contact without a NumPy
warning, a ledger that does not close flagged, idle bodies that take no columns.
"""

from __future__ import annotations

import tracemalloc
import warnings

import numpy as np
import pytest

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact

COURT = FixedBody(name="court")


def _ball(inertia: float, velocity, mass: float = 0.058, spin=(30.0, -80.0, 10.0)) -> RigidBody:
    return RigidBody(name="ball", mass=mass, inertia_com=np.eye(3) * inertia,
                     position_com=[0.0, 0.0, 0.033], velocity_com=velocity,
                     angular_velocity=spin)  # fmt: skip


def _solve(ball: RigidBody, **contact) -> object:
    c = PointContact(a="ball", b="court", point=[0, 0, 0], normal=[0, 0, 1], restitution=0.75,
                     **contact)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return solve_impact(ImpactProblem(bodies={"ball": ball, "court": COURT}, contacts=[c]))


def test_a_tiny_inertia_with_friction_solves() -> None:
    """Defect 7 (c0688 with J = 1e-20 instead of 1e-300, now refused at load). The contact
    point is below the centre of mass, so the normal impulse is the particle's, Poisson's
    ``(1 + e) m |v_n|``; the tangential inverse mass ``1/m + r^2/J`` is huge, so slip stops
    at once and the tangential impulse is ~0 (Stronge 2000, ch. 5)."""
    result = _solve(_ball(1e-20, [6.0, 2.0, -5.0]), friction=0.5, law="poisson")
    assert result.contacts[0].normal_impulse == pytest.approx(1.75 * 0.058 * 5.0, rel=1e-9)
    e = result.energy
    assert abs(e.dissipated - e.dissipated_theorem) <= 1e-9 * e.before


def test_a_tiny_inertia_sticking_contact_is_not_a_contradiction() -> None:
    """Defect 7 (c0748 with J = 1e-20): one sticking contact cannot contradict itself; the
    normal impulse is Newton's ``(1 + e) m |v_n|`` (the point is below the centre of mass)."""
    result = _solve(_ball(1e-20, [1.2, -1.6, -2.0], mass=2.0), friction=0.3, tangential="stick")
    assert result.contacts[0].normal_impulse == pytest.approx(1.75 * 2.0 * 2.0, rel=1e-9)


def test_a_grazing_sticking_contact_has_no_numpy_warning() -> None:
    """Defect 4/3 inside the solver: an approach speed of 1e-320 m/s (accepted: a velocity
    has no lower bound) and a sticking contact."""
    result = _solve(_ball(1e-4, [1.0, 0.0, -1e-320], spin=(0, 0, 0)), friction=0.3,
                    tangential="stick")  # fmt: skip
    assert result.contacts[0].friction_required == np.inf
    assert "friction_insufficient" in result.flag_codes()


def test_a_ledger_that_does_not_close_is_not_returned_silently() -> None:
    ball = RigidBody(name="ball", mass=1e-50, inertia_com=np.eye(3) * 1e-50,
                     position_com=[0, 0, 0.033])  # fmt: skip
    contact = PointContact(a="ball", b="court", point=[1e50] * 3, normal=[0, 0, 1],
                           impulse=[1e50] * 3, moment=[1e50] * 3)  # fmt: skip
    result = solve_impact(ImpactProblem(bodies={"ball": ball, "court": COURT}, contacts=[contact]))
    e = result.energy
    closes = abs(e.dissipated - e.dissipated_theorem) <= 1e-9 * (e.before + e.after)
    assert closes or any("ledger" in code for code in result.flag_codes())


def _idle_scene(idle: int) -> ImpactProblem:
    bodies: dict[str, RigidBody | FixedBody] = {
        f"idle{i}": RigidBody(name=f"idle{i}", mass=1.0, inertia_com=np.eye(3) * 0.004,
                              position_com=[10.0 * i, 5.0, 0.0])  # fmt: skip
        for i in range(idle)
    }
    bodies["ball"] = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3) * 0.004,
                               position_com=[0, 0, 0.1], velocity_com=[0, 0, -2.0])  # fmt: skip
    bodies["floor"] = FixedBody(name="floor")
    contact = PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1], restitution=0.5)
    return ImpactProblem(bodies=bodies, contacts=[contact])


def _peak_bytes(problem: ImpactProblem) -> int:
    tracemalloc.start()
    try:
        result = solve_impact(problem)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
        assert result.bodies["ball"].velocity_after[2] == pytest.approx(1.0)


def test_idle_bodies_cost_memory_in_proportion() -> None:
    """Defect 8, measured as memory (deterministic, unlike time): four times the idle bodies
    must take at most about four times the peak memory, not sixteen."""
    small, large = _peak_bytes(_idle_scene(50)), _peak_bytes(_idle_scene(200))
    assert large <= 6 * small

"""Contact space (carnot.space) and the free-body producer (carnot.model.free_bodies).

Two routes throughout: the closed-form Jacobian of free bodies (``r x c_lin`` by cross products)
against the generic ``W_i = C_i J_i``; the Schur complement of held rows against the explicit
elimination of the held impulses; the pipeline's pin reaction against the textbook closed form.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carnot import FixedBody, ImpactProblem, Pin, PointContact, RigidBody, solve_impact
from carnot.errors import InputError
from carnot.model.free_bodies import assemble
from carnot.space import ContactSpace


def _random_body(rng: np.random.Generator, name: str) -> RigidBody:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moments = rng.uniform(1.0, 2.0, 3)
    return RigidBody(name=name, mass=rng.uniform(0.5, 3.0),
                     inertia_com=q @ np.diag(moments) @ q.T,
                     position_com=rng.normal(size=3), velocity_com=rng.normal(size=3),
                     angular_velocity=rng.normal(size=3))  # fmt: skip


@pytest.mark.parametrize("seed", range(5))
def test_free_body_jacobian_equals_rows_times_motion(seed: int) -> None:
    """W from cross products equals C_i J_i computed generically, and w = J u equals the
    bodies' point velocities v + omega x r (conventions.py)."""
    rng = np.random.default_rng(seed)
    a, b = _random_body(rng, "a"), _random_body(rng, "b")
    point = rng.normal(size=3)
    items = [
        PointContact(a="a", b="b", point=point, normal=rng.normal(size=3), tangential="stick"),
        Pin(body="a", point=rng.normal(size=3), other="b", where="constraints[0]"),
    ]
    problem = ImpactProblem(bodies={"a": a, "b": b}, contacts=items[:1], constraints=items[1:])
    fb = assemble(problem, items, [i.rows() for i in items])
    s = fb.space
    generic = ContactSpace(u_before=s.u_before, mass_matrix=s.mass_matrix,
                           mass_matrix_inv=s.mass_matrix_inv, motion=s.motion, blocks=s.blocks)
    np.testing.assert_allclose(s.jacobian, generic.jacobian, rtol=0, atol=1e-13)
    w, omega = s.motion_at(0, s.u_before)
    direct = a.velocity_of_point(point) - b.velocity_of_point(point)
    np.testing.assert_allclose(w, direct, rtol=0, atol=1e-13)
    np.testing.assert_allclose(omega, a.angular_velocity - b.angular_velocity, atol=1e-15)
    g = s.delassus()
    np.testing.assert_allclose(g, g.T, atol=1e-13)
    assert np.all(np.linalg.eigvalsh(g) > -1e-12)


def test_held_schur_equals_explicit_elimination() -> None:
    """The contact's K with held rows folded in equals solving the held impulses explicitly:
    for any contact impulse P, Lambda_h = -G_hh^-1 (w_h + G_hc P) leaves the held rows at 0 and
    the contact rows at w' + K P."""
    rng = np.random.default_rng(7)
    a, b = _random_body(rng, "a"), _random_body(rng, "b")
    items = [PointContact(a="a", b="b", point=rng.normal(size=3), normal=[0, 0, 1],
                          friction=0.5),
             Pin(body="b", point=rng.normal(size=3), where="constraints[0]")]  # fmt: skip
    problem = ImpactProblem(bodies={"a": a, "b": b}, contacts=items[:1], constraints=items[1:])
    s = assemble(problem, items, [i.rows() for i in items]).space
    contact, held = s.slices[0], np.arange(s.slices[1].start, s.slices[1].stop)
    u = s.u_before
    k, w_c = s.held_schur(contact, held, u)
    p = rng.normal(size=3)
    w_h = s.row_velocities(u, held) + s.coupling(held, contact) @ p
    lam_h = -np.linalg.solve(s.delassus(held), w_h)
    impulses = np.zeros(s.size)
    impulses[contact], impulses[held] = p, lam_h
    u_after = u + s.velocity_change(impulses)
    np.testing.assert_allclose(s.row_velocities(u_after, held), 0, atol=1e-12)
    np.testing.assert_allclose(s.row_velocities(u_after, contact), w_c + k @ p, atol=1e-12)


def test_bodies_in_no_contact_take_no_columns() -> None:
    """Idle bodies keep their motion and energy and cost no columns (the cost follows the
    bodies that take part: issue 19's 2000 idle bodies)."""
    bodies: dict[str, RigidBody | FixedBody] = {
        f"idle{i}": RigidBody(name=f"idle{i}", mass=1.0, inertia_com=np.eye(3),
                              position_com=[3.0 * i, 5, 0], velocity_com=[0, 1.0, 0])
        for i in range(300)
    }  # fmt: skip
    bodies["ball"] = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3) * 0.4,
                               velocity_com=[0, 0, -1.0])  # fmt: skip
    bodies["floor"] = FixedBody(name="floor")
    contact = PointContact(a="ball", b="floor", point=[0, 0, -1.0], normal=[0, 0, 1],
                           restitution=0.5)  # fmt: skip
    problem = ImpactProblem(bodies=bodies, contacts=[contact])
    fb = assemble(problem, [contact], [contact.rows()])
    assert list(fb.columns) == ["ball"] and fb.space.mass_matrix.shape == (6, 6)
    res = solve_impact(problem)
    assert res.bodies["ball"].velocity_after.tolist() == [0.0, 0.0, 0.5]
    assert res.bodies["idle7"].velocity_after.tolist() == [0.0, 1.0, 0.0]
    assert res.energy.before == pytest.approx(0.5 + 300 * 0.5, rel=1e-15)
    assert res.energy.dissipated == pytest.approx(0.5 * (1 - 0.25), rel=1e-12)
    assert res.energy.dissipated == pytest.approx(res.energy.dissipated_theorem, rel=1e-12)


def test_pin_at_rest_to_round_off_is_accepted_and_its_reaction_is_the_closed_form() -> None:
    """A rod pivoted at one end, its state computed in floating point (the pivot's velocity is
    round-off, not 0), strikes a stop with its tip (issue 15's defect). Closed forms for a
    uniform rod of mass m and length L about its end (Beer and Johnston, Vector Mechanics,
    impulse and angular momentum about the pivot): the tip impulse is
    P = (1 + e) (m L / 3) omega' and the pivot's reaction (1 + e) m L omega' / 6."""
    m, length, e = 2.0, 1.2, 0.4
    theta, omega = 1.1, 3.1
    axis = np.array([math.cos(theta), math.sin(theta), 0.0])
    centre = 0.5 * length * axis
    # omega x centre written out: in floating point the pivot then moves at ~2e-16 m/s
    velocity = 0.5 * length * omega * np.array([-math.sin(theta), math.cos(theta), 0.0])
    i_perp = m * length**2 / 12  # a slender rod; a tiny moment about its own axis
    inertia = i_perp * (np.eye(3) - np.outer(axis, axis)) + 1e-6 * i_perp * np.outer(axis, axis)
    link = RigidBody(name="rod", mass=m, inertia_com=inertia,
                     position_com=centre, velocity_com=velocity,
                     angular_velocity=[0, 0, omega])  # fmt: skip
    assert np.linalg.norm(link.velocity_of_point([0.0, 0.0, 0.0])) > 0  # round-off, not 0
    tip = length * axis
    normal = -np.cross([0.0, 0.0, 1.0], axis)  # against the tip's motion
    problem = ImpactProblem(
        bodies={"rod": link, "stop": FixedBody(name="stop")},
        contacts=[PointContact(a="rod", b="stop", point=tip, normal=normal, restitution=e)],
        constraints=[Pin(body="rod", point=[0.0, 0.0, 0.0], where="constraints[0]")],
    )
    res = solve_impact(problem)
    assert res.bodies["rod"].angular_velocity_after[2] == pytest.approx(-e * omega, rel=1e-12)
    assert res.contacts[0].normal_impulse == pytest.approx((1 + e) * m * length / 3 * omega,
                                                           rel=1e-12)  # fmt: skip
    reaction = res.constraints[0].impulse
    assert np.linalg.norm(reaction) == pytest.approx((1 + e) * m * length * omega / 6, rel=1e-12)
    assert res.energy.dissipated == pytest.approx(res.energy.dissipated_theorem, rel=1e-12)


def test_a_pin_on_a_moving_point_is_still_refused() -> None:
    link = RigidBody(name="rod", mass=1.0, inertia_com=np.eye(3) * 0.1,
                     velocity_com=[1e-6, 0, 0])  # fmt: skip
    with pytest.raises(InputError, match="constraints\\[0\\]: a pin needs zero relative"):
        solve_impact(ImpactProblem(bodies={"rod": link},
                                   constraints=[Pin(body="rod", point=[0, 0, 0],
                                                    where="constraints[0]")]))  # fmt: skip

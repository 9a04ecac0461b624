"""simulate/impacts.py's parts of an impact: validated once, cached by value and bounded, the
same as built from scratch."""

from __future__ import annotations

import numpy as np
import pytest

from carnot.errors import InputError
from carnot.laws.multiple import ContactRows
from carnot.model import FixedBody, ImpactProblem, PointContact, RigidBody
from carnot.simulate import impacts
from carnot.simulate.motion import BodyState, SimBody, quat_matrix
from carnot.simulate.shapes import Sphere

_INERTIA = np.diag([1e-3, 2e-3, 2.5e-3])


def _body(name: str = "b", mass: float = 1.0) -> SimBody:
    return SimBody(name=name, mass=mass, inertia_body=_INERTIA.copy(), shape=Sphere(radius=0.1))


def _state(q: list[float]) -> BodyState:
    q_ = np.array(q) / np.linalg.norm(q)
    return BodyState(position=np.array([0.0, 1.0, 0.0]), orientation=q_,
                     velocity=np.array([0.1, -2.0, 0.0]),
                     angular_velocity=np.array([0.0, 0.5, 3.0]))  # fmt: skip


def test_a_turned_body_is_the_one_built_in_world_axes() -> None:
    state = _state([0.9, 0.1, -0.3, 0.2])
    fast = impacts._rigid_body(_body(), state)
    rot = quat_matrix(state.orientation)
    slow = RigidBody(name="b", mass=1.0, inertia_com=rot @ _INERTIA @ rot.T,
                     position_com=state.position, velocity_com=state.velocity,
                     angular_velocity=state.angular_velocity)  # fmt: skip
    np.testing.assert_allclose(fast.inertia_com, slow.inertia_com, rtol=0, atol=1e-18)
    np.testing.assert_allclose(fast.inertia_com_inv, slow.inertia_com_inv, rtol=1e-12)
    assert fast.float_state[2:] == slow.float_state[2:]
    assert fast.kinetic_energy() == pytest.approx(slow.kinetic_energy(), rel=1e-14)


def test_the_caches_are_keyed_on_values_and_bounded() -> None:
    state = _state([1.0, 0.0, 0.0, 0.0])
    first = impacts.body_template(_body())
    assert impacts.body_template(_body()) is first  # another body, the same values
    assert impacts.body_template(_body(mass=2.0)) is not first
    for k in range(impacts.TEMPLATES_KEPT + 10):
        impacts._rigid_body(_body(mass=1.0 + k), state)
    assert impacts._template_of.cache_info().currsize <= impacts.TEMPLATES_KEPT
    assert impacts._oriented.cache_info().currsize <= impacts.ORIENTED_KEPT


def test_a_signed_zero_in_the_orientation_is_its_own_entry() -> None:
    body = _body()
    plus, minus = _state([1.0, 0.0, 0.0, 0.0]), _state([1.0, -0.0, 0.0, 0.0])
    a, b = impacts._rigid_body(body, plus), impacts._rigid_body(body, minus)
    assert np.array_equal(a.inertia_com, b.inertia_com)  # (the same values, each its own)
    assert impacts._oriented(body.value_key, impacts.exact_key(minus.orientation.tolist())) \
        is not impacts._oriented(body.value_key, impacts.exact_key(plus.orientation.tolist()))


def test_a_moved_body_and_contact_refuse_what_is_not_finite() -> None:
    body = RigidBody(name="b", mass=1.0, inertia_com=np.eye(3))
    with pytest.raises(InputError, match="bodies.b.velocity"):
        body.moved([0.0, 0.0, 0.0], [0.0, np.inf, 0.0], [0.0, 0.0, 0.0])
    contact = PointContact(a="b", b="floor", point=[0, 0, 0], normal=[0, 0, 1])
    with pytest.raises(InputError, match=r"contacts\[0\].point"):
        contact.at([0.0, np.nan, 0.0])
    with pytest.raises(InputError, match="patch"):
        PointContact(a="b", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                     patch=[[0, 0, 0]]).at([1.0, 0.0, 0.0])  # fmt: skip
    with pytest.raises(InputError, match="proper rotation"):
        body.turned(2 * np.eye(3))


def test_the_one_contact_problem_is_the_constructors() -> None:
    ball = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3), velocity_com=[0, 0, -1])
    floor = FixedBody(name="floor")
    contact = PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1])
    fast = ImpactProblem.one_contact(body=ball, other=floor, contact=contact, title="t")
    slow = ImpactProblem(bodies={"ball": ball, "floor": floor}, contacts=[contact], title="t")
    assert vars(fast) == vars(slow) and list(vars(fast)) == list(vars(slow))
    with pytest.raises(InputError, match="must name the body"):
        ImpactProblem.one_contact(body=RigidBody(name="other", mass=1.0, inertia_com=np.eye(3)),
                                  other=floor, contact=contact)  # fmt: skip


def test_contact_rows_of_a_contact_are_the_constructors() -> None:
    c = PointContact(a="a", b="b", point=[0, 0, 0], normal=[0, 0, 1], restitution=0.3,
                     friction=0.4, tangential="stick", stiffness=2.0, exponent=1.0)  # fmt: skip
    fast = ContactRows.of_contact(c, normal=3, tangents=(4, 5))
    slow = ContactRows(normal=3, tangents=(4, 5), restitution=0.3, friction=0.4, stick=True,
                       stiffness=2.0, exponent=1.0, name="contacts[0]")  # fmt: skip
    assert fast == slow and list(vars(fast)) == list(vars(slow))
    with pytest.raises(InputError, match="needs tangent rows"):
        ContactRows.of_contact(c, normal=0)
    with pytest.raises(InputError, match="row index"):
        ContactRows.of_contact(c, normal=True, tangents=(1, 2))


def test_a_state_after_an_impact_keeps_its_rotation() -> None:
    state = _state([0.9, 0.1, -0.3, 0.2])
    rotation = state.rotation
    after = state.with_motion(np.zeros(3), np.ones(3))
    assert after.rotation is rotation and after.position is state.position
    made = BodyState.from_floats(state.position.tolist(), state.orientation.tolist(),
                                 [0.0] * 3, [0.0] * 3, rotation=True)  # fmt: skip
    assert np.array_equal(made.rotation, quat_matrix(state.orientation))
    # (both made by BodyState's own methods: every field, in __init__'s order)
    for fast in (after, made):
        slow = BodyState(position=fast.position, orientation=fast.orientation,
                         velocity=fast.velocity, angular_velocity=fast.angular_velocity)
        assert list(vars(fast))[:4] == list(vars(slow))

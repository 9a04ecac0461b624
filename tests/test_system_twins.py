"""Two front ends, one answer (issue 15, DESIGN.md section 7): the same planar chain as free
rigid bodies joined by pins and as a system in generalized coordinates (tests/chains.py)
must give the same velocities, impulses and energy ledger under every law, to 1e-10; in each,
the theorem equals the direct kinetic-energy difference to 1e-12.

The two are independent routes: the free bodies' contact space is assembled from 6 columns
per body with the joints as pins (their impulses solved with the impact), the system's from
the reduced mass matrix ``M(q)`` and the point Jacobians, with no joint impulses at all.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from chains import Chain

from carnot import ImpactProblem, PointConstraint, PointContact, solve_impact
from carnot.model.system import System, SystemConstraint, SystemContact, SystemProblem
from carnot.result import ImpactResult

TOL = 1e-10


def double_pendulum(**kw: Any) -> Chain:
    return Chain(
        masses=[1.0, 0.8],
        lengths=[1.0, 0.7],
        angles=[math.radians(-80), math.radians(-60)],
        rates=[-1.0, -2.5],
        **kw,
    )


def cart_pole() -> Chain:
    return Chain(
        masses=[0.5],
        lengths=[1.0],
        angles=[math.radians(-60)],
        rates=[-2.0],
        base="cart",
        base_position=[0.3, 0.0],
        base_rate=[1.0],
    )


def three_link() -> Chain:
    return Chain(
        masses=[1.0, 0.7, 0.4],
        lengths=[0.8, 0.6, 0.5],
        angles=[math.radians(-70), math.radians(-40), math.radians(-10)],
        rates=[-0.8, -1.5, -2.2],
    )


def twins(
    chain: Chain,
    contacts: list[tuple[int, float, dict[str, Any]]],
    fasten: tuple[int, float] | None = None,
    base_pin: bool = False,
) -> tuple[ImpactResult, ImpactResult]:
    """Solve the chain both ways: ``contacts`` (link, distance along it, contact keys) against
    the ground; ``fasten`` a point (link, distance) to the world; ``base_pin`` pins a
    floating base at its point (the system's ``pin``; the free bodies' base pin)."""
    sys_contacts = []
    fb_contacts = []
    for k, (link, d, keys) in enumerate(contacts):
        point = chain.point(link, d)
        sys_contacts.append(
            SystemContact(
                jacobian=chain.jacobian(link, d), point=point, where=f"contacts[{k}]", **keys
            )
        )
        fb_contacts.append(
            PointContact(
                a=f"link{link + 1}", b="ground", point=point, where=f"contacts[{k}]", **keys
            )
        )
    sys_constraints = []
    fb_constraints = []
    if fasten is not None:
        link, d = fasten
        sys_constraints.append(SystemConstraint(kind="fasten", jacobian=chain.jacobian(link, d)))
        fb_constraints.append(
            PointConstraint(kind="fasten", body=f"link{link + 1}", point=chain.point(link, d))
        )
    if base_pin:
        sys_constraints.append(
            SystemConstraint(
                kind="pin",
                jacobian=chain.base_jacobian(),
                where=f"constraints[{len(sys_constraints)}]",
            )
        )
        fb_constraints.append(
            PointConstraint(
                kind="pin",
                body="link1",
                point=chain.base_point(),
                where=f"constraints[{len(fb_constraints)}]",
            )
        )
    system = System(
        mass_matrix=chain.mass_matrix(), velocity=chain.velocity, coordinates=chain.coordinates
    )
    generalized = solve_impact(
        SystemProblem(system=system, contacts=sys_contacts, constraints=sys_constraints)
    )
    if chain.base == "cart":
        fb_contacts.append(chain.rail(f"contacts[{len(fb_contacts)}]"))
    pins = chain.joint_pins(first=len(fb_constraints))
    if base_pin:
        pins = pins[:]  # the floating base's pin is already the item under test
    bodies = solve_impact(
        ImpactProblem(
            bodies=chain.bodies(), contacts=fb_contacts, constraints=[*fb_constraints, *pins]
        )
    )
    return generalized, bodies


def assert_agree(chain: Chain, generalized: ImpactResult, bodies: ImpactResult) -> None:
    assert generalized.system is not None
    q_after = generalized.system.velocity_after
    scale = float(np.linalg.norm(chain.velocity)) * max(chain.lengths)
    for name, (v, omega) in chain.body_velocities(q_after).items():
        assert np.allclose(v, bodies.bodies[name].velocity_after, rtol=0, atol=TOL * scale), name
        assert np.allclose(
            omega, bodies.bodies[name].angular_velocity_after, rtol=0, atol=TOL * scale
        ), name
    impulse_scale = max(
        float(np.linalg.norm(o.impulse)) for o in (*bodies.contacts, *bodies.constraints)
    )
    for g, f in zip(generalized.contacts, bodies.contacts, strict=False):  # the rail is extra
        assert np.allclose(g.impulse, f.impulse, rtol=0, atol=TOL * impulse_scale), g.where
        assert np.allclose(g.moment, f.moment, rtol=0, atol=TOL * impulse_scale), g.where
        assert g.regime == f.regime
        assert g.dissipated == pytest.approx(f.dissipated, rel=0, abs=TOL * bodies.energy.before)
    for g, f in zip(generalized.constraints, bodies.constraints, strict=False):
        assert g.kind == f.kind
        assert np.allclose(g.impulse, f.impulse, rtol=0, atol=TOL * impulse_scale), g.where
    e_g, e_f = generalized.energy, bodies.energy
    for key in (
        "before",
        "after",
        "dissipated",
        "dissipated_theorem",
        "lost_velocities",
        "carnot_condition",
        "dissipated_normal",
        "dissipated_tangential",
    ):
        assert getattr(e_g, key) == pytest.approx(getattr(e_f, key), rel=0, abs=TOL * e_f.before), (
            key
        )
    for result in (generalized, bodies):
        assert result.energy.dissipated == pytest.approx(
            result.energy.dissipated_theorem, rel=0, abs=1e-12 * result.energy.before
        )
    assert generalized.system.momentum_residual < 1e-12
    # the same flags, but for the free cart's rail (at rest, so "not approaching"); the
    # system's out-of-plane rows carry nothing and raise nothing
    rail = f"contacts[{len(generalized.contacts)}]"
    assert sorted((w.code, w.where) for w in generalized.warnings) == sorted(
        (w.code, w.where) for w in bodies.warnings if w.where != rail
    )
    assert "statically_indeterminate" not in generalized.flag_codes()


FRICTIONLESS = {"normal": [0, 1, 0], "restitution": 0.5}

DOUBLE_PENDULUM_CASES = {
    "newton": FRICTIONLESS,
    "poisson": {**FRICTIONLESS, "law": "poisson"},
    "stronge": {**FRICTIONLESS, "law": "stronge"},
    "stick": {"normal": [0, 1, 0], "restitution": 0.3, "tangential": "stick"},
    "stick-tilted-normal": {"normal": [0.3, 1, 0], "restitution": 0.2, "tangential": "stick"},
    "slip-newton": {"normal": [0, 1, 0], "restitution": 0.0, "friction": 0.1},
    "slip-poisson": {"normal": [0, 1, 0], "restitution": 0.5, "friction": 0.1, "law": "poisson"},
    "reversal-stronge": {
        "normal": [0, 1, 0],
        "restitution": 1.0,
        "friction": 0.1,
        "law": "stronge",
    },
    "slip-stick-newton": {"normal": [0, 1, 0], "restitution": 1.0, "friction": 0.8},
    "slip-stick-tilted": {
        "normal": [-0.2, 1, 0],
        "restitution": 0.5,
        "friction": 0.8,
        "law": "poisson",
    },
    "given": {"normal": [0, 1, 0], "impulse": [0.3, 1.2, 0.0]},
}


@pytest.mark.parametrize("case", DOUBLE_PENDULUM_CASES)
def test_double_pendulum_every_law(case: str) -> None:
    chain = double_pendulum()
    generalized, bodies = twins(chain, [(1, 0.7, DOUBLE_PENDULUM_CASES[case])])
    assert_agree(chain, generalized, bodies)


def test_double_pendulum_regimes_are_the_ones_named() -> None:
    """The friction cases above reach each regime of the impulse-space integration."""
    chain = double_pendulum()
    regimes = {
        case: twins(chain, [(1, 0.7, DOUBLE_PENDULUM_CASES[case])])[0].contacts[0].regime
        for case in ("slip-newton", "reversal-stronge", "slip-stick-newton")
    }
    assert regimes == {
        "slip-newton": "slip",
        "reversal-stronge": "slip-reversal",
        "slip-stick-newton": "slip-stick",
    }


def test_double_pendulum_two_contacts_at_once() -> None:
    """The elbow and the tip land together (frictionless, simultaneous equalities)."""
    chain = double_pendulum()
    generalized, bodies = twins(
        chain,
        [
            (1, 0.0, {"normal": [0, 1, 0], "restitution": 0.2}),
            (1, 0.7, {"normal": [0, 1, 0], "restitution": 0.6}),
        ],
    )
    assert_agree(chain, generalized, bodies)
    assert len(generalized.contacts) == 2


def test_double_pendulum_fastened_tip() -> None:
    chain = double_pendulum()
    generalized, bodies = twins(chain, [], fasten=(1, 0.7))
    assert_agree(chain, generalized, bodies)
    tip = chain.jacobian(1, 0.7) @ generalized.system.velocity_after
    assert np.linalg.norm(tip) < 1e-12


@pytest.mark.parametrize(
    "keys",
    [FRICTIONLESS, DOUBLE_PENDULUM_CASES["slip-stick-newton"], DOUBLE_PENDULUM_CASES["stick"]],
)
def test_floating_base_held_by_a_pin(keys: dict[str, Any]) -> None:
    """The double pendulum with its base point as two more coordinates, held by a system
    ``pin``: the pin's impulse equals the free bodies' base pin's."""
    chain = double_pendulum(base="floating", base_position=[0.0, 0.0], base_rate=[0.0, 0.0])
    generalized, bodies = twins(chain, [(1, 0.7, keys)], base_pin=True)
    assert_agree(chain, generalized, bodies)
    assert generalized.constraints[0].kind == "pin"
    assert np.linalg.norm(generalized.constraints[0].impulse) > 0.1


@pytest.mark.parametrize(
    "keys",
    [
        {"normal": [1, 0.2, 0], "restitution": 0.4},
        {"normal": [1, 0.2, 0], "restitution": 0.0, "tangential": "stick"},
    ],
)
def test_cart_pole(keys: dict[str, Any]) -> None:
    """The pole's tip strikes a wall; the free cart rides a frictionless rail (a surface
    contact at rest, e = 0) where the generalized coordinates simply have no height."""
    chain = cart_pole()
    generalized, bodies = twins(chain, [(0, 1.0, keys)])
    assert_agree(chain, generalized, bodies)


def test_cart_pole_fastened_tip() -> None:
    chain = cart_pole()
    generalized, bodies = twins(chain, [], fasten=(0, 1.0))
    assert_agree(chain, generalized, bodies)


@pytest.mark.parametrize(
    "keys",
    [
        {"normal": [0, 1, 0], "restitution": 0.5},
        {"normal": [0, 1, 0], "restitution": 0.5, "tangential": "stick"},
        {"normal": [0, 1, 0], "restitution": 0.5, "friction": 0.3, "law": "stronge"},
    ],
)
def test_three_link_chain(keys: dict[str, Any]) -> None:
    chain = three_link()
    generalized, bodies = twins(chain, [(2, 0.5, keys)])
    assert_agree(chain, generalized, bodies)

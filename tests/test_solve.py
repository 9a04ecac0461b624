"""The simultaneous solve: given impulses, redundancy, conflicts, and the flags."""

from __future__ import annotations

import numpy as np
import pytest

from carnot import (
    Fasten,
    FixedBody,
    ImpactProblem,
    InputError,
    Pin,
    PointContact,
    RigidBody,
    solve_impact,
)


def _box(**kw) -> RigidBody:
    args = {"name": "box", "mass": 2.0, "inertia_com": np.diag([0.1, 0.2, 0.25]),
            "position_com": [0.0, 0.0, 0.5], "velocity_com": [0.5, 0.0, -1.0],
            "angular_velocity": [0.3, -0.2, 0.1]}  # fmt: skip
    return RigidBody(**{**args, **kw})


FLOOR = FixedBody(name="floor")


def _problem(*contacts, constraints=(), box=None) -> ImpactProblem:
    return ImpactProblem(bodies={"box": box or _box(), "floor": FLOOR}, contacts=contacts,
                         constraints=constraints)  # fmt: skip


def test_given_impulse_is_applied_by_hand() -> None:
    """u'' = u' + M^-1 W^T P, by hand: dv = P/m, d omega = J^-1 (r x P + M_P)."""
    p, mp = np.array([0.2, -0.1, 1.5]), np.array([0.0, 0.05, 0.0])
    point = np.array([0.1, 0.2, 0.0])
    res = solve_impact(_problem(PointContact(a="box", b="floor", point=point, normal=[0, 0, 1],
                                             impulse=p, moment=mp)))  # fmt: skip
    box = _box()
    assert np.allclose(res.bodies["box"].velocity_after, box.velocity_com + p / box.mass)
    dw = np.linalg.solve(box.inertia_com, np.cross(point - box.position_com, p) + mp)
    assert np.allclose(res.bodies["box"].angular_velocity_after, box.angular_velocity + dw)
    assert res.contacts[0].regime == "given"
    e = res.energy
    assert e.dissipated == pytest.approx(e.dissipated_theorem, rel=1e-12)


def test_redundant_consistent_is_flagged_and_the_motion_unique() -> None:
    """Two fastenings of the same point: the split is indeterminate, the motion is not."""
    once = solve_impact(_problem(constraints=[Fasten(body="box", point=[0, 0, 0])]))
    twice = solve_impact(_problem(constraints=[
        Fasten(body="box", point=[0, 0, 0], where="constraints[0]"),
        Fasten(body="box", point=[0, 0, 0], where="constraints[1]")]))  # fmt: skip
    assert once.warnings == ()
    assert twice.flag_codes() == ["statically_indeterminate"]
    assert np.allclose(once.bodies["box"].angular_velocity_after,
                       twice.bodies["box"].angular_velocity_after)  # fmt: skip
    # minimum norm: the two share the impulse equally
    assert np.allclose(twice.constraints[0].impulse, once.constraints[0].impulse / 2)
    assert np.allclose(twice.constraints[1].impulse, once.constraints[0].impulse / 2)


def test_negative_normal_impulse_and_not_approaching_are_flagged() -> None:
    box = _box(velocity_com=[0.0, 0.0, 1.0], angular_velocity=[0, 0, 0])  # moving away
    res = solve_impact(
        _problem(
            PointContact(a="box", b="floor", point=[0, 0, 0], normal=[0, 0, 1], restitution=0.5),
            box=box,
        )
    )
    assert res.flag_codes() == ["not_approaching", "negative_normal_impulse"]


def test_friction_insufficient_for_sticking() -> None:
    contact = PointContact(a="box", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                           restitution=0.0, tangential="stick", friction=0.01)  # fmt: skip
    res = solve_impact(_problem(contact))
    assert res.contacts[0].friction_required > 0.01
    assert res.flag_codes() == ["friction_insufficient"]
    generous = PointContact(a="box", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                            restitution=0.0, tangential="stick", friction=100.0)  # fmt: skip
    assert solve_impact(_problem(generous)).warnings == ()


def test_centre_of_pressure_inside_and_outside_the_patch() -> None:
    """A box landing flat, face on a floor: rotation about x makes one edge strike first."""
    square = [[0.2, 0.2, 0], [-0.2, 0.2, 0], [-0.2, -0.2, 0], [0.2, -0.2, 0]]
    flat = _box(angular_velocity=[0, 0, 0])
    res = solve_impact(_problem(PointContact(a="box", b="floor", point=[0, 0, 0],
                                             normal=[0, 0, 1], restitution=0.3, patch=square),
                                box=flat))  # fmt: skip
    assert res.warnings == ()
    assert np.allclose(res.contacts[0].centre_of_pressure, [0, 0, 0], atol=1e-12)
    # Flat landing: the whole face stops (e = 0.3 at every point), no rotation after.
    assert np.allclose(res.bodies["box"].angular_velocity_after, 0, atol=1e-12)
    # The same patch, with a spin that lifts one side: the face cannot pull it down.
    lifting = _box(velocity_com=[0, 0, -0.1], angular_velocity=[3.0, 0, 0])
    res = solve_impact(_problem(PointContact(a="box", b="floor", point=[0, 0, 0],
                                             normal=[0, 0, 1], restitution=0.3, patch=square),
                                box=lifting))  # fmt: skip
    assert "centre_of_pressure_outside_patch" in res.flag_codes()


def test_unsupported_cases_are_refused_not_guessed() -> None:
    rough = [
        PointContact(a="box", b="floor", point=[x, 0, 0], normal=[0, 0, 1], restitution=0.5,
                     friction=0.3, where=f"contacts[{i}]")
        for i, x in enumerate((0.1, -0.1))
    ]  # fmt: skip
    # several frictional contacts: the simultaneous law (issue 14), no longer refused
    both = solve_impact(_problem(*rough))
    assert both.multiple_impact == "simultaneous" and both.complementarity_residual < 1e-12
    patch = [[0.1, 0.1, 0], [-0.1, 0.1, 0], [-0.1, -0.1, 0], [0.1, -0.1, 0]]
    with pytest.raises(InputError, match="over a contact patch"):
        solve_impact(_problem(PointContact(a="box", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                                           friction=0.3, patch=patch)))  # fmt: skip
    two = [
        PointContact(
            a="box",
            b="floor",
            point=[x, 0, 0],
            normal=[0, 0, 1],
            restitution=0.5,
            law="poisson",
            where=f"contacts[{i}]",
        )
        for i, x in enumerate((0.1, -0.1))
    ]
    with pytest.raises(InputError, match="Poisson's and Stronge's"):
        solve_impact(_problem(*two))


def test_poisson_and_stronge_equal_newton_for_one_frictionless_contact() -> None:
    outs = [
        solve_impact(_problem(PointContact(a="box", b="floor", point=[0.1, 0, 0],
                                           normal=[0, 0, 1], restitution=0.7, law=law)))
        for law in ("newton", "poisson", "stronge")
    ]  # fmt: skip
    for other in outs[1:]:
        assert np.array_equal(other.row_impulses, outs[0].row_impulses)


def test_pin_keeps_its_point_still() -> None:
    """A pendulum pinned at the origin, struck at its tip by a given impulse: the pivot stays
    at rest, and the pin does no work (w' = w'' = 0)."""
    rod = RigidBody(name="rod", mass=1.0, inertia_com=np.diag([0.1, 0.1, 0.01]),
                    position_com=[0, 0, -0.5], velocity_com=[-1.0, 0, 0],
                    angular_velocity=[0, 2.0, 0])  # fmt: skip
    res = solve_impact(ImpactProblem(
        bodies={"rod": rod, "floor": FLOOR},
        contacts=[PointContact(a="rod", b="floor", point=[0, 0, -1.0], normal=[1, 0, 0],
                               impulse=[3.0, 0, 0])],
        constraints=[Pin(body="rod", point=[0, 0, 0])],
    ))  # fmt: skip
    after = rod.with_motion(res.bodies["rod"].velocity_after,
                            res.bodies["rod"].angular_velocity_after)  # fmt: skip
    assert np.allclose(after.velocity_of_point([0, 0, 0]), 0, atol=1e-15)
    assert res.constraints[0].dissipated == pytest.approx(0.0, abs=1e-14)
    # About the pivot: J_O d(omega_y) = (r x P)_y = -1 * 3 (lever -z, impulse +x).
    j_o = 0.1 + 1.0 * 0.25
    assert res.bodies["rod"].angular_velocity_after[1] == pytest.approx(2.0 - 3.0 / j_o)
    assert res.energy.dissipated == pytest.approx(res.energy.dissipated_theorem, abs=1e-14)

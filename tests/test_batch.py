"""carnot.batch: the array kernels against the single-impact solver (parity to 1e-12), their
broadcasting, masks and refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from carnot import FixedBody, ImpactProblem, InputError, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies, point_impacts
from carnot.batch.kernels import FRICTIONLESS, STICK
from carnot.system import assemble


def _random_bodies(rng: np.random.Generator, n: int) -> BatchBodies:
    """Masses over six decades, realizable inertias in random principal axes."""
    mass = 10 ** rng.uniform(-3, 3, n)
    size = 10 ** rng.uniform(-1.5, 0.5, n)
    a, b = rng.uniform(0.05, 1.0, (2, n))
    c = rng.uniform(np.maximum(np.abs(a - b), 1e-3), a + b)
    moments = np.stack([a, b, c], -1) * (mass * size**2)[:, None]
    rot = Rotation.random(n, random_state=rng).as_matrix()
    inertia = rot @ (moments[:, :, None] * np.eye(3)) @ np.swapaxes(rot, -1, -2)
    return BatchBodies(mass=mass, inertia_com=inertia, position_com=rng.uniform(-2, 2, (n, 3)),
                       velocity_com=rng.uniform(-10, 10, (n, 3)),
                       angular_velocity=rng.uniform(-10, 10, (n, 3)))  # fmt: skip


def _one(bodies: BatchBodies, k: int, name: str) -> RigidBody:
    return RigidBody(name=name, mass=bodies.mass[k], inertia_com=bodies.inertia_com[k],
                     position_com=bodies.position_com[k], velocity_com=bodies.velocity_com[k],
                     angular_velocity=bodies.angular_velocity[k])  # fmt: skip


@pytest.mark.parametrize("tangential", ["slip", "stick"])
@pytest.mark.parametrize("obstacle", [False, True])
def test_parity_with_the_single_impact_solver(tangential, obstacle) -> None:
    """300 random impacts: the batch answer equals carnot.solve_impact's to 1e-12."""
    rng = np.random.default_rng(20261123 + obstacle + 2 * (tangential == "stick"))
    n = 300
    a = _random_bodies(rng, n)
    b = None if obstacle else _random_bodies(rng, n)
    point = rng.uniform(-2, 2, (n, 3))
    normal = rng.normal(size=(n, 3))
    e = rng.uniform(0, 1, n)
    out = point_impacts(a, b, point, normal, e, tangential=tangential)
    for k in range(n):
        bodies = {"a": _one(a, k, "a"),
                  "b": FixedBody(name="b") if b is None else _one(b, k, "b")}  # fmt: skip
        ref = solve_impact(ImpactProblem(bodies=bodies, contacts=[PointContact(
            a="a", b="b", point=point[k], normal=normal[k], restitution=e[k],
            tangential=tangential)]))  # fmt: skip
        # 1e-12 relative, times the condition number of the contact's inverse mass K: the
        # two routes solve with K differently (here a batched solve, there an
        # eigendecomposition of the Delassus operator), so their round-off differs by that.
        problem = ImpactProblem(bodies=bodies, contacts=[PointContact(
            a="a", b="b", point=point[k], normal=normal[k], restitution=e[k],
            tangential=tangential)])  # fmt: skip
        space = assemble(problem, tuple(c.rows() for c in problem.contacts))
        rel = 1e-12 * np.linalg.cond(space.delassus())
        c = ref.contacts[0]
        size = np.linalg.norm(c.impulse)
        assert np.linalg.norm(out.impulse[k] - c.impulse) <= rel * size + 1e-300
        dv = out.velocity_a[k] - ref.bodies["a"].velocity_after
        assert np.linalg.norm(dv) <= rel * size / a.mass[k] + 1e-300
        en = ref.energy
        for mine, theirs in ((out.before[k], en.before), (out.dissipated[k], en.dissipated),
                             (out.dissipated_theorem[k], en.dissipated_theorem),
                             (out.lost_velocities[k], en.lost_velocities)):  # fmt: skip
            assert abs(mine - theirs) <= rel * en.before + 1e-300
        assert out.not_approaching[k] == ("not_approaching" in ref.flag_codes())
        assert out.negative_normal_impulse[k] == ("negative_normal_impulse" in ref.flag_codes())
    # the theorem against the direct difference, on every impact
    assert np.all(np.abs(out.dissipated - out.dissipated_theorem) <= 1e-11 * out.before)


def test_one_impact_is_the_empty_shape_and_arguments_broadcast() -> None:
    ball = BatchBodies(mass=2.0, inertia_com=np.eye(3) * 0.02, position_com=[0, 0, 0.1],
                       velocity_com=[1.0, 0, -3.0])  # fmt: skip
    one = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], 0.6)
    assert one.impulse.shape == (3,) and one.dissipated.shape == ()
    # Newton's closed form for a sphere-like body hit under its centre: v_z'' = -e v_z
    assert one.velocity_a.tolist() == pytest.approx([1.0, 0.0, 1.8])
    assert float(one.dissipated) == pytest.approx(0.5 * 2.0 * 9 * (1 - 0.36))
    grid = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.linspace(0, 1, 5)[:, None]
                         * np.ones((5, 4)))  # fmt: skip
    assert grid.impulse.shape == (5, 4, 3) and grid.regime.shape == (5, 4)
    assert np.all(grid.regime == FRICTIONLESS)


def test_masks_for_stick_and_its_friction() -> None:
    """A ball sliding at 1 m/s lands at 1 m/s: sticking needs mu = (2/7) 1 / (1 + e) (Brach
    1991): a mask per impact, not a branch."""
    ball = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.4, position_com=[0, 0, 1.0],
                       velocity_com=[1.0, 0, -1.0])  # fmt: skip
    e = 0.5
    mu = np.array([0.1, 0.2, 0.3])
    out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], e, tangential="stick", friction=mu)
    needed = (2 / 7) / (1 + e)
    assert np.all(out.regime == STICK)
    assert out.friction_required == pytest.approx(np.full(3, needed))
    assert out.friction_insufficient.tolist() == (mu < needed).tolist()


def test_refusals_name_the_field() -> None:
    ball = BatchBodies(mass=1.0, inertia_com=np.eye(3), position_com=[0, 0, 1.0])
    with pytest.raises(InputError, match="friction: Coulomb slip is not in the batch"):
        point_impacts(ball, None, [0, 0, 0], [0, 0, 1], 0.5, friction=0.3)
    with pytest.raises(InputError, match=r"restitution: must be in \[0, 1\]"):
        point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.array([0.5, 1.5]))
    with pytest.raises(InputError, match="normal: must be non-zero"):
        point_impacts(ball, None, [0, 0, 0], [0, 0, 0], 0.5)

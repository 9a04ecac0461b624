"""Properties on random bodies (Hypothesis): the theorem against the direct difference,
momentum balances, and the textbook scalar formula as an independent route."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact

SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

unit = st.floats(-1.0, 1.0, allow_nan=False)
coords = st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=3, max_size=3)
speeds = st.lists(st.floats(-10.0, 10.0, allow_nan=False), min_size=3, max_size=3)


@st.composite
def rotations(draw) -> np.ndarray:
    q = np.array([draw(unit) for _ in range(4)]) + np.array([1e-3, 0, 0, 0])
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


@st.composite
def bodies(draw, name: str) -> RigidBody:
    """A random body: mass over six decades, a realizable inertia (random principal axes,
    moments obeying the triangle rule, the smallest at least 1e-3 of the largest)."""
    mass = 10 ** draw(st.floats(-3, 3))
    size = 10 ** draw(st.floats(-1.5, 0.5))
    a = draw(st.floats(0.05, 1.0))
    b = draw(st.floats(0.05, 1.0))
    c = draw(st.floats(max(abs(a - b), 1e-3), a + b))
    moments = np.array([a, b, c]) * mass * size**2
    rot = draw(rotations())
    return RigidBody(
        name=name,
        mass=mass,
        inertia_com=rot @ np.diag(moments) @ rot.T,
        position_com=draw(coords),
        velocity_com=draw(speeds),
        angular_velocity=draw(speeds),
    )


@st.composite
def impacts(draw, *, stick: bool | None = None, obstacle: bool | None = None):
    a = draw(bodies("a"))
    fixed = draw(st.booleans()) if obstacle is None else obstacle
    b = FixedBody(name="b") if fixed else draw(bodies("b"))
    normal = np.array([draw(unit) for _ in range(3)]) + np.array([0, 0, 1e-3])
    sticks = draw(st.booleans()) if stick is None else stick
    contact = PointContact(
        a="a", b="b", point=draw(coords), normal=normal, restitution=draw(st.floats(0, 1)),
        tangential="stick" if sticks else "slip",
    )  # fmt: skip
    return ImpactProblem(bodies={"a": a, "b": b}, contacts=[contact])


def speed_scale(problem: ImpactProblem, point: np.ndarray) -> float:
    """The round-off scale of velocities at ``point`` (m/s): ``|v| + |omega| |r|`` summed over
    the movable bodies, not ``|v + omega x r|``, which cancels to 0 when omega is parallel to
    r while the solver's w'' still carries round-off (CI found such a case). Largest
    components, not Euclidean norms: squares of values like 1e-227 underflow to 0."""
    return float(sum(
        np.abs(b.velocity_com).max()
        + np.abs(b.angular_velocity).max() * np.abs(point - b.position_com).max()
        for b in problem.bodies.values()
        if not b.fixed
    ))  # fmt: skip


@SETTINGS
@given(impacts())
def test_theorem_equals_direct_difference(problem) -> None:
    e = solve_impact(problem).energy
    assert abs(e.dissipated - e.dissipated_theorem) <= 1e-12 * e.before + 1e-300


@SETTINGS
@given(impacts())
def test_carnot_condition_always(problem) -> None:
    """E_d - E_p = -sum P . w'' for any impulse (paper eqs. 12-13)."""
    e = solve_impact(problem).energy
    assert abs(e.carnot_defect - e.carnot_condition) <= 1e-11 * (e.before + e.lost_velocities)


@SETTINGS
@given(impacts(obstacle=False))
def test_two_free_bodies_conserve_linear_momentum(problem) -> None:
    res = solve_impact(problem)
    a, b = problem.bodies["a"], problem.bodies["b"]
    before = a.mass * a.velocity_com + b.mass * b.velocity_com
    after = a.mass * res.bodies["a"].velocity_after + b.mass * res.bodies["b"].velocity_after
    scale = a.mass * np.linalg.norm(a.velocity_com) + b.mass * np.linalg.norm(b.velocity_com)
    assert np.linalg.norm(after - before) <= 1e-11 * (scale + np.linalg.norm(res.row_impulses))


@SETTINGS
@given(impacts())
def test_angular_momentum_about_the_contact_point(problem) -> None:
    """A single point contact exerts no moment about its point: each body's angular momentum
    about it is conserved (computed here from the velocities, not from carnot's check)."""
    res = solve_impact(problem)
    p = problem.contacts[0].point
    for name in ("a", "b"):
        body = problem.bodies[name]
        if body.fixed:
            continue
        after = body.with_motion(
            res.bodies[name].velocity_after, res.bodies[name].angular_velocity_after
        )
        h1, h2 = body.angular_momentum_about(p), after.angular_momentum_about(p)
        # the sizes of the terms, not of their sum h1 (J omega and r x m v can cancel to 0
        # while the solver's answer still carries round-off), as in speed_scale
        lever = np.abs(body.position_com - p).max()
        scale = (np.abs(body.inertia_com @ body.angular_velocity).max()
                 + lever * body.mass * np.abs(body.velocity_com).max()
                 + lever * np.abs(res.contacts[0].impulse).max())  # fmt: skip
        assert np.linalg.norm(h2 - h1) <= 1e-10 * (scale + 1e-300)


@SETTINGS
@given(impacts(stick=False))
def test_frictionless_newton_dissipates_and_is_elastic_at_e_1(problem) -> None:
    res = solve_impact(problem)
    contact = problem.contacts[0]
    approaching = res.contacts[0].relative_velocity_before @ contact.normal < 0
    e = res.energy
    if approaching:
        assert e.dissipated >= -1e-12 * e.before
    elastic = ImpactProblem(
        bodies=problem.bodies,
        contacts=[PointContact(a="a", b="b", point=contact.point, normal=contact.normal,
                               restitution=1.0)],
    )  # fmt: skip
    e1 = solve_impact(elastic).energy
    assert abs(e1.dissipated) <= 1e-12 * e1.before


_SPIN_FRICTIONLESS = ImpactProblem(  # w' = 0 exactly, omega parallel to r: round-off only
    bodies={
        "a": RigidBody(name="a", mass=1.0, inertia_com=np.eye(3),
                       position_com=[0.51094289, 1.625, 0.0],
                       angular_velocity=[0.51094289, 1.625, 0.0]),
        "b": FixedBody(name="b"),
    },
    contacts=[PointContact(a="a", b="b", point=[0, 0, 0], normal=[0, 0, 1], restitution=0.0)],
)  # fmt: skip


@SETTINGS
@given(impacts(stick=False))
@example(_SPIN_FRICTIONLESS)
def test_frictionless_against_the_scalar_formula(problem) -> None:
    """Independent route: P_n = -(1 + e) n.w' / (1/m_a + 1/m_b + (r_a x n).J_a^-1 (r_a x n)
    + (r_b x n).J_b^-1 (r_b x n)), the effective mass at the contact (Stronge, *Impact
    Mechanics*, CUP 2000, ch. 3)."""
    res = solve_impact(problem)
    c = problem.contacts[0]
    n = c.normal
    inverse_mass = 0.0
    w = np.zeros(3)
    for name, sign in (("a", 1.0), ("b", -1.0)):
        body = problem.bodies[name]
        if body.fixed:
            continue
        r = c.point - body.position_com
        rn = np.cross(r, n)
        inverse_mass += 1 / body.mass + rn @ np.linalg.solve(body.inertia_com, rn)
        w += sign * body.velocity_of_point(c.point)
    p_n = -(1 + c.restitution) * (n @ w) / inverse_mass
    momentum = sum(b.mass for b in problem.bodies.values() if not b.fixed) * speed_scale(
        problem, c.point)  # fmt: skip
    assert abs(res.contacts[0].normal_impulse - p_n) <= 1e-9 * abs(p_n) + 1e-12 * momentum


_SPIN_ABOUT_THE_LEVER_ARM = ImpactProblem(  # w' = 0 while omega != 0: CI found this one
    bodies={
        "a": RigidBody(name="a", mass=1.0, inertia_com=np.eye(3),
                       position_com=[0.74451742, 0.74451742, 1.5],
                       angular_velocity=[0.74451742, 0.74451742, 1.5]),
        "b": FixedBody(name="b"),
    },
    contacts=[PointContact(a="a", b="b", point=[0, 0, 0], normal=[0, 0, 1], restitution=0.0,
                           tangential="stick")],
)  # fmt: skip


@SETTINGS
@given(impacts(stick=True))
@example(_SPIN_ABOUT_THE_LEVER_ARM)
def test_stick_with_e_0_loses_exactly_the_lost_velocities(problem) -> None:
    """Sticking with e = 0 leaves w'' = 0, so P . w'' = 0 and E_d = E_p (Carnot)."""
    c = problem.contacts[0]
    plastic = ImpactProblem(
        bodies=problem.bodies,
        contacts=[PointContact(a="a", b="b", point=c.point, normal=c.normal, restitution=0.0,
                               tangential="stick")],
    )  # fmt: skip
    res = solve_impact(plastic)
    e = res.energy
    speeds = speed_scale(problem, c.point)
    assert np.linalg.norm(res.contacts[0].relative_velocity_after) <= 1e-9 * speeds + 1e-300
    # E_d - E_p = -P . w'' (eqs. 12-13), so it is as small as w'' allows: |P| times the bound
    # above (a tight 1e-11 E' alone fails for ill-conditioned bodies, whose w'' round-off
    # grows with the condition number of the contact's inverse mass)
    impulse = np.linalg.norm(res.contacts[0].impulse)
    assert abs(e.dissipated - e.lost_velocities) <= (
        1e-11 * e.before + impulse * 1e-9 * speeds + 1e-300)  # fmt: skip

"""Every scenario in examples/ against a published closed form, with its source.

Each test states the file's parameters as constants, checks that the loaded problem holds
exactly those (so that the file and the test cannot drift apart), and computes the expected
impulses, velocities and energies from the closed form. The solver never supplies an expected
value. Every solve is also checked for the paper's theorem (E_d direct == E_d by the theorem,
to 1e-12 E'), Carnot's condition (E_d - E_p == -sum P . w'') and momentum balance.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import EXAMPLES

from carnot import ImpactProblem, ImpactResult, RigidBody, solve_impact
from carnot.io.scenario import load_scenario

REL = 1e-11


def _load(name: str) -> ImpactProblem:
    return load_scenario(EXAMPLES / name)


def _body(
    problem: ImpactProblem,
    name: str,
    *,
    mass: float,
    position: object = (0.0, 0.0, 0.0),
    velocity: object = (0.0, 0.0, 0.0),
    angular_velocity: object = (0.0, 0.0, 0.0),
) -> RigidBody:
    """The body, after checking that the file holds the test's parameters."""
    body = problem.bodies[name]
    assert isinstance(body, RigidBody)
    assert body.mass == mass
    for got, want in (
        (body.position_com, position),
        (body.velocity_com, velocity),
        (body.angular_velocity, angular_velocity),
    ):
        # To rounding: a state the test derives (v = omega x r) may differ in the last bit
        # from the decimal written in the file.
        assert np.allclose(got, np.asarray(want, dtype=float), rtol=1e-15, atol=1e-15)
    return body


def _solve(problem: ImpactProblem) -> ImpactResult:
    res = solve_impact(problem)
    e = res.energy
    # The theorem against the direct difference of kinetic energies.
    assert abs(e.dissipated - e.dissipated_theorem) <= 1e-12 * e.before
    # Paper eqs. 12-13: E_d - E_p == -sum P . w''.
    assert abs(e.carnot_defect - e.carnot_condition) <= 1e-12 * e.before
    assert res.momentum.linear_residual < 1e-12
    assert res.momentum.angular_residual < 1e-12
    return res


def _vec(result_vector: object, expected: object) -> None:
    """Vector equality to REL of the expected vector's size (zeros included)."""
    got = np.asarray(result_vector, dtype=float)
    want = np.asarray(expected, dtype=float)
    assert np.linalg.norm(got - want) <= REL * max(float(np.linalg.norm(want)), 1e-300), (
        got,
        want,
    )


def test_two_billiard_balls() -> None:
    """Oblique frictionless impact of two spheres: Newton's restitution along the line of
    centres with momentum conserved, tangential components unchanged,
        P = (1 + e) m1 m2 / (m1 + m2) (-v'_rel . n),
        E_d = (1 - e^2) m1 m2 v_rel,n^2 / (2 (m1 + m2))
    (W. Goldsmith, *Impact: The Theory and Physical Behaviour of Colliding Solids*, Arnold 1960,
    elementary impact theory of spheres; W. J. Stronge, *Impact Mechanics*, CUP 2000, collinear
    impact of rigid bodies);
    for equal masses v''_An = (1 - e)/2 v'_An, v''_Bn = (1 + e)/2 v'_An."""
    problem = _load("two_billiard_balls.toml")
    m1 = m2 = 0.17
    e = 0.9
    v_a = np.array([2.0, 0.0, 0.0])
    n = np.array([-0.8, -0.6, 0.0])
    _body(problem, "A", mass=m1, position=(-0.048, -0.036, 0.0), velocity=v_a.tolist())
    _body(problem, "B", mass=m2)
    assert problem.contacts[0].restitution == e
    assert problem.contacts[0].normal.tolist() == n.tolist()
    res = _solve(problem)

    v_rel_n = v_a @ n  # B at rest
    p = (1 + e) * m1 * m2 / (m1 + m2) * -v_rel_n
    _vec(res.contacts[0].impulse, p * n)
    assert res.contacts[0].normal_impulse == pytest.approx(p, rel=REL)
    a, b = res.bodies["A"], res.bodies["B"]
    _vec(a.velocity_after, v_a + p / m1 * n)
    _vec(b.velocity_after, -p / m2 * n)
    # The equal-mass form, with the tangential component of A kept.
    _vec(a.velocity_after, v_a - v_rel_n * n + (1 - e) / 2 * v_rel_n * n)
    _vec(b.velocity_after, (1 + e) / 2 * v_rel_n * n)
    assert np.all(a.angular_velocity_after == 0) and np.all(b.angular_velocity_after == 0)
    e_d = (1 - e**2) * m1 * m2 * v_rel_n**2 / (2 * (m1 + m2))
    assert res.energy.dissipated == pytest.approx(e_d, rel=REL)
    assert res.warnings == ()


def test_bat_and_ball() -> None:
    """A free bat responds at the impact point with its effective mass
    M_eff = (1/M + d^2/I_cm)^-1; the ball rebounds at v (e M_eff - m)/(m + M_eff)
    (H. Brody, "The sweet spot of a baseball bat", Am. J. Phys. 54, 640 (1986);
    R. Cross, "The sweet spot of a baseball bat", Am. J. Phys. 66, 772 (1998))."""
    problem = _load("bat_and_ball.toml")
    m, v, e = 0.145, 40.0, 0.5
    big_m, length, d = 0.9, 0.84, 0.15
    _body(problem, "ball", mass=m, position=(d, 0.0666, 0.0), velocity=(0.0, -v, 0.0))
    _body(problem, "bat", mass=big_m)
    assert problem.contacts[0].restitution == e
    assert problem.contacts[0].point.tolist() == [d, 0.03, 0.0]
    res = _solve(problem)

    i_cm = big_m * length**2 / 12  # slender rod (Brody's uniform-bat model)
    m_eff = 1 / (1 / big_m + d**2 / i_cm)
    p = (1 + e) * v / (1 / m + 1 / m_eff)
    _vec(res.contacts[0].impulse, [0.0, p, 0.0])
    ball, bat = res.bodies["ball"], res.bodies["bat"]
    _vec(ball.velocity_after, [0.0, -v + p / m, 0.0])
    _vec(ball.velocity_after, [0.0, v * (e * m_eff - m) / (m + m_eff), 0.0])
    _vec(bat.velocity_after, [0.0, -p / big_m, 0.0])
    # The bat receives -P y at r = (d, .., 0) from its centre: (d x) x (-P y) = -P d z.
    _vec(bat.angular_velocity_after, [0.0, 0.0, -p * d / i_cm])
    e_d = (1 - e**2) * v**2 / 2 / (1 / m + 1 / m_eff)
    assert res.energy.dissipated == pytest.approx(e_d, rel=REL)
    assert res.warnings == ()


def test_ballistic_pendulum() -> None:
    """The bullet embeds: angular momentum about the pivot is conserved,
    m v d = (I_O + m d^2) omega'', I_O = M L^2/3, and E_d = (1/2) m v^2 I_O / (I_O + m d^2)
    (B. Robins, *New Principles of Gunnery*, 1742; J. L. Meriam and L. G. Kraige,
    *Engineering Mechanics: Dynamics*, angular impulse and momentum of rigid bodies)."""
    problem = _load("ballistic_pendulum.toml")
    m, v, d = 0.01, 300.0, 0.8
    big_m, length = 2.0, 1.0
    _body(problem, "bullet", mass=m, position=(0.0, 0.0, -d), velocity=(v, 0.0, 0.0))
    _body(problem, "pendulum", mass=big_m, position=(0.0, 0.0, -length / 2))
    pin, fasten = problem.constraints
    assert (pin.kind, fasten.kind) == ("pin", "fasten")
    res = _solve(problem)

    i_o = big_m * length**2 / 3
    omega = m * v * d / (i_o + m * d**2)
    # The pendulum swings towards +x below the pivot: a rotation about -y.
    _vec(res.bodies["pendulum"].angular_velocity_after, [0.0, -omega, 0.0])
    _vec(res.bodies["pendulum"].velocity_after, [omega * length / 2, 0.0, 0.0])
    _vec(res.bodies["bullet"].velocity_after, [omega * d, 0.0, 0.0])
    # The bullet keeps its (zero) spin only if the fastening gives it no moment: it is a point.
    assert np.linalg.norm(res.bodies["bullet"].angular_velocity_after) < 1e-12 * omega
    # Impulses: the fastening stops the bullet relative to the rod; the pivot supplies the
    # difference of the linear momenta.
    pin_out, fasten_out = res.constraints
    _vec(fasten_out.impulse, [m * (omega * d - v), 0.0, 0.0])
    _vec(pin_out.impulse, [m * omega * d + big_m * omega * length / 2 - m * v, 0.0, 0.0])
    e_d = 0.5 * m * v**2 * i_o / (i_o + m * d**2)
    assert res.energy.dissipated == pytest.approx(e_d, rel=REL)
    assert res.warnings == ()


def test_rod_on_ledge() -> None:
    """A rod falling flat onto a ledge at d from its centre: effective mass
    m_eff = (1/m + d^2/I)^-1, P = (1 + e) m_eff v, E_d = (1 - e^2) m_eff v^2 / 2
    (W. J. Stronge, *Impact Mechanics*, CUP 2000, planar impact of rigid bodies;
    E. J. Routh, *Elementary Rigid Dynamics*, 1905, the chapter on impulsive forces)."""
    problem = _load("rod_on_ledge.toml")
    m, length, d, v, e = 1.2, 1.0, 0.3, 2.0, 0.4
    _body(problem, "rod", mass=m, velocity=(0.0, 0.0, -v))
    assert problem.contacts[0].point.tolist()[0] == d
    assert problem.contacts[0].restitution == e
    res = _solve(problem)

    i_cm = m * length**2 / 12
    m_eff = 1 / (1 / m + d**2 / i_cm)
    p = (1 + e) * m_eff * v
    _vec(res.contacts[0].impulse, [0.0, 0.0, p])
    _vec(res.bodies["rod"].velocity_after, [0.0, 0.0, -v + p / m])
    # P z at (d, 0, ..) from the centre: (d x) x (P z) = -P d y.
    _vec(res.bodies["rod"].angular_velocity_after, [0.0, -p * d / i_cm, 0.0])
    # Newton's law at the ledge, from the closed-form motion.
    assert -v + p / m + p * d * d / i_cm == pytest.approx(e * v, rel=REL)
    assert res.energy.dissipated == pytest.approx((1 - e**2) * m_eff * v**2 / 2, rel=REL)
    assert res.warnings == ()


def test_spinning_plate_corner() -> None:
    """A corner of a plate spinning about its centre is suddenly fixed: angular momentum about
    the corner is conserved, I_C omega' = I_O omega'' with I_O = I_C + m c^2 (c the half
    diagonal; I_O = 4 I_C for any rectangle), E_d = (1/2) I_C omega'^2 (1 - I_C / I_O)
    (E. J. Routh, *Elementary Rigid Dynamics*, 1905, impulsive motion about a fixed point)."""
    problem = _load("spinning_plate_corner.toml")
    m, a, b, w = 1.5, 0.4, 0.3, 10.0
    _body(problem, "plate", mass=m, angular_velocity=(0.0, 0.0, w))
    corner = np.array([a / 2, b / 2, 0.0])
    assert problem.constraints[0].point.tolist() == corner.tolist()
    res = _solve(problem)

    i_c = m * (a * a + b * b) / 12
    i_o = i_c + m * (corner @ corner)
    w2 = w * i_c / i_o
    assert w2 == pytest.approx(w / 4, rel=1e-14)
    plate = res.bodies["plate"]
    _vec(plate.angular_velocity_after, [0.0, 0.0, w2])
    v_c = np.cross([0.0, 0.0, w2], -corner)  # the centre turns about the corner
    _vec(plate.velocity_after, v_c)
    _vec(res.constraints[0].impulse, m * v_c)  # the centre was at rest
    e_d = 0.5 * i_c * w**2 * (1 - i_c / i_o)
    assert res.energy.dissipated == pytest.approx(e_d, rel=REL)
    assert res.warnings == ()


def test_rocking_block() -> None:
    """A rectangular block (width 2b, height 2h) rocking on one corner lands on the other:
    angular momentum about the new corner gives Housner's
    omega''/omega' = 1 - (3/2) sin^2(alpha), alpha = atan(b/h), and the kinetic energy falls by
    the square of that ratio (G. W. Housner, "The behavior of inverted pendulum structures
    during earthquakes", Bull. Seismol. Soc. Am. 53(2), 403-417, 1963)."""
    problem = _load("rocking_block.toml")
    m, b, h, w = 50.0, 0.2, 0.5, -1.5
    centre = np.array([0.0, 0.0, h])
    o1, o2 = np.array([b, 0.0, 0.0]), np.array([-b, 0.0, 0.0])
    v_before = np.cross([0.0, w, 0.0], centre - o1)
    _body(
        problem,
        "block",
        mass=m,
        position=centre.tolist(),
        velocity=v_before.tolist(),
        angular_velocity=(0.0, w, 0.0),
    )
    assert problem.constraints[0].point.tolist() == o2.tolist()
    res = _solve(problem)

    ratio = 1 - 1.5 * math.sin(math.atan(b / h)) ** 2
    w2 = ratio * w
    block = res.bodies["block"]
    _vec(block.angular_velocity_after, [0.0, w2, 0.0])
    v_after = np.cross([0.0, w2, 0.0], centre - o2)
    _vec(block.velocity_after, v_after)
    _vec(res.constraints[0].impulse, m * (v_after - v_before))
    i_o = m * (b * b + h * h) * 4 / 3  # about a bottom edge
    e_before = 0.5 * i_o * w**2
    assert res.energy.before == pytest.approx(e_before, rel=REL)
    assert res.energy.after == pytest.approx(ratio**2 * e_before, rel=REL)
    assert res.energy.dissipated == pytest.approx((1 - ratio**2) * e_before, rel=REL)
    assert res.warnings == ()


def test_spinning_ball_bounce() -> None:
    """A ball with backspin grips a rough floor and leaves rolling: the impulse acts at the
    contact point, so angular momentum about it is conserved, giving
    v''_x = (5 v'_x + 2 R omega'_y)/7 (with v_x = R omega_y for rolling), and Newton's
    v''_z = -e v'_z; E_d = (1 - e^2) m v_z^2/2 + (1/2)(2m/7) s^2 with s the initial slip
    speed (H. Brody, "That's how the ball bounces", Phys. Teach. 22, 494 (1984); R. Cross,
    "Bounce of a spinning ball near normal incidence", Am. J. Phys. 73, 914 (2005))."""
    problem = _load("spinning_ball_bounce.toml")
    m, r, e, mu = 0.25, 0.04, 0.8, 0.5
    vx, vz, wy = 3.0, -4.0, -50.0
    _body(
        problem,
        "ball",
        mass=m,
        position=(0.0, 0.0, r),
        velocity=(vx, 0.0, vz),
        angular_velocity=(0.0, wy, 0.0),
    )
    contact = problem.contacts[0]
    assert (contact.restitution, contact.friction, contact.tangential) == (e, mu, "stick")
    res = _solve(problem)

    vx2 = (5 * vx + 2 * r * wy) / 7
    ball = res.bodies["ball"]
    _vec(ball.velocity_after, [vx2, 0.0, -e * vz])
    _vec(ball.angular_velocity_after, [0.0, vx2 / r, 0.0])
    p_t, p_n = m * (vx2 - vx), m * (1 + e) * -vz
    _vec(res.contacts[0].impulse, [p_t, 0.0, p_n])
    assert res.contacts[0].friction_required == pytest.approx(abs(p_t) / p_n, rel=REL)
    slip = vx - r * wy
    e_normal = (1 - e**2) * m * vz**2 / 2
    e_tangential = 0.5 * (2 * m / 7) * slip**2
    assert res.energy.dissipated == pytest.approx(e_normal + e_tangential, rel=REL)
    # The theorem's split: the normal impulse accounts for the normal part, the friction
    # impulse for the rest.
    assert res.energy.dissipated_normal == pytest.approx(e_normal, rel=REL)
    assert res.energy.dissipated_tangential == pytest.approx(e_tangential, rel=REL)
    assert res.warnings == ()


def test_centre_of_percussion() -> None:
    """A pivoted rod struck at its centre of percussion q = I_O / (M L/2) = 2L/3 below the
    pivot: the pivot takes no impulse; the rod responds with the effective mass I_O / q^2
    (J. L. Meriam and L. G. Kraige, *Engineering Mechanics: Dynamics*, ch. 6, fixed-axis
    rotation, centre of percussion; E. J. Routh, *Elementary Rigid Dynamics*, 1905, centre of
    percussion)."""
    problem = _load("centre_of_percussion.toml")
    m, v, e = 0.2, 5.0, 0.5
    big_m, length = 1.2, 0.9
    q = 2 * length / 3
    _body(problem, "ball", mass=m, position=(0.06, 0.0, -q), velocity=(-v, 0.0, 0.0))
    _body(problem, "rod", mass=big_m, position=(0.0, 0.0, -length / 2))
    assert problem.contacts[0].point.tolist()[2] == -q
    assert problem.contacts[0].restitution == e
    res = _solve(problem)

    i_o = big_m * length**2 / 3
    assert q == pytest.approx(i_o / (big_m * length / 2), rel=1e-15)
    p = (1 + e) * v / (1 / m + q**2 / i_o)
    _vec(res.contacts[0].impulse, [p, 0.0, 0.0])
    omega = p * q / i_o
    _vec(res.bodies["rod"].angular_velocity_after, [0.0, omega, 0.0])
    _vec(res.bodies["rod"].velocity_after, [-omega * length / 2, 0.0, 0.0])
    _vec(res.bodies["ball"].velocity_after, [-v + p / m, 0.0, 0.0])
    # No impulse at the pivot, to rounding.
    assert np.linalg.norm(res.constraints[0].impulse) <= 1e-12 * p
    e_d = (1 - e**2) * v**2 / (2 * (1 / m + q**2 / i_o))
    assert res.energy.dissipated == pytest.approx(e_d, rel=REL)
    assert res.warnings == ()


def test_ball_on_floor() -> None:
    """Newton's restitution on a fixed frictionless floor: v''_z = -e v'_z, v''_x unchanged,
    P = (1 + e) m |v'_z|, E_d = (1 - e^2) m v'_z^2 / 2 (I. Newton, *Principia*, 1687, the
    experiments on colliding pendulums in the scholium to the laws of motion; W. J. Stronge,
    *Impact Mechanics*, CUP 2000, collinear impact of rigid bodies)."""
    problem = _load("ball_on_floor.toml")
    m, e, vx, vz = 0.5, 0.6, 1.0, -3.0
    _body(problem, "ball", mass=m, position=(0.0, 0.0, 0.1), velocity=(vx, 0.0, vz))
    assert problem.contacts[0].restitution == e
    res = _solve(problem)

    _vec(res.bodies["ball"].velocity_after, [vx, 0.0, -e * vz])
    _vec(res.contacts[0].impulse, [0.0, 0.0, (1 + e) * m * -vz])
    assert res.energy.dissipated == pytest.approx((1 - e**2) * m * vz**2 / 2, rel=REL)
    assert res.warnings == ()


#: Warning codes an example is expected to raise (all others must be clean).
EXPECTED_FLAGS = {
    "paper_pendulum_plane.toml": ["statically_indeterminate"],
    "box_lands_flat.toml": ["statically_indeterminate"],
}


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.name)
def test_every_example_solves_cleanly(path) -> None:
    res = _solve(load_scenario(path))
    assert res.flag_codes() == EXPECTED_FLAGS.get(path.name, [])
    assert res.energy.dissipated >= -1e-12 * res.energy.before


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.name)
def test_every_example_explains_itself(path) -> None:
    """Each file opens with a comment header that states the setup and the closed form."""
    lines = path.read_text(encoding="utf-8").splitlines()
    header = [ln for ln in lines[: lines.index("format = 1")] if ln.startswith("#")]
    assert len(header) >= 3

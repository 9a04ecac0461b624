"""Every scenario in examples/ against a published closed form, with its source.

The expected values are computed here from the closed forms with the files' parameters; the
solver never supplies them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import EXAMPLES

from carnot import solve_impact
from carnot.io.scenario import load_scenario


def _solve(name: str):
    res = solve_impact(load_scenario(EXAMPLES / name))
    e = res.energy
    # The theorem against the direct difference, for every example.
    assert abs(e.dissipated - e.dissipated_theorem) <= 1e-12 * e.before
    assert e.carnot_defect == pytest.approx(e.carnot_condition, rel=1e-9, abs=1e-12 * e.before)
    return res


def test_two_billiard_balls() -> None:
    """Newton's restitution along the line of centres with momentum conserved; equal masses:
    v_An'' = (1 - e)/2 v_An', v_Bn'' = (1 + e)/2 v_An', tangential components unchanged;
    E_d = (1 - e^2) m1 m2 v_rel^2 / (2 (m1 + m2)) (W. Goldsmith, *Impact*, Arnold 1960, ch. 1;
    W. J. Stronge, *Impact Mechanics*, CUP 2000, section 2.2)."""
    res = _solve("two_billiard_balls.toml")
    m, e = 0.17, 0.9
    n = np.array([-0.8, -0.6, 0.0])
    v_a = np.array([2.0, 0.0, 0.0])
    v_an = v_a @ n
    a, b = res.bodies["A"], res.bodies["B"]
    assert np.allclose(a.velocity_after, v_a - v_an * n + (1 - e) / 2 * v_an * n, atol=1e-14)
    assert np.allclose(b.velocity_after, (1 + e) / 2 * v_an * n, atol=1e-14)
    assert np.allclose(a.angular_velocity_after, 0, atol=1e-13)
    assert res.energy.dissipated == pytest.approx((1 - e**2) * m * m * v_an**2 / (4 * m), rel=1e-12)
    assert res.warnings == ()


def test_bat_and_ball() -> None:
    """The bat's effective mass at the impact point, M_eff = (1/M + d^2/I)^-1 (H. Brody, "The
    sweet spot of a baseball bat", Am. J. Phys. 54, 640 (1986); R. Cross, "The sweet spot of a
    baseball bat", Am. J. Phys. 66, 772 (1998))."""
    res = _solve("bat_and_ball.toml")
    m, big_m, length, d, v, e = 0.145, 0.9, 0.84, 0.15, 40.0, 0.5
    inertia = big_m * length**2 / 12
    m_eff = 1 / (1 / big_m + d**2 / inertia)
    p = (1 + e) * v / (1 / m + 1 / m_eff)
    assert res.contacts[0].normal_impulse == pytest.approx(p, rel=1e-12)
    assert res.bodies["ball"].velocity_after[1] == pytest.approx(-v + p / m, rel=1e-12)
    assert res.bodies["bat"].velocity_after[1] == pytest.approx(-p / big_m, rel=1e-12)
    assert res.bodies["bat"].angular_velocity_after[2] == pytest.approx(-p * d / inertia, rel=1e-12)
    # The ball's rebound in Brody's form: v'' = v (e M_eff - m) / (m + M_eff).
    assert res.bodies["ball"].velocity_after[1] == pytest.approx(
        v * (e * m_eff - m) / (m + m_eff), rel=1e-12
    )
    e_d = (1 - e**2) * v**2 / 2 / (1 / m + 1 / m_eff)
    assert res.energy.dissipated == pytest.approx(e_d, rel=1e-12)


def test_ballistic_pendulum() -> None:
    """Angular momentum about the pivot: m v d = (I_O + m d^2) omega'' (B. Robins, *New
    Principles of Gunnery*, 1742; e.g. Meriam & Kraige, *Engineering Mechanics: Dynamics*,
    angular impulse and momentum)."""
    res = _solve("ballistic_pendulum.toml")
    m, v, d, big_m, length = 0.01, 300.0, 0.8, 2.0, 1.0
    i_o = big_m * length**2 / 3
    omega = m * v * d / (i_o + m * d**2)
    assert -res.bodies["pendulum"].angular_velocity_after[1] == pytest.approx(omega, rel=1e-12)
    assert res.bodies["bullet"].velocity_after[0] == pytest.approx(omega * d, rel=1e-12)
    assert res.energy.dissipated == pytest.approx(
        0.5 * m * v**2 * i_o / (i_o + m * d**2), rel=1e-12
    )
    # The pivot takes the difference between the momentum after and before.
    p_after = m * omega * d + big_m * omega * length / 2
    assert res.constraints[0].impulse[0] == pytest.approx(p_after - m * v, rel=1e-12)
    assert res.warnings == ()


def test_rod_on_ledge() -> None:
    """The rod's effective mass at the ledge, m_eff = (1/m + d^2/I)^-1, and Newton's e
    (Stronge, *Impact Mechanics*, CUP 2000, ch. 2-3; E. J. Routh, *Elementary Rigid Dynamics*,
    1905, ch. on impulsive forces)."""
    res = _solve("rod_on_ledge.toml")
    m, length, d, v, e = 1.2, 1.0, 0.3, 2.0, 0.4
    inertia = m * length**2 / 12
    m_eff = 1 / (1 / m + d**2 / inertia)
    p = (1 + e) * m_eff * v
    assert res.contacts[0].normal_impulse == pytest.approx(p, rel=1e-12)
    assert res.bodies["rod"].velocity_after[2] == pytest.approx(-v + p / m, rel=1e-12)
    assert res.bodies["rod"].angular_velocity_after[1] == pytest.approx(-p * d / inertia, rel=1e-12)
    assert res.energy.dissipated == pytest.approx((1 - e**2) * m_eff * v**2 / 2, rel=1e-12)


def test_spinning_plate_corner() -> None:
    """Angular momentum about the fastened corner is conserved, I_C omega' = I_O omega''
    (Routh, *Elementary Rigid Dynamics*, impulsive motion about a fixed point); for a rectangle
    I_O = 4 I_C."""
    res = _solve("spinning_plate_corner.toml")
    m, a, b, w = 1.5, 0.4, 0.3, 10.0
    i_c = m * (a * a + b * b) / 12
    i_o = i_c + m * (a * a + b * b) / 4
    assert res.bodies["plate"].angular_velocity_after[2] == pytest.approx(w * i_c / i_o, rel=1e-12)
    assert res.bodies["plate"].angular_velocity_after[2] == pytest.approx(w / 4, rel=1e-12)
    assert res.energy.dissipated == pytest.approx(0.5 * i_c * w**2 * (1 - i_c / i_o), rel=1e-12)


def test_rocking_block() -> None:
    """Housner's coefficient: omega''/omega' = 1 - (3/2) sin^2(alpha), alpha = atan(b/h)
    (G. W. Housner, "The behavior of inverted pendulum structures during earthquakes",
    Bull. Seismol. Soc. Am. 53(2), 403-417, 1963)."""
    res = _solve("rocking_block.toml")
    m, b, h, w = 50.0, 0.2, 0.5, -1.5
    ratio = 1 - 1.5 * math.sin(math.atan(b / h)) ** 2
    assert res.bodies["block"].angular_velocity_after[1] == pytest.approx(ratio * w, rel=1e-12)
    e_before = 0.5 * (m * (4 * b * b + 4 * h * h) / 3) * w**2  # rotation about a corner
    assert res.energy.before == pytest.approx(e_before, rel=1e-12)
    assert res.energy.after == pytest.approx(ratio**2 * e_before, rel=1e-12)


def test_ball_on_floor() -> None:
    """Newton's restitution on a fixed floor: v_z'' = -e v_z', E_d = (1 - e^2) m v_z^2/2."""
    res = _solve("ball_on_floor.toml")
    assert res.bodies["ball"].velocity_after == pytest.approx([1.0, 0.0, 1.8], rel=1e-12)
    assert res.energy.dissipated == pytest.approx((1 - 0.36) * 0.5 * 9 / 2, rel=1e-12)


EXPECTED_FLAGS = {"paper_pendulum_plane.toml": ["statically_indeterminate"]}


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.name)
def test_every_example_solves_cleanly(path) -> None:
    res = _solve(path.name)
    assert res.flag_codes() == EXPECTED_FLAGS.get(path.name, [])
    assert res.momentum.linear_residual < 1e-12
    assert res.momentum.angular_residual < 1e-12

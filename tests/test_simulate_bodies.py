"""Simulated impacts between movable bodies of different shapes: a sphere and a box.

Closed forms (W. Goldsmith, *Impact*, Arnold 1960, ch. 2 and 4; W. J. Stronge, *Impact
Mechanics*, 2nd ed., Cambridge 2018, ch. 2): a frictionless impact of a sphere (mass m1) on a
free body (m2, inertia J2 about the axis normal to the plane of the impact) at a lever ``d``
from the body's centre of mass, along the normal, with Newton's coefficient e and approach
speed v: the effective mass ``1/m = 1/m1 + 1/m2 + d^2/J2``, the impulse ``P = (1 + e) m v``,
the energy lost ``E_d = 1/2 m (1 - e^2) v^2``; central (d = 0):
``v1' = (m1 - e m2) v / (m1 + m2)``, ``v2' = (1 + e) m1 v / (m1 + m2)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carnot.simulate import parse_simulation, run

M1, M2, R = 0.5, 2.0, 0.05
SIZE = [0.2, 0.3, 0.4]  # the box's edges (m)


def _scene(offset: float, e: float, v: float, gravity: float = 0.0) -> dict:
    return {"format": 1, "simulation": {"duration": 0.5, "gravity": [0.0, -gravity, 0.0]},
            "bodies": {"ball": {"mass": M1, "shape": "sphere", "radius": R,
                                "position": [-0.5, offset, 0.0], "velocity": [v, 0.0, 0.0]},
                       "box": {"mass": M2, "shape": "box", "size": SIZE}},
            "pairs": [{"a": "ball", "b": "box", "restitution": e}]}  # fmt: skip


def _first_impact(res):  # type: ignore[no-untyped-def]
    return next(ev for ev in res.events if ev.kind == "impact")


@pytest.mark.parametrize("e", [0.3, 0.6, 1.0])
def test_sphere_hits_a_free_box_centrally(e) -> None:  # type: ignore[no-untyped-def]
    v = 3.0
    res = run(parse_simulation(_scene(0.0, e, v)))
    ev = _first_impact(res)
    gap = 0.5 - SIZE[0] / 2 - R
    assert ev.time == pytest.approx(gap / v, rel=1e-12)
    bodies = ev.impact.result.bodies
    assert bodies["ball"].velocity_after[0] == pytest.approx((M1 - e * M2) * v / (M1 + M2),
                                                             abs=1e-12)
    assert bodies["box"].velocity_after[0] == pytest.approx((1 + e) * M1 * v / (M1 + M2),
                                                            abs=1e-12)
    lost = 0.5 * M1 * M2 / (M1 + M2) * (1 - e * e) * v * v
    energy = ev.impact.result.energy
    assert energy.dissipated == pytest.approx(lost, abs=1e-12)
    assert energy.dissipated_theorem == pytest.approx(lost, abs=1e-12)
    assert abs(res.energy.residual) <= 1e-12 * res.energy.initial


def test_sphere_hits_a_free_box_off_centre_and_spins_it() -> None:
    e, v, d = 0.5, 2.0, 0.1  # the ball's path 0.1 m above the box's centre (face x = -0.1)
    res = run(parse_simulation(_scene(d, e, v)))
    ev = _first_impact(res)
    j2 = M2 * (SIZE[0] ** 2 + SIZE[1] ** 2) / 12  # about z
    m = 1 / (1 / M1 + 1 / M2 + d * d / j2)
    impulse = (1 + e) * m * v
    box = ev.impact.result.bodies["box"]
    ball = ev.impact.result.bodies["ball"]
    assert box.velocity_after[0] == pytest.approx(impulse / M2, rel=1e-12)
    # the impulse +x at lever (-0.1, 0.1): omega_z = -(0.1 P)/J2
    assert box.angular_velocity_after[2] == pytest.approx(-impulse * d / j2, rel=1e-12)
    assert ball.velocity_after[0] == pytest.approx(v - impulse / M1, rel=1e-12)
    energy = ev.impact.result.energy
    assert energy.dissipated == pytest.approx(0.5 * m * (1 - e * e) * v * v, rel=1e-12)
    assert energy.dissipated_theorem == pytest.approx(energy.dissipated, rel=1e-12)
    # the box turns away and the ball goes back: no second impact in the rest of the run
    assert sum(ev.kind == "impact" for ev in res.events) == 1
    assert abs(res.energy.residual) <= 1e-10 * res.energy.initial


def test_ball_dropped_on_a_box_resting_on_the_floor_rebounds_at_e_v() -> None:
    """The box rests on a floor (plastic): struck from above, its corners are pushed into the
    floor, join the impact (the law of several contacts), and the box stays; the ball
    leaves at e times its speed, as from the floor itself."""
    g, h, e = 9.81, 0.3, 0.7
    data = {"format": 1, "simulation": {"duration": 0.3, "gravity": [0.0, -g, 0.0]},
            "bodies": {"ball": {"mass": M1, "shape": "sphere", "radius": R,
                                "position": [0.0, SIZE[1] + R + h, 0.0]},
                       "box": {"mass": M2, "shape": "box", "size": SIZE,
                               "position": [0.0, SIZE[1] / 2, 0.0]},
                       "floor": {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0],
                                                          "normal": [0.0, 1.0, 0.0]}}},
            "pairs": [{"a": "ball", "b": "box", "restitution": e},
                      {"a": "box", "b": "floor", "restitution": 0.0},
                      {"a": "ball", "b": "floor", "restitution": 0.0}]}  # fmt: skip
    res = run(parse_simulation(data))
    ev = _first_impact(res)
    speed = math.sqrt(2 * g * h)
    assert ev.time == pytest.approx(math.sqrt(2 * h / g), rel=1e-12)
    bodies = ev.impact.result.bodies
    assert bodies["ball"].velocity_after[1] == pytest.approx(e * speed, rel=1e-9)
    np.testing.assert_allclose(bodies["box"].velocity_after, 0.0, atol=1e-9)
    assert ev.impact.result.energy.dissipated == pytest.approx(
        0.5 * M1 * (1 - e * e) * speed**2, rel=1e-9)  # fmt: skip
    assert abs(res.energy.residual) <= 1e-9 * res.energy.initial


def test_box_strikes_a_free_box_face_on_like_a_central_impact() -> None:
    """A small box (4 corners striking at once: the law of several contacts) moving face-on
    into a larger free box: the velocities of a central collision."""
    m1, m2, e, v = 1.0, 3.0, 0.5, 2.0
    data = {"format": 1, "simulation": {"duration": 0.4, "gravity": [0.0, 0.0, 0.0]},
            "bodies": {"small": {"mass": m1, "shape": "box", "size": [0.2, 0.2, 0.2],
                                 "position": [-0.6, 0.0, 0.0], "velocity": [v, 0.0, 0.0]},
                       "large": {"mass": m2, "shape": "box", "size": [0.4, 0.6, 0.6]}},
            "pairs": [{"a": "small", "b": "large", "restitution": e}]}  # fmt: skip
    res = run(parse_simulation(data))
    ev = _first_impact(res)
    assert ev.time == pytest.approx((0.6 - 0.1 - 0.2) / v, rel=1e-12)
    assert len(ev.contacts) == 4  # the small box's four leading corners
    bodies = ev.impact.result.bodies
    np.testing.assert_allclose(bodies["small"].velocity_after,
                               [(m1 - e * m2) * v / (m1 + m2), 0, 0], atol=1e-12)
    np.testing.assert_allclose(bodies["large"].velocity_after,
                               [(1 + e) * m1 * v / (m1 + m2), 0, 0], atol=1e-12)
    np.testing.assert_allclose(bodies["large"].angular_velocity_after, 0.0, atol=1e-12)
    energy = ev.impact.result.energy
    lost = 0.5 * m1 * m2 / (m1 + m2) * (1 - e * e) * v * v
    assert energy.dissipated == pytest.approx(lost, rel=1e-12)
    assert energy.dissipated_theorem == pytest.approx(lost, rel=1e-12)
    assert sum(ev.kind == "impact" for ev in res.events) == 1

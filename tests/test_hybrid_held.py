"""Contacts held in the flow (carnot.hybrid.flow.held_flow, carnot.hybrid.simulate): a point
on a plane after a plastic strike or a chatter, sticking while ``|F_t| <= mu F_n``, sliding
against Coulomb's force ``-mu F_n sign(v_t)`` otherwise, released where ``F_n`` falls to zero;
each change an event found on the dense output, the friction's work in the ledger.

Closed forms (a particle of mass m on a plane inclined at ``a``, gravity g):

* sliding on level ground from ``v``: it stops after ``v / (mu g)`` s and ``v^2 / (2 mu g)`` m,
  friction taking ``m v^2 / 2``;
* thrown up an incline with ``mu < tan a``: it decelerates at ``g (sin a + mu cos a)``, stops,
  and slides back at ``g (sin a - mu cos a)``; with ``mu > tan a`` at rest it stays;
* a ball dropped from h with restitution e bounces at ``t_k``, the series accumulating at
  ``t_1 + 2 e v_1 / (g (1 - e))``, ``t_1 = sqrt(2 h / g)``, ``v_1 = g t_1`` (then held);
* a cart on the ground carrying a pendulum (a rod of length L, bob m_p): while the cart
  sticks the pendulum swings about a fixed pivot with the rod's tension
  ``T = m_p (g cos theta + L theta'^2)``, so the ground's force on the cart is
  ``F_n = m_c g + T cos theta``, ``F_t = -T sin theta``; the cart slips where
  ``mu F_n = |F_t|``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from carnot.hybrid.flow import Hold, held_flow
from carnot.hybrid.guards import motion_model, plane_guard
from carnot.hybrid.mechanism import Body, Mechanism, compile_mechanism
from carnot.hybrid.model import HybridModel
from carnot.hybrid.simulate import simulate
from carnot.hybrid.strike import Law

G = 9.81


def particle(slope: float = 0.0, m: float = 2.0) -> HybridModel:
    """A point mass over the plane through the origin rising at ``slope`` (rad) towards +x:
    its normal ``(-sin a, cos a)``, its tangent ``t = (cos a, sin a)`` (uphill)."""
    x, y = sp.symbols("x y")
    mech = compile_mechanism(Mechanism(
        floating=(x, y), coordinates=(x, y), embedding=(x, y),
        bodies=(Body(mass=m, position=(x, y)),), points={"p": (x, y)}, gravity=(0, -G)), {})
    guard = plane_guard(mech, "p", normal=(-math.sin(slope), math.cos(slope)), name="ground")
    return motion_model(mech, [guard], coordinates=("x", "y"), total_mass=m)


def closes(run: object) -> bool:
    energy = run.energy  # type: ignore[attr-defined]
    return abs(energy["residual"]) < 1e-10 * max(1.0, abs(energy["initial"]))


def test_a_point_landing_with_friction_slides_to_a_stop_as_coulomb_says() -> None:
    m, mu, h, v_x, v_y = 2.0, 0.3, 0.1, 3.0, -1.0
    run = simulate(particle(m=m), np.array([0.0, h, v_x, v_y]), 2.0, Law(friction=mu))
    assert [e.kind for e in run.events] == ["impact", "contact_start", "stick"]
    impact, start, stick = run.events
    v_n = math.sqrt(v_y**2 + 2 * G * h)  # at the strike; the plastic strike slips throughout
    t_hit = (v_y + v_n) / G
    assert impact.time == pytest.approx(t_hit, abs=1e-12)
    v_t = v_x - mu * v_n
    assert start.state[2] == pytest.approx(v_t, rel=1e-12) and start.flags[1:] == ("sliding",
                                                                                    "+t")
    assert stick.time - start.time == pytest.approx(v_t / (mu * G), abs=1e-10)
    assert stick.state[0] - start.state[0] == pytest.approx(v_t**2 / (2 * mu * G), abs=1e-10)
    assert abs(stick.state[2]) < 1e-12 and stick.flags[1:] == ("sticking",)
    assert run.energy["sliding"] == pytest.approx(m * v_t**2 / 2, rel=1e-10)
    assert np.allclose(run.final, [stick.state[0], 0.0, 0.0, 0.0], atol=1e-12)
    assert closes(run)


@pytest.mark.parametrize("slope", [0.3, -0.2])
def test_thrown_up_an_incline_it_stops_and_slides_back(slope: float) -> None:
    """Thrown along the plane at 2 m/s uphill (mu < tan |a|): the slide's stop, its return
    the other way, and the position and speed at the end, each the closed form; friction
    takes mu m g cos a over the whole path."""
    m, mu, speed, duration = 2.0, 0.1, 2.0, 1.5
    t = np.array([math.cos(slope), math.sin(slope)])
    uphill = 1.0 if slope > 0 else -1.0
    x0 = np.concatenate([[0.0, 0.0], uphill * speed * t])
    run = simulate(particle(slope, m), x0, duration, Law(friction=mu))
    assert [e.kind for e in run.events] == ["contact_start", "slip"]
    up = G * (abs(math.sin(slope)) + mu * math.cos(slope))
    down = G * (abs(math.sin(slope)) - mu * math.cos(slope))
    t_stop = speed / up
    assert run.events[1].time == pytest.approx(t_stop, abs=1e-10)
    back = duration - t_stop
    s_end = speed**2 / (2 * up) - down * back**2 / 2  # uphill distance from the start
    assert float(run.final[:2] @ t) * uphill == pytest.approx(s_end, abs=1e-9)
    assert float(run.final[2:] @ t) * uphill == pytest.approx(-down * back, abs=1e-9)
    path = speed**2 / (2 * up) + down * back**2 / 2
    assert run.energy["sliding"] == pytest.approx(mu * m * G * math.cos(slope) * path, rel=1e-9)
    assert closes(run)


def test_at_rest_on_an_incline_it_sticks_inside_the_cone_and_slides_outside() -> None:
    slope = 0.3
    stays = simulate(particle(slope), np.zeros(4), 1.0, Law(friction=math.tan(slope) + 0.01))
    assert [e.kind for e in stays.events] == ["contact_start"]
    assert stays.events[0].flags[1:] == ("sticking",)
    assert np.allclose(stays.final, 0.0, atol=1e-14) and stays.energy["sliding"] == 0.0
    mu = 0.2  # tan 0.3 = 0.309: it slides down from rest (a slide that starts at zero speed)
    slides = simulate(particle(slope), np.zeros(4), 1.0, Law(friction=mu))
    assert [e.kind for e in slides.events] == ["contact_start"]
    assert slides.events[0].flags[1:] == ("sliding", "-t")
    a = G * (math.sin(slope) - mu * math.cos(slope))
    t = np.array([math.cos(slope), math.sin(slope)])
    assert float(slides.final[:2] @ t) == pytest.approx(-a / 2, abs=1e-10)
    assert float(slides.final[2:] @ t) == pytest.approx(-a, abs=1e-10)
    assert closes(slides)


def test_a_bouncing_point_chatters_into_a_hold_at_the_accumulation_time() -> None:
    e, h = 0.5, 0.2
    run = simulate(particle(), np.array([0.0, h, 0.0, 0.0]), 1.0, Law(restitution=e))
    held = next(ev for ev in run.events if ev.kind == "contact_start")
    t1 = math.sqrt(2 * h / G)
    accumulation = t1 + 2 * e * G * t1 / (G * (1 - e))
    assert held.time == pytest.approx(accumulation, abs=1e-7 * e / (1 - e) + 1e-12)
    assert run.events[-1] is held and np.allclose(run.final, [0, 0, 0, 0], atol=1e-9)
    assert closes(run)


def cart_pendulum(m_c: float = 1.0, m_p: float = 1.0, length: float = 1.0) -> HybridModel:
    x, y, th = sp.symbols("x y theta")
    bob = (x + length * sp.sin(th), y - length * sp.cos(th))
    mech = compile_mechanism(Mechanism(
        floating=(x, y, th), coordinates=(x, y, th), embedding=(x, y, th),
        bodies=(Body(mass=m_c, position=(x, y)), Body(mass=m_p, position=bob)),
        points={"cart": (x, y)}, gravity=(0, -G)), {})
    return motion_model(mech, [plane_guard(mech, "cart", name="ground")],
                        coordinates=("x", "y", "theta"), total_mass=m_c + m_p)  # fmt: skip


def test_a_cart_slips_where_the_pendulum_pulls_it_out_of_its_cone() -> None:
    """A cart on the ground with a pendulum swinging from it (mu = 0.3, from 1 rad at rest):
    it slides, sticks, and slips again as the swing goes. At each slip from sticking the
    pendulum's pull (the rod's tension, by hand) is on the cone; at each stick the cart is
    at rest; the held force is the hand's; the friction's work closes the ledger."""
    m_c = m_p = length = 1.0
    mu = 0.3
    model = cart_pendulum(m_c, m_p, length)
    run = simulate(model, np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]), 3.0, Law(friction=mu))
    kinds = [e.kind for e in run.events]
    assert kinds[0] == "contact_start" and kinds.count("stick") >= 2 and kinds.count("slip") >= 2

    def by_hand(x: np.ndarray) -> tuple[float, float]:
        th, rate = x[2], x[5]
        tension = m_p * (G * math.cos(th) + length * rate**2)
        return m_c * G + tension * math.cos(th), -tension * math.sin(th)

    for before, ev in zip(run.events, run.events[1:], strict=False):
        if ev.kind == "stick":
            assert abs(ev.state[3]) < 1e-12
            f_n, f_t = held_flow(model, (Hold(index=0),), ev.state, mu)[1][0]
            assert (f_n, f_t) == pytest.approx(by_hand(ev.state), rel=1e-10)
        if ev.kind == "slip" and before.kind == "stick":
            f_n, f_t = by_hand(ev.state)
            assert mu * f_n == pytest.approx(abs(f_t), rel=1e-9)
            assert ev.flags[2] == ("-t" if f_t > 0 else "+t")  # against the sticking force
    assert run.energy["sliding"] > 0 and closes(run)


def test_a_rod_landing_on_one_end_then_the_other_comes_to_rest_on_both() -> None:
    """A rod dropped tilted lands on its lower end (held, sliding), then its other end
    strikes with the first one taking part: both end at rest on the ground, nothing goes
    through it, and the ledger (strikes and friction) closes."""
    x, y, th = sp.symbols("x y theta")
    m, length = 1.0, 1.0
    ends = {"a": (x - length / 2 * sp.cos(th), y - length / 2 * sp.sin(th)),
            "b": (x + length / 2 * sp.cos(th), y + length / 2 * sp.sin(th))}  # fmt: skip
    mech = compile_mechanism(Mechanism(
        floating=(x, y, th), coordinates=(x, y, th), embedding=(x, y, th),
        bodies=(Body(mass=m, position=(x, y), inertia=m * length**2 / 12, angle=th),),
        points=ends, gravity=(0, -G)), {})
    rod = motion_model(mech, [plane_guard(mech, "a", name="end_a"),
                              plane_guard(mech, "b", name="end_b")],
                       coordinates=("x", "y", "theta"), total_mass=m)  # fmt: skip
    run = simulate(rod, np.array([0.0, 0.5, 0.2, 0.0, 0.0, 0.0]), 1.0, Law(friction=0.5))
    strikes = [e for e in run.events if e.kind == "impact"]
    assert [e.strike.guard.name for e in strikes] == ["end_a", "end_b"]  # type: ignore[union-attr]
    last = strikes[-1].strike
    assert last is not None and len(last.result.contacts) == 2  # the held end took part
    assert np.allclose(run.final[1:], [0.0, 0.0, 0.0, 0.0, 0.0], atol=1e-10)
    assert run.events[-1].kind == "contact_start" and closes(run)

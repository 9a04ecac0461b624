"""carnot simulate: event-driven motion against published closed forms and independent
integrations, each with its source."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from carnot.cli import main
from carnot.simulate import parse_simulation, run
from carnot.simulate.ground import GroundMotion
from carnot.simulate.motion import BodyState, Flight, SimBody
from carnot.simulate.output import to_dict
from carnot.simulate.shapes import Convex, box_vertices

G = 9.81
EXAMPLES = Path(__file__).resolve().parent.parent / "examples" / "simulate"
FLOOR = {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}}


def _ball(e: float, height: float, duration: float, friction: float = 0.0) -> dict:
    return {
        "format": 1,
        "simulation": {"duration": duration, "gravity": [0.0, -G, 0.0]},
        "bodies": {"ball": {"mass": 0.2, "shape": "sphere", "radius": 0.05,
                            "position": [0.0, height + 0.05, 0.0]}, "floor": FLOOR},
        "pairs": [{"a": "ball", "b": "floor", "restitution": e, "friction": friction}],
    }  # fmt: skip


# --- the bouncing ball ----------------------------------------------------------------------
# Closed forms of a ball dropped from rest from height h on a rigid floor, Newton's e: first
# impact t_1 = sqrt(2h/g) at speed v_1 = g t_1, k-th rebound speed e^k v_1, flights
# 2 e^k v_1 / g, accumulation t_inf = t_1 (1 + e)/(1 - e) (B. Brogliato, Nonsmooth Mechanics,
# 3rd ed., Springer 2016, section 1.3.2; A. Goldsmith, Impact, 1960, ch. 1).


@pytest.mark.parametrize("e", [0.5, 0.8])
def test_bouncing_ball_times_speeds_and_accumulation(e) -> None:
    h = 1.0
    t1 = math.sqrt(2 * h / G)
    t_inf = t1 * (1 + e) / (1 - e)
    res = run(parse_simulation(_ball(e, h, t_inf + 1.0)))
    impacts = [ev for ev in res.events if ev.kind == "impact"]
    assert len(impacts) == 3  # the third shows the geometric series; the rest is summed
    expected_t = t1
    for k, ev in enumerate(impacts):
        assert ev.time == pytest.approx(expected_t, abs=1e-12)  # located to 1e-12 s
        after = ev.impact.result.bodies["ball"].velocity_after[1]
        assert after == pytest.approx(e ** (k + 1) * G * t1, rel=1e-12)
        expected_t += 2 * e ** (k + 1) * G * t1 / G
    (acc,) = [ev for ev in res.events if ev.kind == "accumulation"]
    assert acc.time == pytest.approx(t_inf, abs=1e-12)
    # the series' energy two ways: direct difference and the theorem summed over the series
    assert acc.energy["dissipated"] == pytest.approx(acc.energy["dissipated_theorem"], rel=1e-9)
    kinds = [ev.kind for ev in res.events]
    assert kinds[-1] == "rest" and res.final[0].position[1] == pytest.approx(0.05, abs=1e-15)
    # after t_inf the ball rests and the simulation goes on to the end, every joule accounted:
    # the drop's whole m g h went into the impacts
    assert res.energy.impacts == pytest.approx(0.2 * G * h, rel=1e-12)
    assert abs(res.energy.residual) <= 1e-12 * res.energy.initial


def test_every_impact_has_both_routes_of_the_ledger() -> None:
    res = run(parse_simulation(_ball(0.7, 0.5, 1.0, friction=0.3)))
    for ev in res.events:
        if ev.kind == "impact":
            led = ev.impact.result.energy
            assert led.dissipated == pytest.approx(led.dissipated_theorem, rel=1e-9, abs=1e-15)


# --- Housner's rocking block --------------------------------------------------------------
# G. W. Housner, "The behavior of inverted pendulum structures during earthquakes", Bull.
# Seismol. Soc. Am. 53 (1963) 403-417: a rectangular block of half-width b, half-height h,
# R = sqrt(b^2 + h^2), alpha = atan(b/h), rocking on rigid ground without bounce or slip
# keeps r = 1 - 3/2 sin^2(alpha) of its angular velocity at each impact (angular momentum
# about the new corner, I_O = 4/3 m R^2), and between impacts follows
# theta'' = -p^2 sin(alpha sgn(theta) - theta), p^2 = 3 g / (4 R).

B, H = 0.1, 0.5


def _block(theta0: float, duration: float, friction: float = 2.0) -> dict:
    c, s = math.cos(theta0), math.sin(theta0)
    return {
        "format": 1,
        "simulation": {"duration": duration, "gravity": [0.0, -G, 0.0]},
        "bodies": {"block": {
            "mass": 3.0, "shape": "convex",
            "vertices": [[B, -H, 0], [B, H, 0], [-B, H, 0], [-B, -H, 0]],
            "position": [c * B - s * H, s * B + c * H, 0.0],
            "orientation": [math.cos(theta0 / 2), 0, 0, math.sin(theta0 / 2)]},
            "ground": FLOOR},
        "pairs": [{"a": "block", "b": "ground", "restitution": 0.0, "friction": friction,
                   "tangential": "stick"}],
    }  # fmt: skip


def _housner(theta0: float, count: int, method: str = "RK45") -> tuple[list[float], list[float]]:
    """Impact times and angular velocities after them, by solve_ivp on Housner's equation
    (``method`` DOP853 for 1e-11 s: RK45 at the same tolerances drifts by 1e-10 s per
    impact)."""
    alpha = math.atan(B / H)
    p2 = 3 * G / (4 * math.hypot(B, H))
    r = 1 - 1.5 * math.sin(alpha) ** 2

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [y[1], -p2 * math.sin(alpha * math.copysign(1.0, y[0]) - y[0])]

    def hit(_t: float, y: np.ndarray) -> float:
        return y[0]

    hit.terminal = True  # type: ignore[attr-defined]
    t, y, times, rates = 0.0, [theta0, 0.0], [], []
    for _ in range(count):
        sol = solve_ivp(rhs, (t, t + 10), y, events=hit, method=method, rtol=1e-12,
                        atol=1e-14 if method == "RK45" else 1e-15,
                        first_step=1e-6 if t else None)  # fmt: skip
        t = float(sol.t_events[0][0])
        w = r * float(sol.y_events[0][0][1])
        times.append(t)
        rates.append(w)
        y = [math.copysign(1e-300, w), w]
    return times, rates


def test_housner_rocking_ratio_decay_and_ledger() -> None:
    theta0 = 0.1
    res = run(parse_simulation(_block(theta0, 2.4)))
    impacts = [ev for ev in res.events if ev.kind == "impact"]
    alpha = math.atan(B / H)
    r = 1 - 1.5 * math.sin(alpha) ** 2
    times, rates = _housner(theta0, len(impacts))
    assert len(impacts) >= 4
    for ev, t_ref, w_ref in zip(impacts, times, rates, strict=True):
        body = ev.impact.result.bodies["block"]
        ratio = body.angular_velocity_after[2] / body.angular_velocity_before[2]
        # sticking and plastic (the equality law); the motion before the impact carries the
        # integrator's drift of the pivot (its velocity 1e-10 m/s: the constraint is held at
        # the acceleration level)
        assert ratio == pytest.approx(r, abs=5e-9)
        assert ev.time == pytest.approx(t_ref, abs=1e-7)  # integrator tolerance
        assert body.angular_velocity_after[2] == pytest.approx(w_ref, rel=1e-7)
        # the pivot model's assumption, checked: the old corner took no impulse and separates
        assert "closed_contacts_released" in [f.code for f in ev.impact.flags]
    assert abs(res.energy.residual) <= 1e-9 * res.energy.initial


def test_rocking_impact_times_match_housners_equation_to_1e_10_s() -> None:
    """Eight impacts of the block released from 0.1 rad, each at the time Housner's equation
    gives (integrated apart, solve_ivp rtol 1e-12) to 1e-10 s, with its angular velocity to
    1e-10. The reference is checked against Housner's closed form first: energy is kept while
    pivoting, so ``|omega_k| = r^k omega_1``, ``1/2 I_O omega_1^2 = m g R (cos(alpha -
    theta_0) - cos alpha)``, ``I_O = 4/3 m R^2``. (A corner just released by an impact came
    back unarmed: its return was found eps deeper, 4e-9 s late at the second impact and 8e-8
    s at the fourth, each error carried on in the state.)"""
    theta0, count = 0.1, 8
    res = run(parse_simulation(_block(theta0, 3.7)))
    impacts = [ev for ev in res.events if ev.kind == "impact"]
    assert len(impacts) == count
    times, rates = _housner(theta0, count, method="DOP853")
    alpha, big_r, mass = math.atan(B / H), math.hypot(B, H), 3.0
    r = 1 - 1.5 * math.sin(alpha) ** 2
    omega_1 = math.sqrt(2 * mass * G * big_r * (math.cos(alpha - theta0) - math.cos(alpha))
                        / (4 / 3 * mass * big_r**2))  # fmt: skip
    for k, rate in enumerate(rates, start=1):
        assert abs(rate) == pytest.approx(r**k * omega_1, rel=1e-11)
    for ev, t_ref, w_ref in zip(impacts, times, rates, strict=True):
        assert ev.time == pytest.approx(t_ref, abs=1e-10)
        after = ev.impact.result.bodies["block"].angular_velocity_after[2]
        assert after == pytest.approx(w_ref, rel=1e-10)
    assert abs(res.energy.residual) <= 1e-12 * res.energy.initial


def test_housner_coulomb_impact_gives_the_same_ratio() -> None:
    """Friction large enough to stick: the Coulomb law (integrated) agrees with stick."""
    res = run(parse_simulation(_block(0.1, 0.5, friction=2.0) | {"pairs": [
        {"a": "block", "b": "ground", "restitution": 0.0, "friction": 2.0}]}))
    (ev,) = [ev for ev in res.events if ev.kind == "impact"]
    body = ev.impact.result.bodies["block"]
    ratio = body.angular_velocity_after[2] / body.angular_velocity_before[2]
    assert ratio == pytest.approx(1 - 1.5 * math.sin(math.atan(B / H)) ** 2, abs=1e-8)


def test_pivoting_without_impacts_conserves_energy() -> None:
    """No impact, no friction work (a sticking pivot does none): energy to the tolerance."""
    res = run(parse_simulation(_block(0.1, 0.3)))
    assert not [ev for ev in res.events if ev.kind == "impact"]
    assert res.energy.final == pytest.approx(res.energy.initial, rel=1e-10)


# --- the rimless wheel ----------------------------------------------------------------------
# T. McGeer, "Passive dynamic walking", Int. J. Robotics Research 9 (1990) 62-82; M. J.
# Coleman, A. Chatterjee, A. Ruina, "Motions of a rimless spoked wheel", Dynamics and
# Stability of Systems 12 (1997) 139-159: with N spokes of length L (alpha = pi/N), slope
# gamma and a hub of mass m and inertia I_C, the angular velocity after each plastic impact
# tends to omega* = c omega_-, c = (m L^2 cos 2 alpha + I_C)/(m L^2 + I_C),
# omega_-^2 = 2 m g L (cos(gamma - alpha) - cos(gamma + alpha)) / (I_O (1 - c^2)).


def _wheel(w0: float, duration: float) -> dict:
    n, length, gamma, inertia = 8, 1.0, 0.08, 0.02
    al = math.pi / n
    verts = [[length * math.sin(2 * al * k), -length * math.cos(2 * al * k), 0.0]
             for k in range(n)]  # fmt: skip
    th0 = gamma - al + 1e-3
    rot = np.array([[math.cos(gamma), math.sin(gamma), 0], [-math.sin(gamma), math.cos(gamma), 0],
                    [0, 0, 1]])  # fmt: skip
    hub = rot @ np.array([length * math.sin(th0), length * math.cos(th0), 0.0])
    phi = -th0 - gamma
    return {
        "format": 1,
        "simulation": {"duration": duration, "gravity": [0.0, -G, 0.0]},
        "bodies": {"wheel": {
            "mass": 1.0, "shape": "convex", "vertices": verts,
            "inertia": [[inertia / 2, 0, 0], [0, inertia / 2, 0], [0, 0, inertia]],
            "position": hub.tolist(), "velocity": np.cross([0, 0, -w0], hub).tolist(),
            "angular_velocity": [0, 0, -w0],
            "orientation": [math.cos(phi / 2), 0, 0, math.sin(phi / 2)]},
            "slope": {"fixed": True, "plane": {"point": [0, 0, 0],
                                               "normal": [math.sin(gamma), math.cos(gamma), 0]}}},
        "pairs": [{"a": "wheel", "b": "slope", "restitution": 0.0, "friction": 5.0,
                   "tangential": "stick"}],
    }  # fmt: skip


@pytest.mark.parametrize("w0", [0.9, 1.6])
def test_rimless_wheel_converges_to_its_limit_cycle(w0) -> None:
    m, length, inertia, gamma, al = 1.0, 1.0, 0.02, 0.08, math.pi / 8
    c = (m * length**2 * math.cos(2 * al) + inertia) / (m * length**2 + inertia)
    i_o = inertia + m * length**2
    w_minus = math.sqrt(2 * m * G * length * (math.cos(gamma - al) - math.cos(gamma + al))
                        / (i_o * (1 - c * c)))  # fmt: skip
    fixed = c * w_minus
    res = run(parse_simulation(_wheel(w0, 9.0)))
    rates = [-ev.impact.result.bodies["wheel"].angular_velocity_after[2]
             for ev in res.events if ev.kind == "impact"]  # fmt: skip
    gaps = [abs(w - fixed) for w in rates]
    assert len(gaps) >= 5
    assert all(b < a for a, b in zip(gaps, gaps[1:], strict=False))  # closer at every step
    assert gaps[-1] < 0.03 * gaps[0] and gaps[-1] < 3e-3
    for ev in res.events:  # each step: the new foot sticks, the old one lifts off (checked)
        if ev.kind == "impact":
            body = ev.impact.result.bodies["wheel"]
            assert body.angular_velocity_after[2] / body.angular_velocity_before[2] == \
                pytest.approx(c, abs=1e-12)  # fmt: skip


# --- free flight ------------------------------------------------------------------------------


def test_axisymmetric_closed_form_matches_euler_integration() -> None:
    """Two routes: the regular precession of an axisymmetric body in closed form against
    DOP853 on Euler's equations (the route of general bodies)."""
    inertia = np.diag([0.3, 0.3, 0.1])
    body = SimBody(name="top", mass=1.0, inertia_body=inertia,
                   shape=Convex(vertices_body=box_vertices([1, 1, 1])))  # fmt: skip
    tilted = SimBody(name="top", mass=1.0, inertia_body=inertia + np.diag([0, 1e-6, 0]),
                     shape=body.shape)  # fmt: skip
    q0 = np.array([math.cos(0.2), math.sin(0.2), 0.1, 0.0])
    state = BodyState(position=np.zeros(3), orientation=q0 / np.linalg.norm(q0),
                      velocity=np.zeros(3), angular_velocity=np.array([1.0, -2.0, 5.0]))
    closed = Flight(body, 0.0, state, np.zeros(3), None)
    assert closed.kind == "axisymmetric"
    from scipy.integrate import solve_ivp as ivp

    from carnot.simulate.motion import quat_multiply

    def euler(_t: float, y: np.ndarray) -> np.ndarray:
        q, wb = y[:4], y[4:]
        return np.concatenate([0.5 * quat_multiply(q, np.concatenate([[0.0], wb])),
                               -np.linalg.solve(inertia, np.cross(wb, inertia @ wb))])
    r0 = state.rotation
    ref = ivp(euler, (0, 2.0), np.concatenate([state.orientation, r0.T @ state.angular_velocity]),
              rtol=1e-12, atol=1e-14, dense_output=True, method="DOP853")  # fmt: skip
    s = np.linspace(0, 2.0, 9)
    q, w = closed.rotation_at(s)
    yq = ref.sol(s)[:4].T
    assert np.allclose(np.abs(np.sum(q * yq, axis=1)), 1.0, atol=1e-10)  # same rotation
    assert tilted.rotation_kind == "general"  # and the numeric route runs for a general body
    assert Flight(tilted, 0.0, state, np.zeros(3), None).kind == "numeric"
    j_world = [body.inertia_world(m) for m in __import__("carnot.simulate.motion", fromlist=[
        "quat_matrix"]).quat_matrix(q)]  # fmt: skip
    energy = [0.5 * wi @ j @ wi for wi, j in zip(w, j_world, strict=True)]
    assert np.allclose(energy, energy[0], rtol=1e-13)


def test_tumbling_box_conserves_energy_in_flight() -> None:
    """A general (three different moments) box tumbling in flight, no impact: energy and the
    angular momentum are conserved to the integrator's tolerance."""
    data = {"format": 1, "simulation": {"duration": 1.5, "gravity": [0.0, -G, 0.0]},
            "bodies": {"die": {"mass": 0.5, "shape": "box", "size": [0.1, 0.2, 0.3],
                               "position": [0, 20.0, 0], "velocity": [1.0, 3.0, 0.0],
                               "angular_velocity": [3.0, 10.0, 0.5]}, "ground": FLOOR},
            "pairs": [{"a": "die", "b": "*", "restitution": 0.5}]}  # fmt: skip
    res = run(parse_simulation(data))
    assert not res.events
    assert res.energy.final == pytest.approx(res.energy.initial, rel=1e-11)


def test_two_balls_exchange_velocities() -> None:
    """Equal spheres, head on, e = 1, frictionless: they exchange velocities (Newton); the
    impact comes when the gap closes, at d / closing speed."""
    data = {"format": 1, "simulation": {"duration": 1.0, "gravity": [0.0, 0.0, 0.0]},
            "bodies": {"a": {"mass": 1.0, "shape": "sphere", "radius": 0.1,
                             "position": [0, 0, 0], "velocity": [2.0, 0, 0]},
                       "b": {"mass": 1.0, "shape": "sphere", "radius": 0.1,
                             "position": [1.0, 0, 0], "velocity": [-1.0, 0, 0]}},
            "pairs": [{"a": "a", "b": "b", "restitution": 1.0}]}  # fmt: skip
    res = run(parse_simulation(data))
    (ev,) = res.events
    assert ev.time == pytest.approx(0.8 / 3.0, abs=1e-14)
    assert res.final[0].velocity.tolist() == pytest.approx([-1.0, 0, 0], abs=1e-12)
    assert res.final[1].velocity.tolist() == pytest.approx([2.0, 0, 0], abs=1e-12)


# --- persistent contacts --------------------------------------------------------------------


def test_box_sliding_to_rest_dissipates_its_kinetic_energy_by_friction() -> None:
    """A box sliding on its face with Coulomb friction: deceleration mu g, stops at
    v0 / (mu g) after v0^2 / (2 mu g) (J. L. Meriam, L. G. Kraige, Engineering Mechanics:
    Dynamics, sec. 3/5), every joule of 1/2 m v0^2 in the sliding ledger; then it rests."""
    v0, mu = 2.0, 0.4
    data = {"format": 1, "simulation": {"duration": 1.0, "gravity": [0.0, -G, 0.0]},
            "bodies": {"box": {"mass": 2.0, "shape": "box", "size": [0.2, 0.1, 0.2],
                               "position": [0, 0.05, 0], "velocity": [v0, 0.0, 0.0]},
                       "ground": FLOOR},
            "pairs": [{"a": "box", "b": "ground", "restitution": 0.0, "friction": mu}]}
    res = run(parse_simulation(data))
    stop = v0 / (mu * G)
    (stick,) = [ev for ev in res.events if ev.kind == "stick"]
    assert stick.time == pytest.approx(stop, abs=1e-9)
    assert res.final[0].position[0] == pytest.approx(v0**2 / (2 * mu * G), abs=1e-9)
    assert res.energy.sliding == pytest.approx(0.5 * 2.0 * v0**2, rel=1e-9)
    assert res.events[-1].kind == "rest"


def test_sphere_rolls_under_ground_acceleration() -> None:
    """Ground motion: a sphere on a rough floor whose ground accelerates at A for T s rolls
    (in the ground's frame) at -5/7 A t (the rolling sphere under a horizontal force
    F = -m A: a = F/(m + I/r^2), Meriam & Kraige sec. 6/6); the ground's work
    -int m A v dt = 5/14 m A^2 T^2 equals the kinetic energy gained (1/2 m v^2 + 1/2 I w^2)."""
    a_g, t_rec, m = 2.0, 0.5, 1.0
    data = {"format": 1, "simulation": {"duration": 1.0, "gravity": [0.0, -G, 0.0]},
            "bodies": {"ball": {"mass": m, "shape": "sphere", "radius": 0.1,
                                "position": [0, 0.1, 0]}, "floor": FLOOR},
            "pairs": [{"a": "ball", "b": "floor", "restitution": 0.0, "friction": 1.0}]}
    sim = parse_simulation(data)
    sim = type(sim)(**{**sim.__dict__, "ground": GroundMotion.from_samples(
        [0.0, t_rec], [[a_g, 0, 0], [a_g, 0, 0]])})  # fmt: skip
    res = run(sim)
    assert res.final[0].velocity[0] == pytest.approx(-5 / 7 * a_g * t_rec, rel=1e-9)
    assert res.energy.ground_work == pytest.approx(5 / 14 * m * a_g**2 * t_rec**2, rel=1e-9)
    assert abs(res.energy.residual) <= 1e-9 * res.energy.ground_work
    assert res.energy.sliding == pytest.approx(0.0, abs=1e-12)  # rolling: no slip


def test_ground_record_integrals() -> None:
    g = GroundMotion.from_samples([0.0, 1.0, 2.0], [[0, 0, 0], [2.0, 0, 0], [0, 0, 0]])
    # triangle pulse: v(2) = area = 2, d(2) = int v = 2 (by symmetry of v about t = 1 ... )
    assert g.velocity(2.0)[0] == pytest.approx(2.0)
    assert g.displacement(1.0)[0] == pytest.approx(1.0 / 3.0)  # int_0^1 t^2 dt = 1/3
    assert g.displacement(2.0)[0] == pytest.approx(2.0)


# --- several contacts at once ---------------------------------------------------------------


def _flat_box(friction: float, tangential: str = "slip") -> dict:
    return {"format": 1, "simulation": {"duration": 0.5, "gravity": [0.0, -G, 0.0]},
            "bodies": {"box": {"mass": 1.0, "shape": "box", "size": [0.2, 0.2, 0.2],
                               "position": [0, 0.3, 0]}, "ground": FLOOR},
            "pairs": [{"a": "box", "b": "ground", "restitution": 0.5, "friction": friction,
                       "tangential": tangential}]}  # fmt: skip


def test_box_landing_flat_is_solved_simultaneously_and_flagged() -> None:
    res = run(parse_simulation(_flat_box(0.0)))
    first = res.events[0]
    assert first.kind == "impact" and len(first.contacts) == 4
    body = first.impact.result.bodies["box"]
    assert body.velocity_after[1] == pytest.approx(-0.5 * body.velocity_before[1], rel=1e-12)
    assert "simultaneous_contacts" in [f.code for f in first.impact.flags]


def test_simultaneous_coulomb_impact_goes_to_the_simultaneous_law() -> None:
    """Four rough corners struck at once (issue 14's law, no longer refused): the box lands
    flat with no slip to oppose, so Newton's rebound holds, v'' = -e v' (Stronge 2000, 2.1),
    and every corner takes part."""
    res = run(parse_simulation(_flat_box(0.5)))
    first = res.events[0]
    assert first.kind == "impact" and len(first.contacts) == 4
    result = first.impact.result
    assert result.multiple_impact == "simultaneous"
    body = result.bodies["box"]
    assert body.velocity_after[1] == pytest.approx(-0.5 * body.velocity_before[1], rel=1e-12)
    assert all(c.active for c in result.contacts)
    e = result.energy
    assert e.dissipated == pytest.approx(e.dissipated_theorem, rel=1e-12)


# --- the command line -------------------------------------------------------------------------


def test_cli_json_has_the_section_8_shape(tmp_path, capsys) -> None:
    path = tmp_path / "ball.json"
    path.write_text(json.dumps(_ball(0.5, 1.0, 3.0)))
    assert main(["simulate", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) >= {"format", "events", "final", "energy"}
    impact = out["events"][0]
    assert impact["kind"] == "impact" and set(impact) >= {"time", "bodies", "contacts", "energy"}
    assert set(impact["energy"]) >= {"before", "after", "dissipated", "dissipated_theorem"}
    e = out["energy"]
    assert e["initial"] + e["ground_work"] - e["impacts"] - e["sliding"] == \
        pytest.approx(e["final"], abs=1e-12)  # fmt: skip
    assert set(out["final"]["ball"]) == {"position", "orientation", "velocity",
                                         "angular_velocity"}  # fmt: skip


def test_cli_table_trajectory_plot_and_animation(tmp_path, capsys) -> None:
    pq = pytest.importorskip("pyarrow.parquet")
    path = tmp_path / "ball.json"
    path.write_text(json.dumps(_ball(0.5, 0.3, 1.0)))
    traj, plot, anim = tmp_path / "t.parquet", tmp_path / "e.png", tmp_path / "a.html"
    assert main(["simulate", str(path), "--trajectory", str(traj), "--plot", str(plot),
                 "--animate", str(anim), "--frames", "5"]) == 0  # fmt: skip
    assert "accumulation" in capsys.readouterr().out
    table = pq.read_table(traj)
    assert table.num_rows > 100 and "kinetic" in table.column_names
    assert plot.stat().st_size > 1000
    assert "<script" in anim.read_text()  # matplotlib's to_jshtml: a page with its player


@pytest.mark.parametrize("change, field", [
    (lambda d: d["bodies"]["ball"].update(position=[0, 0.01, 0]), "bodies.ball.position"),
    (lambda d: d["simulation"].update(duration=float("inf")), "simulation.duration"),
    (lambda d: d["simulation"].update(duration=-1.0), "simulation.duration"),
    (lambda d: d["simulation"].pop("duration"), "simulation.duration"),
    (lambda d: d["simulation"].update(duration=1e9), "simulation.duration"),
    (lambda d: d["bodies"]["ball"].pop("radius"), "bodies.ball.radius"),
    (lambda d: d["pairs"][0].update(b="wall"), "pairs[0].b"),
    (lambda d: d.update(pairs=[]), "pairs"),
    (lambda d: d["simulation"].update(max_events=0), "simulation.max_events"),
])  # fmt: skip
def test_bad_input_exits_2_with_one_line_naming_the_field(change, field, tmp_path,
                                                          capsys) -> None:  # fmt: skip
    data = _ball(0.5, 1.0, 2.0)
    change(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data).replace("Infinity", "1e999"))
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f": {field}:" in err, err


def test_event_limit_stops_a_long_run(tmp_path, capsys) -> None:
    data = _ball(1.0, 0.2, 100.0)  # elastic: bounces for ever, no accumulation
    data["simulation"]["max_events"] = 20
    path = tmp_path / "elastic.json"
    path.write_text(json.dumps(data))
    assert main(["simulate", str(path)]) == 2
    assert "simulation.max_events" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["bouncing_ball.toml", "rimless_wheel.toml",
                                  "rocking_block_pulse.toml", "rocking_overturning_map.toml",
                                  "ball_on_vibrating_table.toml"])
def test_examples_run(name) -> None:
    from carnot.simulate import load_simulation

    res = run(load_simulation(EXAMPLES / name))
    d = to_dict(res)
    assert d["events"] and abs(res.energy.residual) <= 1e-8 * abs(res.energy.initial)


# --- more: rocking onset under ground motion, records, refusals ---------------------------


def test_rocking_starts_when_the_ground_acceleration_reaches_g_tan_alpha() -> None:
    """A block at rest on both corners under a horizontal ground acceleration ramp
    a_g = k t: the uplift condition a_g = g b / h (Housner 1963; N. Makris, Y. Roussos,
    Geotechnique 50 (2000) 243-262) is reached at t* = g b / (h k); the leading corner's
    normal force reaches zero (a lift-off, then pivoting on the other corner) there."""
    k = 10.0
    data = _block(0.0, 0.4)
    data["bodies"]["block"]["position"] = [0.0, H, 0.0]
    data["bodies"]["block"]["orientation"] = [1.0, 0.0, 0.0, 0.0]
    sim = parse_simulation(data)
    sim = type(sim)(**{**sim.__dict__, "ground": GroundMotion.from_samples(
        [0.0, 1.0], [[0.0, 0, 0], [k, 0, 0]])})  # fmt: skip
    res = run(sim)
    ends = [ev for ev in res.events if ev.kind == "contact_end"]
    assert ends and ends[0].time == pytest.approx(G * B / (H * k), abs=1e-9)
    assert abs(res.energy.residual) <= 1e-9 * res.energy.initial


def test_ground_record_is_validated(tmp_path, capsys) -> None:
    record = tmp_path / "quake.csv"
    record.write_text("t,a\n0.0,1.0\n0.2,2.0\n0.1,0.0\n")
    data = _ball(0.5, 1.0, 1.0)
    data["simulation"]["ground_motion"] = "quake.csv"
    path = tmp_path / "s.json"
    path.write_text(json.dumps(data))
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "simulation.ground_motion (row 3): times must increase strictly" in err


def test_a_resting_stack_of_spheres_is_refused_in_one_line(tmp_path, capsys) -> None:
    """One sphere dropped onto another resting on the floor: the impact (two contacts, the
    lower one joining) is solved, then the persistent sphere-on-sphere contact is refused."""
    data = {"format": 1, "simulation": {"duration": 1.0},
            "bodies": {"a": {"mass": 1, "shape": "sphere", "radius": 0.1, "position": [0, 0.1, 0]},
                       "b": {"mass": 1, "shape": "sphere", "radius": 0.1, "position": [0, 0.5, 0]},
                       "floor": FLOOR},
            "pairs": [{"a": "a", "b": "*", "restitution": 0.0},
                      {"a": "b", "b": "*", "restitution": 0.0}]}  # fmt: skip
    path = tmp_path / "stack.json"
    path.write_text(json.dumps(data))
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "two movable spheres" in err


def test_ball_bouncing_down_a_rough_slope_settles_and_the_ledger_closes() -> None:
    gamma = 0.3
    data = _ball(0.5, 1.0, 2.0, friction=0.3)
    data["bodies"]["floor"] = {"fixed": True, "plane": {
        "point": [0.0, 0.0, 0.0], "normal": [math.sin(gamma), math.cos(gamma), 0.0]}}
    res = run(parse_simulation(data))
    kinds = [ev.kind for ev in res.events]
    assert "accumulation" in kinds and kinds.count("impact") > 3
    assert abs(res.energy.residual) <= 1e-12 * res.energy.initial


# --- properties -------------------------------------------------------------------------------


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(e=st.floats(0.0, 0.9), height=st.floats(0.05, 1.0), friction=st.floats(0.0, 1.0),
       slope=st.floats(0.0, 0.4), spin=st.floats(-20.0, 20.0))  # fmt: skip
def test_a_ball_on_any_slope_keeps_every_joule(e, height, friction, slope, spin) -> None:
    """Whatever the law and the slope: no impact creates energy, and the ledger closes."""
    data = _ball(e, height, 1.0, friction=friction)
    data["bodies"]["ball"]["angular_velocity"] = [0.0, 0.0, spin]
    data["bodies"]["floor"] = {"fixed": True, "plane": {
        "point": [0.0, 0.0, 0.0], "normal": [math.sin(slope), math.cos(slope), 0.0]}}
    res = run(parse_simulation(data))
    scale = res.energy.initial + 0.2 * G * 2.0
    for ev in res.events:
        if ev.impact is not None:
            assert ev.impact.result.energy.dissipated >= -1e-12 * scale
    assert abs(res.energy.residual) <= 1e-9 * scale


# --- a rocking block coming to rest: its impacts summed ----------------------------------
# Housner (1963): between impacts the block pivots on a corner, its half cycle lasting
# 2 int_0^theta_m dtheta/theta'; the angular velocity after impact j is r^j omega. Linearised
# (slender blocks), the half cycle is (2/p) artanh(omega / (p alpha)) (Housner's eq. for the
# free rocking of a slender block, ``theta(t) = alpha - (alpha - theta_0) cosh(p t)``).


def test_half_cycle_tends_to_housners_slender_block_formula() -> None:
    from carnot.simulate.zeno import half_cycle

    p2 = 3 * G / (4 * 0.5)
    p = math.sqrt(p2)
    for alpha in (1e-3, 1e-2):
        for fraction in (0.1, 0.5, 0.9):  # omega as a fraction of the overturning speed
            omega = fraction * p * alpha
            linear = 2 / p * math.atanh(omega / (p * alpha))
            # the linearisation's error is of the order alpha^2
            assert half_cycle(omega, p2, alpha) == pytest.approx(linear, rel=3 * alpha**2)


def test_rocking_block_comes_to_rest_at_the_sum_of_its_half_cycles() -> None:
    """Released from 0.1 rad: three impacts show the ratio r, then the series is summed to
    t_inf; the reference sums the same series by integrating Housner's equation impact by
    impact (150 of them, then the small-angle tail 2 omega / (p^2 sin alpha (1 - r)))."""
    theta0 = 0.1
    res = run(parse_simulation(_block(theta0, 20.0)))
    kinds = [ev.kind for ev in res.events]
    assert kinds.count("impact") == 3 and "accumulation" in kinds and kinds[-1] == "rest"
    acc = next(ev for ev in res.events if ev.kind == "accumulation")
    alpha = math.atan(B / H)
    r = 1 - 1.5 * math.sin(alpha) ** 2
    p2 = 3 * G / (4 * math.hypot(B, H))
    times, rates = _housner(theta0, 150)
    t_inf = times[-1] + 2 * abs(rates[-1]) / (p2 * math.sin(alpha) * (1 - r))
    assert acc.time == pytest.approx(t_inf, abs=1e-7)  # the reference integrator's tolerance
    assert acc.energy["ratio"] == pytest.approx(r, abs=5e-9)
    # the series took every joule left above rest: by the theorem and directly
    assert acc.energy["dissipated"] == pytest.approx(acc.energy["dissipated_theorem"],
                                                     rel=1e-12)
    potential = 3.0 * G * math.hypot(B, H) * (math.cos(alpha - theta0) - math.cos(alpha))
    # (the pivot phases are integrated: to their tolerance; each corner's return found at its
    # gap's zero, not eps deeper, so that the block ends upright to round-off)
    assert res.energy.impacts == pytest.approx(potential, rel=1e-10)
    assert res.energy.final == pytest.approx(3.0 * G * H, rel=1e-12)  # upright, at rest
    assert abs(res.energy.residual) <= 1e-9 * res.energy.initial

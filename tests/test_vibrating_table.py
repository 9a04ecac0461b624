"""A ball on a sinusoidally vibrating table (``[simulation] ground_oscillation``) against
Holmes' period-1 orbit in closed form, its stability from the exact impact map's Jacobian
(checked against finite differences of carnot's own simulated map), and the period doubling
where that Jacobian says; bad input; the ledger of a block sliding and rocking on a table
that shakes sideways.

Sources:
- P. J. Holmes, "The dynamics of repeated impacts with a sinusoidally vibrating table",
  J. Sound Vib. 84 (1982) 173-189: the table ``s(t) = A sin(w t + phi)``, Newton's ``e``; the
  period-1 orbit strikes once per period ``T = 2 pi / w`` at the same phase ``phi``:
  ``Gamma cos(phi) = pi (1 - e) / (1 + e)``, ``Gamma = A w^2 / g``.
- J. Guckenheimer and P. Holmes, *Nonlinear Oscillations, Dynamical Systems, and
  Bifurcations of Vector Fields*, Springer 1983, section 2.4: the high-bounce map
  ``phi' = phi + v``, ``v' = alpha v - gamma cos(phi + v)`` (``alpha = e``, ``gamma = 2 (1 +
  e) Gamma``, the table's displacement neglected in the flight time) has its period-1 orbit
  stable for ``(2 pi (1 - alpha))^2 < gamma^2 < (2 pi (1 - alpha))^2 + 4 (1 + alpha)^2``,
  that is ``0 < Gamma sin(phi) < 1``.

The exact map (derived here, no high-bounce approximation). State just after impact ``k``:
the table's phase ``theta_k`` and the ball's upward velocity ``V_k`` (world). The flight time
``tau`` solves ``F = A sin(theta) + V tau - g tau^2 / 2 - A sin(theta + w tau) = 0``; then
``theta' = theta + w tau`` and ``V' = -e (V - g tau) + (1 + e) A w cos(theta')``. On the
period-1 orbit ``tau = T``, ``V = g T / 2``, the ball lands at ``-g T / 2`` on a table
moving at ``u = A w cos(phi)``, and Newton's law gives ``g T / 2 - u = e (g T / 2 + u)``:
Holmes' condition, exactly. Implicit differentiation (``F_theta = 0``, ``F_V = T``, ``F_tau =
-(g T / 2 + u) = -g T / (1 + e)``) gives the Jacobian of ``(theta, V) -> (theta', V')``

    J = [[1, a], [b, e^2 + a b]],  a = 2 pi (1 + e) / (g T),  b = -(1 + e) A w sin(phi),

so ``det J = e^2`` and ``tr J = 1 + e^2 - (1 + e)^2 Gamma sin(phi)``. By Jury's test both
eigenvalues lie inside the unit circle iff ``1 - tr + det > 0`` and ``1 + tr + det > 0``:
``0 < Gamma sin(phi) < 2 (1 + e^2) / (1 + e)^2``. The root ``sin(phi) < 0`` is unstable (an
eigenvalue above 1); past the upper bound an eigenvalue crosses -1, a period doubling. As
``e -> 1`` the bound tends to Guckenheimer and Holmes' ``Gamma sin(phi) < 1``; at ``e = 0.5``
it is 1.111, not 1, which the simulations below tell apart.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from holmes import DOUBLING, FREQUENCY, HOLMES, RADIUS, E, G, T, W
from holmes import amplitude as _amplitude
from holmes import orbit as _orbit
from scipy.integrate import quad

from carnot.cli import main
from carnot.simulate import load_simulation, parse_simulation, run
from carnot.simulate.events import Feature
from carnot.simulate.ground import Oscillation


def _scenario(gamma: float, phase: float, v_up: float, periods: float) -> dict:
    """The ball just after an impact at ``t = 0``, the table at ``phase``, leaving at ``v_up``
    (m/s, world): relative to the table, ``v_up - A w cos(phase)``."""
    a = _amplitude(gamma)
    return {
        "format": 1,
        "simulation": {"duration": periods * T, "gravity": [0.0, -G, 0.0],
                       "ground_oscillation": {"amplitude": a, "frequency": FREQUENCY,
                                              "direction": [0.0, 1.0, 0.0], "phase": phase}},
        "bodies": {"ball": {"mass": 0.1, "shape": "sphere", "radius": RADIUS,
                            "position": [0.0, RADIUS, 0.0],
                            "velocity": [0.0, v_up - a * W * math.cos(phase), 0.0]},
                   "table": {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0],
                                                      "normal": [0.0, 1.0, 0.0]}}},
        "pairs": [{"a": "ball", "b": "table", "restitution": E}],
    }  # fmt: skip


def _impact_times(gamma: float, phase: float, v_up: float, periods: float) -> np.ndarray:
    res = run(parse_simulation(_scenario(gamma, phase, v_up, periods)))
    _closes(res)
    return np.array([ev.time for ev in res.events if ev.kind == "impact"])


def _closes(res) -> None:
    """``initial + ground_work - impacts - sliding = final`` to round-off (flight is exact)."""
    led = res.energy
    scale = max(abs(led.initial), abs(led.ground_work), abs(led.impacts))
    assert abs(led.residual) <= 1e-13 * scale, (led.residual, scale)


def _jacobian(gamma: float, phi: float) -> np.ndarray:
    """The exact map's Jacobian on the period-1 orbit (module docstring)."""
    a = 2 * math.pi * (1 + E) / (G * T)
    b = -(1 + E) * _amplitude(gamma) * W * math.sin(phi)
    return np.array([[1.0, a], [b, E * E + a * b]])


def _simulated_map(gamma: float, theta: float, v_up: float) -> np.ndarray:
    """carnot's impact-to-impact map: ``(theta, V)`` just after one impact to the same just
    after the next (``theta`` less ``2 pi``), read off its first impact event."""
    res = run(parse_simulation(_scenario(gamma, theta, v_up, 1.5)))
    hit = next(ev for ev in res.events if ev.kind == "impact")
    after = hit.impact.states[0].velocity[1]  # relative to the table
    theta1 = W * hit.time + theta
    return np.array([theta1 - 2 * math.pi, after + _amplitude(gamma) * W * math.cos(theta1)])


def _deviations(times: np.ndarray) -> np.ndarray:
    """``t_k - k T``: the phase's departure from the period-1 orbit, times ``1/w``."""
    return times - T * np.arange(1, len(times) + 1)


def test_oscillation_closed_forms_are_each_others_derivatives() -> None:
    """``v_g = d'(t)``, ``a_g = v_g'(t)`` by central differences, and the flight's ground work
    in closed form against a quadrature of ``-m a_g . v``."""
    table = Oscillation(amplitude=0.01, frequency=3.0, direction=np.array([0.6, 0.8, 0.0]),
                        phase=0.7)  # fmt: skip
    h = 1e-6
    for t in (0.0, 0.13, 2.9):
        v_fd = (table.displacement(t + h) - table.displacement(t - h)) / (2 * h)
        a_fd = (table.velocity(t + h) - table.velocity(t - h)) / (2 * h)
        assert np.allclose(v_fd, table.velocity(t), atol=1e-9)
        assert np.allclose(a_fd, table.accel(t), atol=1e-7)
    v0, g, m = np.array([0.3, 2.0, 0.0]), np.array([0.0, -G, 0.0]), 0.7

    def power(t: float) -> float:
        v = v0 + g * (t - 0.2) - (table.velocity(t) - table.velocity(0.2))
        return -m * float(table.accel(t) @ v)

    quadrature, _ = quad(power, 0.2, 0.9, epsabs=0.0, epsrel=1e-11, limit=200)
    assert table.work_in_flight(m, 0.2, 0.9, v0, g) == pytest.approx(quadrature, rel=1e-11)


def test_holmes_period_one_orbit_repeats_on_the_stable_root() -> None:
    """The stable root (``Gamma sin(phi) = 0.6``): every impact at ``k T`` to 1e-9 s for 50
    periods, each landing at ``-g T / (1 + e)`` relative to the table and leaving at ``e``
    times that (Newton), dissipating ``m (1 - e^2) (g T / (1 + e))^2 / 2``; the ledger
    closes to round-off."""
    gamma, phi = _orbit(0.6)
    assert gamma * math.cos(phi) == pytest.approx(HOLMES, rel=1e-15)
    res = run(parse_simulation(_scenario(gamma, phi, G * T / 2, 50.25)))
    _closes(res)
    impacts = [ev for ev in res.events if ev.kind == "impact"]
    assert len(impacts) == 50 and len(res.events) == 50
    times = np.array([ev.time for ev in impacts])
    assert np.max(np.abs(_deviations(times))) <= 1e-9
    approach = G * T / (1 + E)
    for ev in impacts:
        c = ev.impact.result.contacts[0]
        normal = np.asarray(c.normal)
        assert float(np.asarray(c.relative_velocity_before) @ normal) == pytest.approx(
            -approach, rel=1e-9)  # fmt: skip
        assert float(np.asarray(c.relative_velocity_after) @ normal) == pytest.approx(
            E * approach, rel=1e-9)  # fmt: skip
        assert ev.impact.result.energy.dissipated == pytest.approx(
            0.5 * 0.1 * (1 - E * E) * approach**2, rel=1e-9)  # fmt: skip


def test_the_other_root_departs_at_the_rate_of_its_eigenvalue() -> None:
    """The root ``-phi`` (``sin(phi) < 0``): the largest eigenvalue of ``J`` exceeds 1, and a
    start 1e-10 m/s off the orbit departs from it by that factor each period (to 1e-3 while
    the departure is small), until the impacts are no longer ``k T`` (by more than T / 100);
    the same start on the stable root stays on it to 1e-9 s."""
    gamma, phi = _orbit(-0.6)
    lam = max(np.linalg.eigvals(_jacobian(gamma, phi)).real)
    assert lam > 1
    times = _impact_times(gamma, phi, G * T / 2 + 1e-10, 40.25)
    d = _deviations(times)
    assert np.max(np.abs(d[:5])) <= 1e-9
    assert np.max(np.abs(d)) > T / 100
    # (past the first periods, where the other eigenvalue's part has died out)
    small = np.flatnonzero((np.abs(d) > 1e-11) & (np.abs(d) < 1e-6))[3:]
    assert len(small) >= 5
    ratios = d[small[1:]] / d[small[:-1]]
    assert np.allclose(ratios, lam, rtol=1e-3), (ratios, lam)
    gamma, phi = _orbit(0.6)
    stable = _impact_times(gamma, phi, G * T / 2 + 1e-10, 40.25)
    assert len(stable) == 40 and np.max(np.abs(_deviations(stable))) <= 1e-9


@pytest.mark.parametrize("gamma_sin", [0.6, -0.6, 1.05 * DOUBLING])
def test_closed_form_jacobian_against_finite_differences_of_the_simulated_map(
        gamma_sin) -> None:  # fmt: skip
    """Two routes to the period-1 orbit's Jacobian: the closed form (module docstring) and
    central differences of carnot's simulated impact map, to 1e-7; the orbit is its fixed
    point to 1e-13."""
    gamma, phi = _orbit(gamma_sin)
    x = np.array([phi, G * T / 2])
    assert np.allclose(_simulated_map(gamma, *x), x, rtol=0, atol=1e-13)
    h = 1e-6
    fd = np.empty((2, 2))
    for j in range(2):
        dx = np.zeros(2)
        dx[j] = h
        fd[:, j] = (_simulated_map(gamma, *(x + dx)) - _simulated_map(gamma, *(x - dx))) / (2 * h)
    closed = _jacobian(gamma, phi)
    assert np.allclose(fd, closed, rtol=0, atol=1e-7), (fd, closed)
    assert np.linalg.det(closed) == pytest.approx(E * E, rel=1e-12)


@pytest.mark.parametrize("side", [0.95, 1.05])
def test_period_doubling_where_the_closed_form_jacobian_says(side) -> None:
    """On either side of ``Gamma sin(phi) = 2 (1 + e^2)/(1 + e)^2`` (5 % below, 5 % above) a
    start 1e-8 m/s off the orbit: its departure alternates in sign and changes by the
    eigenvalue of ``J`` nearest -1 each period (to 1e-3), shrinking below the bound and
    growing above it. Below, a start 1e-4 m/s off settles back on the period-1 orbit (every
    interval T to 1e-9 s); above it lands on a period-2 orbit, intervals alternating long and
    short, ``t_{k+2} - t_k = 2 T`` to 1e-9 s. At 5 % below, Guckenheimer and Holmes'
    high-bounce bound (``Gamma sin(phi) < 1``) is already passed: the exact map's is the one
    that holds."""
    gamma, phi = _orbit(side * DOUBLING)
    eigenvalues = np.linalg.eigvals(_jacobian(gamma, phi))
    assert np.all(np.isreal(eigenvalues))
    lam = float(min(eigenvalues.real))
    assert (abs(lam) < 1) == (side < 1)
    d = _deviations(_impact_times(gamma, phi, G * T / 2 + 1e-8, 30.25))
    # past 10 periods (the other eigenvalue's part down by (mu / lambda)^10 < 1e-4), while
    # the departure is small (linear) and far above round-off
    window = np.flatnonzero((np.abs(d) > 1e-11) & (np.abs(d) < 1e-5))
    window = window[window >= 10]
    assert len(window) >= 8
    ratios = d[window[1:]] / d[window[:-1]]
    assert np.allclose(ratios, lam, rtol=1e-3), (ratios, lam)
    intervals = np.diff(_impact_times(gamma, phi, G * T / 2 + 1e-4, 150.25))
    late = intervals[-20:]
    if side < 1:
        assert gamma * math.sin(phi) > 1  # past the high-bounce bound, yet stable
        assert np.max(np.abs(late - T)) <= 1e-9
    else:
        assert np.min(np.abs(late - T)) > T / 100
        assert np.all(np.sign(late[1:] - T) != np.sign(late[:-1] - T))
        assert np.max(np.abs(late[1:] + late[:-1] - 2 * T)) <= 1e-9


def test_the_example_holds_holmes_orbit() -> None:
    """examples/simulate/ball_on_vibrating_table.toml: its numbers satisfy Holmes' condition
    to round-off and start the ball on the orbit (``e g T / (1 + e)`` relative to the
    table); its impacts come every T."""
    sim = load_simulation(EXAMPLES / "simulate" / "ball_on_vibrating_table.toml")
    table = sim.ground
    assert isinstance(table, Oscillation)
    w, g = table.angular_frequency, -float(sim.gravity[1])
    e = sim.law_of(Feature(body=0, plane=0)).restitution
    gamma = table.amplitude * w * w / g
    assert gamma * math.cos(table.phase) == pytest.approx(math.pi * (1 - e) / (1 + e), rel=1e-15)
    assert 0 < gamma * math.sin(table.phase) < 2 * (1 + e * e) / (1 + e) ** 2
    assert sim.initial[0].velocity[1] == pytest.approx(e * g * table.period / (1 + e), rel=1e-15)
    res = run(sim)
    _closes(res)
    times = np.array([ev.time for ev in res.events if ev.kind == "impact"])
    assert len(times) == 49  # (the 50th would be at the end, 10 s: not reached)
    assert np.max(np.abs(times - table.period * np.arange(1, len(times) + 1))) <= 1e-9


@pytest.mark.parametrize("gamma", [0.5, 2.0])
def test_a_ball_resting_on_the_table_leaves_it_where_the_table_falls_faster_than_g(
        gamma) -> None:  # fmt: skip
    """A ball at rest on the table (``e = 0``): the contact holds while the normal force
    ``m (g + a_g)`` is positive, ``a_g = -A w^2 sin(w t)``, so that it lifts off first at
    ``sin(w t) = 1 / Gamma`` (a contact phase's lift-off event, to 1e-12 s) and never for
    ``Gamma < 1``; either way the ledger closes."""
    data = _scenario(gamma, 0.0, _amplitude(gamma) * W, 10.0)  # resting: 0 relative to it
    data["pairs"][0]["restitution"] = 0.0
    res = run(parse_simulation(data))
    _closes(res)
    ends = [ev.time for ev in res.events if ev.kind == "contact_end"]
    if gamma < 1:
        assert [ev.kind for ev in res.events] == ["contact_start"]
    else:
        assert ends[0] == pytest.approx(math.asin(1 / gamma) / W, abs=1e-12)
        assert len(ends) >= 5  # it lands (plastic), rides, and leaves again every period


# --- bad input -----------------------------------------------------------------------------

OSC = "simulation.ground_oscillation"


@pytest.mark.parametrize("change, field, words", [
    (lambda o: o.update(amplitude=-0.01), f"{OSC}.amplitude", "must be >= 0, got -0.01"),
    (lambda o: o.update(amplitude=1e999), f"{OSC}.amplitude", "must be finite"),
    (lambda o: o.update(amplitude=1e49), f"{OSC}.amplitude", "peak acceleration"),
    (lambda o: o.update(frequency=0.0), f"{OSC}.frequency", "must be > 0, got 0.0"),
    (lambda o: o.update(frequency=-5.0), f"{OSC}.frequency", "must be > 0, got -5.0"),
    (lambda o: o.update(frequency=1e7), f"{OSC}.frequency", "must be <= 1e+06 Hz"),
    (lambda o: o.pop("frequency"), f"{OSC}.frequency", "required"),
    (lambda o: o.update(direction=[0.0, 0.0, 0.0]), f"{OSC}.direction", "non-zero"),
    (lambda o: o.update(direction=[0.0, 1.0]), f"{OSC}.direction", ""),
    (lambda o: o.pop("direction"), f"{OSC}.direction", "required"),
    (lambda o: o.update(phase=-1e999), f"{OSC}.phase", "must be finite"),
    (lambda o: o.update(phase="zero"), f"{OSC}.phase", "must be a number"),
    (lambda o: o.update(period=0.2), f"{OSC}", "period"),
])  # fmt: skip
def test_bad_oscillation_exits_2_with_one_line_naming_the_field(change, field, words,
                                                                tmp_path, capsys) -> None:
    data = _scenario(*_orbit(0.6), G * T / 2, 2.0)
    change(data["simulation"]["ground_oscillation"])
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data).replace("Infinity", "1e999"))
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"bad.json: {field}" in err and words in err, err


@pytest.mark.parametrize("other", ["ground_pulse", "ground_motion"])
def test_oscillation_with_another_ground_motion_is_refused(other, tmp_path, capsys) -> None:
    data = _scenario(*_orbit(0.6), G * T / 2, 2.0)
    data["simulation"][other] = {"shape": "sine", "amplitude": 1.0, "period": 0.5} \
        if other == "ground_pulse" else "record.csv"  # fmt: skip
    path = tmp_path / "both.json"
    path.write_text(json.dumps(data))
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert other in err and "ground_oscillation" in err and "excludes" in err, err


# --- a block on a table shaking sideways ---------------------------------------------------
# A lamina 2b x 2h (b = 0.1 m, h = 0.3 m) standing on a table that moves by A sin(w t) along
# x: in the table's frame it feels -m a_g(t) = m A w^2 sin(w t) x. Sticking, it starts to
# slide when that force reaches Coulomb's mu m g (mu < b / h: before it can tip), at
# t* = asin(mu g / (A w^2)) / w; with mu > b / h it tips instead when the force reaches
# m g b / h (Housner 1963; N. Makris and Y. Roussos, Geotechnique 50 (2000) 243-262), its
# trailing corner lifting at asin(g b / (h A w^2)) / w. Both cases integrate contact phases:
# the ledger closes to the integrator's tolerance.

B, H = 0.1, 0.3


def _block(amplitude: float, frequency: float, mu: float, duration: float) -> dict:
    return {
        "format": 1,
        "simulation": {"duration": duration, "gravity": [0.0, -G, 0.0],
                       "ground_oscillation": {"amplitude": amplitude, "frequency": frequency,
                                              "direction": [1.0, 0.0, 0.0]}},
        "bodies": {"block": {"mass": 10.0, "shape": "convex",
                             "vertices": [[B, -H, 0.0], [B, H, 0.0], [-B, H, 0.0], [-B, -H, 0.0]],
                             "position": [0.0, H, 0.0]},
                   "table": {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0],
                                                      "normal": [0.0, 1.0, 0.0]}}},
        "pairs": [{"a": "block", "b": "table", "restitution": 0.0, "friction": mu}],
    }  # fmt: skip


@pytest.mark.parametrize("mu", [0.2, 0.8])
def test_block_slides_or_rocks_on_a_shaking_table_and_the_ledger_closes(mu) -> None:
    amplitude, frequency = 0.03, 2.0
    w = 2 * math.pi * frequency
    res = run(parse_simulation(_block(amplitude, frequency, mu, 1.2)))
    led = res.energy
    assert led.ground_work > 0.1
    assert abs(led.residual) <= 1e-9 * max(led.initial, led.ground_work)
    kinds = [ev.kind for ev in res.events]
    if mu < B / H:
        first = next(ev for ev in res.events if ev.kind == "slip")
        assert first.time == pytest.approx(math.asin(mu * G / (amplitude * w * w)) / w, abs=1e-9)
        assert led.sliding > 0.1 and "impact" not in kinds
    else:
        first = next(ev for ev in res.events if ev.kind == "contact_end")
        assert first.time == pytest.approx(math.asin(G * B / (H * amplitude * w * w)) / w,
                                           abs=1e-9)  # fmt: skip
        assert kinds.count("impact") >= 2 and led.impacts > 0.1

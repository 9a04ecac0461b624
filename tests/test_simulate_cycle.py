"""``carnot cycle`` on free bodies (simulate/cycle.py): Holmes' ball on a vibrating table
found by Newton shooting on the simulator's return map, its multipliers by three routes
(saltation matrices through each impact, central differences of the simulated map, Holmes'
exact Jacobian), its stability and the period doubling where that Jacobian's eigenvalue
crosses -1, the energy per period, and bad input.

Sources:
- P. J. Holmes, "The dynamics of repeated impacts with a sinusoidally vibrating table",
  J. Sound Vib. 84 (1982) 173-189: the period-1 orbit ``Gamma cos(phi) = pi (1 - e)/(1 + e)``,
  ``Gamma = A w^2 / g``.
- The exact impact map's Jacobian on that orbit in Holmes' coordinates (table phase
  ``theta``, the ball's world velocity ``V``), derived in tests/test_vibrating_table.py:
  ``J = [[1, a], [b, e^2 + a b]]``, ``a = 2 pi (1 + e)/(g T)``, ``b = -(1 + e) A w sin(phi)``;
  stable for ``0 < Gamma sin(phi) < 2 (1 + e^2)/(1 + e)^2``, a period doubling at the bound.
- Saltation matrices: Aizerman and Gantmacher (1958); Kong, Payne, Council and Johnson,
  *The saltation matrix* (2023), eq. 7.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES
from holmes import DOUBLING, FREQUENCY, HOLMES, RADIUS, E, G, T, W
from holmes import amplitude as _amplitude
from holmes import orbit as _orbit

from carnot.cli import main
from carnot.simulate import parse_simulation, run
from carnot.simulate.cycle import SectionPoint, find_cycle, return_map

MASS = 0.1


def _scenario(gamma: float, phase: float, v_up: float, *, e: float = E) -> dict:
    """Just after an impact at ``t = 0``, the table at ``phase``, the ball leaving at
    ``v_up`` (m/s, world; the file holds it relative to the table)."""
    a = _amplitude(gamma)
    return {
        "format": 1,
        "simulation": {"duration": 1.0, "gravity": [0.0, -G, 0.0],
                       "ground_oscillation": {"amplitude": a, "frequency": FREQUENCY,
                                              "direction": [0.0, 1.0, 0.0], "phase": phase}},
        "bodies": {"ball": {"mass": MASS, "shape": "sphere", "radius": RADIUS,
                            "position": [0.0, RADIUS, 0.0],
                            "velocity": [0.0, v_up - a * W * math.cos(phase), 0.0]},
                   "table": {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0],
                                                      "normal": [0.0, 1.0, 0.0]}}},
        "pairs": [{"a": "ball", "b": "table", "restitution": e}],
    }  # fmt: skip


def _holmes_jacobian(gamma: float, phi: float) -> np.ndarray:
    a = 2 * math.pi * (1 + E) / (G * T)
    b = -(1 + E) * _amplitude(gamma) * W * math.sin(phi)
    return np.array([[1.0, a], [b, E * E + a * b]])


def _cycle_cli(tmp_path: Path, capsys, data: dict, *extra: str) -> tuple[int, dict]:
    path = tmp_path / "ball.json"
    path.write_text(json.dumps(data))
    code = main(["cycle", str(path), "--json", *extra])
    return code, json.loads(capsys.readouterr().out)


def _sorted(z) -> np.ndarray:
    z = np.array([complex(*p) if isinstance(p, list) else p for p in z])
    return z[np.lexsort((z.imag, z.real))]


def test_holmes_orbit_found_from_a_nearby_guess(tmp_path, capsys) -> None:
    """From 5 % off in velocity and 0.1 rad off in phase, ``carnot cycle`` lands on Holmes'
    orbit: ``Gamma cos(phase) = pi (1 - e)/(1 + e)`` to 1e-10 at the impact's phase, the
    ball leaving at ``e g T/(1 + e)`` relative to the table, one impact per forcing period
    (``m = 1``), the period ``T`` to 1e-12 s; stable, its two multipliers those of Holmes'
    exact Jacobian (complex here, modulus ``e``: ``det J = e^2``)."""
    gamma, phi = _orbit(0.6)
    code, out = _cycle_cli(tmp_path, capsys, _scenario(gamma, phi + 0.1, 1.05 * G * T / 2))
    assert code == 0 and out["converged"] and out["residual"] < 1e-11
    assert out["iterations"] >= 2
    phase = out["state"]["phase"]
    assert gamma * math.cos(phase) == pytest.approx(HOLMES, abs=1e-10)
    assert math.sin(phase) > 0  # the stable root
    ball = out["state"]["bodies"]["ball"]
    assert ball["velocity"][1] == pytest.approx(E * G * T / (1 + E), abs=1e-10)
    assert ball["position"][1] == pytest.approx(RADIUS, abs=1e-15)
    assert set(ball) == {"position", "velocity"}  # it does not turn
    assert out["forcing_periods"] == 1 and out["period"] == pytest.approx(T, abs=1e-12)
    assert out["stable"] is True and out["multipliers_route"] == "saltation"
    exact = np.linalg.eigvals(_holmes_jacobian(gamma, phi))
    assert np.allclose(_sorted(out["multipliers"]), _sorted(exact), atol=1e-8)
    assert np.allclose(np.abs(exact), E, rtol=1e-12)
    sec = out["section"]
    assert sec["constraints"] == [["ball", "table"]]
    assert len(sec["neutral"]) == 4 and np.allclose(_sorted(sec["neutral_multipliers"]), 1.0)
    assert len(out["impacts"]) == 1 and out["impacts"][0]["format"] == 1


@pytest.mark.parametrize("gamma_sin", [0.6, -0.6, 0.95 * DOUBLING, 1.05 * DOUBLING])
def test_three_routes_to_the_multipliers_and_stability(gamma_sin) -> None:
    """On the stable root, the unstable one (an eigenvalue above 1), 5 % below and 5 % above
    the period doubling (an eigenvalue through -1): the multipliers by saltation and by
    finite differences of the simulated map equal Holmes' exact ones (1e-8 and 1e-6), and
    the section's 2 x 2 map, carried into Holmes' coordinates (``theta = w tau + phase``,
    ``V = v + A w cos(theta)``), is his Jacobian entry by entry; ``stable`` is Jury's test."""
    gamma, phi = _orbit(gamma_sin)
    sim = parse_simulation(_scenario(gamma, phi, G * T / 2))
    c = find_cycle(sim, check=True)
    assert c.converged and c.iterations == 0 and c.flags == ()
    exact = np.linalg.eigvals(_holmes_jacobian(gamma, phi))
    assert np.allclose(_sorted(c.multipliers), _sorted(exact), atol=1e-8)
    assert np.allclose(_sorted(c.check), _sorted(exact), atol=1e-6)
    assert c.stable == (0 < gamma_sin < DOUBLING)
    if gamma_sin > DOUBLING:
        assert min(exact.real) < -1 and np.all(np.isreal(exact))
    # the (time, velocity.y) block of A on the section's tangent space
    coords = [n for n in c.layout.coordinates if n != "ball.position.y"]
    k = [coords.index("time"), coords.index("ball.velocity.y")]
    block = c.jacobian[np.ix_(k, k)]
    conv = np.array([[W, 0.0], [-_amplitude(gamma) * W * W * math.sin(phi), 1.0]])
    assert np.allclose(conv @ block @ np.linalg.inv(conv), _holmes_jacobian(gamma, phi),
                       rtol=0, atol=1e-7)  # fmt: skip


def _settled_guess(gamma: float, phi: float, periods: float) -> dict:
    """A scenario starting where a start 1e-4 m/s off the period-1 orbit is after
    ``periods`` forcing periods (just after its last impact)."""
    res = run(parse_simulation({**_scenario(gamma, phi, G * T / 2 + 1e-4),
                                "simulation": {**_scenario(gamma, phi, 0.0)["simulation"],
                                               "duration": periods * T}}))  # fmt: skip
    last = [ev for ev in res.events if ev.kind == "impact"][-1]
    data = _scenario(gamma, phi + W * last.time, 0.0)
    data["bodies"]["ball"]["velocity"] = last.impact.states[0].velocity.tolist()
    data["bodies"]["ball"]["position"] = last.impact.states[0].position.tolist()
    return data


@pytest.mark.parametrize("side", [0.95, 1.05])
def test_period_doubling_and_the_period_two_orbit(side, tmp_path, capsys) -> None:
    """From where the motion settles (40 periods from a start near the period-1 orbit),
    ``--strikes 2``: 5 % above the bound a period-2 orbit (two forcing periods, its two
    intervals long and short, its own state off the period-1 orbit's by more than 1 cm/s),
    stable, the product of its multipliers ``e^4``; 5 % below only the period-1 orbit is
    there, found again as a 2-strike cycle with the squares of its multipliers."""
    gamma, phi = _orbit(side * DOUBLING)
    code, out = _cycle_cli(tmp_path, capsys, _settled_guess(gamma, phi, 40.25), "--strikes", "2")
    assert code == 0 and out["converged"] and out["strikes"] == 2
    assert out["forcing_periods"] == 2 and out["period"] == pytest.approx(2 * T, abs=1e-10)
    v = out["state"]["bodies"]["ball"]["velocity"][1]
    v1 = E * G * T / (1 + E)
    sim = parse_simulation(_scenario(gamma, phi, G * T / 2))
    if side < 1:
        assert v == pytest.approx(v1, abs=1e-9)
        squares = np.linalg.eigvals(_holmes_jacobian(gamma, phi)) ** 2
        assert np.allclose(_sorted(out["multipliers"]), _sorted(squares), atol=1e-8)
        assert out["stable"] is True
    else:
        assert abs(v - v1) > 1e-2
        assert out["stable"] is True
        # Liouville: the flight conserves volume in (t, y, v), so between sections y = r its
        # map's determinant is the ratio of the normal speeds, take-off over landing; an
        # impact multiplies by e. Around a closed orbit the ratios cancel: det = e^(2 k).
        mults = [complex(*z) for z in out["multipliers"]]
        assert np.prod(mults) == pytest.approx(E**4, abs=1e-8)
        # the two impacts: one period-1 return from the orbit's state is not the orbit
        start = SectionPoint(time=out["state"]["time"], states=(sim.initial[0].__class__(
            position=np.array(out["state"]["bodies"]["ball"]["position"]),
            orientation=np.array([1.0, 0, 0, 0]), velocity=np.array([0.0, v, 0.0]),
            angular_velocity=np.zeros(3)),))  # fmt: skip
        one = return_map(parse_simulation(_scenario(gamma, phi, 0.0)), start)
        assert abs(one.flight - T) > T / 100
        assert abs(float(one.point.states[0].velocity[1]) - v) > 1e-2


def test_energy_per_period_impacts_equal_ground_work() -> None:
    """Over one period of Holmes' orbit the ledger (the simulator's own, over exactly the
    period) closes: the impact takes what the table gives, ``m (1 - e^2)(g T/(1 + e))^2 / 2``
    (Newton's law at the landing speed ``g T/(1 + e)`` relative to the table), to 1e-12."""
    gamma, phi = _orbit(0.6)
    c = find_cycle(parse_simulation(_scenario(gamma, phi, G * T / 2)))
    en = c.energy
    closed = 0.5 * MASS * (1 - E * E) * (G * T / (1 + E)) ** 2
    assert en["impacts"] == pytest.approx(closed, rel=1e-12)
    assert en["ground_work"] == pytest.approx(closed, rel=1e-12)
    assert en["sliding"] == 0.0 and abs(en["residual"]) < 1e-15


def test_the_example_is_on_its_orbit(capsys) -> None:
    """examples/simulate/ball_on_vibrating_table.toml: ``carnot cycle`` finds it on the orbit
    at once (no Newton step), the text report too; ``carnot simulate`` still runs it."""
    path = str(EXAMPLES / "simulate" / "ball_on_vibrating_table.toml")
    assert main(["cycle", path, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["converged"] and out["iterations"] == 0 and out["stable"] is True
    assert out["state"]["time"] == 0.0 and out["state"]["phase"] == pytest.approx(0.5, abs=1e-12)
    assert main(["cycle", path, "--check"]) == 0
    text = capsys.readouterr().out
    assert "periodic orbit" in text and "finite differences" in text and "stable" in text


def test_a_ball_bouncing_without_loss_is_a_family() -> None:
    """No ground motion, ``e = 1``: every bounce returns (period ``2 v/g``, no time
    coordinate); the multiplier of the normal velocity is 1 (a family of orbits by energy,
    which is not a symmetry of the scene and is left in), so not ``stable``."""
    data = _scenario(1.0, 0.0, 0.0, e=1.0)
    del data["simulation"]["ground_oscillation"]
    data["bodies"]["ball"]["velocity"] = [0.0, 2.0, 0.0]
    c = find_cycle(parse_simulation(data))
    assert c.converged and c.forcing_periods == 0 and "time" not in c.layout.coordinates
    assert c.period == pytest.approx(2 * 2.0 / G, rel=1e-12)
    assert np.allclose(c.multipliers, [1.0], atol=1e-9) and c.stable is False


# --- bad input -----------------------------------------------------------------------------


def test_no_impact_is_a_flagged_non_convergence(tmp_path, capsys) -> None:
    """A ball thrown up with gravity pointing away from the table never comes back."""
    data = _scenario(*_orbit(0.6), G * T / 2)
    data["simulation"]["gravity"] = [0.0, G, 0.0]
    code, out = _cycle_cli(tmp_path, capsys, data)
    assert code == 0 and out["converged"] is False and out["multipliers"] is None
    assert {w["code"] for w in out["warnings"]} >= {"not_converged", "no_return"}


def test_a_guess_far_from_any_orbit_is_flagged_with_its_residual(tmp_path, capsys) -> None:
    """A table too weak for Holmes' orbit (``Gamma = 0.5 < pi (1 - e)/(1 + e)``: no period-1
    orbit exists), the ball leaving fast: Newton stops short and says so, with the residual
    it reached."""
    data = _scenario(0.5, 0.3, 1.5)
    code, out = _cycle_cli(tmp_path, capsys, data)
    assert code == 0 and out["converged"] is False
    assert out["residual"] is None or out["residual"] > 1e-6
    assert "not_converged" in {w["code"] for w in out["warnings"]}


@pytest.mark.parametrize("change, words", [
    (lambda d: d["simulation"].pop("ground_oscillation") and d["simulation"].update(
        ground_pulse={"shape": "sine", "amplitude": 1.0, "period": 0.5}),
     "simulation.ground_pulse: ends"),
    (lambda d: d["bodies"].pop("table") and d.update(pairs=[]), "bodies: can strike nothing"),
    (lambda d: d.update(cycle={"strikes": "two"}), "cycle.strikes: must be an integer"),
    (lambda d: d.update(cycle={"tolerance": 1.0}), "cycle.tolerance"),
    (lambda d: d.update(cycle={"periods": 2}), "cycle"),
])  # fmt: skip
def test_bad_input_exits_2_with_one_line(change, words, tmp_path, capsys) -> None:
    data = _scenario(*_orbit(0.6), G * T / 2)
    change(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    assert main(["cycle", str(path), "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bad.json: " in err and words in err, err


def test_strikes_out_of_range_exits_2(capsys) -> None:
    path = str(EXAMPLES / "simulate" / "ball_on_vibrating_table.toml")
    assert main(["cycle", path, "--strikes", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--strikes" in err, err


def test_cycle_table_and_no_duration(tmp_path, capsys) -> None:
    """``[cycle] strikes`` is read (the 2-strike cycle of the period-1 orbit: two forcing
    periods), ``duration`` may be left out for ``carnot cycle``, and ``carnot simulate``
    runs the same file (with its duration) ignoring ``[cycle]``."""
    data = _scenario(*_orbit(0.6), G * T / 2)
    data["cycle"] = {"strikes": 2, "tolerance": 1e-10}
    del data["simulation"]["duration"]
    code, out = _cycle_cli(tmp_path, capsys, data)
    assert code == 0 and out["converged"] and out["strikes"] == 2
    assert out["forcing_periods"] == 2 and len(out["impacts"]) == 2
    data["simulation"]["duration"] = 0.5
    path = tmp_path / "sim.json"
    path.write_text(json.dumps(data))
    assert main(["simulate", str(path), "--json"]) == 0
    assert len(json.loads(capsys.readouterr().out)["events"]) == 2


def test_a_sweep_of_the_table_s_amplitude_finds_holmes_period_doubling(tmp_path) -> None:
    """``carnot sweep`` over a free-body [cycle] scenario: one orbit per amplitude; the
    period-one orbit is stable below Holmes' exact bound ``Gamma sin phi = 2 (1 + e^2) /
    (1 + e)^2`` (with ``Gamma cos phi = pi (1 - e) / (1 + e)``) and unstable above it."""
    pytest.importorskip("pyarrow")
    from carnot.io.sweep_files import read_sweep

    bound = 2 * (1 + E**2) / (1 + E) ** 2
    gamma = math.hypot(bound, HOLMES)
    amplitude = gamma * G / W**2  # the amplitude where a multiplier reaches -1
    text = (EXAMPLES / "simulate" / "ball_on_vibrating_table.toml").read_text()
    path = tmp_path / "holmes.toml"
    path.write_text(text + "\n[cycle]\nstrikes = 1\n")
    out = tmp_path / "amplitudes.csv"
    low, high = 0.97 * amplitude, 1.03 * amplitude
    code = main(["sweep", str(path), "--vary",
                 f"simulation.ground_oscillation.amplitude={low!r}:{high!r}:2",
                 "--out", str(out), "--plot", str(tmp_path / "a.png"), "--workers", "1"])
    assert code == 0
    t = read_sweep(out)
    assert list(t.column("stable").to_numpy(zero_copy_only=False)) == [True, False]
    mult = t.column("max_multiplier").to_numpy()
    assert mult[0] < 1 < mult[1]
    assert np.allclose(t.column("period").to_numpy(), T, rtol=1e-12)
    drop = t.column("ground_work").to_numpy()
    assert np.allclose(t.column("energy_impacts").to_numpy(), drop, rtol=1e-9)

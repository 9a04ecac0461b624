"""The hopping leg (``hopping_leg``): a body of mass M on a massless spring leg (k, l0, damper
c) with a foot of mass m, moving vertically; every phase against its closed form.

* **Flight**: both masses free. The centre of mass falls on its parabola,
  ``y_c = y_c0 + v_c0 t - g t^2 / 2``, and the leg's length oscillates about its rest length
  at ``omega_f = sqrt(k / mu)``, ``mu = M m / (M + m)``, unaffected by gravity:
  ``l = l0 + (l_0 - l0) cos omega_f t + (l_0' / omega_f) sin omega_f t`` (c = 0).
* **Touchdown**: the foot strikes the ground, plastic. The mass matrix is diagonal, so only
  the foot stops; the energy taken is Carnot's lost velocity, ``m v_foot^2 / 2``.
* **Stance**: the foot held, the body on the spring: ``M y'' = k (l0 - y) - c y' - M g``, a
  (damped) oscillation about ``y_eq = l0 - M g / k`` at ``omega = sqrt(k / M)``. The ground's
  force on the foot (the foot's own balance, ``y_foot'' = 0``) is
  ``F = k (l0 - l) - c l' + m g``; the foot lifts off where it falls to zero, with c = 0 at
  ``y = l0 + m g / k`` rising: with ``y - y_eq = A cos(omega t - phi)``, at
  ``omega t = phi - arccos((M + m) g / (k A))`` (mod 2 pi).
* **Dampers** (c > 0): their work ``int c l'^2 dt`` is booked in the ledger; over a stance
  it equals the closed form's integral and the energy the state lost.

The parameters are ours (no published set is transcribed): M = 10 kg, m = 1 kg,
k = 1e4 N/m, l0 = 0.5 m, dropped from 0.2 m with the leg at its rest length.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from carnot.cli import main
from carnot.hybrid.flow import Hold, fly
from carnot.hybrid.models import named_model
from carnot.hybrid.simulate import HybridRun, simulate
from carnot.hybrid.strike import Law

BIG_M, M, K, L0, G = 10.0, 1.0, 1.0e4, 0.5, 9.81
DROP = 0.2
X0 = np.array([L0 + DROP, DROP, 0.0, 0.0])


def flight(state: np.ndarray, tau: Any) -> np.ndarray:
    """The closed-form flight (c = 0) from ``state`` after ``tau`` (s; a number, or an array
    of times: then each entry of the state is an array over them)."""
    yb, yf, vb, vf = state
    total, mu = BIG_M + M, BIG_M * M / (BIG_M + M)
    w = math.sqrt(K / mu)
    yc, vc = (BIG_M * yb + M * yf) / total, (BIG_M * vb + M * vf) / total
    r0, rd0 = yb - yf, vb - vf
    r = L0 + (r0 - L0) * np.cos(w * tau) + rd0 / w * np.sin(w * tau)
    rd = -(r0 - L0) * w * np.sin(w * tau) + rd0 * np.cos(w * tau)
    c, cd = yc + vc * tau - G * tau**2 / 2, vc - G * tau
    return np.array([c + M * r / total, c - BIG_M * r / total, cd + M * rd / total,
                     cd - BIG_M * rd / total])  # fmt: skip


def touchdown_time(state: np.ndarray) -> float:
    """The first time the closed-form flight's foot falls through the ground (the first
    crossing on a grid of 10 us, then Brent's method on :func:`flight` itself)."""
    taus = np.linspace(1e-7, 2.0, 200_001)
    feet = flight(state, taus)[1]
    k = int(np.argmax((feet[:-1] > 0) & (feet[1:] <= 0)))
    return float(brentq(lambda tau: flight(state, tau)[1], taus[k], taus[k + 1], xtol=1e-15))


def lift_off(state: np.ndarray) -> tuple[float, float, float]:
    """The closed-form stance (c = 0, the foot at rest at 0): the time to lift-off, and the
    body's height and rate there."""
    yb, _, vb, _ = state
    w = math.sqrt(K / BIG_M)
    x0 = yb - (L0 - BIG_M * G / K)
    amp, phi = math.hypot(x0, vb / w), math.atan2(vb / w, x0)
    d = (BIG_M + M) * G / K
    tau = (phi - math.acos(d / amp)) % (2 * math.pi) / w
    return tau, L0 + M * G / K, amp * w * math.sqrt(1 - (d / amp) ** 2)


def hops(duration: float = 2.5, **params: float) -> HybridRun:
    return simulate(named_model("hopping_leg", params), X0, duration)


def test_every_phase_of_an_undamped_run_is_its_closed_form() -> None:
    """Flight, touchdown, stance and lift-off, event by event over several hops, each from
    the state the simulator reached at the event before: times to 1e-9 s, states to 1e-8."""
    run = hops()
    kinds = [e.kind for e in run.events]
    assert kinds.count("contact_start") >= 4 and kinds.count("contact_end") >= 4
    assert run.events[0].time == pytest.approx(math.sqrt(2 * DROP / G), abs=1e-12)
    checked = {"flight": 0, "stance": 0, "touchdown": 0}
    for before, after in zip(run.events, run.events[1:], strict=False):
        if after.kind == "impact":  # a flight from the state after ``before``
            if before.kind == "impact" and after.time == before.time:
                continue
            tau = touchdown_time(before.state)
            assert after.time - before.time == pytest.approx(tau, abs=1e-9)
            assert after.strike is not None
            assert np.allclose(after.strike.x_before, flight(before.state, tau), atol=1e-8)
            checked["flight"] += 1
        if after.kind == "contact_end":  # a stance from ``before``, its contact_start
            assert before.kind == "contact_start"
            tau, height, rate = lift_off(before.state)
            assert after.time - before.time == pytest.approx(tau, abs=1e-9)
            assert after.state[0] == pytest.approx(height, abs=1e-9)
            assert after.state[2] == pytest.approx(rate, rel=1e-8)
            assert after.state[1] == pytest.approx(0.0, abs=1e-12)
            checked["stance"] += 1
    for e in run.events:
        if e.kind == "impact":  # the foot's kinetic energy, all of it and nothing else
            assert e.strike is not None
            v_foot = e.strike.x_before[3]
            assert float(e.strike.result.energy.dissipated) == pytest.approx(
                M * v_foot**2 / 2, rel=1e-12)  # fmt: skip
            assert e.strike.x_after[2] == e.strike.x_before[2]  # the body goes on
            assert e.strike.x_after[3] == pytest.approx(0.0, abs=1e-14)
            checked["touchdown"] += 1
    assert min(checked.values()) >= 4, checked
    assert abs(run.energy["residual"]) < 1e-10 * run.energy["initial"]
    assert run.energy["dampers"] == 0.0 and run.energy["sliding"] == 0.0


def test_a_touchdown_with_the_leg_stretched_lifts_the_foot_again() -> None:
    """Where the leg is longer than l0 + m g / k at touchdown, the spring pulls the foot up
    harder than gravity: the plastic strike stops it, but it is not held (the ground would
    pull), and it flies on until it strikes again."""
    run = hops()
    pairs = [(a, b) for a, b in zip(run.events, run.events[1:], strict=False)
             if a.kind == "impact" and b.kind == "impact"]  # fmt: skip
    assert pairs
    for first, _ in pairs:
        assert first.state[0] - first.state[1] > L0 + M * G / K


def test_the_dampers_work_is_booked_and_is_the_closed_form_integral() -> None:
    """With c > 0 the stance is a damped oscillation; from the simulator's contact_start the
    lift-off (F = k (l0 - y) - c y' + m g through zero) and the damper's work over the stance,
    int c y'^2 dt, by their closed forms, against the flow's own quadrature and the energy
    the state lost."""
    c = 40.0
    hop = named_model("hopping_leg", {"c": c})
    run = simulate(hop, X0, 2.0)
    start = next(e for e in run.events if e.kind == "contact_start")
    leg = fly(hop, start.state, start.time, 10.0, held=(Hold(index=0),))
    assert leg.ended == "release"
    w = math.sqrt(K / BIG_M)
    sigma = c / (2 * BIG_M)
    wd = math.sqrt(w**2 - sigma**2)
    a = start.state[0] - (L0 - BIG_M * G / K)
    b = (start.state[2] + sigma * a) / wd

    def rate(tau: float) -> float:
        e = math.exp(-sigma * tau)
        return e * ((-sigma * a + b * wd) * math.cos(wd * tau)
                    + (-sigma * b - a * wd) * math.sin(wd * tau))  # fmt: skip

    def force(tau: float) -> float:
        y = L0 - BIG_M * G / K + math.exp(-sigma * tau) * (a * math.cos(wd * tau)
                                                           + b * math.sin(wd * tau))
        return K * (L0 - y) - c * rate(tau) + M * G

    taus = np.linspace(1e-9, 1.0, 100_001)
    values = np.array([force(tau) for tau in taus])
    k = int(np.argmax((values[:-1] > 0) & (values[1:] <= 0)))
    tau = brentq(force, taus[k], taus[k + 1], xtol=1e-15)
    assert leg.t1 - start.time == pytest.approx(tau, abs=1e-9)
    work, _ = quad(lambda s: c * rate(s) ** 2, 0.0, tau, epsabs=1e-13, epsrel=1e-13)
    assert leg.damping == pytest.approx(work, rel=1e-9)
    lost = hop.energy(start.state, np.zeros(2)) - hop.energy(leg.x1, np.zeros(2))
    assert leg.damping == pytest.approx(lost, rel=1e-9)
    # the whole run: impacts and dampers take what the state lost
    assert run.energy["dampers"] > work
    assert abs(run.energy["residual"]) < 1e-9 * run.energy["initial"]


def test_a_bouncing_foot_chatters_to_a_hold() -> None:
    """With e = 0.5 the foot bounces on the ground; the chatter closes plastic, the foot is
    held, and the ledger still closes."""
    run = simulate(named_model("hopping_leg"), X0, 1.0, Law(restitution=0.5))
    kinds = [e.kind for e in run.events]
    assert kinds.count("impact") > kinds.count("contact_start") >= 1
    assert abs(run.energy["residual"]) < 1e-9 * run.energy["initial"]


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_the_example_hops_with_its_ledger_in_the_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "simulate", "examples/motion/hopping_leg.toml", "--json")
    d = json.loads(out)
    assert code == 0 and d["model"]["name"] == "hopping_leg"
    kinds = [e["kind"] for e in d["events"]]
    assert "contact_start" in kinds and "contact_end" in kinds
    held = next(e for e in d["events"] if e["kind"] == "contact_start")
    assert held["contacts"] == ["touchdown"]
    en = d["energy"]
    assert en["dampers"] > 0
    assert en["initial"] - en["impacts"] - en["dampers"] - en["sliding"] == pytest.approx(
        en["final"], abs=1e-9)  # fmt: skip
    code, out, _ = run_cli(capsys, "simulate", "examples/motion/hopping_leg.toml")
    assert code == 0 and "dampers" in out


@pytest.mark.parametrize(("state", "message"), [
    ("{ q = [0.7, -0.1], qdot = [0.0, 0.0] }", "y_foot >= 0"),
    ("{ q = [0.1, 0.2], qdot = [0.0, 0.0] }", "y_body > y_foot"),
])  # fmt: skip
def test_a_hopper_below_its_ground_or_inside_out_exits_2(
        tmp_path: object, capsys: pytest.CaptureFixture[str], state: str, message: str) -> None:
    path = tmp_path / "bad.toml"  # type: ignore[operator]
    path.write_text(f'format = 1\n[model]\nname = "hopping_leg"\nstate = {state}\n'
                    "[simulation]\nduration = 1.0\n")  # fmt: skip
    code, _, err = run_cli(capsys, "simulate", str(path))
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_a_negative_spring_is_refused() -> None:
    from carnot.errors import InputError

    with pytest.raises(InputError, match="k: must be > 0"):
        named_model("hopping_leg", {"k": -1.0})


def test_started_in_stance_the_foot_is_held_from_the_start_and_lifts_as_the_closed_form() -> None:
    """The body pressed 5 cm below its loaded rest length, the foot on the ground, at rest:
    the foot is held from t = 0 (the ground pushes) and lifts off at the closed form's time."""
    y_eq = L0 - BIG_M * G / K
    x0 = np.array([y_eq - 0.05, 0.0, 0.0, 0.0])
    run = simulate(named_model("hopping_leg"), x0, 0.2)
    assert [e.kind for e in run.events][:2] == ["contact_start", "contact_end"]
    assert run.events[0].time == 0.0
    tau, height, rate = lift_off(x0)
    end = run.events[1]
    assert end.time == pytest.approx(tau, abs=1e-9)
    assert end.state[[0, 2]] == pytest.approx([height, rate], rel=1e-9)
    assert abs(run.energy["residual"]) < 1e-10 * abs(run.energy["initial"])
    # too little compression to lift the foot: held to the end, oscillating
    calm = simulate(named_model("hopping_leg"), np.array([y_eq - 0.005, 0.0, 0.0, 0.0]), 0.5)
    assert [e.kind for e in calm.events] == ["contact_start"] and calm.final[1] == 0.0

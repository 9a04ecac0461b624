"""Systems in motion (DESIGN.md section 10): walkers and the rimless wheel against their
published results, and every number by two routes.

* **Rimless wheel** (McGeer, *Passive dynamic walking*, IJRR 9, 1990; Tedrake, *Underactuated
  Robotics*, ch. "Simple models of walking"): with ``2 alpha = 2 pi / N`` between spokes, the
  strike keeps the angular momentum about the new foot, ``omega+ = c omega-`` with
  ``c = (I + m l^2 cos 2 alpha) / (I + m l^2)``, and the stance phase gains
  ``omega-^2 = omega+^2 + K``, ``K = 4 m g l sin(alpha) sin(slope) / (m l^2 + I)``; the
  rolling fixed point is ``omega* = c sqrt(K / (1 - c^2))`` (for ``I = 0``, Tedrake's
  ``cot(2 alpha) sqrt(4 (g / l) sin alpha sin slope)``) and its multiplier ``c^2``.
* **Simplest walker** (Garcia, Chatterjee, Ruina and Coleman, *The simplest walking model:
  stability, complexity, and scaling*, J. Biomech. Eng. 120, 1998): the long-period gait at
  ``gamma = 0.009`` just after heel strike, ``theta* = 0.20031090049483``,
  ``theta'* = -0.19983247291764`` (their fixed point to 1e-10, distributed with the Cornell
  group's walker code), ``phi = 2 theta``, ``phi' = (1 - cos 2 theta) theta'``. Their model is
  the limit of vanishing foot mass ``beta``; carnot's walker has ``beta > 0``, and its numbers
  at ``beta`` and ``2 beta``, extrapolated linearly to 0 (Richardson), must meet theirs. The
  multipliers are checked against the stride function of Garcia's own equations of motion
  and transition (their eqs. 3-5), integrated here with SciPy apart from carnot.
* **Compass gait** (Goswami, Thuilot and Espiau, INRIA RR-2996, 1996, and IJRR 17, 1998):
  their nominal walker (m = 5 kg, m_h = 10 kg, a = b = 0.5 m) on a 3 degree slope has a
  stable period-one gait with, just after heel strike, ``|theta_s| = 0.2187``,
  ``|theta_ns| = 0.3234``, ``|theta_s'| = 1.0918``, ``|theta_ns'| = 0.3772`` (rad, rad/s);
  the heel strike itself is their closed form (tests/test_walkers.py).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_walkers import goswami_transition

from carnot.cli import main
from carnot.hybrid.cycle import find_cycle, finite_difference_jacobian, return_map
from carnot.hybrid.models import named_model
from carnot.hybrid.simulate import is_grazing, simulate
from carnot.hybrid.strike import Law, strike

GARCIA_THETA, GARCIA_RATE = 0.20031090049483, -0.19983247291764


def garcia_state(theta: float, rate: float) -> np.ndarray:
    return np.array([theta, 2 * theta, rate, (1 - math.cos(2 * theta)) * rate])


def wheel_fixed_point(spokes: int, slope: float, inertia: float, g: float = 9.81,
                      m: float = 1.0, ll: float = 1.0) -> tuple[float, float]:  # fmt: skip
    alpha = math.pi / spokes
    c = (inertia + m * ll**2 * math.cos(2 * alpha)) / (inertia + m * ll**2)
    k = 4 * m * g * ll * math.sin(alpha) * math.sin(slope) / (m * ll**2 + inertia)
    return c * math.sqrt(k / (1 - c**2)), c**2


@pytest.mark.parametrize(("spokes", "slope", "inertia"), [(8, 0.08, 0.0), (10, 0.15, 0.25)])
def test_rimless_wheel_fixed_point_and_multiplier_are_mcgeers(spokes: int, slope: float,
                                                              inertia: float) -> None:
    wheel = named_model("rimless_wheel", {"spokes": spokes, "slope": slope, "I": inertia})
    alpha = math.pi / spokes
    rate, multiplier = wheel_fixed_point(spokes, slope, inertia)
    if inertia == 0:  # Tedrake's form of the same number
        tedrake = math.sqrt(4 * 9.81 * math.sin(alpha) * math.sin(slope)) / math.tan(2 * alpha)
        assert rate == pytest.approx(tedrake, rel=1e-14)
    c = find_cycle(wheel, np.array([slope - alpha, 0.8 * rate]))
    assert c.converged and c.stable and c.flags == ()
    assert c.state[0] == pytest.approx(slope - alpha, abs=1e-14)
    assert c.state[1] == pytest.approx(rate, rel=1e-11)
    assert c.multipliers is not None and len(c.multipliers) == 1
    assert abs(c.multipliers[0]) == pytest.approx(multiplier, rel=1e-9)
    # the strikes take what the slope gives, per period
    assert c.energy["impacts"] == pytest.approx(c.energy["potential_drop"], rel=1e-10)


def test_rimless_wheel_on_flat_ground_rocks_to_rest_with_a_closed_ledger() -> None:
    wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.0})
    run = simulate(wheel, np.array([-math.pi / 8, 0.5]), 3.0)
    assert run.ended == "rest" and run.events[-1].kind == "rest"
    kinds = {e.strike.guard.name for e in run.events if e.strike is not None}
    assert kinds == {"next_spoke", "previous_spoke"}  # it rocks between two spokes
    assert abs(run.energy["residual"]) < 1e-9 * run.energy["initial"]
    # at rest on two spokes: all the kinetic energy went into the strikes
    assert run.energy["impacts"] == pytest.approx(0.5 * 0.5**2, rel=1e-9)
    assert not np.any(run.final[1:])


def test_a_wheel_started_on_its_guard_and_rocking_back_strikes_again_later_not_at_once() -> None:
    wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    on_guard = np.array([0.08 + math.pi / 8, -0.02])  # the spoke just struck, rolling back
    r = return_map(wheel, on_guard)
    assert r.period > 1e-3 and r.strikes[0].guard.name == "next_spoke"
    assert r.strikes[0].x_before[1] > 0  # it turned round before striking


def simplest_cycle(beta: float) -> tuple[np.ndarray, np.ndarray]:
    walker = named_model("simplest_walker", {"slope": 0.009, "beta": beta})
    c = find_cycle(walker, garcia_state(GARCIA_THETA, GARCIA_RATE))
    assert c.converged and c.flags == () and c.multipliers is not None
    return c.state, c.multipliers[:2]


def garcia_stride_multipliers() -> np.ndarray:
    """The eigenvalues of Garcia et al.'s stride function (theta, theta') -> next, from their
    equations (3)-(5), integrated here by SciPy apart from carnot, by central differences."""
    gamma = 0.009

    def flow(t: float, y: np.ndarray) -> list[float]:
        th, ph, thd, phd = y
        thdd = math.sin(th - gamma)
        return [thd, phd, thdd, math.sin(ph) * (thd**2 - math.cos(th - gamma)) + thdd]

    def mid(t: float, y: np.ndarray) -> float:
        return y[0]

    def heel(t: float, y: np.ndarray) -> float:
        return y[1] - 2 * y[0]

    mid.terminal, mid.direction = True, -1  # type: ignore[attr-defined]
    heel.terminal, heel.direction = True, 1  # type: ignore[attr-defined]

    def stride(z: np.ndarray) -> np.ndarray:
        opts = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-13}
        a = solve_ivp(flow, (0, 20), garcia_state(*z), events=mid, **opts)
        b = solve_ivp(flow, (a.t_events[0][0], 20), a.y_events[0][0], events=heel, **opts)
        th, _, thd, _ = b.y_events[0][0]
        return np.array([-th, math.cos(2 * th) * thd])

    z = np.array([GARCIA_THETA, GARCIA_RATE])
    jac = np.column_stack([(stride(z + e) - stride(z - e)) / 2e-6 for e in 1e-6 * np.eye(2)])
    eig = np.linalg.eigvals(jac)
    return eig[np.argsort(eig.imag)[::-1]]


def test_simplest_walker_limit_cycle_is_garcias_fixed_point() -> None:
    state, mult = simplest_cycle(1e-5)  # the default foot mass: O(beta) from their limit
    assert np.allclose(state, garcia_state(GARCIA_THETA, GARCIA_RATE), atol=5e-6, rtol=0)
    state2, mult2 = simplest_cycle(2e-5)
    limit = 2 * state - state2  # Richardson: the O(beta) term removed
    assert np.allclose(limit, garcia_state(GARCIA_THETA, GARCIA_RATE), atol=2e-10, rtol=0)
    garcia = garcia_stride_multipliers()
    both = 2 * mult - mult2
    assert np.allclose(np.sort_complex(both), np.sort_complex(garcia), atol=2e-6)
    assert np.all(np.abs(both) < 1)  # stable, as Garcia et al. found for gamma < 0.015


def test_compass_gait_limit_cycle_is_goswamis_with_two_routes_to_its_multipliers() -> None:
    walker = named_model("compass_gait")  # their nominal walker, slope 3 degrees
    c = find_cycle(walker, np.array([-0.2, 0.3, 1.0, 0.4]))
    assert c.converged and c.stable and c.flags == ()
    assert np.allclose(np.abs(c.state), [0.2187, 0.3234, 1.0918, 0.3772], atol=1e-3)
    assert c.residual < 1e-12
    assert c.energy["impacts"] == pytest.approx(c.energy["potential_drop"], rel=1e-10)
    # the multipliers from saltation matrices against finite differences of the return map
    fd = np.linalg.eigvals(finite_difference_jacobian(walker, c.state))
    fd = fd[np.argsort(-np.abs(fd))][:3]
    assert c.multipliers is not None
    assert np.allclose(np.sort_complex(c.multipliers), np.sort_complex(fd), atol=1e-6)
    # its heel strike is Goswami's closed form (legs relabelled: theta_ns = swing)
    s = c.strikes[0]
    st, sw, rst, rsw = s.x_before
    # Goswami's angles run the other way round the hip (from the downward vertical)
    rates = goswami_transition(-sw, -st, -np.array([rsw, rst]))
    assert np.allclose(-s.x_after[2:][::-1], rates, rtol=1e-12, atol=0)


def test_a_walk_keeps_its_ledger_and_every_strike_its_theorem() -> None:
    walker = named_model("compass_gait")
    run = simulate(walker, np.array([-0.2187, 0.3234, 1.0918, 0.3772]), 3.0, saltation=True)
    impacts = [e for e in run.events if e.kind == "impact"]
    assert run.ended == "duration" and len(impacts) == 4
    assert abs(run.energy["residual"]) < 1e-9 * abs(run.energy["initial"])
    for e in impacts:
        led = e.strike.result.energy  # type: ignore[union-attr]
        assert led.dissipated == pytest.approx(led.dissipated_theorem, rel=1e-12)
        assert e.saltation is not None and e.saltation.shape == (4, 4)
    # the walker walks downhill: the stance foot moves towards +x and down
    assert run.anchor[0] > 1.0 and run.anchor[1] < 0


def test_a_strike_with_too_little_friction_is_flagged_not_walked() -> None:
    walker = named_model("compass_gait")
    x = np.array([0.3235, -0.2187 + 0.0004, 1.49, 1.8])
    x[1] = 2 * 0.0524 - x[0]  # on the guard
    ok = strike(walker, walker.guards[0], x, Law())
    assert ok.flags == ()
    slips = strike(walker, walker.guards[0], x, Law(friction=0.05))
    assert "stance_slips" in slips.flags


def test_a_run_stopped_by_a_strike_that_is_not_walking_closes_its_ledger() -> None:
    """A heel strike that bounces (Poisson, e = 0.3, mu = 0.5) leaves velocities the chart
    cannot hold: the run stops there, and its last energy is the floating one's after the
    strike, ``T(qf'+) + V``, so that the ledger still closes (it read 1.3 J off when the
    chart's least-squares reading of those velocities stood in for them)."""
    walker = named_model("compass_gait")
    run = simulate(walker, np.array([-0.2187, 0.3234, 1.0918, 0.3772]), 2.0,
                   Law(restitution=0.3, friction=0.5, law="poisson"))  # fmt: skip
    last = run.events[-1]
    assert run.ended == "stop" and last.strike is not None and "stance_slips" in last.flags
    led = last.strike.result.energy
    assert led.dissipated > 0 and led.dissipated == pytest.approx(led.dissipated_theorem,
                                                                  rel=1e-10)  # fmt: skip
    assert abs(run.energy["residual"]) < 1e-9 * abs(run.energy["initial"])
    # the chart's reading of the state after misses the floating kinetic energy
    assert abs(walker.kinetic(last.state) - led.after) > 0.1


def test_grazing_is_said() -> None:
    wheel = named_model("rimless_wheel", {"spokes": 8})
    guard = wheel.guards[0]
    assert is_grazing(wheel, guard, np.array([0.08 + math.pi / 8, 0.0]))
    assert not is_grazing(wheel, guard, np.array([0.08 + math.pi / 8, 1.0]))


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_cycle_command_prints_section_10(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "cycle", "examples/motion/rimless_wheel.toml", "--json",
                           "--check")  # fmt: skip
    assert code == 0
    d = json.loads(out)
    for key in ("period", "state", "multipliers", "stable", "residual", "impacts", "energy"):
        assert key in d
    assert d["stable"] is True and len(d["state"]["q"]) == 1
    assert d["multipliers"][0][0] == pytest.approx(0.5, rel=1e-9)
    assert d["multipliers_finite_difference"][0][0] == pytest.approx(0.5, rel=1e-6)
    assert d["impacts"][0]["system"]["coordinates"] == ["x_hub", "y_hub"]


def test_simulate_command_on_a_model(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "simulate", "examples/motion/rimless_wheel.toml", "--json",
                           "--saltation")  # fmt: skip
    assert code == 0
    d = json.loads(out)
    impact = d["events"][0]
    assert impact["kind"] == "impact" and impact["energy"]["dissipated"] > 0
    assert set(impact["system"]) >= {"q", "qdot", "qdot_before"}
    assert np.array(impact["saltation"]).shape == (2, 2)
    assert set(d["final"]["system"]) == {"q", "qdot"}
    assert abs(d["energy"]["residual"]) < 1e-9


@pytest.mark.parametrize(("text", "words"), [
    ('[model]\nname = "walker"\nstate = {q = [0.0], qdot = [0.0]}', "model.name: must be one of"),
    ('[model]\nname = "compass_gait"\nparameters = {a = -0.5}\nstate = {q = [0.0, 0.0], '
     'qdot = [0.0, 0.0]}', "model.parameters.a: must be > 0"),
    ('[model]\nname = "rimless_wheel"\nstate = {q = [0.0, 1.0], qdot = [0.0]}',
     "model.state.q: must be a list of 1 numbers"),
    ('[model]\nname = "rimless_wheel"\nparameters = {spokes = 4.5}\nstate = {q = [0.0], '
     'qdot = [1.0]}', "model.parameters.spokes: must be an integer"),
])  # fmt: skip
def test_bad_model_files_exit_2_with_one_line(tmp_path: object, capsys: pytest.CaptureFixture[str],
                                              text: str, words: str) -> None:
    path = tmp_path / "bad.toml"  # type: ignore[operator]
    path.write_text("format = 1\n" + text + "\n[simulation]\nduration = 1.0\n")
    for command in ("cycle", "simulate"):
        code, out, err = run_cli(capsys, command, str(path))
        assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
        assert words in err


def test_a_guess_far_from_any_orbit_is_a_flagged_non_convergence(
        tmp_path: object, capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    path = tmp_path / "far.toml"  # type: ignore[operator]
    path.write_text('format = 1\n[model]\nname = "compass_gait"\n'
                    'state = {q = [-0.2, 0.3], qdot = [4.0, -3.0]}\n')  # fmt: skip
    code, out, _ = run_cli(capsys, "cycle", str(path), "--json")
    d = json.loads(out)
    assert code == 0 and d["converged"] is False
    assert "not_converged" in {w["code"] for w in d["warnings"]}
    assert d["multipliers"] is None or d["stable"] is None


def test_a_sweep_over_the_slope_is_a_bifurcation_diagram(tmp_path: object) -> None:
    """``carnot sweep`` over a [model] file: one periodic orbit per slope, each the orbit
    ``carnot cycle`` finds alone; the period-one gait of the compass walker loses its
    stability as the slope steepens (a multiplier leaves the unit circle)."""
    pytest.importorskip("pyarrow")
    from carnot.io.sweep_files import read_sweep

    out = tmp_path / "slopes.csv"  # type: ignore[operator]
    png = tmp_path / "slopes.png"  # type: ignore[operator]
    code = main(["sweep", "examples/motion/compass_gait.toml", "--vary",
                 "model.parameters.slope=0.02:0.08:3", "--out", str(out), "--plot", str(png),
                 "--workers", "1"])  # fmt: skip
    assert code == 0 and png.stat().st_size > 0
    t = read_sweep(out)
    slopes = t.column("model.parameters.slope").to_numpy()
    stable = t.column("stable").to_numpy(zero_copy_only=False)
    assert list(stable) == [True, True, False]
    walker = named_model("compass_gait", {"slope": float(slopes[1])})
    alone = find_cycle(walker, np.array([-0.2187, 0.3234, 1.0918, 0.3772]))
    assert t.column("period").to_numpy()[1] == pytest.approx(alone.period, rel=1e-12)
    assert t.column("max_multiplier").to_numpy()[2] > 1
    drop = t.column("potential_drop").to_numpy()
    assert np.allclose(t.column("energy_impacts").to_numpy(), drop, rtol=1e-10)


def test_compass_gait_equations_are_goswamis_closed_form() -> None:
    """The flow compiled from the model's masses against Goswami et al.'s M(q) and
    h(q, q') = C(q, q') q' + G(q) written out (their eq. 2, in carnot's angles)."""
    m, mh, a, b, g = 5.0, 10.0, 0.5, 0.5, 9.81
    ll = a + b
    walker = named_model("compass_gait")
    rng = np.random.default_rng(3)
    for _ in range(5):
        st, sw, dst, dsw = rng.uniform(-0.6, 0.6, 4)
        c, s = math.cos(st - sw), math.sin(st - sw)
        mass = np.array([[(mh + m) * ll**2 + m * a**2, -m * ll * b * c],
                         [-m * ll * b * c, m * b**2]])  # fmt: skip
        bias = np.array([-m * ll * b * s * dsw**2 - (mh * ll + m * a + m * ll) * g * math.sin(st),
                         m * ll * b * s * dst**2 + m * b * g * math.sin(sw)])  # fmt: skip
        q, qd = np.array([st, sw]), np.array([dst, dsw])
        assert np.allclose(walker.mechanism.mass(q), mass, rtol=1e-14, atol=1e-14)
        assert np.allclose(walker.mechanism.bias(q, qd), bias, rtol=1e-13, atol=1e-13)
        # the flow's Jacobian (symbolic) against central differences of the flow
        x = np.concatenate([q, qd])
        fd = np.column_stack([(walker.mechanism.flow(x + e) - walker.mechanism.flow(x - e))
                              / 2e-6 for e in 1e-6 * np.eye(4)])  # fmt: skip
        assert np.allclose(walker.mechanism.flow_jacobian(x), fd, rtol=1e-7, atol=1e-7)


def test_past_the_period_doubling_a_two_strike_gait_is_stable() -> None:
    """At slope 0.08 rad the compass walker's period-one gait has a multiplier below -1 (a
    period doubling, as Goswami et al. found on steeper slopes); the period-two gait found
    with two strikes per period is stable, its two steps unequal."""
    walker = named_model("compass_gait", {"slope": 0.08})
    one = find_cycle(walker, np.array([-0.2187, 0.3234, 1.0918, 0.3772]))
    assert one.converged and one.stable is False and one.multipliers is not None
    assert one.multipliers[0].real < -1 and abs(one.multipliers[0].imag) < 1e-12
    two = find_cycle(walker, one.state + np.array([0.01, -0.01, 0.05, 0.0]), steps=2)
    assert two.converged and two.stable
    first, second = two.strikes[0].x_after, two.strikes[1].x_after
    assert abs(first[0] - second[0]) > 0.01  # a long step, then a short one
    assert np.allclose(second, two.state, atol=1e-10)
    assert two.energy["impacts"] == pytest.approx(two.energy["potential_drop"], rel=1e-10)


def sympy_double_pendulum(m1: object, m2: object, l1: object, l2: object, g: object
                          ) -> tuple[object, ...]:  # fmt: skip
    """The double pendulum written with sympy.physics.mechanics, as a user would: two
    particles at the links' ends, their potential energy, a LagrangesMethod with its
    equations formed. Returns the method, the coordinates, the frame, the pivot, the tip and
    the potential energy."""
    import sympy as sp
    from sympy.physics.mechanics import (
        LagrangesMethod,
        Lagrangian,
        Particle,
        Point,
        ReferenceFrame,  # fmt: skip
        dynamicsymbols,
    )

    t1, t2 = dynamicsymbols("t1 t2")
    frame, pivot = ReferenceFrame("N"), Point("O")
    pivot.set_vel(frame, 0)
    elbow = pivot.locatenew("E", l1 * (sp.sin(t1) * frame.x - sp.cos(t1) * frame.y))
    tip = elbow.locatenew("T", l2 * (sp.sin(t1 + t2) * frame.x - sp.cos(t1 + t2) * frame.y))
    for p in (elbow, tip):
        p.set_vel(frame, p.pos_from(pivot).dt(frame))
    parts = [Particle("a", elbow, m1), Particle("b", tip, m2)]
    for part, point in zip(parts, (elbow, tip), strict=True):
        part.potential_energy = part.mass * g * point.pos_from(pivot).dot(frame.y)
    potential = sum(part.potential_energy for part in parts)
    method = LagrangesMethod(Lagrangian(frame, *parts), [t1, t2])
    method.form_lagranges_equations()
    return method, (t1, t2), frame, pivot, tip, potential


def test_double_pendulum_equations_are_sympy_mechanics_own() -> None:
    """The double pendulum's M and h from carnot's mechanism against the equations SymPy's
    LagrangesMethod forms from the same particles (an independent derivation)."""
    import sympy as sp

    m1, m2, l1, l2, g = 1.3, 0.7, 0.9, 0.6, 9.81
    method, (t1, t2), *_ = sympy_double_pendulum(m1, m2, l1, l2, g)
    rates = [sp.diff(t1), sp.diff(t2)]
    walker = named_model("double_pendulum", {"m1": m1, "m2": m2, "l1": l1, "l2": l2})
    rng = np.random.default_rng(5)
    for _ in range(4):
        q, qd = rng.uniform(-1, 1, 2), rng.uniform(-2, 2, 2)
        values = {t1: q[0], t2: q[1], rates[0]: qd[0], rates[1]: qd[1]}
        mass = np.array(method.mass_matrix.subs(values), dtype=float)
        forcing = np.array(method.forcing.subs(values), dtype=float).ravel()
        assert np.allclose(walker.mechanism.mass(q), mass, rtol=1e-13, atol=1e-13)
        assert np.allclose(walker.mechanism.bias(q, qd), -forcing, rtol=1e-12, atol=1e-12)


def test_a_double_pendulum_striking_its_stop() -> None:
    """The elbow's stop, struck with e: the joint-impact closed form
    ``q'+ = q'- - (1 + e) (n . q'-) M^-1 n / (n M^-1 n)``, ``E_d = (1 - e^2) (n q'-)^2 /
    (2 n M^-1 n)`` with ``n = d g / d q``; an elastic stop keeps the energy, run after run."""
    pend = named_model("double_pendulum")
    x = np.array([0.9, 0.0, -0.4, 1.5])  # at the stop, the elbow closing onto it
    n = np.array([0.0, -1.0])
    m_inv = np.linalg.inv(pend.mechanism.mass(x[:2]))
    for e in (0.0, 0.5, 1.0):
        s = strike(pend, pend.guards[0], x, Law(restitution=e))
        rate = n @ x[2:]
        expected = x[2:] - (1 + e) * rate * m_inv @ n / (n @ m_inv @ n)
        assert np.allclose(s.x_after[2:], expected, rtol=1e-13, atol=1e-14)
        e_d = (1 - e**2) * rate**2 / (2 * n @ m_inv @ n)
        assert s.result.energy.dissipated == pytest.approx(e_d, rel=1e-12, abs=1e-14)
    run = simulate(pend, np.array([1.2, -0.6, 0.0, 0.0]), 3.0, Law(restitution=1.0))
    assert len(run.events) >= 3 and abs(run.energy["impacts"]) < 1e-12
    assert abs(run.energy["residual"]) < 1e-10


def test_a_plastic_stop_holds_the_elbow_and_the_pendulum_swings_as_one_body() -> None:
    """With e = 0 the elbow stays at its stop while the stop pushes: the pendulum moves as
    one rigid body (inertia m1 l1^2 + m2 L^2, L = l1 + l2), integrated here apart, and the
    stop's torque m2 l2 (L theta1'' + g sin theta1) vanishes at theta1 = 0: it releases
    there. A chatter (e = 0.5) ends held too, its ledger closed."""
    m1 = m2 = l1 = 1.0  # and l2 = 1: L = 2
    g, big_l = 9.81, 2.0
    pend = named_model("double_pendulum")
    run = simulate(pend, np.array([1.2, -0.6, 0.0, 0.0]), 1.0, Law(restitution=0.0))
    kinds = [e.kind for e in run.events]
    assert kinds[:3] == ["impact", "contact_start", "contact_end"]
    start, end = run.events[1], run.events[2]
    assert abs(end.state[0]) < 1e-10 and abs(end.state[1]) < 1e-12  # released at theta1 = 0

    def rigid(t: float, y: np.ndarray) -> list[float]:
        return [y[1], -(m1 * l1 + m2 * big_l) * g * math.sin(y[0]) / (m1 * l1**2 + m2 * big_l**2)]

    sol = solve_ivp(rigid, (start.time, end.time), [start.state[0], start.state[2]],
                    method="DOP853", rtol=1e-12, atol=1e-12)  # fmt: skip
    assert sol.y[0, -1] == pytest.approx(end.state[0], abs=1e-9)
    assert sol.y[1, -1] == pytest.approx(end.state[2], rel=1e-9)
    chatter = simulate(pend, np.array([1.2, -0.6, 0.0, 0.0]), 3.0, Law(restitution=0.5))
    assert "contact_start" in [e.kind for e in chatter.events]
    assert abs(chatter.energy["residual"]) < 1e-9 * abs(chatter.energy["initial"])


@pytest.mark.parametrize("name", ["compass_gait", "simplest_walker", "rimless_wheel",
                                  "double_pendulum_stop", "hopping_leg"])
def test_every_motion_example_runs_with_a_closed_ledger(name: str,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "simulate", f"examples/motion/{name}.toml", "--json")
    d = json.loads(out)
    assert code == 0 and d["ended"] in ("duration", "rest")
    assert any(e["kind"] == "impact" for e in d["events"])
    assert abs(d["energy"]["residual"]) < 1e-9 * max(1.0, abs(d["energy"]["initial"]))


def test_a_model_from_sympy_mechanics_moves_as_the_named_one() -> None:
    """The double pendulum written by its user with sympy.physics.mechanics (a
    LagrangesMethod, its elbow stop a stop_guard) and the named model (carnot's own masses):
    two derivations, the same motion, strike for strike (the chatter and the hold included)."""
    import sympy as sp

    from carnot.hybrid.guards import motion_model, stop_guard
    from carnot.hybrid.mechanism import compile_mechanics

    m, ll, g = sp.symbols("m l g", positive=True)
    method, _, frame, pivot, tip, potential = sympy_double_pendulum(m, m, ll, ll, g)
    mech = compile_mechanics(method, potential=potential, points={"tip": tip}, frame=frame,
                             origin=pivot, values={m: 1.0, ll: 1.0, g: 9.81})  # fmt: skip
    theirs = motion_model(mech, [stop_guard(mech, 1, 0.0, name="elbow_stop")],
                          coordinates=("theta1", "theta2"), total_mass=2.0)  # fmt: skip
    ours = named_model("double_pendulum")
    x0 = np.array([1.2, -0.6, 0.0, 0.0])
    a = simulate(theirs, x0, 3.0, Law(restitution=0.5))
    b = simulate(ours, x0, 3.0, Law(restitution=0.5))
    assert [e.kind for e in a.events] == [e.kind for e in b.events]
    assert "contact_start" in [e.kind for e in a.events]
    times = np.array([[e.time for e in a.events], [e.time for e in b.events]])
    assert np.allclose(times[0], times[1], atol=1e-10, rtol=0)
    assert np.allclose(a.final, b.final, atol=1e-9)
    assert a.energy["impacts"] == pytest.approx(b.energy["impacts"], rel=1e-9)
    assert abs(a.energy["residual"]) < 1e-9


def test_the_orbit_and_the_run_are_drawn(tmp_path: object,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    cyc = tmp_path / "orbit.png"  # type: ignore[operator]
    run = tmp_path / "run.png"  # type: ignore[operator]
    assert main(["cycle", "examples/motion/rimless_wheel.toml", "--plot", str(cyc)]) == 0
    assert main(["simulate", "examples/motion/double_pendulum_stop.toml", "--plot",
                 str(run)]) == 0  # fmt: skip
    assert cyc.stat().st_size > 10_000 and run.stat().st_size > 10_000
    code, _, err = run_cli(capsys, "cycle", "examples/motion/rimless_wheel.toml", "--plot",
                           str(tmp_path / "orbit.docx"))  # type: ignore[operator]
    assert code == 2 and "--plot" in err


def test_the_stance_foot_force_is_the_momentum_balance_and_a_fast_walker_lifts() -> None:
    """The ground's force on the stance foot, integrated over a step, equals the change of
    the walker's momentum less gravity's impulse, with the centre of mass written here from
    Goswami's masses (hip, stance leg at a from its foot, swing leg at b from the hip); a
    walker started so fast that the stance foot would be pulled is stopped, flagged, and one
    on a slippery slope (mu = 0.05) slips."""
    from carnot.hybrid.plot import sampled

    m, mh, a, b, g = 5.0, 10.0, 0.5, 0.5, 9.81
    ll = a + b
    walker = named_model("compass_gait")

    def com(q: np.ndarray) -> np.ndarray:
        st, sw = q
        hip = ll * np.array([math.sin(st), math.cos(st)])
        stance = a * np.array([math.sin(st), math.cos(st)])
        swing = hip - b * np.array([math.sin(sw), math.cos(sw)])
        return (mh * hip + m * stance + m * swing) / (mh + 2 * m)

    def v_com(x: np.ndarray) -> np.ndarray:
        jac = np.column_stack([(com(x[:2] + e) - com(x[:2] - e)) / 2e-7 for e in 1e-7 * np.eye(2)])
        return jac @ x[2:]

    x0 = np.array([-0.2187, 0.3234, 1.0918, 0.3772])
    leg = return_map(walker, x0).strikes[0]
    t1 = float(return_map(walker, x0).period)
    ts, xs = sampled(walker, x0, 0.0, t1, 2001)
    forces = np.array([walker.mechanism.support(x) for x in xs])
    impulse = np.trapezoid(forces, ts, axis=0)
    total = mh + 2 * m
    expected = total * (v_com(leg.x_before) - v_com(x0)) - total * np.array([0.0, -g]) * t1
    assert np.allclose(impulse, expected, rtol=1e-5, atol=1e-5)
    assert np.all(forces[:, 1] > 0)  # the foot is pressed all step long
    fast = simulate(walker, np.array([-0.2, 0.3, 6.0, 0.0]), 1.0)
    assert fast.ended == "stop" and fast.events[-1].flags == ("stance_lifts",)
    assert fast.events[-1].time < 0.05
    slippery = simulate(walker, x0, 1.0, Law(friction=0.05))
    assert slippery.ended == "stop" and slippery.events[-1].flags == ("stance_slips",)


def test_the_strikes_least_squares_is_numpys_bit_for_bit() -> None:
    """The rates after a strike are the least-squares preimage by LAPACK's dgelsd called
    directly (``strike._least_squares``): NumPy's lstsq to the last bit, on random systems of
    the charts' shapes (4 x 2, 6 x 3, 3 x 1), nearly dependent columns among them."""
    from carnot.hybrid.strike import _least_squares

    rng = np.random.default_rng(11)
    for k in range(600):
        m, n = ((4, 2), (6, 3), (3, 1))[k % 3]
        a = rng.normal(size=(m, n))
        if k % 4 == 0 and n > 1:
            a[:, -1] = 2.0 * a[:, 0] + 1e-10 * rng.normal(size=m)
        b = rng.normal(size=m)
        assert np.array_equal(_least_squares(a, b), np.linalg.lstsq(a, b, rcond=None)[0])

"""The flow's two routes (carnot.hybrid.flow): the compiled stepper (SciPy's ``ode`` DOP853,
each step's end watched, the step with a crossing taken again by the ``DOP853`` class and its
dense output) against the dense stepper alone (``fly(..., compiled=False)``). The routes'
step-size controllers differ in detail, so they agree to the integrator's tolerance, not bit
for bit: the same events, at the same times and states to ~1e-12 (1e-12 being the
tolerance), on a walker's step (an arming inside it), a wheel that starts on its guard, held
contacts (a release, a slide that starts from rest), the linearization beside the state, and
an arming so close to the strike that both fall in one step."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import sympy as sp

from carnot.hybrid.flow import Hold, Leg, fly
from carnot.hybrid.guards import motion_model, plane_guard
from carnot.hybrid.mechanism import Body, Mechanism, compile_mechanism
from carnot.hybrid.models import named_model
from carnot.hybrid.simulate import simulate

#: The compass gait's period-one gait just after heel strike (benchmarks/bench_walkers.py).
GAIT = np.array([-0.218699145234, 0.323499145234, 1.092522156319, 0.377019189923])
WHEEL_START = np.array([0.08 - math.pi / 8, 1.0])
#: How far the routes may part: a few times the tolerance, in time (s) and in the state.
AGREE = 1e-11


def both(*args: object, **kwargs: object) -> tuple[Leg, Leg]:
    return fly(*args, **kwargs), fly(*args, **kwargs, compiled=False)  # type: ignore[arg-type]


def agree(a: Leg, b: Leg) -> None:
    assert a.ended == b.ended and a.guard is b.guard
    assert a.t1 == pytest.approx(b.t1, abs=AGREE)
    np.testing.assert_allclose(a.x1, b.x1, rtol=0, atol=AGREE * max(1.0, np.abs(b.x1).max()))
    assert a.damping == pytest.approx(b.damping, abs=AGREE)
    assert a.sliding == pytest.approx(b.sliding, abs=AGREE)
    assert a.evaluations > 0 and b.evaluations > 0


def test_a_compass_gait_step_armed_mid_stance() -> None:
    walker = named_model("compass_gait")
    a, b = both(walker, GAIT, 0.0, 100.0)
    assert a.ended == "heel_strike"
    agree(a, b)


def test_a_rimless_wheel_leaving_the_spoke_it_stands_on() -> None:
    wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    a, b = both(wheel, WHEEL_START, 0.0, 10.0)
    assert a.ended == "next_spoke"
    agree(a, b)
    assert a.x1[0] == pytest.approx(0.08 + math.pi / 8, abs=1e-12)


def test_the_linearization_beside_the_state() -> None:
    walker = named_model("compass_gait")
    a, b = both(walker, GAIT, 0.0, 100.0, variational=True)
    agree(a, b)
    assert a.phi is not None and b.phi is not None
    np.testing.assert_allclose(a.phi, b.phi, rtol=0, atol=AGREE * np.abs(b.phi).max())


def test_a_held_foot_released_with_the_dampers_work() -> None:
    hop = named_model("hopping_leg", {"c": 40.0})
    run = simulate(hop, np.array([0.7, 0.2, 0.0, 0.0]), 2.0)
    start = next(e for e in run.events if e.kind == "contact_start")
    a, b = both(hop, start.state, start.time, 10.0, held=(Hold(index=0),))
    assert a.ended == "release" and a.damping > 0
    agree(a, b)


def incline(slope: float) -> object:
    x, y = sp.symbols("x y")
    mech = compile_mechanism(Mechanism(
        floating=(x, y), coordinates=(x, y), embedding=(x, y),
        bodies=(Body(mass=2.0, position=(x, y)),), points={"p": (x, y)},
        gravity=(0, -9.81)), {})  # fmt: skip
    guard = plane_guard(mech, "p", normal=(-math.sin(slope), math.cos(slope)), name="ground")
    return motion_model(mech, [guard], coordinates=("x", "y"), total_mass=2.0)


def test_a_slide_that_starts_from_rest_and_its_frictions_work() -> None:
    """At rest on a 0.3 rad incline with mu = 0.2 it slides down from zero speed: the slide's
    start (an event that goes on) inside the first steps, then to the leg's end."""
    a, b = both(incline(0.3), np.zeros(4), 0.0, 1.0, held=(Hold(index=0, slip=-1),),
                friction=0.2)  # fmt: skip
    assert a.ended == "end" and a.t1 == 1.0 and a.sliding > 0
    agree(a, b)
    accel = 9.81 * (math.sin(0.3) - 0.2 * math.cos(0.3))
    assert float(np.hypot(*a.x1[2:])) == pytest.approx(accel, rel=1e-10)


def test_an_arming_in_the_strikes_own_step_gives_the_same_strike() -> None:
    """The heel strike armed by the stance angle 1e-5 rad short of its value at the strike:
    the arming and the strike fall in one step, so the arming must be located (on the dense
    output) before the strike is searched for in the rest of the step; both routes find the
    strike of the mid-stance arming."""
    walker = named_model("compass_gait")
    late = fly(walker, GAIT, 0.0, 100.0)
    at = float(late.x1[0]) - 1e-5
    guard = dataclasses.replace(walker.guards[0], arming=lambda x: float(x[0]) - at,
                                arming_direction=1)  # fmt: skip
    armed_late = dataclasses.replace(walker, guards=(guard,))
    a, b = both(armed_late, GAIT, 0.0, 100.0)
    assert a.ended == "heel_strike"
    agree(a, b)
    assert a.t1 == pytest.approx(late.t1, abs=AGREE)
    np.testing.assert_allclose(a.x1, late.x1, atol=AGREE * 10)


def test_a_leg_flown_inside_anothers_callback_is_not_disturbed() -> None:
    """SciPy's compiled DOP853 holds one call per thread: a leg flown from a watched function
    of another (here the walker's fall surface flies a wheel) takes the dense route, and
    neither leg is changed by the other."""
    walker = named_model("compass_gait")
    wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    inner: list[Leg] = []
    fall = walker.fall
    assert fall is not None

    def flying_fall(x: np.ndarray) -> float:
        if not inner:
            inner.append(fly(wheel, WHEEL_START, 0.0, 10.0))
        return fall(x)

    nested = fly(dataclasses.replace(walker, fall=flying_fall), GAIT, 0.0, 100.0)
    agree(nested, fly(walker, GAIT, 0.0, 100.0))
    agree(inner[0], fly(wheel, WHEEL_START, 0.0, 10.0, compiled=False))


def test_the_dense_output_on_floats_is_scipys_bit_for_bit() -> None:
    """The crossing's root is sought on the DOP853 interpolant evaluated on floats
    (``flow._dense_floats``): SciPy's own numbers, to the last bit, at 2000 times in a
    walker's step, for its state alone and for the state's part of a linearized leg's vector
    (20 components, 4 of them watched); another dense output is called as it is."""
    from scipy.integrate import DOP853, RK45

    from carnot.hybrid.flow import _dense_floats

    walker = named_model("compass_gait")
    times = np.random.default_rng(7).uniform(0.0, 1.0, 2000)

    def rate(t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate([walker.mechanism.flow(y[:4]), 0.1 * y[4:]])

    for y0 in (GAIT, np.concatenate([GAIT, np.eye(4).ravel()])):
        solver = DOP853(rate, 0.0, y0, 1.0, rtol=1e-12, atol=1e-12, first_step=0.03)
        solver.step()
        dense = solver.dense_output()
        at = _dense_floats(dense, 4)
        for t in dense.t_old + times * (dense.t - dense.t_old):
            assert at(float(t)).tolist() == dense(float(t))[:4].tolist()
    other = RK45(lambda t, y: walker.mechanism.flow(y), 0.0, GAIT, 1.0)
    other.step()
    dense = other.dense_output()
    assert _dense_floats(dense, 4)(0.001).tolist() == dense(0.001)[:4].tolist()


def test_an_error_in_the_compiled_free_flow_is_raised_as_itself() -> None:
    """The free flow on floats, called by the compiled stepper itself: its error comes out,
    not SciPy's (the compiled expression's ``sin`` of an infinite angle)."""
    walker = named_model("compass_gait")
    with pytest.raises(ValueError, match="math domain error"):
        fly(walker, np.array([np.inf, 0.3, 1.0, 0.4]), 0.0, 1.0)


def test_an_error_in_the_flow_is_raised_as_itself() -> None:
    """SciPy's compiled wrapper puts a ValueError of its own in place of a callback's error:
    the flow's own comes out (here a guard that cannot be held)."""
    walker = named_model("compass_gait")
    with pytest.raises(ValueError, match="cannot be held in the flow"):
        fly(walker, GAIT, 0.0, 1.0, held=(Hold(index=0),))

"""Saltation matrices of MJCF models with free and ball joints (``nq != nv``), in the tangent
chart (carnot.hybrid.model.tangent_step; carnot.hybrid.simulate.saltation_matrix).

A perturbation of the state ``x = (qpos, qvel)`` is ``dx = (dq, dv)``, ``2 nv`` numbers:
``x (+) dx = (mj_integratePos(qpos, dq, 1), qvel + dv)`` (MuJoCo's own convention; its
inverse ``mj_differentiatePos``). In that chart the saltation matrix (Kong, Payne, Council
and Johnson, *The saltation matrix*, 2024, eq. 7)

    S = D_x R + (f+ - D_x R f-) (D_x G) / (D_x G f-)

maps a perturbation just before the strike's time to one just after. The second route here
shares nothing with ``S``'s own formula: the hybrid flow map ``x0 -> x(T)`` across one strike
(carnot's own simulator, from perturbed states ``x0 (+) eps e_j``, which strike at their own
times) differentiated by central differences in the same chart, against the chain rule
``Phi(T, t_s) S Phi(t_s, 0)``, the two flights' own maps differentiated likewise (SciPy's
DOP853 on MuJoCo's flow, no guard). A third, for the sphere dropped on a frictionless
plane: the closed form. Its only strike is in ``z`` (restitution ``e``, approached at
``vz- < 0``, gravity ``g``): ``D_x R`` is the identity but ``vz -> -e vz``, and with ``f =
(v, (0, 0, -g, 0, 0, 0))`` the formula gives ``S`` the identity but ``S[z, z] = S[vz, vz] =
-e`` and ``S[vz, z] = -g (1 + e) / vz-`` (e.g. Kong et al.'s bouncing ball, their section V).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from carnot.cli import main
from carnot.hybrid.cycle import finite_difference_jacobian, return_map
from carnot.hybrid.flow import fly
from carnot.hybrid.mjcf import MjcfMotion, mjcf_model
from carnot.hybrid.model import (
    HybridModel,
    position_map,
    tangent_difference,
    tangent_flow,
    tangent_gradient,
    tangent_step,
)
from carnot.hybrid.simulate import (
    HybridEvent,
    held_field,
    jump_saltation,
    saltation_matrix,
    simulate,
)
from carnot.hybrid.strike import reset_jacobian

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "tests" / "models"
G = 9.81


def _lift(model: HybridModel, x: np.ndarray) -> np.ndarray:
    """The tangent chart's map into ``(qpos, qvel)`` at ``x`` ((nq + n) x 2n):
    :func:`position_map` on the positions, the identity on the velocities."""
    nq, n = model.nq, model.n
    out = np.zeros((nq + n, 2 * n))
    out[:nq, :n] = position_map(model, x[:nq])
    out[nq:, n:] = np.eye(n)
    return out


EPS = 1e-6  # the central differences' step in the tangent chart
_BOX = mjcf_model(MODELS / "free_box_corner.xml", keyframe="spin")  # (read once, for Hypothesis)


def flight(model: HybridModel, x: np.ndarray, t: float) -> np.ndarray:
    """The flow's own map over ``t`` (s), no guard: SciPy's DOP853 on MuJoCo's flow."""
    sol = solve_ivp(lambda _t, y: model.mechanism.flow(y), (0.0, t), x, method="DOP853",
                    rtol=1e-13, atol=1e-14)  # fmt: skip
    return sol.y[:, -1]


def tangent_fd(model: HybridModel, fun: Callable[[np.ndarray], np.ndarray],
               x: np.ndarray) -> np.ndarray:  # fmt: skip
    """``d fun / d x`` in the tangent chart at ``x`` and at ``fun(x)``, central differences."""
    n2 = 2 * model.n
    base = fun(x)
    out = np.zeros((n2, n2))
    for j in range(n2):
        step = np.zeros(n2)
        step[j] = EPS
        out[:, j] = (tangent_difference(model, base, fun(tangent_step(model, x, step)))
                     - tangent_difference(model, base, fun(tangent_step(model, x, -step)))
                     ) / (2 * EPS)  # fmt: skip
    return out


def first_strike(motion: MjcfMotion, duration: float) -> HybridEvent:
    run = simulate(motion.model, motion.state, duration, motion.law, saltation=True)
    assert run.events and run.events[0].kind == "impact", run.events
    event = run.events[0]
    assert event.saltation is not None and event.saltation.shape == (2 * motion.model.n,) * 2
    return event


def chain_error(motion: MjcfMotion, event: HybridEvent, end: float) -> float:
    """``|D_fd - Phi_after S Phi_before| / |D_fd|`` (max norms) for the hybrid flow map from
    the start to ``end`` (s), after the first strike and before the next."""
    model, law, x0 = motion.model, motion.law, motion.state
    assert event.saltation is not None
    hybrid = tangent_fd(model, lambda y: simulate(model, y, end, law).final, x0)
    before = tangent_fd(model, lambda y: flight(model, y, event.time), x0)
    after = tangent_fd(model, lambda y: flight(model, y, end - event.time), event.state)
    chained = after @ event.saltation @ before
    return float(np.max(np.abs(hybrid - chained)) / np.max(np.abs(hybrid)))


def test_a_spinning_sphere_s_strike_meets_the_closed_form_and_the_flow_map() -> None:
    motion = mjcf_model(MODELS / "free_sphere_drop.xml", keyframe="thrown")  # e = 0.5
    event = first_strike(motion, 0.5)
    assert event.strike is not None
    e, vz = motion.law.restitution, float(event.strike.x_before[7 + 2])
    closed = np.eye(12)
    closed[2, 2] = closed[8, 8] = -e
    closed[8, 2] = -G * (1 + e) / vz
    np.testing.assert_allclose(event.saltation, closed, rtol=0, atol=1e-8)
    # (measured: 1.2e-9 of the flow map's size)
    assert chain_error(motion, event, 0.5) < 1e-6


def test_the_ball_joint_s_strike_on_its_cone_meets_the_flow_map() -> None:
    # the rod bounces off its cone (e = 0.5), 0.0559 s in; the next strike is at 0.0572 s
    motion = mjcf_model(MODELS / "ball_cone.xml", keyframe="cone", restitution=0.5)
    event = first_strike(motion, 0.0565)
    assert event.flags == () and event.strike is not None
    assert chain_error(motion, event, 0.0565) < 1e-6  # (measured: 2.0e-9)


def test_a_free_box_s_corner_strike_meets_the_flow_map() -> None:
    # tilted and spinning, it lands on one corner at 0.2584 s; the next strike is at 0.2738 s
    motion = mjcf_model(MODELS / "free_box_corner.xml", keyframe="spin")
    event = first_strike(motion, 0.265)
    assert event.strike is not None and len(event.strike.result.contacts) == 1
    assert chain_error(motion, event, 0.265) < 1e-6  # (measured: 8.6e-9)


@pytest.mark.parametrize(("name", "key", "duration", "e", "k"), [
    ("free_box_corner.xml", "spin", 0.265, None, 3),
    ("ball_cone.xml", "cone", 0.0565, 0.5, 0),
])  # fmt: skip
def test_the_quaternion_part_acts_on_its_three_tangent_directions(
        name: str, key: str, duration: float, e: float | None, k: int) -> None:  # fmt: skip
    """Read in ``qpos`` (``nq + nv`` numbers) through ``E(q) = d (q (+) dq) / d dq``, the
    saltation matrix ``E+ S E-^+`` has rank ``2 nv`` and no part along the quaternion
    (``quat`` itself, at ``qpos[k : k + 4]``), in what it takes or what it gives: the
    perturbations it maps keep the quaternion on its sphere."""
    motion = mjcf_model(MODELS / name, keyframe=key, restitution=e)
    model = motion.model
    event = first_strike(motion, duration)
    assert event.strike is not None and event.saltation is not None
    nq, n = model.nq, model.n
    lift = functools.partial(_lift, model)

    x_minus, x_plus = event.strike.x_before, event.strike.x_after
    ambient = lift(x_plus) @ event.saltation @ np.linalg.pinv(lift(x_minus))
    assert np.linalg.matrix_rank(ambient, tol=1e-9 * np.max(np.abs(ambient))) == 2 * n
    for x, side in ((x_minus, ambient), (x_plus, ambient.T)):
        radial = np.zeros(nq + n)
        radial[k : k + 4] = x[k : k + 4]
        assert np.max(np.abs(side @ radial)) < 1e-12 * np.max(np.abs(ambient))
    # E's quaternion columns (the joint's angular dofs, here at k too) are 1/2 quat (x) (0,
    # e_j): orthogonal to quat, of length 1/2
    quat_columns = position_map(model, x_minus[:nq])[k : k + 4, k : k + 3]
    np.testing.assert_allclose(quat_columns.T @ quat_columns, np.eye(3) / 4, atol=1e-12)
    np.testing.assert_allclose(x_minus[k : k + 4] @ quat_columns, 0.0, atol=1e-15)


def test_the_chart_is_the_identity_where_nq_is_nv() -> None:
    """A model of hinges (the two-link arm striking its table): the same formula, with ``x (+)
    dx = x + dx``, ``E = I``, ``f`` the flow itself and ``D_x G`` the guard's own gradient;
    and the same second route."""
    motion = mjcf_model(MODELS / "two_link_arm.xml", keyframe="strike")
    model = motion.model
    x = motion.state
    dx = np.array([0.1, -0.2, 0.3, 0.4])
    np.testing.assert_array_equal(tangent_step(model, x, dx), x + dx)
    np.testing.assert_array_equal(tangent_difference(model, x, x + dx), (x + dx) - x)
    np.testing.assert_array_equal(tangent_flow(model, x), model.mechanism.flow(x))
    np.testing.assert_array_equal(position_map(model, x[:2]), np.eye(2))
    guard = model.guards[0]
    np.testing.assert_array_equal(tangent_gradient(model, guard, x), guard.gradient(x))
    run = simulate(model, x, 1.0, motion.law, saltation=True)
    event = run.events[0]
    assert event.kind == "impact" and event.strike is not None and event.saltation is not None
    # the plastic strike leaves the tip held on the table: f+ is the held flow's field
    start = run.events[1]
    assert start.kind == "contact_start" and start.flags == ("tip/table",)
    x_minus = event.strike.x_before
    again = jump_saltation(reset_jacobian(model, guard, x_minus, motion.law),
                           tangent_flow(model, x_minus),
                           held_field(model, start.held, event.state, None),
                           tangent_gradient(model, guard, x_minus))  # fmt: skip
    np.testing.assert_array_equal(again, event.saltation)
    # (the free field after, saltation_matrix's, differs where the table holds the tip)
    free = saltation_matrix(model, guard, event.strike, motion.law)
    assert np.max(np.abs(free - event.saltation)) > 1e-3
    # the example's arm (e = 0.6): after its elbow's stop (0.145 s), its tip strikes the table
    # (0.107 s later), then the stop again (0.021 s after that)
    arm = mjcf_model(ROOT / "examples" / "motion" / "arm_strikes_table.xml", keyframe="swing")
    run = simulate(arm.model, arm.state, 0.2, arm.law)
    assert run.events[0].strike is not None
    assert run.events[0].strike.guard.name == "elbow lower stop"
    after_stop = replace(arm, state=run.events[0].state)
    event = first_strike(after_stop, 0.115)
    assert event.strike is not None and event.strike.guard.name == "tip/table"
    assert chain_error(after_stop, event, 0.115) < 1e-6


def test_carnot_simulate_saltation_prints_the_tangent_chart_s_matrices(
        capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    code = main(["simulate", str(MODELS / "free_sphere_drop.xml"), "--keyframe", "thrown",
                 "--duration", "1", "--json", "--saltation"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0, err
    events = [ev for ev in json.loads(out)["events"] if ev["kind"] == "impact"]
    assert len(events) >= 2
    for ev in events:  # 2 nv = 12 rows of 12: the quaternion's part in velocity space
        assert len(ev["saltation"]) == 12 and all(len(row) == 12 for row in ev["saltation"])
        assert ev["saltation"][2][2] == pytest.approx(-0.5, abs=1e-8)
    code = main(["simulate", str(MODELS / "ball_pendulum.xml"), "--keyframe", "swirl",
                 "--duration", "1", "--json", "--saltation"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0, err


@pytest.mark.parametrize(("name", "key", "duration", "e"), [
    ("free_box_corner.xml", "spin", 0.2, None),  # spinning about three unequal axes
    ("ball_cone.xml", "cone", 0.02, 0.5),  # swinging towards its cone
])  # fmt: skip
def test_the_flow_s_linearization_in_the_tangent_chart_meets_the_flight_map(
        name: str, key: str, duration: float, e: float | None) -> None:  # fmt: skip
    """``Phi`` integrated beside the state (``Phi' = A Phi``, ``A`` the flow's Jacobian in the
    tangent chart, its quaternion block ``-[omega]x``: without it the box's ``Phi`` is off by
    0.58 of its size) against central differences of the flight map in the same chart."""
    motion = mjcf_model(MODELS / name, keyframe=key, restitution=e)
    model = motion.model
    leg = fly(model, motion.state, 0.0, duration, variational=True)
    assert leg.ended == "end" and leg.phi is not None and leg.phi.shape == (2 * model.n,) * 2
    fd = tangent_fd(model, lambda y: flight(model, y, duration), motion.state)
    # (measured: 8.7e-9 for the box, 2.9e-8 for the rod: A's central differences)
    assert np.max(np.abs(leg.phi - fd)) < 1e-6 * np.max(np.abs(fd))


def test_the_return_map_s_derivative_and_monodromy_of_a_free_box() -> None:
    """The box from its keyframe to just after its first corner strike: ``D P`` from the
    saltation route against central differences of the return map (both in the tangent
    chart); the monodromy ``S Phi`` carries the flow into the flow (``M f(x0) = f(P x0)``: a
    shift in time along the motion), and read in ``qpos`` it has rank ``2 nv`` and no part
    along the quaternion."""
    motion = mjcf_model(MODELS / "free_box_corner.xml", keyframe="spin")
    model, x0 = motion.model, motion.state
    ret = return_map(model, x0, motion.law, linearize=True)
    assert ret.jacobian is not None and ret.monodromy is not None
    fd = finite_difference_jacobian(model, x0, motion.law)
    assert np.max(np.abs(ret.jacobian - fd)) < 1e-6 * np.max(np.abs(fd))  # (measured: 2.1e-9)
    carried = ret.monodromy @ tangent_flow(model, x0)
    np.testing.assert_allclose(carried, tangent_flow(model, ret.x), rtol=0,
                               atol=1e-6 * float(np.max(np.abs(carried))))  # fmt: skip
    nq, n = model.nq, model.n
    lift = functools.partial(_lift, model)

    ambient = lift(ret.x) @ ret.monodromy @ np.linalg.pinv(lift(x0))
    assert np.linalg.matrix_rank(ambient, tol=1e-9 * np.max(np.abs(ambient))) == 2 * n
    for x, side in ((x0, ambient), (ret.x, ambient.T)):
        radial = np.zeros(nq + n)
        radial[3:7] = x[3:7]
        assert np.max(np.abs(side @ radial)) < 1e-12 * np.max(np.abs(ambient))


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-0.5, 0.5), min_size=12, max_size=12),
       st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4))  # fmt: skip
def test_the_chart_s_difference_undoes_its_step(dx: list[float], quat: list[float]) -> None:
    """``(x (+) dx) (-) x = dx`` at a random orientation of the free box (a turn under pi),
    and the step keeps the quaternion unit: the chart is one to one near ``x``."""
    model = _BOX.model
    q = np.array(quat) + np.array([2.0, 0.0, 0.0, 0.0])  # (away from zero)
    x = np.array(_BOX.state)
    x[3:7] = q / np.linalg.norm(q)
    y = tangent_step(model, x, np.array(dx))
    assert abs(np.linalg.norm(y[3:7]) - 1.0) < 1e-14
    np.testing.assert_allclose(tangent_difference(model, x, y), dx, rtol=0, atol=1e-12)

"""The same double pendulum as free bodies with pins and in generalized coordinates (issue 34:
"the same system as free bodies with pins and in generalized coordinates gives the same
motion").

Two rigid links swing from a fixed pivot in the plane ``x, y`` (gravity ``-y``); link ``i``
has mass ``m_i``, its centre of mass ``c_i`` along it from its proximal joint, inertia ``I_i``
about its centre; the elbow has a stop at ``theta2 = 0`` (``theta2 <= 0``).

* **Generalized coordinates** (carnot's route): ``q = (theta1, theta2)`` from a
  ``sympy.physics.mechanics`` LagrangesMethod of the two rigid bodies, compiled by
  :func:`carnot.hybrid.mechanism.compile_mechanics`, the stop a
  :func:`carnot.hybrid.guards.stop_guard`, run by :func:`carnot.hybrid.simulate.simulate`: its
  strikes are ``solve_impact`` on the system's coordinates (a ``SystemProblem``).
* **Free bodies with pins** (written here apart from carnot's motion code): each link's
  centre ``p_i`` and angle ``phi_i`` (6 coordinates), the pivot and the elbow four constraint
  equations ``C(x) = 0``, the flow the index-1 KKT system
  ``[M J^T; J 0] [a; lambda] = [f; -J' v]`` (with Baumgarte's terms, zero on the constraint
  manifold, against drift), integrated by SciPy's DOP853 with the stop found as an event; each
  strike is carnot's *free-body* route: an ``ImpactProblem`` of two ``RigidBody`` links, two
  ``Pin`` constraints (pivot, elbow) and the stop as a ``PointContact`` between the links at
  ``d`` beyond the elbow, whose normal relative velocity is ``-d theta2'``: the joint limit's
  row scaled by ``d``, so the same impact (assembled by ``carnot.model.free_bodies``, not by
  ``carnot.model.system``).

The two routes share no assembly and no integrator; they must give the same strike times and
the same states after each strike.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from carnot import solve_impact
from carnot.hybrid.guards import motion_model, stop_guard
from carnot.hybrid.mechanism import compile_mechanics
from carnot.hybrid.simulate import simulate
from carnot.hybrid.strike import Law
from carnot.model import ImpactProblem, Pin, PointContact, RigidBody

G = 9.81
#: The links: mass (kg), length (m), centre from the proximal joint (m), inertia (kg m^2).
LINKS = ((1.2, 1.0, 0.55, 0.09), (0.8, 0.7, 0.3, 0.04))
STOP_ARM = 0.1  # d: the stop's contact point beyond the elbow (m)


def generalized_model():  # type: ignore[no-untyped-def]
    """The two links as a user writes them in sympy.physics.mechanics (rigid bodies)."""
    import sympy as sp
    from sympy.physics.mechanics import (
        LagrangesMethod,
        Lagrangian,
        Point,
        ReferenceFrame,
        dynamicsymbols,
        inertia,
    )
    from sympy.physics.mechanics import (
        RigidBody as SymRigidBody,
    )

    (m1, l1, c1, i1), (m2, _, c2, i2) = LINKS
    t1, t2 = dynamicsymbols("t1 t2")
    frame, pivot = ReferenceFrame("N"), Point("O")
    pivot.set_vel(frame, 0)
    a, b = frame.orientnew("A", "Axis", [t1, frame.z]), frame.orientnew("B", "Axis",
                                                                       [t1 + t2, frame.z])
    down_a, down_b = -a.y, -b.y  # each link's direction, from the downward vertical
    com1 = pivot.locatenew("C1", c1 * down_a)
    elbow = pivot.locatenew("E", l1 * down_a)
    com2 = elbow.locatenew("C2", c2 * down_b)
    for p in (com1, elbow, com2):
        p.set_vel(frame, p.pos_from(pivot).dt(frame))
    a.set_ang_vel(frame, sp.diff(t1) * frame.z)
    b.set_ang_vel(frame, (sp.diff(t1) + sp.diff(t2)) * frame.z)
    bodies = [SymRigidBody("L1", com1, a, m1, (inertia(a, 0, 0, i1), com1)),
              SymRigidBody("L2", com2, b, m2, (inertia(b, 0, 0, i2), com2))]
    for body in bodies:
        body.potential_energy = body.mass * G * body.masscenter.pos_from(pivot).dot(frame.y)
    potential = sum(body.potential_energy for body in bodies)
    method = LagrangesMethod(Lagrangian(frame, *bodies), [t1, t2])
    method.form_lagranges_equations()
    mech = compile_mechanics(method, potential=potential, points={"elbow": elbow}, frame=frame,
                             origin=pivot)  # fmt: skip
    return motion_model(mech, [stop_guard(mech, 1, 0.0, name="elbow_stop")],
                        coordinates=("theta1", "theta2"), total_mass=m1 + m2)  # fmt: skip


def _down(phi: float) -> np.ndarray:
    return np.array([math.sin(phi), -math.cos(phi)])


def _across(phi: float) -> np.ndarray:  # d/dphi of _down
    return np.array([math.cos(phi), math.sin(phi)])


def constraints(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``C(x)`` (4: the pivot, then the elbow) and ``J = dC/dx`` (4 x 6) of the free links,
    ``x = (p1x, p1y, phi1, p2x, p2y, phi2)``."""
    (_, l1, c1, _), (_, _, c2, _) = LINKS
    p1, phi1, p2, phi2 = x[0:2], x[2], x[3:5], x[5]
    c = np.concatenate([p1 - c1 * _down(phi1),
                        p2 - c2 * _down(phi2) - p1 - (l1 - c1) * _down(phi1)])  # fmt: skip
    jac = np.zeros((4, 6))
    jac[0:2, 0:2] = np.eye(2)
    jac[0:2, 2] = -c1 * _across(phi1)
    jac[2:4, 0:2] = -np.eye(2)
    jac[2:4, 2] = -(l1 - c1) * _across(phi1)
    jac[2:4, 3:5] = np.eye(2)
    jac[2:4, 5] = -c2 * _across(phi2)
    return c, jac


def free_flow(_t: float, y: np.ndarray) -> np.ndarray:
    """The links' accelerations from the KKT system with Baumgarte's terms (rate 20/s)."""
    (m1, l1, c1, i1), (m2, _, c2, i2) = LINKS
    x, v = y[:6], y[6:]
    mass = np.diag([m1, m1, i1, m2, m2, i2])
    force = np.array([0.0, -m1 * G, 0.0, 0.0, -m2 * G, 0.0])
    c, jac = constraints(x)
    w1, w2 = v[2], v[5]
    # J' v: the centripetal terms of C'' = J a + gamma
    gamma = np.concatenate([c1 * w1**2 * _down(x[2]),
                            c2 * w2**2 * _down(x[5]) + (l1 - c1) * w1**2 * _down(x[2])])
    rate = 20.0
    kkt = np.block([[mass, jac.T], [jac, np.zeros((4, 4))]])
    rhs = np.concatenate([force, -gamma - 2 * rate * (jac @ v) - rate**2 * c])
    return np.concatenate([v, np.linalg.solve(kkt, rhs)[:6]])


def to_free(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Generalized state (theta1, theta2, rates) -> the free links' state (12)."""
    (_, l1, c1, _), (_, _, c2, _) = LINKS
    phi1, phi2 = q[0], q[0] + q[1]
    w1, w2 = qd[0], qd[0] + qd[1]
    p1, p2 = c1 * _down(phi1), l1 * _down(phi1) + c2 * _down(phi2)
    v1 = c1 * w1 * _across(phi1)
    v2 = l1 * w1 * _across(phi1) + c2 * w2 * _across(phi2)
    return np.concatenate([p1, [phi1], p2, [phi2], v1, [w1], v2, [w2]])


def body(name: str, mass: float, inertia_z: float, y: np.ndarray, k: int) -> RigidBody:
    """Link ``k`` of the free state ``y`` as a 3D rigid body in the plane z = 0 (its inertia
    isotropic, so a planar motion stays planar)."""
    pos, vel = y[3 * k: 3 * k + 2], y[6 + 3 * k: 6 + 3 * k + 2]
    return RigidBody(mass=mass, inertia_com=np.eye(3) * inertia_z, name=name,
                     position_com=[pos[0], pos[1], 0.0], velocity_com=[vel[0], vel[1], 0.0],
                     angular_velocity=[0.0, 0.0, y[6 + 3 * k + 2]])  # fmt: skip


def free_strike(y: np.ndarray, restitution: float) -> tuple[np.ndarray, float]:
    """The stop's strike on the free links by carnot's free-body route: two pins and the stop
    as a contact between the links; returns the state after and E_d (J)."""
    (m1, l1, c1, i1), (m2, _, _, i2) = LINKS
    links = {"L1": body("L1", m1, i1, y, 0), "L2": body("L2", m2, i2, y, 1)}
    elbow = np.append(y[0:2] + (l1 - c1) * _down(y[2]), 0.0)
    along = np.append(_down(y[5]), 0.0)  # the links are aligned at the stop
    normal = -np.cross([0.0, 0.0, 1.0], along)  # L2 leaves the stop as theta2 decreases
    problem = ImpactProblem(
        bodies=links,
        contacts=[PointContact(a="L2", b="L1", point=elbow + STOP_ARM * along, normal=normal,
                               restitution=restitution)],  # fmt: skip
        constraints=[Pin(body="L1", point=[0.0, 0.0, 0.0]),
                     Pin(body="L2", other="L1", point=elbow, where="constraints[1]")],
    )
    result = solve_impact(problem)
    assert not result.warnings, result.warnings
    after = np.array(y)
    for k, name in enumerate(("L1", "L2")):
        state = result.bodies[name]
        after[6 + 3 * k: 6 + 3 * k + 2] = np.asarray(state.velocity_after)[:2]
        after[6 + 3 * k + 2] = float(np.asarray(state.angular_velocity_after)[2])
    return after, result.energy.dissipated


def free_run(y0: np.ndarray, duration: float, restitution: float, strikes: int
             ) -> list[tuple[float, np.ndarray, float]]:  # fmt: skip
    """Up to ``strikes`` strikes of the stop on the free links: (time, state after, E_d)."""

    def stop(_t: float, y: np.ndarray) -> float:  # theta2 = phi2 - phi1 <= 0
        return y[2] - y[5]

    stop.terminal = True  # type: ignore[attr-defined]
    stop.direction = -1  # type: ignore[attr-defined]
    out: list[tuple[float, np.ndarray, float]] = []
    t, y = 0.0, np.array(y0)
    while len(out) < strikes and t < duration:
        # leave the stop before watching it again (the state after a strike is on it)
        start = t + 1e-9 if out else t
        if out:
            y = solve_ivp(free_flow, (t, start), y, method="DOP853", rtol=1e-13,
                          atol=1e-13).y[:, -1]  # fmt: skip
        sol = solve_ivp(free_flow, (start, duration), y, method="DOP853", rtol=1e-13,
                        atol=1e-13, events=stop)  # fmt: skip
        if not sol.t_events[0].size:
            break
        t, y = float(sol.t_events[0][0]), sol.y_events[0][0]
        y, e_d = free_strike(y, restitution)
        out.append((t, y, e_d))
    return out


def generalized_of(y: np.ndarray) -> np.ndarray:
    """The free links' state read as (theta1, theta2, rates)."""
    return np.array([y[2], y[5] - y[2], y[8], y[11] - y[8]])


@pytest.mark.parametrize("restitution", [0.5, 1.0])
def test_free_links_with_pins_move_as_the_generalized_model(restitution: float) -> None:
    model = generalized_model()
    x0 = np.array([1.1, -0.7, 0.0, 0.0])
    run = simulate(model, x0, 2.5, Law(restitution=restitution))
    impacts = [e for e in run.events if e.kind == "impact"][:4]
    assert len(impacts) >= 3
    free = free_run(to_free(x0[:2], x0[2:]), 2.5, restitution, len(impacts))
    assert len(free) == len(impacts)
    for event, (t, y, e_d) in zip(impacts, free, strict=True):
        c, jac = constraints(y[:6])
        assert np.max(np.abs(c)) < 1e-10 and np.max(np.abs(jac @ y[6:])) < 1e-9
        assert t == pytest.approx(event.time, abs=1e-10)
        assert np.allclose(generalized_of(y), event.state, rtol=0, atol=1e-9)
        assert event.strike is not None
        assert e_d == pytest.approx(event.strike.result.energy.dissipated, rel=1e-9, abs=1e-12)
    assert abs(run.energy["residual"]) < 1e-9 * abs(run.energy["initial"])


def test_the_stop_contact_is_the_joint_limit_scaled() -> None:
    """One strike, both routes, to round-off: the free links (pins and a contact d beyond the
    elbow) and the generalized strike (the joint limit) from the same state on the stop."""
    from carnot.hybrid.strike import strike

    model = generalized_model()
    x = np.array([0.4, 0.0, -0.9, 2.1])  # on the stop, the elbow closing onto it
    for e in (0.0, 0.3, 1.0):
        s = strike(model, model.guards[0], x, Law(restitution=e))
        after, e_d = free_strike(to_free(x[:2], x[2:]), e)
        assert np.allclose(generalized_of(after), s.x_after, rtol=1e-12, atol=1e-12)
        assert e_d == pytest.approx(s.result.energy.dissipated, rel=1e-11, abs=1e-14)

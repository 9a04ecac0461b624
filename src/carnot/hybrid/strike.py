"""A strike: the impact at a guard, solved by :func:`carnot.solve_impact` in the model's
floating coordinates, and the state read back in the new stance's chart.

The impact's system is the whole model free in the plane: ``M_f(q_f)``, ``q_f' = (d chi /
d q) q'`` (the chart's velocity, the stance point at rest), with the striking point and the
points that held before (the stance foot) as contacts on the ground (normal ``n``). The law
(restitution, friction or sticking) is the model's ``[simulation]`` law; the stance foot
takes part, so it lifts off or stays as the law decides, with the law's certificate. A
guard with its own ``problem`` (a model from MJCF) builds the impact itself.

After the impact the state is read in the new chart: ``q+ = A q- + c`` and ``q'+`` solves
``(d chi / d q)(q+) q'+ = P_f q_f'+`` by least squares; its residual is the new stance
point's velocity, zero when it sticks. Two outcomes are not walking and are flagged, never
returned as a step: the new stance point does not stick (``stance_slips``: too little
friction, or a bounce), or the old stance point does not lift off (``double_support``).

A massless rod's foot (a rimless wheel's spoke on a point-mass hub) acts on its anchor along
the rod, frictionless there (the rod can turn freely about its foot); with Coulomb friction
the foot holds only if the rod's push lies in the ground's cone, else ``stance_slips``.

``reset_jacobian`` differentiates the whole strike ``x- -> x+`` by central differences (step
``RESET_STEP`` relative), the regime (which contacts stick, which lift) held fixed by the
smallness of the step, in the tangent chart (``2 n`` numbers; ``x + dx`` where ``nq == n``,
``mj_integratePos`` on an MJCF model's quaternions): the saltation matrices use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from carnot.hybrid.model import (
    Guard,
    HybridModel,
    Law,
    tangent_difference,
    tangent_gradient,
    tangent_step,
)
from carnot.model.system import SystemProblem
from carnot.result import ImpactResult

#: The new stance point's speed after the strike, relative to the state's speed scale, above
#: which it is said not to stick; and the old stance point's normal speed below which it has
#: not lifted off.
AT_REST = 1e-9
#: The relative step of the strike's central differences.
RESET_STEP = 1e-6


#: The walker papers' law: plastic, the struck point sticks.
PLASTIC = Law()


@dataclass(frozen=True, kw_only=True, eq=False)
class Strike:
    """The strike's ``result`` (an :class:`~carnot.ImpactResult` in floating coordinates),
    the state ``x_after`` in the new chart, the struck point ``struck`` (chart coordinates of
    the state before, m) and the ``flags`` of what is not walking."""

    guard: Guard
    x_before: np.ndarray
    x_after: np.ndarray
    result: ImpactResult
    struck: np.ndarray
    flags: tuple[str, ...]


def _problem(model: HybridModel, guard: Guard, x: np.ndarray, law: Law,
             held: tuple[Guard, ...] = ()) -> SystemProblem:  # fmt: skip
    from carnot.model.system import System, SystemContact

    if guard.problem is not None:  # the guard builds its own (a model from MJCF), with the
        # contacts held closed taking part (MuJoCo finds them; closed and at rest)
        return guard.problem(x, law, resting=True) if held else guard.problem(x, law)
    builder = next((g.problem for g in held if g.problem is not None), None)
    if builder is not None:  # a stop struck while an MJCF contact is held: MuJoCo builds it,
        # the stop's limit row and the held contacts in it
        return builder(x, law, resting=True)
    mech = model.mechanism
    q, qd = x[: model.nq], x[model.nq :]
    qf = mech.embed(q)
    qfd = mech.embed_jacobian(q) @ qd
    stick = law.friction is None
    contacts = []
    if guard.limit_row is not None:  # a joint's stop: one frictionless row on the coordinates
        jac = np.zeros((3, mech.n_floating))
        jac[0] = guard.limit_row
        contacts.append(SystemContact(jacobian=jac, normal=[1.0, 0.0, 0.0],
                                      restitution=law.restitution, law=law.law,
                                      name=guard.striking, where="contacts[0]"))  # fmt: skip
    for k, name in enumerate(() if guard.limit_row is not None else
                             (guard.striking, *guard.holding)):  # fmt: skip
        if name in mech.rods:  # a massless rod's foot: it pushes its anchor along the rod
            anchor = mech.rods[name]
            foot = mech.rod_foot(name, q)
            jac = mech.point_jacobian(anchor, qf)
            normal = np.array([*(mech.point(anchor, qf) - foot), 0.0])
            normal /= np.linalg.norm(normal)
            p, friction = foot, 0.0
            tangential: Literal["slip", "stick"] = "slip"
        else:
            p, jac = mech.point(name, qf), mech.point_jacobian(name, qf)
            normal = model.normal if guard.normal is None else guard.normal
            friction = 0.0 if law.friction is None else float(law.friction)
            tangential = "stick" if stick else "slip"
        contacts.append(SystemContact(
            jacobian=jac, normal=normal, point=[float(p[0]), float(p[1]), 0.0],
            restitution=law.restitution, law=law.law, friction=friction,
            tangential=tangential, name=name, where=f"contacts[{k}]",
        ))  # fmt: skip
    for k, other in enumerate(held, start=len(contacts)):  # closed contacts held in the flow
        if other.limit_row is not None:
            jac = np.zeros((3, mech.n_floating))
            jac[0] = other.limit_row
            contacts.append(SystemContact(jacobian=jac, normal=[1.0, 0.0, 0.0],
                                          restitution=law.restitution, law=law.law,
                                          name=other.striking, where=f"contacts[{k}]"))
            continue
        p = mech.point(other.striking, qf)
        contacts.append(SystemContact(
            jacobian=mech.point_jacobian(other.striking, qf),
            normal=model.normal if other.normal is None else other.normal,
            point=[float(p[0]), float(p[1]), 0.0], restitution=law.restitution, law=law.law,
            friction=0.0 if law.friction is None else float(law.friction),
            tangential="stick" if stick else "slip", name=other.striking, where=f"contacts[{k}]",
        ))  # fmt: skip
    return SystemProblem(
        title=f"{model.name}: {guard.name}",
        system=System(mass_matrix=mech.floating_mass(qf), velocity=qfd,
                      coordinates=model.floating),  # fmt: skip
        contacts=contacts,
    )


def strike(model: HybridModel, guard: Guard, x: np.ndarray, law: Law,
           held: tuple[Guard, ...] = ()) -> Strike:  # fmt: skip
    """Solve the strike at ``x`` (on ``guard``) and read the state after in the new chart;
    the contacts ``held`` closed in the flow (points on their planes, joints at their stops)
    take part, as closed contacts that the impact may press or open (DESIGN.md section 6).

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8})
    >>> a = np.pi / 8
    >>> s = strike(wheel, wheel.guards[0], np.array([0.08 + a, 1.0]), Law())
    >>> round(float(s.x_after[1]), 12), round(float(np.cos(2 * a)), 12), s.flags
    (0.707106781187, 0.707106781187, ())
    """
    from carnot import solve_impact

    nq = model.nq
    mech = model.mechanism
    result = solve_impact(_problem(model, guard, x, law, held))
    assert result.system is not None
    qfd_after = np.asarray(result.system.velocity_after, dtype=float)
    q_after = guard.relabel @ x[:nq] + guard.offset
    target = guard.velocity_relabel @ qfd_after
    jac = mech.embed_jacobian(q_after)
    qd_after, *_ = np.linalg.lstsq(jac, target, rcond=None)
    scale = max(float(np.linalg.norm(mech.embed_jacobian(x[:nq]) @ x[nq:])), 1e-300)
    flags: list[str] = []
    if np.linalg.norm(jac @ qd_after - target) > AT_REST * scale:
        flags.append("stance_slips")
    for outcome in result.contacts[1 : 1 + len(guard.holding)]:  # the old stance points
        normal = np.asarray(outcome.normal, dtype=float)
        if float(normal @ np.asarray(outcome.relative_velocity_after)) <= AT_REST * scale:
            flags.append("double_support")
    if law.friction is not None and guard.striking in mech.rods:
        outcome = result.contacts[0]
        along = float(np.asarray(outcome.normal) @ model.normal)  # the rod's push, the ground
        if along <= 0 or math.sqrt(max(1 - along**2, 0.0)) > law.friction * along:
            flags.append("stance_slips")  # the rod's push leaves the friction cone
    struck = mech.point_in_chart(guard.striking, x[:nq]) if guard.moves_anchor else np.zeros(2)
    return Strike(guard=guard, x_before=np.array(x), x_after=np.concatenate([q_after, qd_after]),
                  result=result, struck=struck, flags=tuple(flags))  # fmt: skip


def reset_jacobian(model: HybridModel, guard: Guard, x: np.ndarray, law: Law) -> np.ndarray:
    """``D_x R`` (2n x 2n): ``d x+ / d x-`` of the strike in the tangent chart
    (:func:`carnot.hybrid.model.tangent_step`; ``x + dx`` where ``nq == n``), by central
    differences of :func:`strike`: column ``j`` is ``(R(x (+) h e_j) (-) R(x) - R(x (-) h
    e_j) (-) R(x)) / 2 h``, ``(-)`` taken at ``R(x)`` (:func:`carnot.hybrid.model.
    tangent_difference`), ``h = RESET_STEP max(1, |x_j|)`` (``|x_j|`` the coordinate's own
    value where it has one: every velocity, and every position where ``nq == n``); where
    the guard has a ``reach`` (its problem finds the contacts within that gap), a position's
    step is at most ``reach / (10 |d G / d x_j|)``, so that the strike's contacts stay."""
    n, n2 = model.n, 2 * model.n
    base = strike(model, guard, x, law).x_after
    scale = np.abs(np.concatenate([x[: model.nq] if model.nq == n else np.zeros(n),
                                   x[model.nq :]]))  # fmt: skip
    steps = RESET_STEP * np.maximum(1.0, scale)
    if guard.reach is not None:
        slope = np.abs(tangent_gradient(model, guard, x)[:n])
        steps[:n] = np.minimum(steps[:n], 0.1 * guard.reach / np.maximum(slope, 1e-300))
    out = np.zeros((n2, n2))
    for j in range(n2):
        h = float(steps[j])
        step = np.zeros(n2)
        step[j] = h
        up = strike(model, guard, tangent_step(model, x, step), law).x_after
        down = strike(model, guard, tangent_step(model, x, -step), law).x_after
        out[:, j] = (tangent_difference(model, base, up)
                     - tangent_difference(model, base, down)) / (2 * h)  # fmt: skip
    return out

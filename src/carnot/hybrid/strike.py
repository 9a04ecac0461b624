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
from functools import lru_cache
from typing import Any, Literal

import numpy as np

from carnot.hybrid.model import (
    Guard,
    HybridModel,
    Law,
    tangent_difference,
    tangent_gradient,
    tangent_step,
)
from carnot.keys import exact_key
from carnot.model.system import SystemContact, SystemProblem
from carnot.result import ImpactResult

#: The new stance point's speed after the strike, relative to the state's speed scale, above
#: which it is said not to stick; and the old stance point's normal speed below which it has
#: not lifted off.
AT_REST = 1e-9
#: The relative step of the strike's central differences.
RESET_STEP = 1e-6
EPS = float(np.finfo(float).eps)


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


#: How many contacts' law data :func:`_law_contact` keeps, checked (a model's strikes share a
#: few: each foot's, with the law of the run).
CONTACTS_KEPT = 256


@lru_cache(maxsize=CONTACTS_KEPT)
def _template(normal: tuple[float, ...], numbers: tuple[float, ...], law: str,
              tangential: Literal["slip", "stick"], name: str, where: str
              ) -> SystemContact:  # fmt: skip
    """A contact with the law data of the key (``normal``, ``numbers``: restitution and
    friction, by :func:`carnot.keys.exact_key`), checked once; its Jacobian and point are
    the strike's (:meth:`SystemContact.at`)."""
    return SystemContact(jacobian=np.zeros((3, 1)), normal=list(normal[:3]),
                         restitution=numbers[0], law=law, friction=numbers[1],
                         tangential=tangential, name=name, where=where)  # fmt: skip


def _law_contact(jacobian: np.ndarray, normal: Any, point: list[float] | None,
                 restitution: float, law: str, friction: float,
                 tangential: Literal["slip", "stick"], name: str, where: str
                 ) -> SystemContact:  # fmt: skip
    """``SystemContact(...)`` of these numbers: the law data's checks and the normal's frame
    made once per law (:func:`_template`), the Jacobian and the point checked finite."""
    key = exact_key(np.asarray(normal, dtype=float).tolist())
    numbers = exact_key([float(restitution), float(friction)])
    return _template(key, numbers, law, tangential, name, where).at(jacobian, point)


def _problem(model: HybridModel, guard: Guard, x: np.ndarray, law: Law,
             held: tuple[Guard, ...] = ()) -> SystemProblem:  # fmt: skip
    from carnot.model.system import System

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
        contacts.append(_law_contact(jac, [1.0, 0.0, 0.0], None, law.restitution, law.law, 0.0,
                                     "slip", guard.striking, "contacts[0]"))  # fmt: skip
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
        if name in mech.rods:  # (its normal the rod's: a new one each strike)
            contacts.append(SystemContact(
                jacobian=jac, normal=normal, point=[float(p[0]), float(p[1]), 0.0],
                restitution=law.restitution, law=law.law, friction=friction,
                tangential=tangential, name=name, where=f"contacts[{k}]",
            ))  # fmt: skip
            continue
        contacts.append(_law_contact(jac, normal, [float(p[0]), float(p[1]), 0.0],
                                     law.restitution, law.law, friction, tangential, name,
                                     f"contacts[{k}]"))  # fmt: skip
    for k, other in enumerate(held, start=len(contacts)):  # closed contacts held in the flow
        if other.limit_row is not None:
            jac = np.zeros((3, mech.n_floating))
            jac[0] = other.limit_row
            contacts.append(_law_contact(jac, [1.0, 0.0, 0.0], None, law.restitution,
                                         law.law, 0.0, "slip", other.striking,
                                         f"contacts[{k}]"))  # fmt: skip
            continue
        p = mech.point(other.striking, qf)
        contacts.append(_law_contact(
            mech.point_jacobian(other.striking, qf),
            model.normal if other.normal is None else other.normal,
            [float(p[0]), float(p[1]), 0.0], law.restitution, law.law,
            0.0 if law.friction is None else float(law.friction),
            "stick" if stick else "slip", other.striking, f"contacts[{k}]",
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
    qd_after = _least_squares(jac, target)
    # (|v| as sqrt(v . v): np.linalg.norm's own formula for a vector, without its dispatch;
    # the floating velocity before is the problem's own, where this module built it)
    before = (result.system.velocity_before if guard.problem is None else
              mech.embed_jacobian(x[:nq]) @ x[nq:])  # fmt: skip
    scale = max(math.sqrt(float(before.dot(before))), 1e-300)
    flags: list[str] = []
    residual = jac @ qd_after - target
    if math.sqrt(float(residual.dot(residual))) > AT_REST * scale:
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


@lru_cache(maxsize=64)
def _workspace(m: int, n: int) -> tuple[int, int]:
    """LAPACK ``dgelsd``'s workspace for ``m x n`` systems (0, 0: none found)."""
    from scipy.linalg import lapack

    work, iwork, info = lapack.dgelsd_lwork(m, n, 1, -1.0)
    return (int(work), int(iwork)) if info == 0 else (0, 0)


def _least_squares(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``numpy.linalg.lstsq(a, b, rcond=None)[0]`` (``a`` m x n, m >= n): the minimum-norm
    least squares solution, singular values below ``eps max(m, n)`` of the largest cut, by
    NumPy's driver, LAPACK's ``dgelsd``, called directly with its workspace found once per
    shape (as :mod:`carnot.laws.multiple.simultaneous` solves its regimes): the same numbers
    (20000 random 4 x 2 systems, near-dependent columns among them, bit for bit), without
    NumPy's wrapper and its workspace query (a strike's 9 of 12 us; 30 us after a leg).

    >>> a = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.0, 0.0]])
    >>> b = np.array([1.0, 2.0, 0.0, 1.0])
    >>> bool(np.array_equal(_least_squares(a, b), np.linalg.lstsq(a, b, rcond=None)[0]))
    True
    """
    m, n = a.shape
    lwork, liwork = _workspace(m, n) if m >= n >= 1 and b.shape == (m,) else (0, 0)
    if lwork:
        from scipy.linalg import lapack

        x, _, _, info = lapack.dgelsd(a, b, lwork, liwork, EPS * max(m, n))
        if info == 0:
            return np.asarray(x[:n])
    return np.linalg.lstsq(a, b, rcond=None)[0]  # (no workspace, or no convergence)


def reset_jacobian(model: HybridModel, guard: Guard, x: np.ndarray, law: Law,
                   held: tuple[Guard, ...] = ()) -> np.ndarray:  # fmt: skip
    """``D_x R`` (2n x 2n): ``d x+ / d x-`` of the strike in the tangent chart
    (:func:`carnot.hybrid.model.tangent_step`; ``x + dx`` where ``nq == n``), by central
    differences of :func:`strike`: column ``j`` is ``(R(x (+) h e_j) (-) R(x) - R(x (-) h
    e_j) (-) R(x)) / 2 h``, ``(-)`` taken at ``R(x)`` (:func:`carnot.hybrid.model.
    tangent_difference`), ``h = RESET_STEP max(1, |x_j|)`` (``|x_j|`` the coordinate's own
    value where it has one: every velocity, and every position where ``nq == n``); where
    the guard has a ``reach`` (its problem finds the contacts within that gap), a position's
    step is at most ``reach / (10 |d G / d x_j|)``, so that the strike's contacts stay.
    ``held``: the contacts held in the flow before the strike, which take part in it
    (:func:`strike`)."""
    n, n2 = model.n, 2 * model.n
    base = strike(model, guard, x, law, held).x_after
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
        up = strike(model, guard, tangent_step(model, x, step), law, held).x_after
        down = strike(model, guard, tangent_step(model, x, -step), law, held).x_after
        out[:, j] = (tangent_difference(model, base, up)
                     - tangent_difference(model, base, down)) / (2 * h)  # fmt: skip
    return out

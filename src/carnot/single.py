"""One point contact between two bodies, frictionless or sticking: the pipeline's short path.

The commonest impact (a ball on the floor, two bodies meeting at a point) is the
single-contact case of the spine of DESIGN.md section 1, and the batch kernels already have it
written once, as formulas on the numbers of one impact (:func:`carnot.batch.pipeline.impact`:
inertia factors, contact frame, ``K`` and ``w'``; the law, :mod:`carnot.batch.laws`; the
velocities after, paper eq. 4; the kinetic energies, paper eq. 5, and Carnot's ``E_p``, eq.
13). Here they run on Python floats (:class:`carnot.batch.ops.PYTHON_FLOATS`): about twenty
microseconds, where the general pipeline's dozens of small NumPy calls on 3- to 12-vectors
take over a hundred. The theorem's share, ``-1/2 P . (w' + w'')`` (eqs. 11 and 16), reads
``w''`` from the velocities after, as the general outcome does (not the law's ``w' + K P``:
that closes the ledger only to the round-off of ``K``). The result is the general
pipeline's, field for field, with the same flags built by the same
functions (:func:`carnot.outcome.point_contact_flags`, :func:`carnot.outcome.flag_energy_gain`,
:func:`carnot.model.free_bodies.momentum_balance`); ``tests/test_single.py`` holds the two
routes to each other, and ``tests/test_twins.py`` the laws.

What takes this path (:func:`short_path`): exactly one contact and no constraint, a point
(no patch) with a law (no given impulse), frictionless or sticking (:func:`carnot.laws.
contact_rule`), body ``a`` movable. Anything else, and any impact whose arithmetic divides by
zero on floats (a contact at rest that sticks: ``P_n = 0``), goes the general way.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from math import inf, sqrt
from types import SimpleNamespace

import numpy as np

from carnot.batch.ops import PYTHON_FLOATS, specialize
from carnot.laws import contact_rule
from carnot.model.bodies import Body, FixedBody, RigidBody
from carnot.model.contacts import PointContact
from carnot.model.free_bodies import fixed_motion, momentum_balance, read_only
from carnot.model.problem import ImpactProblem
from carnot.outcome import flag_energy_gain, ledger_closes, ledger_flag, point_contact_flags
from carnot.result import (
    BodyMotion,
    EnergyLedger,
    Flag,
    ImpactResult,
    ItemOutcome,
    MomentumCheck,
)

# a fixed obstacle as the formulas take it: mass 1, unit inertia, at rest (movable_b = 0)
#: The nine entries of a unit inertia tensor, and a velocity (or a point) at rest: the fixed
#: world's stand-ins in the short path's float arguments.
UNIT_INERTIA = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
REST = (0.0, 0.0, 0.0)
_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)


@functools.cache
def _formulas(rule: str) -> SimpleNamespace:
    """The batch formulas with the law ``rule`` (``frictionless`` or ``stick``), on floats."""
    return specialize(PYTHON_FLOATS, rule)


@functools.lru_cache(maxsize=4096)
def inertia_factor(inertia: tuple[float, ...]) -> tuple[tuple[float, ...], bool]:
    """The Cholesky factor of an inertia tensor's nine entries and its validity
    (:func:`carnot.batch.rigid.factor`), kept: a body meets the floor again and again."""
    return _formulas("frictionless").factor(inertia)


def short_path(problem: ImpactProblem) -> str | None:
    """The law rule (``"frictionless"`` or ``"stick"``) when ``problem`` takes this path (module
    docstring), else ``None``.

    >>> from carnot import FixedBody
    >>> ball = RigidBody(mass=1.0, inertia_com=np.eye(3) * 0.004, name="ball")
    >>> c = PointContact(a="ball", b="floor", point=[0, 0, -0.1], normal=[0, 0, 1])
    >>> short_path(ImpactProblem(bodies={"ball": ball, "floor": FixedBody(name="floor")},
    ...                          contacts=[c]))
    'frictionless'
    """
    if problem.constraints or len(problem.contacts) != 1:
        return None
    contact = problem.contacts[0]
    if contact.patch is not None or contact.is_given:
        return None
    if not isinstance(problem.bodies[contact.a], RigidBody):
        return None
    rule = contact_rule(tangential=contact.tangential, friction=contact.friction)
    return rule if rule in ("frictionless", "stick") else None


def solve_single(problem: ImpactProblem, rule: str) -> ImpactResult | None:
    """The outcome of ``problem`` (which :func:`short_path` gave ``rule``), or ``None`` when the
    float arithmetic divided by zero (the caller then takes the general pipeline)."""
    contact = problem.contacts[0]
    a = problem.bodies[contact.a]
    b = problem.bodies[contact.b]
    assert isinstance(a, RigidBody)
    point = tuple(contact.point.tolist())
    m_a, j_a, x_a, v_a, om_a = a.float_state
    if isinstance(b, RigidBody):
        m_b, j_b, x_b, v_b, om_b = b.float_state
        movable_b = 1.0
    else:  # a fixed obstacle as the formulas take it
        m_b, j_b, x_b, v_b, om_b, movable_b = 1.0, UNIT_INERTIA, point, REST, REST, 0.0
    e, mu, normal = contact.restitution, contact.friction, tuple(contact.normal.tolist())
    out = single_floats(rule, m_a, j_a, x_a, v_a, om_a, m_b, j_b, x_b, v_b, om_b, movable_b,
                        point, normal, e, mu)  # fmt: skip
    if out is None:
        return None
    return _result(problem, contact, a, b, rule, *out)


def single_floats(rule: str, m_a: float, j_a: tuple[float, ...], x_a: Sequence[float],
                  v_a: Sequence[float], om_a: Sequence[float], m_b: float,
                  j_b: tuple[float, ...], x_b: Sequence[float], v_b: Sequence[float],
                  om_b: Sequence[float], movable_b: float, point: Sequence[float],
                  normal: Sequence[float], e: float, mu: float
                  ) -> tuple[tuple[float, ...], tuple[float, ...]] | None:  # fmt: skip
    """The arithmetic of :func:`solve_single` on the impact's floats (as
    :attr:`carnot.RigidBody.float_state` gives them; a fixed ``b``: mass 1, unit inertia, at
    ``point``, at rest, ``movable_b = 0``): the formulas' floats
    (:data:`carnot.batch.pipeline.FLOAT_FIELDS`) and the law's output, or ``None`` when they
    divided by zero. A caller that has built and validated the impact's bodies and contact
    once (``carnot simulate``'s event loop) calls it directly, and :func:`single_result`
    when it wants the result.

    >>> floats, law = single_floats("frictionless", 1.0, (0.004, 0, 0, 0, 0.004, 0, 0, 0, 0.004),
    ...     (0, 0, 0.1), (0, 0, -2.0), (0, 0, 0), 1.0, UNIT_INERTIA, (0, 0, 0), REST, REST,
    ...     0.0, (0, 0, 0), (0, 0, 1.0), 0.5, 0.0)
    >>> floats[4:7], floats[22] - floats[23]   # v'' (m/s), E_d (J)
    ((0.0, 0.0, 1.0), 1.5)
    """
    return factored_floats(rule, inertia_factor(j_a), inertia_factor(j_b), m_a, j_a, x_a, v_a,
                           om_a, m_b, j_b, x_b, v_b, om_b, movable_b, point, normal, e,
                           mu)  # fmt: skip


def factored_floats(rule: str, factor_a: tuple[tuple[float, ...], bool],
                    factor_b: tuple[tuple[float, ...], bool], m_a: float,
                    j_a: tuple[float, ...], x_a: Sequence[float], v_a: Sequence[float],
                    om_a: Sequence[float], m_b: float, j_b: tuple[float, ...],
                    x_b: Sequence[float], v_b: Sequence[float], om_b: Sequence[float],
                    movable_b: float, point: Sequence[float], normal: Sequence[float],
                    e: float, mu: float
                    ) -> tuple[tuple[float, ...], tuple[float, ...]] | None:  # fmt: skip
    """:func:`single_floats` with the inertia factors of ``a`` and ``b`` given (each
    ``inertia_factor(j)``: the Cholesky factor and its validity), for a caller that meets the same
    bodies at every impact and keeps them (``carnot simulate``'s lean loop)."""
    f = _formulas(rule)
    try:
        geo = f.factored_geometry(*factor_a, *factor_b, m_a, x_a, v_a, om_a, m_b, x_b, v_b,
                                  om_b, movable_b, point, normal)  # fmt: skip
        law_out = f.law(geo[9], geo[11], e, mu)
        floats = f.outcome(m_a, j_a, v_a, om_a, m_b, j_b, v_b, om_b, movable_b, geo, law_out)
    except ZeroDivisionError:
        return None
    return floats, law_out


def single_result(problem: ImpactProblem, rule: str, floats: tuple[float, ...],
                  law_out: tuple[float, ...]) -> ImpactResult:  # fmt: skip
    """:func:`solve_single`'s result from :func:`single_floats`' output on ``problem``'s
    floats (``problem`` takes the short path with ``rule``: :func:`short_path`)."""
    contact = problem.contacts[0]
    a = problem.bodies[contact.a]
    assert isinstance(a, RigidBody)
    return _result(problem, contact, a, problem.bodies[contact.b], rule, floats, law_out)


def _result(
    problem: ImpactProblem,
    contact: PointContact,
    a: RigidBody,
    b: object,
    rule: str,
    floats: tuple[float, ...],
    law_out: tuple[float, ...],
) -> ImpactResult:
    """The general pipeline's result (:func:`carnot.solve._result`) from the formulas' floats
    (:data:`carnot.batch.pipeline.FLOAT_FIELDS`) and the law's row impulses."""
    movers = [a, b] if isinstance(b, RigidBody) else [a]

    def momentum(pairs: list[tuple[list[float], tuple[float, ...]]], outcome: ItemOutcome
                 ) -> Callable[[], MomentumCheck]:  # fmt: skip
        moves = [(body, before, after) for body, (before, after) in zip(movers, pairs,
                                                                          strict=True)]
        return functools.partial(momentum_balance, problem, moves, (outcome,))

    return _assemble(problem.title, problem.bodies, contact, a.float_state,
                     (a.velocity_com, a.angular_velocity), b, rule, floats, law_out,
                     momentum)  # fmt: skip


def plane_result(title: str, contact: PointContact, plane: FixedBody,
                 state_a: tuple[float, tuple[float, ...], tuple[float, ...],
                                tuple[float, ...], tuple[float, ...]],
                 before_a: tuple[np.ndarray, np.ndarray], rule: str,
                 floats: tuple[float, ...], law_out: tuple[float, ...],
                 problem: Callable[[], ImpactProblem]) -> ImpactResult:  # fmt: skip
    """:func:`single_result` for the problem ``problem()`` of one body ``contact.a`` striking
    the fixed ``plane`` (``contact.b``), titled ``title``, from its parts, without building
    it: the body's :attr:`carnot.RigidBody.float_state` ``state_a`` and its velocity and
    angular velocity before (read-only arrays, as the body holds them). ``problem()`` is
    called only if the momentum check is read (``carnot simulate``'s lean loop, whose
    thousands of results are read for their ledger and impulses; a picklable callable, such
    as a :func:`functools.partial`, for a result that pickles)."""

    def momentum(pairs: list[tuple[list[float], tuple[float, ...]]], outcome: ItemOutcome
                 ) -> Callable[[], MomentumCheck]:  # fmt: skip
        # (a partial of module functions: a result pickles with it, as solve_impact's does)
        return functools.partial(_plane_momentum, problem, contact.a, pairs[0], outcome)

    # (the body is the one that moves: _assemble reads it from before_a, not from here)
    return _assemble(title, {contact.a: None, contact.b: plane}, contact, state_a, before_a,
                     plane, rule, floats, law_out, momentum)  # fmt: skip


def _plane_momentum(problem: Callable[[], ImpactProblem], name: str,
                    pair: tuple[list[float], tuple[float, ...]], outcome: ItemOutcome
                    ) -> MomentumCheck:  # fmt: skip
    """:func:`plane_result`'s momentum check: :func:`momentum_balance` on ``problem()``, body
    ``name`` moving from the first to the second ``(v, omega)`` of ``pair``."""
    built = problem()
    body = built.bodies[name]
    assert isinstance(body, RigidBody)
    return momentum_balance(built, [(body, *pair)], (outcome,))


def _assemble(
    title: str,
    bodies: Mapping[str, Body | None],
    contact: PointContact,
    state_a: tuple[float, tuple[float, ...], tuple[float, ...], tuple[float, ...],
                   tuple[float, ...]],
    arrays_a: tuple[np.ndarray, np.ndarray],
    b: object,
    rule: str,
    floats: tuple[float, ...],
    law_out: tuple[float, ...],
    momentum: Callable[[list[tuple[list[float], tuple[float, ...]]], ItemOutcome],
                       Callable[[], MomentumCheck]],
) -> ImpactResult:
    """The result of the problem titled ``title`` with ``bodies`` (in its order; ``None`` for
    body ``a``, which moves) from its parts: body ``a``'s float state and its ``(v, omega)``
    before as arrays, body ``b``, and ``momentum(pairs, outcome)``: the check made when read,
    from each moving body's ``(v, omega)`` before and after (``a``'s, then ``b``'s)."""
    p_n, p_1, p_2 = law_out[0], law_out[1], law_out[2]
    px, py, pz = floats[0:3]
    n0, n1, n2 = contact.normal.tolist()
    w1 = floats[16:19]
    after_a = floats[4:10]
    before_a = [*state_a[3], *state_a[4]]  # (v, omega) before: the body's motion_com
    pairs = [(before_a, after_a)]
    moved = {contact.a: after_a}
    befores = {contact.a: arrays_a}
    om_rel = [*before_a[3:], *after_a[3:]]  # Omega' then Omega''
    # w'' from the velocities after, as the general outcome reads it (J u''), not the law's
    # w' + K P: the theorem then closes against the direct difference to round-off
    point = contact.point.tolist()
    w2 = point_velocity(after_a, state_a[2], point)
    if isinstance(b, RigidBody):
        after_b = floats[10:16]
        before_b = b.motion_com.tolist()
        pairs.append((before_b, after_b))
        moved[contact.b] = after_b
        befores[contact.b] = (b.velocity_com, b.angular_velocity)
        om_rel = [x - y for x, y in zip(om_rel, (*before_b[3:], *after_b[3:]), strict=True)]
        w2_b = point_velocity(after_b, b.float_state[2], point)
        w2 = [x - y for x, y in zip(w2, w2_b, strict=True)]
    # the theorem's share (outcome.theorem_terms): -1/2 P . (w' + w''), normal and tangential
    s0, s1, s2 = w1[0] + w2[0], w1[1] + w2[1], w1[2] + w2[2]
    d_normal = -0.5 * p_n * (n0 * s0 + n1 * s1 + n2 * s2) + 0.0  # + 0.0: no negative zero
    # the tangential impulse, and the outcome's vectors in one array (rows as views)
    tx, ty, tz = px - p_n * n0, py - p_n * n1, pz - p_n * n2
    vectors = np.array((px, py, pz, tx, ty, tz, *w1, *w2, *om_rel)).reshape(6, 3)
    vectors.setflags(write=False)
    friction_required = None
    if rule == "stick":
        friction_required = sqrt(tx * tx + ty * ty + tz * tz) / p_n if p_n > 0 else inf
    flags: list[Flag] = point_contact_flags(
        contact, w_normal=w1[0] * n0 + w1[1] * n1 + w1[2] * n2, normal_impulse=p_n,
        scale=sqrt(px * px + py * py + pz * pz) + 1e-300, friction_required=friction_required,
    )  # fmt: skip
    d_tangential = -0.5 * (tx * s0 + ty * s1 + tz * s2) + 0.0
    before, after, lost = floats[22], floats[23], floats[28]
    if len(bodies) > len(moved) + (not isinstance(b, RigidBody)):
        # bodies in no contact keep their kinetic energy, on both sides of the ledger
        idle = sum(body.kinetic_energy() for name, body in bodies.items()
                   if isinstance(body, RigidBody) and name not in moved)  # fmt: skip
        before, after = before + idle, after + idle
    dissipated = d_normal + d_tangential
    # (Record.from_fields: every field in declaration order, as the dataclasses' __init__
    # sets them; tests/test_single.py holds them to the general route's)
    outcome = ItemOutcome.from_fields({
        "where": contact.where, "kind": "contact", "a": contact.a, "b": contact.b,
        "point": contact.point, "normal": contact.normal, "impulse": vectors[0],
        "moment": _ZERO3, "normal_impulse": p_n, "tangential_impulse": vectors[1],
        "regime": rule, "relative_velocity_before": vectors[2],
        "relative_velocity_after": vectors[3], "relative_angular_velocity_before": vectors[4],
        "relative_angular_velocity_after": vectors[5], "dissipated": dissipated,
        "dissipated_normal": d_normal, "dissipated_tangential": d_tangential,
        "dissipated_moment": 0.0, "friction_required": friction_required,
        "centre_of_pressure": None, "law": contact.law, "process": None, "active": None,
        "name": contact.name, "generalized_impulse": None})  # fmt: skip
    ledger = EnergyLedger.from_fields({
        "before": before, "after": after, "dissipated": before - after,
        "dissipated_theorem": dissipated, "lost_velocities": lost,
        "carnot_defect": (before - after) - lost,
        # -Lambda . W u'' = -P . w'' (the rows are the contact frame's, or n with P = p_n n)
        "carnot_condition": -(px * w2[0] + py * w2[1] + pz * w2[2]),
        "dissipated_normal": d_normal, "dissipated_tangential": d_tangential,
        "dissipated_moment": 0.0})  # fmt: skip
    gain = flag_energy_gain(ledger, (contact,), {})  # (the problem's one contact)
    if not ledger_closes(ledger):
        flags.append(ledger_flag(ledger))
    # (momentum_later given: no "momentum" field until read, ImpactResult.__post_init__)
    return ImpactResult.from_fields({
        "title": title, "bodies": _motions(bodies, moved, befores), "contacts": (outcome,),
        "constraints": (), "energy": ledger, "momentum": None,
        "warnings": (*flags, gain) if gain is not None else tuple(flags),
        "row_impulses": np.array((p_n, p_1, p_2) if rule == "stick" else (p_n,)),
        "multiple_impact": None, "complementarity_residual": None, "stages": (),
        "alternatives": (), "system": None, "solver": None, "solver_groups": (),
        "momentum_later": momentum(pairs, outcome)})


def point_velocity(motion: Sequence[float], x: Sequence[float], point: list[float]
                    ) -> list[float]:  # fmt: skip
    """``v + omega x r`` (m/s) at ``point`` of a body at ``x`` moving with ``(v, omega)``."""
    r0, r1, r2 = point[0] - x[0], point[1] - x[1], point[2] - x[2]
    v0, v1, v2, o0, o1, o2 = motion
    return [v0 + o1 * r2 - o2 * r1, v1 + o2 * r0 - o0 * r2, v2 + o0 * r1 - o1 * r0]


def _motions(bodies: Mapping[str, Body | None], after: dict[str, tuple[float, ...]],
             before: dict[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, BodyMotion]:
    """Every body's motion (:func:`carnot.model.free_bodies.body_report`'s, in the problem's
    order); ``after``: the ``(v, omega)`` after of the bodies in the contact, ``before``:
    their velocity and angular velocity before (the bodies' read-only arrays)."""
    motions = {}
    for name, body in bodies.items():
        moved = after.get(name)
        if moved is not None:  # (a body in the contact: movable)
            both = np.array(moved)
            both.setflags(write=False)
            v1, om1 = before[name]
            motions[name] = BodyMotion.from_fields({
                "name": name, "fixed": False, "velocity_before": v1,
                "angular_velocity_before": om1, "velocity_after": both[:3],
                "angular_velocity_after": both[3:]})  # fmt: skip
        elif not isinstance(body, RigidBody):
            motions[name] = fixed_motion(name)
        else:
            motions[name] = BodyMotion.from_fields({
                "name": name, "fixed": False, "velocity_before": body.velocity_com,
                "angular_velocity_before": body.angular_velocity,
                "velocity_after": read_only(body.velocity_com),
                "angular_velocity_after": read_only(body.angular_velocity)})  # fmt: skip
    return motions

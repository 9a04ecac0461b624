"""Simulate a hybrid model: flow, strike, relabel, until the duration ends, the model falls,
comes to rest, or does something that is not walking (DESIGN.md section 10).

Each strike is one :func:`carnot.solve_impact` (its result is the event's, as in a section 8
impact event); the ledger is the model's total energy ``E = T + V`` (the chart's origin moves
with each step, and ``V`` with it):

    E(0) - sum of the strikes' E_d - W_dampers - W_sliding = E(end)
                                                  to the integrator's tolerance,

and it is checked in every run (``energy.residual``); ``W_dampers`` (the mechanism's
dampers, ``int c l'^2 dt``) and ``W_sliding`` (the friction at sliding held contacts) are
integrated beside the state (:func:`carnot.hybrid.flow.fly`). The saltation matrix of a strike at
``x-`` on the guard ``G(x) = 0`` with reset ``R`` (Aizerman and Gantmacher 1958; Kong, Payne,
Council and Johnson, *The saltation matrix*, 2023, eq. 7) is

    S = D_x R + (f+ - D_x R f-) (D_x G) / (D_x G f-),

``f-`` and ``f+`` the flow before and after; it maps a perturbation just before the strike's
time to one just after. It is written in the tangent chart (:func:`carnot.hybrid.model.
tangent_step`: ``2 n`` numbers, the positions' part in velocity space; the identity where
``nq == n``), so that an MJCF model's quaternions are perturbed on their sphere. A strike
where ``D_x G f-`` vanishes (the guard met tangentially) is *grazing*: no saltation matrix
exists there, and it is flagged. Where contacts are held before the strike or after it (the
strike that starts a hold, a held stance foot's successor), ``f-`` and ``f+`` are the held
flows' fields on each side (:func:`held_field`) and ``D_x R`` differentiates the strike with
the held contacts in it; a hold's change in the flow has its own (:func:`hold_saltation`).

A joint's stop (a double pendulum's elbow) that is struck again within ``HOLD_INTERVAL``
(s) is chattering towards rest against it: that strike is made plastic, and the joint is
*held* at the stop (as after any strike that leaves it at rest there, a plastic one):
``contact_start``, the flow constrained (:func:`carnot.hybrid.flow.held_flow`)
while the stop pushes, and released (``contact_end``) where its force falls to zero. The
accumulation's time is then off by at most ``HOLD_INTERVAL e / (1 - e)``.

A point on a plane (a guard with ``rows``: :func:`carnot.hybrid.guards.plane_guard`, the
hopping leg's foot) is held the same way, by the same flow, after a strike (or a chatter)
leaves it at rest on its plane, or from the start where it rests there: *sticking* (its gap
and tangent rows held) while the force that holds it lies in the friction cone
``|F_t| <= mu F_n``, else *sliding* against Coulomb's force ``F_t = -mu F_n sign(v_t)``;
``slip`` where a stick's force leaves the cone, ``stick`` where a slide's speed reaches zero
(and the cone holds it; else it slides back, a ``slip``), ``contact_end`` where ``F_n`` falls
to zero. Another guard's strike takes the held contacts into its impact; after it each is
held anew or released.

A contact between two bodies from MJCF (a guard with ``several`` points: its ``rows`` give
each contact point MuJoCo finds for the pair) chatters the same way, its chatter closed by
a plastic strike, and is held the same way on its points closed and at rest (gap ``<=
TOUCH``, normal speed ``<= AT_REST`` of the speed scale), anchored by their labels: each
point sticking while its ``|F_t| <= mu F_n`` (the Euclidean norm of its two tangential
components), else sliding against ``-mu F_n v_t / |v_t|`` (:func:`carnot.hybrid.flow.
slide_direction`), a slide from rest in the direction its slip then grows. The held
forces of several points are not unique: the least-norm ones made non-negative
(:func:`carnot.hybrid.flow.held_solution`). The pair's next point is struck where its gap
falls through zero, the held points taking part as resting contacts, and the pair is held
anew after it. Before each leg the held rows' residual velocities are made zero by the
least kinetic change (:func:`settle`, its energy booked with the impacts). Where the held
flow's forces grow without bound (a sliding point's Painleve singularity), the run stops
(``held_singular``).

A pair held on several points that no pushing forces hold any longer is held on those whose
forces push, the others released (a box tipping over an edge); a hold that would start so
starts on those. What is not held ends the run with a ``stop`` event flagged
``contact_persists``: a contact that is closed (``|G| <= TOUCH``, at rest) and pressed by
the flow, ``G'' < 0``, that no hold takes (at the start too); a pair whose pushing points
cannot hold it either; a slide that stops where its point cannot stick (its force
outside its cone) and cannot slide from rest either (:func:`_turns_back`); a regime that
changes more than ``MAX_CHANGES`` times at one instant. ``G''`` is the second difference
of ``G`` along the flow,
``(G(x + tau f + tau^2/2 f') + G(x - tau f + tau^2/2 f') - 2 G(x)) / tau^2``, with
``f' = D_x f f`` by central differences of the flow (``tau = PRESS_STEP``); a pair's points
are at rest where each closed point's normal speed is (its least distance ``G`` has no
gradient where corners tie).

A sequence of strikes closer than ``MIN_INTERVAL`` (s) in time, or a kinetic energy after a
strike below ``REST`` of the run's energy scale, ends the run at ``rest``: a rimless wheel
rocking to a stop on two spokes strikes infinitely often in a finite time, and the strikes
still to come take what kinetic energy is left, which the ledger counts with the impacts; the
model then stays at rest until the duration.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from carnot.hybrid.flow import (
    RANK_TOLERANCE,
    SLIDE_START,
    TOLERANCE,
    Hold,
    Leg,
    contact_points,
    fly,
    has_cone,
    held_flow,
    held_margins,
    held_points,
    held_solution,
    point_friction,
    slide_margin,
    stance_margins,
)
from carnot.hybrid.model import (
    Guard,
    HybridModel,
    Law,
    tangent_flow,
    tangent_gradient,
)
from carnot.hybrid.strike import AT_REST, PLASTIC, Strike, reset_jacobian, strike

#: Strikes closer in time than this (s) end the run at rest.
MIN_INTERVAL = 1e-9
#: Kinetic energy (relative to the run's energy scale) below which the model is at rest.
REST = 1e-14
#: ``|D_x G f-|`` below this (relative to ``|D_x G| |f-|``) is a grazing strike.
GRAZING = 1e-6
#: Two strikes on one joint's stop closer than this (s) are a chatter: the next is plastic
#: and the joint is held at the stop while the stop pushes.
HOLD_INTERVAL = 1e-7
#: The most strikes in one run.
MAX_STRIKES = 100_000
#: The most changes of a held contact's regime at one instant (within ``MIN_INTERVAL``):
#: beyond them no regime holds, and the run stops (``contact_persists``).
MAX_CHANGES = 8
#: A contact's gap ``|G|`` (m) at or below this, after a strike, is closed.
TOUCH = 1e-9
#: The time step (s) of the second difference that says whether the flow presses a closed
#: contact.
PRESS_STEP = 1e-3


@dataclass(frozen=True, kw_only=True, eq=False)
class HybridEvent:
    """An event at ``time`` (s): ``kind`` ``impact`` (with its ``strike`` and, on request, its
    ``saltation`` matrix), ``fall``, ``rest`` or ``stop`` (a strike that is not walking:
    ``flags`` say why), or a held contact's ``contact_start``, ``contact_end``, ``stick``,
    ``slip`` (``flags``: the guard, and how it is held); ``state`` is x = (q, q') after it,
    in the chart whose origin is ``anchor`` (m; after a held contact's change, its holds'
    rows' velocities made zero there: :func:`settle`); ``held``: the contacts held in the flow
    after it (a later event at the same time may change them)."""

    time: float
    kind: str
    state: np.ndarray
    anchor: np.ndarray
    strike: Strike | None = None
    saltation: np.ndarray | None = None
    flags: tuple[str, ...] = ()
    held: tuple[Hold, ...] = ()


@dataclass(frozen=True, kw_only=True, eq=False)
class HybridRun:
    """A run: its ``events``, the ``final`` state at ``time`` (s) with its ``anchor``, and the
    ledger ``energy``: ``initial``, ``final``, ``impacts`` (the strikes' E_d) and
    ``residual`` (initial - impacts - final, J), all in J; ``start`` the initial state; with
    ``linearize`` (:func:`simulate`) the return map's ``jacobian``, the ``monodromy``, the
    linearization's ``flags`` and the hold changes' ``jumps``."""

    model: HybridModel
    law: Law
    events: tuple[HybridEvent, ...]
    final: np.ndarray
    time: float
    anchor: np.ndarray
    energy: dict[str, float]
    ended: str
    start: np.ndarray
    jacobian: np.ndarray | None = None
    monodromy: np.ndarray | None = None
    flags: tuple[str, ...] = ()
    jumps: tuple[float, ...] = ()


def saltation_matrix(model: HybridModel, guard: Guard, s: Strike, law: Law, *,
                     reset: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """``S = D_x R + (f+ - D_x R f-) (D_x G) / (D_x G f-)`` (2n x 2n) at the strike ``s``, in
    the tangent chart (:func:`carnot.hybrid.model.tangent_step`: ``dx = (dq, dv)``, ``dq``
    in velocity space; where ``nq == n`` the identity, ``x + dx``): ``f`` the flow there
    (:func:`carnot.hybrid.model.tangent_flow`: ``(v, v')``), ``D_x G`` the guard's gradient
    through the chart (:func:`carnot.hybrid.model.tangent_gradient`), ``D_x R`` the strike's
    (:func:`carnot.hybrid.strike.reset_jacobian`); ``reset``: that ``D_x R`` where the
    caller has made it already (its 4n strikes are most of the matrix's cost)."""
    f_minus = tangent_flow(model, s.x_before)
    f_plus = tangent_flow(model, s.x_after)
    dr = reset_jacobian(model, guard, s.x_before, law) if reset is None else reset
    grad = tangent_gradient(model, guard, s.x_before)
    return jump_saltation(dr, f_minus, f_plus, grad)


def is_grazing(model: HybridModel, guard: Guard, x: np.ndarray) -> bool:
    """Whether the guard is met tangentially at ``x``: ``|D_x G f| <= GRAZING |D_x G| |f|``
    (in the tangent chart, as the saltation matrix is: :func:`saltation_matrix`)."""
    f = tangent_flow(model, x)
    grad = tangent_gradient(model, guard, x)
    return abs(float(grad @ f)) <= GRAZING * float(np.linalg.norm(grad) * np.linalg.norm(f))


def pressed_contacts(model: HybridModel, x: np.ndarray, held: tuple[Hold, ...] = (),
                     friction: float | None = None) -> tuple[str, ...]:  # fmt: skip
    """The contacts (guards with their own ``problem``) that are closed at ``x`` and pressed
    by the flow (module docstring), by name."""
    indices = {h.index for h in held}
    contacts = [g for k, g in enumerate(model.guards) if g.problem is not None
                and k not in indices]  # fmt: skip
    if not contacts:
        return ()

    def flow(y: np.ndarray) -> np.ndarray:
        return held_flow(model, held, y, friction)[0] if held else model.mechanism.flow(y)

    f = flow(x)
    speed = max(float(np.linalg.norm(f)), 1e-300)
    delta = 1e-6 * max(1.0, float(np.linalg.norm(x))) / speed
    f_rate = (flow(x + delta * f) - flow(x - delta * f)) / (2 * delta)
    tau = PRESS_STEP
    ahead, behind = x + tau * f + 0.5 * tau**2 * f_rate, x - tau * f + 0.5 * tau**2 * f_rate
    out = []
    for g in contacts:
        gap = g.function(x)
        rates = _closed_rates(model, g, x) if g.several else [float(g.gradient(x) @ f)]
        if abs(gap) > TOUCH or max(map(abs, rates), default=0.0) > AT_REST * max(speed, 1.0):
            continue
        if (g.function(ahead) + g.function(behind) - 2 * gap) / tau**2 < 0:
            out.append(g.name)
    return tuple(out)


def _starting_strike(model: HybridModel, x: np.ndarray, t: float) -> Leg | None:
    """A contact (a guard with its own ``problem``) closed at the start (``|G| <= TOUCH``)
    and approaching strikes at once: the flow would not see it fall through zero."""
    f = model.mechanism.flow(x)
    speed = max(model.kinetic(x), 1e-300) ** 0.5
    for g in model.guards:
        if (g.problem is not None or g.rows is not None) and abs(g.function(x)) <= TOUCH:
            if g.several:  # a pair's points: one of those closed approaching (G, the least
                # distance, has no gradient where several points tie)
                rates = _closed_rates(model, g, x)
                if rates and min(rates) < -AT_REST * speed:
                    return Leg(t0=t, t1=t, x1=np.array(x), phi=None, ended=g.name, guard=g,
                               evaluations=0)  # fmt: skip
            elif g.direction * float(g.gradient(x) @ f) > 0:
                return Leg(t0=t, t1=t, x1=np.array(x), phi=None, ended=g.name, guard=g,
                           evaluations=0)  # fmt: skip
    return None


def _closed(model: HybridModel, guard: Guard, x: np.ndarray, scale: float) -> bool:
    """Whether the guard's contact is closed at ``x`` and at rest there: ``|G| <= TOUCH``,
    ``|G'| <= AT_REST`` of the speed scale ``sqrt(scale)``. (The gap first: the flow is
    evaluated only for a guard that touches, as few do of the many a robot's geoms have,
    each asked after every strike.)"""
    if not abs(guard.function(x)) <= TOUCH:
        return False
    rate = float(guard.gradient(x) @ model.mechanism.flow(x))
    speed = max(model.kinetic(x), scale) ** 0.5
    return abs(rate) <= AT_REST * speed


def _closed_rates(model: HybridModel, guard: Guard, x: np.ndarray) -> list[float]:
    """The normal speeds ``J_n q'`` (m/s) of the guard's points closed at ``x`` (gap
    ``|g| <= TOUCH``)."""
    qd = x[model.nq :]
    return [float(r.normal @ qd) for r in contact_points(model, guard, x) if abs(r.gap) <= TOUCH]


def _multi(guard: Guard, x: np.ndarray) -> bool:
    """Whether the guard's contact may hold several points (its rows a tuple: an MJCF pair)."""
    return guard.rows is not None and guard.several


def _closed_points(model: HybridModel, guard: Guard, x: np.ndarray, scale: float,
                   index: int) -> Hold | None:  # fmt: skip
    """The hold (sticking, to be decided) of the guard's contact points that are closed at
    ``x`` and at rest there: gap ``|g| <= TOUCH``, normal speed ``|J_n q'| <= AT_REST`` of
    the speed scale, anchored at their labels; ``None`` where there is none."""
    speed = max(model.kinetic(x), scale) ** 0.5
    qd = x[model.nq :]
    closed = [r for r in contact_points(model, guard, x)
              if abs(r.gap) <= TOUCH and abs(float(r.normal @ qd)) <= AT_REST * speed]  # fmt: skip
    if not closed or min(_closed_rates(model, guard, x)) < -AT_REST * speed:
        return None  # (none at rest, or one approaching: it strikes first)
    anchors = (tuple(tuple(float(c) for c in np.asarray(r.label)) for r in closed)
               if all(r.label is not None for r in closed) else ())  # fmt: skip
    return Hold(index=index, points=len(closed), anchors=anchors)


def _new_hold(model: HybridModel, held: tuple[Hold, ...], index: int, x: np.ndarray,
              friction: float | None, scale: float, base: Hold | None = None
              ) -> Hold | None:  # fmt: skip
    """How the guard ``index``, closed and at rest at ``x`` (on the points of ``base``, a
    sticking hold; default: its one point), is held, or ``None`` where the flow would pull
    it off: each point sliding along its tangential velocity where it has one (with
    friction), else sticking while its ``|F_t| <= mu F_n``, else sliding against the
    sticking force."""
    speed = max(model.kinetic(x), scale) ** 0.5
    probe = Hold(index=index) if base is None else base
    qd = x[model.nq :]
    slips: list[np.ndarray | None] = []  # each point's slip velocity, where it slides
    for r in held_points(model, probe, x):
        tangents = r.tangents()
        v = None if tangents is None or point_friction(r, friction) is None else tangents[0] @ qd
        slips.append(v if v is not None and float(np.linalg.norm(v)) > AT_REST * speed
                     else None)  # fmt: skip
    if _planar(model, probe, x):
        hold = (_sliding(probe, [slips[0]]) if slips[0] is not None else
                _stick_or_slip(model, held, probe, x, friction))  # fmt: skip
    else:
        hold = _regimes(model, held, probe, x, friction, slips)
    margin = held_margins(model, (*held, hold), len(held), x, friction)[0]
    if margin > 0:
        return hold
    if hold.points > 1:  # no pushing forces hold them all: those that push, held on
        fewer = _pushing(model, held, hold, x, friction)
        if fewer is not None:
            return _new_hold(model, held, index, x, friction, scale, _subset(probe, fewer))
    return None


def _pushing(model: HybridModel, held: tuple[Hold, ...], hold: Hold, x: np.ndarray,
             friction: float | None) -> list[int] | None:  # fmt: skip
    """The points of ``hold`` (the last of ``held + hold``) whose forces push, where some
    do not (``None`` where all or none do): a box tipping over an edge keeps the edge's."""
    f_n = held_solution(model, (*held, hold), x, friction).normal[-1]
    size = max(1.0, float(np.max(np.abs(f_n)))) if f_n.size else 1.0
    keep = [i for i, f in enumerate(f_n) if f > 1e-9 * size]
    return keep if 0 < len(keep) < len(f_n) else None


def _subset(hold: Hold, keep: list[int]) -> Hold:
    """``hold`` on its points ``keep`` only (their anchors and directions)."""
    anchors = tuple(hold.anchors[i] for i in keep) if hold.anchors else ()
    direction = tuple(hold.direction[i] for i in keep) if hold.direction else ()
    return replace(hold, points=len(keep), anchors=anchors, direction=direction)


def _planar(model: HybridModel, base: Hold, x: np.ndarray) -> bool:
    """Whether ``base`` holds one point with at most one tangent row (a point on a plane in
    a planar model: one regime, ``slip = +-1`` along the plane's tangent)."""
    points = held_points(model, base, x)
    return len(points) == 1 and (points[0].tangent is None
                                 or np.ndim(points[0].tangent) == 1)  # fmt: skip


def _sliding(base: Hold, slips: list[np.ndarray]) -> Hold:
    """``base``'s points sliding along ``slips`` (each point's slip velocity, or the
    direction it starts to slide in): ``slip = sign(v_t)`` with one point on one tangent row
    (the plane's), else each point's reference the unit slip direction."""
    if len(slips) == 1 and slips[0].size == 1:
        return replace(base, slip=1 if float(slips[0][0]) >= 0 else -1, direction=())
    return _compose(base, list(slips))


def _compose(base: Hold, slips: list[np.ndarray | None]) -> Hold:
    """``base``'s points in space, each sliding along its ``slips`` entry (made a unit
    vector) or, where it is ``None``, sticking."""
    if all(v is None for v in slips):
        return replace(base, slip=0, direction=())
    units: list[tuple[float, ...]] = []
    for v in slips:
        if v is None:
            units.append(())
            continue
        size = float(np.linalg.norm(v))
        units.append(tuple(float(c) for c in (v / size if size > 0 else np.eye(v.size)[0])))
    return replace(base, slip=1, direction=tuple(units))


def _units(hold: Hold, count: int) -> list[np.ndarray | None]:
    """Each of the hold's ``count`` points' reference direction, ``None`` where it sticks."""
    return [hold.reference(i) if hold.slides(i) else None for i in range(count)]


def _stick_or_slip(model: HybridModel, held: tuple[Hold, ...], base: Hold, x: np.ndarray,
                   friction: float | None) -> Hold:  # fmt: skip
    """A contact at rest in its slide (the points of ``base``): it sticks where the force
    that holds each point is inside its cone, ``|F_t| <= mu F_n``, and slides against that
    force otherwise."""
    stick = replace(base, slip=0, direction=())
    if not has_cone(model, stick, x, friction):
        return stick
    if not _planar(model, stick, x):
        return _regimes(model, held, stick, x, friction, [None] * stick.points)
    f_n, f_t = (v[-1] for v in _forces(model, held, stick, x, friction))
    mu = point_friction(held_points(model, stick, x)[0], friction)
    assert mu is not None
    return stick if abs(float(f_t[0, 0])) <= mu * float(f_n[0]) else _sliding(stick, [-f_t[0]])


Forces = tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]


def _forces(model: HybridModel, held: tuple[Hold, ...], hold: Hold, x: np.ndarray,
            friction: float | None) -> Forces:  # fmt: skip
    """The held points' normal and tangential forces with ``hold`` after ``held``."""
    sol = held_solution(model, (*held, hold), x, friction)
    return sol.normal, sol.tangent


#: The most fixed-point steps that turn a slide from rest to its consistent direction.
SLIDE_ITERATIONS = 50


def _regimes(model: HybridModel, held: tuple[Hold, ...], base: Hold, x: np.ndarray,
             friction: float | None, slips: list[np.ndarray | None],
             starting: tuple[int, ...] = ()) -> Hold:  # fmt: skip
    """In space, ``base``'s points sliding along ``slips`` (``None``: sticking), the points
    ``starting`` starting to slide from rest, and every sticking point whose force leaves
    its cone, ``|F_t| > mu F_n``, made to slide against that force; a point starting from
    rest slides in the direction ``u`` in which its slip velocity then grows, a fixed point
    of ``u <- a_t(u) / |a_t(u)|`` (``a_t`` its tangential acceleration with Coulomb's force
    along ``-u``), started at ``-F_t / |F_t|``."""
    points = held_points(model, base, x)
    current = list(slips)
    new = set(starting)
    for _ in range(len(points) + 1):
        hold = _compose(base, current)
        f_n, f_t = (v[-1] for v in _forces(model, held, hold, x, friction))
        out = False
        for i, r in enumerate(points):
            mu = point_friction(r, friction)
            if current[i] is not None or mu is None or r.tangent is None:
                continue
            if float(np.linalg.norm(f_t[i])) > mu * float(f_n[i]):
                current[i], out = -f_t[i], True
                new.add(i)
        if not out:
            break
    hold = _compose(base, current)
    for _ in range(SLIDE_ITERATIONS if new else 0):  # the starting slides' directions
        flow = held_solution(model, (*held, hold), x, friction).flow
        turned = list(current)
        for i in new:
            tangents = points[i].tangents()
            if tangents is not None and current[i] is not None:
                a_t = tangents[0] @ flow[model.nq :] + tangents[1]
                if float(np.linalg.norm(a_t)) > 0:
                    turned[i] = a_t
        change = max(float(np.linalg.norm(_unit(a) - _unit(b)))
                     for a, b in zip(turned, current, strict=True)
                     if a is not None and b is not None)  # fmt: skip
        current = turned
        hold = _compose(base, current)
        if change <= 1e-12:
            break
    return hold


def _unit(v: np.ndarray) -> np.ndarray:
    size = float(np.linalg.norm(v))
    return v / size if size > 0 else v


def _turns_back(model: HybridModel, held: tuple[Hold, ...], hold: Hold, x: np.ndarray,
                friction: float | None, starts: list[int]) -> bool:  # fmt: skip
    """Whether a point of ``hold`` (after ``held``) that ``starts`` to slide from rest, its
    sticking force outside its cone (:func:`_regimes`), would turn back at once: its slip
    acceleration ``a_t`` (m/s^2, tangent coordinates) is not within 60 degrees of its
    slide's direction ``u``, ``slide_margin(u, a_t) <= 0``
    (:func:`carnot.hybrid.flow.slide_margin`). From rest the slip is ``v_t = a_t tau`` after
    ``tau``: the slide's watch, the same margin of ``v_t``, would end it at once, and the
    point would stick outside its cone again. Where a slide has just stopped so, neither
    regime holds and the run stops (:func:`_change_hold`).

    Decided on ``a_t``, not by flying the slide: flown, it turns back within a round-off
    of its start, to its watch's level ``-SLIDE_START``, which the leg that tries it again
    starts from; whether that leg counted it as started (its margin a few ulps past the
    level) or not decided between ending at once (the run stopped after ``MAX_CHANGES``
    tries) and creeping on at a slip of ``SLIDE_START`` for 5e-5 s before the next try: a
    box sliding at 1 m/s and spinning at 5 rad/s stopped at 0.32665 s, or after 130 tries
    at 0.32831 s and 120 s of work, as the BLAS's kernels rounded. There the fixed point of
    :func:`_regimes` is not reached: ``a_t`` turns against each ``u`` it is given (round
    the circle of ``u`` its margin stays below -0.79 m/s^2, its size above 0.69 m/s^2)."""
    if not starts:
        return False
    flow = held_solution(model, (*held, hold), x, friction).flow
    points = held_points(model, hold, x)
    for i in starts:
        tangents = points[i].tangents()
        if tangents is not None:
            a_t = tangents[0] @ flow[model.nq :] + tangents[1]
            if slide_margin(hold.reference(i), a_t) <= 0.0:
                return True
    return False


def _change_hold(model: HybridModel, held: tuple[Hold, ...], index: int, x: np.ndarray,
                 why: str, friction: float | None, scale: float, retry: bool = False
                 ) -> tuple[tuple[Hold, ...], str, Hold | None]:  # fmt: skip
    """The holds after a hold's event ``why`` at ``x``, the event's kind and the new hold:
    ``release`` (``contact_end``), ``slip_start`` (``slip``: the point at its cone's edge
    slides against the sticking force), ``stick`` (a point's slide stopped: ``stick`` where
    the cone holds it, else ``slip`` the other way, or ``contact_end`` where nothing presses
    it; a slide that turned past 60 degrees of its reference goes on, its reference turned:
    kind ``turn``, no event). A hold of several points that no pushing forces hold any
    longer goes on with those that push (``contact_end``: the others released, a box tipping
    over an edge); where they cannot hold it either, kind ``stop`` (``contact_persists``),
    as where a slide stops at a point that can neither stick nor slide from rest
    (:func:`_turns_back`; not asked on a ``retry``: the slide that stopped was one from rest
    that turned back before it had started, :attr:`carnot.hybrid.flow.Leg.from_rest`, and
    is tried again)."""
    others = tuple(h for h in held if h.index != index)
    current = next(h for h in held if h.index == index)
    several = current.points > 1
    points = held_points(model, current, x)
    if why == "release":  # one point released; of several, those that no longer push
        keep = _pushing(model, others, current, x, friction) if several else None
        if keep is None:
            return (held, "stop", current) if several else (others, "contact_end", None)
        fewer = _subset(current, keep)
        if held_margins(model, (*others, fewer), len(others), x, friction)[0] <= 0:
            return held, "stop", current
        return (*others, fewer), "contact_end", fewer
    if _planar(model, current, x):
        if why == "slip_start":
            f_t = held_solution(model, held, x, friction).tangent[held.index(current)]
            hold = _sliding(current, [-f_t[0]])
        else:
            hold = _stick_or_slip(model, others, current, x, friction)
    elif why == "slip_start":  # the sticking point(s) at the cone's edge start to slide
        sol = held_solution(model, held, x, friction)
        j = held.index(current)
        f_n, f_t = sol.normal[j], sol.tangent[j]
        units = _units(current, len(points))
        margins = {}
        for i, r in enumerate(points):
            mu = point_friction(r, friction)
            if units[i] is None and r.tangent is not None and mu is not None:
                margins[i] = mu * float(f_n[i]) - float(np.linalg.norm(f_t[i]))
        least = min(margins.values())
        edge = tuple(i for i, m in margins.items()
                     if m <= least + 1e-9 * max(1.0, float(np.max(np.abs(f_n)))))  # fmt: skip
        for i in edge:
            units[i] = -f_t[i]
        hold = _regimes(model, others, current, x, friction, units, edge)
    else:  # a sliding point stopped, or its slide turned
        qd = x[model.nq :]
        speed = max(model.kinetic(x), scale) ** 0.5
        still = max(AT_REST * speed, 10 * SLIDE_START * max(1.0, float(np.linalg.norm(x))))
        units = _units(current, len(points))
        stopped = False
        for i, r in enumerate(points):
            tangents = r.tangents()
            if units[i] is None or tangents is None:
                continue
            v = tangents[0] @ qd
            if float(np.linalg.norm(v)) <= still:
                units[i], stopped = None, True
            else:
                units[i] = v
        if not stopped:  # each slide turned: its reference turns with it
            turned = _compose(current, units)
            return tuple(turned if h is current else h for h in held), "turn", turned
        hold = _regimes(model, others, current, x, friction, units)
        starts = [i for i, u in enumerate(units) if u is None and hold.slides(i)]
        if not retry and _turns_back(model, others, hold, x, friction, starts):
            return held, "stop", current
    if held_margins(model, (*others, hold), len(others), x, friction)[0] <= 0:
        return (held, "stop", current) if several else (others, "contact_end", None)
    sticks = sum(not hold.slides(i) for i in range(len(points)))
    was = sum(not current.slides(i) for i in range(len(points)))
    return (*others, hold), ("stick" if sticks > was or hold.slip == 0 else "slip"), hold


def starting_holds(model: HybridModel, x: np.ndarray, friction: float | None,
                   scale: float, held: tuple[Hold, ...] = ()) -> tuple[Hold, ...]:  # fmt: skip
    """The holds of a run that starts at ``x`` (:func:`simulate`; the return map's section,
    :mod:`carnot.hybrid.cycle`), after ``held``: ``held`` and each other contact (a guard
    with ``rows``) closed and at rest there (gap ``<= TOUCH``, normal speed ``<= AT_REST`` of
    the speed scale ``sqrt(scale)``, ``scale`` in J), on its points closed at rest, sticking
    or sliding as :func:`_new_hold` decides; none where the flow would pull it off. After a
    strike (``held`` those it leaves held), the contacts it leaves closed and at rest beside
    the struck one: a foot landing flat on several geoms."""
    taken = {h.index for h in held}
    for k, g in enumerate(model.guards):
        if g.rows is not None and k not in taken and _closed(model, g, x, scale):
            base: Hold | None = (_closed_points(model, g, x, scale, k) if _multi(g, x)
                                 else Hold(index=k))  # fmt: skip
            hold = None if base is None else _new_hold(model, held, k, x, friction, scale, base)
            if hold is not None:
                held = (*held, hold)
    return held


def held_field(model: HybridModel, held: tuple[Hold, ...], x: np.ndarray,
               friction: float | None) -> np.ndarray:  # fmt: skip
    """The flow at ``x`` with the contacts ``held`` (:func:`carnot.hybrid.flow.held_flow`;
    the free flow where none is), in the tangent chart (:func:`carnot.hybrid.model.
    tangent_flow`: ``(v, v')``; the flow itself where ``nq == n``)."""
    if not held:
        return tangent_flow(model, x)
    f = held_solution(model, held, x, friction).flow
    nq = model.nq
    return f if nq == model.n else np.concatenate([np.asarray(x[nq:], dtype=float), f[nq:]])


def jump_saltation(d_reset: np.ndarray, f_minus: np.ndarray, f_plus: np.ndarray,
                   grad: np.ndarray) -> np.ndarray:  # fmt: skip
    """``S = D_x R + (f+ - D_x R f-) (D_x G) / (D_x G f-)`` (2n x 2n): the saltation matrix of
    an event on ``G = 0`` (``grad`` its ``D_x G``) with the reset's Jacobian ``d_reset``,
    the fields ``f_minus`` before and ``f_plus`` after (module docstring; a hold's change
    has ``D_x R = I``).

    >>> jump_saltation(np.eye(2), np.array([1.0, 0.0]), np.array([1.0, 0.0]),
    ...                np.array([1.0, 0.0])).tolist()  # the fields agree: the identity
    [[1.0, 0.0], [0.0, 1.0]]
    """
    return d_reset + np.outer(f_plus - d_reset @ f_minus, grad) / float(grad @ f_minus)


#: The relative step of a hold event's function's central differences (its gradient in the
#: saltation matrix of :func:`hold_saltation`).
EVENT_STEP = 1e-6


def hold_saltation(model: HybridModel, before: tuple[Hold, ...], after: tuple[Hold, ...],
                   why: str, j: int, x: np.ndarray, friction: float | None
                   ) -> tuple[np.ndarray, float]:  # fmt: skip
    """The saltation matrix of a held contact's change at ``x`` (``why``: ``release``,
    ``slip_start`` or ``stick`` of the ``j``-th hold of ``before``; ``after``: the holds
    after it), and ``|f+ - f-| / |f-|``. No reset: ``S = I + (f+ - f-) (D_x h) / (D_x h
    f-)`` (:func:`jump_saltation`), ``h`` the function the flow watched (the hold's support,
    its cone margin, its slide's speed: :func:`carnot.hybrid.flow.held_margins`), ``D_x h``
    by central differences (step ``EVENT_STEP`` relative), ``f-`` and ``f+`` the fields of
    ``before`` and ``after`` (:func:`held_field`), ``nq == n``. Where the force that ends
    (a release's normal force, the friction at the cone's edge) falls to zero continuously
    the two fields agree, and ``S = I`` to that; a slide that stops is where they differ
    (the tangential acceleration jumps)."""
    from carnot.hybrid.flow import _slide_speed

    def h(y: np.ndarray) -> float:
        if why == "stick":
            return _slide_speed(model, before[j], y)
        return held_margins(model, before, j, y, friction)[0 if why == "release" else 1]

    x = np.asarray(x, dtype=float)
    grad = np.zeros(x.size)
    for i in range(x.size):
        step = EVENT_STEP * max(1.0, abs(float(x[i])))
        up, down = x.copy(), x.copy()
        up[i] += step
        down[i] -= step
        grad[i] = (h(up) - h(down)) / (2 * step)
    f_minus = held_field(model, before, x, friction)
    f_plus = held_field(model, after, x, friction)
    jump = float(np.linalg.norm(f_plus - f_minus)) / max(float(np.linalg.norm(f_minus)), 1e-300)
    return jump_saltation(np.eye(x.size), f_minus, f_plus, grad), jump


def settle(model: HybridModel, held: tuple[Hold, ...], x: np.ndarray,
           friction: float | None) -> tuple[np.ndarray, float]:  # fmt: skip
    """``x`` with the velocity along the held rows ``A`` (each held point's normal, and its
    tangents where it sticks) made zero by the least kinetic change,
    ``v+ = v - M^-1 A^T (A M^-1 A^T)^+ A v``, and the kinetic energy that takes (J, >= 0).
    A contact is held once at rest to ``AT_REST`` of the speed scale, not to round-off, and
    the held flow keeps its rows' velocities (their accelerations are held at zero): the held
    force would do work on what is left, ``F_n v_n``, which the ledger does not book."""
    if not held:
        return x, 0.0
    rows = held_solution(model, held, x, friction).rows
    q, v = x[: model.nq], x[model.nq :]
    w = rows @ v
    if not rows.size or not np.any(w):
        return x, 0.0
    m_inv_at = np.linalg.solve(model.mechanism.mass(q), rows.T)
    lam = np.linalg.lstsq(rows @ m_inv_at, w, rcond=RANK_TOLERANCE)[0]
    out = np.concatenate([q, v - m_inv_at @ lam])
    return out, max(model.kinetic(x) - model.kinetic(out), 0.0)


def _held_event(model: HybridModel, t: float, kind: str, x: np.ndarray, anchor: np.ndarray,
                guard: Guard, hold: Hold | None, held: tuple[Hold, ...]
                ) -> HybridEvent:  # fmt: skip
    """A held contact's event, flagged with the guard and, where it can slide, how it is held
    (``sticking``, or ``sliding``: towards ``+t`` or ``-t`` on a plane's one tangent row)."""
    how: tuple[str, ...] = ()
    points = [] if hold is None else held_points(model, hold, x)
    if hold is not None and any(r.tangent is not None for r in points):
        sliding = [hold.slides(i) for i, r in enumerate(points) if r.tangent is not None]
        if not any(sliding):
            how = ("sticking",)
        elif not hold.direction:
            how = ("sliding", "+t" if hold.slip > 0 else "-t")
        else:
            how = ("sliding",) if all(sliding) else ("sticking and sliding",)
    return HybridEvent(time=t, kind=kind, state=np.array(x), anchor=anchor.copy(),
                       flags=(guard.name, *how), held=held)  # fmt: skip


def simulate(model: HybridModel, x0: np.ndarray, duration: float, law: Law = PLASTIC, *,
             saltation: bool = False, tolerance: float = TOLERANCE, strikes: int | None = None,
             linearize: bool = False) -> HybridRun:  # fmt: skip
    """Run ``model`` from the state ``x0`` (chart coordinates, the origin at the stance point)
    for ``duration`` (s), or until ``strikes`` impacts (``ended = "strikes"``, just after the
    last, its contacts held or released: the return map's section, :mod:`carnot.hybrid.
    cycle`).

    ``linearize`` (``nq == n``) integrates the flow's Jacobian ``Phi`` beside each leg, free
    or held (:func:`carnot.hybrid.flow.fly`), and composes the run's ``monodromy``: ``Phi``,
    then at each strike its saltation matrix with the fields of the contacts held before
    and after (:func:`jump_saltation`; ``D_x R`` with the held contacts in the strike), and
    at each change of a hold :func:`hold_saltation`; and the return map's ``jacobian``, the
    strike's ``D_x R (I - f- D_x G / (D_x G f-))`` in place of its saltation matrix. The
    settling of the held rows' velocities before a leg (:func:`settle`: zero on the held
    contacts' manifold, where the section's states lie) is left out. A grazing strike or a
    chatter leaves both ``None`` (``flags``); ``jumps`` lists each hold change's ``|f+ -
    f-| / |f-|``.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> run = simulate(wheel, np.array([0.08 - np.pi / 8, 1.0]), 2.0)
    >>> run.ended, [e.kind for e in run.events], abs(run.energy["residual"]) < 1e-9
    ('duration', ['impact'], True)
    """
    x = np.array(x0, dtype=float)
    if x.shape != (model.nq + model.n,):
        raise ValueError(f"the state must have {model.nq + model.n} entries")
    anchor = np.zeros(2)
    t = 0.0
    initial = model.energy(x, anchor)
    scale = max(abs(initial), model.kinetic(x), 1e-300)
    impacts = dampers = sliding = 0.0
    events: list[HybridEvent] = []
    ended = "duration"
    last = -np.inf
    held: tuple[Hold, ...] = ()
    changes, changed_at = 0, -np.inf  # the held regimes' changes at one instant
    last_on: dict[int, float] = {}  # each guard's last strike (s)
    final_energy: float | None = None
    friction = law.friction
    if linearize and model.nq != model.n:
        raise ValueError("the run's linearization is built where nq == n only")
    eye = np.eye(2 * model.n)
    jac: np.ndarray | None = eye if linearize else None  # the return map's D P
    mono: np.ndarray | None = eye if linearize else None  # the monodromy
    lin_flags: list[str] = []
    jumps: list[float] = []
    struck = 0  # the strikes so far
    for first in starting_holds(model, x, friction, scale):  # resting at the start: held
        held = (*held, first)
        events.append(_held_event(model, t, "contact_start", x, anchor,
                                  model.guards[first.index], first, held))  # fmt: skip
    pressed = pressed_contacts(model, x, held, friction)
    if pressed:  # a model from MJCF resting on a contact: it is not held (yet)
        events.append(HybridEvent(time=t, kind="stop", state=x, anchor=anchor.copy(),
                                  flags=("contact_persists", *pressed)))  # fmt: skip
        ended = "stop"
    elif model.stance and getattr(model.mechanism, "support", None) is not None:
        f_n, cone = stance_margins(model, x, friction)
        if f_n < 0 or cone < 0:  # the stance foot cannot hold from the start
            pressed = ("stance_lifts" if f_n < 0 else "stance_slips",)
            events.append(HybridEvent(time=t, kind="stop", state=x, anchor=anchor.copy(),
                                      flags=pressed))  # fmt: skip
            ended = "stop"
    start = None if held else _starting_strike(model, x, t)
    while not pressed:
        if held and start is None:  # the held rows' velocities to round-off
            x, lost = settle(model, held, x, friction)
            impacts += lost
        leg = start if start is not None else fly(model, x, t, duration, tolerance=tolerance,
                                                  held=held, friction=friction,
                                                  variational=linearize)  # fmt: skip
        start = None
        t, x = leg.t1, leg.x1
        if jac is not None and mono is not None and leg.phi is not None:
            jac, mono = leg.phi @ jac, leg.phi @ mono
        dampers += leg.damping
        sliding += leg.sliding
        if leg.ended == "end":
            break
        if leg.ended in ("release", "slip_start", "stick"):
            assert leg.guard is not None
            index = model.guards.index(leg.guard)
            prior = held
            held, kind, hold = _change_hold(model, held, index, x, leg.ended, friction, scale,
                                            retry=leg.from_rest)  # fmt: skip
            if jac is not None and mono is not None and kind != "turn":
                j = next(i for i, h in enumerate(prior) if h.index == index)
                salt_h, jump = hold_saltation(model, prior, held, leg.ended, j, x, friction)
                jac, mono = salt_h @ jac, salt_h @ mono
                jumps.append(jump)
            changes = changes + 1 if t - changed_at <= MIN_INTERVAL else 1
            changed_at = t
            if changes > MAX_CHANGES:  # no regime holds: a point that would neither stick
                kind = "stop"  # nor start to slide (the pair's forces are not unique)
            if kind == "stop":  # what the hold does next is not followed yet
                events.append(HybridEvent(time=t, kind="stop", state=x, anchor=anchor.copy(),
                                          flags=("contact_persists", leg.guard.name),
                                          held=held))  # fmt: skip
                ended = "stop"
                break
            # the holds after it settled here, not at the next leg's start: the event's state
            # is the one the flow goes on from (a slide's stop, found to the integrator's
            # tolerance, left a box's velocities at 1e-12 where its four corners stick)
            x, lost = settle(model, held, x, friction)
            impacts += lost
            event = _held_event(model, t, kind, x, anchor, leg.guard, hold, held)
            again = events and t - events[-1].time <= MIN_INTERVAL and (
                events[-1].kind, events[-1].flags) == (event.kind, event.flags)  # fmt: skip
            if kind != "turn" and not again:  # (a regime tried again at once: said once)
                events.append(event)
            continue
        if leg.ended == "singular":  # the held system's forces grew without bound
            names = tuple(model.guards[h.index].name for h in held)
            events.append(HybridEvent(time=t, kind="stop", state=x, anchor=anchor.copy(),
                                      flags=("held_singular", *names), held=held))  # fmt: skip
            ended = "stop"
            break
        if leg.ended == "drift":  # a held point left MuJoCo's list (flow.held_drift)
            assert leg.guard is not None
            events.append(HybridEvent(time=t, kind="stop", state=x, anchor=anchor.copy(),
                                      flags=("held_point_lost", leg.guard.name),
                                      held=held))  # fmt: skip
            ended = "stop"
            break
        if leg.ended == "fall":
            events.append(HybridEvent(time=t, kind="fall", state=x, anchor=anchor.copy()))
            ended = "fall"
            break
        if leg.ended in ("lift", "slip"):  # the stance foot would leave: not walking
            flag = "stance_lifts" if leg.ended == "lift" else "stance_slips"
            events.append(HybridEvent(time=t, kind="stop", state=x, anchor=anchor.copy(),
                                      flags=(flag,)))  # fmt: skip
            ended = "stop"
            break
        guard = leg.guard
        assert guard is not None
        index = model.guards.index(guard)
        holdable = guard.limit_row is not None or guard.rows is not None
        chatter = ((holdable or guard.problem is not None)
                   and t - last_on.get(index, -np.inf) < HOLD_INTERVAL)  # fmt: skip
        last_on[index] = t
        # a chatter against a stop or a plane: its strikes accumulate; the last one is
        # plastic, and the contact is held where it pushes
        law_now = Law(restitution=0.0, friction=friction, law=law.law) if chatter else law
        held_before = held
        s = strike(model, guard, x, law_now, tuple(model.guards[h.index] for h in held))
        struck += 1
        grazing = ("grazing",) if is_grazing(model, guard, x) else ()
        impacts += float(s.result.energy.dissipated)
        anchor = anchor + s.struck if guard.moves_anchor else anchor
        if s.flags:
            # not walking: the chart cannot hold the velocities after (a slipping or staying
            # foot), so the ledger's last energy is the floating one's, T(qf'+) + V, and the
            # state is the chart's least-squares reading of it
            final_energy = (model.energy(x, anchor - s.struck if guard.moves_anchor else anchor)
                            - model.kinetic(x) + float(s.result.energy.after))  # fmt: skip
            events.append(HybridEvent(time=t, kind="stop", state=s.x_after, anchor=anchor.copy(),
                                      strike=s, flags=s.flags + grazing))  # fmt: skip
            x, ended = s.x_after, "stop"
            break
        x = s.x_after
        events.append(HybridEvent(time=t, kind="impact", state=x, anchor=anchor.copy(),
                                  strike=s, saltation=None, flags=grazing,
                                  held=held))  # fmt: skip
        at = len(events) - 1  # (its saltation matrix once the holds after it are known)
        for k in [h.index for h in held]:  # each held contact: opened, or held anew
            others = tuple(h for h in held if h.index != k)
            g = model.guards[k]
            base: Hold | None = Hold(index=k)
            if _multi(g, x):  # a pair of geoms: held anew on the points closed at rest
                base = _closed_points(model, g, x, scale, k)
            elif float(g.gradient(x) @ model.mechanism.flow(x)) > AT_REST * max(
                    model.kinetic(x), scale) ** 0.5:  # fmt: skip
                base = None  # it opens
            hold = None if base is None else _new_hold(model, others, k, x, friction, scale, base)
            before = next(h for h in held if h.index == k)
            if hold is None:
                held = others
                events.append(_held_event(model, t, "contact_end", x, anchor, g, None, held))
            else:
                held = tuple(hold if h.index == k else h for h in held)
                if hold.points != before.points:  # a pair held on more (or fewer) points
                    events.append(_held_event(model, t, "contact_start", x, anchor, g, hold,
                                              held))  # fmt: skip
                elif (hold.slip == 0) != (before.slip == 0) or (
                        not hold.direction and hold.slip != before.slip):  # fmt: skip
                    events.append(_held_event(model, t, "stick" if hold.slip == 0 else "slip",
                                              x, anchor, g, hold, held))  # fmt: skip
        rate = abs(float(guard.gradient(x) @ model.mechanism.flow(x)))  # the gap's rate
        speed = max(model.kinetic(x), scale) ** 0.5
        base = Hold(index=index)
        if holdable and _multi(guard, x):  # a pair of geoms: held on its points closed at rest
            base = _closed_points(model, guard, x, scale, index)
            rate = 0.0 if base is not None else np.inf
        already = any(h.index == index for h in held)  # (a held pair's next point struck)
        resting = holdable and not already and (chatter or rate <= AT_REST * speed)
        hold = (_new_hold(model, held, index, x, friction, scale, base)
                if resting and base is not None else None)  # fmt: skip
        if hold is not None:
            held = (*held, hold)
            events.append(_held_event(model, t, "contact_start", x, anchor, guard, hold, held))
        # every other contact the strike leaves closed and at rest is held too: one that took
        # part in it (Unitree G1's foot landing flat on eight spheres, one of them struck)
        # would start the next leg on its surface, its gap a round-off below zero, where no
        # strike is found, and sink unstruck (4.5 cm in 0.07 s)
        for extra in starting_holds(model, x, friction, scale, held)[len(held):]:
            held = (*held, extra)
            events.append(_held_event(model, t, "contact_start", x, anchor,
                                      model.guards[extra.index], extra, held))  # fmt: skip
        linear = jac is not None and mono is not None
        if (linear or saltation) and not grazing:
            # the strike as applied (plastic where it closes a chatter), the contacts held
            # before it in its reset and their field before it, those held after in f+
            x_minus = s.x_before
            dr = reset_jacobian(model, guard, x_minus, law_now,
                                tuple(model.guards[h.index] for h in held_before))
            f_minus = held_field(model, held_before, x_minus, friction)
            grad = tangent_gradient(model, guard, x_minus)
            salt_s = jump_saltation(dr, f_minus, held_field(model, held, x, friction), grad)
            if saltation:
                events[at] = replace(events[at], saltation=salt_s)
            if linear and not chatter:
                assert jac is not None and mono is not None
                crossing = float(grad @ f_minus)
                jac = dr @ (eye - np.outer(f_minus, grad) / crossing) @ jac
                mono = salt_s @ mono
        if linear and (grazing or chatter):  # no saltation matrix, or a strike made plastic
            lin_flags.append("grazing" if grazing else "chatter")
            jac = mono = None
        if strikes is not None and struck >= strikes:
            ended = "strikes"
            break
        if hold is not None:
            last = t
            continue
        pressed = pressed_contacts(model, x, held, friction)
        if pressed:  # a contact that stays closed and that carnot cannot hold
            events.append(HybridEvent(time=t, kind="stop", state=x, anchor=anchor.copy(),
                                      flags=("contact_persists", *pressed)))  # fmt: skip
            ended = "stop"
            break
        if t - last < MIN_INTERVAL or model.kinetic(x) < REST * scale:
            # what is left is what the rest of the accumulating strikes take
            impacts += model.kinetic(x)
            x = np.concatenate([x[: model.nq], np.zeros(model.n)])
            events.append(HybridEvent(time=t, kind="rest", state=x, anchor=anchor.copy()))
            t, ended = max(t, duration), "rest"
            break
        if len(events) >= MAX_STRIKES:
            ended = "max_strikes"
            break
        last = t
    final = model.energy(x, anchor) if final_energy is None else final_energy
    energy = {"initial": initial, "final": final, "impacts": impacts, "dampers": dampers,
              "sliding": sliding, "residual": initial - impacts - dampers - sliding - final}
    return HybridRun(model=model, law=law, events=tuple(events), final=x, time=t,
                     anchor=anchor, energy=energy, ended=ended,
                     start=np.array(x0, dtype=float), jacobian=jac, monodromy=mono,
                     flags=tuple(dict.fromkeys(lin_flags)), jumps=tuple(jumps))  # fmt: skip

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
time to one just after. A strike where ``D_x G f-`` vanishes (the guard met tangentially) is
*grazing*: no saltation matrix exists there, and it is flagged.

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

A contact between two bodies from MJCF (a guard with its own ``problem``, and no ``rows``)
chatters the same way; its chatter is closed by a plastic strike too. carnot does not yet
hold such a contact in the flow: a contact that is closed (``|G| <= TOUCH``,
``|G'| <= AT_REST`` of the speed scale) and pressed by the flow, ``G'' < 0``, ends the run
with a ``stop`` event flagged ``contact_persists`` (at the start too). ``G''`` is the second
difference of ``G`` along the flow,
``(G(x + tau f + tau^2/2 f') + G(x - tau f + tau^2/2 f') - 2 G(x)) / tau^2``, with
``f' = D_x f f`` by central differences of the flow (``tau = PRESS_STEP``).

A sequence of strikes closer than ``MIN_INTERVAL`` (s) in time, or a kinetic energy after a
strike below ``REST`` of the run's energy scale, ends the run at ``rest``: a rimless wheel
rocking to a stop on two spokes strikes infinitely often in a finite time, and the strikes
still to come take what kinetic energy is left, which the ledger counts with the impacts; the
model then stays at rest until the duration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from carnot.hybrid.flow import TOLERANCE, Hold, Leg, fly, gap_rows, held_flow, stance_margins
from carnot.hybrid.model import Guard, HybridModel, Law, require_velocity_chart
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
    in the chart whose origin is ``anchor`` (m); ``held``: the contacts held in the flow
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
    ``residual`` (initial - impacts - final, J), all in J; ``start`` the initial state."""

    model: HybridModel
    law: Law
    events: tuple[HybridEvent, ...]
    final: np.ndarray
    time: float
    anchor: np.ndarray
    energy: dict[str, float]
    ended: str
    start: np.ndarray


def saltation_matrix(model: HybridModel, guard: Guard, s: Strike, law: Law, *,
                     reset: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """``S = D_x R + (f+ - D_x R f-) (D_x G) / (D_x G f-)`` at the strike ``s`` (refused
    where ``nq != n``: :func:`carnot.hybrid.model.require_velocity_chart`); ``reset``: the
    strike's ``D_x R`` (:func:`carnot.hybrid.strike.reset_jacobian`) where the caller has
    made it already (its 4n strikes are most of the matrix's cost)."""
    require_velocity_chart(model, "saltation matrices")
    mech = model.mechanism
    f_minus = mech.flow(s.x_before)
    f_plus = mech.flow(s.x_after)
    dr = reset_jacobian(model, guard, s.x_before, law) if reset is None else reset
    grad = guard.gradient(s.x_before)
    return dr + np.outer(f_plus - dr @ f_minus, grad) / float(grad @ f_minus)


def is_grazing(model: HybridModel, guard: Guard, x: np.ndarray) -> bool:
    """Whether the guard is met tangentially at ``x``: ``|D_x G f| <= GRAZING |D_x G| |f|``."""
    f = model.mechanism.flow(x)
    grad = guard.gradient(x)
    return abs(float(grad @ f)) <= GRAZING * float(np.linalg.norm(grad) * np.linalg.norm(f))


def pressed_contacts(model: HybridModel, x: np.ndarray, held: tuple[Hold, ...] = (),
                     friction: float | None = None) -> tuple[str, ...]:  # fmt: skip
    """The contacts (guards with their own ``problem``) that are closed at ``x`` and pressed
    by the flow (module docstring), by name."""
    contacts = [g for g in model.guards if g.problem is not None]
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
        if abs(gap) > TOUCH or abs(float(g.gradient(x) @ f)) > AT_REST * max(speed, 1.0):
            continue
        if (g.function(ahead) + g.function(behind) - 2 * gap) / tau**2 < 0:
            out.append(g.name)
    return tuple(out)


def _starting_strike(model: HybridModel, x: np.ndarray, t: float) -> Leg | None:
    """A contact (a guard with its own ``problem``) closed at the start (``|G| <= TOUCH``)
    and approaching strikes at once: the flow would not see it fall through zero."""
    f = model.mechanism.flow(x)
    for g in model.guards:
        if (g.problem is not None or g.rows is not None) and abs(g.function(x)) <= TOUCH:
            if g.direction * float(g.gradient(x) @ f) > 0:
                return Leg(t0=t, t1=t, x1=np.array(x), phi=None, ended=g.name, guard=g,
                           evaluations=0)  # fmt: skip
    return None


def _closed(model: HybridModel, guard: Guard, x: np.ndarray, scale: float) -> bool:
    """Whether the guard's contact is closed at ``x`` and at rest there: ``|G| <= TOUCH``,
    ``|G'| <= AT_REST`` of the speed scale ``sqrt(scale)``."""
    rate = float(guard.gradient(x) @ model.mechanism.flow(x))
    speed = max(model.kinetic(x), scale) ** 0.5
    return abs(guard.function(x)) <= TOUCH and abs(rate) <= AT_REST * speed


def _new_hold(model: HybridModel, held: tuple[Hold, ...], index: int, x: np.ndarray,
              friction: float | None, scale: float) -> Hold | None:  # fmt: skip
    """How the guard ``index``, closed and at rest at ``x``, is held, or ``None`` where the
    flow would pull it off: sliding along its tangent's velocity where it has one (with
    friction), else sticking while ``|F_t| <= mu F_n``, else sliding where the sticking force
    points against (``s = -sign F_t``)."""
    rows = gap_rows(model, model.guards[index], x)
    speed = max(model.kinetic(x), scale) ** 0.5
    v_t = 0.0 if rows.tangent is None else float(rows.tangent @ x[model.n :])
    slides = friction is not None and rows.tangent is not None
    if slides and abs(v_t) > AT_REST * speed:
        hold = Hold(index=index, slip=1 if v_t > 0 else -1)
    else:
        hold = _stick_or_slip(model, held, index, x, friction)
    force = held_flow(model, (*held, hold), x, friction)[1][-1]
    return hold if force[0] > 0 else None


def _stick_or_slip(model: HybridModel, held: tuple[Hold, ...], index: int, x: np.ndarray,
                   friction: float | None) -> Hold:  # fmt: skip
    """A contact at rest in its slide: it sticks where the force that holds it is inside the
    cone, ``|F_t| <= mu F_n``, and slides against that force otherwise."""
    stick = Hold(index=index)
    if friction is None or gap_rows(model, model.guards[index], x).tangent is None:
        return stick
    f_n, f_t = held_flow(model, (*held, stick), x, friction)[1][-1]
    return stick if abs(f_t) <= friction * f_n else Hold(index=index, slip=-1 if f_t > 0 else 1)


def _change_hold(model: HybridModel, held: tuple[Hold, ...], index: int, x: np.ndarray,
                 why: str, friction: float | None
                 ) -> tuple[tuple[Hold, ...], str, Hold | None]:  # fmt: skip
    """The holds after a hold's event ``why`` at ``x``, the event's kind and the new hold:
    ``release`` (``contact_end``), ``slip_start`` (``slip``: sliding against the sticking
    force), ``stick`` (the slide stopped: ``stick`` where the cone holds it, else ``slip``
    the other way, or ``contact_end`` where nothing presses it)."""
    others = tuple(h for h in held if h.index != index)
    if why == "release":
        return others, "contact_end", None
    if why == "slip_start":
        f_t = held_flow(model, held, x, friction)[1][[h.index for h in held].index(index)][1]
        hold = Hold(index=index, slip=-1 if f_t > 0 else 1)
    else:
        hold = _stick_or_slip(model, others, index, x, friction)
    if held_flow(model, (*others, hold), x, friction)[1][-1][0] <= 0:
        return others, "contact_end", None
    return (*others, hold), ("stick" if hold.slip == 0 else "slip"), hold


def _held_event(model: HybridModel, t: float, kind: str, x: np.ndarray, anchor: np.ndarray,
                guard: Guard, hold: Hold | None, held: tuple[Hold, ...]
                ) -> HybridEvent:  # fmt: skip
    """A held contact's event, flagged with the guard and, where it can slide, how it is held
    (``sticking``, or ``sliding`` towards ``+t`` or ``-t``)."""
    how: tuple[str, ...] = ()
    if hold is not None and gap_rows(model, guard, x).tangent is not None:
        how = (("sliding", "+t" if hold.slip > 0 else "-t") if hold.slip else ("sticking",))
    return HybridEvent(time=t, kind=kind, state=np.array(x), anchor=anchor.copy(),
                       flags=(guard.name, *how), held=held)  # fmt: skip


def simulate(model: HybridModel, x0: np.ndarray, duration: float, law: Law = PLASTIC, *,
             saltation: bool = False, tolerance: float = TOLERANCE) -> HybridRun:  # fmt: skip
    """Run ``model`` from the state ``x0`` (chart coordinates, the origin at the stance point)
    for ``duration`` (s).

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> run = simulate(wheel, np.array([0.08 - np.pi / 8, 1.0]), 2.0)
    >>> run.ended, [e.kind for e in run.events], abs(run.energy["residual"]) < 1e-9
    ('duration', ['impact'], True)
    """
    x = np.array(x0, dtype=float)
    if x.shape != (model.nq + model.n,):
        raise ValueError(f"the state must have {model.nq + model.n} entries")
    if saltation:
        require_velocity_chart(model, "saltation matrices")
    anchor = np.zeros(2)
    t = 0.0
    initial = model.energy(x, anchor)
    scale = max(abs(initial), model.kinetic(x), 1e-300)
    impacts = dampers = sliding = 0.0
    events: list[HybridEvent] = []
    ended = "duration"
    last = -np.inf
    held: tuple[Hold, ...] = ()
    last_on: dict[int, float] = {}  # each guard's last strike (s)
    final_energy: float | None = None
    friction = law.friction
    for k, g in enumerate(model.guards):  # a point resting on its plane at the start is held
        if g.rows is not None and _closed(model, g, x, scale):
            hold = _new_hold(model, held, k, x, friction, scale)
            if hold is not None:
                held = (*held, hold)
                events.append(_held_event(model, t, "contact_start", x, anchor, g, hold, held))
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
        leg = start if start is not None else fly(model, x, t, duration, tolerance=tolerance,
                                                  held=held, friction=friction)  # fmt: skip
        start = None
        t, x = leg.t1, leg.x1
        dampers += leg.damping
        sliding += leg.sliding
        if leg.ended == "end":
            break
        if leg.ended in ("release", "slip_start", "stick"):
            assert leg.guard is not None
            index = model.guards.index(leg.guard)
            held, kind, hold = _change_hold(model, held, index, x, leg.ended, friction)
            events.append(_held_event(model, t, kind, x, anchor, leg.guard, hold, held))
            continue
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
        s = strike(model, guard, x, Law(restitution=0.0, friction=friction, law=law.law)
                   if chatter else law, tuple(model.guards[h.index] for h in held))  # fmt: skip
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
        salt = None
        if saltation and not grazing and not held:  # (the free flow's, on both sides)
            salt = saltation_matrix(model, guard, s, law)
        x = s.x_after
        events.append(HybridEvent(time=t, kind="impact", state=x, anchor=anchor.copy(),
                                  strike=s, saltation=salt, flags=grazing,
                                  held=held))  # fmt: skip
        for k in [h.index for h in held]:  # each held contact: opened, or held anew
            others = tuple(h for h in held if h.index != k)
            g = model.guards[k]
            opens = float(g.gradient(x) @ model.mechanism.flow(x)) > AT_REST * max(
                model.kinetic(x), scale) ** 0.5  # fmt: skip
            hold = None if opens else _new_hold(model, others, k, x, friction, scale)
            before = next(h for h in held if h.index == k)
            if hold is None:
                held = others
                events.append(_held_event(model, t, "contact_end", x, anchor, g, None, held))
            else:
                held = tuple(hold if h.index == k else h for h in held)
                if hold != before:
                    events.append(_held_event(model, t, "stick" if hold.slip == 0 else "slip",
                                              x, anchor, g, hold, held))  # fmt: skip
        rate = abs(float(guard.gradient(x) @ model.mechanism.flow(x)))  # the gap's rate
        speed = max(model.kinetic(x), scale) ** 0.5
        resting = holdable and (chatter or rate <= AT_REST * speed)
        hold = _new_hold(model, held, index, x, friction, scale) if resting else None
        if hold is not None:
            held = (*held, hold)
            events.append(_held_event(model, t, "contact_start", x, anchor, guard, hold, held))
            last = t
            continue
        pressed = pressed_contacts(model, x, held, friction)
        if pressed:  # a contact that stays closed: not held in the flow (yet)
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
                     start=np.array(x0, dtype=float))  # fmt: skip

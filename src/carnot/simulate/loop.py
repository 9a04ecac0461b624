"""The event-driven loop: free flight, impacts, persistent contacts, Zeno, to the end.

At each instant the features are classified by gap and normal velocity (tolerances ``eps``, a
billionth of the scene's size, and ``eps_v``, 1e-8 of its speed scale ``sqrt(|g| L)``):
approaching ones are an impact (impacts.py), closed ones (touching, normal velocity ~0) take
part in the persistent-contact problem (contacts.py), and with none of them every body flies
(motion.py, events.py). A body at rest on its contacts with nothing that changes in time (no
ground motion left) rests to the end (a ``rest`` event). ``max_events`` bounds the number of
events so that nothing runs forever (a scenario that needs more is refused, naming the key).

The energy ledger (J) is kept in the ground's frame (ground.py; the world frame without ground
motion): ``initial + ground_work - impacts - sliding = final``, where ``impacts`` sums ``E_d``
of every impact (the solver's direct difference; its theorem route is in each event) and of
every Zeno series, ``sliding`` the work of sliding friction and ``ground_work`` the ground's.
Flight is exact, so the ledger closes to round-off there; contact phases are integrated, so it
closes to the integrator's tolerance there: the remainder is reported as ``residual``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.simulate.contacts import (
    Active,
    Scene,
    SimulationError,
    integrate,
    select_modes,
    solve_body,
)
from carnot.simulate.events import (
    Feature,
    corner_groups,
    features,
    gaps_and_speeds,
    geometry,
    next_contact,
    trigger_levels,
)
from carnot.simulate.ground import Ground
from carnot.simulate.impacts import (
    Event,
    Impact,
    PairLaw,
    feature_names,
    settle_at,
    solve_at,
)
from carnot.simulate.lean import LoopState, advance, lean_scene
from carnot.simulate.motion import (
    NUMERIC_HORIZON,
    BodyState,
    Flight,
    SimBody,
    kinetic_energy,
    potential_energy,
)
from carnot.simulate.shapes import Plane, Sphere
from carnot.simulate.zeno import (
    BounceMotion,
    BounceRecord,
    RockRecord,
    bounce,
    detect_rocking,
)

#: Default and largest ``simulation.max_events``.
DEFAULT_MAX_EVENTS = 10_000
MAX_EVENTS_LIMIT = 10_000_000
#: Impacts allowed at one instant (a chain of pairwise impacts at the same time).
MAX_IMPACTS_PER_INSTANT = 50


@dataclass(frozen=True, kw_only=True, eq=False)
class Simulation:
    """A simulation scenario: movable bodies with their initial states, fixed planes (and
    their names), gravity (m/s^2), ground motion, duration (s), the pair law of each
    feature, the event limit and the trajectory sampling step (s)."""

    title: str
    bodies: list[SimBody]
    initial: list[BodyState]
    planes: list[Plane]
    plane_names: list[str]
    gravity: np.ndarray
    ground: Ground | None
    duration: float
    law_of: Callable[[Feature], PairLaw]
    max_events: int = DEFAULT_MAX_EVENTS
    sample_step: float | None = None


@dataclass(frozen=True, kw_only=True, eq=False)
class Ledger:
    """Energies (J), see the module docstring."""

    initial: float
    final: float
    impacts: float
    sliding: float
    ground_work: float

    @property
    def residual(self) -> float:
        return self.initial + self.ground_work - self.impacts - self.sliding - self.final


@dataclass(kw_only=True, eq=False)
class Samples:
    """Sampled motion: times (s), per body states, and the running ledger at each sample."""

    times: list[float] = field(default_factory=list)
    states: list[list[BodyState]] = field(default_factory=list)
    impacts: list[float] = field(default_factory=list)
    sliding: list[float] = field(default_factory=list)
    ground_work: list[float] = field(default_factory=list)


@dataclass(frozen=True, kw_only=True, eq=False)
class SimulationResult:
    """Events, final states, the ledger and (when asked) the sampled motion."""

    simulation: Simulation
    events: list[Event]
    final: list[BodyState]
    energy: Ledger
    samples: Samples | None


def mechanical_energy(sim: Simulation, states: list[BodyState]) -> float:
    """Kinetic plus gravitational potential energy of every movable body (J)."""
    return sum(kinetic_energy(b, s) + potential_energy(b, s, sim.gravity)
               for b, s in zip(sim.bodies, states, strict=True))  # fmt: skip


def scales(sim: Simulation) -> tuple[float, float]:
    """``(eps, eps_v)``: gap (m) and velocity (m/s) tolerances from the scene's size and
    gravity."""
    size = max(max(b.shape.size for b in sim.bodies), 1e-6)
    speed = max(float(np.sqrt(np.linalg.norm(sim.gravity) * size)),
                max(float(np.linalg.norm(s.velocity)) + size * float(np.linalg.norm(
                    s.angular_velocity)) for s in sim.initial), 1e-6)  # fmt: skip
    eps = 1e-9 * size
    # a rebound slower than sqrt(2 g eps) cannot lift the contact by eps: below twice that it
    # is no flight but a closed contact (else round-off bounces would chatter for ever)
    return eps, max(1e-8 * speed, 2 * float(np.sqrt(2 * np.linalg.norm(sim.gravity) * eps)))


def run(sim: Simulation, *, record: bool = False, progress: Any = None) -> SimulationResult:
    """Simulate ``sim`` from 0 to its duration (module docstring); ``record`` samples the
    motion every ``sample_step`` (for plots, animations and trajectories); ``progress`` is
    called with the current time (s)."""
    feats = features(sim.bodies, sim.planes)
    groups = corner_groups(feats, sim.bodies)
    eps, eps_v = scales(sim)
    scene = Scene(bodies=sim.bodies, planes=sim.planes, gravity=sim.gravity, ground=sim.ground,
                  friction=lambda f: sim.law_of(f).friction)  # fmt: skip
    states = list(sim.initial)
    t = 0.0
    events: list[Event] = []
    impacts = sliding = ground_work = 0.0
    bounces: list[BounceRecord] = []
    flight_since_impact = True
    active_prev: list[Active] = []
    same_instant = stalled = 0
    at_cone: frozenset[Feature] = frozenset()  # contacts whose sticking just left the cone
    rocks: list[RockRecord] = []  # a rocking block's impacts (zeno.detect_rocking)
    pivoting = False  # only pivoting on one sticking corner since the last impact
    samples = Samples() if record else None
    step = sim.sample_step or sim.duration / 500

    def sample(time: float, st: list[BodyState], slid: float = 0.0, worked: float = 0.0
               ) -> None:  # fmt: skip
        if samples is not None:
            samples.times.append(time)
            samples.states.append(list(st))
            samples.impacts.append(impacts)
            samples.sliding.append(sliding + slid)
            samples.ground_work.append(ground_work + worked)

    sample(0.0, states)
    initial = mechanical_energy(sim, states)
    # flights and single impacts of one body on planes, by the lean loop (lean.py) while they
    # last; the general steps below take whatever else comes, and hand back after it
    lean = lean_scene(sim) if samples is None else None
    while t < sim.duration:
        if lean is not None and not active_prev:
            at = LoopState(t=t, state=states[0], impacts=impacts, flight=flight_since_impact,
                           same_instant=same_instant, stalled=stalled, pivoting=pivoting)
            advance(lean, at, events, bounces, eps, eps_v, MAX_IMPACTS_PER_INSTANT, progress)
            t, states, impacts = at.t, [at.state], at.impacts
            flight_since_impact, same_instant = at.flight, at.same_instant
            stalled, pivoting = at.stalled, at.pivoting
            if t >= sim.duration:
                break
        if len(events) >= sim.max_events:
            raise InputError(
                "simulation.max_events",
                f"reached at t = {t:.9g} s of {sim.duration:g} s (raise it, at most "
                f"{MAX_EVENTS_LIMIT}, or shorten the duration)",
                sim.max_events,
            )
        if progress is not None:
            progress(t)
        gaps, speeds = gaps_and_speeds(feats, sim.bodies, sim.planes, states, groups)
        touching = [f for f in feats if gaps[f] <= eps]
        approaching = [f for f in touching if speeds[f] < -eps_v]
        if approaching:
            same_instant += 1
            if same_instant > MAX_IMPACTS_PER_INSTANT:
                raise SimulationError(f"more than {MAX_IMPACTS_PER_INSTANT} impacts at "
                                      f"t = {t:.12g} s")  # fmt: skip
            closed = [f for f in touching
                      if f not in approaching and abs(speeds[f]) <= eps_v]
            hit = solve_at(t, sim.bodies, sim.planes, sim.plane_names, states, approaching,
                           closed, sim.law_of, eps_v)  # fmt: skip
            e_d = hit.result.energy.dissipated
            impacts += e_d
            states = hit.states
            names = [feature_names(f, sim.bodies, sim.plane_names) for f in approaching]
            events.append(Event(time=t, kind="impact", contacts=names, impact=hit))
            sample(t, states)
            zeno = _zeno(sim, hit, bounces, flight_since_impact, states)
            if zeno is None:
                zeno = _rocking(sim, t, hit, rocks, pivoting, states)
            flight_since_impact = False
            pivoting = True
            if zeno is not None and zeno.time < sim.duration:
                i = approaching[0].body
                before = mechanical_energy(sim, states)
                states = [zeno.state if k == i else s for k, s in enumerate(states)]
                if len(sim.bodies) > 1:  # the others fly on to t_inf
                    states = _fly_others(sim, t, zeno.time - t, states, i)
                series = before - mechanical_energy(sim, states)
                impacts += series
                t = zeno.time
                bounces.clear()
                rocks.clear()
                events.append(Event(time=t, kind="accumulation", contacts=names[:1], energy={
                    "dissipated": series, "dissipated_theorem": zeno.dissipated_theorem,
                    "ratio": zeno.ratio, "series_start": zeno.start}))  # fmt: skip
                sample(t, states)
            continue
        same_instant = 0
        closed = [f for f in touching if abs(speeds[f]) <= eps_v]
        active = select_modes(scene, t, states, closed, eps_v, at_cone) if closed else []
        at_cone = frozenset()
        unsettled = _unsettled(sim, states, active, eps_v)
        if unsettled:
            rocks.clear()
            settle = settle_at(t, sim.bodies, sim.planes, sim.plane_names, states, unsettled,
                               sim.law_of)  # fmt: skip
            impacts += settle.result.energy.dissipated
            states = settle.states
            names = [feature_names(c.feature, sim.bodies, sim.plane_names) for c in unsettled]
            events.append(Event(time=t, kind="accumulation", contacts=names, impact=settle))
            sample(t, states)
            continue
        _contact_events(sim, t, active_prev, active, events)
        active_prev = active
        if active:
            if _at_rest(sim, scene, t, states, active, eps_v):
                events.append(Event(time=t, kind="rest", contacts=[
                    feature_names(c.feature, sim.bodies, sim.plane_names) for c in active]))
                t = sim.duration
                sample(t, states)
                break
            if len(active) != 1 or active[0].mode != "stick":
                pivoting = False
            on = {c.feature for c in active}
            free = [f for f in feats if f not in on]
            levels = trigger_levels({f: gaps[f] for f in free}, eps)
            until = sim.duration
            if sim.ground is not None and t < sim.ground.end:
                until = min(until, sim.ground.end)  # small steps only there
            phase = integrate(scene, t, until, states, active, free, levels, eps,
                              step if samples is not None else None)  # fmt: skip
            if samples is not None:
                ts, ys = phase.samples
                for k in range(1, len(ts)):
                    if ts[k] >= phase.time:
                        break
                    sample(float(ts[k]), [BodyState.from_array(ys[13 * i: 13 * i + 13, k])
                                          for i in range(len(sim.bodies))],
                           float(ys[-2, k]), float(ys[-1, k]))  # fmt: skip
            sliding += phase.sliding
            ground_work += phase.ground_work
            t, states = phase.time, phase.states
            sample(t, states)
            flight_since_impact = False
            if phase.reason in ("slip", "stick") and phase.feature is not None:
                events.append(Event(time=t, kind=phase.reason, contacts=[
                    feature_names(phase.feature, sim.bodies, sim.plane_names)]))
                pivoting = False
                if phase.reason == "slip":
                    at_cone = frozenset(c.feature for c in active
                                        if c.feature.body == phase.feature.body)
            continue
        # free flight of every body
        pivoting = False
        flights = [Flight(b, t, s, sim.gravity, sim.ground, sim.duration - t)
                   for b, s in zip(sim.bodies, states, strict=True)]  # fmt: skip
        horizon = min(f.horizon for f in flights)
        levels = trigger_levels(gaps, eps)
        hit_s = next_contact(flights, sim.bodies, sim.planes, feats, horizon, levels, eps,
                             groups)  # fmt: skip
        if hit_s is not None and hit_s <= 0.0:
            stalled += 1
            if stalled > MAX_IMPACTS_PER_INSTANT:
                raise SimulationError(f"no progress at t = {t:.12g} s (a contact found again "
                                      "and again at the same instant)")  # fmt: skip
        else:
            stalled = 0
        s_end = horizon if hit_s is None else hit_s
        if samples is not None:
            for s in np.arange(step - (t % step), s_end, step):
                worked = 0.0 if sim.ground is None else sum(
                    sim.ground.work_in_flight(b.mass, t, t + float(s), st.velocity, sim.gravity)
                    for b, st in zip(sim.bodies, states, strict=True))  # fmt: skip
                sample(t + float(s), [f.state(float(s)) for f in flights], 0.0, worked)
        if sim.ground is not None:
            ground_work += sum(sim.ground.work_in_flight(b.mass, t, t + s_end, s.velocity,
                                                         sim.gravity)
                               for b, s in zip(sim.bodies, states, strict=True))  # fmt: skip
        states = [f.state(s_end) for f in flights]
        t = sim.duration if hit_s is None and s_end >= sim.duration - t else t + s_end
        sample(t, states)
        flight_since_impact = True
    final = mechanical_energy(sim, states)
    ledger = Ledger(initial=initial, final=final, impacts=impacts, sliding=sliding,
                    ground_work=ground_work)  # fmt: skip
    return SimulationResult(simulation=sim, events=events, final=states, energy=ledger,
                            samples=samples)  # fmt: skip


def _minus(a: Any, b: Any) -> list[float]:
    """``a - b`` of two 3-vectors, as Python floats."""
    return [x - y for x, y in zip(np.asarray(a).tolist(), np.asarray(b).tolist(), strict=True)]


def _zeno(sim: Simulation, hit: Impact, bounces: list[BounceRecord], flight: bool,
          states: list[BodyState]) -> Any:  # fmt: skip
    if len(hit.features) != 1 or hit.features[0].other >= 0:
        bounces.clear()
        return None
    f = hit.features[0]
    body = sim.bodies[f.body]

    def motion() -> BounceMotion:
        # on Python floats: a handful of 3-vectors, where NumPy's per-call cost dominates
        c = hit.result.contacts[0]
        moved = hit.result.bodies[body.name]
        return (_minus(moved.velocity_after, moved.velocity_before),
                _minus(moved.angular_velocity_after, moved.angular_velocity_before),
                np.asarray(c.normal).tolist(), np.asarray(c.relative_velocity_before).tolist(),
                np.asarray(c.relative_velocity_after).tolist(), c.normal_impulse or 0.0)

    return bounce(bounces, time=hit.time, feature=f, sphere=isinstance(body.shape, Sphere),
                  size=body.shape.size, spin=states[f.body].angular_velocity.tolist(),
                  state=lambda: states[f.body], motion=motion, flight=flight,
                  gravity=sim.gravity, ground=sim.ground is not None)  # fmt: skip


def _rocking(sim: Simulation, t: float, hit: Impact, rocks: list[RockRecord], pivoting: bool,
             states: list[BodyState]) -> Any:  # fmt: skip
    """A rocking block's impacts summed (zeno.detect_rocking), or None: one lamina struck on
    one corner, no ground motion left."""
    if len(hit.features) != 1 or hit.features[0].other >= 0 or hit.features[0].vertex < 0 or (
            sim.ground is not None and t <= sim.ground.end):  # fmt: skip
        rocks.clear()
        return None
    f = hit.features[0]
    body = sim.bodies[f.body]
    if body.plane_normal_body is None:
        rocks.clear()
        return None
    s = states[f.body]
    normal = s.rotation @ body.plane_normal_body
    motion = hit.result.bodies[body.name]
    before = float(np.asarray(motion.angular_velocity_before) @ normal)
    after = float(np.asarray(motion.angular_velocity_after) @ normal)
    if rocks and rocks[-1].feature.body != f.body:
        rocks.clear()
    rocks.append(RockRecord(time=t, feature=f, ratio=after / before if before else 0.0,
                            pivoting=pivoting))  # fmt: skip
    del rocks[:-3]
    if len(rocks) < 3:
        return None
    other = rocks[-2].feature
    energy = hit.result.energy
    return detect_rocking(
        rocks, body.mass, body.inertia_world(s.rotation), normal, s,
        geometry(f, sim.bodies, sim.planes, states).point,
        geometry(other, sim.bodies, sim.planes, states).point, sim.gravity,
        kinetic=energy.after, theorem_fraction=energy.dissipated_theorem / energy.before)


def _fly_others(sim: Simulation, t: float, span: float, states: list[BodyState], skip: int
                ) -> list[BodyState]:  # fmt: skip
    out = list(states)
    for k, (b, s) in enumerate(zip(sim.bodies, states, strict=True)):
        if k != skip:
            out[k] = Flight(b, t, s, sim.gravity, sim.ground).state(span)
    return out


def _unsettled(sim: Simulation, states: list[BodyState], active: list[Active], eps_v: float
               ) -> list[Active]:  # fmt: skip
    """The active contacts of a body whose relative velocity there is not zero though below
    the tolerance (they are closed) but above 1e-6 of it: the remaining motion of a body
    settling, a rocking block's or a ball's last bounces (impacts.settle_at). Left alone, a
    normal velocity ``w_n`` under a held contact would let its force ``lambda_n`` work at
    ``lambda_n w_n``; the round-off of a plastic impact (about 1e-11 m/s) stays below."""
    out: list[Active] = []
    if not active:
        return out
    for i in range(len(sim.bodies)):
        mine = [c for c in active if c.feature.body == i]
        if not mine:
            continue
        speeds = []
        for c in mine:
            g = geometry(c.feature, sim.bodies, sim.planes, states)
            w = g.relative_velocity if c.mode == "stick" else g.normal_velocity * g.normal
            speeds.append(float(np.linalg.norm(w)))
        if max(speeds) > 1e-6 * eps_v:
            out.extend(mine)
    return out


def _at_rest(sim: Simulation, scene: Scene, t: float, states: list[BodyState],
             active: list[Active], eps_v: float) -> bool:  # fmt: skip
    if sim.ground is not None and t <= sim.ground.end:
        return False
    size = max(b.shape.size for b in sim.bodies)
    g = float(np.linalg.norm(sim.gravity))
    for i, s in enumerate(states):
        if float(np.linalg.norm(s.velocity)) + size * float(np.linalg.norm(
                s.angular_velocity)) > eps_v:  # fmt: skip
            return False
        mine = [c for c in active if c.feature.body == i]
        u, _ = solve_body(scene, i, t, s, mine)
        if float(np.linalg.norm(u[:3])) + size * float(np.linalg.norm(u[3:])) > 1e-9 * g:
            return False
    return True


def _contact_events(sim: Simulation, t: float, before: list[Active], after: list[Active],
                    events: list[Event]) -> None:  # fmt: skip
    if not before and not after:  # flight to flight: nothing started or ended
        return
    old = {c.feature for c in before}
    new = {c.feature for c in after}
    started = [f for f in new if f not in old]
    ended = [f for f in old if f not in new]
    if ended:
        events.append(Event(time=t, kind="contact_end", contacts=[
            feature_names(f, sim.bodies, sim.plane_names) for f in ended]))
    if started:
        events.append(Event(time=t, kind="contact_start", contacts=[
            feature_names(f, sim.bodies, sim.plane_names) for f in started]))


__all__ = ["NUMERIC_HORIZON", "Event", "Ledger", "Simulation", "SimulationResult", "run"]

"""The lean event loop: one body flying over planes and striking them one point at a time.

Most events of a bouncing ball or a tumbling die are the same two steps: a flight in closed
form to the next impact, and an impact of one point on one plane. :func:`advance` runs those
steps for a scene of one movable body (a sphere, or a convex body with equal principal moments,
``J = c I``: a cube) over fixed planes, without ground motion, every plane's law frictionless or
sticking (:func:`carnot.single.short_path`'s rules), as long as nothing else happens; it stops,
leaving everything as it was at the start of that step, at the first step that needs more (two
points struck at once, a closed contact, a body that does not turn, a division by zero in the
solver's arithmetic, a non-finite state, the event limit), which the general loop
(:func:`carnot.simulate.loop.run`) then takes, calling this again after it.

It is the general loop's own arithmetic, not a second implementation: the same gaps (the
corners' :func:`carnot.simulate.corners.corner_kinematics`, :func:`carnot.simulate.events.
sphere_gap_speed`), the same next impact (:func:`carnot.simulate.corners.first_corner_impact`,
:func:`carnot.simulate.events.quadratic_first_down_root`), the same flight
(:func:`carnot.simulate.motion.flight_floats`), the same contact point
(:func:`carnot.simulate.events.on_plane`), the same Zeno test (:func:`carnot.simulate.zeno.
bounce`), and each impact solved by the solver of ``carnot solve``'s short path for one point
contact (:func:`carnot.single.single_floats`, which :func:`carnot.solve_impact` runs for such an
impact; called as :func:`carnot.single.factored_floats`, with the body's inertia factors
kept), on the floats of the body and contact validated once (:func:`carnot.simulate.impacts.
body_template`, :func:`carnot.simulate.impacts.plane_contact_template`). What it leaves out is the
per-event cost of the general route: dictionaries of features, a :class:`carnot.ImpactProblem`
built and dispatched at every impact, NumPy calls on 3-vectors. Each impact's full
:class:`carnot.ImpactResult` (impulses, ``E_d`` by the theorem and by the direct difference,
flags) is built from the solver's numbers when first read (:class:`carnot.simulate.impacts.
Impact`), by :func:`carnot.single.plane_result` (:func:`carnot.single.single_result`'s
assembly) from the parts of the problem the general loop would have built (:func:`carnot.
simulate.impacts.plane_problem`), which is built itself only if the momentum check is read;
``E_d`` enters the ledger at once.

The events, states and ledger are the general loop's, bit for bit (``tests/test_simulate_lean.py``
runs both; :data:`LEAN` False turns this loop off).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.laws import contact_rule
from carnot.model import PointContact
from carnot.result import ImpactResult
from carnot.simulate import events as _events
from carnot.simulate.events import (
    Feature,
    features,
    on_plane,
    quadratic_first_down_root,
    sphere_gap_speed,
    sphere_quadratic,
    sphere_tip,
)
from carnot.simulate.impacts import (
    Event,
    Impact,
    PairLaw,
    body_template,
    contact_at,
    fixed_body,
    impact_title,
    plane_contact_template,
    plane_problem,
)
from carnot.simulate.motion import (
    BodyState,
    SimBody,
    flight_floats,
    kinetic_energy,
    potential_energy,
    spin_rate,
)
from carnot.simulate.shapes import Sphere
from carnot.simulate.zeno import BounceMotion, BounceRecord, bounce
from carnot.single import (
    REST,
    UNIT_INERTIA,
    factored_floats,
    inertia_factor,
    plane_result,
    point_velocity,
)

#: The lean loop runs where it applies (False: the general loop only, the tests' second route
#: and the benchmark's in-run baseline).
LEAN = True


@dataclass(frozen=True, kw_only=True, eq=False)
class LeanPlane:
    """A fixed plane as the lean loop reads it: its index, normal and point (floats and
    arrays), the body's features on it (in :func:`carnot.simulate.events.features`' order),
    the pair's names and law, the law's rule and restitution and friction as the validated
    contact template holds them."""

    index: int
    normal: list[float]
    point: list[float]
    normal_array: np.ndarray
    point_array: np.ndarray
    features: list[Feature]
    names: tuple[str, str]
    law: PairLaw
    rule: str
    restitution: float
    friction: float
    contact: PointContact  # the validated template (impacts.plane_contact_template)


@dataclass(frozen=True, kw_only=True, eq=False)
class LeanScene:
    """What :func:`advance` reads of a simulation, worked out once (:func:`lean_scene`)."""

    sim: Any  # carnot.simulate.loop.Simulation (not imported: the loop imports this module)
    body: SimBody
    sphere: bool
    radius: float
    vertices: np.ndarray  # (K, 3) body axes, contiguous (a convex body's corners)
    planes: list[LeanPlane]
    feats: list[Feature]
    plane_of: list[LeanPlane]  # of each feature
    gravity: list[float]
    mass: float
    inertia: tuple[float, ...]  # the template's nine entries (float_state)
    factor: tuple[tuple[float, ...], bool]  # its Cholesky factor (carnot.single.inertia_factor)
    unit_factor: tuple[tuple[float, ...], bool]  # a fixed obstacle's (single_floats')
    kernels: Any  # carnot.simulate.corners, for a convex body


def lean_scene(sim: Any) -> LeanScene | None:
    """The scene as :func:`advance` reads it, or None when it does not apply (module
    docstring): more than one movable body, ground motion, a lamina (its velocities are
    projected on its plane, and it rocks), a body whose inertia is not exactly ``c I``, a law
    that is neither frictionless nor sticking."""
    if not LEAN or len(sim.bodies) != 1 or sim.ground is not None:
        return None
    body: SimBody = sim.bodies[0]
    if body.plane_normal_body is not None or body.rotation_kind != "isotropic" or \
            not body.inertia_scalar:  # fmt: skip
        return None
    try:
        template = body_template(body)
    except InputError:  # (the general loop reports it at the first impact)
        return None
    feats = features(sim.bodies, sim.planes)
    planes: list[LeanPlane] = []
    plane_of: list[LeanPlane] = []
    for p, plane in enumerate(sim.planes):
        mine = [f for f in feats if f.plane == p]
        try:
            law: PairLaw = sim.law_of(mine[0])
            contact: PointContact = plane_contact_template(body.name, sim.plane_names[p],
                                                   plane.normal, law, "contacts[0]")
        except InputError:
            return None
        rule = contact_rule(tangential=contact.tangential, friction=contact.friction)
        if rule not in ("frictionless", "stick") or contact.patch is not None or \
                contact.is_given:  # fmt: skip
            return None
        lean_plane = LeanPlane(
            index=p, normal=plane.normal.tolist(), point=plane.point.tolist(),
            normal_array=plane.normal, point_array=plane.point, features=mine,
            names=(body.name, sim.plane_names[p]), law=law, rule=rule,
            restitution=contact.restitution, friction=contact.friction,
            contact=contact)  # fmt: skip
        planes.append(lean_plane)
        plane_of.extend([lean_plane] * len(mine))
    sphere = isinstance(body.shape, Sphere)
    kernels: Any = None
    if sphere:
        vertices = np.zeros((0, 3))
    else:
        from carnot.simulate import corners

        kernels = corners  # (imported here: Numba, which a ball need not load)
        vertices = np.ascontiguousarray(body.shape.vertices_body)  # type: ignore[union-attr]
    return LeanScene(sim=sim, body=body, sphere=sphere,
                     radius=body.shape.radius if sphere else 0.0,  # type: ignore[union-attr]
                     vertices=vertices, planes=planes,
                     feats=[f for lp in planes for f in lp.features], plane_of=plane_of,
                     gravity=sim.gravity.tolist(), mass=template.float_state[0],
                     inertia=template.float_state[1],
                     factor=inertia_factor(template.float_state[1]),
                     unit_factor=inertia_factor(UNIT_INERTIA), kernels=kernels)  # fmt: skip


@dataclass(kw_only=True, eq=False)
class LoopState:
    """The general loop's variables that the lean loop reads and moves on (see
    :func:`carnot.simulate.loop.run`): time (s), the body's state, the energy lost in impacts
    (J), whether only flight preceded the coming impact, impacts at this instant, flights that
    found a contact at once, and whether only pivoting preceded it (always False after a
    flight)."""

    t: float
    state: BodyState
    impacts: float
    flight: bool
    same_instant: int
    stalled: int
    pivoting: bool


def advance(scene: LeanScene, at: LoopState, events: list[Event],
            bounces: list[BounceRecord], eps: float, eps_v: float, limit: int,
            progress: Callable[[float], Any] | None = None) -> None:  # fmt: skip
    """Run the lean steps from ``at`` (moved on in place; events appended) until the end of
    the simulation or a step it does not take (module docstring). ``limit``: impacts at one
    instant, or flights that find a contact at once, before the general loop's error."""
    sim = scene.sim
    duration, max_events = sim.duration, sim.max_events
    body, feats, plane_of = scene.body, scene.feats, scene.plane_of
    sphere, radius, verts, g = scene.sphere, scene.radius, scene.vertices, scene.gravity
    g_array = sim.gravity
    t, state = at.t, at.state
    x, q = state.position.tolist(), state.orientation.tolist()
    v, w = state.velocity.tolist(), state.angular_velocity.tolist()
    kin = scene.kernels
    while t < duration and len(events) < max_events:
        # every feature's gap and normal velocity (events.gaps_and_speeds)
        if sphere:
            both = [sphere_gap_speed(lp.normal, lp.point, x, v, radius) for lp in scene.planes]
            gaps = [b[0] for b in both]
            speeds = [b[1] for b in both]
        else:
            gaps, speeds = [], []
            for lp in scene.planes:
                rows = kin.corner_kinematics(verts, state.orientation, state.position,
                                             state.velocity, state.angular_velocity,
                                             lp.normal_array, lp.point_array).tolist()
                gaps += rows[0]
                speeds += rows[1]
        touching = [k for k, gap in enumerate(gaps) if gap <= eps]
        approaching = [k for k in touching if speeds[k] < -eps_v]
        if approaching:
            if len(approaching) != 1 or at.same_instant + 1 > limit or any(
                    k != approaching[0] and abs(speeds[k]) <= eps_v for k in touching):
                return  # two struck at once, a closed contact: the general loop's
            k = approaching[0]
            f, lp = feats[k], plane_of[k]
            tip = sphere_tip(lp.normal, radius) if sphere else \
                (state.rotation @ body.shape.vertices_body[f.vertex]).tolist()  # type: ignore[union-attr]
            _, point, _, _ = on_plane(lp.normal, lp.point, x, tip, v, w)
            if not math.isfinite(x[0] + x[1] + x[2] + v[0] + v[1] + v[2] + w[0] + w[1] + w[2]
                                 + point[0] + point[1] + point[2]):
                return  # (a sum is finite only when every term is) the general loop names it
            out = factored_floats(lp.rule, scene.factor, scene.unit_factor, scene.mass,
                                  scene.inertia, x, v, w, 1.0, UNIT_INERTIA, point, REST,
                                  REST, 0.0, point, lp.normal, lp.restitution,
                                  lp.friction)  # fmt: skip
            if out is None:
                return  # divided by zero: solve_impact's general route, in the general loop
            if progress is not None:
                progress(t)
            at.same_instant += 1
            floats, law_out = out
            before = state
            v_after, w_after = list(floats[4:7]), list(floats[7:10])
            # (Record.from_fields: the dataclasses' fields as their __init__ sets them, at
            # every event; the state keeps its rotation matrix, the same orientation's)
            state = before.with_motion(np.array(v_after), np.array(w_after))
            at.impacts += floats[22] - floats[23]  # E_d, the direct difference (E' - E'')
            events.append(Event.from_fields({
                "time": t, "kind": "impact", "contacts": [lp.names], "impact": Impact(
                    time=t, features=[f], states=[state], flags=(),
                    later=_later(scene, t, lp, before, point, x, v, w, floats, law_out)),
                "energy": None}))  # fmt: skip
            zeno = bounce(bounces, time=t, feature=f, sphere=sphere, size=body.shape.size,
                          spin=w_after, state=lambda s=state: s,  # type: ignore[misc]
                          motion=_motion(lp, x, v, w, point, floats, law_out),
                          flight=at.flight, gravity=g_array, ground=False)  # fmt: skip
            # (loop._rocking: no lamina here, so its records stay empty)
            at.flight, at.pivoting = False, True
            v, w = v_after, w_after
            if zeno is not None and zeno.time < duration:
                energy = kinetic_energy(body, state) + potential_energy(body, state, g_array)
                state = zeno.state
                series = energy - (kinetic_energy(body, state)
                                   + potential_energy(body, state, g_array))  # fmt: skip
                at.impacts += series
                t = zeno.time
                bounces.clear()
                events.append(Event(time=t, kind="accumulation", contacts=[lp.names], energy={
                    "dissipated": series, "dissipated_theorem": zeno.dissipated_theorem,
                    "ratio": zeno.ratio, "series_start": zeno.start}))  # fmt: skip
                x, q = state.position.tolist(), state.orientation.tolist()
                v, w = state.velocity.tolist(), state.angular_velocity.tolist()
            at.t, at.state = t, state
            continue
        if any(abs(speeds[k]) <= eps_v for k in touching):
            return  # a closed contact: the general loop's contact phases
        speed = spin_rate(state.angular_velocity)  # (Flight's kind: constant, or still)
        if not sphere and not (speed > 0.0 and _events.CLOSED_FORM_CORNERS):
            return  # a convex body that does not turn: its gaps are quadratics there
        # free flight to the first gap closing (events.next_contact)
        horizon = duration - t
        levels = [0.0 if gap > eps else min(-eps, gap - eps) for gap in gaps]
        best: float | None = None
        if sphere:
            for k, lp in enumerate(scene.planes):
                a, b, c = sphere_quadratic(lp.normal_array, lp.point_array, g_array,
                                           state.position, state.velocity, radius)
                root = quadratic_first_down_root(a, b, c, levels[k], eps)
                if root is not None and root <= horizon and (best is None or root < best):
                    best = root
        else:
            start = 0
            for lp in scene.planes:
                stop = start + len(lp.features)
                found = kin.first_corner_impact(verts, state.rotation, state.position,
                                                state.velocity, state.angular_velocity,
                                                g_array, lp.normal_array, lp.point_array,
                                                np.array(levels[start:stop]), eps, horizon)
                start = stop
                if found != np.inf and (best is None or float(found) < best):
                    best = float(found)
        if best is not None and best <= 0.0:
            if at.stalled + 1 > limit:
                return  # the general loop's error
            at.stalled += 1
        else:
            at.stalled = 0
        if progress is not None:
            progress(t)
        at.same_instant = 0
        s_end = horizon if best is None else best
        x, q, v = flight_floats(x, q, v, w, g, s_end, speed)
        # (a convex body's rotation matrix worked out at once: the next step reads it)
        state = BodyState.from_floats(x, q, v, w, rotation=not sphere)
        t = duration if best is None and s_end >= duration - t else t + s_end
        at.flight, at.pivoting = True, False
        at.t, at.state = t, state


def _motion(lp: LeanPlane, x: list[float], v: list[float], w: list[float], point: list[float],
            floats: tuple[float, ...], law_out: tuple[float, ...]
            ) -> Callable[[], BounceMotion]:  # fmt: skip
    """What the Zeno test reads of the impact (:func:`carnot.simulate.zeno.bounce`), from the
    solver's numbers as :func:`carnot.single.single_result` reports them: the changes of
    ``v`` and ``omega``, the normal, ``w'`` and ``w''`` (read from the velocities after) and
    ``P_n``."""

    def motion() -> BounceMotion:
        after = floats[4:10]
        return ([a - b for a, b in zip(after[:3], v, strict=True)],
                [a - b for a, b in zip(after[3:], w, strict=True)], lp.normal,
                list(floats[16:19]), point_velocity(after, x, point), law_out[0])

    return motion


def _later(scene: LeanScene, t: float, lp: LeanPlane, before: BodyState, point: list[float],
           x: list[float], v: list[float], w: list[float], floats: tuple[float, ...],
           law_out: tuple[float, ...]) -> Callable[[], ImpactResult]:  # fmt: skip
    """The impact's :class:`carnot.ImpactResult`, made when first read: the short path's
    result from the solver's numbers (:func:`carnot.single.plane_result`, which is
    :func:`carnot.single.single_result` on the problem's parts) for the problem the general
    loop builds (:func:`carnot.simulate.impacts.plane_problem`, which :func:`carnot.
    simulate.impacts.impact_problem` calls for one body on one plane, at the same point:
    :func:`carnot.simulate.events.geometry` finds it by the same :func:`carnot.simulate.
    events.on_plane`), itself built only if the momentum check is read. The parts are that
    problem's: its title, contact and fixed plane, the body's float state (``x, v, w``: the
    lists of ``before``'s arrays) and its velocities as read-only arrays."""

    def make() -> ImpactResult:
        # (the problem solve_impact takes its short path for, with lp.rule: the contact is a
        # copy of the template that lean_scene read the rule of)
        plane = lp.names[1]
        problem = functools.partial(plane_problem, t, scene.body, plane, before,
                                    lp.normal_array, point, lp.law)  # fmt: skip
        velocity, spin = np.array(v, dtype=float), np.array(w, dtype=float)
        velocity.setflags(write=False)
        spin.setflags(write=False)
        return plane_result(
            impact_title(t), contact_at(lp.contact, point),
            fixed_body(plane), (scene.mass, scene.inertia, tuple(x), tuple(v), tuple(w)),
            (velocity, spin), lp.rule, floats, law_out, problem)  # fmt: skip

    return make


__all__ = ["LEAN", "LeanScene", "LoopState", "advance", "lean_scene"]

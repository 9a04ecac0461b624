"""Persistent contacts: resting, pivoting (rocking), rolling and sliding on planes.

While some features touch with zero normal velocity, the motion is that of Newton-Euler's
equations with contact forces ``lambda`` from the acceleration-level complementarity problem
(Pfeiffer and Glocker, *Multibody Dynamics with Unilateral Contacts*, 1996, ch. 5):

    M u' = f(t, u) + W_f^T lambda,      a = W u' + b,
    0 <= lambda_n  _|_  a_n >= 0,       stick: a_t = 0 and |lambda_t| <= mu lambda_n,
    slip: lambda_t = -mu lambda_n s (s the unit slip velocity), no tangent row

``W`` has the rows ``[d, r x d]`` of each constrained direction ``d`` (normal, and the two
tangents when sticking) at lever arm ``r``; ``b = d . (omega x (omega x r))`` for a vertex (a
material point), 0 for a sphere (its contact point is not a material point: rolling). The
problem is small, so it is solved by enumerating the active sets (the fewest contacts first:
a contact about to lift off is released rather than kept at zero force), each by a
least-squares solve (redundant contacts, a box on a face, take the minimum-norm split; the
motion is unique). Stick is tried first; a contact whose sticking force leaves the friction
cone slips against the tangential force it would have needed.

Between events the equations are integrated by SciPy's ``solve_ivp`` (DOP853, rtol 1e-12,
atol 1e-13) with the transitions as terminal events located by its root finder: a free
feature's gap closing (an impact), ``lambda_n`` of an active contact reaching 0 (lift-off),
``mu lambda_n - |lambda_t|`` reaching 0 (stick to slip), the slip velocity reversing along its
initial direction (slip to stick); and, for a feature touching at the start (a corner just
released by an impact), its gap opening to ``ARM_GAP eps``, which ends the phase without an
event so that the next one finds the corner's return at its gap's zero, not at the negative
level it had while touching. Two integrals run beside the state: the work dissipated by
sliding friction ``int mu lambda_n |v_slip| dt`` and the ground's work ``-int m a_g . v dt``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from itertools import combinations
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from carnot.errors import CarnotError
from carnot.simulate.events import Feature, frame, geometry, pair_scale
from carnot.simulate.ground import Ground
from carnot.simulate.motion import BodyState, SimBody, quat_multiply
from carnot.simulate.shapes import Plane, Sphere
from carnot.vector3 import cross

#: Largest number of touching features of one body whose active sets are enumerated.
MAX_CANDIDATES = 10
#: Tolerances of the integration of contact phases (DOP853).
RTOL, ATOL = 1e-12, 1e-13
#: A feature touching at a phase's start is armed (its impact found at its gap's zero) once
#: its gap has opened to this many eps: more than the eps of :func:`carnot.simulate.events.
#: trigger_levels`, so that the next phase finds it open whatever the root finder's round-off.
ARM_GAP = 2.0
#: Relative tolerance of the complementarity checks (forces and accelerations).
LCP_TOLERANCE = 1e-9


class SimulationError(CarnotError):
    """A situation the simulation does not handle (said in one line)."""


@dataclass(frozen=True, kw_only=True)
class Active:
    """An active persistent contact: its feature, ``mode`` (``stick``, ``slip``,
    ``frictionless``), the friction coefficient and, when slipping, the initial unit slip
    direction (world)."""

    feature: Feature
    mode: str
    friction: float
    slip_direction: tuple[float, float, float] | None = None


@dataclass(frozen=True, kw_only=True, eq=False)
class Scene:
    """What the dynamics need: bodies, planes, gravity (m/s^2), ground motion, the friction
    coefficient of each feature (from the pairs)."""

    bodies: list[SimBody]
    planes: list[Plane]
    gravity: np.ndarray
    ground: Ground | None
    friction: Callable[[Feature], float]


def _forces(scene: Scene, i: int, t: float, s: BodyState) -> tuple[np.ndarray, np.ndarray,
                                                                     np.ndarray]:  # fmt: skip
    """Unconstrained ``u'`` (6,), the world inertia ``J`` and its inverse for body ``i``."""
    body = scene.bodies[i]
    r = s.rotation
    j = body.inertia_world(r)
    j_inv = r @ body.inertia_body_inv @ r.T
    accel = scene.gravity - (scene.ground.accel(t) if scene.ground is not None else 0.0)
    w = s.angular_velocity
    alpha = -j_inv @ cross(w, j @ w)
    return np.concatenate([accel, alpha]), j, j_inv


def _rows(scene: Scene, c: Active, s: BodyState) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                          np.ndarray]:  # fmt: skip
    """Constraint rows ``W`` (k, 6), force rows ``W_f`` (k, 6), bias ``b`` (k,) and the
    contact frame (3, 3) of an active contact."""
    f = c.feature
    n, t1, t2 = frame(scene.planes[f.plane].normal)
    shape = scene.bodies[f.body].shape
    if isinstance(shape, Sphere):
        r = -shape.radius * n
        centripetal = np.zeros(3)
    else:
        r = s.rotation @ shape.vertices_body[f.vertex]
        w = s.angular_velocity
        centripetal = cross(w, cross(w, r))
    dirs = [n, t1, t2] if c.mode == "stick" else [n]
    rows = np.array([np.concatenate([d, cross(r, d)]) for d in dirs])
    bias = np.array([d @ centripetal for d in dirs])
    force = rows.copy()
    if c.mode == "slip":
        slip = _slip_velocity(scene, c, s)
        speed = float(np.linalg.norm(slip))
        initial = np.array(c.slip_direction)
        # the current slip direction while it keeps a part along the initial one; past that
        # (the slip reversing: the ``stick`` event) the initial one, so that the friction
        # force does not flip inside a step (a discontinuous right-hand side on which the
        # integrator would crawl, the slip velocity held at zero from both sides)
        direction = slip / speed if speed > 0 and float(slip @ initial) > 0 else initial
        d = n - c.friction * direction
        force = np.array([np.concatenate([d, cross(r, d)])])
    return rows, force, bias, np.array([n, t1, t2])


def _slip_velocity(scene: Scene, c: Active, s: BodyState) -> np.ndarray:
    g = geometry(c.feature, scene.bodies, scene.planes, [s] * (c.feature.body + 1))
    return g.tangential_velocity()


def solve_body(scene: Scene, i: int, t: float, s: BodyState, active: list[Active]
               ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Accelerations ``u' = (a, alpha)`` (6,) of body ``i`` and the contact multipliers (one
    per row, stacked in the order of ``active``) with ``active`` held as equalities."""
    body = scene.bodies[i]
    u0, _, j_inv = _forces(scene, i, t, s)
    if not active:
        return u0, np.zeros(0)
    m_inv = np.zeros((6, 6))
    m_inv[:3, :3] = np.eye(3) / body.mass
    m_inv[3:, 3:] = j_inv
    blocks = [_rows(scene, c, s) for c in active]
    w = np.vstack([b[0] for b in blocks])
    wf = np.vstack([b[1] for b in blocks])
    bias = np.concatenate([b[2] for b in blocks])
    a = w @ m_inv @ wf.T
    rhs = -(w @ u0 + bias)
    lam = np.linalg.lstsq(a, rhs, rcond=1e-12)[0]
    u = u0 + m_inv @ wf.T @ lam
    if body.plane_normal_body is not None:
        lin, ang = body.planar_velocity(s.rotation, u[:3], u[3:])
        u = np.concatenate([lin, ang])
    return u, lam


def normal_forces(active: list[Active], lam: np.ndarray) -> list[tuple[float, np.ndarray]]:
    """``(lambda_n, lambda_t)`` per active contact from the stacked multipliers."""
    out: list[tuple[float, np.ndarray]] = []
    k = 0
    for c in active:
        if c.mode == "stick":
            out.append((float(lam[k]), lam[k + 1 : k + 3].copy()))
            k += 3
        else:
            out.append((float(lam[k]), np.zeros(2)))
            k += 1
    return out


def select_modes(scene: Scene, t: float, states: list[BodyState], candidates: list[Feature],
                 eps_v: float, at_cone: frozenset[Feature] = frozenset()
                 ) -> list[Active]:  # fmt: skip
    """The active contacts (with their stick or slip modes) among touching ``candidates``
    whose normal velocity is ~0: the first active set, fewest contacts first, with
    ``lambda_n >= 0`` on the active contacts, ``a_n >= 0`` on the others and friction inside
    its cone (module docstring). ``at_cone``: contacts whose sticking force has just reached
    the cone (a ``slip`` event): on the cone, within a relative 1e-6, they slip (else stick
    would be chosen again, on the cone's edge, and the event found again at once)."""
    chosen: list[Active] = []
    for i in range(len(scene.bodies)):
        mine = [f for f in candidates if f.body == i]
        if not mine:
            continue
        if any(f.other >= 0 for f in mine):
            raise SimulationError(
                "persistent contact between two movable spheres, or a sphere or a box and a "
                "box (a stack, or one resting on another) is not supported by this version: "
                "only impacts between them"
            )
        if len(mine) > MAX_CANDIDATES:
            raise SimulationError(
                f"body {scene.bodies[i].name!r} touches with {len(mine)} vertices at once "
                f"(at most {MAX_CANDIDATES} are enumerated)"
            )
        chosen.extend(_select_body(scene, i, t, states[i], mine, eps_v, at_cone))
    return chosen


def _select_body(scene: Scene, i: int, t: float, s: BodyState, mine: list[Feature],
                 eps_v: float, at_cone: frozenset[Feature] = frozenset()
                 ) -> list[Active]:  # fmt: skip
    u_free, _ = solve_body(scene, i, t, s, [])
    scale = max(float(np.linalg.norm(scene.gravity)), float(np.linalg.norm(u_free[:3])), 1e-300)
    tol = LCP_TOLERANCE * scale
    for size in range(0, len(mine) + 1):
        for subset in combinations(mine, size):
            active = [_initial_mode(scene, f, s, eps_v) for f in subset]
            for _ in range(2):  # stick, then slip where the cone is left
                u, lam = solve_body(scene, i, t, s, active)
                forces = normal_forces(active, lam)
                mass = scene.bodies[i].mass
                pulled = any(fn < -tol * mass for fn, _ in forces)
                groups = stick_groups(active)
                margins = cone_margins(active, forces, groups)
                out = [g for g, m in zip(groups, margins, strict=True)
                       if m < -tol * mass or (m <= 1e-6 * scale * mass and any(
                           active[k].feature in at_cone for k in g))]  # fmt: skip
                if pulled:
                    # sticking would need a pull, but sliding may not: a block on two corners
                    # of a table that accelerates beyond g b / h, its friction below b / h,
                    # would tip if it stuck, and slides on both corners instead. Slip is tried
                    # where a group, pressed on the whole, leaves its cone; else this set fails
                    out = [g for g in out if sum(forces[k][0] for k in g) > 0]
                    if not out:
                        break
                if out:
                    for group in out:
                        total = sum(_tangent_force_world(scene, active[k], s, forces[k][1])
                                    for k in group)  # fmt: skip
                        direction = -np.asarray(total) / float(np.linalg.norm(total))
                        for k in group:
                            c = active[k]
                            active[k] = Active(feature=c.feature, mode="slip",
                                               friction=c.friction,
                                               slip_direction=tuple(direction.tolist()))
                    continue
                others = [f for f in mine if f not in subset]
                if all(_normal_acceleration(scene, f, s, u) >= -tol for f in others):
                    return active
                break
    raise SimulationError(
        f"no consistent contact mode for body {scene.bodies[i].name!r} at t = {t:.12g} s "
        "(the complementarity problem of its resting contacts has no solution this version "
        "finds)"
    )


def stick_groups(active: list[Active]) -> list[list[int]]:
    """Indices of the sticking contacts of ``active`` grouped by plane. Within a group the
    tangential forces can be shared out among the contacts (they act in one plane, and a
    redundant support such as a block on two corners leaves their split undetermined), so
    Coulomb's cone is checked on the group's totals, ``|sum lambda_t| <= mu sum lambda_n``:
    a simplification that is exact for a lamina on its corners, not in general."""
    groups: dict[int, list[int]] = {}
    for k, c in enumerate(active):
        if c.mode == "stick":
            groups.setdefault(c.feature.plane, []).append(k)
    return list(groups.values())


def cone_margins(active: list[Active], forces: list[tuple[float, np.ndarray]],
                 groups: list[list[int]]) -> list[float]:  # fmt: skip
    """``mu sum lambda_n - |sum lambda_t|`` (N) of each group (see :func:`stick_groups`)."""
    out = []
    for group in groups:
        fn = sum(forces[k][0] for k in group)
        ft = sum(forces[k][1] for k in group)
        out.append(active[group[0]].friction * fn - float(np.linalg.norm(ft)))
    return out


def _tangent_force_world(scene: Scene, c: Active, s: BodyState, ft: np.ndarray) -> np.ndarray:
    _, t1, t2 = frame(scene.planes[c.feature.plane].normal)
    return ft[0] * t1 + ft[1] * t2


def _initial_mode(scene: Scene, f: Feature, s: BodyState, eps_v: float) -> Active:
    mu = scene.friction(f)
    if mu == 0.0:
        return Active(feature=f, mode="frictionless", friction=0.0)
    g = geometry(f, scene.bodies, scene.planes, [s] * (f.body + 1))
    slip = g.tangential_velocity()
    speed = float(np.linalg.norm(slip))
    if speed > eps_v:
        return Active(feature=f, mode="slip", friction=mu,
                      slip_direction=tuple((slip / speed).tolist()))  # fmt: skip
    return Active(feature=f, mode="stick", friction=mu)


def _normal_acceleration(scene: Scene, f: Feature, s: BodyState, u: np.ndarray) -> float:
    rows, _, bias, _ = _rows(scene, Active(feature=f, mode="frictionless", friction=0.0), s)
    return float(rows[0] @ u + bias[0])


def _return_time(scene: Scene, t: float, states: list[BodyState], by_body: dict[int, list[Active]],
                 free: list[Feature], levels: dict[Feature, float], eps: float
                 ) -> float:  # fmt: skip
    """The shortest time ``2 w_n / |a_n|`` (s) in which a feature just released (touching, or
    just armed: within ``2 ARM_GAP eps``; rising with ``w_n > 0`` against ``a_n < 0``) comes
    back: the integrator must take several steps in it, or its return would fall inside one
    step and its event be missed (a rocking block whose rocking is dying out)."""
    out = np.inf
    for f in free:
        if f.other >= 0:
            continue
        s = states[f.body]
        g = geometry(f, scene.bodies, scene.planes, states)
        if levels.get(f, 0.0) >= 0 and g.gap > 2 * ARM_GAP * eps:
            continue
        if g.normal_velocity <= 0:
            continue
        u, _ = solve_body(scene, f.body, t, s, by_body[f.body])
        a_n = _normal_acceleration(scene, f, s, u)
        if a_n < 0:
            out = min(out, 2 * g.normal_velocity / -a_n)
    return float(out)


def _pair_step(scene: Scene, states: list[BodyState], free: list[Feature]) -> float:
    """A step (s) in which no free pair (two spheres, a sphere and a box) moves by more than a
    fifth of the smaller radius (or half extent) at its current relative speed plus what
    gravity adds over a radius."""
    out = np.inf
    g = float(np.linalg.norm(scene.gravity))
    for f in free:
        if f.other < 0:
            continue
        radius = pair_scale(scene.bodies[f.body].shape, scene.bodies[f.other].shape)
        speed = float(np.linalg.norm(states[f.body].velocity - states[f.other].velocity))
        out = min(out, 0.2 * radius / (speed + float(np.sqrt(2 * g * radius)) + 1e-300))
    return float(out)


def _split(y: np.ndarray, count: int) -> list[BodyState]:
    return [BodyState.from_array(y[13 * i : 13 * i + 13]) for i in range(count)]


@dataclass(frozen=True, kw_only=True, eq=False)
class ContactPhase:
    """The end of a contact phase: time (s), states, sliding dissipation and ground work
    (J) accumulated, the reason (``end``, ``impact``, ``lift_off``, ``slip``, ``stick``,
    ``armed``: a feature touching at the start has opened, see :data:`ARM_GAP`) and the
    feature concerned (None at the end)."""

    time: float
    states: list[BodyState]
    sliding: float
    ground_work: float
    reason: str
    feature: Feature | None
    samples: tuple[np.ndarray, np.ndarray]


def integrate(scene: Scene, t0: float, t1: float, states: list[BodyState],
              active: list[Active], free: list[Feature], levels: dict[Feature, float],
              eps: float, sample_step: float | None = None) -> ContactPhase:  # fmt: skip
    """Integrate from ``t0`` towards ``t1`` with ``active`` contacts until the first event
    (module docstring); ``sample_step`` (s): the phase's samples on that grid (from the
    integrator's dense output), else at its steps."""
    count = len(scene.bodies)
    by_body: dict[int, list[Active]] = {i: [] for i in range(count)}
    for c in active:
        by_body[c.feature.body].append(c)
    cache: dict[str, Any] = {"key": None}

    def evaluate(t: float, y: np.ndarray) -> tuple[np.ndarray, dict[int, np.ndarray]]:
        key = (t, y.tobytes())  # (one entry; y: the integrator's float64 state, one length)
        if cache["key"] == key:
            return cache["dy"], cache["lam"]
        states_ = _split(y, count)
        dy = np.zeros_like(y)
        lams: dict[int, np.ndarray] = {}
        power_slide = 0.0
        power_ground = 0.0
        a_g = scene.ground.accel(t) if scene.ground is not None else None
        for i, s in enumerate(states_):
            u, lam = solve_body(scene, i, t, s, by_body[i])
            lams[i] = lam
            base = 13 * i
            dy[base : base + 3] = s.velocity
            dy[base + 3 : base + 7] = 0.5 * quat_multiply(
                np.concatenate([[0.0], s.angular_velocity]), s.orientation)
            dy[base + 7 : base + 13] = u
            for c, (fn, _) in zip(by_body[i], normal_forces(by_body[i], lam), strict=True):
                if c.mode == "slip":
                    speed = float(np.linalg.norm(_slip_velocity(scene, c, s)))
                    power_slide += c.friction * fn * speed
            if a_g is not None:
                power_ground -= scene.bodies[i].mass * float(a_g @ s.velocity)
        dy[-2] = power_slide
        dy[-1] = power_ground
        cache.update(key=key, dy=dy, lam=lams)
        return dy, lams

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        return evaluate(t, y)[0]

    events: list[Callable[[float, np.ndarray], float]] = []
    labels: list[tuple[str, Feature]] = []
    rising: list[Callable[[float, np.ndarray], float]] = []
    for f in free:
        level = levels.get(f, 0.0)

        def gap_event(t: float, y: np.ndarray, f: Feature = f, level: float = level) -> float:
            return geometry(f, scene.bodies, scene.planes, _split(y, count)).gap - level

        events.append(gap_event)
        labels.append(("impact", f))
        if level < 0:
            # touching at the start, its impact counts below its (negative) level until it has
            # opened: the phase ends where it has (an ``armed`` end, no event), so that the
            # next phase finds its return at the gap's zero and not eps deeper (a rocking
            # block's corner coming back: eps / w_n late, 4e-9 s at each impact, and the
            # error carried on through the state)
            def armed(t: float, y: np.ndarray, f: Feature = f) -> float:
                return geometry(f, scene.bodies, scene.planes, _split(y, count)).gap \
                    - ARM_GAP * eps  # fmt: skip

            events.append(armed)
            rising.append(armed)
            labels.append(("armed", f))
    for i in range(count):
        for k, c in enumerate(by_body[i]):

            def lift(t: float, y: np.ndarray, i: int = i, k: int = k) -> float:
                return normal_forces(by_body[i], evaluate(t, y)[1][i])[k][0]

            events.append(lift)
            labels.append(("lift_off", c.feature))
            if c.mode == "stick":
                groups = stick_groups(by_body[i])
                g_index = next(n for n, g in enumerate(groups) if k in g)
                if groups[g_index][0] != k:
                    continue  # one event per group, on its first contact

                def cone(t: float, y: np.ndarray, i: int = i, g_index: int = g_index) -> float:
                    forces = normal_forces(by_body[i], evaluate(t, y)[1][i])
                    groups = stick_groups(by_body[i])
                    return cone_margins(by_body[i], forces, groups)[g_index]

                events.append(cone)
                labels.append(("slip", c.feature))
            elif c.mode == "slip":
                direction = np.array(c.slip_direction)

                def reverse(t: float, y: np.ndarray, i: int = i, c: Active = c,
                            direction: np.ndarray = direction) -> float:  # fmt: skip
                    s = _split(y, count)[i]
                    return float(_slip_velocity(scene, c, s) @ direction)

                events.append(reverse)
                labels.append(("stick", c.feature))
    for e in events:
        e.terminal = True  # type: ignore[attr-defined]
        e.direction = 1 if e in rising else -1  # type: ignore[attr-defined]
    y0 = np.concatenate([*(s.as_array() for s in states), [0.0, 0.0]])
    max_step = np.inf
    pieces = [t0, t1]
    if scene.ground is not None and t0 < scene.ground.end:
        # the ground's acceleration has kinks (a record's samples, a pulse's end): one solve
        # per smooth piece (a step across a kink fails its error test again and again)
        pieces = scene.ground.kinks(t0, t1)
        # and no step longer than the ground's spacing (a short spike would be missed)
        max_step = scene.ground.max_step
    max_step = min(max_step, _return_time(scene, t0, states, by_body, free, levels, eps) / 8)
    pair_step = _pair_step(scene, states, free)
    if pair_step < np.inf:
        # two spheres: their gap |x_a - x_b| - r is not monotone (one could pass through the
        # other inside a step): steps of a fifth of a radius, and a phase of 64 of them
        max_step = min(max_step, pair_step)
        t1 = min(t1, t0 + 64 * pair_step)
        pieces = [p for p in pieces if p < t1] + [t1]
    ts: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    y = y0
    for a, b in zip(pieces[:-1], pieces[1:], strict=True):
        t_eval = None
        if sample_step is not None:
            grid = np.arange(np.ceil(a / sample_step), np.floor(b / sample_step) + 1) \
                * sample_step  # fmt: skip
            t_eval = np.concatenate([[a], grid[(grid > a) & (grid < b)], [b]])
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=RTOL, atol=ATOL, events=events,
                        max_step=max_step, t_eval=t_eval)  # fmt: skip
        if sol.status == -1:
            raise SimulationError(f"the contact phase from t = {a:.12g} s failed: {sol.message}")
        ts.append(sol.t if not ts else sol.t[1:])
        ys.append(sol.y if not ys else sol.y[:, 1:])
        y = sol.y[:, -1]
        if sol.status == 1:
            break
    reason, feature, t_end, y_end = "end", None, float(sol.t[-1]), sol.y[:, -1]
    if sol.status == 1:
        hits = [(float(te[0]), k) for k, te in enumerate(sol.t_events) if len(te)]
        first = min(t for t, _ in hits)
        # events at the same instant: a slip stopping also moves the normal forces; report
        # the cause (stick, slip, impact) before its consequence (a lift-off)
        order = {"stick": 0, "slip": 1, "impact": 2, "lift_off": 3, "armed": 4}
        t_end, k = min(((t, k) for t, k in hits if t - first <= 1e-12 * max(1.0, abs(first))),
                       key=lambda h: order[labels[h[1]][0]])  # fmt: skip
        y_end = sol.y_events[k][0]
        reason, feature = labels[k]
    return ContactPhase(time=t_end, states=_split(y_end, count), sliding=float(y_end[-2]),
                        ground_work=float(y_end[-1]), reason=reason, feature=feature,
                        samples=(np.concatenate(ts), np.concatenate(ys, axis=1)))  # fmt: skip

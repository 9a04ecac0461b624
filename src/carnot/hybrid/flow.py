"""The flow between impacts and the strike: integrate ``M q'' + h = 0`` until a guard is
crossed, then solve the strike as one impact (DESIGN.md section 10).

The flow is integrated by SciPy's DOP853 stepper (an explicit Runge-Kutta method of order 8
with a dense output of order 7) at relative and absolute tolerance ``TOLERANCE``; a guard's
crossing is the root of ``G(x(t))`` on the step's dense output, found by Brent's method to a
few units of round-off in time (as ``solve_ivp`` locates its events). The loop over steps is
carnot's own, not ``solve_ivp``'s, so that an arming (mid-stance) inside a step arms the
strike for the rest of that same step: one integration per leg, not one per arming.

Only armed guards are watched, and only their crossings in the stated
direction. A state that starts on a guard's surface, leaving it (a rimless wheel rocking back
off the spoke it just struck with), is watched for the guard's rate ``G' = D_x G f`` turning
back first: the root at the start is never found again, and the return is.

Contacts held closed (:class:`Hold`: a joint at its stop, a point on its plane, sticking or
sliding) constrain the flow through their gap rows (:func:`held_flow`); their forces are
watched, each change (``release``, ``slip_start``, ``stick``) a root on the dense output as
for a guard. Where the model has dampers or a hold slides, the work they take is integrated
beside the state (two more components; none otherwise, so that the other models' steps are
the same).

With ``variational=True`` the linearization ``Phi' = A(x) Phi``, ``A = d flow / d x`` (exact,
from the mechanism's symbolic derivatives), is integrated beside the state: ``Phi(t)`` is the
flow's Jacobian ``d x(t) / d x(t0)``, from which saltation matrices build the monodromy.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from carnot.hybrid.model import GapRows, Guard, HybridModel, require_velocity_chart

#: The integrator's relative and absolute tolerance.
TOLERANCE = 1e-12
#: The largest time one leg of the flow may take (s), against a walker that never strikes.
MAX_FLIGHT = 1e3
EPS = float(np.finfo(float).eps)


@dataclass(frozen=True, kw_only=True, eq=False)
class Leg:
    """The flow from ``t0`` to ``t1`` (s): the state there ``x1``, ``phi`` (the flow's
    Jacobian, with ``variational``), and why it ended: ``guard`` (the strike's guard),
    ``"fall"``, ``"end"`` (the time limit), or a hold's ``"release"``, ``"slip_start"`` or
    ``"stick"`` (``guard`` the held one); ``damping`` and ``sliding``: the work the dampers
    and the sliding holds' friction took over the leg (J, >= 0)."""

    t0: float
    t1: float
    x1: np.ndarray
    phi: np.ndarray | None
    ended: str
    guard: Guard | None
    evaluations: int
    damping: float = 0.0
    sliding: float = 0.0


@dataclass(frozen=True, kw_only=True)
class Hold:
    """A guard held closed in the flow: ``index`` (in the model's guards) and ``slip``: 0
    sticking (the gap's row held, and the tangent's where the point can slide), +1 or -1
    sliding along +t or -t, the tangent row then carrying Coulomb's force ``-mu F_n slip``.
    A joint's stop holds its one row (frictionless)."""

    index: int
    slip: int = 0


def gap_rows(model: HybridModel, guard: Guard, x: np.ndarray) -> GapRows:
    """The held guard's rows at ``x``: a stop's ``limit_row`` (its gap linear in the chart:
    no bias, no tangent), or the guard's own ``rows``."""
    if guard.limit_row is not None:
        q = x[: model.nq]
        return GapRows(normal=np.asarray(guard.limit_row) @ model.mechanism.embed_jacobian(q))
    if guard.rows is None:
        raise ValueError(f"the guard {guard.name!r} cannot be held in the flow")
    return guard.rows(x)


def held_flow(model: HybridModel, held: tuple[Hold, ...], x: np.ndarray,
              friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The flow with the guards ``held`` closed, and their forces ``(F_n, F_t)`` (N, or N m
    at a joint; one row per hold):

        M q'' = -h + sum_i (J_n,i - mu s_i J_t,i)^T F_n,i + J_t,i^T F_t,i
        J_n,i q'' + b_n,i = 0,   J_t,i q'' + b_t,i = 0 where i sticks

    (``b`` the rows' biases: the gap's and the slide's acceleration stay zero; a sliding
    hold ``s_i = +-1`` carries ``F_t = -mu s F_n`` on its tangent instead of a row, with
    ``mu = friction``). ``F_n >= 0`` pushes the point off its plane (the joint off its stop);
    the hold ends where it would pull. The system is solved by least squares where its rows
    are dependent (more held rows than the chart can honour: the forces are then not unique,
    the motion is)."""
    n = model.n
    q, qd = x[: model.nq], x[model.nq :]
    rows: list[np.ndarray] = []  # the held rows (acceleration constraints)
    forces: list[np.ndarray] = []  # the directions of each unknown force, in the chart
    biases: list[float] = []
    where: list[tuple[int, int]] = []  # each hold's (normal unknown, tangent unknown or -1)
    mu = 0.0 if friction is None else float(friction)
    for hold in held:
        r = gap_rows(model, model.guards[hold.index], x)
        k = len(rows)
        rows.append(r.normal)
        biases.append(r.normal_bias)
        if hold.slip and r.tangent is not None:
            forces.append(r.normal - mu * hold.slip * r.tangent)
            where.append((k, -1))
        elif r.tangent is not None:
            forces += [r.normal, r.tangent]
            rows.append(r.tangent)
            biases.append(r.tangent_bias)
            where.append((k, k + 1))
        else:
            forces.append(r.normal)
            where.append((k, -1))
    m = model.mechanism.mass(q)
    k = len(rows)
    kkt = np.zeros((n + k, n + k))
    kkt[:n, :n] = m
    kkt[:n, n:] = -np.array(forces).T
    kkt[n:, :n] = np.array(rows)
    rhs = np.concatenate([-model.mechanism.bias(q, qd), -np.array(biases)])
    try:
        sol = np.linalg.solve(kkt, rhs)
    except np.linalg.LinAlgError:
        sol = np.linalg.lstsq(kkt, rhs, rcond=None)[0]
    lam = sol[n:]
    out = np.zeros((len(held), 2))
    for j, (hold, (kn, kt)) in enumerate(zip(held, where, strict=True)):
        out[j, 0] = lam[kn]
        out[j, 1] = lam[kt] if kt >= 0 else -mu * hold.slip * lam[kn]
    return np.concatenate([model.mechanism.position_rate(q, qd), sol[:n]]), out


def fly(model: HybridModel, x0: np.ndarray, t0: float, t_end: float, *,
        variational: bool = False, tolerance: float = TOLERANCE,
        held: tuple[Hold, ...] = (), friction: float | None = None) -> Leg:  # fmt: skip
    """Integrate from ``(t0, x0)`` until a guard strikes (armings in between re-arm and go
    on), the model falls, a held contact or stop releases (``ended = "release"``, ``guard``
    the held one), a sticking hold's force leaves the cone of ``friction``
    (``"slip_start"``), a sliding one's slide stops (``"stick"``), a stance foot's force
    would pull (``"lift"``) or leave the cone (``"slip"``; ``None``: the foot sticks
    whatever the force), or ``t_end``.

    Beside the state, where the model has dampers or a hold slides, the work they take is
    integrated (``Leg.damping``: ``int sum c l'^2 dt``; ``Leg.sliding``:
    ``int sum mu F_n s v_t dt``, ``v_t = J_t q'``), J.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> leg = fly(wheel, np.array([0.08 - np.pi / 8, 1.0]), 0.0, 10.0)
    >>> leg.ended, round(float(leg.x1[0]), 12) == round(0.08 + np.pi / 8, 12)
    ('next_spoke', True)
    """
    from scipy.integrate import DOP853

    n2 = model.nq + model.n
    mech = model.mechanism
    damping = getattr(mech, "damping_power", None)
    sliding = [j for j, h in enumerate(held) if h.slip]
    quad = 2 if damping is not None or sliding else 0  # the works' slots after the state
    if held and variational:
        raise ValueError("the flow's linearization is not built with a contact held")
    if variational:
        require_velocity_chart(model, "the flow's linearization and saltation matrices")

    def state_rate(x: np.ndarray) -> np.ndarray:
        if not held:
            return mech.flow(x) if not quad else np.concatenate([mech.flow(x), _works(x)])
        f, forces = held_flow(model, held, x, friction)
        if not quad:
            return f
        works = _works(x)
        for j in sliding:  # the friction's power: -F_t v_t = mu F_n s v_t >= 0
            r = gap_rows(model, model.guards[held[j].index], x)
            if r.tangent is not None:
                works[1] -= forces[j, 1] * float(r.tangent @ x[model.nq :])
        return np.concatenate([f, works])

    def _works(x: np.ndarray) -> np.ndarray:
        return np.array([0.0 if damping is None else damping(x), 0.0])

    if variational:

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            x = y[:n2]
            phi = y[n2 + quad :].reshape(n2, n2)
            return np.concatenate([state_rate(x), (mech.flow_jacobian(x) @ phi).ravel()])

        y = np.concatenate([x0, np.zeros(quad), np.eye(n2).ravel()])
    elif held or quad:

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            return state_rate(y[:n2])

        y = np.concatenate([np.asarray(x0, dtype=float), np.zeros(quad)])
    else:  # the free flow, one compiled call: the integrator's inner loop (a walker's step)

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            return mech.flow(y)

        y = np.array(x0, dtype=float)
    held_index = {h.index for h in held}
    armed = [g.arming is None and k not in held_index for k, g in enumerate(model.guards)]
    # a guard that the leg starts on, moving off it, must turn back (its rate G' = D_x G f
    # crossing zero) before it can strike: else the root at t0 itself would be found again
    turning = [armed[k] and _leaving(model, g, np.asarray(x0, dtype=float))
               for k, g in enumerate(model.guards)]  # fmt: skip
    # a slide that starts from rest (a stick leaving its cone) is watched for stopping only
    # once its speed has left zero by SLIDE_START; before that, for turning back past it
    started = [abs(_slide_speed(model, h, np.asarray(x0, dtype=float))) > _slide_scale(x0)
               for h in held]  # fmt: skip
    t_stop = min(t_end, t0 + MAX_FLIGHT)
    solver = DOP853(rhs, t0, y, t_stop, rtol=tolerance, atol=tolerance)
    t_old, y_old = t0, y
    watch: list[tuple[Callable[[np.ndarray], float], int, str, int]] | None = None
    values: dict[tuple[str, int], float] = {}  # each watched function at the step's start
    while True:
        message = solver.step()
        if message is not None:
            raise RuntimeError(f"the integrator stopped at t = {solver.t:g}: {message}")
        t_new, y_new = solver.t, solver.y
        dense = None
        lo = t_old  # the step's part still to search: each arming moves it on
        while True:
            if watch is None:  # (built again only when an arming or a turn changes it)
                watch = _watched(model, armed, turning, n2, friction) + _held_watch(
                    model, held, friction, started, _slide_scale(x0))
            found: tuple[float, str, int] | None = None
            ends: dict[tuple[str, int], float] = {}
            for fn, direction, kind, k in watch:
                g_old = values.get((kind, k)) if lo == t_old else None
                if g_old is None:  # a function watched from inside this step, or new
                    g_old = fn((dense(lo) if lo > t_old and dense is not None else y_old)[:n2])
                g_new = ends[(kind, k)] = fn(y_new[:n2])
                rising = direction > 0 and g_old < 0 <= g_new
                if rising or (direction < 0 and g_old > 0 >= g_new):
                    if dense is None:
                        dense = solver.dense_output()
                    root = _root(fn, dense, lo, t_new, n2)
                    if found is None or root < found[0]:
                        found = (root, kind, k)
            if found is None:
                values = ends
                break
            root, kind, k = found
            y_root = np.asarray(dense(root), dtype=np.float64)  # type: ignore[misc]
            if kind == "strike":
                g = model.guards[k]
                return _leg(t0, root, y_root, n2, quad, variational, g.name, g, solver.nfev)
            if kind in ("fall", "lift", "slip"):
                return _leg(t0, root, y_root, n2, quad, variational, kind, None, solver.nfev)
            if kind in ("release", "slip_start", "stick"):
                g = model.guards[held[k].index]
                return _leg(t0, root, y_root, n2, quad, variational, kind, g, solver.nfev)
            if kind == "turn":
                turning[k] = False
            elif kind == "slide":
                started[k] = True
            else:
                armed[k] = True
            watch = None
            lo = root
        if solver.status == "finished":
            return _leg(t0, t_new, np.array(y_new), n2, quad, variational, "end", None,
                        solver.nfev)  # fmt: skip
        t_old, y_old = t_new, np.array(y_new)


#: A slide's speed (relative to the state's size, m/s) below which it has not yet started.
SLIDE_START = 1e-10


def _slide_scale(x: np.ndarray) -> float:
    return SLIDE_START * max(1.0, float(np.linalg.norm(x)))


def _slide_speed(model: HybridModel, hold: Hold, x: np.ndarray) -> float:
    """``s v_t`` (m/s): a sliding hold's speed along its slide (> 0 while it slides)."""
    if not hold.slip:
        return 0.0
    r = gap_rows(model, model.guards[hold.index], x)
    return 0.0 if r.tangent is None else hold.slip * float(r.tangent @ x[model.nq :])


def _held_watch(model: HybridModel, held: tuple[Hold, ...], friction: float | None,
                started: list[bool], scale: float
                ) -> list[tuple[Callable[[np.ndarray], float], int, str, int]]:  # fmt: skip
    """What the holds watch (function, direction, kind, the hold's position): the normal
    force falling through zero (``release``); a sticking hold's cone margin
    ``mu F_n - |F_t|`` falling through zero (``slip_start``); a sliding hold's speed
    ``s v_t`` falling through zero (``stick``), or, before it has started (``slide``,
    rising through ``scale``), falling through ``-scale``."""
    out: list[tuple[Callable[[np.ndarray], float], int, str, int]] = []
    for j, hold in enumerate(held):
        out.append((_held_force(model, held, j, friction, 0), -1, "release", j))
        guard = model.guards[hold.index]
        if guard.limit_row is not None or friction is None:
            continue
        if hold.slip == 0:
            out.append((_held_force(model, held, j, friction, 1), -1, "slip_start", j))
        elif started[j]:
            out.append((_speed_past(model, hold, 0.0), -1, "stick", j))
        else:
            out.append((_speed_past(model, hold, -scale), -1, "stick", j))
            out.append((_speed_past(model, hold, scale), 1, "slide", j))
    return out


def _speed_past(model: HybridModel, hold: Hold, level: float
                ) -> Callable[[np.ndarray], float]:  # fmt: skip
    """``s v_t - level``: a sliding hold's speed past ``level`` (m/s)."""
    return lambda x: _slide_speed(model, hold, x) - level


def _held_force(model: HybridModel, held: tuple[Hold, ...], j: int, friction: float | None,
                which: int) -> Callable[[np.ndarray], float]:  # fmt: skip
    """The ``j``-th hold's normal force (``which = 0``), or its cone margin
    ``mu F_n - |F_t|`` (``which = 1``)."""
    mu = 0.0 if friction is None else float(friction)

    def fn(x: np.ndarray) -> float:
        f = held_flow(model, held, x, friction)[1][j]
        return float(f[0]) if which == 0 else float(mu * f[0] - abs(f[1]))

    return fn


def stance_margins(model: HybridModel, x: np.ndarray, friction: float | None
                   ) -> tuple[float, float]:  # fmt: skip
    """A stance foot's ground force ``F`` (N) against what the ground can give: ``F_n``
    (>= 0: it pushes) and ``mu F_n - |F_t|`` (>= 0: inside the cone; ``inf`` where the foot
    sticks whatever the force)."""
    force = model.mechanism.support(x)  # type: ignore[attr-defined]
    normal = np.asarray(model.normal[:2], dtype=float)
    f_n = float(normal @ force)
    f_t = float(np.linalg.norm(force - f_n * normal))
    return f_n, (np.inf if friction is None else friction * f_n - f_t)


def _watched(model: HybridModel, armed: list[bool], turning: list[bool], n2: int,
             friction: float | None = None
             ) -> list[tuple[Callable[[np.ndarray], float], int, str, int]]:  # fmt: skip
    """The functions watched now: (function, direction, kind, guard index)."""
    out: list[tuple[Callable[[np.ndarray], float], int, str, int]] = []
    for k, g in enumerate(model.guards):
        if turning[k]:
            out.append((_rate(model, g), g.direction, "turn", k))
        elif armed[k]:
            out.append((g.function, g.direction, "strike", k))
        elif g.arming is not None:
            out.append((g.arming, g.arming_direction, "arm", k))
    if model.fall is not None:
        out.append((model.fall, -1, "fall", -1))
    if model.stance and getattr(model.mechanism, "support", None) is not None:
        out.append((lambda x: stance_margins(model, x, None)[0], -1, "lift", -1))
        if friction is not None:
            out.append((lambda x: stance_margins(model, x, friction)[1], -1, "slip", -1))
    return out


def _root(fn: Callable[[np.ndarray], float], dense: Any, lo: float, hi: float, n2: int) -> float:
    """The crossing in ``[lo, hi]`` on the step's dense output, by Brent's method to a few
    units of round-off (SciPy's own event location)."""
    from scipy.optimize import brentq

    return float(brentq(lambda t: fn(dense(t)[:n2]), lo, hi, xtol=4 * EPS, rtol=4 * EPS))


#: |G(x)| below this (relative to |D_x G| |x|) is on the guard's surface.
ON_SURFACE = 1e-12


def _rate(model: HybridModel, g: Guard) -> Callable[[np.ndarray], float]:
    """``G'(x) = D_x G(x) . f(x)``, the guard's rate along the flow."""
    return lambda x: float(g.gradient(x) @ model.mechanism.flow(x))


def _leaving(model: HybridModel, g: Guard, x: np.ndarray) -> bool:
    """Whether ``x`` is on the guard's surface, moving off it (against its direction)."""
    grad = g.gradient(x)
    size = max(1.0, float(np.linalg.norm(grad) * np.linalg.norm(x)))
    on = abs(g.function(x)) <= ON_SURFACE * size
    return on and g.direction * float(grad @ model.mechanism.flow(x)) < 0


def _leg(t0: float, t1: float, y: np.ndarray, n2: int, quad: int, variational: bool,
         ended: str, guard: Guard | None, evaluations: int) -> Leg:  # fmt: skip
    x1 = np.array(y[:n2])
    works = np.array(y[n2 : n2 + quad]) if quad else np.zeros(2)
    phi = np.array(y[n2 + quad :]).reshape(n2, n2) if variational else None
    return Leg(t0=t0, t1=t1, x1=x1, phi=phi, ended=ended, guard=guard, evaluations=evaluations,
               damping=float(works[0]), sliding=float(works[1]))  # fmt: skip

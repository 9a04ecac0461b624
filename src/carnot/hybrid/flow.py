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

With ``variational=True`` the linearization ``Phi' = A(x) Phi``, ``A = d flow / d x`` (exact,
from the mechanism's symbolic derivatives), is integrated beside the state: ``Phi(t)`` is the
flow's Jacobian ``d x(t) / d x(t0)``, from which saltation matrices build the monodromy.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from carnot.hybrid.model import Guard, HybridModel

#: The integrator's relative and absolute tolerance.
TOLERANCE = 1e-12
#: The largest time one leg of the flow may take (s), against a walker that never strikes.
MAX_FLIGHT = 1e3
EPS = float(np.finfo(float).eps)


@dataclass(frozen=True, kw_only=True, eq=False)
class Leg:
    """The flow from ``t0`` to ``t1`` (s): the state there ``x1``, ``phi`` (the flow's
    Jacobian, with ``variational``), and why it ended: ``guard`` (the strike's guard),
    ``"fall"``, or ``"end"`` (the time limit)."""

    t0: float
    t1: float
    x1: np.ndarray
    phi: np.ndarray | None
    ended: str
    guard: Guard | None
    evaluations: int


def held_flow(model: HybridModel, held: tuple[int, ...], x: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The flow with the joints of the guards ``held`` at their stops, and the stops' forces:

        [[M, -J^T], [J, 0]] [q''; lambda] = [-h; 0],    J the held stops' gap gradients,

    (the gaps ``g = J q + c`` are linear in the chart: ``J' = 0``); ``lambda >= 0`` pushes the
    joint off its stop, and the stop releases when it would pull."""
    n = model.n
    q, qd = x[:n], x[n:]
    rows = np.array([np.asarray(model.guards[k].limit_row) @ model.mechanism.embed_jacobian(q)
                     for k in held], dtype=float)  # fmt: skip
    m = model.mechanism.mass(q)
    k = len(held)
    kkt = np.zeros((n + k, n + k))
    kkt[:n, :n] = m
    kkt[:n, n:] = -rows.T
    kkt[n:, :n] = rows
    rhs = np.concatenate([-model.mechanism.bias(q, qd), np.zeros(k)])
    sol = np.linalg.solve(kkt, rhs)
    return np.concatenate([qd, sol[:n]]), sol[n:]


def fly(model: HybridModel, x0: np.ndarray, t0: float, t_end: float, *,
        variational: bool = False, tolerance: float = TOLERANCE,
        held: tuple[int, ...] = (), friction: float | None = None) -> Leg:  # fmt: skip
    """Integrate from ``(t0, x0)`` until a guard strikes (armings in between re-arm and go
    on), the model falls, a held stop releases (``ended = "release"``, ``guard`` the stop),
    a stance foot's force would pull (``"lift"``) or leave the cone of ``friction``
    (``"slip"``; ``None``: the foot sticks whatever the force),
    or ``t_end``.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> leg = fly(wheel, np.array([0.08 - np.pi / 8, 1.0]), 0.0, 10.0)
    >>> leg.ended, round(float(leg.x1[0]), 12) == round(0.08 + np.pi / 8, 12)
    ('next_spoke', True)
    """
    from scipy.integrate import DOP853

    n2 = 2 * model.n
    mech = model.mechanism
    if held:
        if variational:
            raise ValueError("the flow's linearization is not built with a joint held")

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            return held_flow(model, held, y)[0]

        y = np.array(x0, dtype=float)
    elif variational:

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            x = y[:n2]
            phi = y[n2:].reshape(n2, n2)
            return np.concatenate([mech.flow(x), (mech.flow_jacobian(x) @ phi).ravel()])

        y = np.concatenate([x0, np.eye(n2).ravel()])
    else:

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            return mech.flow(y)

        y = np.array(x0, dtype=float)
    armed = [g.arming is None and k not in held for k, g in enumerate(model.guards)]
    # a guard that the leg starts on, moving off it, must turn back (its rate G' = D_x G f
    # crossing zero) before it can strike: else the root at t0 itself would be found again
    turning = [armed[k] and _leaving(model, g, np.asarray(x0, dtype=float))
               for k, g in enumerate(model.guards)]  # fmt: skip
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
                watch = _watched(model, armed, turning, n2, friction) + [
                    (_stop_force(model, held, j), -1, "release", k) for j, k in enumerate(held)]
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
                return _leg(t0, root, y_root, n2, variational, g.name, g, solver.nfev)
            if kind in ("fall", "lift", "slip"):
                return _leg(t0, root, y_root, n2, variational, kind, None, solver.nfev)
            if kind == "release":
                g = model.guards[k]
                return _leg(t0, root, y_root, n2, variational, "release", g, solver.nfev)
            if kind == "turn":
                turning[k] = False
            else:
                armed[k] = True
            watch = None
            lo = root
        if solver.status == "finished":
            return _leg(t0, t_new, np.array(y_new), n2, variational, "end", None, solver.nfev)
        t_old, y_old = t_new, np.array(y_new)


def _stop_force(model: HybridModel, held: tuple[int, ...], j: int
                ) -> Callable[[np.ndarray], float]:  # fmt: skip
    """The force of the ``j``-th held stop (it releases where this falls through zero)."""
    return lambda x: float(held_flow(model, held, x)[1][j])


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


def _leg(t0: float, t1: float, y: np.ndarray, n2: int, variational: bool, ended: str,
         guard: Guard | None, evaluations: int) -> Leg:  # fmt: skip
    x1 = np.array(y[:n2])
    phi = np.array(y[n2:]).reshape(n2, n2) if variational else None
    return Leg(t0=t0, t1=t1, x1=x1, phi=phi, ended=ended, guard=guard, evaluations=evaluations)

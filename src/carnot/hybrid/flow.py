"""The flow between impacts and the strike: integrate ``M q'' + h = 0`` until a guard is
crossed, then solve the strike as one impact (DESIGN.md section 10).

The flow is integrated by SciPy's DOP853 (an explicit Runge-Kutta method of order 8 with a
dense output of order 7) at relative and absolute tolerance ``TOLERANCE``; a guard's crossing
is the root of ``G(x(t))`` on the dense output, found by Brent's method to a few units of
round-off in time. Only armed guards are watched, and only their crossings in the stated
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

import numpy as np

from carnot.hybrid.model import Guard, HybridModel

#: The integrator's relative and absolute tolerance.
TOLERANCE = 1e-12
#: The largest time one leg of the flow may take (s), against a walker that never strikes.
MAX_FLIGHT = 1e3


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


def _event(fn: Callable[[np.ndarray], float], n2: int, direction: int) -> Callable[..., float]:
    def event(t: float, y: np.ndarray) -> float:
        return fn(y[:n2])

    event.terminal = True  # type: ignore[attr-defined]
    event.direction = direction  # type: ignore[attr-defined]
    return event


def fly(model: HybridModel, x0: np.ndarray, t0: float, t_end: float, *,
        variational: bool = False, tolerance: float = TOLERANCE) -> Leg:  # fmt: skip
    """Integrate from ``(t0, x0)`` until a guard strikes (armings in between re-arm and go
    on), the model falls, or ``t_end``.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> leg = fly(wheel, np.array([0.08 - np.pi / 8, 1.0]), 0.0, 10.0)
    >>> leg.ended, round(float(leg.x1[0]), 12) == round(0.08 + np.pi / 8, 12)
    ('next_spoke', True)
    """
    from scipy.integrate import solve_ivp

    n2 = 2 * model.n
    mech = model.mechanism
    if variational:

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            x = y[:n2]
            phi = y[n2:].reshape(n2, n2)
            return np.concatenate([mech.flow(x), (mech.flow_jacobian(x) @ phi).ravel()])

        y = np.concatenate([x0, np.eye(n2).ravel()])
    else:

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            return mech.flow(y)

        y = np.array(x0, dtype=float)
    armed = [g.arming is None for g in model.guards]
    # a guard that the leg starts on, moving off it, must turn back (its rate G' = D_x G f
    # crossing zero) before it can strike: else the root at t0 itself would be found again
    turning = [armed[k] and _leaving(model, g, np.asarray(x0, dtype=float))
               for k, g in enumerate(model.guards)]  # fmt: skip
    t = t0
    evaluations = 0
    t_stop = min(t_end, t0 + MAX_FLIGHT)
    while True:
        events: list[Callable[..., float]] = []
        owners: list[tuple[str, int]] = []
        for k, g in enumerate(model.guards):
            if turning[k]:
                events.append(_event(_rate(model, g), n2, g.direction))
                owners.append(("turn", k))
            elif armed[k]:
                events.append(_event(g.function, n2, g.direction))
                owners.append(("strike", k))
            elif g.arming is not None:
                events.append(_event(g.arming, n2, g.arming_direction))
                owners.append(("arm", k))
        if model.fall is not None:
            events.append(_event(model.fall, n2, -1))
            owners.append(("fall", -1))
        sol = solve_ivp(rhs, (t, t_stop), y, method="DOP853", rtol=tolerance, atol=tolerance,
                        events=events)  # fmt: skip
        evaluations += int(sol.nfev)
        hit = [(float(te[0]), i) for i, te in enumerate(sol.t_events) if len(te)]
        if not hit:
            y = sol.y[:, -1]
            return _leg(t0, float(sol.t[-1]), y, n2, variational, "end", None, evaluations)
        t, i = min(hit)
        y = np.array(sol.y_events[i][0], dtype=float)
        kind, k = owners[i]
        if kind == "strike":
            g = model.guards[k]
            return _leg(t0, t, y, n2, variational, g.name, g, evaluations)
        if kind == "fall":
            return _leg(t0, t, y, n2, variational, "fall", None, evaluations)
        if kind == "turn":
            turning[k] = False
        else:
            armed[k] = True


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

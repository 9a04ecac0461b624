"""Periodic orbits of a hybrid model: the return map, Newton shooting, Floquet multipliers
from saltation matrices (DESIGN.md section 10).

The section is the state just after a strike. The return map ``P`` flows a state ``x`` to the
``k``-th strike (``k`` = ``steps``, the orbit's period in strikes) and applies it. Its
linearization is built without differencing the flow: ``Phi``, the flow's Jacobian, is
integrated beside the state (:func:`carnot.hybrid.flow.fly`), and at each strike

    D P = D_x R (I - f- (D_x G) / (D_x G f-)) Phi,     the monodromy  S Phi,

with ``S`` the strike's saltation matrix (:func:`carnot.hybrid.simulate.saltation_matrix`),
all in the tangent chart (:func:`carnot.hybrid.model.tangent_step`: an MJCF model's free or
ball joint perturbs its quaternion on its sphere; ``x + dx`` where ``nq == n``).
The monodromy over one period has the eigenvalue 1 along the flow (a shift in time along the
orbit returns shifted); the other ``2n - 1`` are the orbit's Floquet multipliers, and it is
stable when they all lie inside the unit circle.

A periodic orbit is a zero of ``P(x) - x``: Newton's method with ``D P - I`` (nonsingular at a
hyperbolic orbit: ``D P`` has 0, not 1, along the flow), each step halved until the residual
falls. It stops at ``|P(x) - x| <= tolerance max(1, |x|)``, or says it did not converge, with
the residual it reached (a guess far from any orbit, or a model that falls).

``finite_difference_jacobian`` is the second route: central differences of ``P`` itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from carnot.hybrid.flow import TOLERANCE, fly, stance_margins
from carnot.hybrid.model import (
    Guard,
    HybridModel,
    Law,
    require_velocity_chart,
    tangent_difference,
    tangent_flow,
    tangent_gradient,
    tangent_step,
)
from carnot.hybrid.simulate import GRAZING, saltation_matrix
from carnot.hybrid.strike import AT_REST, PLASTIC, Strike, reset_jacobian, strike

#: The most Newton steps, and how often a step may be halved.
MAX_NEWTON = 40
MAX_HALVINGS = 12
#: The relative step of the finite-difference route.
FD_STEP = 1e-6
#: A converged state whose kinetic energy is below this (of the guess's energy scale) is the
#: state of rest, not a periodic motion.
AT_REST_ORBIT = 1e-20
#: How far (absolute) the monodromy's eigenvalue along the flow may lie from 1 before the
#: linearization is said to be off (``trivial_multiplier``).
TRIVIAL = 1e-6
#: The longest time one period may take (s or the model's unit).
MAX_PERIOD = 100.0


class ReturnFailed(Exception):
    """The flow from a state did not reach the section: it fell, or no strike came."""


class HeldContact(ReturnFailed):
    """A strike left its contact closed and at rest: the simulator holds it in the flow,
    which the return map (built on the free flow) does not follow."""


@dataclass(frozen=True, kw_only=True, eq=False)
class Return:
    """One return: the state ``x`` after ``steps`` strikes, the ``period`` (s), the strikes,
    ``jacobian`` D P and ``monodromy`` (with ``linearize``), and ``anchor`` (how far the
    chart's origin moved, m) and ``flags`` (``grazing``, or a strike's own)."""

    x: np.ndarray
    period: float
    strikes: tuple[Strike, ...]
    jacobian: np.ndarray | None
    monodromy: np.ndarray | None
    anchor: np.ndarray
    flags: tuple[str, ...]


def return_map(model: HybridModel, x0: np.ndarray, law: Law = PLASTIC, *, steps: int = 1,
               linearize: bool = False, tolerance: float = TOLERANCE) -> Return:  # fmt: skip
    """Flow from ``x0`` through ``steps`` strikes (ReturnFailed if it falls or never strikes).

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> r = return_map(wheel, np.array([0.08 - np.pi / 8, 1.0]))
    >>> round(float(r.x[0]), 12) == round(0.08 - np.pi / 8, 12), r.flags
    (True, ())
    """
    n2 = 2 * model.n
    x = np.array(x0, dtype=float)
    t = 0.0
    jac = mono = np.eye(n2) if linearize else np.zeros((0, 0))  # (D P, the monodromy)
    anchor = np.zeros(2)
    strikes: list[Strike] = []
    flags: list[str] = []
    if model.stance and getattr(model.mechanism, "support", None) is not None:
        f_n, cone = stance_margins(model, x, law.friction)
        if f_n < 0 or cone < 0:
            raise ReturnFailed("the stance foot cannot hold at the start")
    for _ in range(steps):
        leg = fly(model, x, t, t + MAX_PERIOD, variational=linearize, tolerance=tolerance,
                  friction=law.friction)  # fmt: skip
        if leg.guard is None:
            why = {"fall": "the model fell", "lift": "the stance foot would lift off",
                   "slip": "the stance foot would slip"}  # fmt: skip
            raise ReturnFailed(why.get(leg.ended, f"no strike within {MAX_PERIOD:g} s"))
        guard = leg.guard
        s = strike(model, guard, leg.x1, law)
        if guard.rows is not None and _comes_to_rest(model, guard, s.x_after):
            raise HeldContact(f"the strike at {leg.t1:g} s leaves {guard.name} closed, held "
                               "in the flow: periodic orbits through a held contact are not "
                               "built yet")  # fmt: skip
        if guard.moves_anchor:
            anchor = anchor + s.struck
        f_minus = tangent_flow(model, leg.x1)  # (in the tangent chart: the flow itself and
        grad = tangent_gradient(model, guard, leg.x1)  # the guard's gradient where nq == n)
        crossing = float(grad @ f_minus)
        # (|v| as sqrt(v . v), np.linalg.norm's own formula for a vector, without its dispatch)
        if abs(crossing) <= GRAZING * (math.sqrt(float(np.dot(grad, grad)))
                                       * math.sqrt(float(np.dot(f_minus, f_minus)))):  # fmt: skip
            flags.append("grazing")
        if linearize and "grazing" not in flags:
            assert leg.phi is not None
            dr = reset_jacobian(model, guard, leg.x1, law)
            jac = dr @ (np.eye(n2) - np.outer(f_minus, grad) / crossing) @ leg.phi @ jac
            mono = saltation_matrix(model, guard, s, law, reset=dr) @ leg.phi @ mono
        strikes.append(s)
        x, t = s.x_after, leg.t1
    lin = linearize and "grazing" not in flags
    return Return(x=x, period=t, strikes=tuple(strikes), jacobian=jac if lin else None,
                  monodromy=mono if lin else None, anchor=anchor,
                  flags=tuple(dict.fromkeys(flags)))  # fmt: skip


def _comes_to_rest(model: HybridModel, guard: Guard, x: np.ndarray) -> bool:
    """Whether the struck contact is at rest on its plane after the strike (``|G'|`` within
    ``AT_REST`` of the state's speed): the simulator holds it there."""
    rate = float(guard.gradient(x) @ model.mechanism.flow(x))
    return abs(rate) <= AT_REST * max(1.0, float(np.linalg.norm(x[model.nq :])))


def finite_difference_jacobian(model: HybridModel, x: np.ndarray, law: Law = PLASTIC, *,
                               steps: int = 1, step: float = FD_STEP) -> np.ndarray:  # fmt: skip
    """``D P`` by central differences of the return map (the second route), in the tangent
    chart (:func:`carnot.hybrid.model.tangent_step`; ``x + dx`` where ``nq == n``): column
    ``j`` is ``(P(x (+) h e_j) (-) P(x) - P(x (-) h e_j) (-) P(x)) / 2 h``, ``h = step max(1,
    |x_j|)`` (``|x_j|`` where the coordinate has its own value, as in
    :func:`carnot.hybrid.strike.reset_jacobian`)."""
    n, n2 = model.n, 2 * model.n
    base = return_map(model, x, law, steps=steps).x
    scale = np.abs(np.concatenate([x[: model.nq] if model.nq == n else np.zeros(n),
                                   x[model.nq :]]))  # fmt: skip
    out = np.zeros((n2, n2))
    for j in range(n2):
        h = step * max(1.0, float(scale[j]))
        dx = np.zeros(n2)
        dx[j] = h
        up = return_map(model, tangent_step(model, x, dx), law, steps=steps).x
        down = return_map(model, tangent_step(model, x, -dx), law, steps=steps).x
        out[:, j] = (tangent_difference(model, base, up)
                     - tangent_difference(model, base, down)) / (2 * h)  # fmt: skip
    return out


def floquet_multipliers(monodromy: np.ndarray) -> np.ndarray:
    """The monodromy's eigenvalues less the one nearest 1 (the flow's own direction),
    largest modulus first."""
    eig = np.linalg.eigvals(monodromy)
    trivial = int(np.argmin(np.abs(eig - 1.0)))
    rest = np.delete(eig, trivial)
    return rest[np.argsort(-np.abs(rest), kind="stable")]


@dataclass(frozen=True, kw_only=True, eq=False)
class Cycle:
    """A periodic orbit, or the attempt: ``state`` on the section, ``period``, ``multipliers``
    (complex, ``None`` if grazing), ``stable``, ``residual`` |P(x) - x|, ``converged``,
    ``iterations``, the strikes of one period, ``energy`` (``impacts``: their E_d;
    ``potential_drop``: the potential energy lost over the period, J), ``steps`` and
    ``flags``."""

    model: HybridModel
    law: Law
    state: np.ndarray
    period: float
    multipliers: np.ndarray | None
    stable: bool | None
    residual: float
    converged: bool
    iterations: int
    strikes: tuple[Strike, ...]
    energy: dict[str, float]
    steps: int
    flags: tuple[str, ...]
    monodromy: np.ndarray | None


def find_cycle(model: HybridModel, guess: np.ndarray, law: Law = PLASTIC, *, steps: int = 1,
               tolerance: float = 1e-11) -> Cycle:  # fmt: skip
    """A periodic orbit through ``steps`` strikes, by Newton shooting from ``guess``.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> c = find_cycle(wheel, np.array([0.08 - np.pi / 8, 1.0]))
    >>> c.converged, c.stable, round(float(abs(c.multipliers[0])), 9)
    (True, True, 0.5)
    """
    require_velocity_chart(model, "periodic orbits")
    x = np.array(guess, dtype=float)
    n2 = 2 * model.n
    if x.shape != (n2,):
        raise ValueError(f"the guess must have {n2} entries")
    iterations = 0
    try:
        ret = return_map(model, x, law, steps=steps, linearize=True)
    except HeldContact:
        return _failed(model, law, x, steps, np.inf, 0, ("held_contact",))
    except ReturnFailed:
        return _failed(model, law, x, steps, np.inf, 0)
    residual = float(np.linalg.norm(ret.x - x))
    while iterations < MAX_NEWTON:
        if residual <= tolerance * max(1.0, float(np.linalg.norm(x))) or ret.jacobian is None:
            break
        iterations += 1
        dx = np.linalg.solve(ret.jacobian - np.eye(n2), -(ret.x - x))
        alpha = 1.0
        for _ in range(MAX_HALVINGS):
            trial = x + alpha * dx
            try:
                new = return_map(model, trial, law, steps=steps, linearize=True)
            except ReturnFailed:
                alpha /= 2
                continue
            new_residual = float(np.linalg.norm(new.x - trial))
            if new_residual < residual:
                x, ret, residual = trial, new, new_residual
                break
            alpha /= 2
        else:
            break  # no step lowers the residual: not converged
    converged = residual <= tolerance * max(1.0, float(np.linalg.norm(x)))
    scale = model.kinetic(guess) + abs(model.energy(guess, np.zeros(2)))
    if converged and model.kinetic(x) <= AT_REST_ORBIT * max(scale, 1e-300):
        # Newton went to the state of rest (a pendulum hanging on its stop), not to a motion
        return _failed(model, law, x, steps, residual, iterations, ("equilibrium",))
    mult = floquet_multipliers(ret.monodromy) if ret.monodromy is not None else None
    stable = None if mult is None or not converged else bool(np.all(np.abs(mult) < 1.0))
    impacts = float(sum(s.result.energy.dissipated for s in ret.strikes))
    drop = float(model.total_mass * model.gravity @ ret.anchor)
    flags = ret.flags + (() if converged else ("not_converged",))
    if converged and ret.monodromy is not None:
        eig = np.linalg.eigvals(ret.monodromy)
        if np.min(np.abs(eig - 1.0)) > TRIVIAL:  # the flow's own multiplier is missing
            flags += ("trivial_multiplier",)
    return Cycle(model=model, law=law, state=x, period=ret.period, multipliers=mult,
                 stable=stable, residual=residual, converged=converged, iterations=iterations,
                 strikes=ret.strikes, energy={"impacts": impacts, "potential_drop": drop},
                 steps=steps, flags=flags, monodromy=ret.monodromy)  # fmt: skip


def _failed(model: HybridModel, law: Law, x: np.ndarray, steps: int, residual: float,
            iterations: int, why: tuple[str, ...] = ("no_return",)) -> Cycle:  # fmt: skip
    return Cycle(model=model, law=law, state=x, period=float("nan"), multipliers=None,
                 stable=None, residual=residual, converged=False, iterations=iterations,
                 strikes=(), energy={"impacts": float("nan"), "potential_drop": float("nan")},
                 steps=steps, flags=("not_converged", *why), monodromy=None)  # fmt: skip


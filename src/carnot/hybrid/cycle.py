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

**Through held contacts.** Where the model has contacts the simulator holds (an MJCF
model's geoms, a point on a plane; ``nq == n``: :func:`holds_contacts`), ``P`` is the
simulator's own run from the section to the period's last strike (:func:`carnot.hybrid.
simulate.simulate` with ``strikes`` and ``linearize``): its holds start, change and release
by the one logic, and its linearization carries the held legs' ``Phi`` (the held field's
Jacobian by central differences, :func:`carnot.hybrid.flow.held_flow_jacobian`) and the
saltation matrices of the strikes with the held fields on each side and of the holds'
changes. The section is then the held contacts' manifold and the orbit may return up to a
declared symmetry (``shift``, ``cyclic``): :mod:`carnot.hybrid.section`; Newton steps and
the multipliers are taken in the section's tangent space, and :func:`section_jacobian` is
the second route there.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from carnot.hybrid.flow import TOLERANCE, Hold, fly, stance_margins
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
from carnot.hybrid.section import (
    CYCLIC_TOLERANCE,
    Symmetry,
    on_section,
    residual,
    symmetry,
    tangent_basis,
)
from carnot.hybrid.simulate import GRAZING, HybridRun, saltation_matrix, simulate
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
    """A strike left its contact closed and at rest, held in the flow, on a model whose
    return map is built on the free flow (one with no contact that can be held: the
    free route never meets it; kept for callers that catch it)."""


@dataclass(frozen=True, kw_only=True, eq=False)
class Return:
    """One return: the state ``x`` after ``steps`` strikes, the ``period`` (s), the strikes,
    ``jacobian`` D P and ``monodromy`` (with ``linearize``), and ``anchor`` (how far the
    chart's origin moved, m) and ``flags`` (``grazing``, or a strike's own); ``run``: the
    simulator's run, where the return went through held contacts (:func:`return_map`)."""

    x: np.ndarray
    period: float
    strikes: tuple[Strike, ...]
    jacobian: np.ndarray | None
    monodromy: np.ndarray | None
    anchor: np.ndarray
    flags: tuple[str, ...]
    run: HybridRun | None = None


def return_map(model: HybridModel, x0: np.ndarray, law: Law = PLASTIC, *, steps: int = 1,
               linearize: bool = False, tolerance: float = TOLERANCE,
               max_period: float = MAX_PERIOD) -> Return:  # fmt: skip
    """Flow from ``x0`` through ``steps`` strikes (ReturnFailed if it falls or never strikes
    within ``max_period``, s). Where the model has contacts the simulator holds
    (:func:`holds_contacts`), the flow is the simulator's run, holds and all.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> r = return_map(wheel, np.array([0.08 - np.pi / 8, 1.0]))
    >>> round(float(r.x[0]), 12) == round(0.08 - np.pi / 8, 12), r.flags
    (True, ())
    """
    if holds_contacts(model):
        return _held_return(model, x0, law, steps, linearize, tolerance, max_period)
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
        leg = fly(model, x, t, t + max_period, variational=linearize, tolerance=tolerance,
                  friction=law.friction)  # fmt: skip
        if leg.guard is None:
            why = {"fall": "the model fell", "lift": "the stance foot would lift off",
                   "slip": "the stance foot would slip"}  # fmt: skip
            raise ReturnFailed(why.get(leg.ended, f"no strike within {max_period:g} s"))
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


def holds_contacts(model: HybridModel) -> bool:
    """Whether the model has contacts that the simulator can hold in the flow (guards with
    ``rows``: a point on a plane, a pair of MJCF geoms) and positions that pair with its
    velocities (``nq == n``: the held flow's linearization is built there): its return map
    is then the simulator's run (:func:`_held_return`). A model with a free or ball joint
    keeps the free flow's return map, which raises :class:`HeldContact` where a strike
    leaves a contact held."""
    return model.nq == model.n and any(g.rows is not None for g in model.guards)


#: Why a run from the section did not come back to it, by its end.
_NO_RETURN = {"fall": "the model fell", "rest": "the model came to rest",
              "max_strikes": "too many strikes"}  # fmt: skip


def _held_return(model: HybridModel, x0: np.ndarray, law: Law, steps: int, linearize: bool,
                 tolerance: float, max_period: float) -> Return:  # fmt: skip
    """The return through held contacts: the simulator's own run from ``x0`` until its
    ``steps``-th strike (:func:`carnot.hybrid.simulate.simulate` with ``strikes``), its holds
    started, changed and released as in any run, and with ``linearize`` its ``jacobian`` and
    ``monodromy`` (the held legs' ``Phi``, the saltation matrices of the strikes with the
    held fields on each side and of the holds' changes)."""
    run = simulate(model, x0, max_period, law, strikes=steps, linearize=linearize,
                   tolerance=tolerance)  # fmt: skip
    if run.ended != "strikes":
        last = run.events[-1].flags if run.events else ()
        why = _NO_RETURN.get(run.ended, f"no strike within {max_period:g} s")
        if run.ended == "stop":
            why = f"the run stopped ({', '.join(last) or 'stop'})"
        raise ReturnFailed(why)
    strikes = tuple(e.strike for e in run.events if e.kind == "impact" and e.strike is not None)
    return Return(x=run.final, period=run.time, strikes=strikes, jacobian=run.jacobian,
                  monodromy=run.monodromy, anchor=run.anchor, flags=run.flags,
                  run=run)  # fmt: skip


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
    symmetry: Symmetry | None = None
    advance: dict[str, float] = field(default_factory=dict)
    basis: np.ndarray | None = None
    jacobian: np.ndarray | None = None


def find_cycle(model: HybridModel, guess: np.ndarray, law: Law = PLASTIC, *, steps: int = 1,
               tolerance: float = 1e-11, shift: Mapping[str, float] | None = None,
               cyclic: Sequence[str] = (), max_period: float = MAX_PERIOD) -> Cycle:  # fmt: skip
    """A periodic orbit through ``steps`` strikes, by Newton shooting from ``guess``.

    ``shift`` and ``cyclic`` declare the symmetry the period returns up to (coordinates by
    name: :mod:`carnot.hybrid.section`): ``P(x) = x + s``, the cyclic coordinates' positions
    left free (their change over the period reported as ``advance``). Where the model has
    contacts that can be held (an MJCF model's geoms, a point on a plane), the return is the
    simulator's run (:func:`return_map`), the guess is put on the section (the contacts near
    closing closed and at rest: :func:`carnot.hybrid.section.on_section`), each Newton step
    is taken in the section's tangent space (``basis``, less the cyclic directions:
    :func:`carnot.hybrid.section.tangent_basis`), and the multipliers are the eigenvalues of
    the monodromy restricted there, less the flow's own. ``max_period`` (s): the longest a
    return may take.

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
    sym = symmetry(model, shift, cyclic)
    held = holds_contacts(model)
    restricted = held or sym.given  # Newton in a subspace: the section's, less the cyclic
    keep = [k for k in range(n2) if k not in sym.cyclic]

    def size(y: np.ndarray) -> float:
        return max(1.0, float(np.linalg.norm(y[keep])))

    holds: tuple[Hold, ...] = ()
    if held:
        try:
            x, holds = on_section(model, x, law)
        except ValueError as err:
            from carnot.errors import InputError

            raise InputError("guess", str(err), show_value=False) from None
    iterations = 0
    try:
        if held:  # (a run that never returns fails here, before its linearization's cost)
            return_map(model, x, law, steps=steps, max_period=max_period)
        ret = return_map(model, x, law, steps=steps, linearize=True, max_period=max_period)
    except HeldContact:
        return _failed(model, law, x, steps, np.inf, 0, ("held_contact",))
    except ReturnFailed:
        return _failed(model, law, x, steps, np.inf, 0)
    if sym.cyclic and ret.jacobian is not None:
        _check_cyclic(model, sym, ret.jacobian)
    basis = tangent_basis(model, x, holds, law, sym) if restricted else np.eye(n2)
    r = residual(model, sym, x, ret.x)
    res = float(np.linalg.norm(r))
    while iterations < MAX_NEWTON:
        if res <= tolerance * size(x) or ret.jacobian is None:
            break
        iterations += 1
        if restricted:  # the step in the section's tangent space
            reduced = basis.T @ (ret.jacobian - np.eye(n2)) @ basis
            dx = basis @ np.linalg.solve(reduced, -(basis.T @ r))
        else:
            dx = np.linalg.solve(ret.jacobian - np.eye(n2), -r)
        alpha = 1.0
        for _ in range(MAX_HALVINGS):
            trial, trial_holds = x + alpha * dx, holds
            try:
                if held:
                    trial, trial_holds = on_section(model, trial, law)
                # (through held contacts a trial's return is taken without its
                # linearization, a tenth of the cost, and linearized once accepted)
                new = return_map(model, trial, law, steps=steps, linearize=not held,
                                 max_period=max_period)  # fmt: skip
                new_r = residual(model, sym, trial, new.x)
                new_res = float(np.linalg.norm(new_r))
                if new_res < res and held:
                    new = return_map(model, trial, law, steps=steps, linearize=True,
                                     max_period=max_period)  # fmt: skip
            except (ReturnFailed, ValueError):
                alpha /= 2
                continue
            if new_res < res:
                x, ret, r, res, holds = trial, new, new_r, new_res, trial_holds
                if held:
                    basis = tangent_basis(model, x, holds, law, sym)
                break
            alpha /= 2
        else:
            break  # no step lowers the residual: not converged
    converged = res <= tolerance * size(x)
    scale = model.kinetic(guess) + abs(model.energy(guess, np.zeros(2)))
    if converged and model.kinetic(x) <= AT_REST_ORBIT * max(scale, 1e-300):
        # Newton went to the state of rest (a pendulum hanging on its stop), not to a motion
        return _failed(model, law, x, steps, res, iterations, ("equilibrium",))
    monodromy = ret.monodromy
    on_basis = None if monodromy is None else (basis.T @ monodromy @ basis if restricted
                                                else monodromy)  # fmt: skip
    mult = floquet_multipliers(on_basis) if on_basis is not None else None
    stable = None if mult is None or not converged else bool(np.all(np.abs(mult) < 1.0))
    if ret.run is not None or sym.given:  # V before less V after (the chart's origin moved)
        e = ret.run.energy if ret.run is not None else {}
        impacts = float(e.get("impacts", sum(s.result.energy.dissipated for s in ret.strikes)))
        drop = float((model.energy(x, np.zeros(2)) - model.kinetic(x))
                     - (model.energy(ret.x, ret.anchor) - model.kinetic(ret.x)))  # fmt: skip
        energy = {"impacts": impacts, "potential_drop": drop}
        energy.update({k: float(e[k]) for k in ("dampers", "sliding") if e.get(k)})
    else:
        impacts = float(sum(s.result.energy.dissipated for s in ret.strikes))
        drop = float(model.total_mass * model.gravity @ ret.anchor)
        energy = {"impacts": impacts, "potential_drop": drop}
    flags = ret.flags + (() if converged else ("not_converged",))
    if converged and on_basis is not None:
        eig = np.linalg.eigvals(on_basis)
        if np.min(np.abs(eig - 1.0)) > TRIVIAL:  # the flow's own multiplier is missing
            flags += ("trivial_multiplier",)
    advance = {sym.names[k]: float(ret.x[k] - x[k]) for k in sym.cyclic}
    return Cycle(model=model, law=law, state=x, period=ret.period, multipliers=mult,
                 stable=stable, residual=res, converged=converged, iterations=iterations,
                 strikes=ret.strikes, energy=energy, steps=steps, flags=flags,
                 monodromy=monodromy, symmetry=sym, advance=advance,
                 basis=basis if restricted else None, jacobian=ret.jacobian)  # fmt: skip


def _check_cyclic(model: HybridModel, sym: Symmetry, jacobian: np.ndarray) -> None:
    """Each cyclic coordinate's column of ``D P`` must be its unit vector (the return map
    does not depend on it: a shifted state returns shifted), else an InputError naming it."""
    for k in sym.cyclic:
        off = float(np.linalg.norm(jacobian[:, k] - np.eye(jacobian.shape[0])[k]))
        if off > CYCLIC_TOLERANCE:
            from carnot.errors import InputError

            raise InputError(f"cyclic {sym.names[k]!r}", "is not cyclic: the return map "
                             f"depends on it (|D P e - e| = {off:.3g}; shift it by a known "
                             "amount instead, or leave it out)", show_value=False)  # fmt: skip


def section_jacobian(cycle: Cycle, *, step: float = FD_STEP) -> np.ndarray:
    """``B^T D P B`` (d x d) by central differences of the return map along the section's
    tangent basis ``B`` (``cycle.basis``; the second route to the multipliers where the
    cycle went through held contacts or up to a symmetry): column ``i`` is ``B^T (P(x +
    h b_i) - P(x - h b_i)) / 2 h``, each state put on the section first
    (:func:`carnot.hybrid.section.on_section`), ``h = step max(1, |x|)``."""
    model, law, x, basis = cycle.model, cycle.law, cycle.state, cycle.basis
    if basis is None:
        raise ValueError("the cycle has no section basis: use finite_difference_jacobian")
    held = holds_contacts(model)
    h = step * max(1.0, float(np.linalg.norm(x)))

    def returned(y: np.ndarray) -> np.ndarray:
        if held:
            y = on_section(model, y, law)[0]
        return return_map(model, y, law, steps=cycle.steps).x

    cols = [(returned(x + h * b) - returned(x - h * b)) / (2 * h) for b in basis.T]
    return np.asarray(basis.T @ np.column_stack(cols))


def finite_difference_multipliers(cycle: Cycle, *, step: float = FD_STEP) -> np.ndarray:
    """The multipliers by central differences of the return map (the second route), largest
    modulus first: the eigenvalues of :func:`section_jacobian` less the one nearest 0 (the
    flow's direction, which ``D P`` maps to 0), or, for a cycle with no section basis,
    those of :func:`finite_difference_jacobian` less the smallest."""
    if cycle.basis is None:
        jac = finite_difference_jacobian(cycle.model, cycle.state, cycle.law, steps=cycle.steps,
                                         step=step)  # fmt: skip
        eig = np.linalg.eigvals(jac)
        return eig[np.argsort(-np.abs(eig), kind="stable")][: jac.shape[0] - 1]
    eig = np.linalg.eigvals(section_jacobian(cycle, step=step))
    eig = np.delete(eig, int(np.argmin(np.abs(eig))))
    return eig[np.argsort(-np.abs(eig), kind="stable")]


def _failed(model: HybridModel, law: Law, x: np.ndarray, steps: int, residual: float,
            iterations: int, why: tuple[str, ...] = ("no_return",)) -> Cycle:  # fmt: skip
    return Cycle(model=model, law=law, state=x, period=float("nan"), multipliers=None,
                 stable=None, residual=residual, converged=False, iterations=iterations,
                 strikes=(), energy={"impacts": float("nan"), "potential_drop": float("nan")},
                 steps=steps, flags=("not_converged", *why), monodromy=None)  # fmt: skip


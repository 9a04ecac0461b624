"""Solve an impact: model -> contact space -> laws -> outcome.

    u'' = u' + M^-1 W^T Lambda,     G = W M^-1 W^T

1. The model (free bodies: :mod:`carnot.model.free_bodies`) gives ``u'``, ``M`` and the rows
   ``W`` of every contact and constraint (:class:`carnot.space.ContactSpace`).
2. The laws (:mod:`carnot.laws`) see only contact space, in this order: given impulses;
   the one contact with Coulomb friction, integrated in impulse space with the held rows (pins)
   folded in by their Schur complement; then every equality row at once (restitution,
   sticking, fasten, pin), ``G Lambda = target(w') - W u_g`` with ``u_g`` after the impulses
   before it. When ``G`` is singular the rows are redundant: if the requirements are
   consistent the motion and ``E_d`` are still unique but the split of the impulse is not;
   carnot reports the minimum-norm ``Lambda`` (``G^+ b``) and says so in ``warnings``. Every
   item's rows are orthonormal in the metric ``|P|^2 + |M_P|^2 / L^2`` (model/contacts.py), so
   this is the split that minimises ``sum |P|^2 + |M_P|^2 / L^2``, whichever basis of the rows
   was used. Contradictory requirements are refused.
3. The outcome (:mod:`carnot.outcome`) reads contact space: impulses, each item's share of
   the theorem, the ledger against the direct kinetic-energy difference, and the flags; the
   model adds its own report (each body's motion, the momentum check).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from carnot.errors import ConstraintConflictError, InputError
from carnot.laws import (
    COULOMB,
    EQUALITY,
    LawParams,
    RowConflictError,
    check_supported,
    contact_rule,
)
from carnot.laws.registry import several_contacts
from carnot.model.contacts import Item, PointContact
from carnot.model.free_bodies import (
    FreeBodySpace,
    assemble,
    body_report,
    check_pins,
    momentum_check,
)
from carnot.model.problem import ImpactProblem
from carnot.model.system import (
    SystemProblem,
    assemble_system,
    check_system_pins,
    generalized_impulses,
)
from carnot.outcome import (
    energy_ledger,
    flag_energy_gain,
    item_outcomes,
    ledger_closes,
    ledger_flag,
)
from carnot.result import Flag, ImpactResult, StageOutcome, SystemMotion
from carnot.single import short_path, solve_single
from carnot.solvers.options import SolverOptions
from carnot.space import RANK_TOLERANCE, ContactSpace, Role

if TYPE_CHECKING:
    from carnot.several import Several


def solve_impact(
    problem: ImpactProblem | SystemProblem, solver: str | SolverOptions | None = None
) -> ImpactResult:
    """Solve ``problem`` and return the outcome with its energy ledger (a system in
    generalized coordinates: :func:`solve_system`). ``solver`` chooses the simultaneous
    law's solver for several contacts (``auto``, ``enumerate``, ``iterative``, or
    :class:`~carnot.solvers.SolverOptions` with its tolerance: DESIGN.md section 9) in place
    of the problem's own (``problem.solver``).

    >>> from carnot import RigidBody, FixedBody, PointContact, ImpactProblem
    >>> ball = RigidBody(mass=1.0, inertia_com=np.eye(3) * 0.004, velocity_com=[0, 0, -2.0],
    ...                  name="ball")
    >>> r = solve_impact(ImpactProblem(
    ...     bodies={"ball": ball, "floor": FixedBody(name="floor")},
    ...     contacts=[PointContact(a="ball", b="floor", point=[0, 0, -0.1], normal=[0, 0, 1],
    ...                            restitution=0.5)]))
    >>> r.bodies["ball"].velocity_after.tolist(), round(r.energy.dissipated, 12)
    ([0.0, 0.0, 1.0], 1.5)
    """
    if solver is not None:
        options = solver if isinstance(solver, SolverOptions) else SolverOptions(name=solver)
        problem = dataclasses.replace(problem, solver=options)
    if isinstance(problem, SystemProblem):
        return solve_system(problem)
    rule = short_path(problem)
    if rule is not None:
        result = solve_single(problem, rule)
        if result is not None:
            return result
    return solve_pipeline(problem)


def solve_pipeline(problem: ImpactProblem) -> ImpactResult:
    """:func:`solve_impact` for free bodies by the general route (module docstring), which
    every problem can take; :func:`solve_impact` takes :mod:`carnot.single`'s short path for
    one frictionless or sticking point contact, which gives the same result."""
    check_supported(
        problem.contacts,
        [k.where for k in problem.constraints if k.kind == "fasten"],
        problem.multiple_impact,
    )
    items: list[Item] = [*problem.contacts, *problem.constraints]
    fb = assemble(problem, items, [item.rows() for item in items])
    check_pins(problem, items, fb)
    flags: list[Flag] = []
    if several_contacts(problem.contacts):
        # imported here: the multiple-impact laws bring SciPy's linear algebra (0.2 s at
        # start-up), which one contact does not use
        from carnot.several import resolve_several

        impulses, several = resolve_several(items, fb.space, problem.multiple_impact, flags,
                                            problem.solver)  # fmt: skip
        return _result(problem, items, fb, impulses, {}, flags, several)
    impulses, processes = resolve_rows(items, fb.space, flags)
    return _result(problem, items, fb, impulses, processes, flags)


def _result(
    problem: ImpactProblem,
    items: list[Item],
    fb: FreeBodySpace,
    impulses: np.ndarray,
    processes: dict[int, Any],
    flags: list[Flag],
    several: Several | None = None,
) -> ImpactResult:
    """The outcome (module docstring, step 3) of the row ``impulses``."""
    space = fb.space
    u_after = space.u_before + space.velocity_change(impulses)
    states = None if several is None else several.states
    outcomes = item_outcomes(items, space, impulses, u_after, processes, flags, states)
    bodies, before, after = body_report(problem, fb, u_after)
    ledger = energy_ledger(space, impulses, u_after, outcomes, before=before, after=after)
    gain = flag_energy_gain(ledger, problem.contacts, processes)
    if not ledger_closes(ledger):
        flags.append(ledger_flag(ledger))
    alternatives: tuple[ImpactResult, ...] = ()
    stages: tuple[StageOutcome, ...] = ()
    if several is not None:
        alternatives = tuple(_result(problem, items, fb, other.impulses, {}, list(other.flags),
                                     other) for other in several.alternatives)  # fmt: skip
        stages = several.stages
    return ImpactResult(
        title=problem.title,
        bodies=bodies,
        contacts=tuple(o for o in outcomes if o.kind == "contact"),
        constraints=tuple(o for o in outcomes if o.kind != "contact"),
        energy=ledger,
        momentum=None,  # made when first read, as on the short path (ImpactResult)
        momentum_later=functools.partial(momentum_check, problem, fb, u_after, outcomes),
        warnings=(*flags, gain) if gain is not None else tuple(flags),
        row_impulses=impulses,
        multiple_impact=None if several is None else several.law,
        complementarity_residual=None if several is None else several.residual,
        solver=None if several is None else several.certificate,
        solver_groups=() if several is None else several.group_certificates,
        stages=stages,
        alternatives=alternatives,
    )


def resolve_rows(
    items: list[Item], space: ContactSpace, flags: list[Flag]
) -> tuple[np.ndarray, dict[int, Any]]:
    """The row impulses of every item by its law (module docstring, step 2), and the process
    records of integrated contacts by item index; ``statically_indeterminate`` is appended to
    ``flags`` when the equality rows are redundant."""
    u_before = space.u_before
    impulses = np.zeros(space.size)
    equality: list[int] = []
    roles: list[Role] = []
    restitution: list[float] = []
    frictional: int | None = None
    for index, (item, rows) in enumerate(zip(items, space.slices, strict=True)):
        if not isinstance(item, PointContact):
            rule = "bilateral"
        else:
            rule = contact_rule(tangential=item.tangential, friction=item.friction,
                                given=item.is_given)  # fmt: skip
        if rule == "given":
            impulses[rows] = item.given_row_impulses()  # type: ignore[union-attr]
        elif rule == "coulomb":
            frictional = index  # check_supported allows one, beside constraints
        else:
            equality.extend(range(rows.start, rows.stop))
            roles.extend(space.blocks[index].roles)
            e = item.restitution if isinstance(item, PointContact) else 0.0
            restitution.extend([e] * (rows.stop - rows.start))
    u_given = u_before + space.velocity_change(impulses)
    held = np.array(equality, dtype=int)
    processes: dict[int, Any] = {}
    if frictional is not None:
        contact = items[frictional]
        assert isinstance(contact, PointContact)
        rows = space.slices[frictional]
        k, w_c = space.held_schur(rows, held, u_given)
        # against the normal row's own scale: a tiny inertia's tangent rows (r^2/J) must not
        # make an ordinary normal inverse mass look like zero
        if not k[0, 0] > RANK_TOLERANCE * float(space.delassus(rows)[0, 0]):
            raise InputError(
                f"{contact.where}",
                "the constraints leave this contact no freedom along its normal (the effective "
                "inverse mass n . K n is 0): it can take no impulse",
                float(k[0, 0]),
            )
        params = LawParams(roles=space.blocks[frictional].roles, restitution=contact.restitution,
                           friction=contact.friction, hypothesis=contact.law)  # fmt: skip
        answer = COULOMB.resolve(*_unreached_tangents(k, w_c), params)
        processes[frictional] = answer.process
        impulses[rows] = answer.impulses  # rows (n, t1, t2): row impulses = frame components
        u_given = u_given + space.velocity_change(answer.impulses, rows)
    if held.size:
        # contiguous rows (the usual case) as a slice: views instead of copies
        rows_eq = slice(held[0], held[-1] + 1) if held[-1] - held[0] + 1 == held.size else held
        params = LawParams(roles=tuple(roles), restitution=np.array(restitution),
                           reference=space.row_velocities(u_before, rows_eq))  # fmt: skip
        try:
            answer = EQUALITY.resolve(
                space.delassus(rows_eq), space.row_velocities(u_given, rows_eq), params
            )
        except RowConflictError as conflict:
            names = list(dict.fromkeys(space.owner[held[r]] for r in conflict.rows))
            raise ConstraintConflictError(
                " and ".join(names),
                "these contacts and constraints contradict each other: no impulse gives the "
                "velocities they require (for instance a point fastened and also required to "
                "rebound); relative residual",
                conflict.residual,
            ) from None
        impulses[rows_eq] = answer.impulses
        if answer.redundant.any():
            redundant_rows = held[np.flatnonzero(answer.redundant)]
            redundant = list(dict.fromkeys(space.owner[r] for r in redundant_rows))
            flags.append(
                Flag(
                    code="statically_indeterminate",
                    where=", ".join(redundant),
                    message=(
                        f"the split of the impulse among {' and '.join(redundant)} is not "
                        "unique (redundant constraints); the motion and the dissipated energy "
                        "are; carnot reports the minimum-norm split"
                    ),
                )
            )
    return impulses, processes


def _unreached_tangents(k: np.ndarray, w_c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(K, w')`` of a frictional contact with a tangent direction ``d`` that no motion
    reaches (``K_tt d = 0``: a planar system's out-of-plane tangent) given a decoupled
    stand-in ``K_nn d d^T``: ``K`` is positive semi-definite, so ``K (0, d) = 0``; with
    ``w'.d = 0`` the slip never turns towards ``d`` and the sticking rate
    ``-K_tt^-1 K_tn`` has no part along it, so ``d`` takes no impulse (the minimum-norm
    choice: an impulse along ``d`` would move nothing) whatever the stand-in. Any other
    ``K`` is returned as it is."""
    k_tt = k[1:, 1:]
    eigval, eigvec = np.linalg.eigh(k_tt)
    if eigval[0] > RANK_TOLERANCE * float(np.trace(k)):
        return k, w_c
    d = np.concatenate([[0.0], eigvec[:, 0]])
    if eigval[1] <= RANK_TOLERANCE * float(np.trace(k)):
        return k, w_c  # no tangent is reached: the law meets a frictionless contact
    keep = np.eye(3) - np.outer(d, d)
    return keep @ k @ keep + float(k[0, 0]) * np.outer(d, d), keep @ w_c


def solve_system(problem: SystemProblem) -> ImpactResult:
    """Solve an impact of a system in generalized coordinates (:mod:`carnot.model.system`):
    the same law stage (:func:`resolve_rows`) and outcome as free bodies, with ``u = q'``;
    the ledger's direct route is ``E = 1/2 q'^T M q'`` before and after.

    A point mass (2 kg) in the plane, coordinates (x, y), lands at 1 m/s while sliding at
    1 m/s; it sticks (paper section 3.1): ``E_d = 1/2 m (1^2 + 1^2) = 2`` J.

    >>> from carnot.model.system import System, SystemContact
    >>> r = solve_system(SystemProblem(system=System(mass_matrix=np.eye(2) * 2,
    ...     velocity=[1.0, -1.0], coordinates=("x", "y")), contacts=[SystemContact(
    ...     jacobian=[[1, 0], [0, 1], [0, 0]], normal=[0, 1, 0], tangential="stick")]))
    >>> r.system.velocity_after.tolist(), r.energy.dissipated, r.warnings
    ([0.0, 0.0], 2.0, ())
    """
    items = problem.law_items
    contacts = [i for i in items if isinstance(i, PointContact)]
    check_supported(
        contacts,
        [k.where for k in items if not isinstance(k, PointContact) and k.kind == "fasten"],
        problem.multiple_impact,
    )
    space = assemble_system(problem)
    check_system_pins(problem, space)
    flags: list[Flag] = []
    if several_contacts(contacts):
        from carnot.several import resolve_several  # here: as in solve_pipeline

        impulses, several = resolve_several(items, space, problem.multiple_impact, flags,
                                            problem.solver)  # fmt: skip
        return _system_result(problem, space, impulses, {}, flags, several)
    impulses, processes = resolve_rows(items, space, flags)
    return _system_result(problem, space, impulses, processes, flags)


def _system_result(
    problem: SystemProblem,
    space: ContactSpace,
    impulses: np.ndarray,
    processes: dict[int, Any],
    flags: list[Flag],
    several: Several | None = None,
) -> ImpactResult:
    """The outcome of a system's row ``impulses`` (the same stage as free bodies', with the
    system's own report: ``q''``, generalized impulses, the generalized momentum balance)."""
    items = problem.law_items
    u_after = space.u_before + space.velocity_change(impulses)
    states = None if several is None else several.states
    outcomes = item_outcomes(items, space, impulses, u_after, processes, flags, states)
    system = problem.system
    gen = generalized_impulses(problem, [o.impulse for o in outcomes],
                               [o.moment for o in outcomes])  # fmt: skip
    # the system's fields (no b, J^T P, the item's name) on the outcomes just made
    outcomes = [o.in_system(g, item.name or "")
                for o, g, item in zip(outcomes, gen, problem.items, strict=True)]
    before, after = system.kinetic_energy(space.u_before), system.kinetic_energy(u_after)
    ledger = energy_ledger(space, impulses, u_after, outcomes, before=before, after=after)
    gain = flag_energy_gain(ledger, [i for i in items if isinstance(i, PointContact)], processes)
    if not ledger_closes(ledger):
        flags.append(ledger_flag(ledger))
    du = system.mass_matrix @ (u_after - space.u_before)
    total = np.sum(gen, axis=0)
    # |x| as sqrt(x . x): np.linalg.norm's own formula for a vector, without its checks
    momentum = system.mass_matrix @ space.u_before
    scale = math.sqrt(float(momentum @ momentum)) + sum(math.sqrt(float(g @ g)) for g in gen)
    q_after = np.array(u_after)
    q_after.setflags(write=False)
    alternatives: tuple[ImpactResult, ...] = ()
    if several is not None:
        alternatives = tuple(
            _system_result(problem, space, other.impulses, {}, list(other.flags), other)
            for other in several.alternatives
        )
    return ImpactResult(
        title=problem.title,
        bodies={},
        contacts=tuple(o for o in outcomes if o.kind == "contact"),
        constraints=tuple(o for o in outcomes if o.kind != "contact"),
        energy=ledger,
        momentum=None,
        warnings=(*flags, gain) if gain is not None else tuple(flags),
        row_impulses=impulses,
        system=SystemMotion(
            coordinates=system.coordinates, velocity_before=system.velocity,
            velocity_after=q_after,
            momentum_residual=float(np.linalg.norm(du - total)) / (scale + 1e-300),
        ),
        multiple_impact=None if several is None else several.law,
        complementarity_residual=None if several is None else several.residual,
        solver=None if several is None else several.certificate,
        solver_groups=() if several is None else several.group_certificates,
        stages=() if several is None else several.stages,
        alternatives=alternatives,
    )  # fmt: skip

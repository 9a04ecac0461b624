"""Several unilateral point contacts at once: the pipeline's law stage for them (DESIGN.md
section 6, issue 14).

The contacts' rows become one complementarity problem in contact space for the scenario's
multiple-impact law (:mod:`carnot.laws.multiple`): each point contact is a
:class:`~carnot.laws.multiple.ContactRows` (its normal row and, with friction or told to stick,
its tangent rows); pins and fastenings are held rows that end at rest; a contact over a surface
is held at its restitution target (every patch point at ``-e`` times its normal velocity, as
with one contact: the paper's surface impact); given impulses act first. The law's row
impulses, each contact's regime and whether it took part, its stages and its other outcomes
come back for the outcome stage, which reads them like any other impulses.

**Independent groups.** Contacts that share no degree of freedom (two balls on a floor far
apart) have a zero Delassus block, ``G_ij = W_i M^-1 W_j^T = 0``, so ``w'' = w' + G Lambda``
splits group by group and each group's impact is a problem of its own. The law is applied to
each group alone (:func:`independent_groups`; held rows go with the items they share
coordinates with; given impulses act on the whole problem first): the simultaneous law's
regimes are enumerated group by group (their count adds up, it no longer multiplies), and the
dispersion and sequential laws take their tolerances, stopping tests and orders of sub-impacts
from the group's own velocities, so a group's answer does not depend on what else is in the
scene. The answers are put together: impulses and contact states side by side, each flag
naming its group's contacts, the stages one group after the other (every contact listed in
each, zero outside the stage's group), the largest residual. A law with several outcomes
(``multiple_solutions``, ``sequential_tie``) gives ``alternatives`` group by group: each is
one group's other outcome with every other group at its first answer (the outcomes of the
whole scene are all their combinations; they are not listed). A problem of one group is solved
exactly as before, on the whole contact space.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from carnot.laws import target_velocity
from carnot.laws.multiple import (
    MULTIPLE_IMPACT_LAWS,
    Certificate,
    ContactRows,
    HeldRows,
    MultipleImpactOutcome,
    Stage,
    dissipated_by_row,
)
from carnot.model.contacts import Item, PointContact
from carnot.model.coupling import coupled_labels
from carnot.result import Flag, StageOutcome
from carnot.solvers.dispatch import resolve
from carnot.solvers.options import SolverOptions
from carnot.space import ContactSpace

#: What each flag of a multiple-impact law means, for people.
MESSAGES = {
    "statically_indeterminate": "the split of the impulse among the contacts is not unique; "
    "over its family the motion and the dissipated energy are the same (whether other "
    "motions hold too is the solver's `velocities_unique`)",
    "multiple_solutions": "the law has several outcomes with different motions: this one and "
    "those in `alternatives`",
    # multiple_solutions where no other outcome is listed: a regime whose family of impulses
    # moves the bodies differently (a continuum), or a group solved apart from the others
    "multiple_solutions_unlisted": "the law has several outcomes with different motions (a "
    "family of them where the impulses of this regime are not unique): this is one of them",
    "no_solution": "no impulse meets the law's conditions: the impulses are zero",
    "sequential_tie": "two contacts approach equally fast, so the order of the sub-impacts is "
    "not defined: this is the first order; `alternatives` holds the others",
    "stage_limit": "the sub-impacts did not end within the stage limit",
    "friction_too_small_to_stick": "a contact told to stick needs more friction than given",
    "separating_contact_approaches": "a contact separating before the impact (so taking no "
    "part) is made to approach by the others' impulses: the bodies would interpenetrate there",
    "not_converged": "the iterative solver stopped short of its tolerance: the answer meets "
    "the law only to the residual in `solver`",
}


@dataclass(frozen=True, kw_only=True, eq=False)
class Several:
    """A multiple-impact law's answer mapped back to the problem's rows and items."""

    law: str
    impulses: np.ndarray
    states: dict[int, tuple[str, bool]]
    residual: float
    flags: tuple[Flag, ...] = ()
    stages: tuple[StageOutcome, ...] = ()
    alternatives: tuple[Several, ...] = field(default=())
    #: the simultaneous law's certificate (every group's, combined: :func:`combined_certificate`)
    certificate: Certificate | None = None
    #: each group's certificate and its contacts, where there are several groups
    group_certificates: tuple[tuple[tuple[str, ...], Certificate], ...] = ()


def resolve_several(
    items: Sequence[Item], space: ContactSpace, law: str, flags: list[Flag],
    solver: SolverOptions | None = None,
) -> tuple[np.ndarray, Several]:
    """Row impulses of every item by the multiple-impact ``law`` (its flags appended to
    ``flags``), and the law's answer for the outcome stage.

    Given impulses act first; the other items are split into their independent groups
    (:func:`independent_groups`) and the law solves each group alone (module docstring), the
    simultaneous law by the solver ``solver`` names (:mod:`carnot.solvers`)."""
    impulses = np.zeros(space.size)
    taking: list[int] = []
    for index, item in enumerate(items):
        if isinstance(item, PointContact) and item.is_given:
            impulses[space.slices[index]] = item.given_row_impulses()
        else:
            taking.append(index)
    w_before = space.row_velocities(space.u_before)
    u_given = space.u_before + space.velocity_change(impulses)
    groups = independent_groups(space, taking) or ((),)  # nothing for the law: as before
    solved = [_solve_group(items, space, law, group, w_before, u_given, solver)
              for group in groups]  # fmt: skip
    if len(solved) == 1:  # one group: the law on the whole contact space, as it always was
        several = _mapped(solved[0].answer, items, space, impulses, solved[0].rows,
                          solved[0].owners)  # fmt: skip
    else:
        several = _assembled(solved, items, space, impulses)
    flags.extend(several.flags)
    return several.impulses, several


def independent_groups(space: ContactSpace, indices: Sequence[int]) -> tuple[tuple[int, ...], ...]:
    """The items ``indices`` (blocks of ``space``) in independent groups, in the order of their
    first item: items ``i`` and ``j`` are in one group when a chain of items joins them, each
    link a Delassus block ``G_ij = W_i M^-1 W_j^T`` that is not structurally zero (the rows'
    nonzero columns meet one block of ``M^-1``: :func:`carnot.model.coupling.coupled_labels`).
    Across groups ``G`` is zero, exact zeros not small values, so each group's impact is a
    problem of its own.

    Two balls, each on the floor (one normal row each): two groups; a contact between them
    joins them.

    >>> from carnot.space import RowBlock
    >>> def row(where):
    ...     return RowBlock(where=where, point=np.zeros(3), linear=np.array([[0, 0, 1.0]]),
    ...                     angular=np.zeros((1, 3)), roles=("normal",))
    >>> blocks = (row("floor-A"), row("floor-B"), row("A-B"))
    >>> jacobian = np.array([[0, 0, 1.0, 0, 0, 0], [0, 0, 0, 0, 0, 1.0], [0, 0, 1.0, 0, 0, -1]])
    >>> space = ContactSpace(u_before=np.zeros(6), mass_matrix=np.eye(6),
    ...                      mass_matrix_inv=np.eye(6), motion=np.zeros((18, 6)),
    ...                      blocks=blocks, jacobian=jacobian)
    >>> independent_groups(space, [0, 1]), independent_groups(space, [0, 1, 2])
    (((0,), (1,)), ((0, 1, 2),))
    """
    n = space.mass_matrix.shape[0]
    if space.is_sparse:  # each block's nonzero columns: a block-by-row indicator times |W| > 0
        sizes = [block.size for block in space.blocks]
        owner = np.repeat(np.arange(len(sizes)), sizes)
        indicator = sp.csr_matrix((np.ones(space.size), (owner, np.arange(space.size))),
                                  shape=(len(sizes), space.size))  # fmt: skip
        pattern = indicator @ (abs(space.jacobian) > 0).astype(float)
        moved = pattern[list(indices)] > 0.0  # sparse: coupled_labels takes it so
    elif space.size and n and all(block.size for block in space.blocks):
        starts = [s.start for s in space.slices]  # each block's nonzero columns at once
        moved = np.logical_or.reduceat(space.jacobian != 0.0, starts, axis=0)[list(indices)]
    else:
        moved = np.zeros((len(space.blocks), n), dtype=bool)[list(indices)]
        for k, i in enumerate(indices):
            moved[k] = np.any(space.jacobian[space.slices[i]] != 0.0, axis=0)
    if not space.is_sparse:
        moved = moved.reshape(len(indices), n)
    labels = coupled_labels(moved, space.mass_matrix).tolist()
    groups: dict[int, list[int]] = {}
    for index, label in zip(indices, labels, strict=True):
        groups.setdefault(label, []).append(int(index))
    return tuple(tuple(group) for group in groups.values())


@dataclass(frozen=True, kw_only=True, eq=False)
class _Group:
    """One independent group's law answer, its rows in ``space`` and its contacts' items."""

    answer: MultipleImpactOutcome
    rows: np.ndarray
    owners: list[int]
    items: tuple[int, ...]


def _solve_group(
    items: Sequence[Item],
    space: ContactSpace,
    law: str,
    group_items: Sequence[int],
    w_before: np.ndarray,
    u_given: np.ndarray,
    solver: SolverOptions | None = None,
) -> _Group:
    """The law on one group's rows: its contacts, and its held rows at their targets."""
    group: list[int] = []
    contacts: list[ContactRows] = []
    owners: list[int] = []
    held_rows: list[int] = []
    held_target: list[float] = []
    for index in group_items:
        item, rows, block = items[index], space.slices[index], space.blocks[index]
        local = list(range(len(group), len(group) + block.size))
        group.extend(range(rows.start, rows.stop))
        if isinstance(item, PointContact) and item.patch is None:
            # (the contact's own checked numbers: ContactRows' checks again were a twentieth
            # of a 4-corner landing's solve)
            contacts.append(ContactRows.of_contact(item, normal=local[0],
                                                   tangents=tuple(local[1:])))  # fmt: skip
            owners.append(index)
            continue
        e = item.restitution if isinstance(item, PointContact) else 0.0
        held_rows.extend(local)
        held_target.extend(target_velocity(w_before[rows], block.roles, e).tolist())
    rows_ = np.array(group, dtype=int)
    held = HeldRows(rows=tuple(held_rows), target=tuple(held_target)) if held_rows else None
    law_of: Callable[..., MultipleImpactOutcome] = MULTIPLE_IMPACT_LAWS[law]
    # every row in order (one group, the usual case): the whole space, no rows picked (the
    # same products of the same numbers)
    every = group == list(range(space.size))
    # (many bodies: the simultaneous law's solvers take G sparse)
    sparse = law == "simultaneous" and space.is_sparse
    g = (space.delassus_sparse if sparse else space.delassus)(None if every else rows_)
    w = space.row_velocities(u_given, None if every else rows_)
    if law == "simultaneous":
        answer = resolve(g, w, contacts, held, solver)
    else:
        answer = law_of(g, w, contacts, held)
    return _Group(answer=answer, rows=rows_, owners=owners, items=tuple(group_items))


def _assembled(
    solved: Sequence[_Group], items: Sequence[Item], space: ContactSpace, given: np.ndarray
) -> Several:
    """The groups' answers as one (module docstring): impulses, states, flags (each naming
    its group's contacts), stages one group after the other, the largest residual; the
    alternatives of each group that has some, the other groups at their answers."""
    primary = _combined([g.answer for g in solved], solved, items, space, given)
    alternatives: list[Several] = []
    seen: set[tuple[bytes, tuple[tuple[str, ...], ...]]] = set()
    for k, group in enumerate(solved):
        for other in group.answer.alternatives:
            answers = [g.answer for g in solved]
            answers[k] = other
            combined = _combined(answers, solved, items, space, given)
            key = (combined.impulses.tobytes(), tuple(st.contacts for st in combined.stages))
            if key in seen:
                continue  # the primary, listed again by a second group (the sequential law
                # lists its primary among its alternatives)
            seen.add(key)
            alternatives.append(combined)
    groups = tuple((tuple(items[i].where for i in (g.owners or g.items)), g.answer.certificate)
                   for g in solved if g.answer.certificate is not None)  # fmt: skip
    return Several(law=primary.law, impulses=primary.impulses, states=primary.states,
                   residual=primary.residual, flags=primary.flags, stages=primary.stages,
                   alternatives=tuple(alternatives),
                   certificate=combined_certificate([c for _, c in groups]),
                   group_certificates=groups)  # fmt: skip


def combined_certificate(certificates: Sequence[Certificate]) -> Certificate | None:
    """The certificates of independent groups as one: the largest residual, the iterations
    added up, unique where every group is (false where one is not, unverified otherwise),
    the solver's name where all groups had the same one (``mixed`` otherwise), the ranges of
    E_d added up (the groups' answers combine freely; unknown where one group's is).

    >>> a = Certificate(solver="enumerate", requested="auto", residual=1e-16, iterations=1,
    ...                 unique=True, velocities_unique=True)
    >>> b = Certificate(solver="iterative", requested="auto", residual=3e-15, iterations=9,
    ...                 unique=None, velocities_unique=True)
    >>> c = combined_certificate([a, b])
    >>> c.solver, c.residual, c.iterations, c.unique, c.velocities_unique
    ('mixed', 3e-15, 10, None, True)
    """
    if not certificates:
        return None

    def all_of(values: list[bool | None]) -> bool | None:
        if any(v is False for v in values):
            return False
        return True if all(v is True for v in values) else None

    names = {c.solver for c in certificates}
    spans = [c.dissipated_range for c in certificates]
    # a group whose range is known brackets itself exactly; all known: no brackets needed
    brackets = [c.dissipated_bounds if c.dissipated_range is None else (
        (c.dissipated_range[0],) * 2, (c.dissipated_range[1],) * 2) for c in certificates]
    return Certificate(
        solver=names.pop() if len(names) == 1 else "mixed",
        requested=certificates[0].requested,
        residual=max(c.residual for c in certificates),
        iterations=sum(c.iterations for c in certificates),
        unique=all_of([c.unique for c in certificates]),
        velocities_unique=all_of([c.velocities_unique for c in certificates]),
        converged=all(c.converged for c in certificates),
        # the groups' E_d add up, each within its own range
        dissipated_range=None if any(s is None for s in spans) else (
            sum(s[0] for s in spans if s is not None),
            sum(s[1] for s in spans if s is not None)),
        dissipated_bounds=None if all(s is not None for s in spans) or any(
            b is None for b in brackets) else tuple(  # type: ignore[arg-type]
                tuple(sum(b[end][k] for b in brackets if b is not None) for k in (0, 1))
                for end in (0, 1)))  # fmt: skip


def _combined(
    answers: Sequence[MultipleImpactOutcome],
    solved: Sequence[_Group],
    items: Sequence[Item],
    space: ContactSpace,
    given: np.ndarray,
) -> Several:
    """One answer per group (``answers``, in ``solved``'s order) as one answer."""
    impulses = given.copy()
    states: dict[int, tuple[str, bool]] = {}
    flags: list[Flag] = []
    stages: list[StageOutcome] = []
    listed = [i for g in solved for i in g.owners]
    for answer, group in zip(answers, solved, strict=True):
        impulses[group.rows] += answer.impulses
        states.update({group.owners[k]: (str(c.regime), c.active)
                       for k, c in enumerate(answer.contacts)})  # fmt: skip
        where = ", ".join(items[i].where for i in (group.owners or group.items))
        flags.extend(_flag(code, where, ()) for code in answer.flags)  # not carried
        for stage in answer.stages:
            stages.append(_stage(stage, items, space, group.rows, group.owners, listed,
                                 len(stages)))  # fmt: skip
    return Several(law=answers[0].law, impulses=impulses, states=states,
                   residual=max(a.residual for a in answers), flags=tuple(flags),
                   stages=tuple(stages))  # fmt: skip


def _flag(code: str, where: str, alternatives: Sequence[object]) -> Flag:
    """The flag ``code`` at ``where``, its message saying whether ``alternatives`` lists the
    other outcomes (it points to them only where it does)."""
    key = code
    if code == "multiple_solutions" and not alternatives:
        key = "multiple_solutions_unlisted"
    return Flag(code=code, where=where, message=MESSAGES.get(key, code))


def _mapped(
    answer: MultipleImpactOutcome,
    items: Sequence[Item],
    space: ContactSpace,
    given: np.ndarray,
    rows: np.ndarray,
    owners: list[int],
) -> Several:
    impulses = given.copy()
    impulses[rows] += answer.impulses
    states: dict[int, tuple[str, bool]] = {
        owners[k]: (str(c.regime), c.active) for k, c in enumerate(answer.contacts)
    }
    where = ", ".join(items[i].where for i in owners)
    flags = tuple(_flag(code, where, answer.alternatives) for code in answer.flags)
    stages = tuple(_stage(stage, items, space, rows, owners) for stage in answer.stages)
    alternatives = tuple(_mapped(other, items, space, given, rows, owners)
                         for other in answer.alternatives)  # fmt: skip
    return Several(law=answer.law, impulses=impulses, states=states, residual=answer.residual,
                   flags=flags, stages=stages, alternatives=alternatives,
                   certificate=answer.certificate)  # fmt: skip


def _stage(
    stage: Stage, items: Sequence[Item], space: ContactSpace, rows: np.ndarray,
    owners: list[int], listed: list[int] | None = None, offset: int | None = None,
) -> StageOutcome:  # fmt: skip
    """A sub-impact or phase, per contact: impulse (world) and share of the theorem.

    ``owners`` are the items of the law's contacts (``stage.contacts`` index them),
    ``listed`` the contacts reported (all the problem's: those of the other groups with
    zero), ``offset`` the stage's index among every group's stages."""
    lam = np.zeros(space.size)
    lam[rows] = stage.impulses
    by_row = np.zeros(space.size)
    by_row[rows] = dissipated_by_row(stage.impulses, stage.w_before, stage.w_after)
    impulses = {}
    shares = {}
    acting = tuple(items[owners[k]].where for k in stage.contacts)
    for i in owners if listed is None else listed:
        s = space.slices[i]
        impulses[items[i].where] = space.blocks[i].linear.T @ lam[s]
        shares[items[i].where] = float(np.sum(by_row[s]))
    index = stage.index if offset is None else offset
    return StageOutcome(index=index, description=stage.description,
                        contacts=acting, impulses=impulses, dissipated_by_contact=shares,
                        dissipated=float(np.sum(by_row)))  # fmt: skip

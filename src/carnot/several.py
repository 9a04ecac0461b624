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
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from carnot.laws import target_velocity
from carnot.laws.multiple import (
    MULTIPLE_IMPACT_LAWS,
    ContactRows,
    HeldRows,
    MultipleImpactOutcome,
    Stage,
    dissipated_by_row,
)
from carnot.model.contacts import Item, PointContact
from carnot.result import Flag, StageOutcome
from carnot.space import ContactSpace

#: What each flag of a multiple-impact law means, for people.
MESSAGES = {
    "statically_indeterminate": "the split of the impulse among the contacts is not unique; "
    "the motion and the dissipated energy are",
    "multiple_solutions": "the law has several outcomes with different motions: this one and "
    "those in `alternatives`",
    "no_solution": "no impulse meets the law's conditions: the impulses are zero",
    "sequential_tie": "two contacts approach equally fast, so the order of the sub-impacts is "
    "not defined: this is the first order; `alternatives` holds the others",
    "stage_limit": "the sub-impacts did not end within the stage limit",
    "friction_too_small_to_stick": "a contact told to stick needs more friction than given",
    "separating_contact_approaches": "a contact separating before the impact (so taking no "
    "part) is made to approach by the others' impulses: the bodies would interpenetrate there",
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


def resolve_several(
    items: Sequence[Item], space: ContactSpace, law: str, flags: list[Flag]
) -> tuple[np.ndarray, Several]:
    """Row impulses of every item by the multiple-impact ``law`` (its flags appended to
    ``flags``), and the law's answer for the outcome stage."""
    impulses = np.zeros(space.size)
    group: list[int] = []
    contacts: list[ContactRows] = []
    owners: list[int] = []
    held_rows: list[int] = []
    held_target: list[float] = []
    w_before = space.row_velocities(space.u_before)
    for index, (item, rows) in enumerate(zip(items, space.slices, strict=True)):
        block = space.blocks[index]
        local = list(range(len(group), len(group) + block.size))
        if isinstance(item, PointContact) and item.is_given:
            impulses[rows] = item.given_row_impulses()
            continue
        group.extend(range(rows.start, rows.stop))
        if isinstance(item, PointContact) and item.patch is None:
            contacts.append(ContactRows(
                normal=local[0], tangents=tuple(local[1:]), restitution=item.restitution,
                friction=item.friction, stick=item.sticks, stiffness=item.stiffness,
                exponent=item.exponent, name=item.name or item.where,
            ))  # fmt: skip
            owners.append(index)
            continue
        e = item.restitution if isinstance(item, PointContact) else 0.0
        held_rows.extend(local)
        held_target.extend(target_velocity(w_before[rows], block.roles, e).tolist())
    rows_ = np.array(group, dtype=int)
    u_given = space.u_before + space.velocity_change(impulses)
    held = HeldRows(rows=tuple(held_rows), target=tuple(held_target)) if held_rows else None
    resolve: Callable[..., MultipleImpactOutcome] = MULTIPLE_IMPACT_LAWS[law]
    answer = resolve(space.delassus(rows_), space.row_velocities(u_given, rows_), contacts, held)
    several = _mapped(answer, items, space, impulses, rows_, owners)
    flags.extend(several.flags)
    return several.impulses, several


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
    flags = tuple(Flag(code=code, where=where, message=MESSAGES.get(code, code))
                  for code in answer.flags)  # fmt: skip
    stages = tuple(_stage(stage, items, space, rows, owners) for stage in answer.stages)
    alternatives = tuple(_mapped(other, items, space, given, rows, owners)
                         for other in answer.alternatives)  # fmt: skip
    return Several(law=answer.law, impulses=impulses, states=states, residual=answer.residual,
                   flags=flags, stages=stages, alternatives=alternatives)  # fmt: skip


def _stage(
    stage: Stage, items: Sequence[Item], space: ContactSpace, rows: np.ndarray,
    owners: list[int],
) -> StageOutcome:  # fmt: skip
    """A sub-impact or phase, per contact: impulse (world) and share of the theorem."""
    lam = np.zeros(space.size)
    lam[rows] = stage.impulses
    by_row = np.zeros(space.size)
    by_row[rows] = dissipated_by_row(stage.impulses, stage.w_before, stage.w_after)
    impulses = {}
    shares = {}
    acting = tuple(items[owners[k]].where for k in stage.contacts)
    for i in owners:
        s = space.slices[i]
        impulses[items[i].where] = space.blocks[i].linear.T @ lam[s]
        shares[items[i].where] = float(np.sum(by_row[s]))
    return StageOutcome(index=stage.index, description=stage.description,
                        contacts=acting, impulses=impulses, dissipated_by_contact=shares,
                        dissipated=float(np.sum(by_row)))  # fmt: skip

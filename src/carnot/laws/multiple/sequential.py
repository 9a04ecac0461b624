"""The sequential multiple-impact law: pairwise sub-impacts, the fastest approach first.

While some contact approaches (``w_n < 0`` beyond 1e-9 of the velocity scale), the contact
with the most negative normal velocity has a sub-impact alone (with the held rows, which hold
throughout): Newton's law on that contact, ``w_n'' = -e w_n``, and the held rows at their
targets. Each sub-impact is a :class:`~carnot.laws.multiple.rows.Stage` with its own impulses,
so its ledger follows from the theorem. A cradle of equal balls with e = 1 sends the last ball
off alone: ``(0, 0, v)`` (the "sequential" or "propagation" model; Brogliato, *Nonsmooth
Mechanics*, 3rd ed., Springer 2016, section 6.2; Ceanga and Hurmuzlu, J. Appl. Mech. 68, 2001).

Two contacts approaching equally fast (to 1e-9 relative) have no defined order: every order is
followed, the outcome is flagged ``sequential_tie`` and each order's outcome is reported in
``alternatives`` (the primary answer is the first order, listed among them too). The law is
frictionless: friction or a contact told to stick is an :class:`~carnot.errors.InputError`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from carnot.conventions import RELATIVE_TOLERANCE
from carnot.errors import InputError
from carnot.laws.multiple.rows import (
    ContactOutcome,
    ContactRows,
    HeldRows,
    MultipleImpactOutcome,
    Stage,
    check_problem,
    frictionless_only,
    held_residual,
    velocity_scale,
)

#: The most sub-impacts one sequence may have, and the most orders ties may branch into
#: (beyond, the lowest index goes first and the outcome is flagged ``tie_orders_truncated``).
MAX_STAGES = 10_000
MAX_ORDERS = 64


def resolve_sequential(
    delassus: object,
    w_before: object,
    contacts: Sequence[ContactRows],
    held: HeldRows | None = None,
    *,
    max_stages: int = MAX_STAGES,
) -> MultipleImpactOutcome:
    """Pairwise sub-impacts until no contact approaches; row impulses ``Lambda`` (N s).

    ``delassus`` is ``G`` (m x m, 1/kg), ``w_before`` the row velocities (m/s).

    Newton's cradle of three unit balls, e = 1 (rows: the two contacts' normal velocities):
    the first ball stops, the last leaves with the striker's speed.

    >>> out = resolve_sequential([[2.0, -1.0], [-1.0, 2.0]], [-1.0, 0.0],
    ...     [ContactRows(normal=0, restitution=1.0), ContactRows(normal=1, restitution=1.0)])
    >>> out.impulses.tolist(), out.order
    ([1.0, 1.0], (0, 1))
    """
    contacts = tuple(contacts)
    frictionless_only(contacts, "sequential")
    if isinstance(max_stages, bool) or not isinstance(max_stages, int) or max_stages < 1:
        raise InputError("max_stages", "must be an integer >= 1", max_stages)
    g, w = check_problem(delassus, w_before, contacts, held)
    scale = velocity_scale(w, held)
    branches = _follow(g, w, contacts, held, scale, max_stages, (), (), [MAX_ORDERS - 1])
    outcomes = [_outcome(g, w, contacts, held, stages, order, flags)
                for stages, order, flags in branches]
    if len(outcomes) == 1:
        return outcomes[0]
    first = outcomes[0]
    return MultipleImpactOutcome(
        law="sequential",
        impulses=first.impulses,
        w_before=first.w_before,
        w_after=first.w_after,
        contacts=first.contacts,
        residual=first.residual,
        flags=(*first.flags, "sequential_tie"),
        stages=first.stages,
        alternatives=tuple(outcomes),
        order=first.order,
    )


_Branch = tuple[tuple[Stage, ...], tuple[int, ...], tuple[str, ...]]


def _follow(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    scale: float,
    max_stages: int,
    stages: tuple[Stage, ...],
    order: tuple[int, ...],
    budget: list[int],
) -> list[_Branch]:
    """Every sequence of sub-impacts from row velocities ``w`` (branching on ties)."""
    tol = RELATIVE_TOLERANCE * scale
    while True:
        normal_w = np.array([w[c.normal] for c in contacts])
        approaching = np.flatnonzero(normal_w < -tol)
        # held rows not at their targets (a given target) and nothing approaching: a stage of
        # the held rows alone sets them
        held_off = held is not None and held_residual(held, w) > tol
        if len(approaching) == 0 and not held_off:
            return [(stages, order, ())]
        if len(stages) >= max_stages:
            return [(stages, order, ("stage_limit",))]
        if len(approaching):
            fastest = float(np.min(normal_w[approaching]))
            tied = [int(i) for i in approaching if normal_w[i] <= fastest + tol]
        else:
            tied = [-1]  # held rows only
        truncated: tuple[str, ...] = ()
        if len(tied) > 1 and budget[0] >= len(tied) - 1:
            budget[0] -= len(tied) - 1  # each tie adds that many orders to follow
            out: list[_Branch] = []
            for i in tied:
                stage, ok = _sub_impact(g, w, contacts, held, i, len(stages))
                if not ok:
                    out.append((stages, order, ("no_solution",)))
                    continue
                out.extend(
                    _follow(g, stage.w_after, contacts, held, scale, max_stages,
                            (*stages, stage), (*order, i), budget)
                )
            return out
        if len(tied) > 1:
            # past MAX_ORDERS orders, the lowest index goes first, and the outcome says so
            truncated = ("tie_orders_truncated",)
        i = tied[0]
        stage, ok = _sub_impact(g, w, contacts, held, i, len(stages))
        if not ok:
            return [(stages, order, ("no_solution",))]
        if truncated:
            rest = _follow(g, stage.w_after, contacts, held, scale, max_stages,
                           (*stages, stage), (*order, i), budget)
            return [(st, od, (*fl, *truncated) if truncated[0] not in fl else fl)
                    for st, od, fl in rest]
        stages = (*stages, stage)
        order = order if i < 0 else (*order, i)
        w = stage.w_after


def _sub_impact(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    i: int,
    index: int,
) -> tuple[Stage, bool]:
    """Contact ``i`` alone (``-1``: none) with the held rows: ``G_RR x = target_R - w_R``."""
    rows = list(held.rows) if held is not None else []
    targets = list(held.target) if held is not None else []
    if i >= 0:
        c = contacts[i]
        rows.append(c.normal)
        targets.append(-c.restitution * float(w[c.normal]))
    rhs = np.array(targets) - w[rows]
    a = g[np.ix_(rows, rows)]
    x = np.linalg.lstsq(a, rhs, rcond=None)[0]
    ok = bool(np.max(np.abs(a @ x - rhs), initial=0.0)
              <= RELATIVE_TOLERANCE * max(1.0, float(np.max(np.abs(rhs), initial=0.0))))
    impulses = np.zeros_like(w)
    impulses[rows] = x
    stage = Stage(
        index=index,
        contacts=() if i < 0 else (i,),
        impulses=impulses,
        w_before=w,
        w_after=w + g @ impulses,
        description="held rows" if i < 0 else f"contact {contacts[i].label}",
    )
    return stage, ok


def _outcome(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    stages: tuple[Stage, ...],
    order: tuple[int, ...],
    flags: tuple[str, ...],
) -> MultipleImpactOutcome:
    """Sum the stages into one outcome; a contact is active when it had a sub-impact."""
    impulses = np.sum([s.impulses for s in stages], axis=0) if stages else np.zeros_like(w)
    w_after = w + g @ impulses
    results = []
    for k, c in enumerate(contacts):
        active = k in order
        # Residual: the law asks no approach at the end and no pull (P_n >= 0) at any stage.
        pulled = min([float(s.impulses[c.normal]) for s in stages] + [0.0])
        residual = max(0.0, -float(w_after[c.normal])) + abs(pulled) * float(g[c.normal, c.normal])
        results.append(
            ContactOutcome(
                active=active,
                regime="frictionless" if active else "separate",
                impulse_normal=float(impulses[c.normal]),
                impulse_tangent=tuple(float(impulses[t]) for t in c.tangents),
                residual=residual,
            )
        )
    return MultipleImpactOutcome(
        law="sequential",
        impulses=impulses,
        w_before=w,
        w_after=w_after,
        contacts=tuple(results),
        residual=max([r.residual for r in results] + [held_residual(held, w_after)]),
        flags=flags,
        stages=stages,
        order=order,
    )

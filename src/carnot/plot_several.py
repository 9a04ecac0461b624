"""Several contacts at once under each multiple-impact law, side by side (matplotlib).

:func:`laws_side_by_side` solves one problem under every law of
:data:`carnot.laws.registry.MULTIPLE_IMPACT_NAMES` that accepts it (sequential and dispersion
are frictionless: a frictional problem is solved by the simultaneous law alone, and the
others are listed as refused, never answered by another law). :func:`plot_laws` draws

* each movable body's outgoing velocity along the direction ``d`` of the total pre-impact
  momentum (m/s; ``d`` = x when the momentum is zero), or for a system in generalized
  coordinates each ``q''``, one group of bars per body or coordinate, one bar per law: a
  cradle's ``((1-2e)/3, (1+e)/3, (1+e)/3) v`` beside ``(0, 0, v)`` and the dispersion law's
  spread;
* each contact's share of the energy dissipated (J, the theorem's term), per law;

and, for many contacts (a wall, a tower), :func:`plot_ledger` draws where the energy went,
contact by contact, under the simultaneous law.

It uses matplotlib's object-oriented API (no pyplot) and is imported only when a picture is
asked for (``carnot solve FILE --plot OUT`` on a scenario with several contacts): the core
does not import it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from carnot.errors import InputError
from carnot.laws.registry import MULTIPLE_IMPACT_NAMES, several_contacts
from carnot.model.bodies import RigidBody
from carnot.model.contacts import PointContact
from carnot.model.problem import ImpactProblem
from carnot.model.system import SystemProblem
from carnot.result import ImpactResult
from carnot.solve import solve_impact


@dataclass(frozen=True, kw_only=True, eq=False)
class LawComparison:
    """The outcomes of one problem under each multiple-impact law: ``results`` by law name
    (in the registry's order), ``refused`` the laws that do not apply with the reason,
    ``direction`` the unit vector along which :func:`outgoing_velocities` projects (world;
    ``None`` for a system in generalized coordinates, whose ``q''`` are drawn)."""

    results: dict[str, ImpactResult]
    refused: dict[str, str]
    direction: np.ndarray | None


def momentum_direction(problem: ImpactProblem) -> np.ndarray:
    """Unit vector along the movable bodies' total pre-impact momentum ``sum m v'`` (x when it
    is zero).

    >>> from carnot.io.scenario import load_scenario
    >>> momentum_direction(load_scenario("examples/newtons_cradle.toml")).tolist()
    [1.0, 0.0, 0.0]
    """
    total = np.zeros(3)
    for body in problem.bodies.values():
        if isinstance(body, RigidBody):
            total += body.mass * np.asarray(body.velocity_com, dtype=float)
    norm = float(np.linalg.norm(total))
    return total / norm if norm > 0.0 else np.array([1.0, 0.0, 0.0])


def laws_side_by_side(problem: ImpactProblem | SystemProblem) -> LawComparison:
    """Solve ``problem`` under each multiple-impact law that accepts it.

    >>> from carnot.io.scenario import load_scenario
    >>> cmp = laws_side_by_side(load_scenario("examples/newtons_cradle.toml"))
    >>> {law: [round(v, 3) for v in outgoing_velocities(cmp, law)] for law in cmp.results}
    ... # doctest: +NORMALIZE_WHITESPACE
    {'simultaneous': [-0.333, 0.667, 0.667], 'sequential': [0.0, 0.0, 1.0],
     'dispersion': [-0.071, 0.076, 0.995]}
    """
    contacts: list[PointContact] = (
        list(problem.contacts) if isinstance(problem, ImpactProblem)
        else [c.contact for c in problem.contacts]  # a system's contact carries its law
    )  # fmt: skip
    if not several_contacts(contacts):
        raise InputError(
            "plot", "compares the multiple-impact laws: it needs two or more unilateral point "
            "contacts", len(problem.contacts),
        )  # fmt: skip
    results: dict[str, ImpactResult] = {}
    refused: dict[str, str] = {}
    for law in MULTIPLE_IMPACT_NAMES:
        try:
            results[law] = solve_impact(replace(problem, multiple_impact=law))
        except InputError as err:  # friction with a frictionless law: say so, never substitute
            refused[law] = str(err)
    direction = momentum_direction(problem) if isinstance(problem, ImpactProblem) else None
    return LawComparison(results=results, refused=refused, direction=direction)


def outgoing_velocities(comparison: LawComparison, law: str) -> list[float]:
    """Each movable body's post-impact velocity along ``comparison.direction`` (m/s), in the
    problem's order of bodies; a system's ``q''``."""
    res = comparison.results[law]
    if comparison.direction is None:
        assert res.system is not None
        return [float(q) for q in res.system.velocity_after]
    return [float(np.dot(b.velocity_after, comparison.direction))
            for b in res.bodies.values() if not b.fixed]  # fmt: skip


def plot_laws(
    problem: ImpactProblem | SystemProblem, path: str | Path | None = None
) -> Figure:
    """Draw the outgoing velocities and each contact's dissipated energy under each law; save
    to ``path`` (PNG, SVG or PDF by the suffix) when given.

    >>> from carnot.io.scenario import load_scenario
    >>> len(plot_laws(load_scenario("examples/newtons_cradle.toml")).axes)
    2
    """
    cmp = laws_side_by_side(problem)
    laws = list(cmp.results)
    first = cmp.results[laws[0]]
    if first.system is not None:
        bodies = list(first.system.coordinates)
    else:
        bodies = [name for name, b in first.bodies.items() if not b.fixed]
    contacts = [c.name or c.where for c in first.contacts]
    fig = Figure(figsize=(max(7.0, 1.2 * len(bodies) + 3.0), 7.0), layout="constrained")
    ax_v, ax_e = fig.subplots(2, 1)
    width = 0.8 / len(laws)
    for k, law in enumerate(laws):
        x = np.arange(len(bodies)) + (k - (len(laws) - 1) / 2) * width
        ax_v.bar(x, outgoing_velocities(cmp, law), width, label=law)
        shares = [c.dissipated for c in cmp.results[law].contacts]
        xe = np.arange(len(contacts)) + (k - (len(laws) - 1) / 2) * width
        ax_e.bar(xe, shares, width, label=law)
    ax_v.set_xticks(np.arange(len(bodies)), bodies)
    if cmp.direction is None:
        ax_v.set_ylabel("generalized velocity after q''")
    else:
        d = ", ".join(f"{c:.3g}" for c in cmp.direction)
        ax_v.set_ylabel(f"velocity after along ({d}) [m/s]")
    ax_v.axhline(0.0, color="0.5", linewidth=0.8)
    ax_v.legend(title="multiple_impact")
    ax_e.set_xticks(np.arange(len(contacts)), contacts)
    ax_e.set_ylabel("dissipated at the contact [J]")
    ax_e.axhline(0.0, color="0.5", linewidth=0.8)
    title = problem.title or "several contacts"
    for law, reason in cmp.refused.items():  # the field and the bound, up to the reason
        title += f"\n{law} not applied: {reason.split(' (')[0]}"
    fig.suptitle(title, fontsize=10)
    if path is not None:
        fig.savefig(path)
    return fig


#: Contacts drawn one by one in :func:`plot_ledger`; the rest are summed in one bar.
LEDGER_BARS = 30
#: Contacts from which ``carnot solve FILE --plot OUT`` draws :func:`plot_ledger` instead of
#: the laws side by side (whose bars, a group per body and contact, no longer read).
LEDGER_FROM = 13


def plot_ledger(result: ImpactResult, path: str | Path | None = None) -> Figure:
    """Where the energy went, contact by contact (many contacts: a wall, a tower): each
    contact's share of ``E_d`` (J, the theorem's term ``-1/2 P . (w' + w'')``), largest first,
    coloured by its regime, the contacts beyond :data:`LEDGER_BARS` summed in one bar; and the
    cumulative fraction of ``E_d`` against the number of contacts, largest first. Saved to
    ``path`` when given.

    >>> from carnot.io.scenario import load_scenario
    >>> fig = plot_ledger(solve_impact(load_scenario("examples/many/brick_wall.toml")))
    >>> len(fig.axes)
    2
    """
    contacts = list(result.contacts)
    shares = np.array([c.dissipated for c in contacts], dtype=float)
    order = np.argsort(-shares, kind="stable")
    shown = order[:LEDGER_BARS]
    labels = [contacts[k].name or contacts[k].where for k in shown]
    values = list(shares[shown])
    colours = {"stick": "tab:blue", "slip": "tab:orange", "frictionless": "tab:green",
               "separate": "0.6"}  # fmt: skip
    bar_colours = [colours.get(str(contacts[k].regime), "tab:purple") for k in shown]
    if len(order) > LEDGER_BARS:
        labels.append(f"the other {len(order) - LEDGER_BARS}")
        values.append(float(shares[order[LEDGER_BARS:]].sum()))
        bar_colours.append("0.3")
    fig = Figure(figsize=(9.0, max(4.0, 0.22 * len(labels) + 1.5)), layout="constrained")
    ax_bar, ax_cum = fig.subplots(1, 2, width_ratios=(3, 2))
    y = np.arange(len(labels))
    ax_bar.barh(y, values, color=bar_colours)
    ax_bar.set_yticks(y, labels, fontsize=7)
    ax_bar.invert_yaxis()
    ax_bar.set_xlabel("dissipated at the contact [J]")
    ax_bar.axvline(0.0, color="0.5", linewidth=0.8)
    for regime, colour in colours.items():
        ax_bar.bar([0], [0], color=colour, label=regime)
    ax_bar.legend(title="regime", fontsize=7, loc="lower right")
    total = float(result.energy.dissipated_theorem)
    if total > 0.0:
        fraction = np.cumsum(shares[order]) / total
        ax_cum.plot(np.arange(1, len(order) + 1), fraction, marker=".", markersize=3)
    ax_cum.set_xlabel("contacts, largest share first")
    ax_cum.set_ylabel("fraction of E_d")
    ax_cum.set_ylim(bottom=0.0)
    ax_cum.grid(True, linewidth=0.3)
    fig.suptitle(f"{result.title or 'several contacts'}: E_d = {total:.4g} J over "
                 f"{len(contacts)} contacts")  # fmt: skip
    if path is not None:
        fig.savefig(path)
    return fig

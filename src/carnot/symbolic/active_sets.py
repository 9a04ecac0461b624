"""Closed forms of several contacts at once: one per active set of the simultaneous law.

The simultaneous law (Moreau/Glocker's generalized Newton, DESIGN.md section 6) is piecewise
linear: for each *active set* ``S`` of the contacts taking part (those approaching or closed
before, ``w_n' <= 0``), the contacts in ``S`` obey Newton's law as equalities
(``w_n'' = -e w_n'``; a contact told to stick also ``w_t'' = 0``), the others receive nothing.
That is the equality problem that :func:`~carnot.symbolic.solve.derive_impact` solves in
closed form, with the contacts outside ``S`` left out. The set's closed form is *the* answer
where its inequalities hold (Glocker, *Set-Valued Force Laws*, Springer 2001, ch. 7):

* ``P_n >= 0`` at every active contact (the floor may only push);
* ``w_n'' + e w_n' >= 0`` at every contact of the taking part that is not active (it
  separates at least as fast as Newton's law would send it);
* ``mu P_n - |P_t| >= 0`` at an active contact told to stick that has a friction coefficient
  (the friction it needs; ``friction_required`` in the numeric result).

Frictionless contacts and contacts told to stick are derived; Coulomb slip has no single
closed form (the single-contact route refuses it too). With frictionless contacts the law is
a monotone complementarity problem: every set that holds gives the same motion (Cottle, Pang
and Stone 1992, thm 3.1.7). Each set is also evaluated at the scenario's own numbers, so the
one the numeric solver found is marked.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from carnot.errors import InputError
from carnot.model.problem import ImpactProblem
from carnot.symbolic.convert import exact as exact_number
from carnot.symbolic.convert import parse_symbols, to_symbolic
from carnot.symbolic.model import SymContact, SymProblem, SymRigidBody
from carnot.symbolic.solve import SymbolicResult, derive_impact, simplify_expr

#: The most contacts taking part whose active sets are enumerated (2^6 = 64 derivations).
MAX_TAKING_PART = 6


@dataclass(frozen=True, kw_only=True, eq=False)
class ActiveSet:
    """One active set: ``active`` the contacts (``where``) with Newton's law as an equality,
    ``result`` its closed forms (contacts outside ``active`` take no impulse), ``conditions``
    by name the expressions that must be ``>= 0`` for it to hold, ``holds`` whether they all
    are at the scenario's own values; ``expressions`` every result by its dotted name (result
    format 1 layout), the contacts numbered as in the scenario, ``contacts.K.active`` 1 or 0."""

    active: tuple[str, ...]
    result: SymbolicResult
    conditions: dict[str, sp.Expr]
    holds: bool
    expressions: dict[str, sp.Expr]


@dataclass(frozen=True, kw_only=True, eq=False)
class SeveralContacts:
    """The active sets of a scenario with several unilateral contacts: ``taking_part`` and
    ``separating`` (before the impact: no impulse, no condition) by ``where``; ``names``
    each contact's ``name`` or ``where``."""

    taking_part: tuple[str, ...]
    separating: tuple[str, ...]
    names: dict[str, str]
    sets: tuple[ActiveSet, ...]


def derive_active_sets(
    problem: ImpactProblem,
    specs: Sequence[str] = (),
    shaped: set[str] | frozenset[str] = frozenset(),
) -> tuple[list[sp.Symbol], SeveralContacts]:
    """The symbols chosen by ``specs`` and the closed form of every active set.

    The three-ball cradle with a symbolic ``e``: with both contacts active, the published
    ``((1 - 2e)/3, (1 + e)/3, (1 + e)/3) v`` (Glocker 2001), which holds at the file's e = 1.

    >>> from carnot.io.scenario import load_scenario
    >>> _, several = derive_active_sets(load_scenario("examples/newtons_cradle.toml"), ["e_0=e",
    ...                                 "e_1=e"])
    >>> both = [s for s in several.sets if len(s.active) == 2][0]
    >>> [both.result.bodies[f"ball{k}"][0][0] for k in (1, 2, 3)], both.holds
    ([-(2*e - 1)/3, (e + 1)/3, (e + 1)/3], True)
    """
    if problem.multiple_impact != "simultaneous":
        raise InputError(
            "multiple_impact",
            "carnot derive gives the closed forms of the simultaneous law (one per active set); "
            "the sequential and dispersion laws have none to derive",
            problem.multiple_impact,
        )
    chosen = parse_symbols(problem, specs)
    sym = to_symbolic(problem, chosen, shaped)
    exact = to_symbolic(problem, {}, shaped)  # the file's own numbers, for the decisions
    values = {s: _value(exact, key) for key, s in chosen.items()}
    unilateral = [k for k, c in enumerate(problem.contacts) if not c.is_given and c.patch is None]
    taking_part: list[int] = []
    separating: list[int] = []
    for k in unilateral:
        w_n = _normal_velocity(exact, exact.contacts[k], exact_after=None)
        (taking_part if w_n <= 0 else separating).append(k)
    if len(taking_part) > MAX_TAKING_PART:
        raise InputError(
            "contacts",
            f"at most {MAX_TAKING_PART} contacts taking part can have their active sets "
            f"enumerated ({2 ** MAX_TAKING_PART} closed forms)",
            len(taking_part),
        )
    sets = []
    for size in range(len(taking_part), -1, -1):  # the widest sets first
        for active in itertools.combinations(taking_part, size):
            sets.append(_active_set(problem, sym, set(active), set(taking_part), values))
    where = [c.where for c in problem.contacts]
    return list(dict.fromkeys(chosen.values())), SeveralContacts(
        taking_part=tuple(where[k] for k in taking_part),
        separating=tuple(where[k] for k in separating),
        names={c.where: c.name or c.where for c in problem.contacts},
        sets=tuple(sets),
    )


def _value(exact: SymProblem, key: str) -> sp.Expr:
    """The file's exact value of a key path (``bodies.NAME.FIELD.I[.J]``, ``contacts.K.FIELD[.I]``,
    ``constraints.K.point.I``)."""
    parts = key.split(".")
    if parts[0] == "bodies":
        body = exact.bodies[parts[1]]
        assert isinstance(body, SymRigidBody)
        field = {"mass": "mass", "inertia": "inertia_com", "position": "position_com",
                 "velocity": "velocity_com", "angular_velocity": "angular_velocity"}[parts[2]]
        value = getattr(body, field)
    else:
        group = exact.contacts if parts[0] == "contacts" else exact.constraints
        value = getattr(group[int(parts[1])], parts[2])
    if len(parts) == 3:
        return sp.sympify(value)
    index = [int(p) for p in parts[3:]]
    return sp.sympify(value[index[0], index[1] if len(index) > 1 else 0])


def _normal_velocity(
    problem: SymProblem, contact: SymContact, exact_after: dict[str, tuple] | None
) -> sp.Expr:
    """``n . w`` at the contact: before the impact, or after with the bodies' velocities
    ``exact_after`` (name -> (v, omega))."""
    w = sp.zeros(3, 1)
    for name, sign in ((contact.a, 1), (contact.b, -1)):
        body = problem.bodies[name]
        if not isinstance(body, SymRigidBody):
            continue
        v, omega = (body.velocity_com, body.angular_velocity) if exact_after is None \
            else exact_after[name]  # fmt: skip
        w += sign * (v + omega.cross(contact.point - body.position_com))
    return sp.expand(contact.normal.dot(w))


def _active_set(
    problem: ImpactProblem,
    sym: SymProblem,
    active: set[int],
    taking_part: set[int],
    values: dict[sp.Symbol, sp.Expr],
) -> ActiveSet:
    keep = [k for k, c in enumerate(problem.contacts)
            if k in active or c.is_given or c.patch is not None]  # fmt: skip
    sub = SymProblem(bodies=sym.bodies, contacts=[sym.contacts[k] for k in keep],
                     constraints=sym.constraints, title=sym.title)  # fmt: skip
    result = derive_impact(sub)
    by_where = {o.where: o for o in result.contacts}
    conditions: dict[str, sp.Expr] = {}
    for k in sorted(taking_part):
        c = problem.contacts[k]
        key = f"contacts.{k}"
        if k in active:
            p_n = by_where[c.where].normal_impulse
            assert p_n is not None
            conditions[f"{key}.normal_impulse"] = p_n
            if c.sticks and c.friction > 0:
                # mu P_n - |P_t| rather than mu - |P_t|/P_n: defined when P_n = 0 as well
                outcome = by_where[c.where]
                p_t = outcome.impulse - p_n * sym.contacts[k].normal
                conditions[f"{key}: mu P_n - |P_t|"] = simplify_expr(
                    exact_number(c.friction) * p_n - sp.sqrt(simplify_expr(p_t.dot(p_t)))
                )
        else:
            sc = sym.contacts[k]
            w_before = _normal_velocity(sym, sc, None)
            w_after = _normal_velocity(sym, sc, result.bodies)
            separation = w_after + sc.restitution * w_before
            conditions[f"{key}: w_n'' + e w_n'"] = simplify_expr(separation)
    holds = all(_non_negative(expr, values) for expr in conditions.values())
    return ActiveSet(active=tuple(problem.contacts[k].where for k in sorted(active)),
                     result=result, conditions=conditions, holds=holds,
                     expressions=_full_expressions(problem, result, keep, active))  # fmt: skip


def _non_negative(expr: sp.Expr, values: dict[sp.Symbol, sp.Expr]) -> bool:
    """Whether ``expr >= 0`` at the scenario's values (exactly where it is rational; else to
    30 digits, with round-off at 1e-25 of its terms' size)."""
    value = sp.sympify(expr).xreplace(values)
    value = sp.nsimplify(value) if value.has(sp.Float) else value
    if value.is_Rational:
        return bool(value >= 0)
    number = sp.N(value, 30)
    return bool(number.is_real and number >= -1e-25)


def _full_expressions(
    problem: ImpactProblem, result: SymbolicResult, keep: list[int], active: set[int]
) -> dict[str, sp.Expr]:
    """The set's results with the contacts numbered as in the scenario (those left out: zero
    impulse, no share of the energy)."""
    inner = result.expressions()
    out: dict[str, sp.Expr] = {k: v for k, v in inner.items() if k.startswith("bodies.")}
    position = {k: i for i, k in enumerate(keep)}
    for k in range(len(problem.contacts)):
        out[f"contacts.{k}.active"] = sp.Integer(int(k in active))
        if k in position:
            prefix = f"contacts.{position[k]}."
            for name, value in inner.items():
                if name.startswith(prefix):
                    out[f"contacts.{k}." + name[len(prefix):]] = value
        else:
            for i in range(3):
                out[f"contacts.{k}.impulse.{i}"] = sp.S.Zero
            out[f"contacts.{k}.normal_impulse"] = sp.S.Zero
            out[f"contacts.{k}.dissipated"] = sp.S.Zero
    for name, value in inner.items():
        if name.startswith(("constraints.", "energy.")):
            out[name] = value
    return out


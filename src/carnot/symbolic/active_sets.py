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

Frictionless contacts and contacts told to stick are derived. A contact with Coulomb
friction has four regimes in a planar motion, each linear, so each with its closed form
(Glocker 2001, ch. 7; the simultaneous law's Coulomb at impact, DESIGN.md section 6):

* ``stick``: ``w_t'' = 0``, holding where ``mu P_n - |P_t| >= 0``;
* ``slip+`` / ``slip-``: the impulse ``P_n (n -+ mu t)`` (``t = k x n``, ``k`` the normal of
  the plane of motion), holding where ``P_n >= 0`` and ``+-t . w'' >= 0`` (the post-impact
  slip runs the way the friction opposes);
* ``separate``, as above.

A motion is planar when one axis ``k`` is normal to every contact normal, velocity, given
impulse and lever arm, and parallel to every angular velocity and given moment, and each body's
inertia maps ``k`` onto itself (checked for every value of the symbols, not only the file's).
Slip in 3D is not derived: its direction is a root of a nonlinear system (the numeric law
solves it), with no closed form in general. With frictionless contacts the law is a monotone
complementarity problem: every set that holds gives the same motion (Cottle, Pang and Stone
1992, thm 3.1.7); with friction several sets may hold, each a different outcome. Each set is
also evaluated at the scenario's own numbers, so the one the numeric solver found is marked.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from carnot.errors import InputError
from carnot.model.problem import ImpactProblem
from carnot.symbolic.convert import parse_symbols, to_symbolic
from carnot.symbolic.model import SymContact, SymProblem, SymRigidBody
from carnot.symbolic.solve import SingularRegime, SymbolicResult, derive_impact, simplify_expr

#: The most contacts taking part whose active sets are enumerated (2^6 = 64 derivations).
MAX_TAKING_PART = 6
#: The most sets derived in all (e.g. four planar Coulomb contacts: 4^4 = 256).
MAX_SETS = 256


@dataclass(frozen=True, kw_only=True, eq=False)
class ActiveSet:
    """One active set: ``active`` the contacts (``where``) with Newton's law as an equality,
    ``result`` its closed forms (contacts outside ``active`` take no impulse), ``conditions``
    by name the expressions that must be ``>= 0`` for it to hold, ``holds`` whether they all
    are at the scenario's own values; ``expressions`` every result by its dotted name (result
    format 1 layout), the contacts numbered as in the scenario, ``contacts.K.active`` 1 or 0;
    ``regimes`` each active contact's regime: ``closed`` (Newton's law; a contact told to
    stick also ``w_t'' = 0``) or, under Coulomb friction, ``stick``, ``slip+`` or ``slip-``;
    ``strict`` the conditions that must be ``> 0`` (a slip regime's ``d . w''``: with no slip
    after the impact the contact sticks, the stick regime's answer)."""

    active: tuple[str, ...]
    result: SymbolicResult
    conditions: dict[str, sp.Expr]
    holds: bool
    expressions: dict[str, sp.Expr]
    regimes: tuple[str, ...] = ()
    strict: frozenset[str] = frozenset()


@dataclass(frozen=True, kw_only=True, eq=False)
class SeveralContacts:
    """The active sets of a scenario with several unilateral contacts: ``taking_part`` and
    ``separating`` (before the impact: no impulse, no condition) by ``where``; ``names``
    each contact's ``name`` or ``where``; ``singular`` the sets with no unique closed form
    (a slip regime whose ``G`` is singular), each as its contacts' ``where: regime``; ``axis``
    the normal ``k`` of the plane of motion where a contact has Coulomb friction."""

    taking_part: tuple[str, ...]
    separating: tuple[str, ...]
    names: dict[str, str]
    sets: tuple[ActiveSet, ...]
    singular: tuple[tuple[str, ...], ...] = ()
    axis: sp.Matrix | None = None


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
    sym = to_symbolic(problem, chosen, shaped, coulomb=True)
    exact = to_symbolic(problem, {}, shaped, coulomb=True)  # the file's numbers, for decisions
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
    coulomb = [k for k in taking_part if problem.contacts[k].slips_with_friction]
    axis = _plane_axis(problem, sym, exact, coulomb[0]) if coulomb else None
    options = [("stick", "slip+", "slip-", "separate") if k in coulomb else ("closed", "separate")
               for k in taking_part]  # fmt: skip
    count = 1
    for o in options:
        count *= len(o)
    if count > MAX_SETS:
        raise InputError(
            "contacts",
            f"at most {MAX_SETS} active sets are derived (each Coulomb contact taking part has "
            "4 regimes, any other 2)",
            count,
        )
    # the widest sets first; among as wide, stick before slip (itertools.product's order)
    patterns = sorted(itertools.product(*options), key=lambda p: p.count("separate"))
    sets = []
    singular = []
    where = [c.where for c in problem.contacts]
    for pattern in patterns:
        regimes = {k: r for k, r in zip(taking_part, pattern, strict=True) if r != "separate"}
        try:
            sets.append(_active_set(problem, sym, regimes, set(taking_part), values, axis))
        except SingularRegime:
            singular.append(tuple(f"{where[k]}: {r}" for k, r in regimes.items()))
    return list(dict.fromkeys(chosen.values())), SeveralContacts(
        taking_part=tuple(where[k] for k in taking_part),
        separating=tuple(where[k] for k in separating),
        names={c.where: c.name or c.where for c in problem.contacts},
        sets=tuple(sets),
        singular=tuple(singular),
        axis=axis,
    )


def _plane_axis(
    problem: ImpactProblem, sym: SymProblem, exact: SymProblem, first: int
) -> sp.Matrix:
    """The unit normal ``k`` of the plane of motion (module docstring), found at the file's
    numbers and checked for every value of the symbols; else InputError naming the Coulomb
    contact ``first``: slip in 3D has no closed form to derive."""
    in_plane, _ = _plane_vectors(exact)
    normal_to_k, parallel_to_k = _plane_vectors(sym)
    inertias = [b.inertia_com for b in sym.bodies.values() if isinstance(b, SymRigidBody)]
    zero = sp.zeros(3, 1)
    for k in sp.Matrix.hstack(*in_plane).T.nullspace():
        k = k / sp.sqrt(k.dot(k))
        if (all(sp.simplify(k.dot(v)) == 0 for v in normal_to_k)
                and all(sp.simplify(k.cross(w)) == zero for w in parallel_to_k)
                and all(sp.simplify(k.cross(i * k)) == zero for i in inertias)):
            return k  # fmt: skip
    c = problem.contacts[first]
    raise InputError(
        f"{c.where}.friction",
        "Coulomb slip is derived in a planar motion only (its 3D slip direction is the root "
        "of a nonlinear system, with no closed form): derive a planar scenario, or with "
        'tangential = "stick" or friction = 0',
        c.friction,
    )


def _plane_vectors(problem: SymProblem) -> tuple[list[sp.Matrix], list[sp.Matrix]]:
    """The vectors a planar motion's axis ``k`` is normal to (contact normals, given impulses,
    lever arms of contact and constraint points, velocities) and those it is parallel to
    (angular velocities, given moments)."""
    normal_to: list[sp.Matrix] = []
    parallel_to: list[sp.Matrix] = []
    points: list[tuple[sp.Matrix, tuple[str | None, ...]]] = []
    for c in problem.contacts:
        normal_to.append(c.normal)
        points.append((c.point, (c.a, c.b)))
        if c.is_given:
            normal_to.append(c.impulse)
            parallel_to.append(c.moment)
    points += [(k.point, (k.body, k.other)) for k in problem.constraints]
    for point, names in points:
        for name in names:
            body = problem.bodies.get(name) if name is not None else None
            if isinstance(body, SymRigidBody):
                normal_to.append(point - body.position_com)
    for body in problem.bodies.values():
        if isinstance(body, SymRigidBody):
            normal_to.append(body.velocity_com)
            parallel_to.append(body.angular_velocity)
    return normal_to, parallel_to


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
    problem: SymProblem,
    contact: SymContact,
    exact_after: dict[str, tuple] | None,
    direction: sp.Matrix | None = None,
) -> sp.Expr:
    """``n . w`` (or ``direction . w``) at the contact: before the impact, or after with the
    bodies' velocities ``exact_after`` (name -> (v, omega))."""
    w = sp.zeros(3, 1)
    for name, sign in ((contact.a, 1), (contact.b, -1)):
        body = problem.bodies[name]
        if not isinstance(body, SymRigidBody):
            continue
        v, omega = (body.velocity_com, body.angular_velocity) if exact_after is None \
            else exact_after[name]  # fmt: skip
        w += sign * (v + omega.cross(contact.point - body.position_com))
    return sp.expand((contact.normal if direction is None else direction).dot(w))


def _active_set(
    problem: ImpactProblem,
    sym: SymProblem,
    regimes: dict[int, str],
    taking_part: set[int],
    values: dict[sp.Symbol, sp.Expr],
    axis: sp.Matrix | None,
) -> ActiveSet:
    """The closed form of one set: ``regimes`` the active contacts' regimes by index (module
    docstring), the other contacts taking part separating; ``axis`` the plane's normal ``k``
    (for the slip regimes)."""
    keep = [k for k, c in enumerate(problem.contacts)
            if k in regimes or c.is_given or c.patch is not None]  # fmt: skip
    chosen: dict[int, SymContact] = {}
    for k in keep:
        contact, regime = sym.contacts[k], regimes.get(k, "closed")
        if regime == "stick":
            contact = dataclasses.replace(contact, tangential="stick")
        elif regime in ("slip+", "slip-"):
            assert axis is not None
            d = axis.cross(contact.normal) * (1 if regime == "slip+" else -1)
            contact = dataclasses.replace(contact, slip=d)
        chosen[k] = contact
    sub = SymProblem(bodies=sym.bodies, contacts=[chosen[k] for k in keep],
                     constraints=sym.constraints, title=sym.title)  # fmt: skip
    result = derive_impact(sub)
    by_where = {o.where: o for o in result.contacts}
    conditions: dict[str, sp.Expr] = {}
    for k in sorted(taking_part):
        c = problem.contacts[k]
        key = f"contacts.{k}"
        if k in regimes:
            p_n = by_where[c.where].normal_impulse
            assert p_n is not None
            conditions[f"{key}.normal_impulse"] = p_n
            if chosen[k].tangential == "stick" and c.friction > 0:
                # mu P_n - |P_t| rather than mu - |P_t|/P_n: defined when P_n = 0 as well
                outcome = by_where[c.where]
                p_t = outcome.impulse - p_n * sym.contacts[k].normal
                conditions[f"{key}: mu P_n - |P_t|"] = simplify_expr(
                    sym.contacts[k].friction * p_n - sp.sqrt(simplify_expr(p_t.dot(p_t)))
                )
            elif chosen[k].slip is not None:
                # the post-impact slip runs along d, the way the friction -mu P_n d opposes
                slip = _normal_velocity(sym, chosen[k], result.bodies, chosen[k].slip)
                conditions[f"{key}: d . w''"] = simplify_expr(slip)
        else:
            sc = sym.contacts[k]
            w_before = _normal_velocity(sym, sc, None)
            w_after = _normal_velocity(sym, sc, result.bodies)
            separation = w_after + sc.restitution * w_before
            conditions[f"{key}: w_n'' + e w_n'"] = simplify_expr(separation)
    strict = frozenset(name for name in conditions if name.endswith(": d . w''"))
    holds = all(_non_negative(expr, values, strict=name in strict)
                for name, expr in conditions.items())  # fmt: skip
    active = sorted(regimes)
    coulomb = {k for k in active if problem.contacts[k].slips_with_friction}
    return ActiveSet(active=tuple(problem.contacts[k].where for k in active),
                     result=result, conditions=conditions, holds=holds,
                     expressions=_full_expressions(problem, result, keep, set(active)),
                     regimes=tuple(regimes[k] if k in coulomb else "closed"
                                   for k in active), strict=strict)  # fmt: skip


def _non_negative(
    expr: sp.Expr, values: dict[sp.Symbol, sp.Expr], strict: bool = False
) -> bool:
    """Whether ``expr >= 0`` (``strict``: ``> 0``) at the scenario's values (exactly where it
    is rational; else to 30 digits, with round-off at 1e-25)."""
    value = sp.sympify(expr).xreplace(values)
    value = sp.nsimplify(value) if value.has(sp.Float) else value
    if value.is_Rational:
        return bool(value > 0) if strict else bool(value >= 0)
    number = sp.N(value, 30)
    return bool(number.is_real and (number > 1e-25 if strict else number >= -1e-25))


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


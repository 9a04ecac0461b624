"""From a numeric problem (a scenario file) to a symbolic one, with chosen values as symbols.

Every number becomes an exact rational (the decimal the file gave: ``0.1`` is ``1/10``), and
the values named by key paths become symbols: ``bodies.ball.mass``, ``bodies.ball.velocity.2``,
``bodies.ball.inertia.0.1`` (both symmetric entries), ``contacts.0.restitution``,
``contacts.0.friction`` (Coulomb, derived in its regimes by several contacts),
``contacts.0.point.0``, ``contacts.0.impulse.1``, ``constraints.0.point.2``. Each has a default
symbol name (:func:`default_symbols`), or the user names it (``KEY=NAME``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from carnot.errors import InputError
from carnot.model.bodies import RigidBody
from carnot.model.problem import ImpactProblem
from carnot.symbolic.model import (
    SymConstraint,
    SymContact,
    SymFixedBody,
    SymProblem,
    SymRigidBody,
)

AXES = "xyz"


def exact(x: float) -> sp.Rational:
    """The simplest rational within 1e-13 (relative) of ``x``: the number the file meant,
    also for values computed from it (a rod's ``m L^2/12 = 0.09999999999999999`` is 1/10).

    >>> exact(0.1), exact(2.0), exact(-1.25), exact(1.2 / 12)
    (1/10, 2, -5/4, 1/10)
    """
    x = float(x)
    if x == 0.0:
        return sp.Integer(0)
    return sp.Rational(sp.nsimplify(x, rational=True, tolerance=1e-13 * abs(x)))


def default_symbols(problem: ImpactProblem) -> dict[str, str]:
    """Every key path that can be a symbol, with its default name.

    >>> from carnot.io.scenario import load_scenario
    >>> names = default_symbols(load_scenario("examples/ball_on_floor.toml"))
    >>> names["bodies.ball.mass"], names["contacts.0.restitution"], names["bodies.ball.velocity.2"]
    ('m_ball', 'e', 'v_ball_z')
    """
    out: dict[str, str] = {}
    for name, body in problem.bodies.items():
        if body.fixed:
            continue
        out[f"bodies.{name}.mass"] = f"m_{name}"
        for key, short in (("position", "x"), ("velocity", "v"), ("angular_velocity", "omega")):
            for i, axis in enumerate(AXES):
                out[f"bodies.{name}.{key}.{i}"] = f"{short}_{name}_{axis}"
        for i in range(3):
            for j in range(i, 3):
                out[f"bodies.{name}.inertia.{i}.{j}"] = f"J_{name}_{AXES[i]}{AXES[j]}"
    single = len(problem.contacts) == 1
    for k, c in enumerate(problem.contacts):
        suffix = "" if single else f"_{k}"
        if not c.is_given:
            out[f"contacts.{k}.restitution"] = f"e{suffix}"
        if c.slips_with_friction:  # derived in its regimes by carnot.symbolic.active_sets
            out[f"contacts.{k}.friction"] = f"mu{suffix}"
        for i, axis in enumerate(AXES):
            out[f"contacts.{k}.point.{i}"] = f"p{suffix}_{axis}"
            if c.is_given:
                out[f"contacts.{k}.impulse.{i}"] = f"P{suffix}_{axis}"
                out[f"contacts.{k}.moment.{i}"] = f"M{suffix}_{axis}"
    for k, _ in enumerate(problem.constraints):
        for i, axis in enumerate(AXES):
            out[f"constraints.{k}.point.{i}"] = f"q_{k}_{axis}"
    return out


def parse_symbols(problem: ImpactProblem, specs: Sequence[str]) -> dict[str, sp.Symbol]:
    """``KEY``, ``KEY=NAME``, a default ``NAME`` or ``DEFAULT=NAME`` -> {key path: symbol}
    (``KEY`` a key path, ``DEFAULT`` a default name, both from :func:`default_symbols`).

    >>> from carnot.io.scenario import load_scenario
    >>> ball = load_scenario("examples/ball_on_floor.toml")
    >>> parse_symbols(ball, ["e", "bodies.ball.mass=m", "v_ball_z=v"])
    {'contacts.0.restitution': e, 'bodies.ball.mass': m, 'bodies.ball.velocity.2': v}
    """
    defaults = default_symbols(problem)
    by_name = {name: key for key, name in defaults.items()}
    out: dict[str, sp.Symbol] = {}
    for spec in specs:
        key, _, name = spec.partition("=")
        key, name = key.strip(), name.strip()
        if key not in defaults and key in by_name:
            key = by_name[key]
        if key not in defaults:
            raise InputError(
                "--symbols",
                f"{key!r} names no value of this scenario that can be a symbol: give a key path "
                "(bodies.NAME.mass, contacts.0.restitution, ...; see --list) or a default name, "
                "optionally followed by =NEWNAME; the default names are "
                + ", ".join(defaults.values()),
                spec,
            )
        name = name or defaults[key]
        positive = (key.endswith((".mass", ".friction"))
                    or ".inertia." in key and key[-1] == key[-3])  # fmt: skip
        out[key] = sp.Symbol(name, positive=True) if positive else sp.Symbol(name, real=True)
    return out


def _vector(values: Any, prefix: str, chosen: Mapping[str, sp.Symbol]) -> sp.Matrix:
    return sp.Matrix([chosen.get(f"{prefix}.{i}", exact(x)) for i, x in enumerate(values)])


def to_symbolic(
    problem: ImpactProblem,
    chosen: Mapping[str, sp.Symbol] | None = None,
    shaped: set[str] | frozenset[str] = frozenset(),
    coulomb: bool = False,
) -> SymProblem:
    """The symbolic twin of ``problem``: exact rationals, and ``chosen`` values as symbols.

    A body named in ``shaped`` got its inertia from a shape, so its inertia scales with its
    mass when the mass is a symbol; any other body keeps the inertia the file gave. A contact
    with Coulomb slip is refused, unless ``coulomb`` (the caller then picks its regime: see
    :mod:`carnot.symbolic.active_sets`)."""
    chosen = dict(chosen or {})
    bodies: dict[str, SymRigidBody | SymFixedBody] = {}
    for name, body in problem.bodies.items():
        if not isinstance(body, RigidBody):
            bodies[name] = SymFixedBody(name=name)
            continue
        p = f"bodies.{name}"
        inertia = sp.zeros(3, 3)
        for i in range(3):
            for j in range(3):
                key = f"{p}.inertia.{min(i, j)}.{max(i, j)}"
                inertia[i, j] = chosen.get(key, exact(body.inertia_com[i, j]))
        if name in shaped and f"{p}.mass" in chosen:
            inertia = inertia * chosen[f"{p}.mass"] / exact(body.mass)
        bodies[name] = SymRigidBody(
            name=name,
            mass=chosen.get(f"{p}.mass", exact(body.mass)),
            inertia_com=inertia,
            position_com=_vector(body.position_com, f"{p}.position", chosen),
            velocity_com=_vector(body.velocity_com, f"{p}.velocity", chosen),
            angular_velocity=_vector(body.angular_velocity, f"{p}.angular_velocity", chosen),
        )
    contacts = []
    for k, c in enumerate(problem.contacts):
        p = f"contacts.{k}"
        if c.slips_with_friction and not coulomb:
            # Slip under Coulomb friction is piecewise in the normal impulse, and in 3D an
            # ODE: no single closed form to derive. Refuse rather than drop the friction.
            raise InputError(
                f"{c.where}.friction",
                "Coulomb friction with slip has no single closed form (its phases are "
                'piecewise, and 3D slip is integrated): derive with tangential = "stick" or '
                "friction = 0",
                c.friction,
            )
        contacts.append(
            SymContact(
                where=c.where,
                a=c.a,
                b=c.b,
                point=_vector(c.point, f"{p}.point", chosen),
                normal=_exact_unit(c.normal),
                restitution=chosen.get(f"{p}.restitution", exact(c.restitution)),
                tangential=c.tangential,
                patch=None if c.patch is None else [[exact(x) for x in q] for q in c.patch],
                impulse=None if c.impulse is None else _vector(c.impulse, f"{p}.impulse", chosen),
                moment=None if c.moment is None else _vector(c.moment, f"{p}.moment", chosen),
                friction=chosen.get(f"{p}.friction", exact(c.friction)),
            )
        )
    constraints = [
        SymConstraint(
            where=k.where,
            kind=k.kind,
            body=k.body,
            other=k.other,
            point=_vector(k.point, f"constraints.{i}.point", chosen),
        )
        for i, k in enumerate(problem.constraints)
    ]
    return SymProblem(
        bodies=bodies, contacts=contacts, constraints=constraints, title=problem.title
    )


def _exact_unit(normal: np.ndarray) -> sp.Matrix:
    """The normal as exact numbers: rational where the file's normal was a unit rational
    vector already, else the exact normalisation of the rationals (square roots)."""
    n = sp.Matrix([exact(x) for x in normal])
    norm2 = sp.nsimplify(n.dot(n))
    return n if norm2 == 1 else n / sp.sqrt(norm2)

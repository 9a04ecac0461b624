"""Scenario files with ``[system]`` instead of ``[bodies]`` (DESIGN.md section 7): a system in
generalized coordinates, its contacts and constraints given by their Jacobians.

Errors name the file and the key path, the bound and the value received, as for format 1
(:mod:`carnot.io.scenario`); unknown keys are errors.
"""

from __future__ import annotations

import json
import math
import tomllib  # noqa: F401  (the doctest reads a file back)
from collections.abc import Mapping
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.io.tables import contact_law
from carnot.io.tables import known as _known
from carnot.io.tables import multiple_impact as _multiple_impact
from carnot.io.tables import require as _require
from carnot.io.tables import solver as _solver
from carnot.io.tables import table as _table
from carnot.io.tables import top_level as _top_level
from carnot.model.system import System, SystemConstraint, SystemContact, SystemProblem

TOP_KEYS = ("format", "title", "system", "contacts", "constraints", "multiple_impact",
            "solver")
SYSTEM_KEYS = ("coordinates", "mass_matrix", "velocity")
CONTACT_KEYS = (
    "name",
    "jacobian",
    "angular_jacobian",
    "normal",
    "point",
    "restitution",
    "law",
    "friction",
    "tangential",
    "patch",
    "impulse",
    "moment",
)
CONSTRAINT_KEYS = ("type", "name", "jacobian", "angular_jacobian", "point")


def parse_system_scenario(data: Any, source: str = "<scenario>") -> SystemProblem:
    """Build a :class:`~carnot.model.system.SystemProblem` from parsed scenario data.

    >>> p = parse_system_scenario({"format": 1, "system": {"mass_matrix": [[2.0]],
    ...     "velocity": [-1.0]}, "contacts": [{"jacobian": [[0], [1], [0]],
    ...     "normal": [0, 1, 0], "restitution": 1}]})
    >>> p.system.coordinates, p.contacts[0].restitution
    (('q0',), 1.0)
    >>> parse_system_scenario({"format": 1, "system": {"mass_matrix": [[2.0]]}}, "s.toml")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: s.toml: system.velocity: is required
    """
    try:
        return _parse(data)
    except InputError as err:
        raise type(err)(
            f"{source}: {err.field}", err.problem, err.value, show_value=err.show_value
        ) from None


def _list(top: Mapping[str, Any], key: str) -> list[Any]:
    value = top.get(key, [])
    if not isinstance(value, list):
        raise InputError(key, f"must be an array of tables ([[{key}]])", value)
    return value


def _parse(data: Any) -> SystemProblem:
    top, title = _top_level(data, TOP_KEYS)
    spec = _table(top["system"], "system")
    _known(spec, SYSTEM_KEYS, "system")
    coordinates = spec.get("coordinates", [])
    if not isinstance(coordinates, list):
        raise InputError("system.coordinates", "must be a list of names", coordinates)
    system = System(
        mass_matrix=_require(spec, "mass_matrix", "system"),
        velocity=_require(spec, "velocity", "system"),
        coordinates=tuple(coordinates),
    )
    contacts = [
        _contact(i, _table(c, f"contacts[{i}]")) for i, c in enumerate(_list(top, "contacts"))
    ]
    constraints = [
        _constraint(i, _table(c, f"constraints[{i}]"))
        for i, c in enumerate(_list(top, "constraints"))
    ]
    multiple_impact = _multiple_impact(top)
    return SystemProblem(system=system, contacts=contacts, constraints=constraints, title=title,
                         multiple_impact=multiple_impact, solver=_solver(top))  # fmt: skip


def _contact(index: int, spec: Mapping[str, Any]) -> SystemContact:
    field = f"contacts[{index}]"
    _known(spec, CONTACT_KEYS, field)
    return SystemContact(
        where=field,
        name=spec.get("name"),
        jacobian=_require(spec, "jacobian", field),
        angular_jacobian=spec.get("angular_jacobian"),
        normal=_require(spec, "normal", field),
        point=spec.get("point"),
        **contact_law(spec, field),
        patch=spec.get("patch"),
    )


def _constraint(index: int, spec: Mapping[str, Any]) -> SystemConstraint:
    field = f"constraints[{index}]"
    _known(spec, CONSTRAINT_KEYS, field)
    kind = _require(spec, "type", field)
    if kind not in ("fasten", "pin"):
        raise InputError(f"{field}.type", "must be 'fasten' or 'pin'", kind)
    return SystemConstraint(
        where=field,
        kind=kind,
        name=spec.get("name"),
        jacobian=_require(spec, "jacobian", field),
        angular_jacobian=spec.get("angular_jacobian"),
        point=spec.get("point"),
    )


def _toml_value(value: Any) -> str:
    """A TOML value: a string (JSON's escapes are TOML's), a number (``repr``: it reads back
    exactly) or a list of them."""
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    out = float(value) + 0.0
    return repr(out) if math.isfinite(out) else json.dumps(str(out))


def system_scenario_toml(problem: SystemProblem) -> str:
    """``problem`` as a ``[system]`` scenario file (TOML) that reads back to the same
    problem (:func:`parse_system_scenario`): numbers are written with ``repr``.

    >>> from carnot.model.system import System, SystemContact
    >>> text = system_scenario_toml(SystemProblem(system=System(mass_matrix=[[2.0]],
    ...     velocity=[-1.0]), contacts=[SystemContact(jacobian=[[0], [1], [0]],
    ...     normal=[0, 1, 0], restitution=0.5)]))
    >>> print(text.splitlines()[3])
    coordinates = ["q0"]
    >>> parse_system_scenario(tomllib.loads(text)).contacts[0].restitution
    0.5
    """
    lines = ["format = 1"]
    if problem.title:
        lines.append(f"title = {_toml_value(problem.title)}")
    if problem.multiple_impact != "simultaneous":
        lines.append(f"multiple_impact = {_toml_value(problem.multiple_impact)}")
    s = problem.system
    lines += [
        "",
        "[system]",
        f"coordinates = {_toml_value(s.coordinates)}",
        f"mass_matrix = {_rows(s.mass_matrix)}",
        f"velocity = {_toml_value(s.velocity)}",
    ]
    for c in problem.contacts:
        lines += ["", "[[contacts]]"]
        if c.name is not None:
            lines.append(f"name = {_toml_value(c.name)}")
        lines.append(f"jacobian = {_rows(c.jacobian)}")
        if c.angular_jacobian is not None:
            lines.append(f"angular_jacobian = {_rows(c.angular_jacobian)}")
        law = c.contact
        lines.append(f"normal = {_toml_value(law.normal)}")
        if c.point is not None:
            lines.append(f"point = {_toml_value(law.point)}")
        if law.is_given:
            lines.append(f"impulse = {_toml_value(law.impulse)}")
            if law.moment is not None:
                lines.append(f"moment = {_toml_value(law.moment)}")
            continue
        lines += [
            f"restitution = {_toml_value(law.restitution)}",
            f'law = "{law.law}"',
            f"friction = {_toml_value(law.friction)}",
            f'tangential = "{law.tangential}"',
        ]
        if law.patch is not None:
            lines.append(f"patch = {_rows(law.patch)}")
    for k in problem.constraints:
        lines += ["", "[[constraints]]", f'type = "{k.kind}"']
        if k.name is not None:
            lines.append(f"name = {_toml_value(k.name)}")
        lines.append(f"jacobian = {_rows(k.jacobian)}")
        if k.angular_jacobian is not None:
            lines.append(f"angular_jacobian = {_rows(k.angular_jacobian)}")
        if k.point is not None:
            lines.append(f"point = {_toml_value(k.constraint.point)}")
    return "\n".join(lines) + "\n"


def _rows(matrix: Any) -> str:
    """A matrix as a TOML array of rows, one row per line."""
    rows = [_toml_value(r) for r in np.asarray(matrix, dtype=float)]
    return "[\n  " + ",\n  ".join(rows) + ",\n]"

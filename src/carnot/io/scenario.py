"""Scenario files, format 1 (DESIGN.md section 3): TOML, or the same structure in JSON.

Every error names the file and the key path, the bound and the value received, for example
``ball.toml: bodies.ball.mass: must be > 0, got -1.0``. Unknown keys are errors (a misspelt
key silently ignored would change the physics).

Limits, checked before the parser runs: a file of at most :data:`MAX_FILE_BYTES` bytes, with
brackets and braces nested at most :data:`MAX_DEPTH` deep (the deepest structure of format 1
is a patch point, four levels down; Python's JSON and TOML parsers recurse and would end in a
``RecursionError`` near 1000 levels). An integer literal of more than 4300 digits (Python's
limit on int conversion) is refused as malformed. A UTF-8 byte-order mark at the start is
accepted (editors on Windows write one). Body names may not contain control characters (a
line break in a name would break the printed table).
"""

from __future__ import annotations

import json
import re
import tomllib
import unicodedata
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from carnot import validate
from carnot.errors import InputError
from carnot.io.files import read_text
from carnot.io.tables import contact_law
from carnot.io.tables import known as _known
from carnot.io.tables import multiple_impact as _multiple_impact
from carnot.io.tables import require as _require
from carnot.io.tables import solver as _solver
from carnot.io.tables import table as _table
from carnot.io.tables import top_level as _top_level
from carnot.model.bodies import Body, FixedBody, RigidBody
from carnot.model.contacts import PointConstraint, PointContact
from carnot.model.inertia import SHAPES, shape_inertia
from carnot.model.problem import ImpactProblem
from carnot.model.system import SystemProblem

TOP_KEYS = ("format", "title", "bodies", "contacts", "constraints", "multiple_impact",
            "solver")
BODY_KEYS = ("mass", "inertia", "shape", "position", "velocity", "angular_velocity", "fixed")
CONTACT_KEYS = (
    "a", "b", "point", "normal", "restitution", "law", "friction", "tangential", "patch",
    "impulse", "moment", "name", "stiffness", "exponent",
)  # fmt: skip
CONSTRAINT_KEYS = ("type", "body", "other", "point")
SHAPE_KEYS = sorted({k for _, req, opt in SHAPES.values() for k in (*req, *opt)})
#: Largest scenario file read (bytes): a scene of 10^5 bodies at about 150 bytes each.
MAX_FILE_BYTES = 16 * 1024 * 1024
#: Deepest nesting of arrays and tables/objects accepted (format 1 needs 4).
MAX_DEPTH = 32
# What can hold a bracket that does not nest: strings (TOML's four kinds, JSON's one) and TOML
# comments. Matched first, so that only the brackets outside them are counted.
_NOT_NESTING = re.compile(
    r'"""(?:[^\\]|\\.)*?"""|\'\'\'.*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*'
    r"|(?P<open>[\[{])|(?P<close>[\]}])",
    re.DOTALL,
)


def load_scenario(path: str | Path) -> ImpactProblem:
    """Read a scenario file (``.json`` as JSON, anything else as TOML) into a problem.

    >>> load_scenario("no/such/file.toml")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: no/such/file.toml: cannot read the file (No such file or directory)
    """
    return parse_scenario(read_scenario_data(path), str(path))


def load_problem(path: str | Path) -> ImpactProblem | SystemProblem:
    """Read a scenario file of free bodies (``[bodies]``) or of a system in generalized
    coordinates (``[system]``, DESIGN.md section 7: :mod:`carnot.io.system_scenario`)."""
    data = read_scenario_data(path)
    if isinstance(data, Mapping) and "system" in data:
        from carnot.io.system_scenario import parse_system_scenario

        return parse_system_scenario(data, str(path))
    return parse_scenario(data, str(path))


def read_scenario_data(path: str | Path) -> Any:
    """The parsed contents of a scenario file (TOML, or JSON for ``.json``), unchecked."""
    source = str(path)
    # -sig: a leading byte-order mark is dropped
    text = read_text(path, MAX_FILE_BYTES, "scenario", "utf-8-sig", "UTF-8 text")
    return parse_text(text, source, json_=source.lower().endswith(".json"))


def parse_text(text: str, source: str = "<scenario>", *, json_: bool = False) -> Any:
    """Parse scenario text (TOML, or JSON with ``json_``) after checking its nesting depth.

    >>> parse_text("format = 1\\ntitle = " + "[" * 100 + "]" * 100, "deep.toml")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: deep.toml: nested deeper than 32 levels of arrays and tables (line 2)
    """
    _check_depth(text, source)
    kind = "JSON" if json_ else "TOML"
    try:
        if json_:
            return json.loads(text, object_pairs_hook=_no_duplicates)
        return tomllib.loads(text)
    except json.JSONDecodeError as err:
        raise InputError(
            source,
            f"malformed JSON at line {err.lineno}, column {err.colno}: {err.msg}",
            show_value=False,
        ) from None
    except tomllib.TOMLDecodeError as err:
        raise InputError(source, f"malformed TOML: {err}", show_value=False) from None
    except _DuplicateKeyError as err:
        raise InputError(source, f"malformed JSON: {err}", show_value=False) from None
    except ValueError as err:  # an integer of more than 4300 digits (int's limit)
        raise InputError(
            source, f"malformed {kind}: a number the parser cannot convert ({str(err)[:60]})",
            show_value=False,
        ) from None  # fmt: skip
    except RecursionError:  # pragma: no cover - _check_depth refuses such nesting first
        raise InputError(source, f"malformed {kind}: nested too deeply", show_value=False) from None


class _DuplicateKeyError(ValueError):
    pass


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object whose keys are unique (TOML refuses duplicates itself; JSON's parser would
    keep the last silently, and a value silently ignored would change the physics)."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKeyError(f"duplicate key {key!r} in one object")
        out[key] = value
    return out


def _check_depth(text: str, source: str) -> None:
    """Refuse brackets nested deeper than :data:`MAX_DEPTH` (outside strings and comments);
    unbalanced ones are left for the parser to report."""
    depth = 0
    for match in _NOT_NESTING.finditer(text):
        if match.group("open"):
            depth += 1
            if depth > MAX_DEPTH:
                line = text.count("\n", 0, match.start()) + 1
                raise InputError(
                    source,
                    f"nested deeper than {MAX_DEPTH} levels of arrays and tables (line {line})",
                    show_value=False,
                )
        elif match.group("close"):
            depth = max(depth - 1, 0)


def shaped_bodies(data: Any) -> set[str]:
    """The bodies of parsed scenario data whose inertia comes from a ``shape`` (it then scales
    with the mass)."""
    bodies = data.get("bodies", {}) if isinstance(data, Mapping) else {}
    return {n for n, b in bodies.items() if isinstance(b, Mapping) and "shape" in b}


def parse_scenario(data: Any, source: str = "<scenario>") -> ImpactProblem:
    """Build a problem from the parsed contents of a scenario file.

    >>> parse_scenario({"format": 1, "bodies": {}, "colour": "red"}, "s.toml")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: s.toml: colour: unknown key (allowed: format, title, bodies, contacts, constraints, multiple_impact, solver), got 'colour'
    """  # noqa: E501
    try:
        return _parse(data)
    except InputError as err:
        raise type(err)(
            f"{source}: {err.field}", err.problem, err.value, show_value=err.show_value
        ) from None




def _string(value: Any, field: str) -> str:
    if not isinstance(value, str) or not value:
        raise InputError(field, "must be a non-empty string", value)
    return value


def _name(value: str, field: str) -> str:
    """A body's name: no control characters (a line break or a tab would break the table
    that ``carnot solve`` prints, and the one-line error messages)."""
    if any(unicodedata.category(ch) == "Cc" for ch in value):
        raise InputError(field, "a body's name must not contain control characters", value)
    return value


def _points(value: Any, field: str) -> np.ndarray:
    """A non-empty list of [x, y, z] points, each checked like any other vector: (K, 3)."""
    if not isinstance(value, list) or not value:
        raise InputError(field, "must be a non-empty list of [x, y, z] points", value)
    return np.array([validate.vector3(point, f"{field}[{k}]") for k, point in enumerate(value)])



def _parse(data: Any) -> ImpactProblem:
    if isinstance(data, Mapping) and "system" in data:
        raise InputError("system", "a system in generalized coordinates is read by "
                         "load_problem and solved by carnot solve; this needs [bodies]",
                         show_value=False)  # fmt: skip
    top, title = _top_level(data, TOP_KEYS)
    bodies_table = _table(top.get("bodies", {}), "bodies")
    if "" in bodies_table:
        raise InputError("bodies", "a body's name must not be empty", "")
    for name in bodies_table:
        _name(name, "bodies")
    bodies: dict[str, Body] = {
        name: _body(name, _table(spec, f"bodies.{name}")) for name, spec in bodies_table.items()
    }
    contacts_list = top.get("contacts", [])
    if not isinstance(contacts_list, list):
        raise InputError("contacts", "must be an array of tables ([[contacts]])", contacts_list)
    constraints_list = top.get("constraints", [])
    if not isinstance(constraints_list, list):
        raise InputError(
            "constraints", "must be an array of tables ([[constraints]])", constraints_list
        )
    contacts = [_contact(i, _table(c, f"contacts[{i}]")) for i, c in enumerate(contacts_list)]
    constraints = [
        _constraint(i, _table(c, f"constraints[{i}]")) for i, c in enumerate(constraints_list)
    ]
    multiple_impact = _multiple_impact(top)
    return ImpactProblem(bodies=bodies, contacts=contacts, constraints=constraints, title=title,
                         multiple_impact=multiple_impact, solver=_solver(top))  # fmt: skip


def _body(name: str, spec: Mapping[str, Any]) -> Body:
    field = f"bodies.{name}"
    if "fixed" in spec:
        if spec["fixed"] is not True:
            raise InputError(f"{field}.fixed", "must be true (or absent)", spec["fixed"])
        _known(spec, (*BODY_KEYS, *SHAPE_KEYS), field)
        others = [k for k in spec if k != "fixed"]
        if others:
            raise InputError(
                f"{field}.{others[0]}",
                "a fixed body takes no other keys (it has no mass and does not move)",
                spec[others[0]],
            )
        return FixedBody(name=name)
    _known(spec, (*BODY_KEYS, *SHAPE_KEYS), field)
    shape = spec.get("shape")
    if shape is None:
        for key in spec:
            if key in SHAPE_KEYS:
                raise InputError(
                    f"{field}.{key}", "is a shape dimension: it goes with shape = ...", spec[key]
                )
    mass = validate.positive_number(_require(spec, "mass", field), f"{field}.mass")
    if shape is not None:
        if "inertia" in spec:
            raise InputError(
                f"{field}.inertia", "give either inertia or shape, not both", spec["inertia"]
            )
        inertia = _shape_inertia(field, shape, mass, spec)
    else:
        inertia = _require(spec, "inertia", field)
    return RigidBody(
        name=name,
        mass=mass,
        inertia_com=inertia,
        position_com=spec.get("position", [0.0, 0.0, 0.0]),
        velocity_com=spec.get("velocity", [0.0, 0.0, 0.0]),
        angular_velocity=spec.get("angular_velocity", [0.0, 0.0, 0.0]),
    )


def _shape_inertia(field: str, shape: Any, mass: float, spec: Mapping[str, Any]) -> Any:
    if not isinstance(shape, str) or shape not in SHAPES:
        raise InputError(f"{field}.shape", f"unknown shape (known: {', '.join(SHAPES)})", shape)
    _, required, optional = SHAPES[shape]
    dims = {k: v for k, v in spec.items() if k in SHAPE_KEYS}
    for key in dims:
        if key not in required and key not in optional:
            raise InputError(
                f"{field}.{key}",
                f"is not a dimension of shape {shape!r} (it takes: "
                f"{', '.join((*required, *optional))})",
                dims[key],
            )
    for key in required:
        if key not in dims:
            raise InputError(f"{field}.{key}", f"is required for shape {shape!r}", show_value=False)
    try:
        inertia = shape_inertia(shape, mass, **dims)
    except InputError as err:
        raise type(err)(
            f"{field}.{err.field}", err.problem, err.value, show_value=err.show_value
        ) from None
    # the inertia it gives is held to the bounds of a given one: named by the shape, which the
    # file has (a sphere of 1e-40 kg and 1e-10 m has moments of 4e-61 kg m^2)
    return validate.inertia_tensor(inertia, f"{field}.shape ({shape}: its inertia)")


def _contact(index: int, spec: Mapping[str, Any]) -> PointContact:
    field = f"contacts[{index}]"
    _known(spec, CONTACT_KEYS, field)
    a = _name(_string(_require(spec, "a", field), f"{field}.a"), f"{field}.a")
    b = _name(_string(_require(spec, "b", field), f"{field}.b"), f"{field}.b")
    return PointContact(
        where=field,
        a=a,
        b=b,
        point=_require(spec, "point", field),
        normal=_require(spec, "normal", field),
        **contact_law(spec, field),
        patch=_points(spec["patch"], f"{field}.patch") if "patch" in spec else None,
        name=_name(_string(spec["name"], f"{field}.name"), f"{field}.name") if "name" in spec
        else "",
        stiffness=spec.get("stiffness", 1.0),
        exponent=spec.get("exponent", 1.5),
    )


def _constraint(index: int, spec: Mapping[str, Any]) -> PointConstraint:
    field = f"constraints[{index}]"
    _known(spec, CONSTRAINT_KEYS, field)
    kind = _require(spec, "type", field)
    if kind not in ("fasten", "pin"):
        raise InputError(f"{field}.type", "must be 'fasten' or 'pin'", kind)
    other = spec.get("other")
    if other is not None:
        other = _string(other, f"{field}.other")
    return PointConstraint(
        where=field,
        kind=kind,
        body=_string(_require(spec, "body", field), f"{field}.body"),
        other=other,
        point=_require(spec, "point", field),
    )

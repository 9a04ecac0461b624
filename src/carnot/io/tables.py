"""Reading a scenario's tables: the checks every loader shares (bodies, ``[system]``,
``[simulation]``), each naming the key path in its message."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from carnot.errors import InputError
from carnot.laws import LAW_NAMES
from carnot.solvers.options import SolverOptions


def table(value: Any, field: str) -> Mapping[str, Any]:
    """``value`` if it is a table (key = value pairs).

    >>> table([1], "bodies.ball")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: bodies.ball: must be a table (key = value pairs), got [1]
    """
    if not isinstance(value, Mapping):
        raise InputError(field, "must be a table (key = value pairs)", value)
    return value


def known(values: Mapping[str, Any], allowed: Sequence[str], field: str) -> None:
    """Every key of ``values`` among ``allowed`` (a misspelt key is an error, not ignored).

    >>> known({"mas": 1.0}, ("mass",), "bodies.ball")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: bodies.ball.mas: unknown key (allowed: mass), got 'mas'
    """
    for key in values:
        if key not in allowed:
            prefix = f"{field}." if field else ""
            raise InputError(f"{prefix}{key}", f"unknown key (allowed: {', '.join(allowed)})", key)


def require(values: Mapping[str, Any], key: str, field: str) -> Any:
    """``values[key]``, which must be there.

    >>> require({}, "mass", "bodies.ball")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: bodies.ball.mass: is required
    """
    if key not in values:
        raise InputError(f"{field}.{key}" if field else key, "is required", show_value=False)
    return values[key]


def contact_law(spec: Mapping[str, Any], field: str) -> dict[str, Any]:
    """A contact's law keys, checked against each other (shared by the bodies' and the
    ``[system]`` loaders): ``restitution`` is required unless an ``impulse`` is given, which
    takes no law keys; ``law`` is a known hypothesis.

    >>> contact_law({"impulse": [0, 0, 1], "friction": 0.3}, "contacts[0]")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: contacts[0].friction: does not go with a given impulse, got 0.3
    """
    given = "impulse" in spec
    if not given and "restitution" not in spec:
        raise InputError(
            f"{field}.restitution",
            "is required (e in [0, 1]) unless impulse is given",
            show_value=False,
        )
    if given:
        for key in ("restitution", "law", "friction", "tangential", "patch"):
            if key in spec:
                raise InputError(f"{field}.{key}", "does not go with a given impulse", spec[key])
    law = spec.get("law", "newton")
    if law not in LAW_NAMES:
        raise InputError(f"{field}.law", f"must be one of {', '.join(LAW_NAMES)}", law)
    return {
        "restitution": spec.get("restitution", 0.0),
        "law": law,
        "friction": spec.get("friction", 0.0),
        "tangential": spec.get("tangential", "slip"),
        "impulse": spec.get("impulse"),
        "moment": spec.get("moment"),
    }


def top_level(data: Any, allowed: Sequence[str]) -> tuple[Mapping[str, Any], str]:
    """A scenario file's top table and its title, after the checks every format-1 file shares:
    a table, known keys only, ``format = 1``, a string ``title``.

    >>> top_level({"format": 2}, ("format",))
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: format: must be 1 (the only format this version reads), got 2
    """
    top = table(data, "scenario")
    known(top, allowed, "")
    fmt = require(top, "format", "scenario")
    if isinstance(fmt, bool) or fmt != 1:
        raise InputError("format", "must be 1 (the only format this version reads)", fmt)
    title = top.get("title", "")
    if not isinstance(title, str):
        raise InputError("title", "must be a string", title)
    return top, title


SOLVER_KEYS = ("name", "tolerance", "max_iterations", "trace_families")


def solver(top: Mapping[str, Any]) -> SolverOptions | None:
    """The ``[solver]`` table (DESIGN.md section 9), ``None`` where absent (``auto``).

    >>> solver({"solver": {"name": "iterative", "tolerance": 1e-10}})
    SolverOptions(name='iterative', tolerance=1e-10, max_iterations=10000, trace_families=False)
    >>> solver({"solver": {"tolerance": 2.0}})
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: solver.tolerance: must be a number in (0, 1e-3], got 2.0
    """
    if "solver" not in top:
        return None
    spec = table(top["solver"], "solver")
    known(spec, SOLVER_KEYS, "solver")
    name = spec.get("name", "auto")
    if not isinstance(name, str):
        raise InputError("solver.name", "must be a string", name)
    return SolverOptions(name=name, tolerance=spec.get("tolerance", 1e-12),
                         max_iterations=spec.get("max_iterations", 10000),
                         trace_families=spec.get("trace_families", False))  # fmt: skip


def multiple_impact(top: Mapping[str, Any]) -> str:
    """The law of several contacts at once (DESIGN.md section 6), ``simultaneous`` by default;
    its value is checked by the problem it goes to."""
    law = top.get("multiple_impact", "simultaneous")
    if not isinstance(law, str):
        raise InputError("multiple_impact", "must be a string", law)
    return law

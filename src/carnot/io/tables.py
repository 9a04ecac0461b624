"""Reading a scenario's tables: the checks every loader shares (bodies, ``[system]``,
``[simulation]``), each naming the key path in its message."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from carnot.errors import InputError


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

"""Checks at the boundary: each raises :class:`~carnot.errors.InputError` naming the field,
the bound and the value received."""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

from carnot.errors import InputError


def finite_number(value: Any, field: str) -> float:
    """A finite real number.

    >>> finite_number(2, "mass")
    2.0
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise InputError(field, "must be a number", value)
    out = float(value)
    if not math.isfinite(out):
        raise InputError(field, "must be finite", value)
    return out


def positive_number(value: Any, field: str) -> float:
    """A finite number > 0."""
    out = finite_number(value, field)
    if out <= 0.0:
        raise InputError(field, "must be > 0", value)
    return out


def number_in(value: Any, field: str, low: float, high: float) -> float:
    """A finite number in the closed interval [low, high]."""
    out = finite_number(value, field)
    if not low <= out <= high:
        raise InputError(field, f"must be in [{low:g}, {high:g}]", value)
    return out


def non_negative_number(value: Any, field: str) -> float:
    """A finite number >= 0."""
    out = finite_number(value, field)
    if out < 0.0:
        raise InputError(field, "must be >= 0", value)
    return out


def _real_entries(value: Any) -> bool:
    """Whether every entry of an array-like is a real number: not a string (numpy would read
    ``"1"`` as 1.0) and not a boolean (``True`` would be 1.0)."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "fiu":
        return True  # the common case from Python callers, without a loop
    return all(
        isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))
        for v in np.ravel(np.asarray(value, dtype=object))
    )


def vector3(value: Any, field: str) -> np.ndarray:
    """Three finite numbers, returned as a read-only float array.

    >>> vector3([0, "1", 0], "velocity")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: velocity: must be a list of 3 numbers, got [0, '1', 0]
    """
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field, "must be a list of 3 numbers", value) from None
    if arr.shape != (3,) or isinstance(value, (str, bytes)) or not _real_entries(value):
        raise InputError(field, "must be a list of 3 numbers", value)
    if not np.all(np.isfinite(arr)):
        raise InputError(field, "must be finite", value)
    arr.setflags(write=False)
    return arr


def unit_vector(value: Any, field: str) -> np.ndarray:
    """A finite non-zero 3-vector, normalised (a user may give any length)."""
    arr = vector3(value, field)
    norm = float(np.linalg.norm(arr))
    if norm == 0.0:
        raise InputError(field, "must be a non-zero vector", value)
    out = arr / norm
    out.setflags(write=False)
    return out


def matrix3(value: Any, field: str) -> np.ndarray:
    """A 3x3 matrix of finite numbers, read-only."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field, "must be a 3x3 matrix of numbers", value) from None
    if arr.shape != (3, 3) or not _real_entries(value):
        raise InputError(field, "must be a 3x3 matrix of numbers", value)
    if not np.all(np.isfinite(arr)):
        raise InputError(field, "must be finite", value)
    arr.setflags(write=False)
    return arr


def inertia_tensor(value: Any, field: str) -> np.ndarray:
    """A physically realizable inertia tensor about the centre of mass (kg m^2).

    Symmetric (to 1e-9 relative), positive definite, and each principal moment at most the
    sum of the other two (the triangle inequality that every mass distribution obeys).

    >>> inertia_tensor([[1, 0, 0], [0, 1, 0], [0, 0, 3]], "inertia")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: inertia: principal moments must each be <= ..., got [1.0, 1.0, 3.0]
    """
    arr = matrix3(value, field)
    scale = float(np.max(np.abs(arr)))
    if scale == 0.0:
        raise InputError(field, "must be positive definite", arr)
    if float(np.max(np.abs(arr - arr.T))) > 1e-9 * scale:
        raise InputError(field, "must be symmetric", arr)
    sym = 0.5 * (arr + arr.T)
    moments = np.linalg.eigvalsh(sym)
    if moments[0] <= 1e-12 * scale:
        raise InputError(
            field, "must be positive definite (principal moments > 0)", np.round(moments, 15)
        )
    if moments[2] > (moments[0] + moments[1]) * (1.0 + 1e-9):
        raise InputError(
            field,
            "principal moments must each be <= the sum of the other two "
            "(not physically realizable)",
            [float(x) for x in np.round(moments, 12)],
        )
    sym.setflags(write=False)
    return sym


def rotation_matrix(value: Any, field: str) -> np.ndarray:
    """A proper rotation (orthonormal, det +1) to 1e-9."""
    arr = matrix3(value, field)
    if float(np.max(np.abs(arr @ arr.T - np.eye(3)))) > 1e-9 or np.linalg.det(arr) < 0:
        raise InputError(field, "must be a proper rotation matrix (orthonormal, det +1)", arr)
    return arr

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


def positive_number(value: Any, field: str, unit: str = "") -> Any:
    """A finite number > 0; for an array (the batch's), every entry, returned as is.

    >>> positive_number(np.array([1.0, -2.0, 0.0]), "a.mass", unit=" kg")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: a.mass: must be > 0 kg, got [-2.0, 0.0]
    """
    if isinstance(value, np.ndarray):
        return _entries_within(value, field, low=0.0, low_open=True, problem=f"must be > 0{unit}")
    out = finite_number(value, field)
    if out <= 0.0:
        raise InputError(field, f"must be > 0{unit}", value)
    return out


def number_in(value: Any, field: str, low: float, high: float) -> Any:
    """A finite number in the closed interval [low, high]; for an array, every entry."""
    problem = f"must be in [{low:g}, {high:g}]"
    if isinstance(value, np.ndarray):
        return _entries_within(value, field, low=low, high=high, problem=problem)
    out = finite_number(value, field)
    if not low <= out <= high:
        raise InputError(field, problem, value)
    return out


def non_negative_number(value: Any, field: str) -> Any:
    """A finite number >= 0; for an array, every entry."""
    if isinstance(value, np.ndarray):
        return _entries_within(value, field, low=0.0, problem="must be >= 0")
    out = finite_number(value, field)
    if out < 0.0:
        raise InputError(field, "must be >= 0", value)
    return out


def _entries_within(
    arr: np.ndarray,
    field: str,
    *,
    problem: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
) -> np.ndarray:
    """Every entry of ``arr`` within the bounds, else an :class:`InputError` with the first
    three that are not. Reductions first (no temporary array the size of a large batch); the
    mask only when something is wrong. NaN entries are out of every bound."""
    if not arr.size:
        return arr
    smallest = arr.min()
    bad = bool(np.isnan(smallest))
    if low is not None:
        bad = bad or smallest < low or (low_open and smallest <= low)
    if high is not None:
        bad = bad or arr.max() > high
    if bad:
        ok = np.ones(arr.shape, dtype=bool)
        if low is not None:
            ok &= (arr > low) if low_open else (arr >= low)
        if high is not None:
            ok &= arr <= high
        raise InputError(field, problem, arr[~ok][:3])
    return arr


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

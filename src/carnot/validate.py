"""Checks at the boundary: each raises :class:`~carnot.errors.InputError` naming the field,
the bound and the value received.

Magnitudes (SI units) are bounded, so that no product the solver forms can overflow or
underflow float64 (largest 1.8e308, smallest normal 2.2e-308):

* every dimensional input (a coordinate, a velocity, an angular velocity, an impulse, a
  moment, an entry of an inertia tensor, a mass, a shape's dimension) has magnitude at most
  :data:`MAX_MAGNITUDE` = 1e50;
* every positive scale (a mass, a shape's dimension, a principal moment of inertia) is at
  least :data:`MIN_SCALE` = 1e-50.

Physically these are far outside anything a rigid-body impact describes (the observable
universe holds about 1e53 kg and is 1e27 m across; an electron is 9e-31 kg). Numerically, the
products the ledger forms are then bounded well inside float64: kinetic energies ``m v^2`` and
``J omega^2`` by 1e150, inverse masses ``1/m`` and ``r^2 / J`` by 1e150, the angular velocity
a given impulse can cause ``J^-1 (r x P)`` by 1e150, the velocity of a contact point
``omega x r`` by 1e200, and the theorem's ``P . w`` by 1e250. Inputs beyond them (a
velocity of 1e200 m/s, a mass of 1e-320 kg, a JSON integer of 10^400) are refused here, at
load, instead of ending in an overflow, a NaN or a failed eigenvalue routine in the solver.
A direction (a contact normal, a shape's axis) may have any finite non-zero length: only its
direction is used, to :data:`DIRECTION_RESOLUTION` (1e-100 rad).
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

from carnot.errors import InputError

#: Largest magnitude of a dimensional input, SI units (see the module docstring).
MAX_MAGNITUDE = 1e50
#: Smallest positive scale: mass (kg), shape dimension (m), principal moment of inertia
#: (kg m^2).
MIN_SCALE = 1e-50
#: Components of a direction smaller than this fraction of its largest are dropped.
DIRECTION_RESOLUTION = 1e-100
_TOO_LARGE = f"must be at most {MAX_MAGNITUDE:g} in magnitude (SI units; module carnot.validate)"


def finite_number(value: Any, field: str) -> float:
    """A finite real number of magnitude at most :data:`MAX_MAGNITUDE`.

    >>> finite_number(2, "mass")
    2.0
    >>> finite_number(10**400, "mass")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: mass: must be at most 1e+50 in magnitude (SI units; module carnot.validate), got an integer of about 401 digits
    """  # noqa: E501
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise InputError(field, "must be a number", value)
    try:
        out = float(value)
    except OverflowError:  # a Python integer beyond float64 (JSON and TOML allow them)
        raise InputError(field, _TOO_LARGE, _shown_integer(value)) from None
    if not math.isfinite(out):
        raise InputError(field, "must be finite", value)
    if abs(out) > MAX_MAGNITUDE:
        raise InputError(field, _TOO_LARGE, _shown_integer(value))
    return out


def _shown_integer(value: Any) -> Any:
    """A huge integer by its size (its repr would fill the terminal, and Python refuses to
    print one of more than 4300 digits)."""
    if isinstance(value, int) and abs(value) > 10**20:
        return _Shown(f"an integer of about {int(abs(value).bit_length() * 0.30103) + 1} digits")
    return value


class _Shown(str):
    """A value described in words: shown without quotes."""

    def __repr__(self) -> str:
        return str(self)


def positive_number(value: Any, field: str, unit: str = "") -> Any:
    """A positive physical scale (a mass, kg; a length, m): in [:data:`MIN_SCALE`,
    :data:`MAX_MAGNITUDE`]. For an array (the batch's), every entry > 0, returned as is.

    >>> positive_number(np.array([1.0, -2.0, 0.0]), "a.mass", unit=" kg")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: a.mass: must be > 0 kg, got [-2.0, 0.0]

    >>> positive_number(1e-320, "bodies.ball.mass")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: bodies.ball.mass: must be >= 1e-50 (SI units; module carnot.validate), got 1e-320
    """  # noqa: E501
    if isinstance(value, np.ndarray):
        return _entries_within(value, field, low=0.0, low_open=True, problem=f"must be > 0{unit}")
    out = finite_number(value, field)
    if out <= 0.0:
        raise InputError(field, f"must be > 0{unit}", value)
    if out < MIN_SCALE:
        raise InputError(field, f"must be >= {MIN_SCALE:g} (SI units; module carnot.validate)",
                         value)  # fmt: skip
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
    if isinstance(value, list | tuple) and _plain_numbers(value):
        return True  # the other common case: lists of floats and ints, by exact type
    return all(
        isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))
        for v in np.ravel(np.asarray(value, dtype=object))
    )


def _plain_numbers(value: list[Any] | tuple[Any, ...]) -> bool:
    """Whether ``value`` holds only ``float`` and ``int`` (exactly: ``bool`` is refused), or
    lists and tuples of them: the quick answer, before the general check of
    :func:`_real_entries`."""
    for v in value:
        kind = type(v)
        if kind is float or kind is int:
            continue
        if (kind is list or kind is tuple) and _plain_numbers(v):
            continue
        return False
    return True


def vector3(value: Any, field: str, *, bound: float = MAX_MAGNITUDE) -> np.ndarray:
    """Three finite numbers of magnitude at most ``bound``, returned as a read-only float
    array (``bound=math.inf`` for a computed state, which an impact may carry past the bound
    of its inputs).

    >>> vector3([0, "1", 0], "velocity")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: velocity: must be a list of 3 numbers, got [0, '1', 0]
    """
    arr = _direction(value, field)
    x, y, z = arr.tolist()  # three floats: Python's arithmetic beats NumPy's calls here
    if max(abs(x), abs(y), abs(z)) > bound:
        raise InputError(field, _TOO_LARGE, value)
    return arr


def _direction(value: Any, field: str) -> np.ndarray:
    """Three finite numbers (any magnitude), read-only."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field, "must be a list of 3 numbers", value) from None
    except OverflowError:  # an integer beyond float64
        raise InputError(field, _TOO_LARGE, _Shown("an integer beyond float64")) from None
    if arr.shape != (3,) or isinstance(value, (str, bytes)) or not _real_entries(value):
        raise InputError(field, "must be a list of 3 numbers", value)
    x, y, z = arr.tolist()
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        raise InputError(field, "must be finite", value)
    arr.setflags(write=False)
    return arr


def unit_vector(value: Any, field: str) -> np.ndarray:
    """A finite non-zero 3-vector, normalised (a user may give any finite length: a very long
    or very short one is scaled by its largest component first, so that neither 1e308 nor
    1e-320 over- or underflows in the norm).

    >>> unit_vector([1e308, 1e308, 0], "normal").round(12).tolist()
    [0.707106781187, 0.707106781187, 0.0]
    >>> unit_vector([0, 1, -1e308], "normal").tolist()
    [0.0, 0.0, -1.0]
    """
    arr = _direction(value, field)
    sizes = [abs(c) for c in arr.tolist()]
    largest = max(sizes)
    if largest == 0.0:
        raise InputError(field, "must be a non-zero vector", value)
    # A component below 1e-100 of the largest tilts the direction by less than 1e-100 rad:
    # nothing physical, but kept it would make ratios such as |P_t| / P_n of a contact met at
    # that grazing angle overflow float64. It is dropped.
    if any(0.0 < size < DIRECTION_RESOLUTION * largest for size in sizes):
        arr = np.where(np.abs(arr) < DIRECTION_RESOLUTION * largest, 0.0, arr)
    # scaled first only where the squares in the norm would over- or underflow (elsewhere
    # the plain quotient, whose round-off the published examples' tests pin down)
    scaled = arr if 1e-150 < largest < 1e150 else arr / largest
    out = scaled / float(np.linalg.norm(scaled))
    out.setflags(write=False)
    return out


def matrix3(value: Any, field: str) -> np.ndarray:
    """A 3x3 matrix of finite numbers, read-only."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field, "must be a 3x3 matrix of numbers", value) from None
    except OverflowError:  # an integer beyond float64
        raise InputError(field, _TOO_LARGE, _Shown("an integer beyond float64")) from None
    if arr.shape != (3, 3) or not _real_entries(value):
        raise InputError(field, "must be a 3x3 matrix of numbers", value)
    if not np.all(np.isfinite(arr)):
        raise InputError(field, "must be finite", value)
    if float(np.max(np.abs(arr))) > MAX_MAGNITUDE:
        raise InputError(field, _TOO_LARGE, arr)
    arr.setflags(write=False)
    return arr


def inertia_tensor(value: Any, field: str) -> np.ndarray:
    """A physically realizable inertia tensor about the centre of mass (kg m^2).

    Symmetric (to 1e-9 relative), positive definite with every principal moment at least
    :data:`MIN_SCALE`, and each principal moment at most the sum of the other two (the
    triangle inequality that every mass distribution obeys).

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
    if moments[0] < MIN_SCALE:
        raise InputError(
            field,
            f"principal moments must each be >= {MIN_SCALE:g} kg m^2 (module carnot.validate)",
            [float(x) for x in moments],
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

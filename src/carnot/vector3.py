"""Arithmetic on single 3-vectors without NumPy's per-call overhead.

``np.cross`` spends about 25 us a call on its axis handling and ``np.linalg.norm`` about 3 us;
a single impact makes dozens of such calls, and event-driven simulation makes one impact per
event. These write the formulas out (under 1 us each) with the same roundings: each product
rounded on its own, no fused multiply-add, so a lever parallel to the normal gives exactly
zero, as ``np.cross`` does.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Vector = NDArray[np.float64]


def cross(a: Vector, b: Vector) -> Vector:
    """``a x b`` of two 3-vectors.

    >>> cross(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])).tolist()
    [0.0, 0.0, 1.0]
    """
    return np.array(cross_floats(np.asarray(a, dtype=float).tolist(),
                                 np.asarray(b, dtype=float).tolist()))  # fmt: skip


def cross_rows(a: Vector, rows: np.ndarray) -> np.ndarray:
    """``a x c`` for each row ``c`` of a (k, 3) array.

    >>> cross_rows(np.array([0, 0, 1.0]), np.eye(3)).tolist()
    [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    """
    return np.array([cross(a, c) for c in rows]).reshape(rows.shape)


def norm(a: Vector) -> float:
    """The Euclidean length ``sqrt(a . a)`` of a vector.

    >>> norm(np.array([3.0, 4.0, 0.0]))
    5.0
    """
    a = np.asarray(a, dtype=float)
    return math.sqrt(float(a @ a))


# The same on plain lists of floats, for loops that convert once (``.tolist()``) and then do
# a few dozen products: each NumPy call on a 3-vector costs about as much as 20 float products.


def cross_floats(a: list[float], b: list[float]) -> list[float]:
    """``a x b`` on lists.

    >>> cross_floats([0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    [0.0, 1.0, 0.0]
    """
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def mat_vec_floats(m: list[list[float]], v: list[float]) -> list[float]:
    """``m v`` for a 3x3 matrix given as rows.

    >>> mat_vec_floats([[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [1.0, 2.0, 3.0])
    [2.0, 2.0, 3.0]
    """
    return [r[0] * v[0] + r[1] * v[1] + r[2] * v[2] for r in m]


def dot_floats(a: list[float], b: list[float]) -> float:
    """``a . b``.

    >>> dot_floats([1.0, 2.0, 3.0], [1.0, 1.0, 1.0])
    6.0
    """
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def length_floats(a: list[float]) -> float:
    """``|a|``.

    >>> length_floats([3.0, 4.0, 0.0])
    5.0
    """
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])

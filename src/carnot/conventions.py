"""The single statement of carnot's signs, frames and units.

* SI units throughout; one right-handed world frame; vectors are world components.
* A contact between bodies ``a`` and ``b`` has a point ``p`` and a unit normal ``n`` pointing
  from ``b`` into ``a``. Lever arms ``r_a = p - x_a``, ``r_b = p - x_b``.
* Relative velocity at the contact point ``w = (v_a + omega_a x r_a) - (v_b + omega_b x r_b)``;
  the bodies approach when ``n . w < 0``.
* The impulse ``P`` (and moment impulse ``M_P`` for a contact over a surface) is what ``a``
  receives; ``b`` receives ``-P`` (and ``-M_P``). A unilateral contact needs ``P . n >= 0``.
* Relative angular velocity ``Omega = omega_a - omega_b``.
* Energy dissipated ``E_d = E' - E''`` and, by the theorem (paper eqs. 11, 15, 16),
  ``E_d = -1/2 sum[P . (w' + w'') + M_P . (Omega' + Omega'')]``.
* Contact frame ``(n, t1, t2)``, right-handed (``t2 = n x t1``): ``t1`` is the projection onto
  the tangent plane of the world axis least aligned with ``n`` (the first such axis on a tie),
  normalised. This is deterministic and continuous away from ties.
"""

from __future__ import annotations

import math

import numpy as np

from carnot.vector3 import Vector, cross, norm

__all__ = ["RELATIVE_TOLERANCE", "Vector", "as_vector", "contact_frame", "contact_frame_into",
           "cross", "norm"]

#: Relative tolerance used to decide that a matrix is symmetric or that a velocity is zero.
RELATIVE_TOLERANCE = 1e-9


def contact_frame(normal: Vector) -> tuple[Vector, Vector, Vector]:
    """Return the right-handed contact frame ``(n, t1, t2)`` for a unit ``normal``.

    ``t1`` is the unit projection onto the tangent plane of the world axis least aligned with
    ``n``; ``t2 = n x t1``. All three are unit world vectors (dimensionless). Computed by
    :func:`contact_frame_into`, the one statement of the rule.

    >>> n, t1, t2 = contact_frame(np.array([0.0, 0.0, 1.0]))
    >>> t1.tolist(), t2.tolist()
    ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    """
    out = np.empty((3, 3))
    contact_frame_into(np.asarray(normal, dtype=float), out)
    return out[0], out[1], out[2]


def contact_frame_into(normal: np.ndarray, out: np.ndarray) -> None:
    """The contact frame of ``normal`` (any length > 0) as the rows ``n, t1, t2`` of ``out``
    (3 x 3): ``n = normal / |normal|``; ``e`` the world axis of the smallest ``|n_i|`` (the
    first on a tie); ``t1 = (e - (e . n) n) / |e - (e . n) n|``, where ``e . n = n_i``
    exactly; ``t2 = n x t1``.

    Written once, in scalar operations only, for two callers: :func:`contact_frame` runs it
    as Python, and the multi-contact batch kernel compiles this same function with Numba
    (``carnot.batch.multi_kernel.frame``), so both give the same bits (products and sums in
    the same order, no ``**``: Python's power of a float need not round as its product
    does).

    >>> out = np.empty((3, 3))
    >>> contact_frame_into(np.array([0.0, 2.0, 0.0]), out)
    >>> out.tolist()
    [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]
    """
    size = math.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
    for i in range(3):
        out[0, i] = normal[i] / size
    axis = 0
    for i in range(1, 3):
        if abs(out[0, i]) < abs(out[0, axis]):
            axis = i
    dot = out[0, axis]
    for i in range(3):
        out[1, i] = (1.0 if i == axis else 0.0) - dot * out[0, i]
    size = math.sqrt(out[1, 0] * out[1, 0] + out[1, 1] * out[1, 1] + out[1, 2] * out[1, 2])
    for i in range(3):
        out[1, i] /= size
    out[2, 0] = out[0, 1] * out[1, 2] - out[0, 2] * out[1, 1]
    out[2, 1] = out[0, 2] * out[1, 0] - out[0, 0] * out[1, 2]
    out[2, 2] = out[0, 0] * out[1, 1] - out[0, 1] * out[1, 0]


def as_vector(value: object) -> Vector:
    """A read-only float copy of a 3-vector (no validation: see the constructors)."""
    out = np.array(value, dtype=float)
    out.setflags(write=False)
    return out


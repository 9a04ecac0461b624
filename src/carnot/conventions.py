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

import numpy as np

from carnot.vector3 import Vector, cross, norm

__all__ = ["RELATIVE_TOLERANCE", "Vector", "as_vector", "contact_frame", "cross", "norm"]

#: Relative tolerance used to decide that a matrix is symmetric or that a velocity is zero.
RELATIVE_TOLERANCE = 1e-9


def contact_frame(normal: Vector) -> tuple[Vector, Vector, Vector]:
    """Return the right-handed contact frame ``(n, t1, t2)`` for a unit ``normal``.

    ``t1`` is the unit projection onto the tangent plane of the world axis least aligned with
    ``n``; ``t2 = n x t1``. All three are unit world vectors (dimensionless).

    >>> n, t1, t2 = contact_frame(np.array([0.0, 0.0, 1.0]))
    >>> t1.tolist(), t2.tolist()
    ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    """
    n = np.asarray(normal, dtype=float)
    n = n / norm(n)
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(n)))] = 1.0
    t1 = axis - (axis @ n) * n
    t1 /= norm(t1)
    t2 = cross(n, t1)
    return n, t1, t2


def as_vector(value: object) -> Vector:
    """A read-only float copy of a 3-vector (no validation: see the constructors)."""
    out = np.array(value, dtype=float)
    out.setflags(write=False)
    return out


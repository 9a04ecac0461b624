"""A batch point contact in contact space: its frame, its inverse mass ``K`` and ``w'``.

Written once for :mod:`carnot.batch.ops`. For a point contact between bodies ``a`` and ``b``
(DESIGN.md section 2: normal ``n`` from ``b`` into ``a``, levers ``r = p - x``) the relative
velocity is affine in the impulse ``P`` that ``a`` receives (paper eq. 4 and 10):

    w(P) = w' + K P,   K = (1/m_a + 1/m_b) I + [r_a]x^T J_a^-1 [r_a]x + [r_b]x^T J_b^-1 [r_b]x

In the contact frame ``(n, t1, t2)`` (the frame of :func:`carnot.conventions.contact_frame`:
``t1`` the tangent projection of the world axis least aligned with ``n``, ``t2 = n x t1``)
the entries are ``K_ij = (1/m_a + 1/m_b) d_ij + c_a,i . c_a,j + c_b,i . c_b,j`` with
``c_i = L^-1 (r x e_i)`` (``J = L L^T``): a Gram matrix, symmetric positive definite by
construction. A fixed ``b`` enters with ``movable_b = 0`` and lever ``0``.

>>> n, t1, t2 = frame((0.0, 0.0, 2.0))
>>> [float(x) + 0.0 for x in n + t1 + t2]  # + 0.0: no signed zeros
[0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
"""

from __future__ import annotations

from typing import Any

from carnot.batch.ops import formula, select, sqrt
from carnot.batch.rigid import cross, dot, lower_solve


@formula
def frame(normal: Any) -> Any:
    """``(n, t1, t2)`` from a non-zero ``normal`` of any length (unit world vectors)."""
    inv_length = 1.0 / sqrt(dot(normal, normal))
    n = (normal[0] * inv_length, normal[1] * inv_length, normal[2] * inv_length)
    ax, ay, az = abs(n[0]), abs(n[1]), abs(n[2])
    # the first axis of smallest |n_i|, as numpy.argmin picks it
    use_x = (ax <= ay) & (ax <= az)
    use_y = (ay < ax) & (ay <= az)
    # t1 = e - (e . n) n for that axis e
    t1x = select(use_x, 1.0 - n[0] * n[0], select(use_y, -n[1] * n[0], -n[2] * n[0]))
    t1y = select(use_x, -n[0] * n[1], select(use_y, 1.0 - n[1] * n[1], -n[2] * n[1]))
    t1z = select(use_x, -n[0] * n[2], select(use_y, -n[1] * n[2], 1.0 - n[2] * n[2]))
    inv_size = 1.0 / sqrt(t1x * t1x + t1y * t1y + t1z * t1z)
    t1 = (t1x * inv_size, t1y * inv_size, t1z * inv_size)
    return n, t1, cross(n, t1)


@formula
def lever_columns(chol: Any, r: Any, n: Any, t1: Any, t2: Any) -> Any:
    """``c_i = L^-1 (r x e_i)`` for ``e = n, t1, t2`` (units kg^-1/2)."""
    return (lower_solve(chol, cross(r, n)), lower_solve(chol, cross(r, t1)),
            lower_solve(chol, cross(r, t2)))  # fmt: skip


@formula
def inverse_mass(inv_mass: Any, ca: Any, cb: Any) -> Any:
    """``K`` in the contact frame (1/kg): ``(k_nn, k_n1, k_n2, k_11, k_12, k_22)``."""
    return (inv_mass + dot(ca[0], ca[0]) + dot(cb[0], cb[0]),
            dot(ca[0], ca[1]) + dot(cb[0], cb[1]),
            dot(ca[0], ca[2]) + dot(cb[0], cb[2]),
            inv_mass + dot(ca[1], ca[1]) + dot(cb[1], cb[1]),
            dot(ca[1], ca[2]) + dot(cb[1], cb[2]),
            inv_mass + dot(ca[2], ca[2]) + dot(cb[2], cb[2]))  # fmt: skip


@formula
def to_world(q: Any, n: Any, t1: Any, t2: Any) -> Any:
    """World components of the contact-frame vector ``q = (q_n, q_1, q_2)``."""
    return (q[0] * n[0] + q[1] * t1[0] + q[2] * t2[0],
            q[0] * n[1] + q[1] * t1[1] + q[2] * t2[1],
            q[0] * n[2] + q[1] * t1[2] + q[2] * t2[2])  # fmt: skip


@formula
def k_times(k: Any, q: Any) -> Any:
    """``K q`` in the contact frame."""
    return (k[0] * q[0] + k[1] * q[1] + k[2] * q[2],
            k[1] * q[0] + k[3] * q[1] + k[4] * q[2],
            k[2] * q[0] + k[4] * q[1] + k[5] * q[2])  # fmt: skip

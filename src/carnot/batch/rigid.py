"""One rigid body's share of a batch impact: its inertia factor, velocity update and energy.

Written once for :mod:`carnot.batch.ops` (scalars compiled by Numba, or arrays of impacts).
Vectors are tuples ``(x, y, z)`` of world components; a symmetric inertia tensor about the
centre of mass (kg m^2, world axes) is the tuple of its nine entries, row by row.

The inertia tensor enters through its Cholesky factor ``J_C = L L^T`` (``L`` lower
triangular, kept as ``(1/l00, l10, 1/l11, l20, l21, 1/l22)``: the reciprocal diagonal, so that
the solves multiply): then ``J_C^-1 = L^-T L^-1``, the rotational part of the contact's
inverse mass is the Gram matrix of the vectors ``L^-1 (r x e)``, and every inverse is two
triangular solves, which are backward stable (an explicit inverse is not).

>>> l, ok = factor((4.0, 0.0, 0.0, 0.0, 9.0, 0.0, 0.0, 0.0, 9.0))
>>> [round(float(x), 12) for x in l], bool(ok)
([0.5, 0.0, 0.333333333333, 0.0, 0.0, 0.333333333333], True)
>>> [float(x) for x in inverse_inertia_times(l, (4.0, 9.0, 18.0))]
[1.0, 1.0, 2.0]
"""

from __future__ import annotations

from typing import Any

from carnot.batch.ops import formula, select, sqrt

#: Relative slack of the symmetry and realizability checks of an inertia tensor (the sums
#: and products that make a tensor rotated into world axes carry this much round-off).
INERTIA_SLACK = 1e-10


@formula
def cross(u: Any, v: Any) -> Any:
    """``u x v``."""
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0])  # fmt: skip


@formula
def dot(u: Any, v: Any) -> Any:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@formula
def factor(j: Any) -> Any:
    """Cholesky factor ``L`` of ``J_C`` and whether ``J_C`` is a valid inertia tensor:
    symmetric, positive definite and realizable (each principal moment at most the sum
    of the other two, i.e. ``tr(J)/2 I - J``, the second moment of the mass about the
    centre, positive semi-definite: all seven principal minors >= 0)."""
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = j
    trace = j00 + j11 + j22
    tol = INERTIA_SLACK * abs(trace)
    symmetric = ((abs(j01 - j10) <= tol) & (abs(j02 - j20) <= tol)
                 & (abs(j12 - j21) <= tol))  # fmt: skip
    s00, s11, s22 = 0.5 * trace - j00, 0.5 * trace - j11, 0.5 * trace - j22
    tol2 = tol * abs(trace)
    # the seven principal minors, combined as a shallow tree (a chain of seven would stall)
    diagonal = ((s00 >= -tol) & (s11 >= -tol)) & (s22 >= -tol)
    pairs = (((s00 * s11 - j01 * j01 >= -tol2) & (s11 * s22 - j12 * j12 >= -tol2))
             & (s00 * s22 - j02 * j02 >= -tol2))  # fmt: skip
    # det S, with S's off-diagonal entries -j01, -j02, -j12
    det = ((s00 * s11) * s22 - 2.0 * (j01 * j12) * j02
           - ((s00 * (j12 * j12) + s11 * (j02 * j02)) + s22 * (j01 * j01)))  # fmt: skip
    realizable = (diagonal & pairs) & (det >= -tol2 * abs(trace))
    # the diagonal of L is kept as its reciprocals: the solves then multiply, not divide
    d0 = j00
    i00 = 1.0 / sqrt(select(d0 > 0, d0, 1.0))
    l10 = j01 * i00
    l20 = j02 * i00
    d1 = j11 - l10 * l10
    i11 = 1.0 / sqrt(select(d1 > 0, d1, 1.0))
    l21 = (j12 - l20 * l10) * i11
    d2 = j22 - l20 * l20 - l21 * l21
    i22 = 1.0 / sqrt(select(d2 > 0, d2, 1.0))
    valid = symmetric & realizable & (d0 > 0) & (d1 > 0) & (d2 > 0)
    return (i00, l10, i11, l20, l21, i22), valid


@formula
def lower_solve(chol: Any, u: Any) -> Any:
    """``L^-1 u`` (forward substitution)."""
    y0 = u[0] * chol[0]
    y1 = (u[1] - chol[1] * y0) * chol[2]
    y2 = (u[2] - chol[3] * y0 - chol[4] * y1) * chol[5]
    return (y0, y1, y2)


@formula
def upper_solve(chol: Any, y: Any) -> Any:
    """``L^-T y`` (back substitution)."""
    z2 = y[2] * chol[5]
    z1 = (y[1] - chol[4] * z2) * chol[2]
    z0 = (y[0] - chol[1] * z1 - chol[3] * z2) * chol[0]
    return (z0, z1, z2)


@formula
def inverse_inertia_times(chol: Any, u: Any) -> Any:
    """``J_C^-1 u = L^-T L^-1 u`` (1/(kg m^2) times ``u``)."""
    return upper_solve(chol, lower_solve(chol, u))


@formula
def point_velocity(v: Any, omega: Any, r: Any) -> Any:
    """``v + omega x r`` (m/s): the velocity of the body's point at lever ``r``."""
    c = cross(omega, r)
    return (v[0] + c[0], v[1] + c[1], v[2] + c[2])


@formula
def kinetic_energy(mass: Any, j: Any, v: Any, omega: Any) -> Any:
    """Koenig: ``1/2 m |v|^2 + 1/2 omega . J_C omega`` (J; paper eq. 5)."""
    jw = (j[0] * omega[0] + j[1] * omega[1] + j[2] * omega[2],
          j[3] * omega[0] + j[4] * omega[1] + j[5] * omega[2],
          j[6] * omega[0] + j[7] * omega[1] + j[8] * omega[2])  # fmt: skip
    return 0.5 * (mass * dot(v, v) + dot(omega, jw))

"""Batch kernels for two-body and body-obstacle 3D point impacts (NumPy).

For a point contact with lever arms ``r_a = p - x_a`` and ``r_b = p - x_b`` the relative
velocity is an affine function of the impulse ``P`` that body ``a`` receives,

    w(P) = w' + K P,     K = I/m_a - [r_a]x J_a^-1 [r_a]x + I/m_b - [r_b]x J_b^-1 [r_b]x

(``[r]x`` the cross-product matrix; the ``b`` terms vanish for a fixed obstacle), which is the
contact block of the Delassus operator of :mod:`carnot.system`. The laws of this first part:

* frictionless Newton: ``P = -(1 + e) (n . w') / (n . K n) n``;
* stick (Newton's restitution, no slip after): ``P = K^-1 (w'' - w')`` with
  ``w'' = -e (n . w') n``; the friction coefficient it needs is ``|P_t| / P_n``.

Shapes: masses and coefficients ``(...)``, vectors ``(..., 3)``, inertia tensors
``(..., 3, 3)`` (world axes, about the centre of mass), all broadcast together. Per-impact
regimes and flags are masks, never Python branches on values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from carnot.errors import InputError

#: ``regime`` codes of :class:`BatchImpacts` (stable, for files).
FRICTIONLESS, STICK = 0, 1


@dataclass(frozen=True, kw_only=True, eq=False)
class BatchBodies:
    """A batch of rigid bodies: ``mass`` (kg), ``inertia_com`` (kg m^2, world axes),
    ``position_com`` (m), ``velocity_com`` (m/s), ``angular_velocity`` (rad/s)."""

    mass: Any
    inertia_com: Any
    position_com: Any
    velocity_com: Any = 0.0
    angular_velocity: Any = 0.0


@dataclass(frozen=True, kw_only=True, eq=False)
class BatchImpacts:
    """What a batch of impacts produced, one entry per impact (shapes as the inputs').

    ``impulse`` (N s) is what ``a`` receives; velocities after (m/s, rad/s; ``None`` for a
    fixed ``b``); energies in J: ``before``, ``after``, ``dissipated`` (direct),
    ``dissipated_theorem`` (``-1/2 P . (w' + w'')``), its ``dissipated_normal`` and
    ``dissipated_tangential`` parts, ``lost_velocities`` (Carnot's ``E_p``); ``regime``
    (``FRICTIONLESS`` or ``STICK``); boolean flags ``not_approaching``,
    ``negative_normal_impulse``, ``friction_insufficient``, ``energy_gain``;
    ``friction_required`` (``|P_t| / P_n`` for stick, NaN otherwise)."""

    impulse: np.ndarray
    normal_impulse: np.ndarray
    velocity_a: np.ndarray
    angular_velocity_a: np.ndarray
    velocity_b: np.ndarray | None
    angular_velocity_b: np.ndarray | None
    relative_velocity_before: np.ndarray
    relative_velocity_after: np.ndarray
    before: np.ndarray
    after: np.ndarray
    dissipated: np.ndarray
    dissipated_theorem: np.ndarray
    dissipated_normal: np.ndarray
    dissipated_tangential: np.ndarray
    lost_velocities: np.ndarray
    regime: np.ndarray
    friction_required: np.ndarray
    not_approaching: np.ndarray
    negative_normal_impulse: np.ndarray
    friction_insufficient: np.ndarray
    energy_gain: np.ndarray


def _cross_matrix(r: np.ndarray) -> np.ndarray:
    """``[r]x`` with ``[r]x q = r x q``: shape ``(..., 3, 3)``."""
    z = np.zeros_like(r[..., 0])
    x, y, w = r[..., 0], r[..., 1], r[..., 2]
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1),
                     np.stack([-y, x, z], -1)], -2)  # fmt: skip


def _matvec(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...ij,...j->...i", m, v)


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", u, v)


class _Side:
    """One body's share of the contact: lever, inverse inertia, its block of ``K``."""

    def __init__(self, body: BatchBodies, point: np.ndarray):
        self.mass = np.asarray(body.mass, dtype=float)
        self.inertia = np.asarray(body.inertia_com, dtype=float)
        self.velocity = np.asarray(body.velocity_com, dtype=float) * np.ones(3)
        self.omega = np.asarray(body.angular_velocity, dtype=float) * np.ones(3)
        self.lever = point - np.asarray(body.position_com, dtype=float)
        self.inertia_inv = np.linalg.inv(self.inertia)
        cross = _cross_matrix(self.lever)
        self.k = np.eye(3) / self.mass[..., None, None] - cross @ self.inertia_inv @ cross

    def point_velocity(self) -> np.ndarray:
        return self.velocity + np.cross(self.omega, self.lever)

    def after(self, impulse: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Velocities after receiving ``impulse`` at the contact point."""
        return (self.velocity + impulse / self.mass[..., None],
                self.omega + _matvec(self.inertia_inv, np.cross(self.lever, impulse)))  # fmt: skip

    def energy(self, v: np.ndarray, om: np.ndarray) -> np.ndarray:
        return 0.5 * (self.mass * _dot(v, v) + _dot(om, _matvec(self.inertia, om)))


def point_impacts(
    a: BatchBodies,
    b: BatchBodies | None,
    point: Any,
    normal: Any,
    restitution: Any,
    *,
    tangential: str = "slip",
    friction: Any = 0.0,
) -> BatchImpacts:
    """Solve a batch of point impacts between ``a`` and ``b`` (``None``: a fixed obstacle).

    ``point`` (m) and ``normal`` (from ``b`` into ``a``, any length) per impact;
    ``restitution`` e in [0, 1] (Newton's); ``tangential``: ``"slip"`` (frictionless here:
    Coulomb slip in batch comes with issue #5's next part) or ``"stick"``; ``friction``: the
    mu that a sticking impulse is checked against (0: not checked).

    A ball (1 kg, I = 0.004) dropped at 2 m/s on a floor with e = 0.5 and e = 1:

    >>> ball = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.004, position_com=[0, 0, 0.1],
    ...                    velocity_com=[0, 0, -2.0])
    >>> out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.array([0.5, 1.0]))
    >>> out.velocity_a[:, 2].tolist(), out.dissipated.round(12).tolist()
    ([1.0, 2.0], [1.5, 0.0])
    """
    if tangential not in ("slip", "stick"):
        raise InputError("tangential", "must be 'slip' or 'stick'", tangential)
    friction_arr = np.asarray(friction, dtype=float)
    if tangential == "slip" and np.any(friction_arr > 0):
        raise InputError(
            "friction",
            "Coulomb slip is not in the batch kernels yet (issue #5): use friction = 0, "
            'tangential = "stick", or carnot.solve_impact one impact at a time',
            float(np.max(friction_arr)),
        )
    e = np.asarray(restitution, dtype=float)
    e = np.broadcast_to(e, np.broadcast_shapes(e.shape, friction_arr.shape))  # outputs' shape
    if np.any(~np.isfinite(e)) or np.any((e < 0) | (e > 1)):
        raise InputError("restitution", "must be in [0, 1]", e[(e < 0) | (e > 1)].tolist()[:3])
    p = np.asarray(point, dtype=float)
    n = np.asarray(normal, dtype=float)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    if np.any(~(length > 0)):
        raise InputError("normal", "must be non-zero and finite", n.tolist())
    n = n / length
    side_a = _Side(a, p)
    side_b = _Side(b, p) if b is not None else None
    k = side_a.k if side_b is None else side_a.k + side_b.k
    w1 = side_a.point_velocity() - (0.0 if side_b is None else side_b.point_velocity())
    w1_n = _dot(n, w1)
    if tangential == "slip":
        p_n = -(1.0 + e) * w1_n / _dot(n, _matvec(k, n))
        impulse = p_n[..., None] * n
        regime = np.full(p_n.shape, FRICTIONLESS, dtype=np.int8)
    else:
        target = -(e * w1_n)[..., None] * n
        impulse = np.linalg.solve(k, (target - w1)[..., None])[..., 0]
        regime = np.full(w1_n.shape, STICK, dtype=np.int8)
    p_n = _dot(impulse, n)
    p_t = impulse - p_n[..., None] * n
    v_a, om_a = side_a.after(impulse)
    e_before = side_a.energy(side_a.velocity, side_a.omega)
    e_after = side_a.energy(v_a, om_a)
    lost = side_a.energy(v_a - side_a.velocity, om_a - side_a.omega)
    v_b = om_b = None
    if side_b is not None:
        v_b, om_b = side_b.after(-impulse)
        e_before = e_before + side_b.energy(side_b.velocity, side_b.omega)
        e_after = e_after + side_b.energy(v_b, om_b)
        lost = lost + side_b.energy(v_b - side_b.velocity, om_b - side_b.omega)
    w2 = w1 + _matvec(k, impulse)
    w_sum = w1 + w2
    d_normal = -0.5 * p_n * _dot(n, w_sum)
    d_tangential = -0.5 * _dot(p_t, w_sum)
    dissipated = e_before - e_after
    scale = np.linalg.norm(impulse, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        required = np.where(regime == STICK, np.linalg.norm(p_t, axis=-1) / p_n, np.nan)
    return BatchImpacts(
        impulse=impulse,
        normal_impulse=p_n,
        velocity_a=v_a,
        angular_velocity_a=om_a,
        velocity_b=v_b,
        angular_velocity_b=om_b,
        relative_velocity_before=w1,
        relative_velocity_after=w2,
        before=e_before,
        after=e_after,
        dissipated=dissipated,
        dissipated_theorem=d_normal + d_tangential,
        dissipated_normal=d_normal,
        dissipated_tangential=d_tangential,
        lost_velocities=lost,
        regime=regime,
        friction_required=required,
        not_approaching=w1_n >= 0,
        negative_normal_impulse=p_n < -1e-12 * scale,
        friction_insufficient=(regime == STICK) & (friction_arr > 0)
        & ~(required <= friction_arr * (1 + 1e-12)),
        energy_gain=dissipated < -1e-12 * e_before,
    )

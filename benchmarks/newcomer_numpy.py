"""The baseline of issue #5: point impacts in NumPy as a newcomer would write them.

Straight from the textbook formulas, on ``(N, 3, 3)`` stacks: ``numpy.linalg.inv`` of the
inertia tensors, ``numpy.cross``, ``einsum`` for the products, ``numpy.linalg.solve`` for
stick. Correct (the benchmark checks it against carnot.batch), vectorized, and every step
writes a temporary array: this is what carnot.batch's fused kernels are measured against.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def _cross_matrix(r: np.ndarray) -> np.ndarray:
    z = np.zeros_like(r[..., 0])
    x, y, w = r[..., 0], r[..., 1], r[..., 2]
    return np.stack([np.stack([z, -w, y], -1), np.stack([w, z, -x], -1),
                     np.stack([-y, x, z], -1)], -2)  # fmt: skip


def _matvec(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...ij,...j->...i", m, v)


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", u, v)


def point_impacts(a: Any, b: Any, point: np.ndarray, normal: np.ndarray, e: np.ndarray,
                  stick: bool = False) -> dict[str, np.ndarray]:  # fmt: skip
    """Impulse, velocities after and the energy ledger of N two-body point impacts."""
    n = normal / np.linalg.norm(normal, axis=-1, keepdims=True)
    sides = []
    for body in (a, b):
        inv = np.linalg.inv(body.inertia_com)
        r = point - body.position_com
        cr = _cross_matrix(r)
        k = np.eye(3) / body.mass[:, None, None] - cr @ inv @ cr
        sides.append((body, inv, r, k))
    k = sides[0][3] + sides[1][3]
    w1 = ((a.velocity_com + np.cross(a.angular_velocity, sides[0][2]))
          - (b.velocity_com + np.cross(b.angular_velocity, sides[1][2])))  # fmt: skip
    w1_n = _dot(n, w1)
    if stick:
        target = -(e * w1_n)[:, None] * n
        impulse = np.linalg.solve(k, (target - w1)[..., None])[..., 0]
    else:
        impulse = (-(1 + e) * w1_n / _dot(n, _matvec(k, n)))[:, None] * n
    out: dict[str, np.ndarray] = {"impulse": impulse}
    before = after = 0.0
    for sign, (body, inv, r, _) in zip((1.0, -1.0), sides, strict=True):
        v2 = body.velocity_com + sign * impulse / body.mass[:, None]
        om2 = body.angular_velocity + _matvec(inv, np.cross(r, sign * impulse))
        before = before + 0.5 * (body.mass * _dot(body.velocity_com, body.velocity_com)
                                 + _dot(body.angular_velocity,
                                        _matvec(body.inertia_com, body.angular_velocity)))
        after = after + 0.5 * (body.mass * _dot(v2, v2) + _dot(om2, _matvec(body.inertia_com,
                                                                             om2)))
        out[f"v{len(out)}"], out[f"w{len(out)}"] = v2, om2
    w2 = w1 + _matvec(k, impulse)
    out["dissipated"] = before - after
    out["dissipated_theorem"] = -0.5 * _dot(impulse, w1 + w2)
    return out

"""The first impact of a spinning convex body's corners on a plane, in closed form.

In free flight without ground motion a body turning at a constant angular velocity ``omega``
(an isotropic body such as a cube, or a rotation about a principal axis: ``Flight.kind ==
"constant"``) has ``R(s) = Rot(u, w s) R0`` (``w = |omega|``, ``u = omega / w``), so that by
Rodrigues' formula the gap of corner ``k`` (lever ``r_k = R0 s_k``) above the plane ``(p, n)``
is

    g_k(s) = c_k + b s + a s^2 + B_k cos(w s) + C_k sin(w s),
    a = n.g/2,  b = n.v0,  c_k = n.(x0 - p) + (n.u)(u.r_k),
    B_k = n.r_k - (n.u)(u.r_k),  C_k = n.(u x r_k) = r_k.(n x u).

Its roots are found without sampling, so none can be missed between samples:
``g'' = 2a - w^2 (B cos + C sin) = 2a - w^2 rho cos(w s - phi)`` vanishes only where
``cos(w s - phi) = 2a / (w^2 rho)``, in closed form. Between two such instants ``g'`` is
monotone, so it has at most one zero there (``g``'s extremum, found by a bracketed Newton
iteration); between those, ``g`` is monotone, and it crosses a level there exactly when its
values at the two ends lie on either side (a bracketed Newton iteration then locates the
crossing to ``~1e-15`` s). The segments are visited in time order, so the root found is the
first. A tangent touch (a minimum exactly at the level) counts as reaching it (``<=``): it is
reported at the minimum, not skipped.

A corner touching at the start (its level negative: :func:`carnot.simulate.events.
trigger_levels`) counts once it has opened by ``eps`` (first crossing of ``+eps`` upward), or
earlier if it sinks below its level first: the semantics of the sampled search it replaces.

Compiled by Numba when present (cached beside this file); without it, the same functions run
as Python.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

try:
    import numba
except ImportError:  # pragma: no cover - numba is a dependency; plain Python without it
    numba = None  # type: ignore[assignment]

_jit: Callable[[Any], Any] = (
    numba.njit(cache=True, nogil=True, error_model="numpy") if numba else lambda f: f
)

#: Iterations allowed to one bracketed Newton search (each at least halves a stalled bracket
#: every other step: 200 is far beyond the 1e-15 s it needs from any bracket up to 1e3 s).
MAX_ITERATIONS = 200


@_jit
def _value(c: float, b: float, a: float, bb: float, cc: float, w: float, s: float,
           order: int) -> float:  # fmt: skip
    """``g``, ``g'`` or ``g''`` (``order`` 0, 1, 2) of one corner at ``s``."""
    cs, sn = math.cos(w * s), math.sin(w * s)
    if order == 0:
        return c + s * (b + a * s) + bb * cs + cc * sn
    if order == 1:
        return b + 2.0 * a * s + w * (cc * cs - bb * sn)
    return 2.0 * a - w * w * (bb * cs + cc * sn)


@_jit
def _crossing(c: float, b: float, a: float, bb: float, cc: float, w: float, lo: float,
              hi: float, order: int, level: float) -> float:  # fmt: skip
    """The zero of ``g^(order) - level`` in ``[lo, hi]``, where it is monotone and changes sign
    (Newton's steps kept inside the bracket, bisection when one leaves it or stalls)."""
    f_lo = _value(c, b, a, bb, cc, w, lo, order) - level
    if f_lo == 0.0:
        return lo
    rising = f_lo < 0.0
    x = 0.5 * (lo + hi)
    for _ in range(MAX_ITERATIONS):
        fx = _value(c, b, a, bb, cc, w, x, order) - level
        if fx == 0.0:
            return x
        if (fx < 0.0) == rising:
            lo = x
        else:
            hi = x
        if hi - lo <= 4e-16 * max(1.0, abs(x)):
            break
        d = _value(c, b, a, bb, cc, w, x, order + 1)
        step = fx / d if d != 0.0 else 0.0
        nxt = x - step
        if not (lo < nxt < hi) or abs(step) > 0.5 * (hi - lo):
            nxt = 0.5 * (lo + hi)  # Newton left the bracket or halves it no better: bisect
        if nxt == x:
            break
        x = nxt
    return x


@_jit
def _above(c: float, b: float, a: float, lo: float, hi: float) -> bool:
    """Whether ``c + b s + a s^2 > 0`` on all of ``[lo, hi]``: with ``c`` the corner's ``c_k -
    rho_k - level``, a lower bound of ``g - level`` there (the rotation's term is at least
    ``-rho``), so that no root can lie in the interval."""
    low = min(lo * (b + a * lo), hi * (b + a * hi))
    if a > 0.0:
        apex = -b / (2.0 * a)
        if lo < apex < hi:
            low = min(low, apex * (b + a * apex))
    # a margin of the round-off of the terms: what it cannot tell from 0 is not excluded
    return c + low > 1e-14 * (abs(c) + abs(low))


@_jit
def _first_below(c: float, b: float, a: float, bb: float, cc: float, w: float, level: float,
                 start: float, stop: float, sign: float) -> float:  # fmt: skip
    """The first ``s`` in ``[start, stop]`` where ``sign g(s) <= sign level`` (sign 1: the gap
    falls to ``level``; -1: it rises to it), given that it does not hold at ``start``; ``inf``
    when there is none."""
    c, b, a, bb, cc, level = sign * c, sign * b, sign * a, sign * bb, sign * cc, sign * level
    rho = math.hypot(bb, cc)
    if _above(c - rho - level, b, a, start, stop):
        return math.inf
    # the zeros of g'': w s - phi = +-alpha + 2 pi m (none when |kappa| > 1 or no rotation)
    phi = math.atan2(cc, bb)
    has_breaks = w > 0.0 and rho > 0.0 and abs(2.0 * a) <= w * w * rho
    alpha = math.acos(2.0 * a / (w * w * rho)) if has_breaks else 0.0
    two_pi = 2.0 * math.pi
    m = math.floor((w * start - phi + alpha) / two_pi) - 1.0  # at or before start
    half = 0  # 0: the next angle is -alpha + 2 pi m; 1: +alpha + 2 pi m
    left = start
    g_left = _value(c, b, a, bb, cc, w, left, 0)
    while left < stop:
        right = stop
        if has_breaks:
            while True:
                angle = (alpha if half else -alpha) + two_pi * m
                if half:
                    m += 1.0
                half = 1 - half
                t = (angle + phi) / w
                if t > left:
                    right = min(t, stop)
                    break
        if _above(c - rho - level, b, a, left, right):  # this piece stays above the level
            left = right
            g_left = _value(c, b, a, bb, cc, w, left, 0)
            continue
        # g' monotone on [left, right]: a minimum inside (g' rising through 0) splits it in
        # two monotone parts; a maximum need not (g > level on an interval about it, so the
        # level is crossed once, after it: bracketed by [left, right] as it stands)
        d_left = _value(c, b, a, bb, cc, w, left, 1)
        d_right = _value(c, b, a, bb, cc, w, right, 1)
        mid = right
        if d_left < 0.0 < d_right:
            mid = _crossing(c, b, a, bb, cc, w, left, right, 1, 0.0)
        for end in (mid, right):
            if end <= left:
                continue
            g_end = _value(c, b, a, bb, cc, w, end, 0)
            if g_end <= level:
                if g_left <= level:
                    return left
                return _crossing(c, b, a, bb, cc, w, left, end, 0, level)
            left, g_left = end, g_end
        left = right
    return math.inf


@_jit
def _lever(rot0: np.ndarray, verts: np.ndarray, k: int) -> tuple[float, float, float]:
    """``r_k = R0 s_k`` (m, world axes)."""
    return (rot0[0, 0] * verts[k, 0] + rot0[0, 1] * verts[k, 1] + rot0[0, 2] * verts[k, 2],
            rot0[1, 0] * verts[k, 0] + rot0[1, 1] * verts[k, 1] + rot0[1, 2] * verts[k, 2],
            rot0[2, 0] * verts[k, 0] + rot0[2, 1] * verts[k, 1] + rot0[2, 2] * verts[k, 2])


@_jit
def first_corner_impact(verts: np.ndarray, rot0: np.ndarray, x0: np.ndarray, v0: np.ndarray,
                        omega: np.ndarray, gravity: np.ndarray, normal: np.ndarray,
                        point: np.ndarray, levels: np.ndarray, eps: float,
                        horizon: float) -> float:  # fmt: skip
    """The first time (s, in ``[0, horizon]``; ``inf`` for none) at which a corner ``verts``
    (K, 3, body axes) of a body flying from ``x0`` (m) with ``v0`` (m/s), rotation matrix
    ``rot0`` and constant ``omega`` (rad/s) under ``gravity`` (m/s^2) reaches the plane
    ``(point, normal)``: each corner's ``levels`` as in the module docstring (0: open).

    >>> cube = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
    >>> s = first_corner_impact(0.1 * cube, np.eye(3), np.array([0.0, 1.1, 0.0]), np.zeros(3),
    ...                         np.zeros(3), np.array([0.0, -10.0, 0.0]), np.array([0.0, 1.0, 0.0]),
    ...                         np.zeros(3), np.zeros(8), 1e-9, 10.0)
    >>> round(s, 12)  # no spin: the bottom face falls 1 m, sqrt(2 / 10) s
    0.4472135955
    """
    n0, n1, n2 = normal[0], normal[1], normal[2]
    speed = math.sqrt(omega[0] ** 2 + omega[1] ** 2 + omega[2] ** 2)
    u0 = u1 = u2 = 0.0
    if speed > 0.0:
        u0, u1, u2 = omega[0] / speed, omega[1] / speed, omega[2] / speed
    nu = n0 * u0 + n1 * u1 + n2 * u2
    # n x u: C_k = r_k . (n x u)
    m0, m1, m2 = n1 * u2 - n2 * u1, n2 * u0 - n0 * u2, n0 * u1 - n1 * u0
    base = n0 * (x0[0] - point[0]) + n1 * (x0[1] - point[1]) + n2 * (x0[2] - point[2])
    a = 0.5 * (n0 * gravity[0] + n1 * gravity[1] + n2 * gravity[2])
    b = n0 * v0[0] + n1 * v0[1] + n2 * v0[2]
    best = math.inf
    bound = math.inf  # by then some open corner has certainly crossed (g <= c + rho + b s + a s^2)
    if a < 0.0:
        for k in range(verts.shape[0]):
            if levels[k] < 0.0:
                continue
            r0, r1, r2 = _lever(rot0, verts, k)
            ur = u0 * r0 + u1 * r1 + u2 * r2
            rho = math.hypot(n0 * r0 + n1 * r1 + n2 * r2 - nu * ur, r0 * m0 + r1 * m1 + r2 * m2)
            top = base + nu * ur + rho - levels[k]  # > 0: the corner is open
            # the positive root of top + b s + a s^2 (a < 0), by the stable formula
            q = -0.5 * (b + math.copysign(math.sqrt(b * b - 4.0 * a * top), b))
            # (widened a little: a cap on the search that round-off must not make too short)
            bound = min(bound, max(q / a, top / q if q != 0.0 else 0.0) * (1.0 + 1e-9))
    for k in range(verts.shape[0]):
        r0, r1, r2 = _lever(rot0, verts, k)
        ur = u0 * r0 + u1 * r1 + u2 * r2
        c = base + nu * ur
        bb = n0 * r0 + n1 * r1 + n2 * r2 - nu * ur
        cc = r0 * m0 + r1 * m1 + r2 * m2
        level = levels[k]
        stop = min(horizon, best, bound)
        if level < 0.0:  # touching at the start: armed once open by eps, or sunk below level
            opened = _first_below(c, b, a, bb, cc, speed, eps, 0.0, stop, -1.0)
            root = _first_below(c, b, a, bb, cc, speed, level, 0.0, min(opened, stop), 1.0)
            if root == math.inf and opened < stop:
                root = _first_below(c, b, a, bb, cc, speed, 0.0, opened, stop, 1.0)
        else:
            root = _first_below(c, b, a, bb, cc, speed, level, 0.0, stop, 1.0)
        if root < best:
            best = root
    return best


@_jit
def corner_kinematics(verts: np.ndarray, q: np.ndarray, x: np.ndarray, v: np.ndarray,
                      omega: np.ndarray, normal: np.ndarray, point: np.ndarray
                      ) -> np.ndarray:  # fmt: skip
    """Gaps (m, row 0) and normal velocities (m/s, row 1) of corners ``verts`` (K, 3, body
    axes) of a body at ``x`` with unit quaternion ``q = [w, x, y, z]``, velocity ``v`` and
    angular velocity ``omega``, on the plane ``(point, normal)``: ``g_k = n . (x + r_k - p)``
    and ``w_n = n . v + r_k . (n x omega)``, ``r_k = R(q) s_k``.

    >>> out = corner_kinematics(np.array([[0.0, -1.0, 0.0]]), np.array([1.0, 0, 0, 0]),
    ...                         np.array([0.0, 3.0, 0.0]), np.array([0.0, -2.0, 0.0]),
    ...                         np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0]), np.zeros(3))
    >>> out.tolist()  # 2 m up, falling at 2 m/s (the spin moves the corner sideways)
    [[2.0], [-2.0]]
    """
    qw, qx, qy, qz = q[0], q[1], q[2], q[3]
    # n^T R: the plane's normal in body axes, so that n . r_k = (R^T n) . s_k
    r00, r01, r02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)
    r10, r11, r12 = 2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)
    r20, r21, r22 = 2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)
    n0, n1, n2 = normal[0], normal[1], normal[2]
    c0, c1, c2 = n1 * omega[2] - n2 * omega[1], n2 * omega[0] - n0 * omega[2], \
        n0 * omega[1] - n1 * omega[0]  # fmt: skip
    base = n0 * (x[0] - point[0]) + n1 * (x[1] - point[1]) + n2 * (x[2] - point[2])
    vn = n0 * v[0] + n1 * v[1] + n2 * v[2]
    out = np.empty((2, verts.shape[0]))
    for k in range(verts.shape[0]):
        s0, s1, s2 = verts[k, 0], verts[k, 1], verts[k, 2]
        l0 = r00 * s0 + r01 * s1 + r02 * s2
        l1 = r10 * s0 + r11 * s1 + r12 * s2
        l2 = r20 * s0 + r21 * s1 + r22 * s2
        out[0, k] = n0 * l0 + n1 * l1 + n2 * l2 + base
        out[1, k] = l0 * c0 + l1 * c1 + l2 * c2 + vn
    return out

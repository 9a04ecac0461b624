"""Bodies, states and free flight under gravity.

A body's state: centre-of-mass position ``x`` (m), orientation the unit quaternion
``q = [w, x, y, z]`` taking body axes to world axes, velocity ``v`` (m/s) and angular velocity
``omega`` (rad/s), both world components. Free flight separates:

- translation, exact: ``x(s) = x0 + v0 s + g s^2/2 - (d_g(t0 + s) - d_g(t0) - v_g(t0) s)``
  (the last term only with ground motion: ground.py);
- rotation without torque, exact where a closed form exists: a constant ``omega`` (an
  isotropic body, or a rotation about a principal axis), and an axisymmetric body (moments
  ``A, A, C`` about the symmetry axis ``k``): with ``L = J omega`` constant,
  ``omega = L/A + mu k``, ``mu = (1/C - 1/A)(k . L)``, so that
  ``R(s) = Rot(L, |L| s/A) R0 Rot_body(k, mu s)`` (regular precession);
  otherwise Euler's equations ``J_b omega_b' = -omega_b x J_b omega_b`` with
  ``q' = 1/2 q (0, omega_b)``, integrated by SciPy's DOP853 (rtol 1e-12) with dense output.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from carnot.keys import exact_key
from carnot.records import Record
from carnot.simulate.ground import Ground
from carnot.simulate.shapes import Convex, Shape, is_flat

#: Relative tolerance deciding that moments of inertia are equal or a rotation is permanent.
SYMMETRY_TOLERANCE = 1e-12
#: Longest stretch (s) of one numerical flight before the state is renewed (bounded memory).
NUMERIC_HORIZON = 2.0


@dataclass(frozen=True, kw_only=True, eq=False)
class SimBody:
    """A movable body: ``mass`` (kg), ``inertia_body`` (kg m^2, body axes, about the centre of
    mass), its ``shape``. Principal moments are worked out once for the closed forms.

    >>> from carnot.simulate.shapes import Sphere
    >>> b = SimBody(name="ball", mass=1.0, inertia_body=np.eye(3) * 0.004,
    ...             shape=Sphere(radius=0.1))
    >>> b.rotation_kind
    'isotropic'
    """

    name: str
    mass: float
    inertia_body: np.ndarray
    shape: Shape
    inertia_body_inv: np.ndarray = field(init=False)
    rotation_kind: str = field(init=False)
    symmetry_axis_body: np.ndarray = field(init=False)
    moment_transverse: float = field(init=False)
    moment_axial: float = field(init=False)
    plane_normal_body: np.ndarray | None = field(init=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        inertia = np.array(self.inertia_body, dtype=float)  # (its own, read-only: the values
        inertia.setflags(write=False)  # worked out from it below and value_key stay true)
        set_(self, "inertia_body", inertia)
        normal = None
        if isinstance(self.shape, Convex) and is_flat(self.shape.vertices_body):
            centred = self.shape.vertices_body - self.shape.vertices_body.mean(axis=0)
            normal = np.linalg.svd(centred)[2][2]
        set_(self, "plane_normal_body", normal)
        set_(self, "inertia_body_inv", np.linalg.inv(self.inertia_body))
        moments, axes = np.linalg.eigh(self.inertia_body)
        scale = float(moments[-1])
        same = np.abs(np.diff(moments)) <= SYMMETRY_TOLERANCE * scale
        if same.all():
            kind, axis, a, c = "isotropic", axes[:, 0], moments[0], moments[0]
        elif same[0]:
            kind, axis, a, c = "axisymmetric", axes[:, 2], moments[0], moments[2]
        elif same[1]:
            kind, axis, a, c = "axisymmetric", axes[:, 0], moments[2], moments[0]
        else:
            kind, axis, a, c = "general", axes[:, 0], moments[0], moments[0]
        set_(self, "rotation_kind", kind)
        set_(self, "symmetry_axis_body", axis)
        set_(self, "moment_transverse", float(a))
        set_(self, "moment_axial", float(c))

    @cached_property
    def value_key(self) -> tuple[str, float, tuple[float, ...]]:
        """The body's name, mass and inertia entries (:func:`carnot.keys.exact_key`): what a
        cache of things made from them (its :class:`carnot.RigidBody`) is keyed on."""
        return self.name, self.mass, exact_key(self.inertia_body.ravel().tolist())

    @cached_property
    def inertia_scalar(self) -> bool:
        """Whether the inertia is exactly ``c I`` (a ball, a cube): then ``R J_b R^T = J_b``
        in every orientation, exactly."""
        j = self.inertia_body
        return bool(np.array_equal(j, j[0, 0] * np.eye(3)))

    def planar_velocity(self, rotation: np.ndarray, velocity: np.ndarray,
                        angular_velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A polygon (a lamina: rocking block, rimless wheel drawn in 2D) moves in its plane:
        its velocity along the plane's normal ``n`` and its angular velocity across ``n`` are
        removed, ``v - (v . n) n`` and ``(omega . n) n``; anything else is returned as is.
        (A lamina on two corners is balanced on an edge in 3D: without this, round-off would
        topple it out of its plane.)"""
        if self.plane_normal_body is None:
            return velocity, angular_velocity
        n = rotation @ self.plane_normal_body
        return velocity - (velocity @ n) * n, (angular_velocity @ n) * n

    def inertia_world(self, rotation: np.ndarray) -> np.ndarray:
        """``J = R J_b R^T`` (kg m^2, world axes)."""
        return rotation @ self.inertia_body @ rotation.T


@dataclass(frozen=True, kw_only=True, eq=False)
class BodyState(Record):
    """Position (m), orientation quaternion ``[w, x, y, z]``, velocity (m/s) and angular
    velocity (rad/s) of a body, world components.

    >>> s = BodyState.from_floats([0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, -2.0, 0.0],
    ...                           [0.0, 0.0, 3.0], rotation=True)
    >>> s.with_motion(np.zeros(3), np.zeros(3)).rotation is s.rotation
    True
    """

    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray

    @cached_property
    def rotation(self) -> np.ndarray:
        """The rotation matrix of ``orientation`` (read-only; worked out once per state: an
        event reads it for the gaps, the impact's inertia and the next flight)."""
        out = quat_matrix(self.orientation)
        out.setflags(write=False)
        return out

    @classmethod
    def from_floats(cls, position: list[float], orientation: list[float],
                    velocity: list[float], angular_velocity: list[float], *,
                    rotation: bool = False) -> BodyState:  # fmt: skip
        """The state of these floats (m; the unit quaternion's four; m/s; rad/s), each made an
        array; ``rotation``: with its :attr:`rotation` worked out at once from the
        quaternion's floats (the lean event loop reads it at the next step)."""
        out = object.__new__(cls)  # (its fields as __init__ sets them, in order: a test's)
        out.__dict__.update(position=np.array(position), orientation=np.array(orientation),
                            velocity=np.array(velocity),
                            angular_velocity=np.array(angular_velocity))  # fmt: skip
        if rotation:  # (the property's value, from the same floats: quat_matrix's route)
            matrix = np.array(rotation_entries(*orientation)).reshape(3, 3)
            matrix.setflags(write=False)
            out.__dict__["rotation"] = matrix
        return out

    def with_motion(self, velocity: np.ndarray, angular_velocity: np.ndarray) -> BodyState:
        """The same position and orientation (its :attr:`rotation` too, if worked out) with
        another ``velocity`` (m/s) and ``angular_velocity`` (rad/s): the state an impact
        leaves."""
        out = object.__new__(BodyState)  # (as from_floats)
        out.__dict__.update(position=self.position, orientation=self.orientation,
                            velocity=velocity, angular_velocity=angular_velocity)
        known = self.__dict__.get("rotation")
        if known is not None:  # the same orientation: its matrix, worked out once
            out.__dict__["rotation"] = known
        return out

    def as_array(self) -> np.ndarray:
        return np.concatenate([self.position, self.orientation, self.velocity,
                               self.angular_velocity])  # fmt: skip

    @classmethod
    def from_array(cls, y: np.ndarray) -> BodyState:
        q = y[3:7] / np.linalg.norm(y[3:7])
        return cls(position=y[0:3].copy(), orientation=q, velocity=y[7:10].copy(),
                   angular_velocity=y[10:13].copy())  # fmt: skip


def quat_matrix(q: np.ndarray) -> np.ndarray:
    """The rotation matrix of unit quaternion(s) ``q = [w, x, y, z]`` ((4,) or (N, 4)).

    >>> np.round(quat_matrix(np.array([np.cos(0.25 * np.pi), 0, 0, np.sin(0.25 * np.pi)])), 12)
    ... # doctest: +NORMALIZE_WHITESPACE
    array([[ 0., -1.,  0.], [ 1.,  0.,  0.], [ 0.,  0.,  1.]])
    """
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:  # one quaternion: plain floats (NumPy's per-call cost dominates here)
        return np.array(rotation_entries(*q.tolist())).reshape(3, 3)
    w, x, y, z = np.moveaxis(q, -1, 0)
    out = np.stack([
        1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
        2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
        2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
    ], axis=-1)  # fmt: skip
    return out.reshape(*out.shape[:-1], 3, 3)


def rotation_entries(w: float, x: float, y: float, z: float) -> list[float]:
    """The nine entries, row by row, of the rotation matrix of the unit quaternion
    ``[w, x, y, z]`` (:func:`quat_matrix`'s, on floats: the lean event loop's route too).

    >>> rotation_entries(1.0, 0.0, 0.0, 0.0)
    [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    """
    return [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
            2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
            2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a b`` (broadcast over leading dimensions)."""
    if a.ndim == 1 and b.ndim == 1:
        aw, ax, ay, az = a.tolist()
        bw, bx, by, bz = b.tolist()
        return np.array([aw * bw - ax * bx - ay * by - az * bz,
                         aw * bx + ax * bw + ay * bz - az * by,
                         aw * by - ax * bz + ay * bw + az * bx,
                         aw * bz + ax * by - ay * bx + az * bw])  # fmt: skip
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ], axis=-1)  # fmt: skip


def quat_about(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Quaternions of rotations by ``angle`` (rad, (N,)) about the unit ``axis``: (N, 4)."""
    half = np.asarray(angle, dtype=float)[..., None] / 2
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


def _quat_scalar(axis: np.ndarray, angle: float) -> np.ndarray:
    half = 0.5 * angle
    return np.concatenate([[np.cos(half)], np.sin(half) * axis])


def quat_from_rotvec(rotvec: np.ndarray) -> np.ndarray:
    """The quaternion of the rotation vector ``rotvec`` (axis times angle, rad)."""
    angle = float(np.linalg.norm(rotvec))
    if angle == 0.0:
        return np.array([1.0, 0.0, 0.0, 0.0])
    return quat_about(rotvec / angle, np.array(angle))


class Flight:
    """Free flight of one body from ``t0`` with ``state0`` under uniform ``gravity`` (m/s^2) and
    the ground's inertia force (see the module docstring). ``at(s)`` gives position,
    quaternion, velocity and angular velocity at times ``s`` after ``t0`` (arrays (N, ...)).

    >>> from carnot.simulate.shapes import Sphere
    >>> ball = SimBody(name="b", mass=1.0, inertia_body=np.eye(3), shape=Sphere(radius=0.1))
    >>> s0 = BodyState(position=np.zeros(3), orientation=np.array([1.0, 0, 0, 0]),
    ...                velocity=np.array([0, 2.0, 0]), angular_velocity=np.zeros(3))
    >>> x, q, v, w = Flight(ball, 0.0, s0, np.array([0, -10.0, 0]), None).at(np.array([0.2]))
    >>> np.round(x[0], 12).tolist(), np.round(v[0], 12).tolist()
    ([0.0, 0.2, 0.0], [0.0, 0.0, 0.0])
    """

    def __init__(self, body: SimBody, t0: float, state0: BodyState, gravity: np.ndarray,
                 ground: Ground | None, horizon: float = np.inf) -> None:  # fmt: skip
        self.body, self.t0, self.state0 = body, t0, state0
        self.gravity, self.ground = gravity, ground
        w0 = state0.angular_velocity
        self.kind: str
        self.horizon = horizon
        if body.rotation_kind == "isotropic":  # (no inertia needed: the common case, fast)
            # (the norm as state() takes it: a spin whose square underflows is none)
            self.kind = "constant" if spin_rate(w0) > 0.0 else "still"
            return
        r0 = state0.rotation
        j_world = body.inertia_world(r0)
        momentum = j_world @ w0
        speed = float(np.linalg.norm(w0))
        if speed == 0.0:
            self.kind = "still"
        elif float(np.linalg.norm(
                np.cross(momentum, w0))) <= SYMMETRY_TOLERANCE * float(
                np.linalg.norm(momentum)) * speed:  # fmt: skip
            self.kind = "constant"
        elif body.rotation_kind == "axisymmetric":
            self.kind = "axisymmetric"
            self.momentum = momentum
            self.k_body = body.symmetry_axis_body
            k_world = r0 @ self.k_body
            a, c = body.moment_transverse, body.moment_axial
            self.precession = float(np.linalg.norm(momentum)) / a
            self.l_axis = momentum / float(np.linalg.norm(momentum))
            self.spin = (1 / c - 1 / a) * float(k_world @ momentum)
        else:
            from scipy.integrate import solve_ivp

            self.kind = "numeric"
            self.horizon = min(horizon, NUMERIC_HORIZON)
            jb, jb_inv = body.inertia_body, body.inertia_body_inv

            def euler(_: float, y: np.ndarray) -> np.ndarray:
                q, wb = y[:4], y[4:]
                dq = 0.5 * quat_multiply(q, np.concatenate([[0.0], wb]))
                return np.concatenate([dq, -jb_inv @ np.cross(wb, jb @ wb)])

            y0 = np.concatenate([state0.orientation, r0.T @ w0])
            self.solution = solve_ivp(euler, (0.0, self.horizon), y0, method="DOP853",
                                      rtol=1e-12, atol=1e-13, dense_output=True).sol

    def rotation_at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Quaternions (N, 4) and angular velocities (N, 3, rad/s) at times ``s`` (N,)."""
        q0, w0 = self.state0.orientation, self.state0.angular_velocity
        n = len(s)
        if self.kind == "still":
            return np.tile(q0, (n, 1)), np.zeros((n, 3))
        if self.kind == "constant":
            speed = float(np.linalg.norm(w0))
            turn = quat_about(w0 / speed, speed * s)
            return quat_multiply(turn, q0), np.tile(w0, (n, 1))
        if self.kind == "axisymmetric":
            outer = quat_about(self.l_axis, self.precession * s)
            inner = quat_about(self.k_body, self.spin * s)
            q = quat_multiply(quat_multiply(outer, q0), inner)
            k_world = np.einsum("nij,j->ni", quat_matrix(q), self.k_body)
            a = self.body.moment_transverse
            return q, self.momentum / a + self.spin * k_world
        y = self.solution(np.asarray(s, dtype=float))
        q = (y[:4] / np.linalg.norm(y[:4], axis=0)).T
        return q, np.einsum("nij,nj->ni", quat_matrix(q), y[4:].T)

    def translation_at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions (N, 3, m) and velocities (N, 3, m/s) at times ``s`` (N,)."""
        s = np.asarray(s, dtype=float)[:, None]
        x = self.state0.position + self.state0.velocity * s + 0.5 * self.gravity * s * s
        v = self.state0.velocity + self.gravity * s
        if self.ground is not None:
            g, t0 = self.ground, self.t0
            d0, vg0 = g.displacement(t0), g.velocity(t0)
            x = x - np.array([g.displacement(t0 + si) - d0 - vg0 * si for si in s[:, 0]])
            v = v - np.array([g.velocity(t0 + si) - vg0 for si in s[:, 0]])
        return x, v

    def at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        x, v = self.translation_at(s)
        q, w = self.rotation_at(s)
        return x, q, v, w

    def state(self, s: float) -> BodyState:
        if self.ground is None and self.kind in ("still", "constant"):
            # one time, closed forms: the scalar route (the arrays' per-call cost was a
            # tenth of an event's)
            s0 = self.state0
            xs, qs, vs = flight_floats(s0.position.tolist(), s0.orientation.tolist(),
                                       s0.velocity.tolist(), s0.angular_velocity.tolist(),
                                       self.gravity.tolist(), s,
                                       spin_rate(s0.angular_velocity)
                                       if self.kind == "constant" else 0.0)  # fmt: skip
            return BodyState(position=np.array(xs), orientation=np.array(qs),
                             velocity=np.array(vs), angular_velocity=s0.angular_velocity.copy())
        x, q, v, w = self.at(np.array([s]))
        return BodyState(position=x[0], orientation=q[0] / np.linalg.norm(q[0]), velocity=v[0],
                         angular_velocity=w[0])  # fmt: skip

    def point_at(self, s: float, point_body: np.ndarray) -> np.ndarray:
        """World position (m) of one body point at one time ``s`` (a scalar route for the
        root finder: the array route's per-call overhead dominates one point)."""
        x = self.state0.position + self.state0.velocity * s + 0.5 * self.gravity * s * s
        if self.ground is not None:
            g, t0 = self.ground, self.t0
            x = x - (g.displacement(t0 + s) - g.displacement(t0) - g.velocity(t0) * s)
        q0 = self.state0.orientation
        if self.kind == "still":
            q = q0
        elif self.kind == "constant":
            w0 = self.state0.angular_velocity
            speed = float(np.linalg.norm(w0))
            q = quat_multiply(_quat_scalar(w0 / speed, speed * s), q0)
        elif self.kind == "axisymmetric":
            q = quat_multiply(quat_multiply(_quat_scalar(self.l_axis, self.precession * s), q0),
                              _quat_scalar(self.k_body, self.spin * s))  # fmt: skip
        else:
            q = self.solution(s)[:4]
            q = q / np.linalg.norm(q)
        return x + quat_matrix(q) @ point_body

    def points(self, s: np.ndarray, points_body: np.ndarray) -> np.ndarray:
        """World positions (N, K, 3) of body points ``points_body`` (K, 3) at times ``s``."""
        x, _ = self.translation_at(s)
        q, _ = self.rotation_at(s)
        return x[:, None, :] + np.einsum("nij,kj->nki", quat_matrix(q), points_body)


def spin_rate(w: np.ndarray) -> float:
    """``|omega|`` (rad/s): :func:`numpy.linalg.norm`'s arithmetic (the square root of the
    dot product), without its per-call cost. A spin whose square underflows is none: the
    flight is then ``still``, and nothing divides by it.

    >>> spin_rate(np.array([3.0, 0.0, 4.0]))
    5.0
    """
    return math.sqrt(float(w.dot(w)))


def flight_floats(x0: Sequence[float], q0: Sequence[float], v0: Sequence[float],
                  w0: Sequence[float], g: Sequence[float], s: float, speed: float
                  ) -> tuple[list[float], list[float], list[float]]:  # fmt: skip
    """Position (m), unit quaternion and velocity (m/s) ``s`` seconds into a flight at constant
    angular velocity ``w0`` (of norm ``speed``: :func:`spin_rate`; 0, not turning) under
    gravity ``g`` (m/s^2), without ground motion: ``x0 + v0 s + g s^2/2``, ``v0 + g s`` and
    ``Rot(w0 / |w0|, |w0| s) q0`` (Hamilton's product, normalised), on Python floats
    (:meth:`Flight.state`'s route, and the lean event loop's: one time, a handful of numbers,
    where NumPy's per-call cost dominates).

    >>> x, q, v = flight_floats([0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0],
    ...                         [0.0, 0.0, math.pi], [0.0, -10.0, 0.0], 0.5, math.pi)
    >>> x, [round(e, 12) for e in q], v    # a quarter turn about z in half a second
    ([0.0, -0.25, 0.0], [0.707106781187, 0.0, 0.0, 0.707106781187], [0.0, -5.0, 0.0])
    """
    ss = s * s
    # x0 + v0 s + g s^2/2 and v0 + g s, in the array route's order (written out: this runs at
    # every event)
    x0_0, x0_1, x0_2 = x0
    v0_0, v0_1, v0_2 = v0
    g0, g1, g2 = g
    x = [x0_0 + v0_0 * s + 0.5 * g0 * ss, x0_1 + v0_1 * s + 0.5 * g1 * ss,
         x0_2 + v0_2 * s + 0.5 * g2 * ss]
    v = [v0_0 + g0 * s, v0_1 + g1 * s, v0_2 + g2 * s]
    if speed == 0.0:
        return x, list(q0), v
    w0_0, w0_1, w0_2 = w0
    # the turn's quaternion times q0 (Hamilton), normalised
    half = 0.5 * speed * s
    c, k = math.cos(half), math.sin(half) / speed
    a1, a2, a3 = k * w0_0, k * w0_1, k * w0_2
    b0, b1, b2, b3 = q0
    e0 = c * b0 - a1 * b1 - a2 * b2 - a3 * b3
    e1 = c * b1 + a1 * b0 + a2 * b3 - a3 * b2
    e2 = c * b2 - a1 * b3 + a2 * b0 + a3 * b1
    e3 = c * b3 + a1 * b2 - a2 * b1 + a3 * b0
    size = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2 + e3 * e3)
    return x, [e0 / size, e1 / size, e2 / size, e3 / size], v


def kinetic_energy(body: SimBody, state: BodyState) -> float:
    """Koenig: ``1/2 m v.v + 1/2 omega . J omega`` (J)."""
    w = state.angular_velocity
    j = body.inertia_world(state.rotation)
    return float(0.5 * body.mass * state.velocity @ state.velocity + 0.5 * w @ j @ w)


def potential_energy(body: SimBody, state: BodyState, gravity: np.ndarray) -> float:
    """``-m g . x`` (J), zero at the world origin."""
    return float(-body.mass * gravity @ state.position)


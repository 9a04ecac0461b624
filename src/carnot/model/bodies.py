"""Rigid bodies and fixed obstacles.

A movable body carries its mass ``m`` (kg), inertia tensor ``J_C`` about its centre of mass in
world axes (kg m^2), the centre-of-mass position ``x`` (m), velocity ``v`` (m/s) and angular
velocity ``omega`` (rad/s). A fixed obstacle has none of these: its rows drop out of the
contact space (DESIGN.md section 1).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from carnot import validate
from carnot.conventions import Vector
from carnot.errors import InputError
from carnot.vector3 import cross


@dataclass(frozen=True, kw_only=True, eq=False)
class RigidBody:
    """A free rigid body, validated on construction.

    Kinetic energy by Koenig's formula (paper eq. 5): ``E = 1/2 (m v.v + omega . J_C omega)``.

    >>> ball = RigidBody(mass=2.0, inertia_com=np.eye(3) * 0.1, velocity_com=[1.0, 0, 0])
    >>> ball.kinetic_energy()
    1.0
    """

    mass: float
    inertia_com: Vector
    position_com: Vector = field(default_factory=lambda: np.zeros(3))
    velocity_com: Vector = field(default_factory=lambda: np.zeros(3))
    angular_velocity: Vector = field(default_factory=lambda: np.zeros(3))
    name: str = "body"
    inertia_com_inv: Vector = field(init=False, repr=False)

    def __post_init__(self) -> None:
        prefix = f"bodies.{self.name}."
        set_ = object.__setattr__
        set_(self, "mass", validate.positive_number(self.mass, prefix + "mass"))
        set_(self, "inertia_com", validate.inertia_tensor(self.inertia_com, prefix + "inertia"))
        set_(self, "position_com", validate.vector3(self.position_com, prefix + "position"))
        set_(self, "velocity_com", validate.vector3(self.velocity_com, prefix + "velocity"))
        set_(
            self,
            "angular_velocity",
            validate.vector3(self.angular_velocity, prefix + "angular_velocity"),
        )
        inverse = np.linalg.inv(self.inertia_com)  # once here: every solve needs J_C^-1
        inverse.setflags(write=False)
        set_(self, "inertia_com_inv", inverse)

    fixed = False

    @cached_property
    def motion_com(self) -> Vector:
        """``(v, omega)`` stacked (m/s, rad/s), read-only: the body's part of ``u``."""
        out = np.concatenate([self.velocity_com, self.angular_velocity])
        out.setflags(write=False)
        return out

    @cached_property
    def float_state(self) -> tuple[float, tuple[float, ...], tuple[float, ...],
                                   tuple[float, ...], tuple[float, ...]]:  # fmt: skip
        """``(m, J_C, x_C, v_C, omega)`` as Python floats (kg; the nine entries of ``J_C``
        row by row, kg m^2; m; m/s; rad/s): what the float formulas of :mod:`carnot.single`
        read."""
        return (self.mass, tuple(self.inertia_com.ravel().tolist()),
                tuple(self.position_com.tolist()), tuple(self.velocity_com.tolist()),
                tuple(self.angular_velocity.tolist()))  # fmt: skip

    @cached_property
    def mass_block(self) -> Vector:
        """The body's 6x6 block of ``M``, ``diag(m I, J_C)`` (kg, kg m^2), read-only."""
        out = np.zeros((6, 6))
        out[:3, :3] = self.mass * np.eye(3)
        out[3:, 3:] = self.inertia_com
        out.setflags(write=False)
        return out

    @cached_property
    def mass_block_inv(self) -> Vector:
        """``diag(I / m, J_C^-1)`` (1/kg, 1/(kg m^2)), read-only."""
        out = np.zeros((6, 6))
        out[:3, :3] = np.eye(3) / self.mass
        out[3:, 3:] = self.inertia_com_inv
        out.setflags(write=False)
        return out

    def velocity_of_point(self, point: Any) -> Vector:
        """Velocity (m/s) of the body point at world position ``point``: ``v + omega x r``."""
        r = np.asarray(point, dtype=float) - self.position_com
        return self.velocity_com + cross(self.angular_velocity, r)

    def kinetic_energy(self) -> float:
        """Koenig's kinetic energy (J), paper eq. (5)."""
        v, w = self.velocity_com, self.angular_velocity
        return float(0.5 * (self.mass * (v @ v) + w @ self.inertia_com @ w))

    def linear_momentum(self) -> Vector:
        """``m v`` (kg m/s)."""
        return self.mass * self.velocity_com

    def angular_momentum_about(self, point: Any) -> Vector:
        """Angular momentum about a fixed world point (kg m^2/s): ``J_C omega + r_CP x m v``
        with ``r = x - point``."""
        r = self.position_com - np.asarray(point, dtype=float)
        return self.inertia_com @ self.angular_velocity + cross(r, self.mass * self.velocity_com)

    def turned(self, rotation: Any) -> RigidBody:
        """The same body turned about its centre of mass by the proper rotation ``rotation``
        (a 3x3 matrix, world axes; orthonormal with det +1, to 1e-9): its inertia
        ``R J_C R^T`` and the inverse ``R J_C^-1 R^T``, each made exactly symmetric, rotated
        from this body's rather than validated and inverted again (a rotation keeps the
        symmetry, the principal moments and their triangle inequality: what the constructor
        checks); position and motion kept.

        >>> rod = RigidBody(mass=1.0, inertia_com=np.diag([1.0, 2.0, 2.0]))
        >>> quarter = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
        >>> rod.turned(quarter).inertia_com.diagonal().tolist()
        [2.0, 1.0, 2.0]
        """
        try:
            rot = np.asarray(rotation, dtype=float)
            plain = rot.shape == (3, 3) and _plainly_rotation(rot.tolist())
        except (TypeError, ValueError):
            plain = False
        if not plain:  # (the boundary's check, with its message: a tenth of an impact)
            rot = validate.rotation_matrix(rotation, f"bodies.{self.name}.rotation")
        out = self._copy()
        for derived in ("mass_block", "mass_block_inv", "float_state"):  # (of the inertia)
            out.__dict__.pop(derived, None)
        for key, tensor in (("inertia_com", self.inertia_com),
                            ("inertia_com_inv", self.inertia_com_inv)):  # fmt: skip
            world = rot @ tensor @ rot.T
            world = 0.5 * (world + world.T)
            world.setflags(write=False)
            object.__setattr__(out, key, world)
        return out

    def moved(self, position_com: Sequence[float], velocity_com: Sequence[float],
              angular_velocity: Sequence[float]) -> RigidBody:  # fmt: skip
        """The same body (mass, inertia) at ``position_com`` (m) with ``velocity_com`` (m/s)
        and ``angular_velocity`` (rad/s), three floats each, world components: a computed
        state, finite (an :class:`~carnot.errors.InputError` naming the field otherwise) but
        not held to the bound on inputs. Its :attr:`float_state` is made at once (the float
        formulas read it first), with this body's inertia entries.

        >>> ball = RigidBody(mass=2.0, inertia_com=np.eye(3) * 0.1)
        >>> ball.moved([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]).kinetic_energy()
        1.0
        """
        x, v, w = tuple(position_com), tuple(velocity_com), tuple(angular_velocity)
        out = self._copy()
        fields = out.__dict__
        fields.pop("motion_com", None)
        checked = len(x) == len(v) == len(w) == 3 and all(map(math.isfinite, x + v + w))
        for key, value in (("position_com", x), ("velocity_com", v),
                           ("angular_velocity", w)):  # fmt: skip
            if not checked and (len(value) != 3 or not all(map(math.isfinite, value))):
                raise InputError(f"bodies.{self.name}.{key.removesuffix('_com')}",
                                 "must be 3 finite numbers", list(value))  # fmt: skip
            arr = np.array(value, dtype=float)
            arr.setflags(write=False)
            fields[key] = arr  # (a copy of this body, made here: the constructor's way)
        fields["float_state"] = (self.mass, self.float_state[1], x, v, w)
        return out

    def _copy(self) -> RigidBody:
        """A shallow copy (its ``__dict__``, cached properties included), for the methods
        above to set fields on before it is returned: what ``copy.copy`` makes, without its
        generic protocol (a sixth of the cost)."""
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        return out

    def with_motion(self, velocity_com: Any, angular_velocity: Any) -> RigidBody:
        """The same body with another velocity state: a computed one, finite but not held to
        the bound on inputs (an impact may carry it past 1e50)."""
        out = copy.copy(self)
        # the copy keeps the cached inertia blocks (same inertia) but not the old motion
        out.__dict__.pop("motion_com", None)
        out.__dict__.pop("float_state", None)
        prefix = f"bodies.{self.name}."
        for key, value in (("velocity_com", velocity_com), ("angular_velocity", angular_velocity)):
            field_ = prefix + key.removesuffix("_com")
            object.__setattr__(out, key, validate.vector3(value, field_, bound=math.inf))
        return out


def _plainly_rotation(rows: list[list[float]]) -> bool:
    """Whether the 3x3 ``rows`` are orthonormal to 1e-10 with det > 0: stricter than
    :func:`carnot.validate.rotation_matrix` (1e-9), so what passes here passes there, in a
    tenth of its time (floats, no NumPy calls); a NaN or an infinity fails.

    >>> _plainly_rotation([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    True
    >>> _plainly_rotation([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])
    False
    """
    (a, b, c), (d, e, f), (g, h, i) = rows
    tol = 1e-10
    return (abs(a * a + b * b + c * c - 1.0) <= tol and abs(d * d + e * e + f * f - 1.0) <= tol
            and abs(g * g + h * h + i * i - 1.0) <= tol and abs(a * d + b * e + c * f) <= tol
            and abs(a * g + b * h + c * i) <= tol and abs(d * g + e * h + f * i) <= tol
            and a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) > 0.0)


@dataclass(frozen=True, kw_only=True, eq=False)
class FixedBody:
    """An immovable obstacle (the ground, a ledge, the world frame): no mass, no velocity.

    >>> FixedBody(name="ground").fixed
    True
    """

    name: str = "ground"
    fixed = True

    def velocity_of_point(self, point: Any) -> Vector:
        """Always zero (m/s)."""
        return np.zeros(3)


Body = RigidBody | FixedBody

"""Rigid bodies and fixed obstacles.

A movable body carries its mass ``m`` (kg), inertia tensor ``J_C`` about its centre of mass in
world axes (kg m^2), the centre-of-mass position ``x`` (m), velocity ``v`` (m/s) and angular
velocity ``omega`` (rad/s). A fixed obstacle has none of these: its rows drop out of the
contact space (DESIGN.md section 1).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from carnot import validate
from carnot.conventions import Vector
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

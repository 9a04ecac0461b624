"""Planar chains of slender links (pendulums, a cart-pole, chains) built two ways: in
generalized coordinates (absolute link angles, and the base's coordinates) and as free rigid
bodies joined by pins. The tests check that the two front ends give the same impact.

Link ``k`` (length ``l_k``, mass ``m_k``, uniform) makes the angle ``theta_k`` with the x axis
in the x-y plane; the point at distance ``d`` along it from its proximal joint is at

    p = b + sum_{j<k} l_j e(theta_j) + d e(theta_k),     e(t) = (cos t, sin t, 0),

so its Jacobian has ``l_j e'(theta_j)`` in the column of ``theta_j`` (j < k), ``d e'(theta_k)``
in that of ``theta_k`` and the identity in the base's columns (``e' = (-sin t, cos t, 0)``).
``M = sum_k m_k J_k^T J_k + I_k J_w^T J_w`` (plus the cart's ``m_c J_c^T J_c``), with
``I_k = m_k l_k^2 / 12`` about the centre of mass.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from carnot import FixedBody, Pin, RigidBody
from carnot.model.contacts import PointConstraint, PointContact

Base = Literal["pinned", "cart", "floating"]


def e(t: float) -> np.ndarray:
    return np.array([np.cos(t), np.sin(t), 0.0])


def e_prime(t: float) -> np.ndarray:
    return np.array([-np.sin(t), np.cos(t), 0.0])


@dataclass
class Chain:
    """``masses``, ``lengths``, ``angles`` (absolute, rad) and ``rates`` (rad/s) of the links;
    ``base``: ``pinned`` (at the origin), ``cart`` (a cart of ``cart_mass`` on a rail along x
    at ``base_position``, rate ``base_rate[0]``) or ``floating`` (the base point free in the
    plane: q = (x, y, theta...))."""

    masses: list[float]
    lengths: list[float]
    angles: list[float]
    rates: list[float]
    base: Base = "pinned"
    base_position: list[float] = field(default_factory=lambda: [0.0, 0.0])
    base_rate: list[float] = field(default_factory=lambda: [0.0, 0.0])
    cart_mass: float = 2.0

    @property
    def base_columns(self) -> int:
        return {"pinned": 0, "cart": 1, "floating": 2}[self.base]

    @property
    def size(self) -> int:
        return self.base_columns + len(self.masses)

    @property
    def velocity(self) -> np.ndarray:
        return np.array([*self.base_rate[: self.base_columns], *self.rates])

    @property
    def coordinates(self) -> tuple[str, ...]:
        base = ("x", "y")[: self.base_columns]
        return (*base, *(f"theta_{k + 1}" for k in range(len(self.masses))))

    def base_point(self) -> np.ndarray:
        return np.array([*self.base_position, 0.0]) if self.base != "pinned" else np.zeros(3)

    def point(self, link: int, d: float) -> np.ndarray:
        p = self.base_point()
        for j in range(link):
            p = p + self.lengths[j] * e(self.angles[j])
        return p + d * e(self.angles[link])

    def jacobian(self, link: int, d: float) -> np.ndarray:
        """3 x n: the velocity of the point at ``d`` along ``link``."""
        jac = np.zeros((3, self.size))
        b = self.base_columns
        jac[:2, :b] = np.eye(2)[:, :b]
        for j in range(link):
            jac[:, b + j] = self.lengths[j] * e_prime(self.angles[j])
        jac[:, b + link] = d * e_prime(self.angles[link])
        return jac

    def base_jacobian(self) -> np.ndarray:
        jac = np.zeros((3, self.size))
        b = self.base_columns
        jac[:2, :b] = np.eye(2)[:, :b]
        return jac

    def angular_jacobian(self, link: int) -> np.ndarray:
        jac = np.zeros((3, self.size))
        jac[2, self.base_columns + link] = 1.0
        return jac

    def inertia(self, link: int) -> float:
        return self.masses[link] * self.lengths[link] ** 2 / 12

    def mass_matrix(self) -> np.ndarray:
        m = np.zeros((self.size, self.size))
        for k, mass in enumerate(self.masses):
            jv = self.jacobian(k, self.lengths[k] / 2)
            jw = self.angular_jacobian(k)
            m += mass * jv.T @ jv + self.inertia(k) * jw.T @ jw
        if self.base == "cart":
            jc = self.base_jacobian()
            m += self.cart_mass * jc.T @ jc
        return m

    # ------------------------------------------------------------------ as free bodies

    def body_velocities(self, q_rate: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Each body's (v, omega) for the generalized velocity ``q_rate``."""
        out = {}
        for k in range(len(self.masses)):
            v = self.jacobian(k, self.lengths[k] / 2) @ q_rate
            out[f"link{k + 1}"] = (v, self.angular_jacobian(k) @ q_rate)
        if self.base == "cart":
            out["cart"] = (self.base_jacobian() @ q_rate, np.zeros(3))
        return out

    def bodies(self) -> dict[str, RigidBody | FixedBody]:
        """The links as slender rods (axial moment 1 % of the transverse one; the motion is
        planar, so only the z moment ``m l^2 / 12`` matters), the cart, and the ground."""
        out: dict[str, RigidBody | FixedBody] = {}
        motion = self.body_velocities(self.velocity)
        for k, mass in enumerate(self.masses):
            a = e(self.angles[k])
            i = self.inertia(k)
            inertia = i * (np.eye(3) - np.outer(a, a)) + 0.01 * i * np.outer(a, a)
            name = f"link{k + 1}"
            out[name] = RigidBody(
                name=name,
                mass=mass,
                inertia_com=inertia,
                position_com=self.point(k, self.lengths[k] / 2),
                velocity_com=motion[name][0],
                angular_velocity=motion[name][1],
            )
        if self.base == "cart":
            out["cart"] = RigidBody(
                name="cart",
                mass=self.cart_mass,
                inertia_com=np.eye(3) * 0.05,
                position_com=self.base_point(),
                velocity_com=motion["cart"][0],
            )
        out["ground"] = FixedBody(name="ground")
        return out

    def joint_pins(self, first: int = 0) -> list[PointConstraint]:
        """The pins between consecutive links (and to the cart, or the world), numbered from
        ``constraints[first]``."""
        pins = []
        if self.base == "pinned":
            pins.append(Pin(body="link1", point=self.base_point()))
        elif self.base == "cart":
            pins.append(Pin(body="link1", other="cart", point=self.base_point()))
        for k in range(1, len(self.masses)):
            pins.append(Pin(body=f"link{k + 1}", other=f"link{k}", point=self.point(k, 0.0)))
        return [
            PointConstraint(
                kind="pin",
                body=p.body,
                other=p.other,
                point=p.point,
                where=f"constraints[{first + i}]",
            )
            for i, p in enumerate(pins)
        ]

    def rail(self, where: str) -> PointContact:
        """The cart's frictionless rail as a surface contact (two wheels, e = 0): it holds the
        cart's height and pitch, as the generalized coordinates do."""
        p = self.base_point()
        return PointContact(
            a="cart",
            b="ground",
            point=p,
            normal=[0, 1, 0],
            restitution=0.0,
            patch=[p - [0.2, 0, 0], p + [0.2, 0, 0]],
            where=where,
        )

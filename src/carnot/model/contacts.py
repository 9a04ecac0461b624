"""Contacts and constraints: each contributes rows of the contact Jacobian.

A row is a linear functional of the relative motion at the item's point ``p``:

    row(w, Omega) = c_lin . w + c_ang . Omega          (w, Omega: see conventions.py)

and an impulse ``lambda`` on that row gives body ``a`` the force impulse ``P = c_lin lambda``
at ``p`` and the moment impulse ``M_P = c_ang lambda`` (``b`` gets the opposite). A point
contact has the normal row ``(n, 0)`` and, when it sticks or has Coulomb friction, the tangent
rows ``(t1, 0)`` and ``(t2, 0)``. A contact over a surface (``patch``) has the normal
velocities of its patch points ``n . (w + Omega x r_k) = n . w + (r_k x n) . Omega`` as rows,
reduced to a basis: one row for a single point, two for points on a line, three for a patch
with area. A ``fasten`` or ``pin``
has the three rows ``(e_x, 0), (e_y, 0), (e_z, 0)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal

import numpy as np

from carnot import validate
from carnot.conventions import Vector, contact_frame
from carnot.errors import InputError
from carnot.laws import LAW_NAMES
from carnot.space import Role, RowBlock, patch_length, row_basis


@dataclass(frozen=True, kw_only=True, eq=False)
class PointContact:
    """A contact at ``point`` between body ``a`` and body ``b`` (which may be fixed).

    ``normal`` is normalised and points from ``b`` into ``a``. ``restitution`` is e in [0, 1]
    (its meaning fixed by ``law``), ``friction`` the Coulomb coefficient mu >= 0, and
    ``tangential="stick"`` asks for no slip. ``patch`` (an (K, 3) array of points in the
    contact plane) makes it a contact over a surface: impulse ``P`` and moment ``M_P`` reduced
    to ``point``. ``impulse`` (and ``moment``) make it a contact with a given impulse instead of
    a law.

    >>> c = PointContact(a="ball", b="ground", point=[0, 0, 0], normal=[0, 0, 2], restitution=1)
    >>> c.normal.tolist()
    [0.0, 0.0, 1.0]
    """

    a: str
    b: str
    point: Vector
    normal: Vector
    restitution: float = 0.0
    law: str = "newton"
    friction: float = 0.0
    tangential: Literal["slip", "stick"] = "slip"
    patch: np.ndarray | None = None
    impulse: Vector | None = None
    moment: Vector | None = None
    where: str = field(default="contacts[0]")
    name: str = ""
    stiffness: float = 1.0
    exponent: float = 1.5

    def __post_init__(self) -> None:
        f = self.where + "."
        set_ = object.__setattr__
        if self.a == self.b:
            raise InputError(f + "b", "must name a different body than a", self.b)
        set_(self, "point", validate.vector3(self.point, f + "point"))
        set_(self, "normal", validate.unit_vector(self.normal, f + "normal"))
        set_(self, "restitution", validate.number_in(self.restitution, f + "restitution", 0, 1))
        set_(self, "friction", validate.non_negative_number(self.friction, f + "friction"))
        set_(self, "stiffness", validate.positive_number(self.stiffness, f + "stiffness"))
        set_(self, "exponent", validate.positive_number(self.exponent, f + "exponent"))
        if not isinstance(self.name, str):
            raise InputError(f + "name", "must be a string", self.name)
        if self.tangential not in ("slip", "stick"):
            raise InputError(f + "tangential", "must be 'slip' or 'stick'", self.tangential)
        if self.law not in LAW_NAMES:
            raise InputError(f + "law", f"must be one of {', '.join(LAW_NAMES)}", self.law)
        if self.impulse is not None:
            set_(self, "impulse", validate.vector3(self.impulse, f + "impulse"))
        if self.moment is not None:
            if self.impulse is None:
                raise InputError(f + "moment", "needs an impulse beside it", self.moment)
            set_(self, "moment", validate.vector3(self.moment, f + "moment"))
        if self.patch is not None:
            set_(self, "patch", self._checked_patch(self.patch, f + "patch"))

    def _checked_patch(self, patch: Any, field_: str) -> np.ndarray:
        try:
            pts = np.array(patch, dtype=float)
        except (TypeError, ValueError):
            raise InputError(field_, "must be a list of [x, y, z] points", patch) from None
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 1:
            raise InputError(field_, "must be a list of [x, y, z] points", patch)
        if not np.all(np.isfinite(pts)):
            raise InputError(field_, "must be finite", patch)
        offsets = pts - self.point
        size = max(float(np.max(np.linalg.norm(offsets, axis=1))), 1e-300)
        heights = offsets @ self.normal
        worst = int(np.argmax(np.abs(heights)))
        if abs(heights[worst]) > 1e-9 * size:
            raise InputError(
                f"{field_}[{worst}]",
                "must lie in the contact plane through point, normal to normal "
                f"(distance {heights[worst]:.3g} m)",
                pts[worst].tolist(),
            )
        pts.setflags(write=False)
        return pts

    def at(self, point: Sequence[float]) -> PointContact:
        """The same contact (bodies, normal, law) at another ``point`` (m, three floats,
        world): a computed point, finite (an :class:`~carnot.errors.InputError` naming the
        field otherwise) but not held to the bound on inputs. Not for a contact over a patch
        (its points must lie in the plane through ``point``: build a new contact). Its rows
        are this contact's (made once, here), at the new point: a point contact's rows do
        not depend on its point.

        >>> c = PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1])
        >>> c.at([1.0, 2.0, 0.0]).point.tolist()
        [1.0, 2.0, 0.0]
        """
        if self.patch is not None:
            raise InputError(self.where + ".patch", "a contact over a patch cannot be moved "
                             "to another point (build a new one)", "a patch")  # fmt: skip
        values = tuple(point)
        if len(values) != 3 or not all(map(math.isfinite, values)):
            raise InputError(self.where + ".point", "must be 3 finite numbers", list(values))
        at = np.array(values, dtype=float)
        at.setflags(write=False)
        out = object.__new__(type(self))  # (a copy of this contact, made here)
        out.__dict__.update(self.__dict__)
        out.__dict__["point"] = at
        rows = self.rows()
        out.__dict__["_rows"] = RowBlock(where=rows.where, point=at, linear=rows.linear,
                                         angular=rows.angular, roles=rows.roles)  # fmt: skip
        return out

    @property
    def is_given(self) -> bool:
        return self.impulse is not None

    @property
    def sticks(self) -> bool:
        return self.tangential == "stick"

    @property
    def slips_with_friction(self) -> bool:
        """Coulomb friction that may slip: solved by the impulse-space integration
        (laws/friction.py), not by an equality law."""
        return self.friction > 0 and not self.sticks and not self.is_given

    def rows(self) -> RowBlock:
        """The Jacobian rows of this contact (see the module docstring)."""
        return self._rows

    @cached_property
    def _rows(self) -> RowBlock:  # once per contact: a contact is immutable
        n, t1, t2 = contact_frame(self.normal)
        if self.is_given:
            linear = np.vstack([np.eye(3), np.zeros((3, 3))])
            angular = np.vstack([np.zeros((3, 3)), np.eye(3)])
            return RowBlock(
                where=self.where,
                point=self.point,
                linear=linear,
                angular=angular,
                roles=("given",) * 6,
            )
        tangential = self.sticks or self.slips_with_friction
        if self.patch is None:  # [n; t1; t2] on w, nothing on Omega: the rows at once
            linear = np.array([n, t1, t2]) if tangential else n[None, :].copy()
            return RowBlock(
                where=self.where,
                point=self.point,
                linear=linear,
                angular=np.zeros(linear.shape),
                roles=("normal", "tangent", "tangent") if tangential else ("normal",),
            )
        offsets = self.patch - self.point
        length = patch_length(offsets)
        normal_rows = row_basis(
            np.array([np.concatenate([n, np.cross(r, n)]) for r in offsets]), length
        )
        tangent_rows = row_basis(
            np.array([np.concatenate([t, np.cross(r, t)]) for r in offsets for t in (t1, t2)]),
            length,
        )
        rows = np.vstack([normal_rows, tangent_rows]) if tangential else normal_rows
        normal_role: list[Role] = ["normal"]
        tangent_role: list[Role] = ["tangent"] if tangential else []
        roles = tuple(normal_role * len(normal_rows) + tangent_role * len(tangent_rows))
        return RowBlock(
            where=self.where,
            point=self.point,
            linear=rows[:, :3],
            angular=rows[:, 3:],
            roles=roles,
        )

    def given_row_impulses(self) -> np.ndarray:
        """The fixed row impulses of a given-impulse contact: ``[P, M_P]`` (N s, N m s)."""
        assert self.impulse is not None
        moment = np.zeros(3) if self.moment is None else self.moment
        return np.concatenate([self.impulse, moment])


@dataclass(frozen=True, kw_only=True, eq=False)
class PointConstraint:
    """A bilateral point constraint on ``body`` (against ``other``, or the fixed world).

    ``kind="fasten"``: the relative velocity at ``point`` becomes zero (paper section 3.3);
    ``kind="pin"``: it is zero before and stays zero (a pivot or a joint).

    >>> PointConstraint(kind="pin", body="link", point=[0, 0, 1]).rows().size
    3
    """

    kind: Literal["fasten", "pin"]
    body: str
    point: Vector
    other: str | None = None
    where: str = "constraints[0]"

    def __post_init__(self) -> None:
        f = self.where + "."
        if self.kind not in ("fasten", "pin"):
            raise InputError(f + "type", "must be 'fasten' or 'pin'", self.kind)
        if self.other == self.body:
            raise InputError(f + "other", "must name a different body than body", self.other)
        object.__setattr__(self, "point", validate.vector3(self.point, f + "point"))

    def rows(self) -> RowBlock:
        """Three rows: the world components of the relative velocity at ``point``."""
        return self._rows

    @cached_property
    def _rows(self) -> RowBlock:  # once per constraint: a constraint is immutable
        return RowBlock(
            where=self.where,
            point=self.point,
            linear=np.eye(3),
            angular=np.zeros((3, 3)),
            roles=("bilateral",) * 3,
        )


def Fasten(  # noqa: N802 (reads as a type in scenarios built in Python)
    *, body: str, point: Any, other: str | None = None, where: str = "constraints[0]"
) -> PointConstraint:
    """A sudden fastening of ``point`` of ``body`` (paper section 3.3)."""
    return PointConstraint(kind="fasten", body=body, point=point, other=other, where=where)


def Pin(  # noqa: N802
    *, body: str, point: Any, other: str | None = None, where: str = "constraints[0]"
) -> PointConstraint:
    """A persistent joint at ``point``: relative velocity zero before and after."""
    return PointConstraint(kind="pin", body=body, point=point, other=other, where=where)


Item = PointContact | PointConstraint

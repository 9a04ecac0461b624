"""Symbolic models: the same bodies, contacts and constraints as the numeric core, with SymPy
symbols or expressions for masses, inertia tensors, geometry, velocities and coefficients.

Symbols are named after their body by default, as :mod:`sympy.physics.mechanics` does: body
``A`` gets ``m_A``, inertia ``J_A_xx ... J_A_yz`` (general symmetric) or principal moments,
position ``x_A_x ...``, velocity ``v_A_x ...`` and angular velocity ``omega_A_x ...``.
Vectors are 3x1 :class:`sympy.Matrix` in world components; the conventions are those of
:mod:`carnot.conventions`.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import sympy as sp

from carnot.errors import InputError

Vec = sp.Matrix


def vector(value: Any) -> sp.Matrix:
    """A 3x1 column of SymPy expressions (floats become exact rationals).

    >>> vector([1, 0.5, "a"]).T
    Matrix([[1, 1/2, a]])
    """
    if isinstance(value, sp.MatrixBase):
        out = sp.Matrix(value).reshape(3, 1)
    else:
        out = sp.Matrix(
            [
                sp.nsimplify(x, rational=True) if isinstance(x, float) else sp.sympify(x)
                for x in value
            ]
        )
    if out.shape != (3, 1):
        raise ValueError(f"a vector needs 3 components, got {value!r}")
    return out


def vector_symbols(name: str, *, planar: bool = False, angular: bool = False) -> sp.Matrix:
    """``[name_x, name_y, name_z]`` as real symbols; in the plane (xy) the out-of-plane
    component of a translation, or the in-plane components of a rotation, are 0.

    >>> vector_symbols("v_A", planar=True).T
    Matrix([[v_A_x, v_A_y, 0]])
    """
    comps = sp.symbols(f"{name}_x {name}_y {name}_z", real=True)
    if not planar:
        return sp.Matrix(comps)
    return sp.Matrix([0, 0, comps[2]]) if angular else sp.Matrix([comps[0], comps[1], 0])


def inertia_symbols(name: str, *, principal: bool = False) -> sp.Matrix:
    """A general symmetric inertia tensor ``J_<name>`` (six symbols), or diagonal with
    ``principal=True``.

    >>> inertia_symbols("A", principal=True)
    Matrix([
    [J_A_xx,      0,      0],
    [     0, J_A_yy,      0],
    [     0,      0, J_A_zz]])
    """
    xx, yy, zz = sp.symbols(f"J_{name}_xx J_{name}_yy J_{name}_zz", positive=True)
    if principal:
        return sp.diag(xx, yy, zz)
    xy, xz, yz = sp.symbols(f"J_{name}_xy J_{name}_xz J_{name}_yz", real=True)
    return sp.Matrix([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _identically_zero(expr: Any) -> bool:
    """Whether ``expr`` is 0 for every value of its symbols: cancelled to one fraction, then,
    unless that is 0, evaluated at a random rational point (a value clearly not 0 there
    proves it is not identically 0) and, only where that is not clear, simplified.

    >>> x = sp.Symbol("x", positive=True)
    >>> _identically_zero((x**2 - 1) / (x + 1) - x + 1), _identically_zero(x - 1)
    (True, False)
    >>> _identically_zero(sp.sin(x)**2 + sp.cos(x)**2 - 1)
    True
    """
    expr = sp.cancel(sp.together(sp.sympify(expr)))
    if expr == 0:
        return True
    rng = random.Random(20261122)
    point = {s: sp.Rational(rng.randint(1, 10**4), rng.randint(1, 10**4))
             for s in sorted(expr.free_symbols, key=str)}  # fmt: skip
    value = sp.N(expr.xreplace(point), 30)
    if value.is_number and value.is_finite and abs(value) > 1e-20:
        return False
    return bool(sp.simplify(expr) == 0)


def _checked_inertia(inertia: sp.Matrix, field: str) -> sp.Matrix:
    """``inertia`` if it is a 3x3 symmetric matrix whose determinant is not identically 0 (the
    impulse laws need its inverse); else :class:`~carnot.errors.InputError` naming ``field``.

    >>> _checked_inertia(sp.diag(1, 2, 0), "bodies.A.inertia_com")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: bodies.A.inertia_com: must be invertible ..., got [[1, 0, 0], ...]
    """
    if inertia.shape != (3, 3):
        raise InputError(field, "must be a 3x3 matrix", inertia.tolist())
    if not all(_identically_zero(inertia[i, j] - inertia[j, i])
               for i in range(3) for j in range(i + 1, 3)):  # fmt: skip
        raise InputError(field, "must be symmetric", inertia.tolist())
    if _identically_zero(inertia.det(method="berkowitz")):
        raise InputError(
            field, "must be invertible (its determinant is identically 0)", inertia.tolist()
        )
    return inertia


@dataclass(frozen=True, kw_only=True, eq=False)
class SymRigidBody:
    """A rigid body with symbolic (or exact) data. Omitted data become symbols named after the
    body; ``planar=True`` restricts the motion to the xy plane (one angular velocity about z).

    >>> b = SymRigidBody(name="A", planar=True)
    >>> b.mass, b.velocity_com.T, b.angular_velocity.T
    (m_A, Matrix([[v_A_x, v_A_y, 0]]), Matrix([[0, 0, omega_A_z]]))
    """

    name: str
    mass: Any = None
    inertia_com: Any = None
    position_com: Any = None
    velocity_com: Any = None
    angular_velocity: Any = None
    planar: bool = False
    principal: bool = False

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        n = self.name
        set_(
            self,
            "mass",
            sp.Symbol(f"m_{n}", positive=True)
            if self.mass is None
            else sp.nsimplify(self.mass, rational=True),
        )
        if _identically_zero(self.mass):
            raise InputError(f"bodies.{n}.mass", "must not be 0", self.mass)
        if self.inertia_com is None:
            inertia = inertia_symbols(n, principal=self.principal or self.planar)
        else:
            inertia = sp.Matrix(self.inertia_com).applyfunc(
                lambda x: sp.nsimplify(x, rational=True)
            )
        set_(self, "inertia_com", _checked_inertia(inertia, f"bodies.{n}.inertia_com"))
        set_(
            self,
            "position_com",
            vector_symbols(f"x_{n}", planar=self.planar)
            if self.position_com is None
            else vector(self.position_com),
        )
        set_(
            self,
            "velocity_com",
            vector_symbols(f"v_{n}", planar=self.planar)
            if self.velocity_com is None
            else vector(self.velocity_com),
        )
        set_(
            self,
            "angular_velocity",
            vector_symbols(f"omega_{n}", planar=self.planar, angular=True)
            if self.angular_velocity is None
            else vector(self.angular_velocity),
        )

    fixed = False

    def velocity_of_point(self, point: sp.Matrix) -> sp.Matrix:
        """``v + omega x (p - x)``."""
        return self.velocity_com + self.angular_velocity.cross(point - self.position_com)

    def kinetic_energy(self) -> sp.Expr:
        """Koenig's formula (paper eq. 5)."""
        v, w = self.velocity_com, self.angular_velocity
        return (self.mass * v.dot(v) + (w.T * self.inertia_com * w)[0, 0]) / 2


@dataclass(frozen=True, kw_only=True, eq=False)
class SymFixedBody:
    """An immovable obstacle."""

    name: str
    fixed = True


@dataclass(frozen=True, kw_only=True, eq=False)
class SymContact:
    """A point contact, or one over a surface (``patch``), or a given impulse: the symbolic
    twin of :class:`carnot.model.contacts.PointContact`. ``normal`` must be a unit vector (an exact
    one, or one you normalise); ``tangents`` (for ``stick``) default to the numeric rule of
    :func:`carnot.conventions.contact_frame` when the normal is numeric.

    ``slip``, a unit tangent ``d``, puts the contact in one slip regime of Coulomb's law at
    impact (the simultaneous law, DESIGN.md section 6): its impulse is ``P_n (n - mu d)``
    with ``mu = friction``, and Newton's law ``w_n'' = -e w_n'`` sets ``P_n``. The regime is
    Coulomb's only where the post-impact slip runs along ``d`` (``d . w'' >= 0``) and
    ``P_n >= 0``; :mod:`carnot.symbolic.active_sets` states those conditions."""

    a: str
    b: str
    point: Any
    normal: Any
    restitution: Any = 0
    tangential: Literal["slip", "stick"] = "slip"
    patch: Sequence[Any] | None = None
    impulse: Any = None
    moment: Any = None
    tangents: tuple[Any, Any] | None = None
    where: str = "contacts[0]"
    friction: Any = 0
    slip: Any = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "point", vector(self.point))
        set_(self, "normal", vector(self.normal))
        set_(self, "restitution", sp.nsimplify(self.restitution, rational=True))
        set_(self, "friction", sp.nsimplify(self.friction, rational=True))
        if self.slip is not None:
            if self.tangential == "stick" or self.patch is not None or self.impulse is not None:
                raise InputError(f"{self.where}.slip", "is for a point contact under Coulomb "
                                 "friction (not told to stick, no patch, no given impulse)",
                                 self.slip)  # fmt: skip
            set_(self, "slip", vector(self.slip))
        if self.impulse is not None:
            set_(self, "impulse", vector(self.impulse))
            set_(self, "moment", vector([0, 0, 0]) if self.moment is None else vector(self.moment))
        if self.patch is not None:
            set_(self, "patch", tuple(vector(p) for p in self.patch))

    @property
    def is_given(self) -> bool:
        return self.impulse is not None


@dataclass(frozen=True, kw_only=True, eq=False)
class SymConstraint:
    """``fasten`` or ``pin`` at ``point`` of ``body`` (against ``other`` or the world)."""

    kind: Literal["fasten", "pin"]
    body: str
    point: Any
    other: str | None = None
    where: str = "constraints[0]"

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", vector(self.point))


@dataclass(frozen=True, kw_only=True, eq=False)
class SymProblem:
    """Bodies by name, contacts and constraints."""

    bodies: Mapping[str, SymRigidBody | SymFixedBody]
    contacts: Sequence[SymContact] = ()
    constraints: Sequence[SymConstraint] = ()
    title: str = ""
    movable: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "bodies", dict(self.bodies))
        object.__setattr__(self, "contacts", tuple(self.contacts))
        object.__setattr__(self, "constraints", tuple(self.constraints))
        object.__setattr__(self, "movable", tuple(n for n, b in self.bodies.items() if not b.fixed))

"""A system in generalized coordinates as a producer of contact space (DESIGN.md section 7).

The user gives the generalized velocity ``q'`` (n entries, each in its coordinate's unit per
second), the mass matrix ``M`` (n x n, symmetric positive definite, so that the kinetic energy
is ``E = 1/2 q'^T M q'`` in J) and, for each contact and constraint, the Jacobian ``J`` (3 x n)
that maps ``q'`` to the world relative velocity ``w = J q'`` (m/s) of its point (of side ``a``
relative to side ``b``), with ``angular_jacobian`` (3 x n, ``Omega = J_ang q'`` in rad/s) for a
contact over a surface. The item's motion rows are ``J_i = [J; J_ang]`` (6 x n; ``J_ang = 0``
when not given), its rows ``C_i`` are those a free-body contact builds
(:meth:`carnot.model.PointContact.rows`), and ``W_i = C_i J_i``: the laws and the outcome do
not change (u = q', free bodies: :mod:`carnot.model.free_bodies`).

**Rows that carry nothing.** A planar system's out-of-plane row (a pin's ``e_z`` row, a
sticking contact's out-of-plane tangent) is identically zero in ``W``: no impulse on it moves
the system, so it carries none. Within each group of an item's rows of one role (normal,
tangent, bilateral), carnot keeps an orthonormal basis of the rows that act (singular value
above ``DEAD_ROW`` of the item's largest) and drops the rest: a rotation within the group
keeps the rows orthonormal in the metric of :func:`carnot.space.row_basis`, so the
minimum-norm split of redundant impulses is unchanged, and a dropped row is never mistaken for
a redundant constraint (no ``statically_indeterminate`` warning). The three rows of a contact
with Coulomb friction are kept in its contact frame (the law integrates in ``(n, t1, t2)``);
a tangent direction that no motion reaches takes no impulse there (``carnot.solve``).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from carnot.errors import InputError
from carnot.laws.registry import MULTIPLE_IMPACT_NAMES
from carnot.model.contacts import Item, PointConstraint, PointContact
from carnot.solvers.options import SolverOptions
from carnot.space import ContactSpace, RowBlock

#: Relative size (of the item's largest singular value) under which a row acts on nothing.
DEAD_ROW = 1e-10
#: A pin's relative velocity before the impact, relative to the system's velocity scale there.
PIN_REST = 1e-9
#: Relative tolerances of the mass matrix's symmetry and of its smallest eigenvalue.
SYMMETRY = 1e-9
DEFINITE = 1e-12

#: The label of the system's side in results (a generalized contact has no body names).
SYSTEM = "system"


def _finite_matrix(value: Any, field_: str, rows: int | None, cols: int | None) -> np.ndarray:
    """A read-only float matrix of finite numbers with the given shape (``None``: any)."""
    shape = f"{rows if rows is not None else 'k'} x {cols if cols is not None else 'n'}"
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field_, f"must be a {shape} matrix of numbers", value) from None
    if isinstance(value, (str, bytes)) or arr.ndim != 2 or arr.size == 0:
        raise InputError(field_, f"must be a {shape} matrix of numbers (a list of rows)", value)
    if (rows is not None and arr.shape[0] != rows) or (cols is not None and arr.shape[1] != cols):
        raise InputError(
            field_, f"must be {shape} (rows x columns)", f"{arr.shape[0]} x {arr.shape[1]}"
        )
    if arr.dtype.kind not in "fiu" or not np.all(np.isfinite(arr)):
        raise InputError(field_, "must have finite entries", value)
    arr.setflags(write=False)
    return arr


def mass_matrix(value: Any, field_: str = "system.mass_matrix") -> np.ndarray:
    """A symmetric positive definite matrix (kg, kg m, kg m^2 by its coordinates' units).

    >>> mass_matrix([[1.0, 2.0], [2.0, 1.0]])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: system.mass_matrix: must be positive definite (smallest eigenvalue > 1e-12 of the largest); eigenvalues, got [-1.0, 3.0]
    """  # noqa: E501
    return _mass_and_blocks(value, field_)[0]


def _mass_and_blocks(value: Any, field_: str) -> tuple[np.ndarray, list[np.ndarray]]:
    """:func:`mass_matrix` and its :func:`diagonal_blocks` (found once: the inverse reuses
    them)."""
    arr = _finite_matrix(value, field_, None, None)
    n = arr.shape[0]
    if arr.shape != (n, n):
        raise InputError(field_, "must be square (n x n)", f"{arr.shape[0]} x {arr.shape[1]}")
    scale = float(np.max(np.abs(arr)))
    asym = float(np.max(np.abs(arr - arr.T)))
    if asym > SYMMETRY * scale:
        raise InputError(
            field_,
            f"must be symmetric (to {SYMMETRY:g} of its largest entry); largest |M - M^T|",
            asym,
        )
    sym = 0.5 * (arr + arr.T)
    # the blocks' eigenvalues are M's (diagonal_blocks: cheaper than M's own eigvalsh)
    blocks = diagonal_blocks(sym)
    if len(blocks) == 1 and blocks[0].shape[0] == 1:  # one block: M's own (sorted) eigenvalues
        eig = np.linalg.eigvalsh(sym)
    else:
        eig = np.sort(np.concatenate([np.ravel(np.linalg.eigvalsh(sym[_index(b)]))
                                      for b in blocks]))  # fmt: skip
    if not eig[0] > DEFINITE * max(float(eig[-1]), 0.0) or eig[-1] <= 0:
        raise InputError(
            field_,
            f"must be positive definite (smallest eigenvalue > {DEFINITE:g} of the largest); "
            "eigenvalues",
            [float(x) for x in np.round(eig, 12)],
        )
    sym.setflags(write=False)
    return sym, blocks


#: The mass matrices last checked and inverted, by their bytes (:func:`_checked_and_inverted`).
_CHECKED: dict[tuple[tuple[int, ...], bytes], tuple[np.ndarray, np.ndarray]] = {}
_CHECKED_LOCK = threading.Lock()
#: How many it keeps, each of at most ``CHECKED_SIZE`` entries (200 x 200: under 1 MB).
CHECKED_KEPT, CHECKED_SIZE = 8, 40_000


def _checked_and_inverted(
    value: Any, field_: str = "system.mass_matrix"
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`mass_matrix` and its inverse (made of its diagonal blocks' inverses; both
    read-only), kept for the last :data:`CHECKED_KEPT` matrices by their exact bytes: many
    impacts share one ``M`` with other velocities (a sweep; an audit's references of free
    bodies, whose ``M`` in MuJoCo's coordinates does not change as they move), and the checks
    and the inverse are the same function of the same numbers (a fifth of the time, a 60 x 60
    ``M``). The oldest is dropped when more are made; a matrix of more than
    :data:`CHECKED_SIZE` entries is not kept.

    >>> m, inv = _checked_and_inverted([[2.0, 0.0], [0.0, 4.0]])
    >>> inv.tolist(), _checked_and_inverted(m)[1] is inv
    ([[0.5, 0.0], [0.0, 0.25]], True)
    """
    arr = _finite_matrix(value, field_, None, None)
    # (a float64 array's shape and bytes: its values bit for bit, the signs of zeros too;
    # a key of the matrix's floats, not of raw bytes another array could share)
    key = (arr.shape, arr.tobytes()) if arr.size <= CHECKED_SIZE else None
    known = None if key is None else _CHECKED.get(key)
    if known is not None:
        return known
    m, blocks = _mass_and_blocks(arr, field_)
    if len(blocks) == 1 and blocks[0].shape[0] == 1:  # one block: M's own inverse
        inverse = np.linalg.inv(m)
    else:
        inverse = np.zeros_like(m)
        for size in blocks:  # M^-1 is made of the blocks' inverses
            inverse[_index(size)] = np.linalg.inv(m[_index(size)])
    inverse = 0.5 * (inverse + inverse.T)
    inverse.setflags(write=False)
    if key is not None:
        with _CHECKED_LOCK:
            while len(_CHECKED) >= CHECKED_KEPT:
                del _CHECKED[next(iter(_CHECKED))]
            _CHECKED[key] = (m, inverse)
    return m, inverse


def diagonal_blocks(m: np.ndarray) -> list[np.ndarray]:
    """The diagonal blocks of ``M`` (n x n) in contiguous runs of coordinates, grouped by
    size: for each size ``s``, the ``k`` blocks' coordinates stacked (k x s). ``M`` is zero
    outside them, so its eigenvalues are the blocks' and its inverse is made of the blocks'
    inverses, a batched LAPACK call per size (several free bodies, several kinematic trees:
    MuJoCo orders each tree's coordinates together; ten free bodies: a 60 x 60 eigvalsh and
    inverse cost several times their 6 x 6 blocks'). A run ends where no entry links a
    coordinate up to it to one after it; one block where nothing splits.

    >>> [b.tolist() for b in diagonal_blocks(np.array([[2.0, 1, 0], [1, 2, 0], [0, 0, 3]]))]
    [[[2]], [[0, 1]]]
    >>> [b.tolist() for b in diagonal_blocks(np.array([[2.0, 0, 1], [0, 2, 0], [1, 0, 3]]))]
    [[[0, 1, 2]]]
    """
    n = m.shape[0]
    if n and m[0, n - 1] != 0.0:  # the first run reaches the last coordinate: one block
        return [np.arange(n)[None, :]]  # (what the search below finds; a walker's M_f)
    columns = np.arange(n)
    nonzero = m != 0.0
    nonzero[columns, columns] = True  # a run reaches at least its own coordinate
    last = (n - 1) - np.argmax(nonzero[:, ::-1], axis=1)  # each row's last nonzero column
    ends = np.flatnonzero(np.maximum.accumulate(last) == columns) + 1
    starts = np.concatenate([[0], ends[:-1]])
    sizes = ends - starts
    return [starts[sizes == size][:, None] + np.arange(size) for size in np.unique(sizes)]


def _index(blocks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fancy index of ``k`` stacked blocks of ``s`` coordinates (k x s): ``m[index]``
    is k x s x s."""
    return blocks[:, :, None], blocks[:, None, :]


@dataclass(frozen=True, kw_only=True, eq=False)
class System:
    """The system at the impact instant: ``mass_matrix`` M (n x n, SPD), ``velocity`` q' (n)
    and optional ``coordinates`` names (``q0, q1, ...`` otherwise).

    >>> s = System(mass_matrix=[[2.0, 0], [0, 1.0]], velocity=[1.0, 2.0])
    >>> s.coordinates, s.kinetic_energy(s.velocity)
    (('q0', 'q1'), 3.0)
    """

    mass_matrix: np.ndarray
    velocity: np.ndarray
    coordinates: tuple[str, ...] = ()
    mass_matrix_inv: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        m, inverse = _checked_and_inverted(self.mass_matrix)
        n = m.shape[0]
        set_(self, "mass_matrix", m)
        try:
            q = np.array(self.velocity, dtype=float)
        except (TypeError, ValueError):
            raise InputError(
                "system.velocity", f"must be a list of {n} numbers", self.velocity
            ) from None
        if q.shape != (n,) or isinstance(self.velocity, (str, bytes)):
            raise InputError(
                "system.velocity",
                f"must be a list of {n} numbers (one per column of mass_matrix)",
                self.velocity,
            )
        if not np.all(np.isfinite(q)):
            raise InputError("system.velocity", "must be finite", self.velocity)
        q.setflags(write=False)
        set_(self, "velocity", q)
        names = tuple(self.coordinates) or tuple(f"q{k}" for k in range(n))
        if len(names) != n:
            raise InputError(
                "system.coordinates",
                f"must name {n} coordinates (one per column of mass_matrix)",
                list(names),
            )
        if not all(isinstance(name, str) and name for name in names):
            for k, name in enumerate(names):
                if not isinstance(name, str) or not name:
                    raise InputError(f"system.coordinates[{k}]", "must be a non-empty string",
                                     name)  # fmt: skip
        if len(set(names)) != n:
            raise InputError("system.coordinates", "must be distinct names", list(names))
        set_(self, "coordinates", names)
        set_(self, "mass_matrix_inv", inverse)

    @property
    def size(self) -> int:
        """The number of coordinates ``n``."""
        return int(self.velocity.shape[0])

    def kinetic_energy(self, velocity: np.ndarray) -> float:
        """``E = 1/2 q'^T M q'`` (J)."""
        return float(0.5 * velocity @ self.mass_matrix @ velocity)


@dataclass(frozen=True, kw_only=True, eq=False)
class SystemContact:
    """A contact of a system: its ``jacobian`` (3 x n, ``w = J q'``), optional
    ``angular_jacobian`` (3 x n, ``Omega = J_ang q'``: needed by a ``patch`` or a given
    ``moment``) and the law data of a free-body contact (``normal`` from ``b`` into ``a``,
    ``restitution``, ``law``, ``friction``, ``tangential``, ``patch``, ``impulse``, ``moment``).
    ``point`` is optional (reports; required with a ``patch``, whose offsets it anchors);
    ``name`` labels it in reports. ``contact`` is the equivalent
    :class:`~carnot.model.PointContact`, whose rows and law data the pipeline reads.

    >>> c = SystemContact(jacobian=[[1.0, 0], [0, 1.0], [0, 0]], normal=[0, 1, 0])
    >>> c.contact.rows().roles, c.contact.a
    (('normal',), 'system')
    """

    jacobian: np.ndarray
    normal: Any
    point: Any = None
    restitution: float = 0.0
    law: str = "newton"
    friction: float = 0.0
    tangential: Literal["slip", "stick"] = "slip"
    patch: Any = None
    impulse: Any = None
    moment: Any = None
    angular_jacobian: np.ndarray | None = None
    name: str | None = None
    where: str = "contacts[0]"
    contact: PointContact = field(init=False, repr=False)

    def __post_init__(self) -> None:
        f = self.where + "."
        set_ = object.__setattr__
        set_(self, "jacobian", _finite_matrix(self.jacobian, f + "jacobian", 3, None))
        n = self.jacobian.shape[1]
        if self.angular_jacobian is not None:
            set_(
                self,
                "angular_jacobian",
                _finite_matrix(self.angular_jacobian, f + "angular_jacobian", 3, n),
            )
        if self.patch is not None and self.point is None:
            raise InputError(
                f + "point",
                "is required with a patch (the patch's reference point)",
                show_value=False,
            )
        if self.angular_jacobian is None:
            for key in ("patch", "moment"):
                if getattr(self, key) is not None:
                    raise InputError(
                        f + "angular_jacobian",
                        f"is required with {key} (the relative angular velocity it acts on)",
                        show_value=False,
                    )
        if self.name is not None and (not isinstance(self.name, str) or not self.name):
            raise InputError(f + "name", "must be a non-empty string", self.name)
        contact = PointContact(
            a=SYSTEM,
            b="world",
            point=np.zeros(3) if self.point is None else self.point,
            normal=self.normal,
            restitution=self.restitution,
            law=self.law,
            friction=self.friction,
            tangential=self.tangential,
            patch=self.patch,
            impulse=self.impulse,
            moment=self.moment,
            where=self.where,
        )
        set_(self, "contact", contact)
        for key in ("normal", "restitution", "friction", "patch", "impulse", "moment"):
            set_(self, key, getattr(contact, key))  # validated: unit normal, floats, arrays
        if self.point is not None:
            set_(self, "point", contact.point)

    def at(self, jacobian: Any, point: Sequence[float] | None = None) -> SystemContact:
        """The same contact (its law data as its constructor checked them) with another
        ``jacobian`` (3 x n, ``w = J q'``; finite, checked) at another ``point`` (m, three
        finite floats; ``None``: where it was): a strike's contact from one made once per
        law, its normal's frame and its rows kept (:meth:`carnot.model.PointContact.at`).
        Not for a contact with an ``angular_jacobian`` (its columns are the old Jacobian's)
        or a ``patch``.

        >>> c = SystemContact(jacobian=np.zeros((3, 2)), normal=[0, 1, 0], tangential="stick")
        >>> d = c.at([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]], [2.0, 0.0, 0.0])
        >>> d.jacobian[1].tolist(), d.point.tolist(), d.contact.rows().roles, c.point
        ([0.0, 1.0], [2.0, 0.0, 0.0], ('normal', 'tangent', 'tangent'), None)
        """
        if self.angular_jacobian is not None:
            raise InputError(self.where + ".angular_jacobian", "a contact with an angular "
                             "Jacobian cannot be given another Jacobian (build a new one)",
                             show_value=False)  # fmt: skip
        if self.patch is not None:
            raise InputError(self.where + ".patch", "a contact over a patch cannot be given "
                             "another Jacobian (build a new one)", show_value=False)  # fmt: skip
        jac = _finite_matrix(jacobian, self.where + ".jacobian", 3, None)
        out = object.__new__(type(self))  # (a copy of this contact, made here)
        out.__dict__.update(self.__dict__)
        out.__dict__["jacobian"] = jac
        if point is not None:
            contact = self.contact.at(point)
            out.__dict__.update(contact=contact, point=contact.point)
        return out


@dataclass(frozen=True, kw_only=True, eq=False)
class SystemConstraint:
    """A ``fasten`` (the relative velocity ``J q'`` becomes zero, paper section 3.3) or a
    ``pin`` (it is zero before, to ``PIN_REST`` of the point's velocity scale, and stays
    zero) given by its ``jacobian`` (3 x n). With ``angular_jacobian`` (3 x n, ``Omega =
    J_ang q'``) the relative angular velocity is held too (a weld: six rows, the last three
    taking the moment ``M_P``). ``constraint`` is the equivalent
    :class:`~carnot.model.PointConstraint` (its law data; :meth:`rows` are the item's rows).

    >>> SystemConstraint(kind="pin", jacobian=[[1.0], [0], [0]]).rows().size
    3
    >>> SystemConstraint(kind="fasten", jacobian=[[1.0], [0], [0]],
    ...                  angular_jacobian=[[0], [0], [1.0]]).rows().roles
    ('bilateral', 'bilateral', 'bilateral', 'bilateral', 'bilateral', 'bilateral')
    """

    kind: Literal["fasten", "pin"]
    jacobian: np.ndarray
    angular_jacobian: np.ndarray | None = None
    point: Any = None
    name: str | None = None
    where: str = "constraints[0]"
    constraint: PointConstraint = field(init=False, repr=False)

    def __post_init__(self) -> None:
        f = self.where + "."
        set_ = object.__setattr__
        set_(self, "jacobian", _finite_matrix(self.jacobian, f + "jacobian", 3, None))
        if self.angular_jacobian is not None:
            n = self.jacobian.shape[1]
            set_(
                self,
                "angular_jacobian",
                _finite_matrix(self.angular_jacobian, f + "angular_jacobian", 3, n),
            )
        if self.name is not None and (not isinstance(self.name, str) or not self.name):
            raise InputError(f + "name", "must be a non-empty string", self.name)
        set_(
            self,
            "constraint",
            PointConstraint(
                kind=self.kind,
                body=SYSTEM,
                point=np.zeros(3) if self.point is None else self.point,
                where=self.where,
            ),
        )

    def rows(self) -> RowBlock:
        """The point constraint's three rows (the relative velocity's world components) and,
        with an ``angular_jacobian``, three more on the relative angular velocity."""
        rows = self.constraint.rows()
        if self.angular_jacobian is None:
            return rows
        zeros = np.zeros((3, 3))
        return RowBlock(
            where=rows.where,
            point=rows.point,
            linear=np.vstack([np.eye(3), zeros]),
            angular=np.vstack([zeros, np.eye(3)]),
            roles=("bilateral",) * 6,
        )


SystemItem = SystemContact | SystemConstraint


@dataclass(frozen=True, kw_only=True, eq=False)
class SystemProblem:
    """A system, its contacts and constraints (solved simultaneously), and a title; every
    Jacobian has one column per coordinate.

    >>> SystemProblem(system=System(mass_matrix=[[1.0]], velocity=[-1.0]),
    ...               contacts=[SystemContact(jacobian=[[0, 0], [1, 0], [0, 0]], normal=[0, 1, 0])])
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: contacts[0].jacobian: must have 1 columns (one per coordinate), got 2
    """

    system: System
    contacts: Sequence[SystemContact] = ()
    constraints: Sequence[SystemConstraint] = ()
    title: str = ""
    multiple_impact: str = "simultaneous"
    solver: SolverOptions | None = None

    def __post_init__(self) -> None:
        if self.multiple_impact not in MULTIPLE_IMPACT_NAMES:
            raise InputError(
                "multiple_impact", f"must be one of {', '.join(MULTIPLE_IMPACT_NAMES)}",
                self.multiple_impact,
            )  # fmt: skip
        object.__setattr__(self, "contacts", tuple(self.contacts))
        object.__setattr__(self, "constraints", tuple(self.constraints))
        if not isinstance(self.system, System):
            raise InputError("system", "must be a System", self.system)
        n = self.system.size
        for item in (*self.contacts, *self.constraints):
            if not isinstance(item, (SystemContact, SystemConstraint)):
                raise InputError("contacts", "must be SystemContact or SystemConstraint", item)
            cols = item.jacobian.shape[1]
            if cols != n:
                raise InputError(
                    f"{item.where}.jacobian", f"must have {n} columns (one per coordinate)", cols
                )
        if not self.contacts and not self.constraints:
            raise InputError("contacts", "at least one contact or constraint is needed", [])

    @property
    def items(self) -> tuple[SystemItem, ...]:
        """Contacts, then constraints: the order of the rows and of the results."""
        return (*self.contacts, *self.constraints)

    @property
    def law_items(self) -> list[Item]:
        """The equivalent free-body items, whose law data the pipeline reads."""
        return [i.contact if isinstance(i, SystemContact) else i.constraint for i in self.items]


def motion_rows(item: SystemItem) -> np.ndarray:
    """``J_i = [J; J_ang]`` (6 x n): ``q' -> (w, Omega)`` at the item's point."""
    out = np.zeros((6, item.jacobian.shape[1]))
    out[:3] = item.jacobian
    angular = getattr(item, "angular_jacobian", None)
    if angular is not None:
        out[3:] = angular
    return out


def acting_rows(block: RowBlock, motion: np.ndarray, coulomb: bool) -> RowBlock:
    """``block`` with the rows that move nothing dropped (module docstring): within each role
    group, an orthonormal basis of the rows whose ``W = C J`` is not zero; the group is kept
    as it is when all its rows act, and a Coulomb contact's rows are kept whole.

    A planar pin (the system moves in the x-y plane): its z row goes.

    >>> pin = RowBlock(where="constraints[0]", point=np.zeros(3), linear=np.eye(3),
    ...                angular=np.zeros((3, 3)), roles=("bilateral",) * 3)
    >>> j = np.vstack([[[1.0, 0.5], [0, 1.0], [0, 0]], np.zeros((3, 2))])
    >>> acting_rows(pin, j, False).linear.tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    return _acting(block, motion, coulomb)[0]


def _acting(block: RowBlock, motion: np.ndarray, coulomb: bool) -> tuple[RowBlock, np.ndarray]:
    """:func:`acting_rows` and the rows' ``W = C J`` (the contact space's, bit for bit)."""
    coefficients = block.coefficients
    w = coefficients @ motion
    whole = "given" in block.roles or coulomb  # kept whole: only "moves nothing" to check
    # (the largest singular value, an SVD, only where it scales the rows that are dropped)
    # (norm(w, 2) and each row's norm by their own formulas: the largest singular value, and
    # sqrt(w_k . w_k), without np.linalg.norm's dispatch, 5 us a call; the same numbers)
    top = (1.0 if np.any(w) else 0.0) if whole else (
        float(np.linalg.svd(w, compute_uv=False)[0]) if w.size else 0.0)  # fmt: skip
    if top == 0.0:
        raise InputError(
            block.where + ".jacobian",
            "moves nothing along the item's rows (J "
            "q' is zero along every constrained direction): the item can take no "
            "impulse",
            show_value=False,
        )
    if whole:
        return block, w
    kept: list[np.ndarray] = []
    roles: list[Any] = []
    for role in dict.fromkeys(block.roles):
        # rows dead on their own go first (the planar case: the rows stay as they were)
        group = [
            k
            for k, r in enumerate(block.roles)
            if r == role and math.sqrt(float(w[k].dot(w[k]))) > DEAD_ROW * top
        ]
        if not group and role == "normal":
            raise InputError(
                block.where + ".normal",
                "no motion of the system reaches the "
                "normal direction (n . J is zero): the contact can take no impulse",
                show_value=False,
            )
        if not group:
            continue
        if len(group) == 1:  # one live row: its singular value is its norm, kept above
            kept.append(coefficients[group])
            roles.append(role)
            continue
        u, sing, _ = np.linalg.svd(w[group], full_matrices=False)
        rank = int(np.sum(sing > DEAD_ROW * top))
        rows = coefficients[group] if rank == len(group) else u[:, :rank].T @ coefficients[group]
        kept.append(rows)
        roles += [role] * rank
    c = np.vstack(kept)
    acting = RowBlock(
        where=block.where, point=block.point, linear=c[:, :3], angular=c[:, 3:], roles=tuple(roles)
    )
    return acting, acting.coefficients @ motion


def assemble_system(problem: SystemProblem) -> ContactSpace:
    """The contact space of ``problem``: ``u' = q'``, ``M``, the motion rows ``J_i`` and the
    acting rows of each item (:func:`acting_rows`).

    A point mass of 2 kg moving in the plane, dropping onto the floor:

    >>> p = SystemProblem(system=System(mass_matrix=np.eye(2) * 2, velocity=[1.0, -1.0]),
    ...     contacts=[SystemContact(jacobian=[[1, 0], [0, 1], [0, 0]], normal=[0, 1, 0],
    ...                             tangential="stick")])
    >>> space = assemble_system(p)
    >>> space.blocks[0].roles, space.delassus().round(12).tolist()
    (('normal', 'tangent'), [[0.5, 0.0], [0.0, 0.5]])
    """
    system = problem.system
    blocks: list[RowBlock] = []
    motions = []
    jacobian = []
    for item, law_item in zip(problem.items, problem.law_items, strict=True):
        motion = motion_rows(item)
        coulomb = isinstance(law_item, PointContact) and law_item.slips_with_friction
        rows = item.rows() if isinstance(item, SystemConstraint) else law_item.rows()
        block, w = _acting(rows, motion, coulomb)
        blocks.append(block)
        motions.append(motion)
        jacobian.append(w)  # C_i J_i as ContactSpace would make it: made here once
    return ContactSpace(
        u_before=system.velocity,
        mass_matrix=system.mass_matrix,
        mass_matrix_inv=system.mass_matrix_inv,
        motion=np.vstack(motions),
        blocks=tuple(blocks),
        jacobian=np.vstack(jacobian),
    )


def check_system_pins(problem: SystemProblem, space: ContactSpace) -> None:
    """A pin holds before the impact: ``|J q'| <= PIN_REST`` times the system's velocity scale
    at the point, ``sqrt(2 E' g)`` with ``g`` the largest eigenvalue of ``J M^-1 J^T``
    (m/s): the largest speed the system's kinetic energy ``E'`` could give the point. (At a
    pin the point's own speed is zero and cannot set the scale; a state computed in floating
    point leaves round-off of that size. The scale does not depend on the coordinates
    chosen.) A pin with an ``angular_jacobian`` holds ``|J_ang q'|`` the same way (rad/s, its
    own scale from ``J_ang M^-1 J_ang^T``)."""
    system = problem.system
    energy = system.kinetic_energy(system.velocity)
    for index, item in enumerate(problem.items):
        if not isinstance(item, SystemConstraint) or item.kind != "pin":
            continue
        w, omega = space.motion_at(index, system.velocity)
        parts = [("jacobian", item.jacobian, w, "velocity", "J q' (m/s)")]
        if item.angular_jacobian is not None:
            parts.append(
                ("angular_jacobian", item.angular_jacobian, omega, "angular velocity",
                 "J_ang q' (rad/s)")
            )  # fmt: skip
        for key, jac, motion, kind, what in parts:
            g = float(np.linalg.eigvalsh(jac @ system.mass_matrix_inv @ jac.T)[-1])
            scale = math.sqrt(2.0 * energy * max(g, 0.0))
            if float(np.linalg.norm(motion)) > PIN_REST * scale:
                raise InputError(
                    item.where if key == "jacobian" else f"{item.where}.{key}",
                    f"a pin needs zero relative {kind} at its point before the impact "
                    f"(|J q'| <= {PIN_REST:g} of the system's velocity scale sqrt(2 E' g), g "
                    'the largest eigenvalue of J M^-1 J^T; type = "fasten" is the sudden '
                    f"constraint); relative {kind} {what}",
                    [float(x) for x in motion],
                )


def generalized_impulses(
    problem: SystemProblem, impulses: Sequence[np.ndarray], moments: Sequence[np.ndarray]
) -> list[np.ndarray]:
    """Each item's generalized impulse ``J^T P + J_ang^T M_P`` (N s times the coordinate's
    unit), from the user's Jacobians and the item's world impulses: the route of the
    generalized momentum check ``M (q'' - q') = sum J^T P``, independent of the rows."""
    out = []
    for item, p, m_p in zip(problem.items, impulses, moments, strict=True):
        q_imp = item.jacobian.T @ p
        angular = getattr(item, "angular_jacobian", None)
        if angular is not None:
            q_imp = q_imp + angular.T @ m_p
        q_imp.setflags(write=False)
        out.append(q_imp)
    return out


__all__ = [
    "System",
    "SystemConstraint",
    "SystemContact",
    "SystemItem",
    "SystemProblem",
    "acting_rows",
    "assemble_system",
    "check_system_pins",
    "generalized_impulses",
    "mass_matrix",
    "motion_rows",
]

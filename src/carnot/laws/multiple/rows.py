"""The contact-space data every multiple-impact law reads and writes (DESIGN.md sections 1, 6).

A law sees only contact space: the Delassus operator ``G = W M^-1 W^T`` (m x m, symmetric
positive semi-definite, 1/kg), the pre-impact row velocities ``w' = W u'`` (m/s), and, per
contact, which row is its normal and which rows (0, 1 or 2) are its tangents, in the frame
``(n, t1, t2)`` of :func:`carnot.conventions.contact_frame`. *Held* rows are bilateral
(``pin``, ``fasten``, or a given target) and end at a prescribed velocity. The laws return row
impulses ``Lambda`` (N s) with ``w'' = w' + G Lambda``; the caller maps them back,
``u'' = u' + M^-1 W^T Lambda``.

The energy theorem holds for *any* impulse in contact space (paper eq. 16 summed over rows):
``E' - E'' = -1/2 Lambda . (w' + w'')``, because ``E'' - E' = Lambda . w' + 1/2 Lambda^T G
Lambda``. So every stage of a sequential or dispersion outcome carries its own ledger:
:func:`dissipated_by_row`.

The complementarity residual (:func:`contact_residual`) is the natural map of Coulomb's cone
with De Saxce's modified velocity, the measure Siconos reports for its ``fc3d`` solvers:
``r = |P - proj_K(P - rho v)| / rho`` with ``K = {|P_t| <= mu P_n}``,
``v = (w_n'' + e w_n' + mu |w_t''|, w_t'')`` and ``rho = 1 / G_nn``; it is in m/s and is zero
exactly when Signorini's condition and Coulomb's law hold.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Literal

import numpy as np

from carnot.conventions import RELATIVE_TOLERANCE
from carnot.errors import InputError
from carnot.laws.cone import contact_law_residual, project_onto_cone
from carnot.solvers.options import Certificate
from carnot.validate import finite_number, non_negative_number, number_in, positive_number

if TYPE_CHECKING:
    from carnot.model.contacts import PointContact

Regime = Literal["separate", "stick", "slip", "frictionless"]

#: Flags an outcome may carry (DESIGN.md section 6 and issue 14).
FLAGS = (
    "statically_indeterminate",  # impulses not unique, velocities unique
    "multiple_solutions",  # several different outcomes: see ``alternatives``
    "no_solution",  # no impulse meets the law; the impulses returned are zero
    "sequential_tie",  # two contacts approach equally fast: each order in ``alternatives``
    "tie_orders_truncated",  # more tied orders than MAX_ORDERS: later ties lowest index first
    "stage_limit",  # the sequence of sub-impacts did not end within the stage limit
    "friction_too_small_to_stick",  # a contact told to stick needs |P_t| > mu P_n
    "separating_contact_approaches",  # a contact separating before (so not taking part,
    # DESIGN.md section 6) is made to approach by the others' impulses: it would interpenetrate
    "not_converged",  # an iterative solver stopped short of its tolerance: see the residual
)


@dataclass(frozen=True, kw_only=True)
class ContactRows:
    """One unilateral contact as seen in contact space.

    ``normal`` is its normal row, ``tangents`` its 0, 1 (planar) or 2 (3D) tangent rows.
    ``restitution`` is ``e`` in [0, 1], ``friction`` the Coulomb ``mu >= 0``; ``stick`` says
    the contact is told to stick (no slip whatever the impulse, DESIGN.md section 3).
    ``stiffness`` (> 0, relative) and ``exponent`` (> 0; 1 linear, 1.5 Hertz) are read by the
    dispersion law only. ``name`` is used in error messages.

    >>> ContactRows(normal=0, tangents=(1,), friction=0.5).kind
    'planar'
    >>> ContactRows(normal=0, restitution=1.5)
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: contacts.0.restitution: must be in [0, 1], got 1.5
    """

    normal: int
    tangents: tuple[int, ...] = ()
    restitution: float = 0.0
    friction: float = 0.0
    stick: bool = False
    stiffness: float = 1.0
    exponent: float = 1.5
    name: str = ""

    def __post_init__(self) -> None:
        where = f"contacts.{self.name or self.normal}"
        if isinstance(self.normal, bool) or not isinstance(self.normal, (int, np.integer)):
            raise InputError(f"{where}.normal", "must be a row index (an integer)", self.normal)
        if len(self.tangents) > 2:
            raise InputError(f"{where}.tangents", "must hold 0, 1 or 2 rows", self.tangents)
        object.__setattr__(self, "tangents", tuple(int(t) for t in self.tangents))
        object.__setattr__(
            self, "restitution", number_in(self.restitution, f"{where}.restitution", 0.0, 1.0)
        )
        object.__setattr__(
            self, "friction", non_negative_number(self.friction, f"{where}.friction")
        )
        object.__setattr__(
            self, "stiffness", positive_number(self.stiffness, f"{where}.stiffness")
        )
        object.__setattr__(self, "exponent", positive_number(self.exponent, f"{where}.exponent"))
        if self.stick and not self.tangents:
            raise InputError(f"{where}.stick", "needs tangent rows to stick", self.tangents)

    @classmethod
    def of_contact(cls, contact: PointContact, *, normal: int,
                   tangents: tuple[int, ...] = ()) -> ContactRows:  # fmt: skip
        """The law's view of the validated point ``contact`` on rows ``normal`` and
        ``tangents`` (its normal and tangent rows in the law's ``G``): its restitution,
        friction, stick, stiffness and exponent as its constructor checked them (the same
        bounds as this class's), its ``name`` or else its ``where`` as the name. Only the row
        indices are checked here (a twentieth of a 4-corner landing's solve was these checks
        made again).

        >>> from carnot import PointContact
        >>> c = PointContact(a="box", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
        ...                  restitution=0.5, friction=0.3)
        >>> ContactRows.of_contact(c, normal=0, tangents=(1, 2)) == ContactRows(
        ...     normal=0, tangents=(1, 2), restitution=0.5, friction=0.3, name="contacts[0]")
        True
        """
        if not isinstance(contact, _point_contact()):
            raise InputError("contacts", "must be a PointContact", contact)
        for row in (normal, *tangents):
            if type(row) is not int or len(tangents) > 2:  # (a bool is not an int here)
                raise InputError(f"contacts.{contact.name or contact.where}.rows",
                                 "must be a row index and at most 2 more (Python ints)",
                                 (normal, tangents))  # fmt: skip
        if contact.sticks and not tangents:
            raise InputError(f"contacts.{contact.name or contact.where}.stick",
                             "needs tangent rows to stick", tangents)  # fmt: skip
        out = object.__new__(cls)
        # (the fields as __post_init__ leaves them, in their order)
        out.__dict__.update(normal=normal, tangents=tuple(tangents),
                            restitution=contact.restitution, friction=contact.friction,
                            stick=contact.sticks, stiffness=contact.stiffness,
                            exponent=contact.exponent, name=contact.name or contact.where)
        return out

    @property
    def label(self) -> str:
        """The name used in messages: ``name`` or the normal row."""
        return self.name or str(self.normal)

    @cached_property  # (a frozen dataclass: its fields never change; the laws ask often)
    def kind(self) -> Literal["frictionless", "told_to_stick", "planar", "spatial"]:
        """How the tangent rows behave: none, told to stick, Coulomb planar, Coulomb 3D."""
        if self.stick:
            return "told_to_stick"
        if self.friction == 0.0 or not self.tangents:
            return "frictionless"
        return "planar" if len(self.tangents) == 1 else "spatial"

    @property
    def rows(self) -> tuple[int, ...]:
        """Normal row first, then the tangent rows."""
        return (self.normal, *self.tangents)


@functools.cache
def _point_contact() -> type[PointContact]:
    """:class:`carnot.PointContact` (imported when first asked for: the model imports the
    laws)."""
    from carnot.model.contacts import PointContact

    return PointContact


@dataclass(frozen=True, kw_only=True)
class HeldRows:
    """Bilateral rows (pins, fasten, given targets) that end at ``target`` (m/s or rad/s).

    >>> HeldRows(rows=(0, 1)).target
    (0.0, 0.0)
    """

    rows: tuple[int, ...]
    target: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        rows = tuple(int(r) for r in self.rows)
        target = tuple(self.target) or (0.0,) * len(rows)
        if len(target) != len(rows):
            raise InputError("held.target", f"must hold {len(rows)} velocities", self.target)
        target = tuple(finite_number(t, f"held.target[{k}]") for k, t in enumerate(target))
        object.__setattr__(self, "rows", rows)
        object.__setattr__(self, "target", target)


@dataclass(frozen=True, kw_only=True)
class ContactOutcome:
    """What one contact did: ``active`` (it received an impulse or stayed closed under load),
    its ``regime``, its normal and tangent impulses (N s) and its complementarity residual
    (m/s, see :func:`contact_residual`)."""

    active: bool
    regime: Regime
    impulse_normal: float
    impulse_tangent: tuple[float, ...]
    residual: float


@dataclass(frozen=True, kw_only=True, eq=False)
class Stage:
    """One sub-impact (sequential law) or phase (dispersion law).

    ``contacts`` are the indices (into the law's ``contacts``) that act in it; ``impulses``
    the row impulses of this stage alone (N s), ``w_before``/``w_after`` the row velocities
    (m/s) at its start and end, so ``w_after = w_before + G impulses`` and its ledger is
    ``-1/2 impulses . (w_before + w_after)`` (:func:`dissipated_by_row`).
    """

    index: int
    contacts: tuple[int, ...]
    impulses: np.ndarray
    w_before: np.ndarray
    w_after: np.ndarray
    description: str = ""


@dataclass(frozen=True, kw_only=True, eq=False)
class MultipleImpactOutcome:
    """The answer of a multiple-impact law in contact space.

    ``impulses`` (m rows, N s) and ``w_after = w' + G impulses`` (m/s); ``contacts`` in the
    order they were given; ``residual`` the largest complementarity residual (m/s) over
    contacts and held rows; ``flags`` from :data:`FLAGS`; ``stages`` for the sequential and
    dispersion laws; ``alternatives`` the other outcomes when ``multiple_solutions`` or
    ``sequential_tie`` is flagged (each complete, with its own stages); ``order`` the contacts
    in the order of their sub-impacts (sequential); ``certificate`` what is known of a
    simultaneous answer (:class:`Certificate`, given by :func:`carnot.solvers.resolve`).
    """

    law: str
    impulses: np.ndarray
    w_before: np.ndarray
    w_after: np.ndarray
    contacts: tuple[ContactOutcome, ...]
    residual: float
    flags: tuple[str, ...] = ()
    stages: tuple[Stage, ...] = ()
    alternatives: tuple[MultipleImpactOutcome, ...] = ()
    order: tuple[int, ...] = ()
    extra: dict[str, float] = field(default_factory=dict)
    certificate: Certificate | None = None

    @property
    def dissipated(self) -> float:
        """``E_d = -1/2 Lambda . (w' + w'')`` (J), the theorem summed over every row."""
        return float(np.sum(dissipated_by_row(self.impulses, self.w_before, self.w_after)))


def dissipated_by_row(
    impulses: np.ndarray, w_before: np.ndarray, w_after: np.ndarray
) -> np.ndarray:
    """Each row's share of the energy dissipated, ``-1/2 Lambda_r (w'_r + w''_r)`` (J).

    >>> dissipated_by_row(np.array([2.0]), np.array([-1.0]), np.array([0.0])).tolist()
    [1.0]
    """
    return -0.5 * np.asarray(impulses) * (np.asarray(w_before) + np.asarray(w_after))


def check_problem(
    delassus: object,
    w_before: object,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Validate the contact-space problem; return ``(G, w')`` as float arrays.

    ``G`` must be square, finite and symmetric to 1e-9 relative; ``w'`` finite with one entry
    per row; every row index in range and used by at most one contact or held row.

    >>> check_problem([[1.0, 0.0]], [0.0], (), None)
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: delassus: must be a square matrix, got shape (1, 2)
    """
    g = np.array(delassus, dtype=float)
    if g.ndim != 2 or g.shape[0] != g.shape[1]:
        raise InputError(
            "delassus", f"must be a square matrix, got shape {g.shape}", show_value=False
        )
    # (array methods, not NumPy's functions: their dispatch was most of this check's cost)
    if not np.isfinite(g).all():
        raise InputError("delassus", "must be finite", g)
    scale = float(np.abs(g).max()) if g.size else 0.0
    if g.size and float(np.abs(g - g.T).max()) > RELATIVE_TOLERANCE * scale:
        raise InputError("delassus", "must be symmetric (1e-9 relative)", g)
    w = np.array(w_before, dtype=float).reshape(-1)
    if w.shape != (g.shape[0],):
        raise InputError("w_before", f"must hold {g.shape[0]} row velocities", w)
    if not np.isfinite(w).all():
        raise InputError("w_before", "must be finite", w)
    m = g.shape[0]
    seen: dict[int, str] = {}
    owners = [(f"contacts.{c.label}", c.rows) for c in contacts]
    if held is not None:
        owners.append(("held.rows", held.rows))
    for owner, rows in owners:
        for r in rows:
            if not 0 <= r < m:
                raise InputError(owner, f"rows must be in [0, {m - 1}]", r)
            if r in seen:
                raise InputError(owner, f"row {r} is already used by {seen[r]}", r)
            seen[r] = owner
    return 0.5 * (g + g.T), w


def project_cone(p: np.ndarray, mu: float) -> np.ndarray:
    """Euclidean projection onto Coulomb's cone ``K = {|p_t| <= mu p_n}`` (exact, circular):
    :func:`carnot.laws.cone.project_onto_cone` on an array.

    ``p`` = (p_n, p_t...) with 0, 1 or 2 tangent entries; ``mu = 0`` is the ray ``p_n >= 0``.

    >>> project_cone(np.array([0.0, 2.0]), 1.0).tolist()
    [1.0, 1.0]
    """
    p = np.asarray(p, dtype=float)
    x = [float(v) for v in p] + [0.0] * (3 - p.shape[0])
    return np.array(project_onto_cone(x[0], x[1], x[2], mu)[: p.shape[0]])


def contact_residual(
    contact: ContactRows,
    delassus: np.ndarray,
    impulses: np.ndarray,
    w_before: np.ndarray,
    w_after: np.ndarray,
    *,
    takes_part: bool = True,
) -> float:
    """Complementarity residual of one contact (m/s): zero exactly when its law holds
    (:func:`carnot.laws.cone.contact_law_residual`, the rule the batch kernel compiles).

    A contact that does not take part (it was separating before) must receive nothing:
    the residual is ``|P| / rho``. A contact told to stick: Signorini on the normal and, when
    loaded, ``|w_t''|``. Otherwise the natural map of the module docstring.

    >>> c = ContactRows(normal=0)
    >>> contact_residual(c, np.eye(1), np.array([1.0]), np.array([-1.0]), np.array([0.0]))
    0.0
    """
    # scalar arithmetic (at most 3 rows): this runs for every contact of every regime tried
    n = contact.normal
    rho = 1.0 / max(float(delassus[n, n]), np.finfo(float).tiny)
    tangents = contact.tangents
    p_1 = float(impulses[tangents[0]]) if tangents else 0.0
    p_2 = float(impulses[tangents[1]]) if len(tangents) > 1 else 0.0
    w_1 = float(w_after[tangents[0]]) if tangents else 0.0
    w_2 = float(w_after[tangents[1]]) if len(tangents) > 1 else 0.0
    v_n = float(w_after[n]) + contact.restitution * float(w_before[n])
    kind = contact.kind
    mu = math.inf if kind == "told_to_stick" else contact.friction
    return contact_law_residual(takes_part, kind == "frictionless", mu, rho,
                                float(impulses[n]), p_1, p_2, v_n, w_1, w_2)  # fmt: skip


def held_residual(held: HeldRows | None, w_after: np.ndarray) -> float:
    """Largest ``|w''_r - target_r|`` over the held rows (m/s)."""
    if held is None or not held.rows:
        return 0.0
    return float(np.max(np.abs(np.asarray(w_after)[list(held.rows)] - np.array(held.target))))


def velocity_scale(w_before: np.ndarray, held: HeldRows | None) -> float:
    """The velocity scale that relative tolerances multiply (m/s); 1 when all is at rest."""
    scale = float(np.abs(w_before).max()) if np.size(w_before) else 0.0
    if held is not None and held.target:
        scale = max(scale, max(abs(t) for t in held.target))
    return scale if scale > 0.0 and math.isfinite(scale) else 1.0


def frictionless_only(contacts: tuple[ContactRows, ...], law: str) -> None:
    """Sequential and dispersion laws are frictionless (DESIGN.md section 6): friction or a
    contact told to stick is an error naming the field, never an answer from another law."""
    for c in contacts:
        if c.friction > 0.0:
            raise InputError(
                f"contacts.{c.label}.friction",
                f"must be 0 with multiple_impact = {law!r} (a frictionless law)",
                c.friction,
            )
        if c.stick:
            raise InputError(
                f"contacts.{c.label}.stick",
                f"is not allowed with multiple_impact = {law!r} (a frictionless law)",
                c.stick,
            )

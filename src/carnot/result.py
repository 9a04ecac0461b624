"""What an impact produced: post-impact motion, impulses, the energy ledger, checks and flags.

All vectors are world components in SI units; impulses are what body ``a`` (or the constrained
body) receives.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from carnot.conventions import Vector
from carnot.records import Record
from carnot.solvers.options import Certificate


@dataclass(frozen=True, kw_only=True, eq=False)
class Flag(Record):
    """A physically doubtful or noteworthy result: ``code`` (stable, for programs),
    ``where`` (``contacts[0]``, ``energy``, ...) and a sentence for people."""

    code: str
    where: str
    message: str


@dataclass(frozen=True, kw_only=True, eq=False)
class BodyMotion(Record):
    """A body's velocity (m/s) and angular velocity (rad/s) before and after."""

    name: str
    fixed: bool
    velocity_before: Vector
    angular_velocity_before: Vector
    velocity_after: Vector
    angular_velocity_after: Vector


@dataclass(frozen=True, kw_only=True, eq=False)
class ItemOutcome(Record):
    """One contact or constraint: its impulse and its share of the theorem.

    ``dissipated = -1/2 [P . (w' + w'') + M_P . (Omega' + Omega'')]`` (J), split into the part
    of the normal impulse, of the tangential impulse and of the moment impulse. ``law`` is the
    contact's restitution hypothesis; ``process`` the impulse-space history of a contact with
    Coulomb friction (phases, works, samples: laws/friction.py), ``None`` otherwise.
    ``active`` (several contacts at once only): whether the contact took part and received an
    impulse or stayed closed; ``None`` when a single contact's law applied.
    """

    where: str
    kind: str  # "contact", "fasten" or "pin"
    a: str
    b: str | None
    point: Vector
    normal: Vector | None
    impulse: Vector
    moment: Vector
    normal_impulse: float | None
    tangential_impulse: Vector | None
    regime: str
    relative_velocity_before: Vector
    relative_velocity_after: Vector
    relative_angular_velocity_before: Vector
    relative_angular_velocity_after: Vector
    dissipated: float
    dissipated_normal: float
    dissipated_tangential: float
    dissipated_moment: float
    friction_required: float | None = None
    centre_of_pressure: Vector | None = None
    law: str | None = None
    process: Any = None
    active: bool | None = None
    name: str = ""
    generalized_impulse: Vector | None = None


    def in_system(self, generalized_impulse: Vector, name: str) -> ItemOutcome:
        """The outcome as a system in generalized coordinates reports it: no ``b`` (the
        system is one body of coordinates), its ``generalized_impulse`` ``J^T P`` (in each
        coordinate's unit of impulse) and the item's ``name``; a new outcome, the other
        fields this one's (a ``dataclasses.replace`` per item was a tenth of a one-contact
        system's solve)."""
        values = dict(self.__dict__)
        values.update(b=None, generalized_impulse=generalized_impulse, name=name)
        return ItemOutcome.from_fields(values)


@dataclass(frozen=True, kw_only=True, eq=False)
class EnergyLedger(Record):
    """Energies in J. ``dissipated = before - after`` (direct), ``dissipated_theorem`` the
    theorem's sum over every contact and constraint, ``lost_velocities`` Carnot's
    ``E_p = 1/2 du^T M du``; ``carnot_defect = E_d - E_p`` computed directly and
    ``carnot_condition = -sum(P . w'' + M_P . Omega'')``, which the theorem says are equal
    (paper eqs. 12-13)."""

    before: float
    after: float
    dissipated: float
    dissipated_theorem: float
    lost_velocities: float
    carnot_defect: float
    carnot_condition: float
    dissipated_normal: float
    dissipated_tangential: float
    dissipated_moment: float


@dataclass(frozen=True, kw_only=True, eq=False)
class MomentumCheck:
    """Change of total linear momentum (kg m/s) and of angular momentum about the world origin
    (kg m^2/s) of the movable bodies against the impulses the fixed world gave them; the
    residuals are relative to the momentum scale of the problem."""

    linear_change: Vector
    linear_external: Vector
    angular_change: Vector
    angular_external: Vector
    linear_residual: float
    angular_residual: float


@dataclass(frozen=True, kw_only=True, eq=False)
class StageOutcome:
    """One sub-impact (sequential law) or phase (dispersion law) of several contacts: the
    contacts acting in it (``where``), each contact's impulse in it (N s, world, what ``a``
    receives) and share of the theorem (J), and the stage's ``dissipated`` (J,
    ``-1/2 Lambda . (w' + w'')`` over the stage's rows)."""

    index: int
    description: str
    contacts: tuple[str, ...]
    impulses: dict[str, Vector]
    dissipated_by_contact: dict[str, float]
    dissipated: float


@dataclass(frozen=True, kw_only=True, eq=False)
class SystemMotion:
    """A system in generalized coordinates: its ``coordinates``' names, ``q'`` and ``q''``
    (each in its coordinate's unit per second), and the relative residual of the generalized
    momentum balance ``M (q'' - q') = sum J^T P + J_ang^T M_P`` over every item."""

    coordinates: tuple[str, ...]
    velocity_before: np.ndarray
    velocity_after: np.ndarray
    momentum_residual: float


@dataclass(frozen=True, kw_only=True, eq=False)
class ImpactResult(Record):
    """Everything :func:`carnot.solve_impact` found: free bodies have ``bodies`` and the
    ``momentum`` check; a system in generalized coordinates has ``system`` instead (its
    ``bodies`` is empty and ``momentum`` is ``None``). With several unilateral contacts:
    ``multiple_impact`` names the law, ``complementarity_residual`` the largest residual of its
    conditions (m/s), ``stages`` its sub-impacts or phases, ``alternatives`` the other outcomes
    when the law has several (``multiple_solutions``, ``sequential_tie``), each a complete
    result; ``solver`` the simultaneous law's certificate (DESIGN.md section 9: the solver
    that answered, the residual evaluated apart from it, uniqueness), ``solver_groups`` each
    independent group's, by its contacts, where there are several.

    ``momentum_later`` (for producers): a function that makes ``momentum`` when it is first
    read, for results often used without it (both routes of :func:`carnot.solve_impact`: the
    check by Newton-Euler is a fifth of a single impact's cost, and a simulation reads it for
    none of its thousands of impacts). Read, it is the same check, computed once. (Given, the
    ``momentum`` passed is ``None``.)

    Producers that make thousands of results from numbers already checked (the short path,
    :func:`carnot.single.single_result`, which ``carnot simulate`` calls at every impact)
    make them and their parts by :meth:`carnot.records.Record.from_fields` (every field, in
    order; ``__post_init__`` run): the generated ``__init__`` of a frozen dataclass sets each
    field by ``object.__setattr__``, a quarter of the cost of such a result.
    ``tests/test_single.py`` holds these results to the general route's, field by field and
    in order."""

    title: str
    bodies: dict[str, BodyMotion]
    contacts: tuple[ItemOutcome, ...]
    constraints: tuple[ItemOutcome, ...]
    energy: EnergyLedger
    momentum: MomentumCheck | None
    warnings: tuple[Flag, ...]
    row_impulses: np.ndarray
    multiple_impact: str | None = None
    complementarity_residual: float | None = None
    stages: tuple[StageOutcome, ...] = ()
    alternatives: tuple[ImpactResult, ...] = ()
    system: SystemMotion | None = None
    solver: Certificate | None = None
    solver_groups: tuple[tuple[tuple[str, ...], Certificate], ...] = ()
    momentum_later: Callable[[], MomentumCheck] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.momentum_later is not None:
            del self.__dict__["momentum"]  # made on first read, by __getattr__

    def __getattr__(self, name: str) -> Any:
        # called only when "momentum" was left to be made (or for a missing attribute)
        later = self.__dict__.get("momentum_later")
        if name != "momentum" or later is None:
            raise AttributeError(f"'ImpactResult' object has no attribute {name!r}")
        momentum = later()
        object.__setattr__(self, "momentum", momentum)
        return momentum

    def flag_codes(self) -> list[str]:
        """The warning codes, in order."""
        return [w.code for w in self.warnings]

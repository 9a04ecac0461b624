"""The contract every impact law meets: it sees only contact space (DESIGN.md section 1).

    law.resolve(G, w', params) -> LawAnswer(impulses, redundant, process)

``G`` is the Delassus operator of the law's rows (1/kg; for a contact with held constraints
the Schur complement that folds them in), ``w'`` the rows' velocities before the impact
(m/s), ``params`` what the law needs per row (roles, restitution) and per contact (friction).
The answer is the row impulses (N s), which rows were redundant (their split of the impulse
is not unique, the motion is) and, for laws integrated in impulse space, a record of the
process (phases, works, samples) for reports and plots.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from carnot.errors import CarnotError
from carnot.space import Role


@dataclass(frozen=True, kw_only=True)
class Support:
    """What a restitution hypothesis can be asked for: ``stick`` (no slip after),
    ``patch`` (a contact over a surface), ``simultaneous`` (with other unilateral rows at
    once), ``coulomb_slip`` (Coulomb friction that may slip, integrated in impulse space)."""

    stick: bool
    patch: bool
    simultaneous: bool
    coulomb_slip: bool


@dataclass(frozen=True, kw_only=True, eq=False)
class LawParams:
    """Per row: ``roles`` and ``restitution`` (e in [0, 1], read on normal rows); per contact:
    ``friction`` (Coulomb's mu >= 0) and ``hypothesis`` (``newton``, ``poisson``, ``stronge``).
    ``reference``: the row velocities at the instant of impact that restitution refers to,
    when other impulses (given ones, an integrated frictional contact) have already changed
    the rows' velocities ``w'`` passed to ``resolve``; ``None``: ``w'`` itself.
    """

    roles: tuple[Role, ...]
    restitution: np.ndarray | float = 0.0
    friction: float = 0.0
    hypothesis: str = "newton"
    reference: np.ndarray | None = None


@dataclass(frozen=True, kw_only=True, eq=False)
class LawAnswer:
    """Row impulses ``impulses`` (N s; N m s on moment rows), the boolean mask of rows whose
    impulse split is not unique (``redundant``), and an optional ``process`` record."""

    impulses: np.ndarray
    redundant: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    process: Any = None


class ImpactLaw(Protocol):
    """A law: a name, what it supports, and ``resolve``."""

    name: str

    def resolve(self, delassus: np.ndarray, w_before: np.ndarray, params: LawParams) -> LawAnswer:
        """Row impulses from contact-space data only."""
        ...


class RowConflictError(CarnotError):
    """Rows whose required velocities no impulse can give (``rows``: their indices among the
    law's rows; ``residual``: the relative size of the contradiction). The pipeline names the
    contacts and constraints they belong to."""

    def __init__(self, rows: np.ndarray, residual: float):
        self.rows = rows
        self.residual = residual
        super().__init__(f"rows {rows.tolist()} contradict each other (residual {residual:.3g})")

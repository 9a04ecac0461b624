"""Impact laws, each seeing only contact space (``resolve(G, w', params)``), in one registry."""

from __future__ import annotations

from carnot.laws.base import ImpactLaw, LawAnswer, LawParams, RowConflictError, Support
from carnot.laws.coulomb import COULOMB
from carnot.laws.registry import (
    HYPOTHESES,
    LAW_NAMES,
    check_hypothesis,
    check_supported,
    contact_rule,
)
from carnot.laws.restitution import EQUALITY, min_norm_solve, target_velocity

__all__ = [
    "COULOMB",
    "EQUALITY",
    "HYPOTHESES",
    "LAW_NAMES",
    "ImpactLaw",
    "LawAnswer",
    "LawParams",
    "RowConflictError",
    "Support",
    "check_hypothesis",
    "check_supported",
    "contact_rule",
    "min_norm_solve",
    "target_velocity",
]

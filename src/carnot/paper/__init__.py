"""The paper's section 3: its examples rebuilt from ordinary bodies, contacts and constraints
(:mod:`~carnot.paper.examples`), its printed formulas transcribed as printed
(:mod:`~carnot.paper.formulas`), and the audit of one against the other
(:mod:`~carnot.paper.audit`)."""

from carnot.paper.audit import (
    AGREEMENT_TOLERANCE,
    Verdict,
    check_formula,
    run_audit,
    theorem_checks,
    verdict_to_dict,
)
from carnot.paper.formulas import FORMULAS, PrintedFormula

__all__ = [
    "AGREEMENT_TOLERANCE",
    "FORMULAS",
    "PrintedFormula",
    "Verdict",
    "check_formula",
    "run_audit",
    "theorem_checks",
    "verdict_to_dict",
]

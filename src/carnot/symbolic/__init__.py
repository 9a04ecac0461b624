"""carnot.symbolic: closed-form impact results with SymPy, from the same formulation as the
numeric core (DESIGN.md section 1), and the tools built on them: proofs of the theorem's
identities and the audit of the paper's printed formulas."""

from carnot.symbolic.model import (
    SymConstraint,
    SymContact,
    SymFixedBody,
    SymProblem,
    SymRigidBody,
    inertia_symbols,
    vector,
    vector_symbols,
)
from carnot.symbolic.solve import SymbolicResult, derive_impact, simplify_expr

__all__ = [
    "SymConstraint",
    "SymContact",
    "SymFixedBody",
    "SymProblem",
    "SymRigidBody",
    "SymbolicResult",
    "derive_impact",
    "inertia_symbols",
    "simplify_expr",
    "vector",
    "vector_symbols",
]

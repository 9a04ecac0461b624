"""carnot: rigid-body impact mechanics with exact energy bookkeeping.

The theorem of *An extension of Carnot's theorem for rigid body collisions*: the kinetic
energy dissipated in an impact equals ``-1/2 sum[P . (w' + w'') + M_P . (Omega' + Omega'')]``.
"""

from carnot.errors import CarnotError, ConstraintConflictError, InputError
from carnot.model import (
    Fasten,
    FixedBody,
    ImpactProblem,
    Pin,
    PointConstraint,
    PointContact,
    RigidBody,
)
from carnot.result import ImpactResult
from carnot.solve import solve_impact

__version__ = "0.1.0"

__all__ = [
    "CarnotError",
    "ConstraintConflictError",
    "Fasten",
    "FixedBody",
    "ImpactProblem",
    "ImpactResult",
    "InputError",
    "Pin",
    "PointConstraint",
    "PointContact",
    "RigidBody",
    "__version__",
    "solve_impact",
]

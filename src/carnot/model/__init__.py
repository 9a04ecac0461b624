"""What collides: bodies, their inertia, contacts and constraints, the problem they make, and
the producers of contact space (free bodies today; systems in generalized coordinates next)."""

from carnot.model.bodies import Body, FixedBody, RigidBody
from carnot.model.contacts import Fasten, Item, Pin, PointConstraint, PointContact
from carnot.model.problem import ImpactProblem

__all__ = [
    "Body",
    "Fasten",
    "FixedBody",
    "ImpactProblem",
    "Item",
    "Pin",
    "PointConstraint",
    "PointContact",
    "RigidBody",
]

"""Contact space: rows, their roles, and the operators every law and outcome reads."""

from carnot.space.contact_space import (
    CONFLICT_TOLERANCE,
    RANK_TOLERANCE,
    ContactSpace,
    is_sparse,
)
from carnot.space.rows import Role, RowBlock, patch_length, row_basis

__all__ = [
    "CONFLICT_TOLERANCE",
    "RANK_TOLERANCE",
    "ContactSpace",
    "Role",
    "RowBlock",
    "is_sparse",
    "patch_length",
    "row_basis",
]

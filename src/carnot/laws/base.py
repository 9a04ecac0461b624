"""The contract every impact law meets: it sees only contact space (DESIGN.md section 1).

An *equality law* prescribes the post-impact value of each of its rows as a function of the
pre-impact one: ``w''_row = target(w'_row)``. All equality rows of a scenario are solved at
once, ``G Lambda = target(w') - w'`` with the Delassus operator ``G = W M^-1 W^T``
(:mod:`carnot.system`). :meth:`EqualityLaw.resolve` does the same for one item on its own.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np

from carnot.contacts import Role


class EqualityLaw(ABC):
    """A law that fixes the post-impact velocity of each of its rows."""

    name: str = ""

    @abstractmethod
    def target_velocity(
        self, w_before: np.ndarray, roles: Sequence[Role], *, restitution: float
    ) -> np.ndarray:
        """Post-impact row velocities (m/s or rad/s) from the pre-impact ones."""

    def resolve(
        self,
        delassus: np.ndarray,
        w_before: np.ndarray,
        roles: Sequence[Role],
        *,
        restitution: float = 0.0,
    ) -> np.ndarray:
        """Row impulses ``Lambda = G^-1 (target(w') - w')`` for one item alone (N s).

        >>> from carnot.laws import LAWS
        >>> LAWS["newton"].resolve(np.array([[0.5]]), np.array([-2.0]), ["normal"],
        ...                        restitution=1.0).tolist()
        [8.0]
        """
        target = self.target_velocity(w_before, roles, restitution=restitution)
        return np.linalg.solve(delassus, target - w_before)

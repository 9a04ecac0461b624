"""Restitution laws for frictionless and sticking contacts.

Newton's kinematic law: the normal relative velocity after is ``-e`` times that before,
``n . w'' = -e n . w'``; a sticking contact also ends with zero tangential relative velocity
(paper section 3.1). For a contact over a surface every patch point obeys the same rule.

Poisson's (kinetic) and Stronge's (energetic) hypotheses give the same answer as Newton's for a
single frictionless contact alone with bilateral constraints: the normal velocity is then an
affine function of the normal impulse, so the restitution impulse is ``e`` times the
compression impulse exactly when the final velocity is ``-e`` times the initial one, and the
restitution work is ``-e^2`` times the compression work likewise (Stronge, *Impact Mechanics*,
CUP 2000, section 2.2). Beyond that (friction with slip, several unilateral contacts) they differ
and need the impulse-space integration of issue #4; :func:`carnot.solve.solve_impact` refuses
those cases with a clear error instead of answering with Newton's.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from carnot.contacts import Role
from carnot.laws.base import EqualityLaw


class NewtonRestitution(EqualityLaw):
    """``w''_n = -e w'_n`` on normal rows, ``w''_t = 0`` on tangent (sticking) rows.

    >>> NewtonRestitution().target_velocity(np.array([-2.0, 1.0]), ["normal", "tangent"],
    ...                                     restitution=0.5).tolist()
    [1.0, 0.0]
    """

    name = "newton"

    def target_velocity(
        self, w_before: np.ndarray, roles: Sequence[Role], *, restitution: float
    ) -> np.ndarray:
        is_normal = np.array([r == "normal" for r in roles])
        return np.where(is_normal, -restitution * w_before, 0.0)


class PoissonRestitution(NewtonRestitution):
    """Poisson's hypothesis, in the cases where it equals Newton's (see the module docstring)."""

    name = "poisson"


class StrongeRestitution(NewtonRestitution):
    """Stronge's energetic hypothesis, where it equals Newton's (see the module docstring)."""

    name = "stronge"


class Bilateral(EqualityLaw):
    """Fasten and pin: the relative velocity at the point is zero after the impact."""

    name = "bilateral"

    def target_velocity(
        self, w_before: np.ndarray, roles: Sequence[Role], *, restitution: float
    ) -> np.ndarray:
        return np.zeros_like(w_before)

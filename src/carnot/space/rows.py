"""Rows of contact space: what a contact or constraint constrains, and what a law does with it.

A row is a linear functional of the relative motion at an item's point ``p``:

    row(w, Omega) = c_lin . w + c_ang . Omega          (w, Omega: see conventions.py)

and an impulse ``lambda`` on that row gives the item's first side the force impulse
``P = c_lin lambda`` at ``p`` and the moment impulse ``M_P = c_ang lambda`` (the other side gets
the opposite). Models (free bodies, systems in generalized coordinates) map their velocity
``u`` to ``(w, Omega)`` at the point; the rows turn that into contact space.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from carnot.conventions import Vector

#: Row roles: what a law does with each row.
Role = Literal["normal", "tangent", "bilateral", "given"]


@dataclass(frozen=True, kw_only=True, eq=False)
class RowBlock:
    """The rows of one contact or constraint, at its point (world axes).

    ``linear`` and ``angular`` are (k, 3) coefficient arrays on ``w`` (m/s) and ``Omega``
    (rad/s); ``roles`` says what each row means to the law; ``where`` names the item in
    messages (``contacts[0]``).

    >>> RowBlock(where="contacts[0]", point=np.zeros(3), linear=np.eye(3)[:1],
    ...          angular=np.zeros((1, 3)), roles=("normal",)).size
    1
    """

    where: str
    point: Vector
    linear: np.ndarray
    angular: np.ndarray
    roles: tuple[Role, ...]

    @property
    def size(self) -> int:
        return len(self.roles)

    @cached_property
    def coefficients(self) -> np.ndarray:
        """``C = [c_lin, c_ang]`` (k, 6): the rows as functionals of ``(w, Omega)`` (read-only,
        made once: a contact keeps its block, and every solve reads it)."""
        out = np.hstack([self.linear, self.angular])
        out.setflags(write=False)
        return out


def row_basis(functionals: np.ndarray, length_scale: float) -> np.ndarray:
    """A basis of the span of 6-component row functionals ``[c_lin, c_ang]``, orthonormal in
    the metric ``|c_lin|^2 + |c_ang|^2 / L^2`` (``L = length_scale``, m).

    With such rows, ``|Lambda|^2 = |P|^2 + |M_P|^2 / L^2`` for the item, so the minimum-norm
    split of redundant impulses (:func:`carnot.laws.min_norm_solve`) depends on the impulses alone,
    not on which basis of the rows was picked, and not on the unit of length. The rank is
    decided in the same metric (relative tolerance 1e-9).

    >>> np.abs(row_basis(np.array([[0, 0, 1.0, 0, 0, 0], [0, 0, 2.0, 0, 0, 0]]), 1.0)).tolist()
    [[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]]
    """
    scale = np.concatenate([np.ones(3), np.full(3, 1.0 / length_scale)])
    _, sing, vt = np.linalg.svd(functionals * scale, full_matrices=False)
    rank = int(np.sum(sing > 1e-9 * sing[0])) if sing.size and sing[0] > 0 else 0
    return vt[:rank] / scale


def patch_length(offsets: np.ndarray) -> float:
    """The patch's RMS distance from the contact point, ``L = sqrt(mean |r_k|^2)`` (m); 1 for
    a patch that is the contact point alone (it has no moment rows to weigh).

    >>> patch_length(np.array([[1.0, 0, 0], [-1.0, 0, 0]]))
    1.0
    """
    length = float(np.sqrt(np.mean(np.sum(offsets**2, axis=1))))
    return length if length > 0 else 1.0

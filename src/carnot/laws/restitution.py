"""Restitution as an equality: the post-impact velocity of every row is prescribed.

Newton's kinematic law: the normal relative velocity after is ``-e`` times that before,
``n . w'' = -e n . w'``; a sticking contact also ends with zero tangential relative velocity
(paper section 3.1); a fasten or pin ends (or stays) at zero relative velocity. For a contact
over a surface every patch point obeys the same rule. All such rows of a problem are solved at
once, ``G Lambda = target(w') - w'``.

Poisson's (kinetic) and Stronge's (energetic) hypotheses give the same answer as Newton's for a
single frictionless contact alone with bilateral constraints: the normal velocity is then an
affine function of the normal impulse, so the restitution impulse is ``e`` times the
compression impulse exactly when the final velocity is ``-e`` times the initial one, and the
restitution work is ``-e^2`` times the compression work likewise (Stronge, *Impact Mechanics*,
CUP 2000, section 2.2). Beyond that (friction with slip, several unilateral contacts) they differ;
the registry (:mod:`carnot.laws`) says so and the pipeline refuses such cases with a clear error
instead of answering with Newton's.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from carnot.laws.base import LawAnswer, LawParams, RowConflictError
from carnot.space import CONFLICT_TOLERANCE, RANK_TOLERANCE, Role


def target_velocity(
    w_before: np.ndarray, roles: Sequence[Role], restitution: np.ndarray | float
) -> np.ndarray:
    """Post-impact row velocities: ``-e w'`` on normal rows, 0 on tangent (sticking) and
    bilateral rows (m/s, or rad/s on moment rows).

    >>> target_velocity(np.array([-2.0, 1.0]), ["normal", "tangent"], 0.5).tolist()
    [1.0, 0.0]
    """
    is_normal = np.array([r == "normal" for r in roles])
    return np.where(is_normal, -np.asarray(restitution) * w_before, 0.0)


def min_norm_solve(delassus: np.ndarray, rhs: np.ndarray) -> LawAnswer:
    """``Lambda = G^+ rhs``, the minimum-norm solution, with the redundant rows marked.

    The rank is decided on the equilibrated operator ``D^-1/2 G D^-1/2`` (``D`` the diagonal
    of ``G``): rows of very different scales (a tiny inertia's ``r^2/J`` beside a mass's
    ``1/m``) are then compared fairly, and an eigenvalue under ``RANK_TOLERANCE`` of the
    largest counts as zero. A row whose diagonal is 0 (an identically zero Jacobian row) is
    null outright. The solution is the minimum-norm one in the rows' own metric (the split of
    redundant impulses, model/contacts.py), found on the complement of the null space. A part of
    ``rhs`` that no impulse can give, larger than ``CONFLICT_TOLERANCE``, means the requirements
    contradict each other (:class:`RowConflictError`).

    Two rows that are one and the same (a point held twice): the impulse splits evenly.

    >>> answer = min_norm_solve(np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([2.0, 2.0]))
    >>> answer.impulses.round(12).tolist(), answer.redundant.tolist()
    ([1.0, 1.0], [True, True])
    """
    if delassus.shape == (1, 1) and delassus[0, 0] > 0.0:  # one row: the common single contact
        return LawAnswer(impulses=rhs / delassus[0, 0], redundant=np.zeros(1, dtype=bool))
    m = rhs.shape[0]
    diagonal = np.diag(delassus).copy()
    live = diagonal > 0.0
    scale = np.zeros(m)
    scale[live] = 1.0 / np.sqrt(diagonal[live])
    eigval, eigvec = np.linalg.eigh(scale[:, None] * delassus * scale[None, :])
    top = max(float(eigval[-1]), 0.0) if eigval.size else 0.0
    keep = eigval > RANK_TOLERANCE * top if top > 0 else np.zeros_like(eigval, dtype=bool)
    if np.all(keep):
        lam = scale * (eigvec @ ((eigvec.T @ (scale * rhs)) / eigval))
        return LawAnswer(impulses=lam, redundant=np.zeros(m, dtype=bool))
    # the null space of G, in the rows' own coordinates, and its orthogonal complement
    null_scaled = scale[:, None] * eigvec[:, ~keep]
    null_scaled[~live] = 0.0
    null = np.hstack([null_scaled, np.eye(m)[:, ~live]])
    u, sing, _ = np.linalg.svd(null, full_matrices=True)
    rank = int(np.sum(sing > 1e-12 * (sing[0] if sing.size else 1.0)))
    basis_null, basis = u[:, :rank], u[:, rank:]
    reduced = basis.T @ delassus @ basis
    lam = basis @ np.linalg.solve(reduced, basis.T @ rhs) if basis.shape[1] else np.zeros(m)
    size = float(np.linalg.norm(rhs)) + 1e-300
    residual = rhs - delassus @ lam
    if np.linalg.norm(residual) > CONFLICT_TOLERANCE * size:
        raise RowConflictError(
            np.flatnonzero(np.abs(residual) > 1e-6 * size), float(np.linalg.norm(residual) / size)
        )
    return LawAnswer(impulses=lam, redundant=np.max(np.abs(basis_null), axis=1) > 1e-6)


class EqualityLaw:
    """Every row ends at its prescribed velocity (:func:`target_velocity`), all rows at once.

    >>> EQUALITY.resolve(np.array([[0.5]]), np.array([-2.0]),
    ...                  LawParams(roles=("normal",), restitution=1.0)).impulses.tolist()
    [8.0]
    """

    name = "equality"

    def resolve(self, delassus: np.ndarray, w_before: np.ndarray, params: LawParams) -> LawAnswer:
        reference = w_before if params.reference is None else params.reference
        target = target_velocity(reference, params.roles, params.restitution)
        return min_norm_solve(delassus, target - w_before)


EQUALITY = EqualityLaw()

"""Contact space: the one formulation every model, law and outcome meets (DESIGN.md section 1).

A model (free rigid bodies, a system in generalized coordinates) gives its velocity ``u'``
(n columns), its mass matrix ``M`` and, for each contact or constraint, the (6, n) *motion*
rows ``J_i`` that map ``u`` to the relative velocity ``w`` (m/s) and the relative angular
velocity ``Omega`` (rad/s) at the item's point. The item's :class:`~carnot.space.RowBlock`
``C_i`` (k, 6) picks the constrained directions, so the contact Jacobian is

    W_i = C_i J_i,      w_rows = W u,      G = W M^-1 W^T   (the Delassus operator, 1/kg),

and an impulse ``Lambda`` on the rows changes the velocity by ``M^-1 W^T Lambda``. Laws see
only ``G`` and ``w'``; the outcome reads ``(w, Omega) = J_i u`` before and after. Nothing here
knows what a body is.

A producer of many bodies passes ``M``, ``M^-1``, the motion rows and ``W`` as SciPy sparse
matrices (free bodies beyond a few dozen: :func:`carnot.model.free_bodies.assemble`): a
thousand contacts couple few bodies each, so ``G`` is mostly zeros, and the products are
then sparse (``delassus_sparse`` for the solvers that take it; ``delassus`` stays dense).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from carnot.space.rows import RowBlock


def is_sparse(matrix: Any) -> bool:
    """Whether ``matrix`` is a SciPy sparse matrix, without importing SciPy (where
    ``scipy.sparse`` was never imported, nothing can be one: a single impact loads no SciPy).

    >>> is_sparse(np.eye(2))
    False
    """
    module = sys.modules.get("scipy.sparse")
    return module is not None and bool(module.issparse(matrix))


#: Relative size under which an eigenvalue of the Delassus operator counts as zero.
RANK_TOLERANCE = 1e-11
#: Relative residual above which simultaneous requirements count as contradictory.
CONFLICT_TOLERANCE = 1e-8


@dataclass(frozen=True, kw_only=True, eq=False)
class ContactSpace:
    """``u'``, ``M``, ``M^-1``, the motion rows ``J_i`` and the row blocks ``C_i`` (SI units).

    ``jacobian`` (``W``, one row per constrained direction) is ``C_i J_i`` block by block;
    a producer may pass it computed in closed form (free bodies: ``r x c_lin`` by cross
    products, so that a central impact gives exactly zero spin). ``slices`` (each block's rows
    in ``W``) and ``owner`` (each row's item, for messages) are derived.

    A ball of 1 kg against a fixed floor, one normal row:

    >>> from carnot.space.rows import RowBlock
    >>> block = RowBlock(where="contacts[0]", point=np.zeros(3), linear=np.array([[0, 0, 1.0]]),
    ...                  angular=np.zeros((1, 3)), roles=("normal",))
    >>> space = ContactSpace(u_before=np.array([0, 0, -2.0]), mass_matrix=np.eye(3),
    ...     mass_matrix_inv=np.eye(3), motion=np.vstack([np.eye(3), np.zeros((3, 3))]),
    ...     blocks=(block,))
    >>> space.delassus().tolist(), space.row_velocities(space.u_before).tolist()
    ([[1.0]], [-2.0])
    """

    u_before: np.ndarray
    mass_matrix: np.ndarray
    mass_matrix_inv: np.ndarray
    motion: np.ndarray
    blocks: tuple[RowBlock, ...]
    jacobian: np.ndarray = None  # type: ignore[assignment]  # derived when not given
    slices: tuple[slice, ...] = field(init=False)
    owner: tuple[str, ...] = field(init=False)
    _inv_mass_wt: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        slices = []
        owner: list[str] = []
        start = 0
        for block in self.blocks:
            slices.append(slice(start, start + block.size))
            owner.extend([block.where] * block.size)
            start += block.size
        jacobian = self.jacobian
        if jacobian is None:
            parts = [b.coefficients @ self.motion[6 * i : 6 * i + 6]
                     for i, b in enumerate(self.blocks)]  # fmt: skip
            jacobian = np.vstack(parts) if parts else np.zeros((0, self.u_before.shape[0]))
            set_(self, "jacobian", jacobian)
        set_(self, "slices", tuple(slices))
        set_(self, "owner", tuple(owner))
        if is_sparse(jacobian) or is_sparse(self.mass_matrix_inv):
            import scipy.sparse as sp  # (many bodies only)

            jacobian = sp.csr_matrix(jacobian)
            set_(self, "jacobian", jacobian)
            set_(self, "_inv_mass_wt", (sp.csr_matrix(self.mass_matrix_inv) @ jacobian.T).tocsc())
        else:
            set_(self, "_inv_mass_wt", self.mass_matrix_inv @ jacobian.T)

    @property
    def is_sparse(self) -> bool:
        """Whether ``W`` and ``M^-1`` are held as sparse matrices (many bodies)."""
        return is_sparse(self.jacobian)

    @property
    def size(self) -> int:
        """The number of rows ``m``."""
        return int(self.jacobian.shape[0])

    def delassus(self, rows: np.ndarray | slice | None = None) -> np.ndarray:
        """``G = W M^-1 W^T`` (1/kg, or its moment-row counterparts) restricted to ``rows``."""
        if self.is_sparse:
            return np.asarray(self.delassus_sparse(rows).toarray())
        if rows is None:
            return self.jacobian @ self._inv_mass_wt
        return self.jacobian[rows] @ self._inv_mass_wt[:, rows]

    def delassus_sparse(self, rows: np.ndarray | slice | None = None) -> Any:
        """``G`` on ``rows`` as a SciPy sparse matrix (computed sparse where ``W`` is)."""
        import scipy.sparse as sp

        if not self.is_sparse:
            return sp.csr_matrix(self.delassus(rows))
        if rows is None:
            return sp.csr_matrix(self.jacobian @ self._inv_mass_wt)
        return sp.csr_matrix(self.jacobian[rows] @ self._inv_mass_wt[:, rows])

    def coupling(self, rows: np.ndarray | slice, other: np.ndarray | slice) -> np.ndarray:
        """The off-diagonal block ``G[rows, other] = W_rows M^-1 W_other^T``."""
        out = self.jacobian[rows] @ self._inv_mass_wt[:, other]
        return np.asarray(out.toarray()) if is_sparse(out) else out

    def row_velocities(self, u: np.ndarray, rows: np.ndarray | slice | None = None) -> np.ndarray:
        """``w = W u`` on ``rows`` (all by default)."""
        return np.asarray((self.jacobian if rows is None else self.jacobian[rows]) @ u)

    def velocity_change(
        self, impulses: np.ndarray, rows: np.ndarray | slice | None = None
    ) -> np.ndarray:
        """``du = M^-1 W^T Lambda`` for row impulses ``impulses`` on ``rows`` (all by default)."""
        if rows is None:
            return np.asarray(self._inv_mass_wt @ impulses)
        return np.asarray(self._inv_mass_wt[:, rows] @ impulses)

    def motion_at(self, index: int, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(w, Omega)`` at block ``index``'s point for the velocity ``u`` (m/s, rad/s)."""
        both = np.asarray(self.motion[6 * index : 6 * index + 6] @ u)
        return both[:3], both[3:]

    def held_schur(
        self, rows: slice, held: np.ndarray, u: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """What ``rows`` see while the ``held`` rows keep their velocity at 0 throughout the
        impact: ``(K, w')`` with the Schur complement ``K = G_cc - G_ch G_hh^+ G_hc`` and
        ``w' = w_c - G_ch G_hh^+ w_h`` (the held impulses follow, ``Lambda_h = -G_hh^+ (w_h +
        G_hc P)``). Without held rows, ``(G_cc, w_c)``."""
        g_cc = self.delassus(rows)
        w_c = self.row_velocities(u, rows)
        if not held.size:
            return 0.5 * (g_cc + g_cc.T), w_c
        g_hh_pinv = np.linalg.pinv(self.delassus(held), rcond=RANK_TOLERANCE, hermitian=True)
        g_ch = self.coupling(rows, held)
        k = g_cc - g_ch @ g_hh_pinv @ g_ch.T
        w_c = w_c - g_ch @ g_hh_pinv @ self.row_velocities(u, held)
        return 0.5 * (k + k.T), w_c

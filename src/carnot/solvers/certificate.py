"""What an iterative answer proves: each contact's regime, and whether the impulses and the
velocities are unique (DESIGN.md section 9).

The enumeration knows uniqueness from having tried every regime; an iterative solver knows
one answer. Two facts still decide much of it:

* **Without friction** the law is a monotone complementarity problem (``G`` symmetric
  positive semi-definite): the answers are the minimizers of the convex quadratic
  ``1/2 r.G r + q.r`` over ``r_n >= 0`` and the held rows, so they all share ``G r`` and the
  velocities are unique (Cottle, Pang and Stone, *The Linear Complementarity Problem*, 1992,
  thm 3.1.7). The impulses are unique unless a direction ``d`` keeps ``G d = 0`` on the rows
  that end at rest (``Z``: closed contacts' normals, held rows) and keeps ``r + t d``
  feasible: none when ``G_ZZ`` is nonsingular (its Cholesky factor's pivots all above 1e-12
  of the largest); otherwise its null space is searched, with the feasibility of the
  contacts that carry no impulse by a linear program.
* **With friction** no such theorem holds (several outcomes, or none, occur), so global
  uniqueness is not claimed (``None``). The impulses are not unique when the answer's regime
  leaves a direction ``d`` (closed contacts' free rows, a slipping contact along its slip)
  with ``G d = 0`` that keeps the impulses in their cones: a statically indeterminate
  answer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from carnot.conventions import RELATIVE_TOLERANCE
from carnot.solvers.problem import ContactProblem, split

#: Largest number of free rows whose null space is computed densely (an SVD or eigh).
DENSE_NULL_SPACE_UP_TO = 1500
#: From this many free rows, and where ``B^T G B`` is sparse (fewer nonzeros than this
#: fraction of its entries), its nonsingularity is first sought by a sparse factorization
#: (:func:`_sparse_pivots_hold`).
SPARSE_PROOF_FROM = 64
SPARSE_FILL = 0.1


@dataclass(frozen=True, kw_only=True)
class Verdict:
    """Each contact's regime (``separate``, ``stick``, ``slip``, ``frictionless``), and what is
    proved of uniqueness (``None``: not verified)."""

    regimes: tuple[str, ...]
    unique: bool | None
    velocities_unique: bool | None


def regimes(problem: ContactProblem, r: np.ndarray, u: np.ndarray, velocity_tol: float
            ) -> tuple[str, ...]:  # fmt: skip
    """Each contact's regime at the answer ``r`` (velocities ``u``): ``separate`` where it
    carries no normal impulse (1e-9 of the largest), otherwise ``frictionless``, ``stick``
    (told to stick, or no slip above ``velocity_tol``) or ``slip``."""
    r_n, _ = split(problem, r)
    _, u_t = split(problem, u)
    impulse_tol = RELATIVE_TOLERANCE * (float(np.abs(r).max()) if r.size else 0.0)
    slip = np.sqrt(np.einsum("ij,ij->i", u_t, u_t))
    out = []
    for k in range(problem.normal.shape[0]):
        mu = float(problem.mu[k])
        if r_n[k] <= impulse_tol:
            out.append("separate")
        elif mu == 0.0:
            out.append("frictionless")
        elif math.isinf(mu) or slip[k] <= velocity_tol:
            out.append("stick")
        else:
            out.append("slip")
    return tuple(out)


def verdict(problem: ContactProblem, r: np.ndarray, u: np.ndarray, velocity_tol: float
            ) -> Verdict:  # fmt: skip
    """The regimes and what is proved of uniqueness at the answer ``r`` (module docstring)."""
    found = regimes(problem, r, u, velocity_tol)
    frictionless = bool(np.all(problem.mu == 0.0))
    impulse_tol = RELATIVE_TOLERANCE * max(float(np.abs(r).max()) if r.size else 0.0, 1e-300)
    columns = _free_directions(problem, r, u, found, velocity_tol)
    if columns.shape[1] == 0:
        return Verdict(regimes=found, unique=True if frictionless else None,
                       velocities_unique=True if frictionless else None)  # fmt: skip
    null = _null_space(problem, columns)
    if null is None:  # too large to look for
        return Verdict(regimes=found, unique=None,
                       velocities_unique=True if frictionless else None)  # fmt: skip
    if null.shape[1] == 0:
        return Verdict(regimes=found, unique=True if frictionless else None,
                       velocities_unique=True if frictionless else None)  # fmt: skip
    moves = _feasible_direction(problem, r, np.asarray(columns @ null), found, impulse_tol)
    unique = False if moves else (True if frictionless else None)
    return Verdict(regimes=found, unique=unique,
                   velocities_unique=True if frictionless else None)  # fmt: skip


def _free_directions(problem: ContactProblem, r: np.ndarray, u: np.ndarray,
                     found: tuple[str, ...], velocity_tol: float) -> sp.csc_matrix:  # fmt: skip
    """The directions ``B`` (m x k, sparse) in which the answer's regime lets the impulses
    move: the normal of every contact at rest along it (``|u_n| <= velocity_tol``), its
    tangents too where it sticks, a slipping contact's ``e_n + mu e_slip`` (its impulse stays
    on the cone's edge against the same slip), and every held row."""
    m = problem.size
    u_n, u_t = split(problem, u)
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []

    count = [0]

    def column(entries: list[tuple[int, float]]) -> None:
        for row, value in entries:
            rows.append(row)
            cols.append(count[0])
            vals.append(value)
        count[0] += 1

    for k, regime in enumerate(found):
        if abs(float(u_n[k])) > velocity_tol:
            continue
        n = int(problem.normal[k])
        tangents = [int(t) for t in problem.tangent[k] if t < m]
        # (an unloaded contact at rest along its normal may start to carry an impulse: its
        # normal only, so that every direction kept stays in its cone)
        if regime in ("frictionless", "separate"):
            column([(n, 1.0)])
        elif regime == "stick":
            for row in (n, *tangents):
                column([(row, 1.0)])
        else:  # slip: along the cone's edge, opposite the slip
            slip = u_t[k] / max(float(np.linalg.norm(u_t[k])), 1e-300)
            column([(n, 1.0), *((row, -float(problem.mu[k]) * float(slip[j]))
                                for j, row in enumerate(tangents))])  # fmt: skip
    for row in problem.held:
        column([(int(row), 1.0)])
    return sp.csc_matrix((vals, (rows, cols)), shape=(m, count[0]))


def _null_space(problem: ContactProblem, columns: sp.csc_matrix) -> np.ndarray | None:
    """A basis of ``{c : G B c = 0}`` (``B`` = ``columns``), from ``B^T G B`` (``G`` is positive
    semi-definite: ``G B c = 0`` exactly where ``c^T B^T G B c = 0``): none where that is
    nonsingular (its Cholesky pivots, or beyond :data:`DENSE_NULL_SPACE_UP_TO` columns its
    sparse LU's, above 1e-12 of the largest), otherwise from its eigenvectors; ``None``
    where it is too large to look for."""
    g = problem.delassus
    k = columns.shape[1]
    if isinstance(g, np.ndarray) and k <= SPARSE_PROOF_FROM:
        dense = dense_gram(g, columns)  # (the sparse products' numbers, without their cost)
        scale = float(np.abs(np.diag(dense)).max()) if k else 0.0
        return np.eye(k) if scale == 0.0 else _dense_null_space(dense, scale)
    btgb = sparse_gram(g, columns)
    scale = float(abs(btgb.diagonal()).max()) if k else 0.0
    if scale == 0.0:
        return np.eye(k)
    if k > DENSE_NULL_SPACE_UP_TO:
        try:
            lu = spla.splu(btgb, diag_pivot_thresh=0.0)
        except RuntimeError:
            return None
        pivots = np.abs(lu.U.diagonal())
        return np.zeros((k, 0)) if float(pivots.min()) > 1e-12 * scale else None
    if k > SPARSE_PROOF_FROM and btgb.nnz < SPARSE_FILL * k * k and _sparse_pivots_hold(
            btgb, scale):  # fmt: skip
        return np.zeros((k, 0))
    return _dense_null_space(btgb.toarray(), scale)


def _dense_null_space(dense: np.ndarray, scale: float) -> np.ndarray:
    """:func:`_null_space` of a dense ``B^T G B`` (``scale``: its largest diagonal entry):
    none where its Cholesky pivots are all above 1e-12 of ``scale``, otherwise the
    eigenvectors of its eigenvalues below 1e-10 of the largest."""
    try:
        factor = sla.cholesky(dense, lower=True, check_finite=False)
        if float((np.diag(factor) ** 2).min()) > 1e-12 * scale:
            return np.zeros((dense.shape[0], 0))
    except sla.LinAlgError:
        pass
    values, vectors = sla.eigh(dense, check_finite=False)
    return np.asarray(vectors[:, values <= 1e-10 * max(float(values.max()), scale)])


def sparse_gram(g: sp.spmatrix | np.ndarray, columns: sp.csc_matrix) -> sp.csc_matrix:
    """``B^T G B`` symmetrized, ``(A + A^T) / 2`` (k x k, sparse), by SciPy's sparse products
    (``B`` = ``columns``, m x k; ``G`` m x m, dense or sparse)."""
    btgb = columns.T @ (g @ columns)
    btgb = sp.csc_matrix(btgb) if sp.issparse(btgb) else sp.csc_matrix(np.asarray(btgb))
    return (0.5 * (btgb + btgb.T)).tocsc()


def dense_gram(g: np.ndarray, columns: sp.csc_matrix) -> np.ndarray:
    """:func:`sparse_gram` of a dense ``G``, dense, with the same numbers: SciPy's products
    of a dense matrix by a sparse one (``csr_matvecs``) sum each column's entries in their
    stored order from zero, ``(G B)_:j = sum_p b_pj G_:p`` and ``(B^T (G B))_i: = sum_p b_pi
    (G B)_p:``, each term rounded before it is added; so do these, a column's ``p``-th
    entries at once (a robot's free rows have 1 to 3 entries each), then ``(A + A^T) / 2``
    with zeros unsigned, as the sparse sum stores none. Some ten NumPy calls where the
    sparse route makes six sparse matrices (a fifth of a certificate on 18 to 50 rows).

    >>> b = sp.csc_matrix(np.array([[1.0, 0.0], [0.5, 0.0], [0.0, 1.0]]))
    >>> g = np.array([[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 3.0]])
    >>> dense_gram(g, b).tolist(), bool(np.array_equal(dense_gram(g, b),
    ...                                                sparse_gram(g, b).toarray()))
    ([[3.5, 0.0], [0.0, 3.0]], True)
    """
    k = columns.shape[1]
    indptr, indices, data = columns.indptr, columns.indices, columns.data
    counts = np.diff(indptr)
    gb_t = np.zeros((k, g.shape[0]))  # (G B)^T: row j is G B's column j
    entries = []
    for p in range(int(counts.max()) if k else 0):
        sel = np.flatnonzero(counts > p)
        at = indptr[sel] + p
        entries.append((sel, indices[at], data[at][:, None]))
    for sel, rows, values in entries:
        gb_t[sel] += values * g[:, rows].T
    gb = gb_t.T
    out = np.zeros((k, k))
    for sel, rows, values in entries:
        out[sel] += values * gb[rows]
    return 0.5 * (out + out.T) + 0.0


def _sparse_pivots_hold(btgb: sp.csc_matrix, scale: float) -> bool:
    """Whether the symmetric positive semi-definite ``B^T G B`` (k x k, sparse) is
    nonsingular by the pivots of its sparse LU in a symmetric ordering, without row
    exchanges (SuperLU's ``SymmetricMode``, the minimum degree of ``A^T + A``): with
    ``P^T A P = L U`` so taken, ``U``'s diagonal is the ``D`` of ``P^T A P = L D L^T``, the
    squared pivots of its Cholesky factor, and every one above 1e-12 of the largest diagonal
    entry is the dense test's condition (on a reordered matrix). Where that fails the dense
    route decides (its eigenvectors give the null space). A 1000-ball cradle's 999 closed
    contacts: a tridiagonal ``B^T G B``, in well under a millisecond, where the dense
    Cholesky took 10 ms."""
    try:
        lu = spla.splu(btgb, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})  # fmt: skip
    except RuntimeError:  # (exactly singular)
        return False
    if not (np.array_equal(lu.perm_r, lu.perm_c)):  # a row exchange after all: not D
        return False
    return bool(float(lu.U.diagonal().min()) > 1e-12 * scale)


def _feasible_direction(problem: ContactProblem, r: np.ndarray, directions: np.ndarray,
                        found: tuple[str, ...], impulse_tol: float) -> bool:  # fmt: skip
    """Whether some nonzero ``d`` in the span of ``directions`` keeps ``r + t d`` in the
    cones for small ``t > 0``: free where every contact it moves carries an impulse strictly
    inside its constraint; where one carries none (``r_n = 0``) its normal must not decrease
    (a linear program, SciPy's HiGHS)."""
    if directions.shape[1] == 0:
        return False
    r_n, _ = split(problem, r)
    tight = [int(problem.normal[k]) for k, reg in enumerate(found)
             if r_n[k] <= impulse_tol]  # fmt: skip
    d_tight = directions[tight] if tight else np.zeros((0, directions.shape[1]))
    if not tight or float(np.abs(d_tight).max()) <= 1e-12:
        return True
    rank = np.linalg.matrix_rank(d_tight, tol=1e-10)
    if rank < directions.shape[1]:
        return True  # a direction that leaves every unloaded contact alone
    from scipy.optimize import linprog

    k = directions.shape[1]
    res = linprog(-d_tight.sum(axis=0), A_ub=-d_tight, b_ub=np.zeros(len(tight)),
                  bounds=[(-1.0, 1.0)] * k, method="highs")  # fmt: skip
    return bool(res.status == 0 and -res.fun > 1e-9)

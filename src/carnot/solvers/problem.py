"""The contact problem every solver of the simultaneous law reads (DESIGN.md section 9).

The simultaneous law in contact space (:mod:`carnot.laws.multiple.simultaneous`) is exactly
the frictional contact problem of nonsmooth mechanics, Siconos' ``fc3d`` in De Saxce's form::

    u = G r + q,     q = w' + e min(w_n', 0) e_n   (per contact),   q_h = w_h' - target_h,

    r_c in K_c = {|r_t| <= mu r_n},   u_hat_c = u_c + mu |u_t| e_n in K_c*,   r_c . u_hat_c = 0,

with ``u`` the post-impact row velocities shifted by restitution (``u_n = w_n'' + e w_n'`` on
approach: Newton's law acts on approach only, so a contact closed but separating before the
impact has ``q_n = w_n'`` and takes part with ``w_n'' >= 0``), and held rows ending at their
target (``u_h = 0``, ``r_h`` free). A contact *told to stick* has ``mu = inf``: loaded, it
does not slip (``u = 0``); unloaded, it receives nothing. A frictionless contact has
``mu = 0``.

This module holds that problem as one immutable value (:class:`ContactProblem`, built once by
:func:`contact_problem` from what the law receives) and its residual (:func:`fc3d_error`),
evaluated from ``G`` and ``q`` alone, apart from any solver, so that a certificate never
repeats what the solver believed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, TypeAlias

import numpy as np
import scipy.sparse as sp

from carnot.errors import InputError
from carnot.laws.multiple.rows import ContactRows, HeldRows

#: ``G`` as the solvers take it: a dense array, or a SciPy sparse matrix for large problems.
Delassus: TypeAlias = Any


@dataclass(frozen=True, kw_only=True, eq=False)
class ContactProblem:
    """``u = G r + q`` with per-contact cones (module docstring), ``m`` rows, ``nc`` contacts.

    ``normal`` (nc,) each contact's normal row; ``tangent`` (nc, 2) its tangent rows, ``m``
    where absent (a planar contact has one, a frictionless one may have none); ``mu`` (nc,)
    its Coulomb coefficient (``inf``: told to stick); ``held`` the held rows (``u_h = 0``).
    Every row belongs to one contact or is held.
    """

    delassus: Delassus
    q: np.ndarray
    normal: np.ndarray
    tangent: np.ndarray
    mu: np.ndarray
    held: np.ndarray

    @property
    def size(self) -> int:
        """The number of rows ``m``."""
        return int(self.q.shape[0])

    @property
    def is_sparse(self) -> bool:
        """Whether ``G`` is a SciPy sparse matrix."""
        return sp.issparse(self.delassus)

    def velocities(self, r: np.ndarray) -> np.ndarray:
        """``u = G r + q`` (m/s; on approach, shifted by restitution)."""
        gr = self.delassus @ r
        if type(gr) is not np.ndarray or gr.ndim != 1:  # (a sparse G's product: a matrix)
            gr = np.asarray(gr).reshape(-1)
        return gr + self.q

    def diagonal(self) -> np.ndarray:
        """``diag(G)`` (1/kg)."""
        g = self.delassus
        return np.asarray(g.diagonal() if sp.issparse(g) else np.diag(g), dtype=float)


def contact_problem(
    delassus: Delassus,
    w_before: np.ndarray,
    contacts: Sequence[ContactRows],
    held: HeldRows | None = None,
) -> ContactProblem:
    """The fc3d problem of the simultaneous law (module docstring) from the law's own inputs:
    ``G`` (m x m, 1/kg), ``w'`` (m/s), the contacts' rows and parameters and the held rows.

    Two balls in a row, the first at 1 m/s into the second at rest, e = 1/2:
    ``q_n = -1 - 1/2 = -1.5``.

    >>> p = contact_problem(np.array([[2.0]]), np.array([-1.0]),
    ...                     [ContactRows(normal=0, restitution=0.5)])
    >>> p.q.tolist(), p.mu.tolist(), p.tangent.tolist()
    ([-1.5], [0.0], [[1, 1]])
    """
    w = np.asarray(w_before, dtype=float).reshape(-1)
    m = w.shape[0]
    nc = len(contacts)
    normal = np.fromiter((c.normal for c in contacts), dtype=np.intp, count=nc)
    tangent = np.full((nc, 2), m, dtype=np.intp)
    mu = np.zeros(nc)
    e = np.zeros(nc)
    for k, c in enumerate(contacts):
        tangent[k, : len(c.tangents)] = c.tangents
        e[k] = c.restitution
        kind = c.kind
        mu[k] = math.inf if kind == "told_to_stick" else (c.friction if c.tangents else 0.0)
        if kind == "frictionless":
            mu[k] = 0.0
    q = w.copy()
    q[normal] += e * np.minimum(w[normal], 0.0)
    rows = np.zeros(0, dtype=np.intp)
    if held is not None and held.rows:
        rows = np.array(held.rows, dtype=np.intp)
        q[rows] -= np.array(held.target)
    g = delassus
    if not sp.issparse(g):
        g = np.asarray(g, dtype=float)
    return ContactProblem(delassus=g, q=q, normal=normal, tangent=tangent, mu=mu, held=rows)


def fc3d_problem(delassus: Delassus, q: np.ndarray, mu: np.ndarray, dimension: int = 3
                 ) -> ContactProblem:  # fmt: skip
    """Siconos' form as it is stored (``W``, ``q``, ``mu``; each contact ``dimension`` rows
    in a row, its normal first): the problem as it is, no restitution, no held rows.

    >>> p = fc3d_problem(np.eye(3), np.array([-1.0, 0.0, 0.0]), np.array([0.5]))
    >>> p.normal.tolist(), p.tangent.tolist()
    ([0], [[1, 2]])
    """
    q = np.asarray(q, dtype=float).reshape(-1)
    mu = np.asarray(mu, dtype=float).reshape(-1)
    if dimension not in (2, 3):
        raise InputError("dimension", "must be 2 or 3", dimension)
    m = q.shape[0]
    if m != dimension * mu.shape[0]:
        raise InputError("q", f"must hold {dimension} rows per contact ({mu.shape[0]} "
                         f"contacts)", m)  # fmt: skip
    if not (np.isfinite(mu).all() and (mu >= 0.0).all()):
        raise InputError("mu", "must be finite and >= 0", mu)
    if not np.isfinite(q).all():
        raise InputError("q", "must be finite", q)
    shape = delassus.shape
    if shape != (m, m):
        raise InputError("W", f"must be {m} x {m}", shape)
    normal = np.arange(0, m, dimension, dtype=np.intp)
    tangent = np.full((mu.shape[0], 2), m, dtype=np.intp)
    tangent[:, 0] = normal + 1
    if dimension == 3:
        tangent[:, 1] = normal + 2
    g = delassus if sp.issparse(delassus) else np.asarray(delassus, dtype=float)
    return ContactProblem(delassus=g, q=q, normal=normal, tangent=tangent, mu=mu,
                          held=np.zeros(0, dtype=np.intp))  # fmt: skip


def project_cones(x_n: np.ndarray, x_t: np.ndarray, mu: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Each ``(x_n, x_t)`` projected on its cone ``{|t| <= mu n}`` (Euclidean, exact, circular;
    ``mu = 0``: the ray ``n >= 0``; ``mu = inf``: the half-space ``n >= 0``, whose loaded
    points keep their tangent and whose others go to zero: a contact told to stick).

    >>> pn, pt = project_cones(np.array([0.0, 1.0]), np.array([[2.0, 0.0], [0.5, 0.0]]),
    ...                        np.array([1.0, 1.0]))
    >>> pn.tolist(), pt.tolist()
    ([1.0, 1.0], [[1.0, 0.0], [0.5, 0.0]])
    """
    told = np.isinf(mu)
    any_told = bool(told.any())
    mu_f = np.where(told, 0.0, mu) if any_told else mu
    nt = np.sqrt(np.einsum("ij,ij->i", x_t, x_t))
    # (x_n >= 0: a frictionless contact, mu = 0 with no tangent rows, has nt = 0 <= mu x_n
    # for every x_n, a pull included; at x = 0, inside and polar agree)
    mu_nt = mu_f * nt
    inside = (nt <= mu_f * x_n) & (x_n >= 0.0)
    polar = ~inside & (mu_nt <= -x_n)
    a = (x_n + mu_nt) / (1.0 + mu_f * mu_f)
    p_n = np.where(inside, x_n, np.where(polar, 0.0, a))
    # (the tangent's scale: 1 inside, 0 in the polar cone or with no tangent, mu a / nt on
    # the surface; nt is positive there)
    on_surface = ~(inside | polar | (nt == 0.0))
    scale = inside.astype(float)
    scale[on_surface] = mu_f[on_surface] * a[on_surface] / nt[on_surface]
    p_t = x_t * scale[:, None]
    if any_told:
        loaded = told & (x_n > 0.0)
        p_n = np.where(told, np.maximum(x_n, 0.0), p_n)
        p_t = np.where(told[:, None], np.where(loaded[:, None], x_t, 0.0), p_t)
    return p_n, p_t


def split(problem: ContactProblem, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A row vector's normal and tangent parts per contact: ``(v_n (nc,), v_t (nc, 2))``,
    zero where a contact has no such row."""
    ext = _extended(v)
    return ext[problem.normal], ext[problem.tangent]


def _extended(v: np.ndarray) -> np.ndarray:
    """``v`` with one spare zero entry at its end, where absent rows point (``np.append``'s
    result, without its checks: this is called several times a solver step)."""
    ext = np.empty(v.shape[0] + 1)
    ext[:-1] = v
    ext[-1] = 0.0
    return ext


def onto_cones(problem: ContactProblem, v: np.ndarray) -> np.ndarray:
    """The row vector ``v`` with each contact's part projected on its cone
    (:func:`project_cones`) and the held rows as they are (their cone is the whole line).

    >>> p = fc3d_problem(np.eye(3), np.zeros(3), np.array([0.5]))
    >>> onto_cones(p, np.array([1.0, 2.0, 0.0])).round(12).tolist()
    [1.6, 0.8, 0.0]
    """
    v_n, v_t = split(problem, v)
    p_n, p_t = project_cones(v_n, v_t, problem.mu)
    out = _extended(v)
    out[problem.normal] = p_n
    out[problem.tangent] = p_t  # (absent tangents write into the spare last entry, dropped)
    return out[:-1]


def natural_map(problem: ContactProblem, r: np.ndarray, rho: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The natural map ``F(r) = r - proj_K(r - rho u_hat(r))`` (row by row; the held rows'
    cone is the whole line, so ``F_h = rho u_h``) and ``u = G r + q``. ``F(r) = 0`` exactly
    when ``r`` meets the law; ``rho`` (m,) is a positive step per row (N s / (m/s))."""
    u = problem.velocities(r)
    u_n, u_t = split(problem, u)
    mu = problem.mu
    mu_f = np.where(np.isinf(mu), 0.0, mu)
    u_hat = u.copy()
    u_hat[problem.normal] = u_n + mu_f * np.sqrt(np.einsum("ij,ij->i", u_t, u_t))
    return r - onto_cones(problem, r - rho * u_hat), u


def fc3d_error(problem: ContactProblem, r: np.ndarray) -> float:
    """Siconos' relative fc3d error of the impulses ``r`` (DESIGN.md section 9)::

        ||r - proj_K(r - u_hat)|| / max(||q||, ||r||, ||u||)     (1 where all three are 0),

    the natural map at unit step over every contact (``fc3d_compute_error.c``), with the held
    rows' ``|u_h|``; zero exactly when ``r`` meets the law. Evaluated from ``G`` and ``q``
    alone.

    >>> p = fc3d_problem(np.eye(3), np.array([-1.0, 0.0, 0.0]), np.array([0.5]))
    >>> fc3d_error(p, np.array([1.0, 0.0, 0.0])), fc3d_error(p, np.zeros(3)) > 0.1
    (0.0, True)
    """
    f, u = natural_map(problem, r, np.ones(problem.size))
    return relative_error(problem, r, f, u)


def relative_error(problem: ContactProblem, r: np.ndarray, f: np.ndarray, u: np.ndarray
                   ) -> float:  # fmt: skip
    """:func:`fc3d_error` from the natural map ``f`` at unit step and ``u = G r + q``:
    ``|f| / max(|q|, |r|, |u|)`` (1 where all three are 0)."""
    scale = max(_norm(problem.q), _norm(r), _norm(u))
    return _norm(f) / (scale if scale > 0.0 else 1.0)


def _norm(x: np.ndarray) -> float:
    """``numpy.linalg.norm`` of a real vector by its own formula, ``sqrt(x . x)`` (the same
    bits), without its checks (a few microseconds: a solver step evaluates four)."""
    return math.sqrt(float(x.dot(x)))

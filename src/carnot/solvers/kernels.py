"""The iterative solver's inner loops, compiled (Numba, cached beside this file; without
Numba the same functions run as plain Python, with the same answers, slower).

Each is a loop over the contacts that does what :mod:`carnot.solvers.problem` writes in
NumPy (the cone projection, the natural map) or what :mod:`carnot.solvers.iterative` needs
of them (the natural map's generalized Jacobian, ADMM's step), with no array temporaries: on
the small problems of a robot's landing (13 to 50 rows) each NumPy call on them costs more
than its arithmetic, and a stalled Newton try evaluates the natural map some 20 to 30 times
a step. The projection and the natural map here give the NumPy functions' numbers to the
last bit (the same operations in the same order; tests/test_solvers.py checks this on random
problems), so the answers do not depend on which ran; the certificate's residual is the
NumPy route's (:func:`carnot.solvers.problem.fc3d_error`).

Only the iterative solver imports this module (Numba's import and the kernels' loading cost
some 0.3 s, which a box's enumerated landing does not pay).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from carnot.batch.ops import compiled_rules, source_digest, stamped
from carnot.laws import cone
from carnot.laws.cone import project_onto_cone

try:
    import numba
except ImportError:  # pragma: no cover - without Numba the loops run as plain Python
    numba = None  # type: ignore[assignment]

#: The digest of the cone's module, whose projection these loops compile: part of every
#: compiled name here (:func:`carnot.batch.ops.stamped`), so that a changed rule is compiled
#: again rather than loaded stale from Numba's cache (which stamps an entry with this file).
_RULES = source_digest([cone])


def _jit(fn: Callable[..., Any]) -> Any:
    """Compiled once per machine (cached beside this file); without Numba, the function as
    written."""
    if numba is None:
        return fn
    return numba.njit(cache=True, nogil=True, error_model="numpy")(stamped(fn, _RULES))


#: Each contact's projection: the cone's one statement (carnot.laws.cone), compiled here.
_onto_cone = (project_onto_cone if numba is None else
              compiled_rules(cone, ("project_onto_cone",), numba.njit(cache=True, nogil=True,
                                                                       error_model="numpy"),
                             _RULES)["project_onto_cone"])  # fmt: skip




@_jit
def project_rows(v: np.ndarray, normal: np.ndarray, tangent: np.ndarray, mu: np.ndarray,
                 out: np.ndarray) -> None:  # fmt: skip
    """``out = v`` with each contact's rows ``(normal[c], tangent[c])`` projected on its cone
    (:func:`carnot.solvers.problem.project_cones`). ``v`` and ``out`` hold one spare last
    entry, where absent rows point (zero in ``v``; what is written there is dropped). One
    loop over the contacts, compiled (the projection is most of a Newton line search's cost:
    Go2's landing takes some 2500 of them): no array temporaries.
    """
    m = v.shape[0]
    for i in range(m):
        out[i] = v[i]
    for c in range(normal.shape[0]):
        p_n, t1, t2 = _onto_cone(v[normal[c]], v[tangent[c, 0]], v[tangent[c, 1]], mu[c])
        out[normal[c]] = p_n
        out[tangent[c, 0]] = t1
        out[tangent[c, 1]] = t2
    out[m - 1] = 0.0


@_jit
def natural_rows(r: np.ndarray, u: np.ndarray, rho: np.ndarray, normal: np.ndarray,
                  tangent: np.ndarray, mu: np.ndarray) -> np.ndarray:  # fmt: skip
    """:func:`natural_map`'s ``F`` from ``r`` and ``u``: ``x = r - rho u_hat``
    (``u_hat_n = u_n + mu |u_t|``, De Saxce's shift), projected (:func:`project_rows`),
    ``F = r - proj(x)``; one compiled pass (absent rows, index ``m``, read as zero)."""
    m = r.shape[0]
    x = np.empty(m + 1)
    u_ext = np.empty(m + 1)
    for i in range(m):
        x[i] = r[i] - rho[i] * u[i]
        u_ext[i] = u[i]
    x[m] = 0.0
    u_ext[m] = 0.0
    for c in range(normal.shape[0]):
        mu_c = mu[c]
        if math.isinf(mu_c):
            mu_c = 0.0  # (told to stick: no shift, u = 0 when loaded)
        t1 = u_ext[tangent[c, 0]]
        t2 = u_ext[tangent[c, 1]]
        n = normal[c]
        x[n] = r[n] - rho[n] * (u[n] + mu_c * math.sqrt(t1 * t1 + t2 * t2))
    out = np.empty(m + 1)
    project_rows(x, normal, tangent, mu, out)
    f = np.empty(m)
    for i in range(m):
        f[i] = r[i] - out[i]
    return f


def natural_map(problem: Any, r: np.ndarray, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`carnot.solvers.problem.natural_map`, compiled: ``F(r)`` and ``u = G r + q``
    (the same numbers), ``problem`` a :class:`~carnot.solvers.problem.ContactProblem`."""
    u = problem.velocities(r)
    return natural_rows(r, u, rho, problem.normal, problem.tangent, problem.mu), u


@_jit
def line_search(r: np.ndarray, d: np.ndarray, g: np.ndarray, q: np.ndarray, rho: np.ndarray,
                normal: np.ndarray, tangent: np.ndarray, mu: np.ndarray, norm_f: float
                ) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, float]:  # fmt: skip
    """Newton's backtracking along ``d`` from ``r`` (:mod:`carnot.solvers.iterative`; ``G``
    dense): the first ``alpha = 2^-k`` with ``|F(r + alpha d)| <= (1 - 1e-4 alpha) |F(r)|``
    (Armijo's rule on ``|F|``), or the last tried, below 1e-10; returns ``alpha``, the trial
    point, ``F`` and ``u = G r + q`` there, and ``|F|``. The products by BLAS (``np.dot``, as
    NumPy's ``@``), the rest as :func:`natural_rows`: the same numbers as the loop written in
    NumPy, without a Python round trip per halving (a stalled try halves 20 to 30 times)."""
    alpha = 1.0
    while True:
        trial = r + alpha * d
        u = np.dot(g, trial) + q
        f = natural_rows(trial, u, rho, normal, tangent, mu)
        norm_t = math.sqrt(np.dot(f, f))
        if norm_t <= (1.0 - 1e-4 * alpha) * norm_f or alpha < 1e-10:
            return alpha, trial, f, u, norm_t
        alpha *= 0.5


def onto_cones(problem: Any, v: np.ndarray) -> np.ndarray:
    """:func:`carnot.solvers.problem.onto_cones`, compiled (the same numbers)."""
    m = v.shape[0]
    ext = np.empty(m + 1)
    ext[:m] = v
    ext[m] = 0.0
    out = np.empty(m + 1)
    project_rows(ext, problem.normal, problem.tangent, problem.mu, out)
    return out[:m]


@_jit
def jacobian_blocks(r: np.ndarray, u: np.ndarray, rho: np.ndarray, normal: np.ndarray,
            tangent: np.ndarray, mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Each contact's 3 x 3 block of ``D`` (rows and columns ``normal, tangent``), the
    derivative of its cone's projection at ``x = r - rho u_hat``, and ``E``'s two entries on
    its normal row, ``mu u_t / |u_t|`` (De Saxce's shift ``d(mu |u_t|)/du_t``; zero where the
    contact does not slip). ``r`` and ``u`` hold one spare last zero entry, where absent
    rows point. Inside a cone ``D = I``; in its polar cone 0; on its surface, with
    ``th = x_t / |x_t|`` and ``c = 1 / (1 + mu^2)``: ``[[c, mu c th^T], [mu c th,
    mu^2 c th th^T + (mu a / |x_t|)(I - th th^T)]]``, ``a = c (x_n + mu |x_t|)``; a
    frictionless contact keeps its normal entry only; one told to stick (``mu = inf``) has
    ``I`` where ``x_n > 0``, else 0. (At ``x = 0``, where either derivative is one of the
    generalized Jacobian's, inside: a contact at rest is active.)"""
    nc = normal.shape[0]
    block = np.zeros((nc, 3, 3))
    e_vals = np.zeros((nc, 2))
    for c in range(nc):
        n, ta, tb = normal[c], tangent[c, 0], tangent[c, 1]
        told = math.isinf(mu[c])
        mu_f = 0.0 if told else mu[c]
        ua, ub = u[ta], u[tb]
        norm_ut = math.sqrt(ua * ua + ub * ub)
        x_n = r[n] - rho[n] * (u[n] + mu_f * norm_ut)
        xa = r[ta] - rho[ta] * ua if ta < rho.shape[0] else 0.0
        xb = r[tb] - rho[tb] * ub if tb < rho.shape[0] else 0.0
        if mu_f > 0.0 and norm_ut > 0.0:
            e_vals[c, 0] = mu_f * ua / norm_ut
            e_vals[c, 1] = mu_f * ub / norm_ut
        if told:
            if x_n > 0.0:
                for i in range(3):
                    block[c, i, i] = 1.0
            continue
        nt = math.sqrt(xa * xa + xb * xb)
        inside = nt <= mu_f * x_n and x_n >= 0.0
        polar = (not inside) and mu_f * nt <= -x_n
        if inside:
            for i in range(3):
                block[c, i, i] = 1.0
        elif not polar:
            th_a = xa / nt if nt > 0.0 else 0.0
            th_b = xb / nt if nt > 0.0 else 0.0
            cc = 1.0 / (1.0 + mu_f * mu_f)
            a = (x_n + mu_f * nt) * cc
            curv = mu_f * a / nt if nt > 0.0 else 0.0
            th = (th_a, th_b)
            block[c, 0, 0] = cc
            for i in range(2):
                block[c, 0, i + 1] = mu_f * cc * th[i]
                block[c, i + 1, 0] = mu_f * cc * th[i]
                for j in range(2):
                    outer = th[i] * th[j]
                    eye = 1.0 if i == j else 0.0
                    block[c, i + 1, j + 1] = mu_f * mu_f * cc * outer + curv * (eye - outer)
        if mu_f == 0.0:  # frictionless: the normal entry only
            for i in range(3):
                for j in range(3):
                    if i > 0 or j > 0:
                        block[c, i, j] = 0.0
    return block, e_vals


@_jit
def dense_jacobian(block: np.ndarray, e_vals: np.ndarray, rho: np.ndarray,
                    normal: np.ndarray, tangent: np.ndarray, held: np.ndarray, g: np.ndarray
                    ) -> np.ndarray:  # fmt: skip
    """``J = I - D + D diag(rho) (I + E) G`` from :func:`jacobian_blocks`' ``D`` and ``E`` (dense):
    a contact's row ``i`` is ``e_i - D_i + sum_j D_ij rho_j ((I + E) G)_j`` over its own rows
    ``j``, with ``((I + E) G)_n = G_n + E_n,t G_t`` on its normal row; a held row's is
    ``rho_h G_h``; every other row (a frictionless contact's tangents) ``e_i``."""
    m = g.shape[0]
    jac = np.zeros((m, m))
    for i in range(m):
        jac[i, i] = 1.0
    g_hat = np.empty(m)
    for c in range(normal.shape[0]):
        rows = (normal[c], tangent[c, 0], tangent[c, 1])
        n = rows[0]
        for col in range(m):
            g_hat[col] = g[n, col]
        for k in range(2):
            t = rows[k + 1]
            if t < m and e_vals[c, k] != 0.0:
                for col in range(m):
                    g_hat[col] += e_vals[c, k] * g[t, col]
        for a in range(3):
            i = rows[a]
            if i >= m:
                continue
            for b in range(3):
                j = rows[b]
                d = block[c, a, b]
                if j >= m or d == 0.0:
                    continue
                jac[i, j] -= d
                coef = d * rho[j]
                if b == 0:
                    for col in range(m):
                        jac[i, col] += coef * g_hat[col]
                else:
                    for col in range(m):
                        jac[i, col] += coef * g[j, col]
    for k in range(held.shape[0]):
        h = held[k]
        for col in range(m):
            jac[h, col] = rho[h] * g[h, col]
    return jac


@_jit
def general_square(a: np.ndarray) -> bool:
    """Whether ``scipy.linalg.solve``, left to detect the structure of the square ``a``, takes
    it as general (LU): entries off the diagonal on both sides (not diagonal, not triangular),
    beyond the first sub- and superdiagonals where ``n > 3`` (not tridiagonal), and ``a`` not
    symmetric (which it tries by Cholesky). Exact zeros and exact equality, as it tests them.
    """
    n = a.shape[0]
    lower = 0
    upper = 0
    for i in range(n):
        for j in range(n):
            if a[i, j] != 0.0:
                if i - j > lower:
                    lower = i - j
                if j - i > upper:
                    upper = j - i
    if lower == 0 or upper == 0 or (n > 3 and lower == 1 and upper == 1):
        return False
    for i in range(n):
        for j in range(i + 1, n):
            if a[i, j] != a[j, i]:
                return True
    return False


@_jit
def admm_rhs(u: np.ndarray, q: np.ndarray, z: np.ndarray, y: np.ndarray, penalty: np.ndarray,
              normal: np.ndarray, tangent: np.ndarray, mu: np.ndarray) -> np.ndarray:  # fmt: skip
    """ADMM's right-hand side ``-(q + s) + R (z - y)``, ``s`` De Saxce's shift
    ``mu |u_t|`` on each contact's normal row (zero for one told to stick), compiled."""
    m = u.shape[0]
    s = np.zeros(m)
    for c in range(normal.shape[0]):
        mu_c = 0.0 if math.isinf(mu[c]) else mu[c]
        ta, tb = tangent[c, 0], tangent[c, 1]
        ua = u[ta] if ta < m else 0.0
        ub = u[tb] if tb < m else 0.0
        s[normal[c]] = mu_c * math.sqrt(ua * ua + ub * ub)
    b = np.empty(m)
    for i in range(m):
        b[i] = -(q[i] + s[i]) + penalty[i] * (z[i] - y[i])
    return b


@_jit
def admm_update(lam: np.ndarray, y: np.ndarray, normal: np.ndarray, tangent: np.ndarray,
                 mu: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:  # fmt: skip
    """ADMM's projection and dual step: ``z = proj_K(lam + y)``, ``y + lam - z``, and
    whether ``z`` is finite; compiled."""
    m = lam.shape[0]
    v = np.empty(m + 1)
    for i in range(m):
        v[i] = lam[i] + y[i]
    v[m] = 0.0
    out = np.empty(m + 1)
    project_rows(v, normal, tangent, mu, out)
    z = out[:m].copy()
    y_new = np.empty(m)
    finite = True
    for i in range(m):
        y_new[i] = y[i] + lam[i] - z[i]
        if not math.isfinite(z[i]):
            finite = False
    return z, y_new, finite

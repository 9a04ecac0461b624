"""The iterative solver's compiled loops (carnot.solvers.kernels) against the NumPy route.

Second routes: the cone projection and the natural map against carnot.solvers.problem's NumPy
functions, to the last bit, on random problems mixing every kind of contact (3D Coulomb,
planar, frictionless with and without tangent rows, told to stick, held rows), at points
inside, outside and on the cones; the generalized Jacobian against central differences of the
natural map at random points (where it is differentiable: away from the cones' surfaces, with
probability one); ADMM's step against its formula written here in NumPy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

from carnot.solvers import kernels
from carnot.solvers.iterative import _jacobian
from carnot.solvers.problem import ContactProblem, natural_map, onto_cones, project_cones


def mixed_problem(seed: int, sparse: bool = False) -> ContactProblem:
    """A random problem of every contact kind: its rows shuffled, ``G = A A^T`` (singular
    where ``A`` has fewer columns than rows: redundant contacts)."""
    rng = np.random.default_rng(seed)
    kinds = rng.choice(["spatial", "planar", "bare", "frictionless", "stick"], size=8)
    sizes = {"spatial": 3, "planar": 2, "bare": 1, "frictionless": 3, "stick": 3}
    held = int(rng.integers(0, 3))
    m = sum(sizes[k] for k in kinds) + held
    order = rng.permutation(m)
    normal, tangent, mu = [], [], []
    at = 0
    for kind in kinds:
        rows = [int(order[at + i]) for i in range(sizes[kind])]
        at += sizes[kind]
        normal.append(rows[0])
        tangent.append((rows[1:] + [m, m])[:2])
        mu.append({"spatial": rng.uniform(0.1, 1.5), "planar": rng.uniform(0.1, 1.5),
                   "bare": 0.0, "frictionless": 0.0, "stick": math.inf}[kind])  # fmt: skip
    a = rng.normal(size=(m, int(rng.integers(m // 2, m + 1))))
    g = a @ a.T + 0.1 * np.eye(m) * rng.integers(0, 2)
    return ContactProblem(
        delassus=sp.csr_matrix(g) if sparse else g, q=rng.normal(size=m),
        normal=np.array(normal, dtype=np.intp), tangent=np.array(tangent, dtype=np.intp),
        mu=np.array(mu), held=np.array([int(i) for i in order[at:]], dtype=np.intp),
    )  # fmt: skip


def points(problem: ContactProblem, seed: int) -> list[np.ndarray]:
    """Random row vectors, their projections (on the cones: the surfaces' kinks) and zero."""
    rng = np.random.default_rng(seed)
    v = [rng.normal(size=problem.size) * s for s in (1e-3, 1.0, 1e3)]
    return v + [onto_cones(problem, x) for x in v] + [np.zeros(problem.size)]


@pytest.mark.parametrize("seed", range(12))
def test_projection_and_natural_map_are_numpys_to_the_bit(seed: int) -> None:
    p = mixed_problem(seed)
    rng = np.random.default_rng(100 + seed)
    for r in points(p, seed):
        assert np.array_equal(kernels.onto_cones(p, r), onto_cones(p, r))
        rho = rng.uniform(0.1, 10.0, size=p.size)
        f, u = kernels.natural_map(p, r, rho)
        f_np, u_np = natural_map(p, r, rho)
        assert np.array_equal(u, u_np)
        assert np.array_equal(f, f_np)
    # project_cones (the NumPy route on split arrays) against the compiled rows, the told to
    # stick and frictionless contacts' special cases included
    x_n = np.array([-1.0, 0.0, 2.0, 0.5, -0.25, 3.0])
    x_t = np.array([[0.5, 0.0], [0.0, 0.0], [3.0, 4.0], [0.1, 0.0], [1.0, 1.0], [0.0, 2.0]])
    mu = np.array([0.5, 0.3, 1.0, math.inf, math.inf, 0.0])
    p_n, p_t = project_cones(x_n, x_t, mu)
    rows = np.zeros(19)
    rows[0:18:3], rows[1:18:3], rows[2:18:3] = x_n, x_t[:, 0], x_t[:, 1]
    out = np.empty(19)
    normal = np.arange(0, 18, 3, dtype=np.intp)
    kernels.project_rows(rows, normal, np.stack([normal + 1, normal + 2], axis=1), mu, out)
    assert np.array_equal(out[0:18:3], p_n)
    assert np.array_equal(out[1:18:3], p_t[:, 0]) and np.array_equal(out[2:18:3], p_t[:, 1])


@pytest.mark.parametrize("sparse", [False, True])
@pytest.mark.parametrize("seed", range(8))
def test_newton_jacobian_is_the_natural_maps_derivative(seed: int, sparse: bool) -> None:
    p = mixed_problem(seed, sparse)
    rng = np.random.default_rng(200 + seed)
    rho = rng.uniform(0.2, 2.0, size=p.size)
    h = 1e-6
    for r in (rng.normal(size=p.size) for _ in range(3)):
        u = p.velocities(r)
        jac = _jacobian(p, r, u, rho)
        jac = jac.toarray() if sp.issparse(jac) else jac
        for d in (rng.normal(size=p.size) for _ in range(3)):
            forward = natural_map(p, r + h * d, rho)[0]
            backward = natural_map(p, r - h * d, rho)[0]
            central = (forward - backward) / (2 * h)
            scale = max(float(np.abs(central).max()), 1.0)
            assert float(np.abs(jac @ d - central).max()) <= 1e-6 * scale


@pytest.mark.parametrize("seed", range(6))
def test_admm_step_is_its_formula(seed: int) -> None:
    p = mixed_problem(seed)
    rng = np.random.default_rng(300 + seed)
    z, y, lam = (rng.normal(size=p.size) for _ in range(3))
    penalty = rng.uniform(0.1, 5.0, size=p.size)
    u = p.velocities(z)
    ext = np.append(u, 0.0)
    mu_f = np.where(np.isinf(p.mu), 0.0, p.mu)
    s = np.zeros(p.size)
    s[p.normal] = mu_f * np.sqrt((ext[p.tangent] ** 2).sum(axis=1))
    expected = -(p.q + s) + penalty * (z - y)
    assert np.allclose(kernels.admm_rhs(u, p.q, z, y, penalty, p.normal, p.tangent, p.mu),
                       expected, rtol=1e-15, atol=1e-15)  # fmt: skip
    z_new, y_new, finite = kernels.admm_update(lam, y, p.normal, p.tangent, p.mu)
    assert np.array_equal(z_new, onto_cones(p, lam + y))
    assert np.array_equal(y_new, y + lam - z_new) and finite
    lam[p.normal[0]] = math.inf  # (an unbounded normal impulse: diverging)
    z_new, _, finite = kernels.admm_update(lam, y, p.normal, p.tangent, p.mu)
    assert not finite and not np.isfinite(z_new).all()


@pytest.mark.parametrize("seed", range(8))
def test_line_search_is_the_numpy_loop(seed: int) -> None:
    p = mixed_problem(seed)
    rng = np.random.default_rng(400 + seed)
    rho = rng.uniform(0.2, 2.0, size=p.size)
    for r, d in ((rng.normal(size=p.size), rng.normal(size=p.size)) for _ in range(4)):
        f, _ = natural_map(p, r, rho)
        norm_f = math.sqrt(float(f.dot(f)))
        alpha = 1.0
        while True:  # Armijo's backtracking, written here in NumPy
            trial = r + alpha * d
            f_t, u_t = natural_map(p, trial, rho)
            norm_t = float(np.linalg.norm(f_t))
            if norm_t <= (1.0 - 1e-4 * alpha) * norm_f or alpha < 1e-10:
                break
            alpha *= 0.5
        got = kernels.line_search(r, d, p.delassus, p.q, rho, p.normal, p.tangent, p.mu, norm_f)
        assert got[0] == alpha and got[4] == norm_t
        for a, b in zip(got[1:4], (trial, f_t, u_t), strict=True):
            assert np.array_equal(a, b)


def _scipy_step(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray | None:
    """The Newton step as scipy.linalg.solve gives it (None where it raises or warns)."""
    import warnings

    import scipy.linalg as sla

    with warnings.catch_warnings():
        warnings.simplefilter("error", sla.LinAlgWarning)
        try:
            return sla.solve(jac, rhs, check_finite=False)
        except (sla.LinAlgError, sla.LinAlgWarning):
            return None


def test_general_square_is_scipys_structure_detection() -> None:
    """Diagonal, triangular, tridiagonal (n > 3) and symmetric matrices are not general (scipy
    solves them otherwise); a tridiagonal 3 x 3 is; one entry beyond the band makes a matrix
    general, one entry's asymmetry too."""
    rng = np.random.default_rng(5)
    a = rng.normal(size=(6, 6))
    tri = np.triu(np.tril(a, 1), -1)
    sym = a + a.T
    assert kernels.general_square(a)
    for structured in (np.diag(np.diag(a)), np.triu(a), np.tril(a), tri, sym, np.eye(6)):
        assert not kernels.general_square(structured)
    assert kernels.general_square(np.triu(np.tril(a[:3, :3], 1), -1))
    beyond = tri.copy()
    beyond[5, 0] = 1.0
    asym = sym.copy()
    asym[2, 4] = np.nextafter(asym[2, 4], np.inf)
    assert kernels.general_square(beyond) and kernels.general_square(asym)


@pytest.mark.parametrize("seed", range(8))
def test_newton_steps_are_scipys_to_the_bit(seed: int) -> None:
    """The LU step and the minimum-norm step against scipy.linalg.solve and lstsq (gelsy,
    cutoff m eps) on the Newton Jacobians of random problems (singular ``G`` among them: rank
    deficient ``J``), a singular and an ill-conditioned ``J`` (both refused, as scipy raises
    and warns): the same numbers to the last bit."""
    import scipy.linalg as sla

    from carnot.solvers.iterative import _lu_step, _min_norm_step

    p = mixed_problem(seed)
    rng = np.random.default_rng(seed)
    rho = 1.0 / np.maximum(np.diag(p.delassus), 1e-3)
    general = 0
    for r in points(p, seed):
        f, u = kernels.natural_map(p, r, rho)
        jac = _jacobian(p, r, u, rho)
        rhs = -f if np.any(f) else rng.normal(size=p.size)
        if kernels.general_square(jac):
            general += 1
            ours, theirs = _lu_step(jac, rhs), _scipy_step(jac, rhs)
            assert (ours is None) == (theirs is None)
            if ours is not None:
                assert ours.tobytes() == theirs.tobytes()
        m = p.size
        reference = sla.lstsq(jac, rhs, cond=m * np.finfo(float).eps, check_finite=False,
                              lapack_driver="gelsy")[0]  # fmt: skip
        assert _min_norm_step(jac, rhs).tobytes() == reference.tobytes()
    assert general >= 3
    singular = rng.normal(size=(7, 7))
    singular[3] = singular[1]  # getrf: an exact zero pivot
    ill = sla.hilbert(13)[::-1].copy()  # rows reversed (not symmetric): rcond about 1e-18
    for bad in (singular, ill):
        assert kernels.general_square(bad)
        ones = np.ones(bad.shape[0])
        assert _lu_step(bad, ones) is None and _scipy_step(bad, ones) is None

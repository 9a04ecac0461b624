"""The range of E_d over a regime's family of answers of any dimension
(:func:`carnot.laws.multiple.simultaneous.dissipated_bounds`,
:mod:`carnot.laws.multiple.energy_range`), each against a second route computed apart:
closed forms by Lagrange multipliers, dense sampling of the family, SciPy's
``HalfspaceIntersection`` for the vertices, and the 1-D function where ``d = 1``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import null_space
from scipy.optimize import linprog
from scipy.spatial import HalfspaceIntersection

from carnot.laws.multiple.energy_range import energy, energy_range
from carnot.laws.multiple.simultaneous import dissipated_bounds, dissipated_range


def _simplex(g_diag: list[float]) -> tuple:
    """``m`` rows, ``Lambda >= 0`` with ``sum Lambda = 1`` fixed (the regime's equation), ``G
    = diag(g)``, ``w' = -1`` each: a family of dimension ``m - 1``."""
    m = len(g_diag)
    return (np.diag(g_diag), -np.ones(m), np.eye(m), np.ones(m) / m,
            null_space(np.ones((1, m))), np.eye(m), np.zeros(m), [])  # fmt: skip


@pytest.mark.parametrize("g_diag", [[1.0, 1.0, 1.0], [1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0],
                                    [0.5, 1.5, 2.0, 2.5, 4.0]])  # fmt: skip
def test_simplex_closed_form(g_diag: list[float]) -> None:
    """``E_d = -Lambda . w' - 1/2 Lambda . G Lambda = 1 - 1/2 sum g_i Lambda_i^2`` over the
    simplex ``Lambda >= 0, sum Lambda = 1``. The most (concave: one stationary point) by a
    Lagrange multiplier: ``g_i Lambda_i = nu``, so ``Lambda_i = (1/g_i) / sum 1/g_j`` (inside
    the simplex) and ``E_d = 1 - 1/(2 sum 1/g_j)``; the least at a vertex ``Lambda = e_i``
    (a concave function's minimum over a polytope), ``1 - max g / 2``. Exact: the polytope's
    vertices are enumerated, and the most's bound meets it."""
    args = _simplex(g_diag)
    found = dissipated_bounds(*args)
    assert found is not None and found.exact
    assert found.most == pytest.approx(1.0 - 0.5 / sum(1.0 / v for v in g_diag), abs=1e-12)
    assert found.least == pytest.approx(1.0 - max(g_diag) / 2.0, abs=1e-12)
    assert found.most_bound - found.most <= 1e-12
    assert dissipated_range(*args) == (found.least, found.most)


def test_rank_deficient_delassus() -> None:
    """``G = J M^-1 J^T`` with ``J`` of rank 2 on 4 rows (a planar body struck at four
    redundant points), the simplex family of dimension 3: ``E_d = 1 - 1/2 Lambda . G
    Lambda``. The most is where ``J^T Lambda`` is least in ``M^-1``'s norm over the simplex;
    found apart from the code by SciPy's trust-constr, and the least at a vertex,
    ``1 - max G_ii / 2``."""
    jac = np.array([[1.0, 0.0], [1.0, 1.0], [1.0, -1.0], [1.0, 2.0]])
    g = jac @ np.diag([1.0, 0.5]) @ jac.T
    m = 4
    args = (g, -np.ones(m), np.eye(m), np.ones(m) / m, null_space(np.ones((1, m))), np.eye(m),
            np.zeros(m), [])  # fmt: skip
    found = dissipated_bounds(*args)
    assert found is not None and found.exact
    assert found.least == pytest.approx(1.0 - float(np.diag(g).max()) / 2.0, abs=1e-12)
    from scipy.optimize import LinearConstraint, minimize

    res = minimize(lambda lam: 0.5 * lam @ g @ lam - lam.sum(), np.ones(m) / m,
                   jac=lambda lam: g @ lam - 1.0, hess=lambda lam: g, method="trust-constr",
                   constraints=[LinearConstraint(np.ones((1, m)), 1.0, 1.0),
                                LinearConstraint(np.eye(m), 0.0, np.inf)],
                   options={"gtol": 1e-12, "xtol": 1e-14})  # fmt: skip
    assert found.most == pytest.approx(-res.fun, abs=1e-8)
    assert found.most >= -res.fun - 1e-12  # ours at least as high: the certified one


def _disc(mu: float, a: float) -> tuple:
    """One 3D contact whose normal impulse is fixed (``p_n = 1``) and whose tangential impulse
    is free in the cone ``|p_t| <= mu p_n`` (a family of dimension 2, a disc), ``G = I``,
    ``w' = (-1, a, 0)``."""
    return (np.eye(3), np.array([-1.0, a, 0.0]), np.eye(3), np.array([1.0, 0.0, 0.0]),
            np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.zeros((0, 3)), np.zeros(0),
            [(0, (1, 2), mu)])  # fmt: skip


def test_cone_closed_form() -> None:
    """The disc (:func:`_disc`): ``E_d = 1/2 - a p_t1 - |p_t|^2 / 2``. The most at ``p_t =
    (-a, 0)`` (``|a| < mu``): ``1/2 + a^2/2``; the least on the circle at ``p_t = (mu sign a,
    0)``: ``1/2 - |a| mu - mu^2 / 2``. The cutting planes close the least's bracket to
    round-off: the range is known."""
    mu, a = 0.5, 0.3
    found = dissipated_bounds(*_disc(mu, a))
    assert found is not None
    least = 0.5 - a * mu - mu * mu / 2.0
    assert found.least_bound <= least + 1e-12 and least <= found.least + 1e-12  # tol: 1e-10
    assert found.least - found.least_bound <= 1e-10 and found.exact  # the vertices: to tol
    assert found.least == pytest.approx(least, abs=1e-10)
    assert found.most == pytest.approx(0.5 + a * a / 2.0, abs=1e-12)
    assert found.most_bound - found.most <= 1e-12
    assert dissipated_range(*_disc(mu, a)) == (found.least, found.most)


def test_cone_bracket_without_cuts(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without cutting planes the least is only bracketed (the circumscribed 16-gon's least
    vertex below, a member's value above): reported as such, not as the range, which stays
    unknown (None)."""
    from carnot.laws.multiple import energy_range as module

    monkeypatch.setattr(module, "MAX_CUTS", 0)
    mu, a = 0.5, 0.3
    found = dissipated_bounds(*_disc(mu, a))
    assert found is not None and not found.exact
    least = 0.5 - a * mu - mu * mu / 2.0
    assert found.least_bound < least - 1e-6  # the polygon's corner lies outside the disc
    assert least - 1e-12 <= found.least <= least + 1e-10  # attained: refined on the circle
    assert dissipated_range(*_disc(mu, a)) is None


def _random_problem(rng: np.random.Generator, d: int, n_cones: int) -> tuple:
    """A random family in ``z``: ``E = e0 + e1 . z + z . E2 z`` with ``E2 = -1/2 L^T G L``
    (``G = J J^T``, rank-deficient), a polytope with ``z = 0`` inside (random rows, ``c > 0``,
    and the box ``|z_i| <= 2``)
    and cones ``mu (a_n + b_n . z) >= |a_t + B_t z|`` with ``z = 0`` inside."""
    rows = d + 3
    jac = rng.normal(size=(rows, rows - 1))
    lam1 = rng.normal(size=(rows, d))
    e2 = -0.5 * lam1.T @ jac @ jac.T @ lam1
    e1 = rng.normal(size=d)
    a = np.vstack([rng.normal(size=(2 * d + 2, d)), np.eye(d), -np.eye(d)])
    c = np.concatenate([rng.uniform(0.5, 1.5, size=2 * d + 2), np.full(2 * d, 2.0)])
    cones = []
    for _ in range(n_cones):
        mu = float(rng.uniform(0.3, 1.0))
        a_t = rng.normal(size=2) * 0.3 * mu
        cones.append((1.0, rng.normal(size=d) * 0.5, a_t, rng.normal(size=(2, d)), mu))
    return 0.3, e1, e2, a, c, cones


def _samples(args: tuple, per_axis: int) -> tuple[np.ndarray, np.ndarray, float]:
    """A grid over the box of the linear rows (HiGHS), its feasible points (rejection: the
    rows and the cones evaluated directly) and their ``E``; the grid's spacing."""
    e0, e1, e2, a, c, cones = args
    d = len(e1)
    lo, hi = np.empty(d), np.empty(d)
    for i in range(d):
        for sign, out in ((1.0, lo), (-1.0, hi)):
            cost = np.zeros(d)
            cost[i] = sign
            res = linprog(cost, A_ub=-a, b_ub=c, bounds=[(None, None)] * d, method="highs")
            out[i] = res.x[i]
    axes = [np.linspace(lo[i], hi[i], per_axis) for i in range(d)]
    z = np.array(np.meshgrid(*axes, indexing="ij")).reshape(d, -1).T
    ok = np.all(z @ a.T + c >= 0.0, axis=1)
    for a_n, b_n, a_t, b_t, mu in cones:
        ok &= mu * (a_n + z @ b_n) >= np.linalg.norm(a_t + z @ b_t.T, axis=1)
    z = z[ok]
    return z, e0 + z @ e1 + np.einsum("ni,ij,nj->n", z, e2, z), float((hi - lo).max()) / (
        per_axis - 1)


@pytest.mark.parametrize(("seed", "d", "n_cones"), [(0, 2, 0), (1, 2, 0), (2, 3, 0), (3, 2, 1),
                                                    (4, 2, 2), (5, 3, 1)])  # fmt: skip
def test_against_sampling(seed: int, d: int, n_cones: int) -> None:
    """Dense sampling of the family on a grid (rejection): every sampled member's ``E`` lies
    in ``[least_bound, most_bound]``, and the sampled extremes come within the grid's
    resolution (``|grad E| h sqrt(d)``) of the attained ones."""
    rng = np.random.default_rng(seed)
    args = _random_problem(rng, d, n_cones)
    found = energy_range(*args)
    assert found is not None
    assert (found.exact if not n_cones else True)
    z, values, step = _samples(args, 301 if d == 2 else 61)
    assert len(values) > 100
    scale = max(1.0, float(np.abs(values).max()))
    assert values.min() >= found.least_bound - 1e-12 * scale
    assert values.max() <= found.most_bound + 1e-12 * scale
    slope = float(np.abs(args[1]).sum() + 2.0 * np.abs(args[2]).sum() * np.abs(z).max())
    reach = 3.0 * slope * step * math.sqrt(d)
    assert values.max() >= found.most - reach
    assert values.min() <= found.least + reach
    assert found.least <= values.min() + 1e-9 * scale  # attained: as low as the grid
    assert found.most >= values.max() - 1e-9 * scale


@pytest.mark.parametrize(("seed", "d"), [(10, 2), (11, 3), (12, 3), (13, 4)])
def test_vertices_against_halfspace_intersection(seed: int, d: int) -> None:
    """A polytope's least ``E`` equals the least over its vertices as Qhull finds them
    (``scipy.spatial.HalfspaceIntersection``, ``A z + c >= 0`` as ``-A z - c <= 0``, the
    interior point ``z = 0``)."""
    rng = np.random.default_rng(seed)
    e0, e1, e2, a, c, _ = _random_problem(rng, d, 0)
    found = energy_range(e0, e1, e2, a, c, [])
    assert found is not None and found.exact
    verts = HalfspaceIntersection(np.column_stack([-a, -c]), np.zeros(d)).intersections
    assert found.least == pytest.approx(float(energy(e0, e1, e2, verts).min()), abs=1e-10)
    assert np.all(found.points[0] @ a.T + c >= -1e-9)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("with_cone", [False, True])
def test_one_dimension_reproduces_the_line(seed: int, with_cone: bool) -> None:
    """Where the family has one dimension, :func:`dissipated_range` is the line's closed form
    (ends and the vertex of ``E_d(t)``); the general routine on the same data agrees with it:
    exactly (to round-off) on a segment, and brackets it with a cone (attained to 1e-9)."""
    rng = np.random.default_rng(100 + seed)
    m = 3
    jac = rng.normal(size=(m, m))
    g = jac @ jac.T
    w = rng.normal(size=m)
    null = rng.normal(size=(m, 1))
    null /= np.linalg.norm(null)
    x = np.array([1.0, 0.1, -0.1])
    lin_a = np.vstack([np.eye(m), -np.eye(m)])
    lin_c = np.array([0.0, 1.0, 1.0, 3.0, 1.0, 1.0])
    cones = [(0, (1, 2), 0.6)] if with_cone else []
    line = dissipated_range(g, w, np.eye(m), x, null, lin_a, lin_c, cones)
    general = dissipated_bounds(g, w, np.eye(m), x, null, lin_a, lin_c, cones)
    assert line is not None and general is not None
    scale = max(1.0, abs(line[0]), abs(line[1]))
    assert general.most == pytest.approx(line[1], abs=1e-9 * scale)
    if with_cone:
        assert general.least_bound <= line[0] + 1e-12 * scale
        assert general.least == pytest.approx(line[0], abs=1e-9 * scale)
    else:
        assert general.exact
        assert general.least == pytest.approx(line[0], abs=1e-12 * scale)


def test_unbounded_or_turning() -> None:
    """An unbounded family, and one along which a 3D slip direction turns, give None."""
    g = np.eye(3)
    null = np.eye(3)[:, :2]
    assert dissipated_bounds(g, -np.ones(3), np.eye(3), np.zeros(3), null, np.eye(3)[:1],
                             np.zeros(1), []) is None  # fmt: skip
    slips = [((1, 2), np.array([1.0, 0.0]))]  # G L1 moves w_t across the direction
    assert dissipated_bounds(g, -np.ones(3), np.eye(3), np.zeros(3), np.eye(3)[:, 1:],
                             np.vstack([np.eye(3), -np.eye(3)]), np.ones(6), [],
                             slips) is None  # fmt: skip


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), d=st.integers(2, 3), n_cones=st.integers(0, 2))
def test_sampled_members_inside_the_range(seed: int, d: int, n_cones: int) -> None:
    """Property: every sampled member of a random family (random points of the box, kept
    where they meet every inequality) has its ``E`` inside ``[least_bound, most_bound]``, and
    the attained values are members' values (inside the bounds)."""
    rng = np.random.default_rng(seed)
    args = _random_problem(rng, d, n_cones)
    found = energy_range(*args)
    assert found is not None
    e0, e1, e2, a, c, cones = args
    z, values, _ = _samples(args, 41 if d == 2 else 15)
    z_rand = rng.uniform(z.min(axis=0), z.max(axis=0), size=(2000, d)) if len(z) else z
    ok = np.all(z_rand @ a.T + c >= 0.0, axis=1)
    for a_n, b_n, a_t, b_t, mu in cones:
        ok &= mu * (a_n + z_rand @ b_n) >= np.linalg.norm(a_t + z_rand @ b_t.T, axis=1)
    values = np.concatenate([values, energy(e0, e1, e2, z_rand[ok])])
    scale = max(1.0, float(np.abs(values).max(initial=0.0)))
    assert np.all(values >= found.least_bound - 1e-10 * scale)
    assert np.all(values <= found.most_bound + 1e-10 * scale)
    assert found.least_bound <= found.least <= found.most <= found.most_bound
    for point in found.points:
        assert np.all(point @ a.T + c >= -1e-8 * scale)


def test_certificate_brackets_combine_and_print() -> None:
    """The certificate's ``dissipated_bounds`` (a range bracketed, not known): groups add up
    end by end (their answers combine freely), a group whose range is known counts as exact
    brackets, and the JSON prints the key only where the range is bracketed."""
    from carnot.io.results import _certificate
    from carnot.several import combined_certificate
    from carnot.solvers.options import Certificate

    known = Certificate(solver="enumerate", requested="auto", residual=0.0, iterations=1,
                        unique=False, velocities_unique=False, dissipated_range=(1.0, 2.0))
    bracketed = Certificate(solver="enumerate", requested="auto", residual=0.0, iterations=1,
                            unique=False, velocities_unique=False,
                            dissipated_bounds=((0.4, 0.5), (0.9, 0.95)))  # fmt: skip
    both = combined_certificate([known, bracketed])
    assert both is not None and both.dissipated_range is None
    assert both.dissipated_bounds == ((1.4, 1.5), (2.9, 2.95))
    assert combined_certificate([known, known]).dissipated_bounds is None  # type: ignore[union-attr]
    assert "dissipated_bounds" not in _certificate(known, ())
    assert _certificate(bracketed, ())["dissipated_bounds"] == [[0.4, 0.5], [0.9, 0.95]]

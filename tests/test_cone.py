"""Coulomb's cone written once (carnot.laws.cone): the projection against its definition, the
residual against the law's conditions, and every route that runs them (the law's Python, the
multi-contact batch kernel's leaf, the iterative solver's compiled loop, the certificate's
NumPy) on the same numbers.

The projection is checked apart from its formula by Moreau's decomposition (Moreau 1962;
Hiriart-Urruty and Lemarechal, *Fundamentals of Convex Analysis*, A.3.2): ``p = proj_K(x)``
exactly when ``p`` is in ``K``, ``x - p`` in the polar cone ``K° = {y: mu |y_t| <= -y_n}``,
and ``p . (x - p) = 0``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carnot.laws.cone import contact_law_residual, project_onto_cone
from carnot.laws.multiple.rows import ContactRows, contact_residual


def _points(seed: int, count: int) -> list[tuple[float, float, float, float]]:
    """``(x_n, x_1, x_2, mu)``: random points and cones, with the edge cases (apex, axis,
    the cone's surface, the polar's surface, one tangent row, mu 0 and infinite)."""
    rng = np.random.default_rng(seed)
    out = [(float(a), float(b), float(c), float(m))
           for a, b, c, m in zip(rng.normal(size=count), rng.normal(size=count),
                                 rng.normal(size=count), rng.uniform(0.0, 2.0, count),
                                 strict=True)]  # fmt: skip
    out += [(0.0, 0.0, 0.0, 0.5), (1.0, 0.0, 0.0, 0.5), (-1.0, 0.0, 0.0, 0.5),
            (2.0, 0.6, 0.8, 0.5), (-1.0, 1.2, 1.6, 0.5), (1.0, 3.0, 0.0, 0.5),
            (1.0, 0.0, 0.0, 0.0), (-1.0, 0.0, 0.0, 0.0), (1.0, 2.0, 0.0, 0.0),
            (2.0, 1.0, -1.0, math.inf), (-2.0, 1.0, -1.0, math.inf), (0.0, 1.0, 1.0, math.inf)]
    return out


def test_the_projection_is_the_nearest_point_of_the_cone() -> None:
    for x_n, x_1, x_2, mu in _points(1, 400):
        p_n, p_1, p_2 = project_onto_cone(x_n, x_1, x_2, mu)
        scale = 1.0 + math.sqrt(x_n * x_n + x_1 * x_1 + x_2 * x_2)
        if math.isinf(mu):  # the half-space p_n >= 0 of a contact told to stick
            assert p_n >= 0.0
            assert (p_1, p_2) == ((x_1, x_2) if x_n > 0.0 else (0.0, 0.0))
            continue
        d_n, d_1, d_2 = x_n - p_n, x_1 - p_1, x_2 - p_2
        assert math.hypot(p_1, p_2) <= mu * p_n + 1e-12 * scale  # p in K
        assert mu * math.hypot(d_1, d_2) <= -d_n + 1e-12 * scale  # x - p in the polar cone
        assert abs(p_n * d_n + p_1 * d_1 + p_2 * d_2) <= 1e-12 * scale * scale  # orthogonal


def test_compiled_and_python_give_the_same_bits() -> None:
    numba = pytest.importorskip("numba")
    from carnot.batch.ops import compiled_rules, source_digest
    from carnot.laws import cone

    rules = compiled_rules(cone, ("project_onto_cone", "contact_law_residual"), numba.njit,
                           source_digest([cone]))  # fmt: skip
    project, residual = rules["project_onto_cone"], rules["contact_law_residual"]
    rng = np.random.default_rng(2)
    for x_n, x_1, x_2, mu in _points(3, 300):
        assert project(x_n, x_1, x_2, mu) == project_onto_cone(x_n, x_1, x_2, mu)
        v_n, w_1, w_2, rho = (*rng.normal(size=3).tolist(), float(rng.uniform(0.1, 3.0)))
        for part, frictionless in ((True, False), (True, True), (False, False)):
            args = (part, frictionless, mu, rho, x_n, x_1, x_2, v_n, w_1, w_2)
            assert residual(*args) == contact_law_residual(*args)


@pytest.mark.parametrize(
    ("impulse", "after", "mu", "holds"),
    [
        ((1.0, 0.2, 0.1), (0.0, 0.0, 0.0), 0.5, True),  # stick inside the cone
        ((1.0, -0.3, -0.4), (0.0, 0.6, 0.8), 0.5, True),  # slip against the slip velocity
        ((1.0, 0.3, 0.4), (0.0, 0.6, 0.8), 0.5, False),  # slip pushing the wrong way
        ((0.0, 0.0, 0.0), (0.5, 1.0, 0.0), 0.5, True),  # separating with no impulse
        ((1.0, 0.0, 0.0), (0.5, 0.0, 0.0), 0.5, False),  # loaded while separating
        ((-1.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.5, False),  # pulling
        ((1.0, 0.9, 0.0), (0.0, 0.0, 0.0), 0.5, False),  # sticking outside the cone
        ((1.0, 0.0, 0.0), (-0.1, 0.0, 0.0), 0.5, False),  # still approaching
    ],
)
def test_the_residual_is_zero_exactly_where_the_law_holds(impulse, after, mu, holds) -> None:  # type: ignore[no-untyped-def]
    # e = 0, so v_n = w_n''; rho = 1 / G_nn = 2
    r = contact_law_residual(True, False, mu, 2.0, *impulse, *after)
    assert (r <= 1e-15) == holds
    assert r >= 0.0


def test_the_laws_residual_and_the_batch_kernels_run_the_one_rule() -> None:
    pytest.importorskip("numba")
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(4)
    contacts = (ContactRows(normal=0, tangents=(1, 2), restitution=0.3, friction=0.6),
                ContactRows(normal=3, tangents=(4,), restitution=0.0, friction=0.4),
                ContactRows(normal=5, restitution=0.5))  # fmt: skip
    nrow = np.array([0, 3, 5])
    trow = np.array([[1, 2], [4, -1], [-1, -1]])
    ntan = np.array([2, 1, 0])
    kinds = (mk.SPATIAL, mk.PLANAR, mk.FRICTIONLESS_KIND)
    e = np.array([c.restitution for c in contacts])
    mu = np.array([c.friction for c in contacts])
    for _ in range(200):
        a = rng.normal(size=(6, 6))
        g = a @ a.T + 0.1 * np.eye(6)
        imp, w, wa = rng.normal(size=6), rng.normal(size=6), rng.normal(size=6)
        for c, contact in enumerate(contacts):
            for part in (True, False):
                law = contact_residual(contact, g, imp, w, wa, takes_part=part)
                kernel = mk.contact_residual(c, g, nrow, trow, ntan, kinds[c], e, mu, imp, w, wa,
                                             part)  # fmt: skip
                assert kernel == law


def test_the_solvers_compiled_projection_is_the_certificates_numpy() -> None:
    from carnot.solvers import kernels
    from carnot.solvers.problem import project_cones

    points = _points(5, 300)
    x = np.array([p[:3] for p in points])
    mu = np.array([p[3] for p in points])
    k = len(points)
    v = np.append(x.ravel(), 0.0)
    normal = 3 * np.arange(k)
    tangent = np.column_stack([normal + 1, normal + 2])
    out = np.empty_like(v)
    kernels.project_rows(v, normal, tangent, mu, out)
    p_n, p_t = project_cones(x[:, 0], x[:, 1:], mu)
    assert np.array_equal(out[:-1].reshape(k, 3), np.column_stack([p_n, p_t]))
    assert np.array_equal(out[:-1].reshape(k, 3),
                          np.array([project_onto_cone(*p) for p in points]))  # fmt: skip

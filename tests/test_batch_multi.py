"""Multi-contact batches (issue 14, item 5): carnot.batch.multi_impacts and
contact_space_impacts give solve_impact's answers, row by row.

The reference is :func:`carnot.solve_impact` (the simultaneous law of
:mod:`carnot.laws.multiple`) on the same impacts, each row compared to round-off times
cond(G): velocities always (they are unique where the impulses are not), impulses where they
are unique. Published closed forms as well (sources in tests/test_several.py): the three-ball
chain under the generalized Newton law ``((1 - 2e)/3, (1 + e)/3, (1 + e)/3) v`` (Glocker,
*Set-Valued Force Laws*, 2001, section 7); a ball striking two touching balls at +-30
degrees, ``v_A'' = (2 - 3e)/5 v`` (Glocker 2001); Housner's rocking block landing on its
other corner, ``omega''/omega' = 1 - 3/2 sin^2 alpha`` (Housner, Bull. Seism. Soc. Am. 53,
1963), the old corner separating with no impulse. Every row's theorem equals its direct
kinetic-energy difference to 1e-12 relative.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies
from carnot.batch.multi import (
    MAX_ROWS,
    REGIME_NAMES,
    contact_space_impacts,
    multi_impacts,
)
from carnot.conventions import RELATIVE_TOLERANCE
from carnot.errors import InputError


def _arenas(k: int = 8, m: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """The compiled solvers' scratch arenas (floats, integers) at their largest."""
    from carnot.batch.multi_kernel import arena_size

    size = arena_size(k, m)
    return np.empty(size), np.empty(size, dtype=np.int64)


def _box_inertia(m: float, size: tuple[float, float, float]) -> np.ndarray:
    a, b, c = size
    return m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def _rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _reference(mass, inertia, x, v, om, points, normals, e, mu):  # type: ignore[no-untyped-def]
    """solve_impact on one body against a fixed ground at several points."""
    contacts = [PointContact(a="body", b="ground", point=p, normal=n, restitution=float(ec),
                             friction=float(mc), where=f"contacts[{k}]", name=f"c{k}")
                for k, (p, n, ec, mc)
                in enumerate(zip(points, normals, e, mu, strict=True))]  # fmt: skip
    body = RigidBody(name="body", mass=mass, inertia_com=inertia, position_com=x,
                     velocity_com=v, angular_velocity=om)  # fmt: skip
    problem = ImpactProblem(bodies={"body": body, "ground": FixedBody(name="ground")},
                            contacts=contacts)  # fmt: skip
    return solve_impact(problem)


def _compare(out, i, res, *, impulses: bool) -> None:  # type: ignore[no-untyped-def]
    """Row ``i`` of a batch result against solve_impact's ``res``."""
    body = res.bodies["body"]
    scale = max(1.0, float(np.max(np.abs(body.velocity_after))))
    assert np.allclose(out.velocity_a[i], body.velocity_after, rtol=0, atol=1e-9 * scale)
    assert np.allclose(out.angular_velocity_a[i], body.angular_velocity_after, rtol=0,
                       atol=1e-9 * scale * 10)  # fmt: skip
    assert out.dissipated[i] == pytest.approx(res.energy.dissipated, rel=1e-9, abs=1e-12)
    flags = set(res.flag_codes())
    assert bool(out.statically_indeterminate[i]) == ("statically_indeterminate" in flags)
    assert bool(out.multiple_solutions[i]) == ("multiple_solutions" in flags)
    assert bool(out.no_solution[i]) == ("no_solution" in flags)
    for k, c in enumerate(res.contacts):
        assert REGIME_NAMES[int(out.regime[i, k])] == c.regime
        assert bool(out.active[i, k]) == c.active
        if impulses:
            p_scale = max(1.0, float(np.max(np.abs(out.impulse[i]))))
            assert np.allclose(out.impulse[i, k], c.impulse, rtol=0, atol=1e-9 * p_scale)
    # the two routes of the ledger, every row
    before = float(out.before[i])
    assert out.dissipated_theorem[i] == pytest.approx(out.dissipated[i], rel=1e-12,
                                                      abs=1e-12 * before)  # fmt: skip
    assert np.sum(out.dissipated_by_contact[i]) == pytest.approx(out.dissipated_theorem[i],
                                                                 rel=1e-12, abs=1e-15)  # fmt: skip


def _corner_block(rng: np.random.Generator, count: int, mu: float):  # type: ignore[no-untyped-def]
    """A planar block (2b x 2h) falling on its two bottom corners, at random velocities."""
    m, b, h = 3.0, 0.25, 1.0
    inertia = _box_inertia(m, (2 * b, 2 * h, 0.2))
    x = np.array([0.0, h, 0.0])
    points = np.array([[-b, 0.0, 0.0], [b, 0.0, 0.0]])
    normals = np.array([[0.0, 1.0, 0.0]] * 2)
    v = np.zeros((count, 3))
    v[:, 0] = rng.uniform(-1, 1, count) * (mu > 0)
    v[:, 1] = rng.uniform(-2, -0.1, count)
    om = np.zeros((count, 3))
    om[:, 2] = rng.uniform(-3, 3, count)
    e = rng.uniform(0, 1, (count, 2))
    return m, inertia, x, v, om, points, normals, e, np.full((count, 2), mu)


@pytest.mark.parametrize("mu", [0.0, 0.4])
def test_block_on_two_corners_matches_solve_impact(mu: float) -> None:
    rng = np.random.default_rng(14)
    count = 12
    m, inertia, x, v, om, points, normals, e, mus = _corner_block(rng, count, mu)
    body = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v,
                       angular_velocity=om)  # fmt: skip
    out = multi_impacts(body, None, points, normals, e, mus)
    assert out.impulse.shape == (count, 2, 3)
    for i in range(count):
        res = _reference(m, inertia, x, v[i], om[i], points, normals, e[i], mus[i])
        _compare(out, i, res, impulses=True)
    assert not out.by_reference.any()
    # both regimes of each corner occur in the sample (not a test of one branch)
    assert {0, 1 if mu == 0 else 2}.issubset(set(out.regime.ravel().tolist()))


def _box(rng: np.random.Generator, count: int, mu: float, slide: float, tilt: float = 0.0):  # type: ignore[no-untyped-def]
    """A box (0.4 x 0.3 x 0.2 m, 2 kg) landing on its four bottom corners (tilted by ``tilt``
    about z: a general orientation), sliding at up to ``slide`` m/s, spinning."""
    m, size = 2.0, (0.4, 0.3, 0.2)
    rot = _rotation(tilt)
    inertia = rot @ _box_inertia(m, size) @ rot.T
    a, b, c = (s / 2 for s in size)
    x = np.array([0.1, -0.2, c])
    points = np.array([x + rot @ np.array([sx * a, sy * b, -c])
                       for sx in (1, -1) for sy in (1, -1)])  # fmt: skip
    normals = np.array([[0.0, 0.0, 1.0]] * 4)
    v = np.zeros((count, 3))
    v[:, :2] = rng.uniform(-slide, slide, (count, 2))
    v[:, 2] = rng.uniform(-2.0, -0.2, count)
    om = rng.uniform(-0.5, 0.5, (count, 3)) * np.array([0.2, 0.2, 1.0])
    e = np.repeat(rng.uniform(0, 1, (count, 1)), 4, axis=1)
    return m, inertia, x, v, om, points, normals, e, np.full((count, 4), mu)


@pytest.mark.parametrize(("mu", "slide"), [(0.0, 0.0), (1.5, 0.8), (0.2, 3.0)])
def test_box_landing_on_four_corners_matches_solve_impact(mu: float, slide: float) -> None:
    rng = np.random.default_rng(1401)
    count = 8
    m, inertia, x, v, om, points, normals, e, mus = _box(rng, count, mu, slide, tilt=0.3)
    body = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v,
                       angular_velocity=om)  # fmt: skip
    out = multi_impacts(body, None, points, normals, e, mus)
    for i in range(count):
        res = _reference(m, inertia, x, v[i], om[i], points, normals, e[i], mus[i])
        indeterminate = "statically_indeterminate" in res.flag_codes()
        _compare(out, i, res, impulses=not indeterminate)
    if slide < 1.0:  # closed or sticking on four corners, three equations: never unique
        assert out.statically_indeterminate.all()
        assert not out.multiple_solutions.any()


def test_housner_rocking_block_closed_form() -> None:
    """Housner (1963): rocking about its left corner, landing on the right one with e = 0
    and enough friction to stick, ``omega''/omega' = 1 - 3/2 sin^2 alpha`` (a block of
    uniform density, 2b x 2h, tan alpha = b/h), the left corner separating."""
    m, b, h = 3.0, 0.25, 1.0
    alpha = math.atan2(b, h)
    count = 5
    omega = -np.linspace(0.2, 2.0, count)  # about the left corner (0, 0, 0)
    x = np.array([b, h, 0.0])
    om = np.zeros((count, 3))
    om[:, 2] = omega
    v = np.cross(om, x)  # omega x r_com
    body = BatchBodies(mass=m, inertia_com=_box_inertia(m, (2 * b, 2 * h, 0.2)),
                       position_com=x, velocity_com=v, angular_velocity=om)  # fmt: skip
    points = [[0.0, 0.0, 0.0], [2 * b, 0.0, 0.0]]
    out = multi_impacts(body, None, points, [[0, 1.0, 0]] * 2, 0.0, 2.0)
    ratio = out.angular_velocity_a[:, 2] / omega
    assert ratio == pytest.approx(np.full(count, 1 - 1.5 * math.sin(alpha) ** 2), rel=1e-12)
    assert out.normal_impulse[:, 0] == pytest.approx(np.zeros(count), abs=1e-12)
    assert [REGIME_NAMES[int(r)] for r in out.regime[0]] == ["separate", "stick"]
    assert not out.active[:, 0].any() and out.active[:, 1].all()


def _chain_delassus(masses: list[float]) -> np.ndarray:
    """G of a chain of balls on a line: contact i between balls i and i+1 (w = v_{i+1} -
    v_i), so G_ii = 1/m_i + 1/m_{i+1}, G_i,i+1 = -1/m_{i+1}."""
    k = len(masses) - 1
    g = np.zeros((k, k))
    for i in range(k):
        g[i, i] = 1 / masses[i] + 1 / masses[i + 1]
        if i + 1 < k:
            g[i, i + 1] = g[i + 1, i] = -1 / masses[i + 1]
    return g


def test_three_ball_cradle_closed_form() -> None:
    """Glocker (2001): ``((1 - 2e)/3, (1 + e)/3, (1 + e)/3) v`` for a ball at v into two
    touching ones, by the contact-space entry (impulses ``p1 = (2 + 2e)/3 v m``, ``p2 = (1
    + e)/3 v m``)."""
    e = np.linspace(0.0, 1.0, 11)
    v = 2.0
    out = contact_space_impacts(_chain_delassus([1.0, 1.0, 1.0]), [-v, 0.0], [0, 0],
                                np.stack([e, e], axis=1))  # fmt: skip
    p1, p2 = out.impulses[:, 0], out.impulses[:, 1]
    assert v - p1 == pytest.approx((1 - 2 * e) / 3 * v, abs=1e-12)  # ball A after
    assert p1 - p2 == pytest.approx((1 + e) / 3 * v, abs=1e-12)  # ball B after
    assert p2 == pytest.approx((1 + e) / 3 * v, abs=1e-12)  # ball C after
    energy_before = 0.5 * v * v
    energy_after = 0.5 * ((v - p1) ** 2 + (p1 - p2) ** 2 + p2**2)
    assert out.dissipated == pytest.approx(energy_before - energy_after, rel=1e-12, abs=1e-13)


def test_ball_into_two_touching_balls_closed_form() -> None:
    """Glocker (2001): a ball striking two touching balls (equal masses) symmetrically at
    +-30 degrees: ``v_A'' = (2 - 3e)/5 v``. Contact space: normals at +-30 degrees to the
    line of approach, ``G = [[2, cos 60], [cos 60, 2]] / m``, ``w' = -v cos 30``."""
    e = np.linspace(0.0, 1.0, 6)
    v = 1.5
    c30 = math.cos(math.radians(30))
    g = np.array([[2.0, 0.5], [0.5, 2.0]])
    out = contact_space_impacts(g, [-v * c30, -v * c30], [0, 0], np.stack([e, e], axis=1))
    v_a = v - (out.impulses[:, 0] + out.impulses[:, 1]) * c30
    assert v_a == pytest.approx((2 - 3 * e) / 5 * v, abs=1e-12)


def test_contact_space_matches_reference_law_on_random_problems() -> None:
    """Random small contact spaces (PSD G of every rank, frictionless, planar and 3D Coulomb
    contacts) against the enumeration of carnot.solvers.resolve, the law solve_impact applies
    (every closed contact taking part: a separating one that the others drive in, with
    e = 0)."""
    from carnot.laws.multiple import ContactRows
    from carnot.solvers import SolverOptions, resolve

    rng = np.random.default_rng(7)
    for layout in ([0, 0, 0], [1, 1], [2, 0], [2, 2]):
        m = len(layout) + sum(layout)
        count = 15
        gs, ws = [], []
        for i in range(count):
            rank = m if i % 3 else max(1, m - 2)
            a = rng.normal(size=(m, rank))
            gs.append(a @ a.T)
            ws.append(rng.normal(size=m) - 0.5)
        e = rng.uniform(0, 1, (count, len(layout)))
        mu = rng.uniform(0, 1, (count, len(layout)))
        out = contact_space_impacts(np.array(gs), np.array(ws), layout, e, mu)
        for i in range(count):
            rows, r = [], 0
            for t in layout:
                rows.append((r, tuple(range(r + 1, r + 1 + t))))
                r += 1 + t
            contacts = [ContactRows(normal=n, tangents=ts, restitution=float(e[i, k]),
                                    friction=float(mu[i, k]))
                        for k, (n, ts) in enumerate(rows)]  # fmt: skip
            ref = resolve(gs[i], ws[i], contacts, options=SolverOptions(name="enumerate"))
            scale = max(1.0, float(np.max(np.abs(ws[i]))))
            cond = float(np.linalg.cond(gs[i])) if i % 3 else 1e6
            assert np.allclose(out.w_after[i], ref.w_after, rtol=0,
                               atol=1e-13 * scale * max(cond, 1.0)), (layout, i)  # fmt: skip
            assert bool(out.no_solution[i]) == ("no_solution" in ref.flags)
            assert bool(out.multiple_solutions[i]) == ("multiple_solutions" in ref.flags)
            assert out.residual[i] == pytest.approx(ref.residual, abs=1e-9 * scale)


def test_limits_and_bad_input_name_the_field() -> None:
    with pytest.raises(InputError, match="layout: at most 12 contact rows"):
        contact_space_impacts(np.eye(15), np.zeros(15), [2] * 5, 0.0)
    with pytest.raises(InputError, match="layout: at most 8 contacts"):
        contact_space_impacts(np.eye(9), np.zeros(9), [0] * 9, 0.0)
    with pytest.raises(InputError, match=r"layout\[0\]: must be 0, 1 or 2"):
        contact_space_impacts(np.eye(4), np.zeros(4), [3], 0.0)
    with pytest.raises(InputError, match="restitution: must be in"):
        contact_space_impacts(np.eye(2), [-1.0, 0.0], [0, 0], 1.5)
    with pytest.raises(InputError, match="delassus: must be symmetric"):
        contact_space_impacts([[1.0, 0.5], [0.0, 1.0]], [-1.0, 0.0], [0, 0], 0.0)
    with pytest.raises(InputError, match="delassus: must be finite"):
        contact_space_impacts([[1.0, np.nan], [np.nan, 1.0]], [-1.0, 0.0], [0, 0], 0.0)
    body = BatchBodies(mass=1.0, inertia_com=np.diag([1.0, 1.0, 3.0]), position_com=[0, 0, 1],
                       velocity_com=[0, 0, -1.0])  # fmt: skip
    with pytest.raises(InputError, match="a.inertia_com: must be symmetric positive definite"):
        multi_impacts(body, None, [[0, 0, 0], [1, 0, 0]], [[0, 0, 1]] * 2, 0.5)
    good = BatchBodies(mass=1.0, inertia_com=np.eye(3), position_com=[0, 0, 1],
                       velocity_com=[0, 0, -1.0])  # fmt: skip
    with pytest.raises(InputError, match="normals: must be non-zero"):
        multi_impacts(good, None, [[0, 0, 0], [1, 0, 0]], [[0, 0, 1], [0, 0, 0]], 0.5)
    with pytest.raises(InputError, match="friction: must be"):
        multi_impacts(good, None, [[0, 0, 0], [1, 0, 0]], [[0, 0, 1]] * 2, 0.5, -0.1)
    assert MAX_ROWS == 12
    assert RELATIVE_TOLERANCE == 1e-9  # the kernel's copy of it (carnot.batch.multi_kernel)


def test_the_kernels_slip_iteration_constants_are_the_laws() -> None:
    """The kernel runs the law's slip-angle iteration (``simultaneous.newton_broyden``) step
    for step: the same most steps, difference step and same-root distance."""
    from carnot.batch import multi_kernel
    from carnot.laws.multiple import simultaneous

    assert multi_kernel.ROOT_STEPS == simultaneous.ROOT_STEPS
    assert multi_kernel.ROOT_DIFFERENCE == simultaneous.ROOT_DIFFERENCE
    assert multi_kernel.SAME_ROOT == simultaneous.SAME_ROOT


@pytest.mark.parametrize("friction", [0.0, 2.0])
def test_sweep_multi_route_equals_the_solve_impact_loop(friction: float) -> None:
    """``carnot sweep`` on a two-contact scenario (examples/block_on_two_corners.toml, with
    and without friction) takes the multi-contact batch route; its columns equal those of
    the solve_impact loop on the same rows."""
    import dataclasses

    from carnot.io.scenario import read_scenario_data
    from carnot.sweep import make_plan, prepare_sweep

    data = read_scenario_data("examples/block_on_two_corners.toml")
    for contact in data["contacts"]:
        contact["friction"] = friction
    plan = make_plan(vary=["bodies.block.angular_velocity.2=-2:1.5:6",
                           "contacts.1.restitution=0:1:3"])  # fmt: skip
    sweep = prepare_sweep(data, plan, compiled=True)
    assert sweep.route == "multi", sweep.why_solve
    fast = sweep.chunk(0, sweep.rows)
    slow = dataclasses.replace(sweep, route="solve").chunk(0, sweep.rows)
    for col in sweep.columns:
        a, b = fast.columns[col.name], slow.columns[col.name]
        if col.kind == "category":
            names_a = [fast.categories[col.name][int(x)] for x in a]
            names_b = [slow.categories[col.name][int(x)] for x in b]
            assert names_a == names_b, col.name
        elif col.kind == "bool":
            assert np.array_equal(a, b), col.name
        else:
            assert np.allclose(a, b, rtol=1e-9, atol=1e-12, equal_nan=True), col.name


def test_compiled_linear_program_matches_highs() -> None:
    """The kernel's linear program for rank-deficient regimes (a simplex on the dual) against
    SciPy's HiGHS, the reference law's solver, on the same problem: maximize the smallest
    slack ``t`` of ``lin_a (x + N z) + lin_c >= t`` and of each cone's 32-gon facets, ``t <=
    scale``. Random problems of family dimension 1 to 6 with two 3D cones; the optimum (not
    the maximizer: it may not be unique) must agree, or, where the kernel stops early, its
    dual bound must lie above HiGHS's optimum and below -0.1 of the scale."""
    from scipy.optimize import linprog

    from carnot.batch.multi_kernel import _POLYGON, _most_feasible_nd

    rng = np.random.default_rng(1414)
    angles = 2.0 * np.pi * (np.arange(_POLYGON) + 0.5) / _POLYGON
    half = math.cos(math.pi / _POLYGON)
    trow = np.array([[1, 2], [4, 5]])
    solved = stopped = 0
    for trial in range(60):
        q = 6
        nn = 1 + trial % 6
        nlin = int(rng.integers(0, 5))
        lin_a = rng.normal(size=(nlin, q))
        lin_c = rng.normal(size=nlin) * 0.3 + (0.5 if trial % 2 else 0.0)
        gdiag = rng.uniform(0.5, 2.0, q)
        g = np.diag(gdiag)
        mus = rng.uniform(0.1, 1.5, 2)
        cones = np.array([[0.0, 0.0, mus[0]], [3.0, 1.0, mus[1]]])
        b = np.eye(q)
        x = rng.normal(size=q) + np.array([2.0, 0, 0, 2.0, 0, 0])
        null = np.linalg.qr(rng.normal(size=(q, nn)))[0]
        scale = 1.0
        rows = [lin_a] if nlin else []
        consts = [lin_c] if nlin else []
        for n, c, mu in cones:
            t1, t2 = trow[int(c)]
            facets = gdiag[int(n)] * (mu * half * b[int(n)][None, :]
                                      - np.cos(angles)[:, None] * b[t1][None, :]
                                      - np.sin(angles)[:, None] * b[t2][None, :])  # fmt: skip
            rows.append(facets)
            consts.append(np.zeros(_POLYGON))
        a_all, c_all = np.vstack(rows), np.concatenate(consts)
        a_ub = np.hstack([-(a_all @ null), np.ones((len(c_all), 1))])
        cost = np.zeros(nn + 1)
        cost[-1] = -1.0
        res = linprog(cost, A_ub=a_ub, b_ub=a_all @ x + c_all,
                      bounds=[(None, None)] * nn + [(None, scale)], method="highs")  # fmt: skip
        assert res.status == 0
        best = -res.fun
        xk = x.copy()
        ok, margin = _most_feasible_nd(lin_a, lin_c, nlin, cones, 2, b, xk, null, q, nn, g,
                                       trow, scale, *_arenas(), 0)  # fmt: skip
        assert ok
        moved = xk - x
        assert np.allclose(moved, null @ (null.T @ moved), atol=1e-12)  # stays in the family
        if margin < -0.1 * scale and np.min(a_all @ xk + c_all) < best - 1e-9:
            stopped += 1  # stopped early: the bound it returned is above the optimum
            assert best <= margin + 1e-9
            continue
        solved += 1
        t_kernel = min(float(np.min(a_all @ xk + c_all)), scale)
        assert t_kernel == pytest.approx(best, abs=1e-9), trial
    assert solved > 20 and stopped > 0


def test_one_dimensional_linear_program_pruned_search_is_the_full_search() -> None:
    """The kernel's linear program over a one-dimensional family (maximize ``min_r (alpha_r z
    + beta_r)``, capped) searches its candidates (z = 0, the crossings of a rising and a
    falling line or of a line and the cap) from a value the envelope reaches, found by
    bisection: the same candidate as the full search, bit for bit, on random line sets with
    ties, flat optima and the cap reached; and the optimum against SciPy's HiGHS (the
    reference law's solver) on the same program."""
    from scipy.optimize import linprog

    from carnot.batch.multi_kernel import _best_candidate, _envelope_floor

    rng = np.random.default_rng(1415)
    for trial in range(300):
        n = int(rng.integers(1, 70))
        alpha = rng.normal(size=n) * 10.0 ** rng.uniform(-2, 2)
        beta = rng.normal(size=n)
        if trial % 3 == 0:  # ties and parallel lines, as polygon facets give
            alpha = np.round(alpha, 1)
            beta = np.round(beta, 1)
        if trial % 5 == 0:  # all rising: the cap decides
            alpha = np.abs(alpha)
        scale = 1.0 if trial % 4 else 1e-3
        alpha = np.append(alpha, 0.0)
        beta = np.append(beta, scale)
        lines = n + 1
        floor = _envelope_floor(alpha, beta, lines)
        pruned = _best_candidate(alpha, beta, lines, floor - 1e-9 * (scale + abs(floor)))
        full = _best_candidate(alpha, beta, lines, -np.inf)
        assert pruned == full or (np.isnan(pruned) and np.isnan(full)), trial
        res = linprog([0.0, -1.0], A_ub=np.column_stack([-alpha, np.ones(lines)]), b_ub=beta,
                      bounds=[(None, None), (None, None)], method="highs")  # fmt: skip
        if res.status == 0:
            assert float(np.min(alpha * full + beta)) == pytest.approx(-res.fun, abs=1e-9)


def test_compiled_least_norm_solve_matches_the_svd() -> None:
    """The kernel's column-pivoted QR solve (slip regimes) against its SVD solve, the
    reference's least-squares minimum-norm answer: square systems of every rank, consistent
    or not; the same rank, answer and null space (as a projector)."""
    from carnot.batch.multi_kernel import _qr_solve, _svd_solve

    rng = np.random.default_rng(15)
    for _ in range(400):
        q = int(rng.integers(1, 9))
        rank = int(rng.integers(0, q + 1))
        a = rng.normal(size=(q, rank)) @ rng.normal(size=(rank, q)) if rank else np.zeros((q, q))
        a *= 10.0 ** rng.uniform(-3, 3)
        rhs = a @ rng.normal(size=q) if rng.random() < 0.7 else rng.normal(size=q)
        x1, n1, x2, n2 = np.zeros(q), np.zeros((q, q)), np.zeros(q), np.zeros((q, q))
        fa, ia = _arenas()
        k1 = _qr_solve(a, rhs, q, x1, n1, fa, ia, 0)
        k2 = _svd_solve(a, rhs, q, x2, n2, fa, 0)
        if k1 < 0:  # (the QR leaves a rank it cannot tell from the SVD's to the SVD)
            continue
        assert k1 == k2 == q - rank
        assert np.allclose(x1, x2, rtol=0, atol=1e-10 * max(1.0, float(np.max(np.abs(x2)))))
        assert np.allclose(n1[:, :k1] @ n1[:, :k1].T, n2[:, :k2] @ n2[:, :k2].T, atol=1e-9)


def test_svd_in_the_arena_is_numpys_to_the_bit() -> None:
    """The kernel's SVD solve calls LAPACK's ``dgesdd`` on arena arrays (``_svd_into``: a
    leaf cannot allocate) where it called ``np.linalg.svd``: against that call, compiled
    by Numba as the kernel had it, on square matrices of every rank, the same minimum-norm
    answer and null space to the last bit; and a non-finite entry is refused as NumPy
    refuses it."""
    import numba

    from carnot.batch import multi_kernel as mk

    @numba.njit(cache=False)
    def svd_solve_numpy(a, rhs, q, x, null):  # type: ignore[no-untyped-def]
        u, s, vt = np.linalg.svd(np.ascontiguousarray(a[:q, :q]))
        rank = 0
        if s[0] > 0.0:
            for i in range(q):
                if s[i] > mk.RANK * s[0]:
                    rank += 1
        for i in range(q):
            x[i] = 0.0
        for k in range(rank):
            c = 0.0
            for i in range(q):
                c += u[i, k] * rhs[i]
            c /= s[k]
            for i in range(q):
                x[i] += vt[k, i] * c
        for c in range(q - rank):
            for i in range(q):
                null[i, c] = vt[rank + c, i]
        return q - rank

    rng = np.random.default_rng(21)
    fa, _ = _arenas()
    for _ in range(300):
        q = int(rng.integers(1, 13))
        rank = int(rng.integers(0, q + 1))
        a = np.zeros((12, 12))
        if rank:
            a[:q, :q] = rng.normal(size=(q, rank)) @ rng.normal(size=(rank, q))
        rhs = rng.normal(size=q)
        x1, n1, x2, n2 = np.zeros(q), np.zeros((q, q)), np.zeros(q), np.zeros((q, q))
        k1 = mk._svd_solve(a, rhs, q, x1, n1, fa, int(rng.integers(0, 100)))
        k2 = svd_solve_numpy(a, rhs, q, x2, n2)
        assert k1 == k2
        assert np.array_equal(x1, x2) and np.array_equal(n1, n2)
    bad = np.eye(3)
    bad[1, 2] = np.nan
    with pytest.raises(np.linalg.LinAlgError, match="infs or NaNs"):
        mk._svd_solve(bad, np.ones(3), 3, np.zeros(3), np.zeros((3, 3)), fa, 0)


def test_box_landings_need_no_reference_rows() -> None:
    """Sticking and sliding box landings: every row decided by the kernel (rank-deficient
    sticking regimes by its own linear program), equal to the reference law."""
    from carnot.batch.multi_kernel import assemble
    from carnot.laws.multiple import ContactRows, resolve_simultaneous

    rng = np.random.default_rng(1402)
    for mu, slide in ((1.5, 0.8), (0.6, 1.0)):
        count = 150
        m, inertia, x, v, om, points, normals, e, mus = _box(rng, count, mu, slide, tilt=0.2)
        body = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v,
                           angular_velocity=om)  # fmt: skip
        out = multi_impacts(body, None, points, normals, e, mus)
        assert not out.by_reference.any()
        for i in range(0, count, 10):
            g, w, *_ = assemble(m, inertia, x, v[i], om[i], 1.0, np.eye(3), np.zeros(3),
                                np.zeros(3), np.zeros(3), False, points, normals,
                                np.ones(4, dtype=np.int64), 12)  # fmt: skip
            rows = [ContactRows(normal=3 * k, tangents=(3 * k + 1, 3 * k + 2),
                                restitution=float(e[i, k]), friction=mu)
                    for k in range(4)]  # fmt: skip
            ref = resolve_simultaneous(g, w, rows)
            res = _reference(m, inertia, x, v[i], om[i], points, normals, e[i], mus[i])
            _compare(out, i, res, impulses=not ref.flags)


@pytest.mark.parametrize("mu", [0.2, 1.5])
def test_box_landing_flat_without_spin_rebounds_at_minus_e_v(mu: float) -> None:
    """A box landing flat, not sliding nor spinning, with friction: Newton's law at each of
    the four corners gives ``u'' = -e u'`` and no spin (Glocker, *Set-Valued Force Laws*,
    2001, ch. 7; Pfeiffer and Glocker, *Multibody Dynamics with Unilateral Contacts*, 1996),
    so ``E_d = 1/2 m v^2 (1 - e^2)``; the corner impulses are not unique (four corners,
    three equations)."""
    rng = np.random.default_rng(1403)
    count = 12
    m, inertia, x, v, om, points, normals, e, mus = _box(rng, count, mu, 0.0, tilt=0.7)
    om[:] = 0.0
    body = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v,
                       angular_velocity=om)  # fmt: skip
    out = multi_impacts(body, None, points, normals, e, mus)
    e_row = e[:, 0]
    expected = np.zeros((count, 3))
    expected[:, 2] = -e_row * v[:, 2]
    assert np.allclose(out.velocity_a, expected, rtol=0, atol=1e-12)
    assert np.allclose(out.angular_velocity_a, 0.0, rtol=0, atol=1e-11)
    lost = 0.5 * m * v[:, 2] ** 2 * (1.0 - e_row**2)
    assert np.allclose(out.dissipated, lost, rtol=1e-12, atol=1e-15)
    assert np.allclose(out.dissipated_theorem, lost, rtol=1e-12, atol=1e-15)
    assert out.statically_indeterminate.all() and not out.multiple_solutions.any()
    assert np.all(out.residual <= 1e-12)


def test_box_landings_with_a_corner_lifting_equal_solve_impact() -> None:
    """Sliding box landings where one corner lifts while three slip (the prediction from the
    sticking impulses often names two corners, or one sticking): the regimes are tried in
    the order the reference law documents (nearest the prediction first), so each row
    equals ``solve_impact`` (regimes, flags, velocities, the ledger)."""
    rng = np.random.default_rng(1404)
    count = 40
    m, inertia, x, v, om, points, normals, e, mus = _box(rng, count, 0.2, 3.0, tilt=0.4)
    body = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v,
                       angular_velocity=om)  # fmt: skip
    out = multi_impacts(body, None, points, normals, e, mus)
    lifting = 0
    for i in range(count):
        res = _reference(m, inertia, x, v[i], om[i], points, normals, e[i], mus[i])
        _compare(out, i, res, impulses=not res.flag_codes())
        lifting += sum(c.regime == "separate" for c in res.contacts) == 1
    assert lifting >= 5  # the case this order is for occurs in the sample


def test_an_overloaded_prediction_puts_a_lifting_corner_back_slipping(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Sliding box landings (mu 0.2, up to 3 m/s) that the sticking impulses predict with two
    corners lifting where one lifts: the friction cannot hold the corners all sticking (the
    prediction is overloaded), so a corner predicted to lift is put back slipping before
    sticking, and no regime mixing 3D stick and slip (whose slip roots all fail here, at
    some 40 slip-angle evaluations each) is tried before the answer. The batch kernel tries
    the same order: its rows equal ``solve_impact``."""
    from carnot.laws.multiple import simultaneous

    tried: list[tuple[str, ...]] = []
    solve_regime = simultaneous._solve_regime

    def record(g, w, contacts, held, pattern, *args, **kwargs):  # type: ignore[no-untyped-def]
        tried.append(pattern)
        return solve_regime(g, w, contacts, held, pattern, *args, **kwargs)

    monkeypatch.setattr(simultaneous, "_solve_regime", record)
    rng = np.random.default_rng(1407)
    count = 60
    m, inertia, x, v, om, points, normals, e, mus = _box(rng, count, 0.2, 3.0, tilt=0.2)
    body = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v,
                       angular_velocity=om)  # fmt: skip
    out = multi_impacts(body, None, points, normals, e, mus)
    put_back = 0
    for i in range(count):
        tried.clear()
        res = _reference(m, inertia, x, v[i], om[i], points, normals, e[i], mus[i])
        _compare(out, i, res, impulses=not res.flag_codes())
        answer = tuple(c.regime for c in res.contacts)
        first = tried[0]
        if first.count("separate") == 2 and answer.count("separate") == 1:
            put_back += 1
            mixed = [p for p in tried[: tried.index(answer)]
                     if "stick" in p and "slip" in p]  # fmt: skip
            assert not mixed, (i, tried)
    assert put_back >= 3  # the case this order is for occurs in the sample


@pytest.mark.parametrize("landing", [
    ([-0.431142086331365, 0.5348286329305418, -0.3380270015447546],
     [0.050706716833992374, -0.07165222152827262, -0.292514537851595], 0.3567948292860511),
    ([0.13334166067654019, -0.5239404189945851, -0.31448409327272175],
     [0.08491520230729546, -0.011376599756475115, -0.2075906572968712], 0.1625811319389291),
])  # fmt: skip
def test_box_sticking_with_its_friction_almost_used_up_is_solved(landing: tuple) -> None:  # type: ignore[type-arg]
    """A box landing flat (mu 1.5, sliding and spinning) whose four corners must stick with
    three of them using their friction to within 0.02 %: the cones' inscribed 32-gons (0.5 %
    inside) hold no impulse of the family, and this impact was reported ``no_solution``.
    The second landing (row 1621 of ``benchmarks/same_answers.py``'s sticking case) was
    answered by a later regime (three corners slipping, one lifting): the exact cones were
    tested only once every regime had failed by the polygons; now in the one pass, so the
    regimes' order alone decides, and the closed regime, tried first, holds.
    The cones tested exactly (cutting planes), every corner sticks; checked against the
    kinematics by hand (sticking at all four corners with Newton's law fixes the motion: the
    rigid motion whose corner velocities are ``(0, 0, -e w_n')``), the exact cones, theorem
    against direct. The batch kernel tests the cones exactly as well (its own cutting planes
    on its own simplex): it answers the row itself, with the reference's velocities."""
    m, inertia = 2.0, _box_inertia(2.0, (0.4, 0.3, 0.2))
    x = np.array([0.0, 0.0, 0.1])
    points = np.array([[sx * 0.2, sy * 0.15, 0.0] for sx in (1, -1) for sy in (1, -1)])
    normals = np.array([[0.0, 0.0, 1.0]] * 4)
    v, om, e, mu = np.array(landing[0]), np.array(landing[1]), landing[2], 1.5
    res = _reference(m, inertia, x, v, om, points, normals, [e] * 4, [mu] * 4)
    assert "no_solution" not in res.flag_codes()
    assert [c.regime for c in res.contacts] == ["stick"] * 4
    # by hand: v'' + om'' x r_k = (0, 0, -e w_n'_k) at the four corners (least squares over
    # the 12 equations, consistent: the targets are a rigid motion's)
    rows, targets = [], []
    for p in points:
        r = p - x
        w_n = (v + np.cross(om, r))[2]
        skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        rows.append(np.hstack([np.eye(3), -skew]))
        targets.append([0.0, 0.0, -e * w_n])
    u = np.linalg.lstsq(np.vstack(rows), np.concatenate(targets), rcond=None)[0]
    body = res.bodies["body"]
    assert np.allclose(body.velocity_after, u[:3], rtol=0, atol=1e-12)
    assert np.allclose(body.angular_velocity_after, u[3:], rtol=0, atol=1e-12)
    for c in res.contacts:  # inside the exact cones, some nearly on them
        assert np.hypot(*c.impulse[:2]) <= mu * c.normal_impulse * (1 + 1e-12)
    # the most feasible impulses (the cutting planes maximize the smallest slack) still use
    # some corner's friction to within the inscribed 32-gon's gap, 1 - cos(pi/32) = 0.48 %
    gap = min(1.0 - np.hypot(*c.impulse[:2]) / (mu * c.normal_impulse) for c in res.contacts)
    assert gap < 1.0 - math.cos(math.pi / 32)
    assert res.energy.dissipated_theorem == pytest.approx(res.energy.dissipated, rel=1e-12)
    batch = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v[None],
                        angular_velocity=om[None])  # fmt: skip
    out = multi_impacts(batch, None, points, normals, e, mu)
    assert not out.by_reference[0] and not out.no_solution[0]
    _compare(out, 0, res, impulses=False)


def test_the_reference_statuses_are_the_kernels() -> None:
    from carnot.batch import multi_kernel
    from carnot.batch.multi import REFERENCE_STATUSES

    assert REFERENCE_STATUSES == (multi_kernel.NEEDS_REFERENCE, multi_kernel.NO_SOLUTION)


def _stick_rows(rng: np.random.Generator, count: int, mu: float, slide: float):  # type: ignore[no-untyped-def]
    """Box landings (:func:`_box`, tilted) with their contact space, the Jacobian ``J`` of
    the box and the system of the regime that sticks all four corners (``G_RR x = rhs``)."""
    from carnot.batch import multi_kernel as mk

    m, inertia, x, v, om, points, normals, e, mus = _box(rng, count, mu, slide, tilt=0.3)
    # read-only, as the batch's frozen inputs reach the solvers: a read-only array is
    # another Numba type than a writable one, and each solver called here with writable
    # coefficients compiled a second copy of itself (solve_into alone: 30 s)
    e.flags.writeable = mus.flags.writeable = False
    tangential = np.ones(4, dtype=np.int64)
    nrow = np.arange(0, 12, 3)
    trow = np.stack([nrow + 1, nrow + 2], axis=1)
    ntan = np.full(4, 2)
    base = np.full(4, mk.STICK_OPT)
    for i in range(count):
        g, w, jac, *_ = mk.assemble(m, inertia, x, v[i], om[i], 1.0, np.eye(3), np.zeros(3),
                                    np.zeros(3), np.zeros(3), False, points, normals,
                                    tangential, 12)  # fmt: skip
        b, rows, targets = np.zeros((12, 12)), np.zeros(12, dtype=np.int64), np.zeros(12)
        q, symmetric = mk._columns(12, nrow, trow, ntan, mus[i], e[i], base, w,
                                   np.zeros((4, 2)), b, rows, targets)  # fmt: skip
        assert q == 12 and symmetric
        yield (m, inertia, g, w, jac, rows, targets - w[rows], nrow, trow, ntan, e[i], mus[i],
               base)  # fmt: skip


def _cones_admit(jac: np.ndarray, y: np.ndarray, mus: np.ndarray, radius: float) -> bool:
    """Whether an impulse ``x`` of four corners (rows ``n, t1, t2`` each) with ``J^T x = y``
    has every corner's ``p_n >= 0`` and ``p_t . u <= radius mu p_n`` for 16 directions ``u``
    (``radius`` 1: the polygon circumscribing the cone; ``cos(pi/16)``: the inscribed one),
    by SciPy's linear program (HiGHS)."""
    from scipy.optimize import linprog

    a_ub = []
    for c in range(4):
        n, t1, t2 = 3 * c, 3 * c + 1, 3 * c + 2
        row = np.zeros(12)
        row[n] = -1.0
        a_ub.append(row)
        for th in 2.0 * np.pi * (np.arange(16) + 0.5) / 16:
            row = np.zeros(12)
            row[t1], row[t2], row[n] = np.cos(th), np.sin(th), -radius * mus[c]
            a_ub.append(row)
    res = linprog(np.zeros(12), A_ub=np.array(a_ub), b_ub=np.zeros(len(a_ub)), A_eq=jac.T,
                  b_eq=y, bounds=[(None, None)] * 12, method="highs")  # fmt: skip
    assert res.status in (0, 2), res.message
    return bool(res.status == 0)


@pytest.mark.parametrize(("mu", "slide"), [(0.2, 3.0), (0.4, 1.5), (1.5, 0.8)])
def test_an_impossible_stick_is_infeasible(mu: float, slide: float) -> None:
    """``_stick_impossible`` (a dual direction of the friction cones as a Farkas certificate
    that no impulse of the stick regime's family meets the cones) against SciPy's linear
    program (HiGHS) on the same family, ``J^T x = y``: where the certificate holds, even the
    polygons circumscribing the cones (16 sides, a relaxation) admit no member; where the
    inscribed polygons admit one (the regime's impulses exist), it never holds. And it
    decides most sliding landings (mu 0.2 at up to 3 m/s), so that the check is not empty."""
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(1409)
    proved = tried = 0
    for (m, inertia, g, w, jac, rows, rhs, nrow, _trow, _ntan, _e, mus,
         base) in _stick_rows(rng, 60, mu, slide):  # fmt: skip
        scale = float(np.max(np.abs(w)))
        part = w[nrow] <= 1e-9 * scale
        if not part.all():
            continue  # (the family of _stick_rows' regime sticks all four corners)
        tried += 1
        x, y = np.zeros(12), np.empty(6)
        ws = (np.empty((6, 6)), np.empty(6), np.empty(6))
        assert mk._body_min_norm(jac, m, inertia, rows, 12, rhs, x, 1e-9 * scale, y, *ws)
        impossible = mk._stick_impossible(jac, y, nrow, part, base.astype(np.int8),
                                          np.full(4, mk.SPATIAL, dtype=np.int8), mus, g,
                                          1e-9 * scale)  # fmt: skip

        if impossible:
            proved += 1
            assert not _cones_admit(jac, y, mus, 1.0)  # (circumscribed: contains the cone)
        elif _cones_admit(jac, y, mus, np.cos(np.pi / 16)):  # (inscribed: inside the cone)
            assert not impossible
    assert tried >= 30
    if mu == 0.2:
        assert proved >= 0.8 * tried
    if mu == 1.5:
        assert proved <= 0.2 * tried


def test_dependent_slip_rows_solve_as_lstsq() -> None:
    """A slip system whose rows depend by structure (a flat box's four corners all slipping:
    normal rows of rank 3) solved from its independent rows (``_row_basis``,
    ``_min_norm_rows``) against NumPy's ``lstsq`` (LAPACK's SVD) of the whole system, the
    reference's route, at random slip angles: the same impulses and slip conditions to
    round-off. Three corners slipping give independent rows (no reduction), and a
    right-hand side made inconsistent is refused (the QR then takes the least squares)."""
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(1410)
    nrow = np.arange(0, 12, 3)
    trow = np.stack([nrow + 1, nrow + 2], axis=1)
    ntan = np.full(4, 2)
    for (_m, _inertia, g, w, _jac, _rows, _rhs, _nrow, _trow, _ntan, e, mus,
         _base) in _stick_rows(rng, 20, 0.2, 3.0):  # fmt: skip
        nws = mk.newton_workspace(4, 12)
        (b, rows, rhs, grows, a, col, x, lu, imp, f, _f2, _jac2, _trial, _step, _null, mats,
         vecs, perm, rowcol, cs, sel, zero_dirs, targets, _setup) = nws  # fmt: skip
        for slipping in (np.arange(4), np.arange(1, 4)):
            pattern = np.full(4, mk.SLIP_OPT, dtype=np.int8)
            if len(slipping) == 3:
                pattern[0] = mk.SEPARATE_OPT
            ns = len(slipping)
            col[:] = 0
            q = mk._slip_system(g, w, nrow, trow, ntan, mus, e, pattern, slipping, ns, b, rows,
                                rhs, grows, a, col, rowcol, zero_dirs, targets)  # fmt: skip
            nsel = mk._row_basis(grows, rhs, q, 12, sel, mats, vecs[0])
            assert (q, nsel) == ((4, 3) if ns == 4 else (3, 3))
            for _ in range(5):
                angles = rng.uniform(-np.pi, np.pi, ns)
                pivot, svd = mk._parallel(g, w, nrow, trow, mus, slipping, ns, angles, 0, ns, q,
                                          b, rhs, grows, a, col, x, lu, imp, f, mats, vecs,
                                          perm, rowcol, cs, True, sel, nsel)  # fmt: skip
                assert not svd
                x_ref = np.linalg.lstsq(a[:q, :q], rhs[:q], rcond=None)[0]
                size = float(np.max(np.abs(x_ref)))
                assert np.allclose(x[:q], x_ref, rtol=0, atol=1e-12 * size)
                w_after = w + g @ (b[:, :q] @ x_ref)
                t1, t2 = trow[slipping, 0], trow[slipping, 1]
                f_ref = w_after[t1] * np.sin(angles) - w_after[t2] * np.cos(angles)
                assert np.allclose(f[:ns], f_ref, rtol=0, atol=1e-12 * float(np.max(np.abs(w))))
        col[:] = 0  # (a right-hand side not consistent with the rows' dependence)
        pattern = np.full(4, mk.SLIP_OPT, dtype=np.int8)
        q = mk._slip_system(g, w, nrow, trow, ntan, mus, e, pattern, np.arange(4), 4, b, rows,
                            rhs, grows, a, col, rowcol, zero_dirs, targets)  # fmt: skip
        bad = rhs.copy()
        bad[q - 1] += 1e-3 * float(np.max(np.abs(rhs[:q])))
        assert mk._row_basis(grows, bad, q, 12, sel, mats, vecs[0]) == q


def test_root_check_on_newtons_solve_is_the_fresh_solve() -> None:
    """A slip root checked on the system the Newton iteration solved there (``_root_regime``:
    its minimum-norm ``x``, and the null space as the complement of the rows the
    evaluation orthonormalized) against the check that builds and solves the system
    afresh by the QR (``linear_regime``, the reference's route): the same verdict, the same
    flags (not unique, continuum) and the same impulses and velocities to round-off, on
    tilted box landings with four corners slipping (rows of rank 3: the independent rows
    solved it) and three (regular: the elimination did)."""
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(2711)
    holds = mk.impact_solvers()[2]  # (the regime's check, a C callback the two routes call)
    checked = {2.0: 0, 1.0: 0}
    for (_m, _inertia, g, w, _jac, _rows, _rhs, nrow, trow, ntan, e, mus,
         _base) in _stick_rows(rng, 12, 0.2, 3.0):  # fmt: skip
        scale = float(np.max(np.abs(w)))
        kind = np.full(4, mk.SPATIAL, dtype=np.int64)
        for slipping in (np.arange(4), np.arange(1, 4)):
            ns = len(slipping)
            pattern = np.full(4, mk.SEPARATE_OPT, dtype=np.int64)
            pattern[slipping] = mk.SLIP_OPT
            nws = mk.newton_workspace(4, 12)
            fresh, reused = mk.regime_workspace(4, 12), mk.regime_workspace(4, 12)
            dirs = np.zeros((4, 2))
            angles = np.array([np.arctan2(w[trow[c, 1]], w[trow[c, 0]]) for c in slipping])
            found, held = mk._newton_angles(g, w, nrow, trow, ntan, mus, e, pattern, dirs,
                                            slipping, np.int64(ns), angles, scale, nws,
                                            fresh[28], 0, np.int64(0))  # fmt: skip
            if found != mk.ROOT:
                continue
            assert held == (mk.MIN_NORM_PATH if ns == 4 else 1.0)
            dirs[slipping, 0], dirs[slipping, 1] = np.cos(angles), np.sin(angles)
            outs = []
            for ws, reuse in ((fresh, False), (reused, True)):
                imp, wa = np.zeros(12), np.zeros(12)
                if reuse:
                    verdict = mk._root_regime(g, w, nrow, trow, ntan, kind, e, mus, pattern,
                                              dirs, scale, imp, wa, ws[:11], nws, held, ws[28],
                                              ws[29], 0, holds)  # fmt: skip
                else:
                    verdict = mk.linear_regime(g, w, nrow, trow, ntan, kind, e, mus, pattern,
                                               dirs, scale, imp, wa, ws[:11], ws[28], ws[29],
                                               0, holds)  # fmt: skip
                outs.append((tuple(int(v) for v in verdict), imp, wa))
            (v1, imp1, wa1), (v2, imp2, wa2) = outs
            assert v1 == v2, (ns, v1, v2)
            if v1[0] == 1:
                checked[held] += 1
                assert np.allclose(wa1, wa2, rtol=0, atol=1e-12 * scale)
                assert np.allclose(imp1, imp2, rtol=0, atol=1e-12 * float(np.max(np.abs(imp1))))
    assert checked[2.0] >= 3 and checked[1.0] >= 3, checked  # (both routes exercised)


def _conditions(system: tuple, angles: np.ndarray) -> tuple[float, np.ndarray]:  # type: ignore[type-arg]
    """The kernel's slip conditions (``_parallel``) of a slip ``system`` at ``angles``, and
    how it solved the system (its ``pivot``)."""
    from carnot.batch import multi_kernel as mk

    (g, w, nrow, trow, mus, slipping, ns, q, b, rhs, grows, a, col, x, lu, imp, mats, vecs, perm,
     rowcol, cs, skip, sel, nsel) = system  # fmt: skip
    out = np.empty(ns)
    pivot, svd = mk._parallel(g, w, nrow, trow, mus, slipping, ns, angles, 0, ns, q, b, rhs,
                              grows, a, col, x, lu, imp, out, mats, vecs, perm, rowcol, cs, skip,
                              sel, nsel)  # fmt: skip
    assert not svd
    return pivot, out


def test_exact_slip_jacobian_is_the_central_differences() -> None:
    """The slip conditions' Jacobian that the kernel's Newton iteration starts from
    (``_jacobian_exact``: the derivative of the regular system's solution, and of the
    minimum-norm solution of a system whose rows depend by structure) against central
    differences of the conditions themselves (``_parallel``, step 1e-6 rad: error ~1e-12),
    at random slip angles of a box's corners: four slipping (rank 3: the minimum-norm path),
    three (regular: elimination), two, two with a third sticking."""
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(1411)
    nrow = np.arange(0, 12, 3)
    trow = np.stack([nrow + 1, nrow + 2], axis=1)
    ntan = np.full(4, 2)
    fa, _ia = _arenas(4, 12)
    paths = set()
    for (_m, _inertia, g, w, _jac, _rows, _rhs, _nrow, _trow, _ntan, e, mus,
         _base) in _stick_rows(rng, 10, 0.2, 3.0):  # fmt: skip
        nws = mk.newton_workspace(4, 12)
        (b, rows, rhs, grows, a, col, x, lu, imp, f, _f2, jac, _trial, _step, _null, mats,
         vecs, perm, rowcol, cs, sel, zero_dirs, targets, _setup) = nws  # fmt: skip
        for slipping in (np.arange(4), np.arange(1, 4), np.array([0, 3]), np.array([0, 1])):
            pattern = np.full(4, mk.SEPARATE_OPT, dtype=np.int8)
            pattern[slipping] = mk.SLIP_OPT
            if len(slipping) == 2 and slipping[1] == 1:
                pattern[3] = mk.STICK_OPT  # (a sticking corner's tangent rows in the system)
            ns = len(slipping)
            col[:] = 0
            q = mk._slip_system(g, w, nrow, trow, ntan, mus, e, pattern, slipping, ns, b, rows,
                                rhs, grows, a, col, rowcol, zero_dirs, targets)  # fmt: skip
            skip = ns == 4
            nsel = mk._row_basis(grows, rhs, q, 12, sel, mats, vecs[0]) if skip else q

            system = (g, w, nrow, trow, mus, slipping, ns, q, b, rhs, grows, a, col, x, lu, imp,
                      mats, vecs, perm, rowcol, cs, skip, sel, nsel)  # fmt: skip
            for _ in range(3):
                angles = rng.uniform(-np.pi, np.pi, ns)
                path, _f = _conditions(system, angles)
                paths.add(path)
                jac[:] = np.nan
                assert mk._jacobian_exact(g, w, trow, mus, slipping, ns, q, b, grows, a, col,
                                          x, imp, jac, mats, rowcol, cs, sel, nsel, path, fa,
                                          0)  # fmt: skip
                h = 1e-6
                ref = np.empty((ns, ns))
                for j in range(ns):
                    step = np.zeros(ns)
                    step[j] = h
                    ref[:, j] = (_conditions(system, angles + step)[1]
                                 - _conditions(system, angles - step)[1]) / (2 * h)  # fmt: skip
                size = float(np.max(np.abs(ref)))
                assert np.allclose(jac[:ns, :ns], ref, rtol=0, atol=1e-7 * size), (ns, path)
                if ns == 4:  # singular by structure, taken whole: the finite differences
                    assert not mk._jacobian_exact(g, w, trow, mus, slipping, ns, q, b, grows,
                                                  a, col, x, imp, jac, mats, rowcol, cs, sel,
                                                  nsel, 0.0, fa, 0)  # fmt: skip
    assert paths == {1.0, mk.MIN_NORM_PATH}  # both solves' derivatives were tested


def test_body_space_solves_are_the_rows_solves() -> None:
    """The stick regime of one free body solved in its 6 velocities (``_body_min_norm``:
    ``G^+ = J (J^T J)^-1 M (J^T J)^-1 J^T``) against the 12 rows' own route (pivoted
    Cholesky, ``_sym_solve``) and against NumPy's pseudo-inverse of ``G_RR`` (SVD); and its
    capacity-weighted impulse (``_body_weighted``) against the rows' route
    (``_capacity_weighted``, the reference's normal equations over the null space) and
    against a direct KKT solve of ``min |D x|`` subject to ``J^T x = J^T x0``."""
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(1407)
    checked = 0
    for (m, inertia, g, w, jac, rows, rhs, nrow, trow, ntan, _e, mus,
         base) in _stick_rows(rng, 60, 0.4, 1.5):  # fmt: skip
        scale = float(np.max(np.abs(w)))
        gr = g[np.ix_(rows, rows)]
        x_body, y = np.zeros(12), np.empty(6)
        ws = (np.empty((6, 6)), np.empty(6), np.empty(6))
        assert mk._body_min_norm(jac, m, inertia, rows, 12, rhs, x_body, 1e-9 * scale, y, *ws)
        x_rows, null = np.zeros(12), np.zeros((12, 12))
        nn = mk._sym_solve(0.5 * (gr + gr.T), rhs, 12, x_rows, null, *_arenas(), 0)
        assert nn == 6
        size = float(np.max(np.abs(x_rows)))
        assert np.allclose(x_body, x_rows, rtol=0, atol=1e-10 * size)
        assert np.allclose(x_body, np.linalg.pinv(gr, rcond=1e-10) @ rhs, rtol=0,
                           atol=1e-10 * size)  # fmt: skip
        assert np.allclose(jac[rows].T @ x_body, y, rtol=0, atol=1e-12 * size)
        # capacity weighting, both routes (from the same minimum-norm impulse)
        b = np.eye(12)[:, rows]
        x_cw = x_rows.copy()
        mk._capacity_weighted(base, np.full(4, mk.SPATIAL), nrow, trow, ntan, mus, b, x_cw,
                              null, 12, nn, 12, _arenas()[0], 0)  # fmt: skip
        x_bw = x_body.copy()
        assert mk._body_weighted(jac, base, nrow, trow, ntan, mus, rows, 12, x_bw, y,
                                 np.empty(12), np.empty((6, 6)), np.empty(6))  # fmt: skip
        assert np.allclose(x_bw, x_cw, rtol=0, atol=1e-9 * size)
        pmax = np.max(np.abs(x_body))
        weights = np.full(12, 1.0 / pmax)
        for c in range(4):
            cap = max(mus[c] * x_body[nrow[c]], 1e-3 * pmax)
            weights[trow[c]] = 1.0 / cap
        jr = jac[rows]
        kkt = np.block([[np.diag(weights[rows] ** 2), jr], [jr.T, np.zeros((6, 6))]])
        direct = np.linalg.solve(kkt, np.concatenate([np.zeros(12), y]))[:12]
        assert np.allclose(x_bw, direct, rtol=0, atol=1e-9 * size)
        checked += 1
    assert checked == 60


@pytest.mark.parametrize(("mu", "slide"), [(1.5, 0.8), (0.2, 3.0), (0.5, 1.5)])
def test_the_front_decides_as_solve_into_does(mu: float, slide: float) -> None:
    """``solve_front`` (the landing that sticks as predicted, decided in leaves) gives
    ``solve_into``'s answer where it decides, and where it does not, ``solve_into`` going on
    from the front's state gives the answer of ``solve_into`` started afresh: the same
    status, flags, regimes, impulses and velocities."""
    from carnot.batch import multi_kernel as mk

    rng = np.random.default_rng(1408)
    decided = undecided = 0
    for (m, inertia, g, w, jac, _rows, _rhs, nrow, trow, ntan, e, mus,
         _base) in _stick_rows(rng, 80, mu, slide):  # fmt: skip
        outs = []
        for route in ("front", "afresh"):
            ws, nws = mk.workspace(4, 12), mk.newton_workspace(4, 12)
            rws = mk.regime_workspace(4, 12)
            imp, wa = np.zeros(12), np.zeros(12)
            regime, active = np.zeros(4, dtype=np.int8), np.zeros(4, dtype=np.bool_)
            state = mk.AFRESH
            if route == "front":
                result = mk.solve_front(g, w, nrow, trow, ntan, e, mus, imp, wa, regime, active,
                                        ws, rws[:4], jac, m, inertia, True,
                                        (rws[24], rws[25], rws[26], rws[27]))  # fmt: skip
                if result[0] != mk.UNDECIDED:
                    decided += 1
                    outs.append((result[:3], imp.copy(), wa.copy(), regime.copy()))
                    continue
                undecided += 1
                state = tuple(result[3:])
            s, f, r = mk.solve_into(g, w, nrow, trow, ntan, e, mus, imp, wa, regime, active, ws,
                                    nws, rws, jac, m, inertia, True, state,
                                    *mk.impact_solvers()[1:])  # fmt: skip
            outs.append(((s, f, r), imp.copy(), wa.copy(), regime.copy()))
        (s1, f1, r1), imp1, wa1, reg1 = outs[0]
        (s2, f2, r2), imp2, wa2, reg2 = outs[1]
        scale = float(np.max(np.abs(w)))
        assert (s1, f1) == (s2, f2)
        assert np.array_equal(reg1, reg2)
        assert np.allclose(wa1, wa2, rtol=0, atol=1e-12 * scale)
        assert np.allclose(imp1, imp2, rtol=0, atol=1e-12 * max(1.0, np.max(np.abs(imp2))))
        assert abs(r1 - r2) <= 1e-12 * scale
    if mu == 1.5:
        assert decided > 60  # (most sticking landings end in the front)
    if mu == 0.2:
        assert undecided == 80  # (a sliding landing is overloaded: the front gives way)


@pytest.mark.parametrize(("mu", "slide"), [(0.0, 0.0), (0.4, 1.5)])
def test_a_batch_is_its_impacts_one_by_one(mu: float, slide: float) -> None:
    """A frictionless batch runs in two passes (the kernel's frictionless front,
    ``run_normal``, then the whole kernel on the impacts it leaves: here the flat landings,
    whose four coplanar corners give a singular ``G``), the batch in parallel tasks of
    ``TASK`` impacts: every impact's answer is the one it gets alone, to the bit."""
    rng = np.random.default_rng(3501)
    count = 200  # several tasks of carnot.batch.multi_kernel.TASK impacts
    m, inertia, x, v, om, points, normals, e, mus = _box(rng, count, mu, slide, tilt=0.3)
    flat = rng.random(count) < 0.5  # no spin: all four corners take part
    om[flat] = 0.0
    om[~flat, 0] = rng.choice([-1.0, 1.0], int((~flat).sum())) * 15.0  # two corners lift
    body = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v,
                       angular_velocity=om)  # fmt: skip
    out = multi_impacts(body, None, points, normals, e, mus)
    assert out.statically_indeterminate[flat].all()
    assert not out.statically_indeterminate[~flat].all()
    fields = ("impulse", "velocity_a", "angular_velocity_a", "dissipated", "regime", "active",
              "residual", "statically_indeterminate", "uniqueness_verified")  # fmt: skip
    for i in range(0, count, 7):
        one = BatchBodies(mass=m, inertia_com=inertia, position_com=x, velocity_com=v[i],
                          angular_velocity=om[i])  # fmt: skip
        alone = multi_impacts(one, None, points, normals, e[i], mus[i])
        for name in fields:
            np.testing.assert_array_equal(getattr(out, name)[i], getattr(alone, name),
                                          err_msg=f"{name} of impact {i}")  # fmt: skip


def test_contact_spaces_in_a_batch_are_their_impacts_one_by_one() -> None:
    """The contact-space route's frictionless front (``solve_rows_normal``) and the whole
    kernel on the rows it leaves (a singular ``G``: two contacts on one row of the body,
    ``[[1, 1], [1, 1]] / m``, both approaching alike: closed, impulses not unique): each
    row's answer is the one it gets alone, to the bit."""
    rng = np.random.default_rng(3502)
    count = 150
    singular = rng.random(count) < 0.4
    g = np.where(singular[:, None, None], np.array([[1.0, 1.0], [1.0, 1.0]]),
                 np.array([[2.0, -1.0], [-1.0, 2.0]]))  # fmt: skip
    w = np.stack([rng.uniform(-2.0, -0.1, count), rng.uniform(-1.0, 0.5, count)], axis=1)
    e = rng.uniform(0.0, 1.0, (count, 2))
    w[singular, 1] = w[singular, 0]
    e[singular, 1] = e[singular, 0]
    out = contact_space_impacts(g, w, [0, 0], e)
    assert out.statically_indeterminate[singular].all()  # (the whole kernel's verdict)
    assert not out.statically_indeterminate[~singular].any()
    for i in range(0, count, 5):
        alone = contact_space_impacts(g[i], w[i], [0, 0], e[i])
        for name in ("impulses", "w_after", "regime", "active", "residual",
                     "statically_indeterminate", "uniqueness_verified"):  # fmt: skip
            np.testing.assert_array_equal(getattr(out, name)[i], getattr(alone, name),
                                          err_msg=f"{name} of row {i}")  # fmt: skip


@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_a_separating_end_driven_into_the_floor_takes_part(mu: float) -> None:
    """Issue 33, item 3 (the rod of the issue): a uniform rod (1 kg, 1 m) whose left end
    lifts at 0.01 m/s while its right end strikes at 1 m/s, e = 0.5. Left out, the lifting
    end would leave going into the floor at 0.74 m/s (the right end's impulse 0.375 N s
    alone); taking part (with e = 0: restitution acts on approach), it carries an impulse
    and stays on the floor. In closed form (frictionless; ``w'' = w' + G P`` with
    ``G = [[4, -2], [-2, 4]]`` for the ends of the rod, ``w' = (0.01, -1)``): the left end
    leaves at 0 and the right at 0.5, so ``4 P_l - 2 P_r = -0.01`` and
    ``-2 P_l + 4 P_r = 1.5``: ``P_l = 0.24667``, ``P_r = 0.49833`` N s. The batch gives it
    through the reference law, as solve_impact does."""
    inertia = np.diag([1e-3, 1 / 12, 1 / 12])
    points = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]])
    normals = np.array([[0.0, 0.0, 1.0]] * 2)
    v, om = np.array([0.0, 0.0, -0.495]), np.array([0.0, 1.01, 0.0])
    ends = v[2] + np.cross(om, points)[:, 2]
    np.testing.assert_allclose(ends, [0.01, -1.0], atol=1e-15)
    body = BatchBodies(mass=[1.0], inertia_com=inertia, position_com=[0, 0, 0],
                       velocity_com=v[None], angular_velocity=om[None])  # fmt: skip
    out = multi_impacts(body, None, points, normals, [0.5, 0.5], [mu, mu])
    after = out.velocity_a[0, 2] + np.cross(out.angular_velocity_a[0], points)[:, 2]
    assert after == pytest.approx([0.0, 0.5], abs=1e-12)
    assert out.normal_impulse[0] == pytest.approx([0.74 / 3, 1.495 / 3], abs=1e-12)
    assert not out.separating_contact_approaches[0] and out.by_reference[0]
    res = _reference(1.0, inertia, np.zeros(3), v, om, points, normals, [0.5, 0.5], [mu, mu])
    _compare(out, 0, res, impulses=True)
    space = contact_space_impacts([[4.0, -2.0], [-2.0, 4.0]], [0.01, -1.0], [0, 0], [0.5, 0.5])
    assert space.impulses == pytest.approx([0.74 / 3, 1.495 / 3], abs=1e-12)
    assert space.w_after == pytest.approx([0.0, 0.5], abs=1e-12)
    assert bool(space.by_reference) and not bool(space.separating_contact_approaches)


def test_a_reference_that_stops_short_is_said(monkeypatch: pytest.MonkeyPatch) -> None:
    """A row the batch hands to the reference (carnot.solvers.resolve) keeps the reference's
    verdict: where its search for a 3D slip answer stopped short (``not_converged``, not a
    proof that none exists), the batch says ``not_converged``, not a clean row. The
    reference is replaced here by one that answers the rod's contact space (the row of
    ``test_a_separating_end_driven_into_the_floor_takes_part``) with that flag."""
    import dataclasses

    import carnot.solvers
    import carnot.solvers.dispatch

    real = carnot.solvers.dispatch.resolve

    def stopping_short(*args, **kwargs):  # type: ignore[no-untyped-def]
        answer = real(*args, **kwargs)
        return dataclasses.replace(answer, flags=(*answer.flags, "not_converged"))

    monkeypatch.setattr(carnot.solvers.dispatch, "resolve", stopping_short)
    monkeypatch.setattr(carnot.solvers, "resolve", stopping_short, raising=False)
    g, w = np.array([[[4.0, -2.0], [-2.0, 4.0]]] * 2), np.array([[0.01, -1.0], [-1.0, -1.0]])
    space = contact_space_impacts(g, w, [0, 0], [0.5, 0.5])
    assert space.by_reference.tolist() == [True, False]
    assert space.not_converged.tolist() == [True, False]


@pytest.mark.parametrize("solver", [{"name": "iterative"},
                                    {"name": "enumerate", "trace_families": True}])
def test_sweep_honours_the_scenarios_solver(solver: dict) -> None:  # type: ignore[type-arg]
    """A scenario that names the iterative solver, or traced families, is swept by the
    ``solve_impact`` loop, which runs that solver, even where the multi-contact batch kernel
    (the enumeration, stopping at the first regime that holds) would fit and is forced: each
    row is then ``carnot solve``'s answer with that solver (DESIGN.md section 9). The
    ``enumerate`` and ``auto`` scenarios keep the kernel."""
    from carnot.io.scenario import parse_scenario, read_scenario_data
    from carnot.sweep import make_plan, prepare_sweep

    data = read_scenario_data("examples/box_lands_flat.toml")
    plan = make_plan(vary=["contacts.0.restitution=0:0.5:3"])
    assert prepare_sweep(data, plan, compiled=True).route == "multi"
    data["solver"] = {"name": "enumerate"}
    assert prepare_sweep(data, plan, compiled=True).route == "multi"
    data["solver"] = solver
    sweep = prepare_sweep(data, plan, compiled=True)
    assert sweep.route == "solve" and "[solver]" in sweep.why_solve
    rows = sweep.chunk(0, sweep.rows)
    for i, e in enumerate([0.0, 0.25, 0.5]):
        data["contacts"][0]["restitution"] = e
        res = solve_impact(parse_scenario(data, "<row>"))
        assert res.solver is not None and res.solver.solver == solver["name"]
        assert rows.columns["dissipated"][i] == pytest.approx(res.energy.dissipated, rel=1e-12)
        assert rows.columns["contacts.0.normal_impulse"][i] == pytest.approx(
            res.contacts[0].normal_impulse, rel=1e-12, abs=1e-15)  # fmt: skip

"""carnot.batch with Coulomb friction (carnot.batch.coulomb): parity with carnot.solve_impact
(planar: exact, 1e-12; 3D slip that turns: the batch integrator's tolerance, 1e-10), the
published closed forms of tests/test_friction.py (Stronge 2000 ch. 5, the slender rod; Brach
1991 and Cross 2002, the ball), the theorem and the work route against the direct
difference, the compiled build against the array builds, masks and shapes.

Each law is compiled once per process (the module-scoped batches below share it)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_batch import _one, _random_bodies
from test_friction import _planar_closed_form

from carnot import FixedBody, ImpactProblem, PointContact, solve_impact
from carnot.batch import BatchBodies, point_impacts
from carnot.batch.coulomb import HYPOTHESIS_ENERGY_GAIN, NORMAL_WORK_GAIN, RTOL, STRONGE
from carnot.batch.laws import FRICTIONLESS, NONE, REGIME_NAMES, STICK
from carnot.model.free_bodies import assemble
from carnot.model.inertia import rod, solid_sphere

HYPOTHESES = ("newton", "poisson", "stronge")
FIELDS = ("mass", "inertia_com", "position_com", "velocity_com", "angular_velocity")


def _planar_bodies(rng: np.random.Generator, n: int) -> BatchBodies:
    """Bodies moving in the x-y plane (inertia with a principal axis along z): every slip
    direction is invariant, the exact piecewise-linear solution applies."""
    mass = 10 ** rng.uniform(-2, 2, n)
    size = 10 ** rng.uniform(-1, 0.5, n)
    a, b = rng.uniform(0.05, 1.0, (2, n))
    moments = np.stack([a, b, a + b], -1) * (mass * size**2)[:, None]
    rot = Rotation.from_euler("z", rng.uniform(0, 2 * np.pi, (n, 1))).as_matrix()
    inertia = rot @ (moments[:, :, None] * np.eye(3)) @ np.swapaxes(rot, -1, -2)
    flat = np.array([1.0, 1.0, 0.0])
    return BatchBodies(mass=mass, inertia_com=inertia,
                       position_com=rng.uniform(-2, 2, (n, 3)) * flat,
                       velocity_com=rng.uniform(-5, 5, (n, 3)) * flat,
                       angular_velocity=rng.uniform(-5, 5, (n, 3)) * (1 - flat))  # fmt: skip


def _bodies_3d(rng: np.random.Generator, n: int) -> BatchBodies:
    """Masses over four decades, realizable inertias in random principal axes."""
    return _random_bodies(rng, n, decades=2.0, smallest=-1.0, speed=5.0)


def _cases(planar: bool, n: int, seed: int) -> dict:
    """``n`` random impacts, the first half against an obstacle, the rest between two bodies;
    mu over [0, 1.2] with some exact zeros, e over [0, 1] with some 0 and 1."""
    rng = np.random.default_rng(seed)
    make = _planar_bodies if planar else _bodies_3d
    a, b = make(rng, n), make(rng, n)
    point = rng.uniform(-2, 2, (n, 3))
    normal = rng.normal(size=(n, 3))
    if planar:
        point[:, 2] = 0.0
        normal[:, 2] = 0.0
    e = rng.uniform(0, 1, n)
    e[rng.random(n) < 0.05] = 0.0
    e[rng.random(n) < 0.05] = 1.0
    mu = rng.uniform(0, 1.2, n)
    mu[rng.random(n) < 0.05] = 0.0
    return dict(a=a, b=b, point=point, normal=normal, e=e, mu=mu, half=n // 2)


def _split(case: dict) -> list[tuple[slice, BatchBodies, BatchBodies | None]]:
    h, n = case["half"], len(case["e"])
    sub = [slice(0, h), slice(h, n)]

    def part(bodies: BatchBodies, s: slice) -> BatchBodies:
        return BatchBodies(**{f: getattr(bodies, f)[s] for f in FIELDS})

    return [(sub[0], part(case["a"], sub[0]), None),
            (sub[1], part(case["a"], sub[1]), part(case["b"], sub[1]))]  # fmt: skip


def _batch(case: dict, law: str, backend: str = "auto") -> list:
    return [(s, point_impacts(a, b, case["point"][s], case["normal"][s], case["e"][s],
                              friction=case["mu"][s], law=law, backend=backend))
            for s, a, b in _split(case)]  # fmt: skip


def _check_parity(case: dict, law: str, rel_tol: float) -> None:
    """Every impact against carnot.solve_impact: the impulse, the velocities after, the
    ledger, the compression impulse and works, the regime and the flags; ``rel_tol`` times
    cond(K) relative (the two routes factor K differently)."""
    for (s, out), (_, a, b) in zip(_batch(case, law), _split(case), strict=True):
        for i, k in enumerate(range(s.start, s.stop)):
            bodies = {"a": _one(a, i, "a"),
                      "b": FixedBody(name="b") if b is None else _one(b, i, "b")}  # fmt: skip
            problem = ImpactProblem(bodies=bodies, contacts=[PointContact(
                a="a", b="b", point=case["point"][k], normal=case["normal"][k],
                restitution=case["e"][k], friction=case["mu"][k], law=law)])  # fmt: skip
            ref = solve_impact(problem)
            space = assemble(problem, problem.contacts, [c.rows() for c in problem.contacts]).space
            rel = rel_tol * np.linalg.cond(space.delassus())
            c = ref.contacts[0]
            size = np.linalg.norm(c.impulse) + 1e-300
            assert np.linalg.norm(out.impulse[i] - c.impulse) <= rel * size, (law, k)
            dv = out.velocity_a[i] - ref.bodies["a"].velocity_after
            assert np.linalg.norm(dv) <= rel * size / a.mass[i] + 1e-300
            en = ref.energy
            for mine, theirs in ((out.dissipated[i], en.dissipated),
                                 (out.dissipated_theorem[i], en.dissipated_theorem),
                                 (out.dissipated_normal[i], en.dissipated_normal),
                                 (out.dissipated_tangential[i], en.dissipated_tangential)):
                assert abs(mine - theirs) <= rel * en.before + 1e-300, (law, k)  # fmt: skip
            name = REGIME_NAMES[int(out.regime[i])]
            process = c.process
            if process is None:  # mu = 0
                assert name == "frictionless" and c.regime == "frictionless"
                continue
            assert name == process.regime, (law, k)
            work = abs(process.work_normal_compression) + abs(process.work_tangential) + 1e-300
            p_c = out.compression_impulse[i] - process.compression_impulse
            assert abs(p_c) <= rel * size, (law, k)
            for mine, theirs in ((out.work_normal_compression[i], process.work_normal_compression),
                                 (out.work_normal_restitution[i], process.work_normal_restitution),
                                 (out.work_tangential_compression[i],
                                  process.work_tangential_compression),
                                 (out.work_tangential_restitution[i],
                                  process.work_tangential_restitution)):  # fmt: skip
                assert abs(mine - theirs) <= rel * work, (law, k)
            codes = ref.flag_codes()
            assert bool(out.law_flags[i] & NORMAL_WORK_GAIN) == ("normal_energy_gain" in codes)
            assert out.not_approaching[i] == ("not_approaching" in codes)
        # the theorem and the works (E_d = -(W_n + W_t)) against the direct difference
        scale = out.before
        assert np.all(np.abs(out.dissipated - out.dissipated_theorem) <= 1e-11 * scale)
        rough = case["mu"][s] > 0
        works = -(out.work_normal_compression + out.work_normal_restitution
                  + out.work_tangential_compression + out.work_tangential_restitution)  # fmt: skip
        assert np.all(np.abs(out.dissipated - works)[rough] <= 1e-9 * scale[rough])


@pytest.mark.parametrize("law", HYPOTHESES)
def test_planar_parity_with_the_single_impact_solver(law) -> None:
    """1200 random planar impacts per hypothesis (every regime: slip, slip-stick,
    slip-reversal, stick, none, frictionless): equal to solve_impact's to 1e-12 cond(K)."""
    case = _cases(True, 1200, 20261201 + HYPOTHESES.index(law))
    _check_parity(case, law, 1e-12)


@pytest.mark.parametrize("law", HYPOTHESES)
def test_3d_parity_with_the_single_impact_solver(law) -> None:
    """150 random 3D impacts per hypothesis, the slip direction turning: equal to
    solve_impact's to the batch integrator's tolerance, ``RTOL cond(K)`` (DOP853 at
    ``carnot.batch.coulomb.RTOL = 1e-10`` against solve_impact's at 1e-12, in other
    variables, with other steps and event searches; seen: 3e-11 cond(K) at most)."""
    case = _cases(False, 150, 20261211 + HYPOTHESES.index(law))
    _check_parity(case, law, RTOL)


# ----------------------------------------------------------- published closed forms


def _rod_batch(thetas, velocities, mu, e, law, mass=1.3, length=0.8, convert=np.asarray):
    """Slender rods (Stronge 2000 ch. 5) in the x-z plane striking a rough floor with their
    lower end at the origin, one row per case (arrays made by ``convert``)."""
    axes = np.stack([np.cos(thetas), np.zeros_like(thetas), np.sin(thetas)], -1)
    inertia = np.array([rod(mass, length, 1e-4, axis=ax) for ax in axes])
    n = len(thetas)
    bodies = BatchBodies(mass=convert(np.full(n, float(mass))), inertia_com=convert(inertia),
                         position_com=convert(0.5 * length * axes),
                         velocity_com=convert(np.asarray(velocities, dtype=float)))  # fmt: skip
    return point_impacts(bodies, None, convert(np.zeros(3)), convert(np.array([0, 0, 1.0])),
                         convert(np.full(n, float(e))), friction=convert(np.asarray(mu, float)),
                         law=law)  # fmt: skip


ROD_CASES = [(40.0, 1.5, 0.1), (40.0, 0.3, 0.7), (40.0, 0.3, 0.2), (60.0, -0.1, 0.6),
             (25.0, 0.2, 0.1)]  # fmt: skip


@pytest.mark.parametrize("law", HYPOTHESES)
def test_stronge_rod_on_a_rough_half_space(law) -> None:
    """Slip, slip-stick and slip-reversal of Stronge's rod, one batch per hypothesis."""
    e, w_n0, mass = 0.6, -1.0, 1.3
    thetas = np.radians([c[0] for c in ROD_CASES])
    velocities = [[w_t0, 0.0, w_n0] for _, w_t0, _ in ROD_CASES]
    mu = np.array([c[2] for c in ROD_CASES])
    out = _rod_batch(thetas, velocities, mu, e, law, mass=mass)
    for i, (theta, w_t0, m) in enumerate(ROD_CASES):
        w_n, w_t, regime = _planar_closed_form(math.radians(theta), mass, w_n0, w_t0, m, e, law)
        assert REGIME_NAMES[int(out.regime[i])] == regime
        after = out.relative_velocity_after[i]
        assert after[2] == pytest.approx(w_n, rel=1e-12, abs=1e-13)
        assert after[0] == pytest.approx(w_t, rel=1e-12, abs=1e-13)
        assert abs(after[1]) < 1e-13
    assert np.allclose(out.dissipated, out.dissipated_theorem, rtol=1e-12, atol=1e-14)


def test_stronge_rod_dropped_vertically_sticks_exactly_above_mu_bar() -> None:
    """mu_bar = beta_2 / beta_1 = 3 sin cos / (1 + 3 sin^2) (Stronge 2000 ch. 5): stick just
    above it, slip just below; a mask per row."""
    thetas = np.radians([15.0, 35.0, 55.0, 75.0])
    mu_bar = 3 * np.sin(thetas) * np.cos(thetas) / (1 + 3 * np.sin(thetas) ** 2)
    both = np.concatenate([thetas, thetas])
    mu = np.concatenate([mu_bar * 1.001, mu_bar * 0.999])
    out = _rod_batch(both, [[0, 0, -2.0]] * 8, mu, 0.4, "poisson")
    assert [REGIME_NAMES[int(r)] for r in out.regime] == ["stick"] * 4 + ["slip"] * 4


def test_newton_with_friction_creates_energy_and_flags_it() -> None:
    """The rod at 55 degrees, e = 1, slip stopping (Kane and Levinson 1985; Stronge 1990):
    Newton gains energy, and says so; Stronge's hypothesis dissipates."""
    newton = _rod_batch(np.radians([55.0]), [[0.7, 0, -1.0]], 0.5, 1.0, "newton")
    assert newton.after[0] > newton.before[0] and newton.energy_gain[0]
    assert newton.law_flags[0] & NORMAL_WORK_GAIN and newton.law_flags[0] & HYPOTHESIS_ENERGY_GAIN
    stronge = _rod_batch(np.radians([55.0]), [[0.7, 0, -1.0]], 0.5, 1.0, "stronge")
    assert stronge.dissipated[0] >= 0 and stronge.law_flags[0] == 0


BALL_CASES = [([3.0, 0.0, -4.0], [0.0, 0.0, 0.0], 0.1), ([3.0, 0.0, -4.0], [0.0, 0.0, 0.0], 0.5),
              ([2.0, 0.0, -4.0], [0.0, -150.0, 0.0], 0.25),
              ([2.0, 0.0, -4.0], [0.0, -150.0, 0.0], 0.9),
              ([1.0, -2.0, -3.0], [40.0, 10.0, 5.0], 0.4)]  # fmt: skip


@pytest.mark.parametrize("law", HYPOTHESES)
def test_spinning_ball_gross_slip_or_rolling_exit(law) -> None:
    """A tennis-like ball (Brach 1991 ch. 4; Cross 2002): gross slip ``v_t'' = v_t - mu (1 +
    e) |v_n| s`` when ``mu (1 + e) |v_n| < 2/7 |slip|``, else it leaves rolling, ``v_t'' = (5
    v_t + 2 R omega x n) / 7``; ``v_n'' = -e v_n`` either way."""
    radius, mass, e = 0.033, 0.057, 0.7
    v = np.array([c[0] for c in BALL_CASES])
    om = np.array([c[1] for c in BALL_CASES])
    mu = np.array([c[2] for c in BALL_CASES])
    ball = BatchBodies(mass=mass, inertia_com=solid_sphere(mass, radius),
                       position_com=[0, 0, radius], velocity_com=v, angular_velocity=om)
    out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], e, friction=mu, law=law)
    slip = v[:, :2] + np.cross(om, [0, 0, -radius])[:, :2]
    speed = np.linalg.norm(slip, axis=1)
    gross = mu * (1 + e) * np.abs(v[:, 2]) < 2 / 7 * speed
    names = [REGIME_NAMES[int(r)] for r in out.regime]
    assert names == ["slip" if g else "slip-stick" for g in gross]
    rolling = (5 * v[:, :2] + 2 * radius * np.stack([om[:, 1], -om[:, 0]], -1)) / 7
    sliding = v[:, :2] - (mu * (1 + e) * np.abs(v[:, 2]) / speed)[:, None] * slip
    expected = np.where(gross[:, None], sliding, rolling)
    assert np.allclose(out.velocity_a[:, :2], expected, rtol=1e-12, atol=1e-12)
    assert np.allclose(out.velocity_a[:, 2], -e * v[:, 2], rtol=1e-12)


# ------------------------------------------------------------- backends, masks, shapes


def test_compiled_build_equals_the_array_build() -> None:
    """The same formulas through Numba and through NumPy arrays (masks), planar and 3D."""
    for planar, seed in ((True, 7), (False, 8)):
        case = _cases(planar, 200, seed)
        for law in HYPOTHESES:
            for (_, mine), (_, theirs) in zip(_batch(case, law, "numba"),
                                              _batch(case, law, "array"), strict=True):  # fmt: skip
                assert np.array_equal(mine.regime, theirs.regime)
                assert np.array_equal(mine.law_flags, theirs.law_flags)
                scale = np.linalg.norm(theirs.impulse, axis=-1)
                assert np.all(np.linalg.norm(mine.impulse - theirs.impulse, axis=-1)
                              <= 1e-12 * scale)  # fmt: skip
                assert np.allclose(mine.work_normal_compression, theirs.work_normal_compression,
                                   rtol=1e-12, atol=0, equal_nan=True)  # fmt: skip


def test_array_api_strict_runs_the_coulomb_laws() -> None:
    xps = pytest.importorskip("array_api_strict")
    case = _cases(False, 12, 9)
    s, a, b = _split(case)[1]

    def strict(x):
        return xps.asarray(np.asarray(x, dtype=np.float64))

    bodies = [BatchBodies(**{f: strict(getattr(x, f)) for f in FIELDS}) for x in (a, b)]
    for law in ("stronge", "newton"):
        ref = point_impacts(a, b, case["point"][s], case["normal"][s], case["e"][s],
                            friction=case["mu"][s], law=law)  # fmt: skip
        out = point_impacts(bodies[0], bodies[1], strict(case["point"][s]),
                            strict(case["normal"][s]), strict(case["e"][s]),
                            friction=strict(case["mu"][s]), law=law)  # fmt: skip
        assert np.allclose(np.asarray(out.impulse), ref.impulse, rtol=1e-12, atol=1e-14)
        assert np.array_equal(np.asarray(out.regime), ref.regime)


def test_jax_runs_the_coulomb_laws_eagerly() -> None:
    """JAX arrays (float64 enabled) through the array build: planar rows (the exact route,
    no adaptive loop: JAX dispatches op by op, which a 3D loop would make slow)."""
    jax = pytest.importorskip("jax")
    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    # Stronge's rod cases: planar, every regime of the exact route
    e, mass = 0.6, 1.3
    thetas = np.radians([c[0] for c in ROD_CASES])
    velocities = [[w_t0, 0.0, -1.0] for _, w_t0, _ in ROD_CASES]
    mu = np.array([c[2] for c in ROD_CASES])
    ref = _rod_batch(thetas, velocities, mu, e, "stronge", mass=mass)
    out = _rod_batch(thetas, velocities, mu, e, "stronge", mass=mass, convert=jnp.asarray)
    assert isinstance(out.impulse, jax.Array)
    assert np.allclose(np.asarray(out.impulse), ref.impulse, rtol=1e-12, atol=1e-14)
    assert np.array_equal(np.asarray(out.regime), ref.regime)


def test_masks_frictionless_rows_not_approaching_and_shapes() -> None:
    """mu = 0 rows give the frictionless answer (regime FRICTIONLESS); a ball moving away
    gets no impulse (regime NONE); one impact is the () case; arguments broadcast."""
    ball = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.4, position_com=[0, 0, 1.0],
                       velocity_com=[1.0, 0, -1.0])  # fmt: skip
    mu = np.array([0.0, 0.1, 0.0, 0.5])
    out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], 0.5, friction=mu, law="stronge")
    free = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], 0.5)
    assert out.regime.tolist() == [FRICTIONLESS, 2, FRICTIONLESS, 3]
    assert np.all(out.impulse[mu == 0] == free.impulse)
    assert np.isnan(out.work_normal_compression[0]) and out.law_flags.dtype == np.uint8
    away = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.4, position_com=[0, 0, 1.0],
                       velocity_com=[1.0, 0, 0.5])  # fmt: skip
    one = point_impacts(away, None, [0, 0, 0], [0, 0, 1], 0.5, friction=0.3, law="newton")
    assert one.impulse.shape == (3,) and one.regime.shape == ()
    assert int(one.regime) == NONE and np.all(one.impulse == 0) and bool(one.not_approaching)
    grid = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.linspace(0, 1, 4)[:, None],
                         friction=np.array([0.05, 0.3, 1.0]), law="poisson")  # fmt: skip
    assert grid.impulse.shape == (4, 3, 3) and grid.regime.shape == (4, 3)
    # a ball at rest in the tangent plane sticks (never slipped): STICK
    drop = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.4, position_com=[0, 0, 1.0],
                       velocity_com=[0.0, 0, -1.0])  # fmt: skip
    assert int(point_impacts(drop, None, [0, 0, 0], [0, 0, 1], 0.5, friction=0.3).regime) == STICK


def test_dop853_tableaux_are_scipys() -> None:
    """The DOP853 coefficients written out in carnot.batch.coulomb (scalars, for the compiled
    and array builds) and carnot.laws.slip3d (arrays) are SciPy's, entry by entry: a
    transcription checked against its source, not against itself."""
    import re

    from scipy.integrate._ivp import dop853_coefficients as dop

    from carnot.batch import coulomb
    from carnot.laws import slip3d

    tables = {"A": dop.A, "B": dop.B, "C": dop.C, "E3": dop.E3, "E5": dop.E5}
    checked = 0
    for name, value in vars(coulomb).items():
        match = re.fullmatch(r"_(A|B|C|E3|E5)_?(\d+)(?:_(\d+))?", name)
        if match and isinstance(value, float):
            kind, i, j = match.groups()
            index = (int(i),) if j is None else (int(i), int(j))
            assert value == tables[kind][index], name
            checked += 1
    assert checked == 85
    for mine, theirs in ((slip3d._A, dop.A), (slip3d._B, dop.B), (slip3d._C, dop.C),
                         (slip3d._E3, dop.E3), (slip3d._E5, dop.E5)):  # fmt: skip
        mine = np.asarray(mine)
        np.testing.assert_array_equal(mine, theirs[tuple(slice(0, n) for n in mine.shape)])


def test_3d_slip_passes_compile_to_a_vectorized_loop() -> None:
    """The 3D slip's passes run across lanes (impacts whose slip turns) in one loop that the
    compiler vectorizes: its machine code multiplies and fuses packed vectors of doubles. A
    call, an ``exp`` or ``pow`` (no vector form here) or a loop of a lane's own length in
    :func:`carnot.batch.coulomb.slip_pass` would silently turn that off (3 to 7 times
    slower): this is the guard. Compiled afresh (a kernel loaded from Numba's cache keeps
    no machine code), on no lanes."""
    import re

    import numba

    from carnot.batch.compiled import BLOCK, LANE_WIDTH, PITCH, lane_kernel

    kernel = numba.njit(error_model="numpy", fastmath={"contract"})(
        lane_kernel("coulomb_stronge").py_func)  # fmt: skip
    kernel(np.zeros(LANE_WIDTH * PITCH), np.zeros(BLOCK, np.int64), 0, STRONGE)
    code = "".join(kernel.inspect_asm(sig) for sig in kernel.signatures)
    packed = re.findall(r"\bv(?:mul|fn?madd\d+|fn?msub\d+)pd\s+%[yz]mm", code)
    assert len(packed) > 500

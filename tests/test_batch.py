"""carnot.batch: the array kernels against the single-impact solver (parity to 1e-12), their
broadcasting, masks and refusals."""

from __future__ import annotations

import functools
import platform
import re

import numba
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from carnot import FixedBody, ImpactProblem, InputError, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies, BatchImpacts, point_impacts
from carnot.batch.compiled import BLOCK, STREAM_MIN_BYTES, compute_kernel, hypothesis
from carnot.batch.kernels import FRICTIONLESS, PARALLEL_MIN, STICK
from carnot.batch.pipeline import FLOAT_WIDTH, INT_WIDTH
from carnot.model.free_bodies import assemble


def _random_bodies(rng: np.random.Generator, n: int, decades: float = 3.0,
                   smallest: float = -1.5, speed: float = 10.0) -> BatchBodies:  # fmt: skip
    """Masses from 10^-decades to 10^decades kg, sizes from 10^smallest to 3 m, realizable
    inertias in random principal axes, speeds up to ``speed`` (m/s, rad/s)."""
    mass = 10 ** rng.uniform(-decades, decades, n)
    size = 10 ** rng.uniform(smallest, 0.5, n)
    a, b = rng.uniform(0.05, 1.0, (2, n))
    c = rng.uniform(np.maximum(np.abs(a - b), 1e-3), a + b)
    moments = np.stack([a, b, c], -1) * (mass * size**2)[:, None]
    rot = Rotation.random(n, random_state=rng).as_matrix()
    inertia = rot @ (moments[:, :, None] * np.eye(3)) @ np.swapaxes(rot, -1, -2)
    return BatchBodies(mass=mass, inertia_com=inertia, position_com=rng.uniform(-2, 2, (n, 3)),
                       velocity_com=rng.uniform(-speed, speed, (n, 3)),
                       angular_velocity=rng.uniform(-speed, speed, (n, 3)))  # fmt: skip


def _one(bodies: BatchBodies, k: int, name: str) -> RigidBody:
    return RigidBody(name=name, mass=bodies.mass[k], inertia_com=bodies.inertia_com[k],
                     position_com=bodies.position_com[k], velocity_com=bodies.velocity_com[k],
                     angular_velocity=bodies.angular_velocity[k])  # fmt: skip


@pytest.mark.parametrize("tangential", ["slip", "stick"])
@pytest.mark.parametrize("obstacle", [False, True])
def test_parity_with_the_single_impact_solver(tangential, obstacle) -> None:
    """300 random impacts: the batch answer equals carnot.solve_impact's to 1e-12."""
    rng = np.random.default_rng(20261123 + obstacle + 2 * (tangential == "stick"))
    n = 300
    a = _random_bodies(rng, n)
    b = None if obstacle else _random_bodies(rng, n)
    point = rng.uniform(-2, 2, (n, 3))
    normal = rng.normal(size=(n, 3))
    e = rng.uniform(0, 1, n)
    out = point_impacts(a, b, point, normal, e, tangential=tangential)
    for k in range(n):
        bodies = {"a": _one(a, k, "a"),
                  "b": FixedBody(name="b") if b is None else _one(b, k, "b")}  # fmt: skip
        ref = solve_impact(ImpactProblem(bodies=bodies, contacts=[PointContact(
            a="a", b="b", point=point[k], normal=normal[k], restitution=e[k],
            tangential=tangential)]))  # fmt: skip
        # 1e-12 relative, times the condition number of the contact's inverse mass K: the
        # two routes solve with K differently (here a batched solve, there an
        # eigendecomposition of the Delassus operator), so their round-off differs by that.
        problem = ImpactProblem(bodies=bodies, contacts=[PointContact(
            a="a", b="b", point=point[k], normal=normal[k], restitution=e[k],
            tangential=tangential)])  # fmt: skip
        space = assemble(problem, problem.contacts, [c.rows() for c in problem.contacts]).space
        rel = 1e-12 * np.linalg.cond(space.delassus())
        c = ref.contacts[0]
        size = np.linalg.norm(c.impulse)
        assert np.linalg.norm(out.impulse[k] - c.impulse) <= rel * size + 1e-300
        dv = out.velocity_a[k] - ref.bodies["a"].velocity_after
        assert np.linalg.norm(dv) <= rel * size / a.mass[k] + 1e-300
        en = ref.energy
        for mine, theirs in ((out.before[k], en.before), (out.dissipated[k], en.dissipated),
                             (out.dissipated_theorem[k], en.dissipated_theorem),
                             (out.lost_velocities[k], en.lost_velocities)):  # fmt: skip
            assert abs(mine - theirs) <= rel * en.before + 1e-300
        assert out.not_approaching[k] == ("not_approaching" in ref.flag_codes())
        assert out.negative_normal_impulse[k] == ("negative_normal_impulse" in ref.flag_codes())
    # the theorem against the direct difference, on every impact
    assert np.all(np.abs(out.dissipated - out.dissipated_theorem) <= 1e-11 * out.before)


def test_one_impact_is_the_empty_shape_and_arguments_broadcast() -> None:
    ball = BatchBodies(mass=2.0, inertia_com=np.eye(3) * 0.02, position_com=[0, 0, 0.1],
                       velocity_com=[1.0, 0, -3.0])  # fmt: skip
    one = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], 0.6)
    assert one.impulse.shape == (3,) and one.dissipated.shape == ()
    # Newton's closed form for a sphere-like body hit under its centre: v_z'' = -e v_z
    assert one.velocity_a.tolist() == pytest.approx([1.0, 0.0, 1.8])
    assert float(one.dissipated) == pytest.approx(0.5 * 2.0 * 9 * (1 - 0.36))
    grid = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.linspace(0, 1, 5)[:, None]
                         * np.ones((5, 4)))  # fmt: skip
    assert grid.impulse.shape == (5, 4, 3) and grid.regime.shape == (5, 4)
    assert np.all(grid.regime == FRICTIONLESS)


def test_masks_for_stick_and_its_friction() -> None:
    """A ball sliding at 1 m/s lands at 1 m/s: sticking needs mu = (2/7) 1 / (1 + e) (Brach
    1991): a mask per impact, not a branch."""
    ball = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.4, position_com=[0, 0, 1.0],
                       velocity_com=[1.0, 0, -1.0])  # fmt: skip
    e = 0.5
    mu = np.array([0.1, 0.2, 0.3])
    out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], e, tangential="stick", friction=mu)
    needed = (2 / 7) / (1 + e)
    assert np.all(out.regime == STICK)
    assert out.friction_required == pytest.approx(np.full(3, needed))
    assert out.friction_insufficient.tolist() == (mu < needed).tolist()


def test_refusals_name_the_field() -> None:
    ball = BatchBodies(mass=1.0, inertia_com=np.eye(3), position_com=[0, 0, 1.0])
    with pytest.raises(InputError, match=r"restitution: must be in \[0, 1\]"):
        point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.array([0.5, 1.5]))
    with pytest.raises(InputError, match="normal: must be non-zero"):
        point_impacts(ball, None, [0, 0, 0], [0, 0, 0], 0.5)


# ------------------------------------------------------- backends: one source, two compilers


def _case(rng: np.random.Generator, n: int, obstacle: bool) -> dict:
    a = _random_bodies(rng, n)
    return dict(a=a, b=None if obstacle else _random_bodies(rng, n),
                point=rng.uniform(-2, 2, (n, 3)), normal=rng.normal(size=(n, 3)),
                restitution=rng.uniform(0, 1, n))  # fmt: skip


def _convert(case: dict, conv) -> dict:  # type: ignore[no-untyped-def]
    def body(s: BatchBodies | None) -> BatchBodies | None:
        if s is None:
            return None
        return BatchBodies(mass=conv(s.mass), inertia_com=conv(s.inertia_com),
                           position_com=conv(s.position_com), velocity_com=conv(s.velocity_com),
                           angular_velocity=conv(s.angular_velocity))  # fmt: skip

    return dict(a=body(case["a"]), b=body(case["b"]), point=conv(case["point"]),
                normal=conv(case["normal"]), restitution=conv(case["restitution"]))  # fmt: skip


def _condition(case: dict) -> np.ndarray:
    """cond(K) of each impact's inverse mass at the contact (NumPy, independently of the
    kernels): the factor by which round-off in one route can differ from another's."""

    def share(s: BatchBodies) -> np.ndarray:
        r = case["point"] - s.position_com
        z = np.zeros(len(r))
        cross = np.stack([np.stack([z, -r[:, 2], r[:, 1]], -1),
                          np.stack([r[:, 2], z, -r[:, 0]], -1),
                          np.stack([-r[:, 1], r[:, 0], z], -1)], -2)  # fmt: skip
        return (np.eye(3) / np.asarray(s.mass)[:, None, None]
                - cross @ np.linalg.inv(s.inertia_com) @ cross)

    k = share(case["a"]) + (0 if case["b"] is None else share(case["b"]))
    return np.linalg.cond(k)


def _assert_same(mine, ref, rel, cond=1.0) -> None:  # type: ignore[no-untyped-def]
    """Every output of ``mine`` equals ``ref``'s, floats to ``rel`` times ``cond`` (per impact)
    of their column's scale."""
    for name, value in ref.as_columns().items():
        got = np.asarray(mine.as_columns()[name])
        want = np.asarray(value)
        if want.dtype.kind == "f":
            scale = np.nanmax(np.abs(want)) if np.any(np.isfinite(want)) else 1.0
            tol = rel * np.asarray(cond) * scale + 1e-300
            both_nan = np.isnan(got) & np.isnan(want)
            bad = ~both_nan & ~(np.abs(got - want) <= tol)
            assert not np.any(bad), (name, got[bad][:3], want[bad][:3])
        else:
            assert np.array_equal(got, want), name


@pytest.mark.parametrize("tangential", ["slip", "stick"])
@pytest.mark.parametrize("obstacle", [False, True])
def test_compiled_and_array_backends_agree(tangential, obstacle) -> None:
    """The Numba build and the NumPy array build of the same formulas give the same numbers,
    every output, to round-off (LLVM contracts some multiply-adds into FMAs, which a solve
    with K amplifies by up to cond(K))."""
    case = _case(np.random.default_rng(7 + obstacle), 400, obstacle)
    compiled = point_impacts(**case, tangential=tangential, backend="numba")
    arrays = point_impacts(**case, tangential=tangential, backend="array")
    _assert_same(arrays, compiled, 1e-13, _condition(case))


@pytest.mark.parametrize(("tangential", "friction"), [("slip", 0.0), ("stick", 0.0),
                                                      ("slip", 0.4)])  # fmt: skip
def test_blocks_and_cores(tangential, friction) -> None:
    """A batch longer than PARALLEL_MIN and than a block, of a length no block divides: the
    parallel build equals the serial build bit for bit (each impact is computed alone, in
    the same order of operations; Coulomb friction too, through its split block) and, for
    the straight-line laws, the array build to round-off; a bad inertia tensor in the middle
    of a late block is named with its index."""
    n = PARALLEL_MIN + 3 * BLOCK + 37
    case = {**_case(np.random.default_rng(11), n, obstacle=False), "friction": friction}
    both = point_impacts(**case, tangential=tangential, parallel=True)
    one = point_impacts(**case, tangential=tangential, parallel=False)
    for name, value in both.as_columns().items():
        assert np.array_equal(value, one.as_columns()[name], equal_nan=True), name
    if friction == 0:  # (Coulomb's builds are compared in test_batch_coulomb.py)
        arrays = point_impacts(**case, tangential=tangential, backend="array")
        _assert_same(arrays, both, 1e-13, _condition(case))
    else:
        assert np.any(both.regime != FRICTIONLESS)
    bad = n - BLOCK // 2 - 1
    inertia = case["a"].inertia_com.copy()
    inertia[bad] = np.diag([1.0, 1.0, 2.5])
    a = BatchBodies(**{**vars(case["a"]), "inertia_com": inertia})
    with pytest.raises(InputError, match=rf"a\.inertia_com\[{bad}\]: must be symmetric"):
        point_impacts(**{**case, "a": a}, tangential=tangential)


def test_outputs_too_large_for_cache_are_written_around_it_with_the_same_numbers() -> None:
    """A batch whose float outputs exceed STREAM_MIN_BYTES is written by non-temporal stores
    (x86-64): the same numbers, bit for bit, as the same impacts in small batches."""
    n = STREAM_MIN_BYTES // (FLOAT_WIDTH * 8) + 1001
    case = _case(np.random.default_rng(12), n, obstacle=True)
    big = point_impacts(**case).as_columns()
    for start in (0, n // 2, n - 1000):
        part = slice(start, start + 1000)
        small = point_impacts(BatchBodies(**{k: v[part] for k, v in vars(case["a"]).items()}),
                              None, case["point"][part], case["normal"][part],
                              case["restitution"][part]).as_columns()  # fmt: skip
        for name, value in small.items():
            assert np.array_equal(big[name][part], value, equal_nan=True), name


def test_out_reuses_an_earlier_results_memory() -> None:
    """``out=``: a second batch written into the first one's memory gives the numbers a
    fresh call gives; a result of another size, of the array backend or of float32 input
    is refused, naming ``out``."""
    rng = np.random.default_rng(13)
    first, second = _case(rng, 500, obstacle=False), _case(rng, 500, obstacle=False)
    earlier = point_impacts(**first)
    fresh = point_impacts(**second, tangential="stick").as_columns()
    reused = point_impacts(**second, tangential="stick", out=earlier)
    assert np.shares_memory(reused.impulse, earlier.impulse)
    for name, value in reused.as_columns().items():
        assert np.array_equal(value, fresh[name], equal_nan=True), name
    with pytest.raises(InputError, match=r"out: must have the batch's 499 impacts, got 500"):
        point_impacts(**{**second, "restitution": second["restitution"][:499],
                         "point": second["point"][:499], "normal": second["normal"][:499],
                         "a": BatchBodies(**{k: v[:499] for k, v in vars(second["a"]).items()}),
                         "b": BatchBodies(**{k: v[:499] for k, v in vars(second["b"]).items()})},
                      out=earlier)  # fmt: skip
    with pytest.raises(InputError, match="out: must be a float64 result of the compiled"):
        point_impacts(**second, backend="array", out=earlier)
    with pytest.raises(InputError, match="out: must be a float64 result of the compiled"):
        point_impacts(**second, out=point_impacts(**second, backend="array"))


@functools.cache
def _fresh_block(law: str):  # type: ignore[no-untyped-def]
    """The block kernel of ``law`` and its compute pass compiled afresh, without Numba's cache
    (a function loaded from the cache keeps no machine code, nor counts its compilations);
    once per law for the tests below (10 s each), which add only signatures the other would
    (the inputs of ``_at_rest`` in the first of the layouts)."""
    from carnot.batch.compiled import _copy, block_kernel

    compute = numba.njit(error_model="numpy")(compute_kernel(law).py_func)
    fn = block_kernel(law).py_func
    block = numba.njit(error_model="numpy")(
        _copy(fn, {**fn.__globals__, "compute": compute}, fn.__qualname__))  # fmt: skip
    return block, compute


def _at_rest(block, n: int, e, point):  # type: ignore[no-untyped-def]
    """``block`` on ``n`` impacts of 2 bodies at rest one above the other: ``out_float``."""
    one, vec, eye = np.ones(n), np.zeros((n, 3)), np.broadcast_to(np.eye(3), (n, 3, 3))
    out_float, out_int = np.empty((n, FLOAT_WIDTH)), np.empty((n, INT_WIDTH), np.int8)
    block(0, n, one, eye, vec + 1, vec, vec, one, eye, vec - 1, vec, vec, 1.0, point,
          vec + 1, e, one, out_float, out_int, False, hypothesis("stick"))  # fmt: skip
    assert np.all(out_float[:, 3] == 0) and np.all(out_int[:, 1] == 1)  # P_n = 0: not approaching
    return out_float


def test_the_compute_pass_compiles_once_per_law_whatever_the_layouts() -> None:
    """Inputs of other layouts (a value broadcast to every impact, a strided view) compile new
    gathers and scatters around the same compute pass: the pass, where a Coulomb law takes
    most of a minute to compile, is compiled once per law (it read the caller's arrays once,
    and each new combination of strides compiled the whole law again: CI went from 6.5 to
    12 minutes)."""
    block, compute = _fresh_block("stick")
    n = 6
    layouts = ((np.ones(n), np.zeros((n, 3))), (np.broadcast_to(1.0, (n,)), np.zeros((n, 3))),
               (np.ones(n), np.zeros((2 * n, 3))[::2]))  # fmt: skip
    outs = [_at_rest(block, n, e, point) for e, point in layouts]
    for out in outs[1:]:
        np.testing.assert_array_equal(out, outs[0])
    assert len(block.signatures) == 3
    assert len(compute.signatures) == 1


def test_the_driver_is_built_once_whatever_the_layouts() -> None:
    """A fixed obstacle (its fields broadcast), the restitution one value or one per impact,
    a strided normal, a contiguous or writable array: every call takes the driver's one
    build (carnot.batch.compiled.SIGNATURE), with the same answers as the contiguous
    inputs'. Typed by layout, each combination built the driver and its block again (the
    Coulomb kernel's 7-10 s each: 31 builds of the three kernels in the test suite)."""
    from carnot.batch.compiled import driver

    rng = np.random.default_rng(5)
    case = _case(rng, 40, True)
    base = point_impacts(**case, backend="numba", parallel=False)
    normal = np.zeros((80, 3))
    normal[::2] = case["normal"]
    variants = [dict(case, restitution=0.5), dict(case, normal=normal[::2]),
                dict(case, b=_random_bodies(rng, 40))]  # fmt: skip
    outs = [point_impacts(**v, backend="numba", parallel=False) for v in variants]
    full = point_impacts(**dict(case, restitution=np.full(40, 0.5)), backend="numba",
                         parallel=False)  # fmt: skip
    np.testing.assert_array_equal(outs[0].impulse, full.impulse)
    np.testing.assert_array_equal(outs[1].impulse, base.impulse)
    assert np.all(np.isfinite(outs[2].impulse)) and outs[2].velocity_b is not None
    assert len(driver("frictionless", False).signatures) == 1


@pytest.mark.skipif(platform.machine().lower() not in ("x86_64", "amd64"),
                    reason="the check reads x86-64 machine code")  # fmt: skip
@pytest.mark.parametrize("law", ["frictionless", "stick"])
def test_straight_line_laws_compile_to_a_vectorized_loop(law) -> None:
    """The compute loop of the frictionless and stick kernels is vectorized across impacts:
    their machine code multiplies packed vectors of doubles (``mulpd``). A branch or a call
    in a formula would silently turn that off (and cost about 2x): this is the guard."""
    block, compute = _fresh_block(law)
    _at_rest(block, 4, np.ones(4), np.zeros((4, 3)))
    code = "".join(compute.inspect_asm(sig) for sig in compute.signatures)
    assert len(re.findall(r"\bv?mulpd\b", code)) > 100


def test_array_api_strict_jax_and_dask_give_numpys_answer() -> None:
    """The array build runs on any array-API namespace and returns that namespace's arrays:
    array_api_strict (the standard and nothing more), JAX (float64 enabled) and Dask."""
    import array_api_strict as xs
    import dask.array as da
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    case = _case(np.random.default_rng(11), 60, False)
    ref = point_impacts(**case, tangential="stick")
    for conv, kind in ((xs.asarray, type(xs.asarray(0.0))), (jnp.asarray, jax.Array),
                       (lambda x: da.from_array(np.asarray(x), chunks=25), da.Array)):  # fmt: skip
        out = point_impacts(**_convert(case, conv), tangential="stick")
        assert isinstance(out.impulse, kind) and isinstance(out.regime, kind)
        if kind is da.Array:
            (computed,) = da.compute(out.as_columns())
            out = BatchImpacts(**{**{f: None for f in BatchImpacts.__dataclass_fields__},
                                  **_uncolumn(computed)})  # fmt: skip
        _assert_same(out, ref, 1e-13, _condition(case))


def _uncolumn(columns: dict) -> dict:
    """BatchImpacts fields from ``as_columns`` output."""
    out: dict = {}
    for name, value in columns.items():
        stem, _, axis = name.rpartition("_")
        if axis in ("x", "y", "z") and stem:
            out.setdefault(stem, [None] * 3)["xyz".index(axis)] = np.asarray(value)
        else:
            out[name] = np.asarray(value)
    return {k: np.stack(v, -1) if isinstance(v, list) else v for k, v in out.items()}


@pytest.mark.parametrize("backend", ["numba", "array"])
def test_float32_in_float32_out_with_documented_accuracy(backend) -> None:
    """float32 inputs give float32 outputs within 1e-5 of the float64 answer (relative to the
    column's scale; the README's figure): the compiled build computes in float64 and rounds
    once, the array build computes in float32."""
    case = _case(np.random.default_rng(3), 300, False)
    ref = point_impacts(**case)
    single = point_impacts(**_convert(case, lambda x: np.asarray(x, dtype=np.float32)),
                           backend=backend)  # fmt: skip
    assert single.impulse.dtype == np.float32 and single.dissipated.dtype == np.float32
    for name in ("impulse", "velocity_a", "angular_velocity_b", "before", "after"):
        want, got = getattr(ref, name), getattr(single, name).astype(float)
        # relative to each impact's own scale, times the conditioning of its inverse mass
        assert np.nanmax(np.abs(got - want)) <= 1e-5 * np.nanmax(np.abs(want)) * 10, name


def test_bad_inertia_is_named_with_its_index() -> None:
    """A tensor that is not positive definite, not symmetric, or not realizable (one moment
    larger than the sum of the other two) is refused, naming the body and the impact."""
    good = np.eye(3)
    for bad in (np.diag([1.0, 1.0, -1.0]), np.array([[1, 0.5, 0], [0, 1, 0], [0, 0, 1.0]]),
                np.diag([1.0, 1.0, 2.5])):  # fmt: skip
        tensors = np.stack([good, good, bad, good])
        a = BatchBodies(mass=1.0, inertia_com=tensors, position_com=[0, 0, 1.0])
        for backend in ("numba", "array"):
            with pytest.raises(InputError, match=r"a\.inertia_com\[2\]: must be symmetric"):
                point_impacts(a, None, [0, 0, 0], [0, 0, 1], 0.5, backend=backend)
    b = BatchBodies(mass=1.0, inertia_com=np.diag([1.0, 1.0, 2.5]), position_com=[0, 0, -1.0])
    with pytest.raises(InputError, match=r"b\.inertia_com: must be symmetric"):
        point_impacts(BatchBodies(mass=1.0, inertia_com=good, position_com=[0, 0, 1.0]), b,
                      [0, 0, 0], [0, 0, 1], 0.5)  # fmt: skip


def test_other_bad_inputs_name_the_field() -> None:
    ball = BatchBodies(mass=np.array([1.0, -2.0]), inertia_com=np.eye(3), position_com=[0, 0, 1.0])
    with pytest.raises(InputError, match=r"a\.mass: must be > 0 kg, got \[-2\.0\]"):
        point_impacts(ball, None, [0, 0, 0], [0, 0, 1], 0.5)
    ok = BatchBodies(mass=1.0, inertia_com=np.eye(3), position_com=[0, 0, 1.0])
    with pytest.raises(InputError, match="point: must be finite"):
        point_impacts(ok, None, [0, np.nan, 0], [0, 0, 1], 0.5)
    with pytest.raises(InputError, match=r"friction: must be >= 0"):
        point_impacts(ok, None, [0, 0, 0], [0, 0, 1], 0.5, tangential="stick", friction=-0.1)
    with pytest.raises(InputError, match=r"a\.inertia_com: must have trailing shape \(3, 3\)"):
        point_impacts(BatchBodies(mass=1.0, inertia_com=np.eye(2), position_com=[0, 0, 1.0]),
                      None, [0, 0, 0], [0, 0, 1], 0.5)  # fmt: skip
    with pytest.raises(InputError, match="batch shapes do not broadcast"):
        point_impacts(ok, None, np.zeros((4, 3)), [0, 0, 1], np.full(5, 0.5))
    with pytest.raises(InputError, match="backend: must be"):
        point_impacts(ok, None, [0, 0, 0], [0, 0, 1], 0.5, backend="gpu")
    with pytest.raises(InputError, match="law: must be"):
        point_impacts(ok, None, [0, 0, 0], [0, 0, 1], 0.5, law="kelvin")


def test_dask_runs_every_law_chunk_by_chunk() -> None:
    """Dask input: a lazy batch whose chunks are solved by the compiled kernel, Coulomb
    friction included; the answer is NumPy's, the shapes are the inputs', and a bad value
    raises when computed, naming its field."""
    import dask
    import dask.array as da

    rng = np.random.default_rng(17)
    case = _case(rng, 300, obstacle=True)
    mu = rng.uniform(0, 0.8, 300)
    ref = point_impacts(**case, friction=mu, law="stronge")
    lazy = _convert(case, lambda x: da.from_array(np.asarray(x), chunks=70))
    out = point_impacts(**lazy, friction=da.from_array(mu, chunks=70), law="stronge")
    assert isinstance(out.impulse, da.Array) and out.velocity_b is None
    (columns,) = dask.compute(out.as_columns())
    for name, value in ref.as_columns().items():
        np.testing.assert_array_equal(np.asarray(columns[name]), value, err_msg=name)
    # a batch of shape (3, 4) with a scalar body b: shapes come back as given
    grid = point_impacts(BatchBodies(mass=da.ones((3, 4)), inertia_com=np.eye(3),
                                     position_com=[0, 0, 1.0], velocity_com=[0, 0, -1.0]),
                         BatchBodies(mass=2.0, inertia_com=np.eye(3), position_com=[0, 0, -1.0]),
                         [0, 0, 0], [0, 0, 1], 0.5)  # fmt: skip
    assert grid.impulse.shape == (3, 4, 3) and grid.regime.shape == (3, 4)
    assert np.allclose(grid.impulse.compute()[..., 2], 1.5 / (1 + 1 / 2))
    bad = point_impacts(BatchBodies(mass=da.from_array(np.array([1.0, -1.0])),
                                    inertia_com=np.eye(3), position_com=[0, 0, 1.0]),
                        None, [0, 0, 0], [0, 0, 1], 0.5)  # fmt: skip
    with pytest.raises(InputError, match=r"a\.mass: must be > 0 kg"):
        bad.impulse.compute()

"""Batch kernels for two-body and body-obstacle 3D point impacts: the public entry point.

For a point contact with lever arms ``r_a = p - x_a`` and ``r_b = p - x_b`` the relative
velocity is an affine function of the impulse ``P`` that body ``a`` receives,

    w(P) = w' + K P,     K = I/m_a - [r_a]x J_a^-1 [r_a]x + I/m_b - [r_b]x J_b^-1 [r_b]x

(``[r]x`` the cross-product matrix; the ``b`` terms vanish for a fixed obstacle), which is the
contact block of the Delassus operator of :mod:`carnot.space`. The laws:

* frictionless (Newton, Poisson and Stronge coincide): ``P = -(1 + e) (n . w') / (n . K n) n``;
* stick (Newton's restitution, no slip after): ``P = K^-1 (w'' - w')`` with
  ``w'' = -e (n . w') n``; the friction coefficient it needs is ``|P_t| / P_n``;
* Coulomb friction with slip, stick and reversal under Newton, Poisson or Stronge
  (:mod:`carnot.batch.coulomb`, when ``friction > 0`` and ``tangential="slip"``).

Two backends run the same formulas (:mod:`carnot.batch.ops`): with NumPy input and Numba
installed, one compiled loop (one per straight-line law, one for the three Coulomb laws) does
the whole impact in registers, in parallel over the batch (``backend="numba"``, the default
for NumPy); any array-API namespace (NumPy, JAX, Dask,
array_api_strict) runs them as array expressions with masks (``backend="array"``).

Shapes: masses and coefficients ``(...)``, vectors ``(..., 3)``, inertia tensors
``(..., 3, 3)`` (world axes, about the centre of mass), all broadcast together; one impact is
the ``()`` case. Per-impact regimes and flags are masks, never Python branches on values.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, Literal

import numpy as np

from carnot import validate
from carnot.batch.laws import FRICTIONLESS, REGIME_NAMES, STICK
from carnot.batch.ops import STRAIGHT_LINE_LAWS, have_numba, specialize
from carnot.batch.pipeline import FLOAT_FIELDS, FLOAT_WIDTH, INT_FIELDS, INT_WIDTH
from carnot.errors import InputError
from carnot.laws.registry import check_hypothesis, contact_rule

__all__ = ["FRICTIONLESS", "STICK", "REGIME_NAMES", "BatchBodies", "BatchImpacts",
           "point_impacts"]  # fmt: skip

Backend = Literal["auto", "numba", "array"]
Hypothesis = Literal["newton", "poisson", "stronge"]


@dataclass(frozen=True, kw_only=True, eq=False)
class BatchBodies:
    """A batch of rigid bodies: ``mass`` (kg), ``inertia_com`` (kg m^2, world axes, about the
    centre of mass), ``position_com`` (m), ``velocity_com`` (m/s), ``angular_velocity``
    (rad/s). Any array type of the array API; each field broadcasts against the others."""

    mass: Any
    inertia_com: Any
    position_com: Any
    velocity_com: Any = 0.0
    angular_velocity: Any = 0.0


@dataclass(frozen=True, kw_only=True, eq=False)
class BatchImpacts:
    """What a batch of impacts produced, one entry per impact (shapes as the inputs').

    ``impulse`` (N s, world) is what ``a`` receives, ``normal_impulse`` its normal part;
    velocities after (m/s, rad/s; ``None`` for a fixed ``b``); relative velocities at the
    contact before and after (m/s, world); energies in J: ``before``, ``after``,
    ``dissipated`` (``E' - E''``, direct), ``dissipated_theorem`` (``-1/2 P . (w' + w'')``),
    its ``dissipated_normal`` and ``dissipated_tangential`` parts, ``lost_velocities``
    (Carnot's ``E_p``); ``friction_required`` (``|P_t| / P_n`` for stick, NaN otherwise);
    for Coulomb friction the normal impulse at maximum compression and the works of the
    normal and tangential impulses in compression and restitution (J; NaN for the other
    laws); ``regime`` (int8 codes of :data:`REGIME_NAMES`); boolean flags
    ``not_approaching``, ``negative_normal_impulse``, ``friction_insufficient``,
    ``energy_gain``; ``law_flags`` (uint8 bits of the Coulomb law's own warnings).

    With the compiled backend the float outputs are views into one ``(..., 35)`` block (one
    row per impact: a single pass of writes), so they are not contiguous.
    """

    impulse: Any
    normal_impulse: Any
    velocity_a: Any
    angular_velocity_a: Any
    velocity_b: Any | None
    angular_velocity_b: Any | None
    relative_velocity_before: Any
    relative_velocity_after: Any
    before: Any
    after: Any
    dissipated: Any
    dissipated_theorem: Any
    dissipated_normal: Any
    dissipated_tangential: Any
    lost_velocities: Any
    friction_required: Any
    compression_impulse: Any
    work_normal_compression: Any
    work_normal_restitution: Any
    work_tangential_compression: Any
    work_tangential_restitution: Any
    regime: Any
    not_approaching: Any
    negative_normal_impulse: Any
    friction_insufficient: Any
    energy_gain: Any
    law_flags: Any

    @classmethod
    def over_blocks(cls, blocks: tuple[Any, Any], fields: dict[str, Any]) -> BatchImpacts:
        """The result of these ``fields``, views into the compiled backend's float and int8
        ``blocks``, which it keeps (not a field: the memory behind the fields, which a later
        call given this result as ``out=`` writes into again)."""
        out = cls(**fields)
        object.__setattr__(out, "_blocks", blocks)  # (its own instance, just made)
        return out

    def as_columns(self) -> dict[str, Any]:
        """Flat named columns (vectors split as ``name_x``, ``name_y``, ``name_z``), for
        tables and files; fields that are ``None`` are left out."""
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            if f.name in _VECTOR_FIELDS:
                for k, axis in enumerate("xyz"):
                    out[f"{f.name}_{axis}"] = value[..., k]
            else:
                out[f.name] = value
        return out


_VECTOR_FIELDS = {name for name, width in FLOAT_FIELDS if width == 3}
_INVALID_FIELDS = ("invalid_input", "invalid_inertia_a", "invalid_inertia_b")
_BOOL_FIELDS = ("not_approaching", "negative_normal_impulse", "friction_insufficient",
                "energy_gain")  # fmt: skip


def point_impacts(
    a: BatchBodies,
    b: BatchBodies | None,
    point: Any,
    normal: Any,
    restitution: Any,
    *,
    tangential: str = "slip",
    friction: Any = 0.0,
    law: str = "newton",
    backend: str = "auto",
    parallel: bool = True,
    out: BatchImpacts | None = None,
) -> BatchImpacts:
    """Solve a batch of point impacts between ``a`` and ``b`` (``None``: a fixed obstacle).

    ``point`` (m) and ``normal`` (from ``b`` into ``a``, any non-zero length) per impact;
    ``restitution`` e in [0, 1]; ``friction`` Coulomb's mu >= 0; ``tangential``: ``"slip"``
    (frictionless when mu = 0, Coulomb friction otherwise) or ``"stick"`` (no slip after;
    mu, when > 0, is only checked: ``friction_insufficient``); ``law``: the restitution
    hypothesis (``newton``, ``poisson``, ``stronge``: they differ only under Coulomb slip);
    ``backend``: ``"auto"`` (compiled for NumPy input when Numba is installed, else arrays),
    ``"numba"`` or ``"array"``; ``parallel``: the compiled loop on all cores (pass False when
    calling from several threads of your own: Numba's parallel loops must not be launched
    concurrently); ``out``: an earlier result of the compiled backend with the same batch
    shape (float64), whose memory this call reuses (its values are replaced): for repeated
    large batches, where writing to fresh memory costs the operating system's page faults
    (a third of the time at 10^6 impacts).

    A ball (1 kg, I = 0.004) dropped at 2 m/s on a floor with e = 0.5 and e = 1:

    >>> ball = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.004, position_com=[0, 0, 0.1],
    ...                    velocity_com=[0, 0, -2.0])
    >>> out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.array([0.5, 1.0]))
    >>> out.velocity_a[:, 2].tolist(), out.dissipated.round(12).tolist()
    ([1.0, 2.0], [1.5, 0.0])
    """
    if tangential not in ("slip", "stick"):
        raise InputError("tangential", "must be 'slip' or 'stick'", tangential)
    check_hypothesis(law, "law")
    if backend not in ("auto", "numba", "array"):
        raise InputError("backend", "must be 'auto', 'numba' or 'array'", backend)
    inputs = _inputs(a, b, point, normal, restitution, friction)
    plain = all(isinstance(v, _PLAIN) for v in inputs.values())  # NumPy or Python numbers
    if backend == "auto" and not plain and _is_dask(inputs):
        return _run_dask(inputs, b is None, tangential=tangential, law=law)
    dtype = _result_dtype(inputs.values())  # before validation makes arrays of Python numbers
    xp: Any = None if plain else _namespace(inputs)
    is_numpy = xp is None
    if backend == "auto":
        backend = "numba" if is_numpy and have_numba() else "array"
    if backend == "numba" and not is_numpy:
        raise InputError("backend", "'numba' takes NumPy arrays (or lists)", type(point).__name__)
    if backend == "numba" and not have_numba():  # pragma: no cover - numba is locked
        raise InputError("backend", "'numba' needs the numba package (pip install numba)",
                         backend)  # fmt: skip
    shape = _check_structure(inputs) if is_numpy else ()
    blocks = None if out is None else _reusable(out, backend, shape, dtype)
    law_key = _law(tangential, law, inputs["friction"])
    if backend == "numba":
        res = _run_numba(law_key, inputs, shape, b is None, parallel, dtype, blocks)
    else:
        res = _run_array(_array_xp(xp), law_key, inputs, b is None,
                         dtype if is_numpy else None)  # fmt: skip
    if is_numpy:
        invalid = [np.asarray(res.pop(name)) for name in _INVALID_FIELDS]
        if backend == "numba":  # the kernel counted the impacts with any of the three flags
            suspect = res.pop("_invalid_count") > 0
        else:
            suspect = any(bool(np.any(column)) for column in invalid)
        if suspect and np.any(invalid[0] != 0):
            _check_values(inputs)  # names the field; passes a sum that merely overflowed
        for side, column in (("a", invalid[1]), ("b", invalid[2])):
            bad = column != 0
            if suspect and np.any(bad):
                index = tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), bad.shape))
                tensor = np.broadcast_to(inputs[f"{side}.inertia_com"], bad.shape + (3, 3))
                where = "" if np.ndim(inputs[f"{side}.inertia_com"]) == 2 else list(index)
                raise InputError(
                    f"{side}.inertia_com{where}",
                    "must be symmetric positive definite and realizable (each principal "
                    "moment <= the sum of the other two)", tensor[index],
                )  # fmt: skip
    else:
        import array_api_compat

        assert xp is not None  # (not NumPy: a namespace was found)
        bad = res.pop("invalid_input")
        if not array_api_compat.is_lazy_array(bad) and bool(xp.any(bad)):
            raise InputError("inputs", "must be finite, with masses > 0, restitution in [0, 1], "
                             "friction >= 0 and non-zero normals", "a row that is not",
                             show_value=False)  # fmt: skip
        for side in ("a", "b"):
            bad = res.pop(f"invalid_inertia_{side}")
            # an eager namespace is checked here; a lazy one (Dask) would have to compute the
            # whole batch for it: there NaN rows mark the bad tensors (see the README)
            if not array_api_compat.is_lazy_array(bad) and bool(xp.any(bad)):
                raise InputError(f"{side}.inertia_com",
                                 "must be symmetric positive definite and realizable (each "
                                 "principal moment <= the sum of the other two)",
                                 "a tensor that is not", show_value=False)  # fmt: skip
    if b is None:
        res["velocity_b"] = res["angular_velocity_b"] = None
    blocks = res.pop("_blocks", None)
    return BatchImpacts(**res) if blocks is None else BatchImpacts.over_blocks(blocks, res)


def _reusable(out: Any, backend: str, shape: tuple[int, ...], dtype: Any
              ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The float and int8 blocks behind ``out``, when a call of ``backend`` with batch shape
    ``shape`` and result type ``dtype`` can write into them."""
    blocks = getattr(out, "_blocks", None)
    if backend != "numba" or blocks is None or dtype != np.float64:
        raise InputError("out", "must be a float64 result of the compiled backend (NumPy "
                         "input) to reuse", type(out).__name__)  # fmt: skip
    if blocks[0].shape[0] != math.prod(shape):
        raise InputError("out", f"must have the batch's {math.prod(shape)} impacts",
                         blocks[0].shape[0])  # fmt: skip
    return blocks


# ---------------------------------------------------------------------------- the inputs


def _inputs(a: BatchBodies, b: BatchBodies | None, point: Any, normal: Any, restitution: Any,
            friction: Any) -> dict[str, Any]:  # fmt: skip
    """The arguments by field name (``a.mass``, ..., ``friction``), as given."""
    out: dict[str, Any] = {}
    for side, body in (("a", a), ("b", b)):
        if body is None:
            continue
        if not isinstance(body, BatchBodies):
            raise InputError(side, "must be a carnot.batch.BatchBodies", type(body).__name__)
        for f in fields(BatchBodies):
            out[f"{side}.{f.name}"] = getattr(body, f.name)
    out.update(point=point, normal=normal, restitution=restitution, friction=friction)
    for name, value in out.items():  # a number for a vector: the same in every component
        if _core_dims(name) == 1 and isinstance(value, int | float):
            out[name] = [float(value)] * 3
    return out


#: Input types that are NumPy's or plain Python's (no array-API namespace to look up).
_PLAIN = (np.ndarray, np.generic, int, float, list, tuple)


def _namespace(inputs: dict[str, Any]) -> Any:
    """``None`` when every input is NumPy or plain Python, else the array-API namespace."""
    import array_api_compat

    foreign = [v for v in inputs.values()
               if array_api_compat.is_array_api_obj(v) and not isinstance(v, np.ndarray)
               and not isinstance(v, np.generic)]  # fmt: skip
    if not foreign:
        return None
    return array_api_compat.array_namespace(*foreign)


def _array_xp(xp: Any) -> Any:
    import array_api_compat

    return array_api_compat.array_namespace(np.empty(0)) if xp is None else xp


_CORE = {"inertia_com": 2, "position_com": 1, "velocity_com": 1, "angular_velocity": 1,
         "point": 1, "normal": 1}  # fmt: skip


def _core_dims(name: str) -> int:
    return _CORE.get(name.rpartition(".")[2], 0)


def _check_structure(inputs: dict[str, Any]) -> tuple[int, ...]:
    """Types and shapes of every NumPy input (their values are checked inside the kernel,
    where they are read anyway: :func:`_check_values` then names the field); returns the
    batch shape."""
    for name, value in list(inputs.items()):
        arr = np.asarray(value)
        if arr.dtype.kind not in "fiub":  # floats, signed and unsigned integers, booleans
            raise InputError(name, "must be numbers", value)
        core = _core_dims(name)
        if core and arr.shape[arr.ndim - core:] != (3,) * core:
            raise InputError(name, f"must have trailing shape {(3,) * core}", arr.shape)
        inputs[name] = arr
    shapes = [arr.shape[: arr.ndim - _core_dims(name)] for name, arr in inputs.items()]
    distinct = set(shapes) - {()}
    if len(distinct) <= 1:  # the common case: one batch shape, and single values
        return distinct.pop() if distinct else ()
    try:
        return tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        raise InputError("inputs", "batch shapes do not broadcast together",
                         {n: s for n, s in zip(inputs, shapes, strict=True)}) from None  # fmt: skip


def _check_values(inputs: dict[str, Any]) -> None:
    """Bounds of every NumPy input, naming the field, the bound and the first bad value."""
    for name, arr in inputs.items():
        # a sum is non-finite when an entry is (or, rarely, when it overflows: then look
        # closer); it needs no temporary array, unlike isfinite over the whole input
        if arr.size and not np.isfinite(arr.sum()) and not np.all(np.isfinite(arr)):
            raise InputError(name, "must be finite", arr[~np.isfinite(arr)][:3])
    for side in ("a", "b"):
        if f"{side}.mass" in inputs:
            validate.positive_number(inputs[f"{side}.mass"], f"{side}.mass", unit=" kg")
    validate.number_in(inputs["restitution"], "restitution", 0.0, 1.0)
    validate.non_negative_number(inputs["friction"], "friction")
    length = np.einsum("...i,...i->...", inputs["normal"], inputs["normal"])
    if np.any(~(length > 0)):
        raise InputError("normal", "must be non-zero", inputs["normal"][~(length > 0)][:3])


def _law(tangential: str, hypothesis: str, friction: Any) -> str:
    """The key of the contact law in ``carnot.batch.ops.LAWS``: the registry's rule
    (:func:`carnot.laws.contact_rule`), the Coulomb one per hypothesis."""
    rule = contact_rule(tangential=tangential, friction=friction)
    return f"coulomb_{hypothesis}" if rule == "coulomb" else rule


# ------------------------------------------------------------------ the compiled backend

#: Fewer impacts than this run on one core: starting the parallel loop costs more than the
#: second core saves (about 20 us on an idle machine; on a loaded one a parallel loop waits
#: for a thread the scheduler has put aside, milliseconds: measured 4 ms for 1000 impacts).
PARALLEL_MIN = 4096
#: The same for the Coulomb laws, whose impacts cost 5 to 25 times a frictionless one: two
#: blocks. Measured at 1000 impacts (load 1.3, medians of 60 calls; p90 in brackets): 3D
#: Stronge 0.84 (0.80) million/s on one core, 1.52 (1.42) on two; planar 3.7 (3.5) and 5.5
#: (5.2); at 512 impacts 0.75 and 1.35, 2.9 and 4.0; at 256, one block, no gain.
PARALLEL_MIN_COULOMB = 512


def _flat(value: np.ndarray, shape: tuple[int, ...], core: int) -> np.ndarray:
    """``value`` broadcast to ``shape + (3,) * core`` as a ``(N, ...)`` array, without a
    copy when it is already full-sized and contiguous or the same for every impact (a
    zero stride)."""
    count = math.prod(shape)
    core_shape = (3,) * core
    if value.shape == shape + core_shape and value.dtype == np.float64 \
            and value.flags.c_contiguous:  # the common case, first: itself, or a view
        flat = value.view() if value.ndim == core + 1 else value.reshape((count,) + core_shape)
    else:
        batch = value.shape[: value.ndim - core]
        arr = np.asarray(value, dtype=np.float64)
        if math.prod(batch) == 1:
            return np.broadcast_to(arr.reshape((1,) + core_shape), (count,) + core_shape)
        full = np.broadcast_to(arr, shape + core_shape)
        flat = np.ascontiguousarray(full).reshape((count,) + core_shape)
    # read-only, as a broadcast is: Numba compiles the gathers once per combination of
    # argument types, and a writable array is another type than a read-only one
    flat.flags.writeable = False
    return flat


def _run_numba(law: str, inputs: dict[str, np.ndarray], shape: tuple[int, ...], fixed_b: bool,
               parallel: bool, dtype: Any,
               blocks: tuple[np.ndarray, np.ndarray] | None = None) -> dict[str, Any]:  # fmt: skip
    """The compiled kernel on the checked NumPy ``inputs`` of batch shape ``shape``, into
    new output blocks or ``blocks``; small batches run on one core (:data:`PARALLEL_MIN`,
    :data:`PARALLEL_MIN_COULOMB`)."""
    from carnot.batch.compile_notice import call_announcing
    from carnot.batch.compiled import driver, hypothesis, prepared

    args = {k: _flat(v, shape, _core_dims(k)) for k, v in inputs.items()}
    if fixed_b:
        args.update(_obstacle(shape, lambda x, core: _flat(np.asarray(x), shape, core),
                              inputs["point"]))  # fmt: skip
    count = math.prod(shape)
    if blocks is None:
        blocks = (np.empty((count, FLOAT_WIDTH)), np.empty((count, INT_WIDTH), dtype=np.int8))
    out_float, out_int = blocks
    threshold = PARALLEL_MIN if law in STRAIGHT_LINE_LAWS else PARALLEL_MIN_COULOMB
    invalid = call_announcing(
        driver(law, parallel and count >= threshold), f"the batch kernel of the {law} law",
        args["a.mass"], args["a.inertia_com"], args["a.position_com"], args["a.velocity_com"],
        args["a.angular_velocity"], args["b.mass"], args["b.inertia_com"],
        args["b.position_com"], args["b.velocity_com"], args["b.angular_velocity"],
        0.0 if fixed_b else 1.0, args["point"], args["normal"], args["restitution"],
        args["friction"], out_float, out_int, hypothesis(law), prepare=prepared,
    )  # fmt: skip
    flat = len(shape) == 1  # the common case: the views need no reshape
    out: dict[str, Any] = {}
    col = 0
    for name, width in FLOAT_FIELDS:
        block = out_float[:, col : col + width] if width > 1 else out_float[:, col]
        if not flat:
            block = block.reshape(shape + ((width,) if width > 1 else ()))
        out[name] = block if dtype == np.float64 else block.astype(dtype)
        col += width
    for k, (name, _) in enumerate(INT_FIELDS):
        column = out_int[:, k] if flat else out_int[:, k].reshape(shape)
        if name in _BOOL_FIELDS:
            column = column.view(np.bool_)
        elif name == "law_flags":
            column = column.view(np.uint8)
        out[name] = column
    out["_invalid_count"] = invalid
    if dtype == np.float64:
        out["_blocks"] = blocks
    return out


def _result_dtype(values: Any) -> Any:
    """float32 when every floating input is float32 (computed in float64 all the same),
    float64 otherwise."""
    kinds = [v.dtype for v in values if isinstance(v, np.ndarray | np.generic)]
    floats = [d for d in kinds if d.kind == "f"]
    return np.float32 if floats and all(d == np.float32 for d in floats) else np.float64


def _obstacle(shape: tuple[int, ...], make: Callable[[Any, int], Any], point: Any
              ) -> dict[str, Any]:  # fmt: skip
    """A fixed ``b`` as the kernels take it: mass 1, unit inertia, at the contact point (lever
    0), at rest, with ``movable_b = 0`` (its inverse mass and energy vanish)."""
    return {"b.mass": make(1.0, 0), "b.inertia_com": make(np.eye(3), 2),
            "b.position_com": make(point, 1), "b.velocity_com": make(np.zeros(3), 1),
            "b.angular_velocity": make(np.zeros(3), 1)}  # fmt: skip


# ------------------------------------------------------------------------------ Dask


def _is_dask(inputs: dict[str, Any]) -> bool:
    import array_api_compat

    return any(array_api_compat.is_dask_array(v) for v in inputs.values())


#: Impacts per Dask chunk when no input says otherwise.
DASK_CHUNK = 65536


def _run_dask(inputs: dict[str, Any], fixed_b: bool, *, tangential: str, law: str
              ) -> BatchImpacts:  # fmt: skip
    """A lazy batch over Dask arrays: the batch is flattened and chunked along the impacts,
    and each chunk is solved by the compiled kernel on NumPy (``da.blockwise``), so that every
    law works and a chunk costs one task, not one per arithmetic operation. Every output is a
    column of one lazy block: ``dask.compute(*fields)`` computes the chunks once. Bad input
    raises when computed, naming the field (its index counts within the chunk)."""
    import dask.array as da

    shapes = [tuple(np.shape(v))[: np.ndim(v) - _core_dims(k)] for k, v in inputs.items()]
    shape = tuple(np.broadcast_shapes(*shapes))
    count = math.prod(shape)
    first = next(v for v in inputs.values() if isinstance(v, da.Array))
    chunk = first.chunks[0][0] if first.ndim and tuple(first.shape[:1]) == shape[:1] \
        and len(shape) == 1 else DASK_CHUNK  # fmt: skip
    names = list(inputs)
    flat = []
    for name in names:
        core = (3,) * _core_dims(name)
        value = da.asarray(inputs[name], dtype=np.float64)
        value = da.broadcast_to(value, shape + core).reshape((count,) + core)
        flat.append(value.rechunk((max(1, chunk),) + core))
    public_ints = [name for name, _ in INT_FIELDS if not name.startswith("invalid")]
    width = FLOAT_WIDTH + len(public_ints)

    def solve_chunk(*blocks: np.ndarray) -> np.ndarray:
        given = dict(zip(names, blocks, strict=True))

        def body(side: str) -> BatchBodies | None:
            if f"{side}.mass" not in given:
                return None
            return BatchBodies(**{f.name: given[f"{side}.{f.name}"] for f in fields(BatchBodies)})

        out = point_impacts(body("a"), body("b"), given["point"], given["normal"],  # type: ignore[arg-type]
                            given["restitution"], tangential=tangential,
                            friction=given["friction"], law=law, parallel=False)  # fmt: skip
        columns = [np.asarray(getattr(out, name) if getattr(out, name) is not None
                              else np.zeros((len(blocks[0]), 3))).reshape(len(blocks[0]), -1)
                   for name, _ in FLOAT_FIELDS]  # fmt: skip
        columns += [np.asarray(getattr(out, name), dtype=np.float64).reshape(-1, 1)
                    for name in public_ints]  # fmt: skip
        return np.concatenate(columns, axis=1)

    letters = {0: "i", 1: "ij", 2: "ijk"}
    pairs: list[Any] = []
    for name, value in zip(names, flat, strict=True):
        pairs += [value, letters[_core_dims(name)]]
    block = da.blockwise(solve_chunk, "iz", *pairs, new_axes={"z": width}, dtype=np.float64,
                         concatenate=True)  # fmt: skip
    out: dict[str, Any] = {}
    col = 0
    for name, w in FLOAT_FIELDS:
        part = block[:, col : col + w] if w > 1 else block[:, col]
        out[name] = part.reshape(shape + ((w,) if w > 1 else ()))
        col += w
    for name in public_ints:  # (the validity flags are checked inside each chunk)
        kind = bool if name in _BOOL_FIELDS else np.uint8 if name == "law_flags" else np.int8
        out[name] = block[:, col].astype(kind).reshape(shape)
        col += 1
    if fixed_b:
        out["velocity_b"] = out["angular_velocity_b"] = None
    return BatchImpacts(**out)


# ---------------------------------------------------------------------- the array backend


def _run_array(xp: Any, law: str, inputs: dict[str, Any], fixed_b: bool, dtype: Any
               ) -> dict[str, Any]:  # fmt: skip
    if dtype is None:
        dtype = _array_dtype(xp, inputs.values())
    arrays = {k: xp.asarray(v, dtype=dtype) if not _is_array(v) else xp.astype(v, dtype)
              for k, v in inputs.items()}  # fmt: skip
    if fixed_b:
        arrays.update(_obstacle((), lambda x, core: xp.asarray(x, dtype=dtype),
                                arrays["point"]))  # fmt: skip
    movable = xp.asarray(0.0 if fixed_b else 1.0, dtype=dtype)

    def vec(x: Any) -> tuple[Any, Any, Any]:
        return x[..., 0], x[..., 1], x[..., 2]

    def tensor(x: Any) -> tuple[Any, ...]:
        return tuple(x[..., i, j] for i in range(3) for j in range(3))

    impact = specialize(xp, law).impact
    with np.errstate(divide="ignore", invalid="ignore"):  # masked rows (x/0) are selected out
        floats, ints = impact(
            arrays["a.mass"], tensor(arrays["a.inertia_com"]), vec(arrays["a.position_com"]),
            vec(arrays["a.velocity_com"]), vec(arrays["a.angular_velocity"]), arrays["b.mass"],
            tensor(arrays["b.inertia_com"]), vec(arrays["b.position_com"]),
            vec(arrays["b.velocity_com"]), vec(arrays["b.angular_velocity"]), movable,
            vec(arrays["point"]), vec(arrays["normal"]), arrays["restitution"], arrays["friction"],
        )  # fmt: skip
    zero = xp.zeros((), dtype=dtype)
    floats = [xp.asarray(f, dtype=dtype) + zero for f in floats]
    shape = tuple(np.broadcast_shapes(*[tuple(f.shape) for f in floats]))
    floats = [xp.broadcast_to(f, shape) for f in floats]
    out: dict[str, Any] = {}
    col = 0
    for name, width in FLOAT_FIELDS:
        if width == 1:
            out[name] = floats[col]
        else:
            out[name] = xp.stack(floats[col : col + width], axis=-1)
        col += width
    for (name, _), value in zip(INT_FIELDS, ints, strict=True):
        value = xp.broadcast_to(xp.asarray(value), shape)
        if name in _BOOL_FIELDS or name.startswith("invalid"):
            out[name] = xp.astype(value, xp.bool)
        else:
            out[name] = xp.astype(value, xp.uint8 if name == "law_flags" else xp.int8)
    return out


def _is_array(value: Any) -> bool:
    import array_api_compat

    return bool(array_api_compat.is_array_api_obj(value))


def _array_dtype(xp: Any, values: Any) -> Any:
    """float32 when every floating array input is float32, float64 otherwise."""
    kinds = [v.dtype for v in values if _is_array(v)]
    floats = [d for d in kinds if xp.isdtype(d, "real floating")]
    if floats and all(d == xp.float32 for d in floats):
        return xp.float32
    return xp.float64

"""The compiled backend: blocks of impacts in three passes, vectorized across impacts (Numba).

:func:`driver` compiles :func:`run` for one contact law. ``run`` splits the batch into
blocks of :data:`BLOCK` impacts, over all cores (``numba.prange``) or serially (that build
releases the GIL, for callers that run their own threads), and :func:`block` does one block
in three passes:

1. **gather**: every input of the block is copied into a scratch array, one row per input
   component (structure of arrays: impact ``i``'s ``x_a[1]`` at ``s[12 * PITCH + i]``);
2. **compute**: one loop over the block calls the pipeline
   (:func:`carnot.batch.pipeline.impact`) on column ``i`` and writes the results to a
   scratch column. For a straight-line law (frictionless, stick) every formula is inlined
   (:func:`carnot.batch.ops.specialize` with ``inline=True``), the loop body is branch-free
   and its loads and stores are unit-stride, so LLVM vectorizes it across impacts: 8 impacts
   per AVX-512 instruction here, about 5 times the scalar loop. The Coulomb laws, whose
   adaptive loops cannot be vectorized, run the same loop one impact at a time;
3. **scatter**: each impact's results are copied from the scratch column to the impact's row
   of the outputs (``out_float[i, k]``: one write stream; writing each result component
   to a row of its own, 44 streams at once, measured 30% slower at 10^6 impacts).

Why the scratch: vectorization needs unit-stride access that the compiler can prove does
not alias (the inputs are arrays of the caller's, of any layout and stride: some are
broadcast with stride 0), and results written straight to the caller's arrays would need
a run-time overlap check per pair of arrays. The scratch rows are ``PITCH = BLOCK + 8``
floats apart, an odd number of cache lines, so that the 46 input rows do not all map to the
same few sets of the L1 cache (a pitch of a power of two thrashes it).

The memory traffic is still one pass over the inputs and one over the outputs (the scratch,
~180 KB per block, stays in the core's L2 cache): what the roofline of
``benchmarks/bench_batch.py`` compares with.
"""

from __future__ import annotations

import functools
import platform
import sys
import types
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import types as nbtypes
from numba.core.errors import TypingError
from numba.extending import intrinsic, overload

from carnot.batch.ops import STRAIGHT_LINE_LAWS, source_digest, specialize
from carnot.batch.pipeline import FLOAT_WIDTH, INT_FIELDS, INT_WIDTH

#: Impacts per block (a multiple of the vector width), and the scratch's row pitch.
BLOCK = 256
PITCH = BLOCK + 8
#: Input components per impact: for ``a`` and ``b`` mass, inertia (9), position, velocity
#: and angular velocity (3 each); the point and the normal (3 each); e; mu.
INPUT_WIDTH = 2 * (1 + 9 + 3 + 3 + 3) + 3 + 3 + 1 + 1

#: The first of the three int columns that flag invalid input (they are the last three).
INVALID_ROWS = INT_WIDTH - 3
assert [name for name, _ in INT_FIELDS[INVALID_ROWS:]] == [
    "invalid_inertia_a", "invalid_inertia_b", "invalid_input"]  # fmt: skip
#: Outputs larger than this (bytes of the float block) are written with non-temporal stores.
STREAM_MIN_BYTES = 32 * 2**20
#: Whether this machine has them (x86-64: MOVNTI and SFENCE); elsewhere, ordinary stores.
X86_64 = platform.machine().lower() in ("x86_64", "amd64")

impact: Any = None  # bound per law by driver()
block: Any = None  # bound per law by driver()
prange = numba.prange


def store(rows, i, values):  # type: ignore[no-untyped-def]
    """``rows[k * PITCH + i] = values[k]`` for every entry of the tuple ``values`` (compiled
    only: the overload below; no annotations, as Numba matches the overload's arguments)."""


def store_row(out, g, values):  # type: ignore[no-untyped-def]
    """``out[g, k] = values[k]`` for every entry of the tuple ``values`` (compiled only)."""


def _unrolled(args: str, line: str, count: int) -> Any:
    # written out entry by entry for the tuple's length: a loop over a tuple's entries
    # would index it with a variable, which Numba compiles to a switch (not vectorizable)
    lines = [line.format(k=k, offset=k * PITCH) for k in range(count)]
    namespace: dict[str, Any] = {}
    exec(f"def impl({args}):\n" + "\n".join(lines) + "\n", namespace)  # noqa: S102
    return namespace["impl"]


@overload(store, inline="always")
def _store(rows, i, values):  # type: ignore[no-untyped-def]
    return _unrolled("rows, i, values", "    rows[{offset} + i] = values[{k}]", len(values))


@overload(store_row, inline="always")
def _store_row(out, g, values):  # type: ignore[no-untyped-def]
    return _unrolled("out, g, values", "    out[g, {k}] = values[{k}]", len(values))


@intrinsic
def stream_store(typingctx, array, index, value):  # type: ignore[no-untyped-def]
    """``array.flat[index] = value`` (a C-contiguous array) with a non-temporal store: the
    value goes to memory around the caches, without the cache line being read first (an
    ordinary store to memory not in cache reads the line, then writes it back: for a
    batch's outputs, a third of all the memory traffic). For outputs too large to stay in
    cache anyway; follow the last one with :func:`store_fence`."""
    if not isinstance(array, nbtypes.Array) or array.layout != "C":
        raise TypingError("stream_store takes a C-contiguous array")

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        array_type, _, value_type = signature.args
        data = context.make_array(array_type)(context, builder, args[0]).data
        value = context.cast(builder, args[2], value_type, array_type.dtype)
        store = builder.store(value, builder.gep(data, [args[1]]))
        if X86_64:  # elsewhere an ordinary store
            store.set_metadata("nontemporal", builder.module.add_metadata([ir.IntType(32)(1)]))
        return context.get_dummy_value()

    return nbtypes.void(array, index, value), codegen


@intrinsic
def store_fence(typingctx):  # type: ignore[no-untyped-def]
    """SFENCE on x86-64: the non-temporal stores before it are visible to every core before
    any store after it (they are weakly ordered; the parallel loop's end must not overtake
    them). Elsewhere nothing (ordinary stores there)."""

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        if X86_64:
            fence = ir.Function(builder.module, ir.FunctionType(ir.VoidType(), []),
                                "llvm.x86.sse.sfence")  # fmt: skip
            if fence.name in builder.module.globals:
                fence = builder.module.globals[fence.name]
            builder.call(fence, [])
        return context.get_dummy_value()

    return nbtypes.void(), codegen


@numba.njit(inline="always")
def _put3(s: Any, col: int, i: int, x: Any, g: int) -> None:
    s[col * PITCH + i] = x[g, 0]
    s[(col + 1) * PITCH + i] = x[g, 1]
    s[(col + 2) * PITCH + i] = x[g, 2]


@numba.njit(inline="always")
def _put9(s: Any, col: int, i: int, x: Any, g: int) -> None:
    for r in range(3):
        for c in range(3):
            s[(col + 3 * r + c) * PITCH + i] = x[g, r, c]


@numba.njit(inline="always")
def _vec(s: Any, col: int, i: int) -> Any:
    return (s[col * PITCH + i], s[(col + 1) * PITCH + i], s[(col + 2) * PITCH + i])


@numba.njit(inline="always")
def _tensor(s: Any, col: int, i: int) -> Any:
    return (s[col * PITCH + i], s[(col + 1) * PITCH + i], s[(col + 2) * PITCH + i],
            s[(col + 3) * PITCH + i], s[(col + 4) * PITCH + i], s[(col + 5) * PITCH + i],
            s[(col + 6) * PITCH + i], s[(col + 7) * PITCH + i],
            s[(col + 8) * PITCH + i])  # fmt: skip


def block_impacts(start, stop, mass_a, inertia_a, x_a, v_a, omega_a, mass_b,  # type: ignore[no-untyped-def]
                  inertia_b, x_b, v_b, omega_b, movable_b, point, normal, e, mu,
                  out_float, out_int, stream):  # fmt: skip
    """Impacts ``start`` to ``stop`` (at most :data:`BLOCK`) of the ``(N, ...)`` inputs into
    rows ``start:stop`` of ``out_float`` and ``out_int`` (see the module docstring); with
    ``stream``, the floats by non-temporal stores."""
    size = stop - start
    s = np.empty(INPUT_WIDTH * PITCH)
    rows_float = np.empty(FLOAT_WIDTH * PITCH)
    rows_int = np.empty(INT_WIDTH * PITCH, dtype=np.int8)
    for i in range(size):  # 1. gather (the column numbers are those of the call below)
        g = start + i
        s[i] = mass_a[g]
        _put9(s, 1, i, inertia_a, g)
        _put3(s, 10, i, x_a, g)
        _put3(s, 13, i, v_a, g)
        _put3(s, 16, i, omega_a, g)
        s[19 * PITCH + i] = mass_b[g]
        _put9(s, 20, i, inertia_b, g)
        _put3(s, 29, i, x_b, g)
        _put3(s, 32, i, v_b, g)
        _put3(s, 35, i, omega_b, g)
        _put3(s, 38, i, point, g)
        _put3(s, 41, i, normal, g)
        s[44 * PITCH + i] = e[g]
        s[45 * PITCH + i] = mu[g]
    for i in range(size):  # 2. compute (vectorized across i for a straight-line law)
        floats, ints = impact(
            s[i], _tensor(s, 1, i), _vec(s, 10, i), _vec(s, 13, i), _vec(s, 16, i),
            s[19 * PITCH + i], _tensor(s, 20, i), _vec(s, 29, i), _vec(s, 32, i),
            _vec(s, 35, i), movable_b, _vec(s, 38, i), _vec(s, 41, i), s[44 * PITCH + i],
            s[45 * PITCH + i])  # fmt: skip
        store(rows_float, i, floats)
        store(rows_int, i, ints)
    # 3. scatter: each impact's results to its row of the outputs (one loop per kind of
    # store: with the test inside the loop, LLVM compiled the streaming one 5 times slower)
    if stream:
        for i in range(size):
            for k in range(FLOAT_WIDTH):
                stream_store(out_float, (start + i) * FLOAT_WIDTH + k, rows_float[k * PITCH + i])
        store_fence()
    else:
        for i in range(size):
            for k in range(FLOAT_WIDTH):
                out_float[start + i, k] = rows_float[k * PITCH + i]
    for i in range(size):
        for k in range(INT_WIDTH):
            out_int[start + i, k] = rows_int[k * PITCH + i]
    invalid = 0  # impacts with bad input (the last three int rows: their flags)
    for i in range(size):
        invalid += (rows_int[INVALID_ROWS * PITCH + i] | rows_int[(INVALID_ROWS + 1) * PITCH + i]
                    | rows_int[(INVALID_ROWS + 2) * PITCH + i]) != 0  # fmt: skip
    return invalid


def block_direct(start, stop, mass_a, inertia_a, x_a, v_a, omega_a, mass_b,  # type: ignore[no-untyped-def]
                 inertia_b, x_b, v_b, omega_b, movable_b, point, normal, e, mu,
                 out_float, out_int, stream):  # fmt: skip
    """The same as :func:`block_impacts`, one impact at a time straight from the inputs to
    the outputs: for the laws with adaptive loops, which gain nothing from the scratch (nor
    from ``stream``: they are not limited by memory)."""
    invalid = 0
    for g in range(start, stop):
        # entries read directly: a row view (inertia_a[g]) would be reference-counted, an
        # atomic update of shared memory per impact that the two cores would fight over
        floats, ints = impact(
            mass_a[g], (inertia_a[g, 0, 0], inertia_a[g, 0, 1], inertia_a[g, 0, 2],
                        inertia_a[g, 1, 0], inertia_a[g, 1, 1], inertia_a[g, 1, 2],
                        inertia_a[g, 2, 0], inertia_a[g, 2, 1], inertia_a[g, 2, 2]),
            (x_a[g, 0], x_a[g, 1], x_a[g, 2]), (v_a[g, 0], v_a[g, 1], v_a[g, 2]),
            (omega_a[g, 0], omega_a[g, 1], omega_a[g, 2]),
            mass_b[g], (inertia_b[g, 0, 0], inertia_b[g, 0, 1], inertia_b[g, 0, 2],
                        inertia_b[g, 1, 0], inertia_b[g, 1, 1], inertia_b[g, 1, 2],
                        inertia_b[g, 2, 0], inertia_b[g, 2, 1], inertia_b[g, 2, 2]),
            (x_b[g, 0], x_b[g, 1], x_b[g, 2]), (v_b[g, 0], v_b[g, 1], v_b[g, 2]),
            (omega_b[g, 0], omega_b[g, 1], omega_b[g, 2]), movable_b,
            (point[g, 0], point[g, 1], point[g, 2]),
            (normal[g, 0], normal[g, 1], normal[g, 2]), e[g], mu[g])  # fmt: skip
        store_row(out_float, g, floats)
        store_row(out_int, g, ints)
        invalid += (ints[INVALID_ROWS] + ints[INVALID_ROWS + 1] + ints[INVALID_ROWS + 2]) != 0
    return invalid


def run(mass_a, inertia_a, x_a, v_a, omega_a, mass_b, inertia_b, x_b, v_b,  # type: ignore[no-untyped-def]
        omega_b, movable_b, point, normal, e, mu, out_float, out_int):  # fmt: skip
    """Rows ``i`` of ``out_float`` ``(N, FLOAT_WIDTH)`` and ``out_int`` ``(N, INT_WIDTH)``
    from impact ``i`` of the ``(N, ...)`` inputs (see :func:`carnot.batch.pipeline.impact`
    for the arguments and the rows), block by block; returns the number of impacts whose
    input is invalid (their flags, the last three int columns, say how)."""
    count = out_float.shape[0]
    stream = out_float.nbytes > STREAM_MIN_BYTES  # too large to stay in cache anyway
    invalid = 0
    for j in prange((count + BLOCK - 1) // BLOCK):
        start = j * BLOCK
        invalid += block(start, min(start + BLOCK, count), mass_a, inertia_a, x_a, v_a,
                         omega_a, mass_b, inertia_b, x_b, v_b, omega_b, movable_b, point,
                         normal, e, mu, out_float, out_int, stream)  # fmt: skip
    return invalid


def _copy(fn: Any, namespace: dict[str, Any], qualname: str) -> Any:
    copy = types.FunctionType(fn.__code__, namespace, fn.__name__, fn.__defaults__)
    copy.__module__ = __name__
    copy.__qualname__ = qualname
    return copy


@functools.cache
def block_kernel(law: str) -> Any:
    """The function of one block (:func:`block_impacts` for a straight-line law, vectorized;
    :func:`block_direct` otherwise) compiled for the contact law ``law``."""
    straight = law in STRAIGHT_LINE_LAWS
    impact_fn = specialize("numba", law, inline=straight).impact
    name = f"block__{_tag(impact_fn)}"
    fn = _copy(block_impacts if straight else block_direct, {**globals(), "impact": impact_fn},
               name)  # fmt: skip
    return numba.njit(cache=True, nogil=True, error_model="numpy")(fn)


def _tag(impact_fn: Any) -> str:
    # the pipeline's name carries its law and the formulas' digest; add this file's
    return f"{impact_fn.py_func.__qualname__}__{source_digest([sys.modules[__name__]])}"


@functools.cache
def driver(law: str, parallel: bool) -> Callable[..., Any]:
    """:func:`run` compiled for the contact law ``law`` (a key of ``carnot.batch.ops.LAWS``),
    on all cores or serial. Its cache entries are named after both and after the digests of
    the sources (``run__parallel__impact__stick__...``), so that entries never mix or go
    stale."""
    block_fn = block_kernel(law)
    kind = "parallel" if parallel else "serial"
    name = f"run__{kind}__{block_fn.py_func.__qualname__.removeprefix('block__')}"
    run_fn = _copy(run, {**globals(), "block": block_fn}, name)
    return numba.njit(parallel=parallel, cache=True, nogil=True, error_model="numpy")(run_fn)

"""The compiled backend: blocks of impacts in three passes, vectorized across impacts (Numba).

:func:`driver` compiles :func:`run` for one contact law. ``run`` splits the batch into
blocks of :data:`BLOCK` impacts, over all cores (``numba.prange``) or serially (that build
releases the GIL, for callers that run their own threads), and :func:`block` does one block
in three passes:

1. **gather**: every input of the block is copied into a scratch array, one row per input
   component (structure of arrays: impact ``i``'s ``x_a[1]`` at ``s[12 * PITCH + i]``);
2. **compute** (:func:`compute_impacts`): one loop over the block calls the pipeline
   (:func:`carnot.batch.pipeline.impact`) on column ``i`` and writes the results to a
   scratch column. For a straight-line law (frictionless, stick) every formula is inlined
   (:func:`carnot.batch.ops.specialize` with ``inline=True``), the loop body is branch-free
   and its loads and stores are unit-stride, so LLVM vectorizes it across impacts: 8 impacts
   per AVX-512 instruction here, about 5 times the scalar loop. The Coulomb laws, whose
   adaptive loops cannot be vectorized as a whole, split this pass around the law and the
   law around its 3D slip (:func:`compute_coulomb`): the geometry vectorized, the law's head
   and tail one impact at a time, and the 3D slip's DOP853 steps vectorized *across the
   impacts whose slip turns* (SIMD lanes, one step per lane and pass:
   :func:`lane_passes`). This pass reads and writes the scratch only, so it is compiled
   once per kernel (:func:`compute_kernel`; one for the three Coulomb laws, whose hypothesis
   is an argument) whatever the layouts of the caller's arrays: a new
   combination of strides recompiles only the gather and the scatter (seconds, where
   the Coulomb laws' pass takes most of a minute);
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
import threading
import types
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import types as nbtypes
from numba.core.errors import TypingError
from numba.extending import intrinsic, overload

from carnot.batch.coulomb import HYPOTHESES
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

impact: Any = None  # bound per straight-line law by compute_kernel()
geometry: Any = None  # bound by compute_kernel()
finish: Any = None  # bound by compute_kernel()
coulomb_head: Any = None  # bound by compute_kernel(), as the four below
coulomb_tail: Any = None
slip_start: Any = None
slip_pass: Any = None
slip_end: Any = None
compute: Any = None  # bound per kernel by block_kernel()
block: Any = None  # bound per kernel by driver()
prange = numba.prange


def store(rows, i, values):  # type: ignore[no-untyped-def]
    """``rows[k * PITCH + i] = values[k]`` for every entry of the tuple ``values`` (compiled
    only: the overload below; no annotations, as Numba matches the overload's arguments)."""


@overload(store, jit_options={"forceinline": True})
def _store(rows, i, values):  # type: ignore[no-untyped-def]
    # written out entry by entry for the tuple's length: a loop over a tuple's entries
    # would index it with a variable, which Numba compiles to a switch (not vectorizable)
    lines = [f"    rows[{k * PITCH} + i] = values[{k}]" for k in range(len(values))]
    namespace: dict[str, Any] = {}
    exec("def impl(rows, i, values):\n" + "\n".join(lines) + "\n", namespace)  # noqa: S102
    return namespace["impl"]


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


# The helpers below, and every formula (carnot.batch.ops.specialize), are inlined by LLVM
# (``forceinline``), not by Numba (``inline="always"``), which copies and types a callee's
# IR again at each call site: that was most of the Coulomb kernel's compile.
@numba.njit(forceinline=True)
def _put3(s: Any, col: int, i: int, x: Any, g: int) -> None:
    s[col * PITCH + i] = x[g, 0]
    s[(col + 1) * PITCH + i] = x[g, 1]
    s[(col + 2) * PITCH + i] = x[g, 2]


@numba.njit(forceinline=True)
def _put9(s: Any, col: int, i: int, x: Any, g: int) -> None:
    for r in range(3):
        for c in range(3):
            s[(col + 3 * r + c) * PITCH + i] = x[g, r, c]


@numba.njit(forceinline=True)
def _vec(s: Any, col: int, i: int) -> Any:
    return (s[col * PITCH + i], s[(col + 1) * PITCH + i], s[(col + 2) * PITCH + i])


@numba.njit(forceinline=True)
def _tensor(s: Any, col: int, i: int) -> Any:
    return (s[col * PITCH + i], s[(col + 1) * PITCH + i], s[(col + 2) * PITCH + i],
            s[(col + 3) * PITCH + i], s[(col + 4) * PITCH + i], s[(col + 5) * PITCH + i],
            s[(col + 6) * PITCH + i], s[(col + 7) * PITCH + i],
            s[(col + 8) * PITCH + i])  # fmt: skip


#: The types of a 3D slip's ``(consts, carry)`` (:func:`carnot.batch.coulomb.slip_start`),
#: of its result (:func:`~carnot.batch.coulomb.slip_end`) and of a Coulomb law's head
#: (:func:`~carnot.batch.coulomb.coulomb_head`), to read them back from the scratch
#: (:func:`load_flat`); their widths in scratch rows, and the row of the flag ``running``.
_F, _B = nbtypes.float64, nbtypes.boolean
CONSTS_TYPE = nbtypes.Tuple((nbtypes.UniTuple(_F, 6), nbtypes.UniTuple(_F, 3), _F, _F, _F, _F))
CARRY_TYPE = nbtypes.Tuple((nbtypes.UniTuple(_F, 8), nbtypes.UniTuple(_F, 8),
                            nbtypes.UniTuple(_F, 5), nbtypes.UniTuple(_F, 11),
                            nbtypes.UniTuple(_B, 7), nbtypes.UniTuple(_F, 4)))  # fmt: skip
LANE_TYPE = nbtypes.Tuple((CONSTS_TYPE, CARRY_TYPE))
#: ``slip_start``'s arguments but the constants: ``(k, w0, e, mu, d1, d2, state)``.
START_TYPE = nbtypes.Tuple((nbtypes.UniTuple(_F, 6), nbtypes.UniTuple(_F, 3), _F, _F, _F, _F,
                            nbtypes.UniTuple(_F, 11)))  # fmt: skip
TURNED_TYPE = nbtypes.Tuple((nbtypes.UniTuple(_F, 11), _B, _B, _B, _F, _F))
HEAD_TYPE = nbtypes.Tuple((nbtypes.UniTuple(_F, 6), nbtypes.UniTuple(_F, 3), _F, _F,
                           nbtypes.UniTuple(_F, 11), _B, _B, _B, _F, _F))  # fmt: skip


def _parts(kind: Any) -> list[Any]:
    """The entries' types of a tuple type (a UniTuple's repeated)."""
    return list(kind)


def _leaves(kind: Any) -> list[Any]:
    """The leaf types of a (nested) tuple type, in order."""
    if isinstance(kind, nbtypes.BaseTuple):
        return [leaf for part in _parts(kind) for leaf in _leaves(part)]
    return [kind]


CONSTS_WIDTH = len(_leaves(CONSTS_TYPE))
LANE_WIDTH = len(_leaves(LANE_TYPE))
TURNED_WIDTH = len(_leaves(TURNED_TYPE))
HEAD_WIDTH = len(_leaves(HEAD_TYPE))
START_WIDTH = len(_leaves(START_TYPE))
RUNNING_ROW = CONSTS_WIDTH + len(_leaves(nbtypes.Tuple(_parts(CARRY_TYPE)[:4])))  # carry[4][0]
#: The 3D slip's lanes are passed in groups of this many (a multiple of the vector width).
LANE_GROUP = 8


def store_flat(rows, i, row, tree):  # type: ignore[no-untyped-def]
    """``rows[(row + n) * PITCH + i] = `` the ``n``-th leaf of the nested tuple ``tree`` (a
    boolean as 1.0 or 0.0; compiled only: the overload below)."""


@overload(store_flat, prefer_literal=True, jit_options={"forceinline": True})
def _store_flat(rows, i, row, tree):  # type: ignore[no-untyped-def]
    # the row a constant of the build, folded into each index: with the row an argument of
    # the inlined function, LLVM could not bound the accesses of the loops over lanes and
    # left them scalar ("cannot identify array bounds": a 3D slip pass 5 times slower)
    if not isinstance(row, nbtypes.IntegerLiteral):
        raise TypingError(f"store_flat: the row must be a constant, got {row}")
    first = row.literal_value
    lines: list[str] = []

    def walk(kind: Any, expr: str) -> None:
        if isinstance(kind, nbtypes.BaseTuple):
            for k, part in enumerate(_parts(kind)):
                walk(part, f"{expr}[{k}]")
        else:
            value = f"(1.0 if {expr} else 0.0)" if isinstance(kind, nbtypes.Boolean) else expr
            lines.append(f"    rows[{(first + len(lines)) * PITCH} + i] = {value}")

    walk(tree, "tree")
    namespace: dict[str, Any] = {}
    exec("def impl(rows, i, row, tree):\n" + "\n".join(lines) + "\n", namespace)  # noqa: S102
    return namespace["impl"]


def load_flat(rows, i, row, kind):  # type: ignore[no-untyped-def]
    """The nested tuple of the Numba type ``kind`` whose ``n``-th leaf is ``rows[(row + n) *
    PITCH + i]`` (the inverse of :func:`store_flat`; compiled only: the overload below)."""


@overload(load_flat, prefer_literal=True, jit_options={"forceinline": True})
def _load_flat(rows, i, row, kind):  # type: ignore[no-untyped-def]
    # the row a constant of the build, folded into each index: with the row an argument of
    # the inlined function, LLVM could not bound the accesses of the loops over lanes and
    # left them scalar ("cannot identify array bounds": a 3D slip pass 5 times slower)
    if not isinstance(row, nbtypes.IntegerLiteral):
        raise TypingError(f"load_flat: the row must be a constant, got {row}")
    leaves = iter(range(row.literal_value, 10**6))

    def build(part: Any) -> str:
        if isinstance(part, nbtypes.BaseTuple):
            return "(" + "".join(build(p) + ", " for p in _parts(part)) + ")"
        read = f"rows[{next(leaves) * PITCH} + i]"
        return f"({read} > 0.5)" if isinstance(part, nbtypes.Boolean) else read

    namespace: dict[str, Any] = {}
    exec(f"def impl(rows, i, row, kind):\n    return {build(kind.instance_type)}\n",  # noqa: S102
         namespace)  # fmt: skip
    return namespace["impl"]


@numba.njit(forceinline=True)
def _swap_lanes(lanes: Any, lane_row: Any, a: int, b: int) -> None:
    for n in range(LANE_WIDTH):
        lanes[n * PITCH + a], lanes[n * PITCH + b] = lanes[n * PITCH + b], lanes[n * PITCH + a]
    lane_row[a], lane_row[b] = lane_row[b], lane_row[a]


@numba.njit(forceinline=True)
def _gather(s, start, size, mass_a, inertia_a, x_a, v_a, omega_a, mass_b,  # type: ignore[no-untyped-def]
            inertia_b, x_b, v_b, omega_b, point, normal, e, mu):  # fmt: skip
    """Gather: the inputs of impacts ``start`` to ``start + size`` into the scratch ``s``, one
    row (``PITCH`` apart) per component, in the order of the pipeline's arguments."""
    for i in range(size):
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


@numba.njit(forceinline=True)
def _scatter(rows_float, rows_int, start, size, out_float, out_int,  # type: ignore[no-untyped-def]
             stream):  # fmt: skip
    """Scatter: each impact's results from the scratch columns to its row of the outputs;
    returns the number of impacts whose input is invalid (their flags, the last three int
    rows)."""
    # one loop per kind of store: with the test inside the loop, LLVM compiled the
    # streaming one 5 times slower
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


def block_impacts(start, stop, mass_a, inertia_a, x_a, v_a, omega_a, mass_b,  # type: ignore[no-untyped-def]
                  inertia_b, x_b, v_b, omega_b, movable_b, point, normal, e, mu,
                  out_float, out_int, stream, hyp):  # fmt: skip
    """Impacts ``start`` to ``stop`` (at most :data:`BLOCK`) of the ``(N, ...)`` inputs into
    rows ``start:stop`` of ``out_float`` and ``out_int`` (see the module docstring); with
    ``stream``, the floats by non-temporal stores; ``hyp``: a Coulomb law's hypothesis
    (:data:`carnot.batch.coulomb.HYPOTHESES`; unread by a straight-line law). The compute
    pass is a function of its own (:func:`compute_impacts` or :func:`compute_coulomb`), on
    the scratch only: compiled once per kernel (:data:`KERNELS`), whatever the layouts of
    the caller's arrays (each new combination of strides compiles only this function's
    gather and scatter, in a second, not the law)."""
    size = stop - start
    s = np.empty(INPUT_WIDTH * PITCH)
    rows_float = np.empty(FLOAT_WIDTH * PITCH)
    rows_int = np.empty(INT_WIDTH * PITCH, dtype=np.int8)
    _gather(s, start, size, mass_a, inertia_a, x_a, v_a, omega_a, mass_b, inertia_b, x_b, v_b,
            omega_b, point, normal, e, mu)  # fmt: skip
    compute(s, size, movable_b, rows_float, rows_int, hyp)
    return _scatter(rows_float, rows_int, start, size, out_float, out_int, stream)


def compute_impacts(s, size, movable_b, rows_float, rows_int, hyp):  # type: ignore[no-untyped-def]
    """Pass 2 for a straight-line law: the pipeline on scratch columns ``0:size`` of ``s``
    (the rows of :func:`_gather`) into columns of ``rows_float`` and ``rows_int``, vectorized
    across impacts (``hyp`` is unread: the signature of :func:`compute_coulomb`)."""
    for i in range(size):
        floats, ints = impact(
            s[i], _tensor(s, 1, i), _vec(s, 10, i), _vec(s, 13, i), _vec(s, 16, i),
            s[19 * PITCH + i], _tensor(s, 20, i), _vec(s, 29, i), _vec(s, 32, i),
            _vec(s, 35, i), movable_b, _vec(s, 38, i), _vec(s, 41, i), s[44 * PITCH + i],
            s[45 * PITCH + i])  # fmt: skip
        store(rows_float, i, floats)
        store(rows_int, i, ints)


def lane_passes(lanes, lane_row, count, hyp):  # type: ignore[no-untyped-def]
    """Step 3 of :func:`compute_coulomb`: :func:`~carnot.batch.coulomb.slip_pass` on the first
    ``count`` lanes until none runs (vectorized across lanes), under the hypothesis ``hyp``.
    A function of its own, the same for every block signature: compiled once."""
    running = count
    while running > 0:
        # vectorized, over whole vectors: a lane that no longer runs passes unchanged, and
        # a scalar remainder loop would run the last few lanes of a long tail at a seventh
        # of the speed (the lanes past ``count`` are scratch: computed, never read)
        for j in range(-(-running // LANE_GROUP) * LANE_GROUP):
            consts, carry = load_flat(lanes, j, 0, LANE_TYPE)
            store_flat(lanes, j, CONSTS_WIDTH, slip_pass(consts, carry, hyp))
        j = 0
        while j < running:
            if lanes[RUNNING_ROW * PITCH + j] > 0.5:
                j += 1
            else:  # stopped: to the end
                running -= 1
                _swap_lanes(lanes, lane_row, j, running)


def compute_coulomb(s, size, movable_b, rows_float, rows_int, hyp):  # type: ignore[no-untyped-def]
    """The same as :func:`compute_impacts` for a Coulomb law (adaptive loops: it does not
    vectorize as a whole), the pipeline split around the law, and the law around its 3D
    slip (:mod:`carnot.batch.coulomb`), under the hypothesis ``hyp`` (an argument, not a
    constant of the build: the three Coulomb laws share one compiled kernel):

    1. vectorized: the geometry (``K`` and ``w'``, :func:`carnot.batch.pipeline.geometry`);
    2. one impact at a time: the law's head (:func:`~carnot.batch.coulomb.coulomb_head`);
       each impact whose slip direction turns becomes a *lane*, whose
       :func:`~carnot.batch.coulomb.slip_start` (a column of ``lanes``) is vectorized;
    3. vectorized across lanes: :func:`~carnot.batch.coulomb.slip_pass` on every running
       lane (one DOP853 step each: 8 lanes per AVX-512 instruction), until none runs; the
       lanes that stop are swapped to the end, so that the pass loops over running lanes
       only; then :func:`~carnot.batch.coulomb.slip_end`, vectorized;
    4. one impact at a time: the law's tail (:func:`~carnot.batch.coulomb.coulomb_tail`);
    5. vectorized: the geometry once more (cheaper than keeping its sixty numbers) and the
       rest of the pipeline (:func:`carnot.batch.pipeline.finish`).

    Measured per impact of the benchmark's 3D cases (serial): geometry 33 ns, head 30,
    starts 21, passes 1010 (18.5 passes of 54 ns), ends 19, tail 36, finish 31."""
    contact = np.empty(9 * PITCH)  # K (6 entries) and w' (3), per impact
    answer = np.empty(10 * PITCH)  # the law's ten numbers, per impact
    heads = np.empty(HEAD_WIDTH * PITCH)  # the law's head, per impact
    starts = np.empty(max(START_WIDTH, TURNED_WIDTH) * PITCH)  # a slip's start, then end
    lanes = np.empty(LANE_WIDTH * PITCH)  # a 3D slip's (consts, carry), per lane
    lane_row = np.empty(BLOCK, dtype=np.int64)
    turned = np.empty(TURNED_WIDTH * PITCH)  # a 3D slip's result, per impact (read where one ran)
    for i in range(size):  # 1. vectorized
        geo = geometry(s[i], _tensor(s, 1, i), _vec(s, 10, i), _vec(s, 13, i), _vec(s, 16, i),
                       s[19 * PITCH + i], _tensor(s, 20, i), _vec(s, 29, i), _vec(s, 32, i),
                       _vec(s, 35, i), movable_b, _vec(s, 38, i), _vec(s, 41, i))  # fmt: skip
        store(contact, i, geo[9] + geo[11])
    count = 0
    for i in range(size):  # 2. one impact at a time
        e_i, mu_i = s[44 * PITCH + i], s[45 * PITCH + i]
        head = coulomb_head(_vec(contact, 0, i) + _vec(contact, 3, i), _vec(contact, 6, i),
                            e_i, mu_i, hyp)  # fmt: skip
        store_flat(heads, i, 0, head)
        if head[7]:  # its slip direction turns: a lane
            store_flat(starts, count, 0, (head[0], head[1], e_i, mu_i, head[8], head[9],
                                          head[4]))  # fmt: skip
            lane_row[count] = i
            count += 1
    for j in range(count):  # the lanes' starts, vectorized
        k, w0, e_j, mu_j, d1, d2, state = load_flat(starts, j, 0, START_TYPE)
        store_flat(lanes, j, 0, slip_start(k, w0, e_j, hyp, mu_j, d1, d2, state, True))
    # 3. (count as int64: typed as the literal 0 at first, it compiled the kernel twice)
    lane_passes(lanes, lane_row, np.int64(count), hyp)
    for j in range(count):  # the lanes' ends, vectorized (to a lane's column of ``starts``)
        consts, carry = load_flat(lanes, j, 0, LANE_TYPE)
        store_flat(starts, j, 0, slip_end(consts, carry, hyp))
    for j in range(count):  # each to its impact's column
        i = lane_row[j]
        for n in range(TURNED_WIDTH):
            turned[n * PITCH + i] = starts[n * PITCH + j]
    for i in range(size):  # 4. one impact at a time
        k, w = _vec(contact, 0, i) + _vec(contact, 3, i), _vec(contact, 6, i)
        store(answer, i, coulomb_tail(k, w, s[44 * PITCH + i], s[45 * PITCH + i], hyp,
                                      load_flat(heads, i, 0, HEAD_TYPE),
                                      load_flat(turned, i, 0, TURNED_TYPE)))  # fmt: skip
    for i in range(size):  # 5. vectorized
        m_a, j_a, x_a_i, v_a_i, w_a_i = (s[i], _tensor(s, 1, i), _vec(s, 10, i),
                                         _vec(s, 13, i), _vec(s, 16, i))  # fmt: skip
        m_b, j_b, x_b_i, v_b_i, w_b_i = (s[19 * PITCH + i], _tensor(s, 20, i), _vec(s, 29, i),
                                         _vec(s, 32, i), _vec(s, 35, i))  # fmt: skip
        point_i, normal_i = _vec(s, 38, i), _vec(s, 41, i)
        geo = geometry(m_a, j_a, x_a_i, v_a_i, w_a_i, m_b, j_b, x_b_i, v_b_i, w_b_i, movable_b,
                       point_i, normal_i)  # fmt: skip
        floats, ints = finish(m_a, j_a, x_a_i, v_a_i, w_a_i, m_b, j_b, x_b_i, v_b_i, w_b_i,
                              movable_b, point_i, normal_i, s[44 * PITCH + i],
                              s[45 * PITCH + i], geo,
                              _tensor(answer, 0, i) + (answer[9 * PITCH + i],))  # fmt: skip
        store(rows_float, i, floats)
        store(rows_int, i, ints)


def run(mass_a, inertia_a, x_a, v_a, omega_a, mass_b, inertia_b, x_b, v_b,  # type: ignore[no-untyped-def]
        omega_b, movable_b, point, normal, e, mu, out_float, out_int, hyp):  # fmt: skip
    """Rows ``i`` of ``out_float`` ``(N, FLOAT_WIDTH)`` and ``out_int`` ``(N, INT_WIDTH)``
    from impact ``i`` of the ``(N, ...)`` inputs (see :func:`carnot.batch.pipeline.impact`
    for the arguments and the rows; ``hyp``: a Coulomb law's hypothesis, :func:`hypothesis`),
    block by block; returns the number of impacts whose
    input is invalid (their flags, the last three int columns, say how)."""
    count = out_float.shape[0]
    stream = out_float.nbytes > STREAM_MIN_BYTES  # too large to stay in cache anyway
    invalid = 0
    for j in prange((count + BLOCK - 1) // BLOCK):
        start = j * BLOCK
        invalid += block(start, min(start + BLOCK, count), mass_a, inertia_a, x_a, v_a,
                         omega_a, mass_b, inertia_b, x_b, v_b, omega_b, movable_b, point,
                         normal, e, mu, out_float, out_int, stream, hyp)  # fmt: skip
    return invalid


def _copy(fn: Any, namespace: dict[str, Any], qualname: str) -> Any:
    copy = types.FunctionType(fn.__code__, namespace, fn.__name__, fn.__defaults__)
    copy.__module__ = __name__
    copy.__qualname__ = qualname
    return copy


#: The kernel that runs each law: a straight-line law's own (its formulas inlined and
#: vectorized as one loop body), and one for the three Coulomb laws, whose hypothesis is an
#: argument (:func:`hypothesis`): their compute pass takes most of a minute to compile, once
#: for all three rather than once per law (a sweep over the laws, the test suite), at no
#: measured cost in speed (the hypothesis selects a few formulas of the law's head and
#: tail, run one impact at a time, and of the 3D slip's pass, where the branch is the same
#: for every lane).
KERNELS = {law: law for law in STRAIGHT_LINE_LAWS} | {law: "coulomb" for law in HYPOTHESES}


def hypothesis(law: str) -> np.int64:
    """The hypothesis argument of :func:`run` for ``law``: a Coulomb law's
    (:data:`carnot.batch.coulomb.HYPOTHESES`), -1 for a straight-line law (unread).

    >>> int(hypothesis("coulomb_poisson")), int(hypothesis("stick"))
    (1, -1)
    """
    return np.int64(HYPOTHESES.get(law, -1))


def block_kernel(law: str) -> Any:
    """:func:`block_impacts` compiled for the kernel of the contact law ``law`` (its compute
    pass: :func:`compute_kernel`)."""
    return _block_kernel(KERNELS[law])


@functools.cache
def _block_kernel(kernel: str) -> Any:
    compute_fn = _compute_kernel(kernel)
    name = f"block__{compute_fn.py_func.__qualname__.removeprefix('compute__')}"
    return numba.njit(cache=True, nogil=True, error_model="numpy")(
        _copy(block_impacts, {**globals(), "compute": compute_fn}, name))


@functools.cache
def _compute_kernel(kernel: str) -> Any:
    inlined = specialize("numba", _LAW_OF[kernel], inline=True)
    # (the 3D slip's start and end copied by Numba: LLVM's inlining of them left their
    # loops over lanes 5-10 % slower; carnot.batch.ops.specialize)
    copied = specialize("numba", _LAW_OF[kernel], inline="ir")
    if kernel in STRAIGHT_LINE_LAWS:
        fn, bound = compute_impacts, {"impact": inlined.impact}
    else:  # the law's parts inlined too: called as functions of their own (each compiled
        # once, its formulas inlined) they compiled in three quarters of the time, but ran
        # 5 to 8% slower on the 3D cases
        fn, bound = compute_coulomb, {
            "geometry": inlined.geometry, "finish": inlined.finish,
            "coulomb_head": inlined.coulomb_head, "coulomb_tail": inlined.coulomb_tail,
            "slip_start": copied.slip_start, "lane_passes": _lane_kernel(kernel),
            "slip_end": copied.slip_end}  # fmt: skip
    name = f"compute__{_tag(kernel)}"
    return numba.njit(cache=True, nogil=True, error_model="numpy")(
        _copy(fn, {**globals(), **bound}, name))


def compute_kernel(law: str) -> Any:
    """The compute pass compiled for the contact law ``law``: :func:`compute_impacts` with
    every formula inlined for a straight-line law (vectorized), else
    :func:`compute_coulomb` (the geometry, the rest and the 3D slip's passes vectorized),
    the same for the three Coulomb laws (:data:`KERNELS`)."""
    return _compute_kernel(KERNELS[law])


@functools.cache
def _lane_kernel(kernel: str) -> Any:
    inlined = specialize("numba", _LAW_OF[kernel], inline=True)
    return numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"})(
        _copy(lane_passes, {**globals(), "slip_pass": inlined.slip_pass},
              f"lane_passes__{_tag(kernel)}"))  # fmt: skip


def lane_kernel(law: str) -> Any:
    """:func:`lane_passes` compiled for the Coulomb law ``law`` (the same for the three),
    every formula of the pass inlined (vectorized), with fused multiply-adds (``contract``:
    ``a * b + c`` rounded once; 4% of a pass)."""
    return _lane_kernel(KERNELS[law])


#: A law whose formulas build each kernel (a Coulomb law's formulas other than ``impact``
#: do not depend on the law: :data:`carnot.batch.ops.LAW_DEPENDENT`).
_LAW_OF = {law: law for law in STRAIGHT_LINE_LAWS} | {"coulomb": "coulomb_newton"}


def _tag(kernel: str) -> str:
    # the kernel, the formulas' digest (as in the pipeline's name) and this file's
    impact = specialize("numba", _LAW_OF[kernel], inline=True).impact.py_func.__qualname__
    digest = impact.rsplit("__", 1)[1]
    return f"impact__{kernel}__inline__{digest}__{source_digest([sys.modules[__name__]])}"


def driver(law: str, parallel: bool) -> Callable[..., Any]:
    """:func:`run` for the kernel of the contact law ``law`` (a key of
    ``carnot.batch.ops.LAWS``; the three Coulomb laws share one, called with their
    :func:`hypothesis`), on all cores or serial, not yet compiled: :func:`prepared` compiles
    it. Its cache entries are named after both and after the digests of the sources
    (``run__parallel__impact__stick__...``), so that entries never mix or go stale."""
    return _driver(KERNELS[law], parallel)


@functools.cache
def _driver(kernel: str, parallel: bool) -> Callable[..., Any]:
    block_fn = _block_kernel(kernel)
    kind = "parallel" if parallel else "serial"
    name = f"run__{kind}__{block_fn.py_func.__qualname__.removeprefix('block__')}"
    run_fn = _copy(run, {**globals(), "block": block_fn}, name)
    return numba.njit(parallel=parallel, cache=True, nogil=True, error_model="numpy")(run_fn)


def _input(ndim: int) -> Any:
    return nbtypes.Array(nbtypes.float64, ndim, "A", readonly=True)


#: The one signature of :func:`run`: every input read-only and of any layout (``A``: a
#: value broadcast to every impact, a strided view or a contiguous array), the outputs
#: C-contiguous. Typed by the arrays' layouts instead, each new combination of them compiled
#: :func:`run` and :func:`block_impacts` again, and with them the compute pass that the
#: block links in: 7-10 s for the Coulomb kernel, and 31 builds of the three kernels in the
#: test suite where 6 now do.
SIGNATURE = (_input(1), _input(3), _input(2), _input(2), _input(2),  # a
             _input(1), _input(3), _input(2), _input(2), _input(2),  # b
             nbtypes.float64, _input(2), _input(2), _input(1), _input(1),
             nbtypes.Array(nbtypes.float64, 2, "C"), nbtypes.Array(nbtypes.int8, 2, "C"),
             nbtypes.int64)  # fmt: skip


def prepared(kernel: Any) -> Any:
    """``kernel`` (a :func:`driver`) compiled for :data:`SIGNATURE` alone, or loaded from
    Numba's cache, its compiling then disabled, so that arrays of every layout take that
    build (Numba converts a contiguous or writable array to it)."""
    with _PREPARING:
        if not kernel.signatures:
            kernel.compile(SIGNATURE)
            kernel.disable_compile()
    return kernel


_PREPARING = threading.Lock()  # (two threads of a sweep reaching a kernel first, together)

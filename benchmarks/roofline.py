"""The machine's roofline, measured in the run that uses it (shared by the batch benchmarks).

* :func:`triad_bandwidth`: STREAM's triad ``a = b + s c`` over arrays far larger than the
  caches, compiled and split over the cores (Numba ``prange``), in bytes per second
  (24 bytes per element: two reads and one write; write-allocate traffic not counted, as in
  STREAM).
* :func:`flop_rate`: independent multiply-add chains kept in registers on every core, in
  floating-point operations per second: what scalar arithmetic alone can reach;
  :func:`vector_flop_rate`: the same in packed fused multiply-adds (an FMA counts 2), what
  arithmetic vectorized across impacts can reach.
* :func:`stream_layout`: a pass that reads every input array of a batch kernel and writes
  every output array, with the same shapes and strides and one add per output value, with
  ordinary and with non-temporal stores (as the kernels write outputs larger than
  ``STREAM_MIN_BYTES``), the faster of the two: the memory-bound floor of a kernel with that
  layout (its impacts per second).
* :func:`count_flops`: the floating-point operations of one impact of a batch formula,
  counted by running the formula's array build on counting numbers (both sides of every
  ``select`` are computed, as the compiled kernel does before it picks one);
  :func:`count_flops_of`: the mean over a sample of real impacts (the Coulomb laws' work
  differs from impact to impact).

Import from the benchmark scripts (they run from this folder).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from timing import best_of

from carnot.batch.compiled import BLOCK, store_fence, stream_store


@numba.njit(parallel=True, cache=True)
def _triad(a: np.ndarray, b: np.ndarray, c: np.ndarray, s: float) -> None:
    for i in numba.prange(a.shape[0]):
        a[i] = b[i] + s * c[i]


def triad_bandwidth(n: int = 40_000_000, repeat: int = 5) -> float:
    """STREAM triad bandwidth (bytes/s), best of ``repeat``, on ``n`` float64 elements."""
    a, b, c = np.zeros(n), np.ones(n), np.full(n, 2.0)
    _triad(a, b, c, 3.0)
    return 24 * n / best_of(lambda: _triad(a, b, c, 3.0), repeat)


@numba.njit(parallel=True, cache=True)
def _chains(x: np.ndarray, steps: int) -> None:
    # 8 independent chains per lane hide the latency of the multiply-add
    for i in numba.prange(x.shape[0]):
        a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = x[i]
        for _ in range(steps):
            a0 = a0 * 0.999999 + 1e-7
            a1 = a1 * 0.999998 + 1e-7
            a2 = a2 * 0.999997 + 1e-7
            a3 = a3 * 0.999996 + 1e-7
            a4 = a4 * 0.999995 + 1e-7
            a5 = a5 * 0.999994 + 1e-7
            a6 = a6 * 0.999993 + 1e-7
            a7 = a7 * 0.999992 + 1e-7
        x[i] = a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7


def flop_rate(lanes: int = 4096, steps: int = 20_000, repeat: int = 3) -> float:
    """Scalar floating-point rate (flop/s) of compiled code on all cores: the arithmetic
    roof of code that runs one number at a time (a Coulomb law's head and tail, one impact
    at a time; separate multiplies and adds, as Numba compiles them by default)."""
    x = np.ones(lanes)
    _chains(x, 10)
    return lanes * steps * 16 / best_of(lambda: _chains(x, steps), repeat)


@numba.njit(parallel=True, cache=True, fastmath={"contract"})
def _vector_chains(x: np.ndarray, steps: int) -> None:
    # the innermost loop runs across a row's 256 independent chains: vectorized (packed
    # multiply-adds), enough chains in flight to hide their latency
    for i in numba.prange(x.shape[0]):
        row = x[i]
        for _ in range(steps):
            for j in range(row.shape[0]):
                row[j] = row[j] * 0.999999 + 1e-7


def vector_flop_rate(rows: int = 64, steps: int = 40_000, repeat: int = 3) -> float:
    """Vectorized floating-point rate (flop/s) of compiled code on all cores: packed fused
    multiply-adds (an FMA counts 2) on independent chains, the arithmetic roof of the
    kernels vectorized across impacts (frictionless, stick, the 3D slip's lanes)."""
    x = np.ones((rows, 256))
    _vector_chains(x, 10)
    return x.size * steps * 2 / best_of(lambda: _vector_chains(x, steps), repeat)


@numba.njit(parallel=True, cache=True)
def _stream_rows(inputs: Any, out_float: np.ndarray, out_int: np.ndarray) -> None:
    for i in numba.prange(out_float.shape[0]):
        total = 0.0
        for j in range(len(inputs)):
            arr = inputs[j]
            for k in range(arr.shape[1]):
                total += arr[i, k]
        for k in range(out_float.shape[1]):
            out_float[i, k] = total + k
        for k in range(out_int.shape[1]):
            out_int[i, k] = k


@numba.njit(parallel=True, cache=True)
def _stream_rows_around_caches(inputs: Any, out_float: np.ndarray, out_int: np.ndarray) -> None:
    count, width = out_float.shape
    for j in numba.prange((count + BLOCK - 1) // BLOCK):
        rows = range(j * BLOCK, min((j + 1) * BLOCK, count))
        sums = np.empty(BLOCK)  # a block's scratch, as in the kernels (it stays in cache)
        for i in rows:  # the inputs, summed per impact (the sums stand in for the results)
            total = 0.0
            for m in range(len(inputs)):
                arr = inputs[m]
                for k in range(arr.shape[1]):
                    total += arr[i, k]
            sums[i - j * BLOCK] = total
        for i in rows:
            for k in range(width):
                stream_store(out_float, i * width + k, sums[i - j * BLOCK] + k)
        store_fence()
        for i in rows:
            for k in range(out_int.shape[1]):
                out_int[i, k] = k


def stream_layout(inputs: list[np.ndarray], out_float: np.ndarray, out_int: np.ndarray,
                  repeat: int = 3) -> float:  # fmt: skip
    """Seconds of the best of ``repeat`` passes that read every array of ``inputs`` (rows
    ``(N, ...)``) and write every entry of ``out_float`` and ``out_int``: the same bytes as
    a batch kernel with that layout, and nothing else. Written both ways the kernels can
    write (ordinary stores, and non-temporal stores for the floats): the faster counts."""
    flat = tuple(np.ascontiguousarray(x).reshape(len(x), -1) for x in inputs)
    best = math.inf
    for fn in (_stream_rows, _stream_rows_around_caches):
        fn(flat, out_float, out_int)
        best = min(best, best_of(lambda fn=fn: fn(flat, out_float, out_int), repeat))
    return best


class _Counted:
    """A number that counts the floating-point operations done on it."""

    count = 0

    def __init__(self, value: float):
        self.value = float(value)

    @staticmethod
    def _v(x: Any) -> float:
        return x.value if isinstance(x, _Counted) else float(x)

    def _op(self, other: Any, fn: Callable[[float, float], Any]) -> Any:
        _Counted.count += 1
        out = fn(self.value, self._v(other))
        return _Counted(out) if not isinstance(out, bool) else out

    def __add__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: a + b)

    def __radd__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: b + a)

    def __sub__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: a - b)

    def __rsub__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: b - a)

    def __mul__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: a * b)

    def __rmul__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: b * a)

    def __truediv__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: a / b if b else math.nan)

    def __rtruediv__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: b / a if a else math.nan)

    def __pow__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: a**b if a > 0 or b == int(b) else math.nan)

    def __rpow__(self, o: Any) -> Any:
        return self._op(o, lambda a, b: b**a if b > 0 or a == int(a) else math.nan)

    def __neg__(self) -> Any:
        return _Counted(-self.value)

    def __abs__(self) -> Any:
        return _Counted(abs(self.value))

    def _cmp(self, o: Any, fn: Callable[[float, float], bool]) -> bool:
        _Counted.count += 1
        return fn(self.value, self._v(o))

    def __lt__(self, o: Any) -> bool:
        return self._cmp(o, lambda a, b: a < b)

    def __le__(self, o: Any) -> bool:
        return self._cmp(o, lambda a, b: a <= b)

    def __gt__(self, o: Any) -> bool:
        return self._cmp(o, lambda a, b: a > b)

    def __ge__(self, o: Any) -> bool:
        return self._cmp(o, lambda a, b: a >= b)

    def __eq__(self, o: Any) -> bool:  # type: ignore[override]
        return self._cmp(o, lambda a, b: a == b)

    def __ne__(self, o: Any) -> bool:  # type: ignore[override]
        return self._cmp(o, lambda a, b: a != b)

    __hash__ = None  # type: ignore[assignment]


class _CountingNamespace:
    """The two functions ``specialize`` needs of a namespace, on counted numbers."""

    __name__ = "counting"

    @staticmethod
    def where(c: Any, a: Any, b: Any) -> Any:
        return a if c else b

    @staticmethod
    def sqrt(x: Any) -> Any:
        _Counted.count += 1
        return _Counted(math.sqrt(max(_Counted._v(x), 0.0)))


_COUNTING = _CountingNamespace()


def count_flops_of(law: str, a: Any, b: Any, point: np.ndarray, normal: np.ndarray,
                   restitution: float, friction: np.ndarray, sample: int) -> float:
    """Floating-point operations (and comparisons) of one impact under ``law``, the mean over
    the first ``sample`` impacts of a batch (``a``, ``b``: BatchBodies, ``b`` None for an
    obstacle): for laws whose work differs from impact to impact (the 3D slip's adaptive
    steps). Each side of every ``select`` counts, as the compiled kernel computes both; the
    compiler's removal of repeated subexpressions does not, so this is an upper bound."""
    from carnot.batch.ops import specialize

    impact = specialize(_COUNTING, law).impact
    c = _Counted

    def body(side: Any, i: int) -> tuple[Any, ...]:
        return (c(side.mass[i]), tuple(c(x) for x in side.inertia_com[i].ravel()),
                tuple(c(x) for x in side.position_com[i]),
                tuple(c(x) for x in side.velocity_com[i]),
                tuple(c(x) for x in side.angular_velocity[i]))  # fmt: skip

    total = 0
    for i in range(sample):
        c.count = 0
        impact(*body(a, i), *body(a if b is None else b, i), c(0.0 if b is None else 1.0),
               tuple(c(x) for x in point[i]), tuple(c(x) for x in normal[i]),
               c(restitution), c(friction[i]))  # fmt: skip
        total += c.count
    return total / sample


def count_flops(law: str, obstacle: bool) -> int:
    """Floating-point operations (and comparisons) of one impact under ``law``."""
    from carnot.batch.ops import specialize

    impact = specialize(_COUNTING, law).impact
    c = _Counted

    def vec(*xs: float) -> tuple[Any, ...]:
        return tuple(c(x) for x in xs)

    eye = vec(0.3, 0.01, 0.02, 0.01, 0.4, 0.03, 0.02, 0.03, 0.5)
    body = (c(2.0), eye, vec(0.1, 0.2, 0.3), vec(1.0, -1.0, 0.5), vec(0.3, 0.2, -0.1))
    c.count = 0
    impact(*body, *body, c(0.0 if obstacle else 1.0), vec(0.0, 0.0, 0.0),
           vec(0.1, 0.2, 1.0), c(0.5), c(0.0 if law != "stick" else 0.3))  # fmt: skip
    return c.count

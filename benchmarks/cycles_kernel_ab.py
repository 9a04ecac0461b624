"""Cycles per box landing, the multi-contact kernel of another revision against this tree's.

``bench_kernel_ab.py`` times whole batches (10^4 landings, 2 threads) alternately; on this
shared 2-core machine its passes still move by 10-20 % from one to the next, as much as a
change to the kernel gains. Here each landing is solved 15 times in a row by each kernel, on
one core, and the fewest cycles of the 15 is kept (the processor's time-stamp counter,
LLVM's ``readcyclecounter``): a pass that another program interrupted does not count. The
sums over the landings compare to about 1 %. Both kernels are loaded in one process as in
``bench_kernel_ab.py`` (the other's ``multi_kernel.py`` a module of its own); each solves
the landing through ``solve_front`` and, where that leaves it undecided, ``solve_into``, as
``run`` does (``assemble`` and ``finish`` are not timed: the same code in both). The
functions' arguments must mean the same in both revisions (true since ``0c2641c``).

Run: ``.venv/bin/python benchmarks/cycles_kernel_ab.py --against REV [--case sliding]
[--n 300]`` (``--case`` sliding or sticking: ``bench_batch_multi.py``'s box landings,
``mu`` 0.2 or 1.5). Prints both kernels' mean cycles per landing and their ratio.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types
from numba.extending import intrinsic

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_batch_multi import box  # noqa: E402
from bench_kernel_ab import other_kernel  # noqa: E402
from same_answers import source_of  # noqa: E402

from carnot.batch import multi_kernel as this_kernel  # noqa: E402
from carnot.batch.multi import _layout  # noqa: E402


@intrinsic
def cycles(typingctx):  # type: ignore[no-untyped-def]
    """The processor's cycle counter (``rdtsc`` on x86-64; 0 where LLVM has none)."""

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        fnty = ir.FunctionType(ir.IntType(64), [])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.readcyclecounter")
        return builder.call(fn, [])

    return types.int64(), codegen


def timer(kernel):  # type: ignore[no-untyped-def]
    """A compiled function: the fewest cycles of ``reps`` solves of one landing by ``kernel``
    (its ``solve_front``, then ``solve_into`` where that leaves it undecided)."""
    front, into, undecided = kernel.solve_front, kernel.solve_into, kernel.UNDECIDED
    # (solve_into's last arguments since its regimes are called by address: their callbacks)
    extra = tuple(kernel.impact_solvers()[1:]) if hasattr(kernel, "impact_solvers") else ()

    @numba.njit
    def fewest(g, w, nrow, trow, ntan, e, mu, jac, mass, inertia, ws, nws, rws, imp, wa, reg,  # type: ignore[no-untyped-def]
               act, reps):  # fmt: skip
        hws = rws[:4]
        bws = (rws[24], rws[25], rws[26], rws[27])
        best = np.int64(1) << 62
        for _ in range(reps):
            start = cycles()
            s, _f, _r, sc, cnt, ver, mono, q, over, bst = front(
                g, w, nrow, trow, ntan, e, mu, imp, wa, reg, act, ws, hws, jac, mass, inertia,
                True, bws)  # fmt: skip
            if s == undecided:
                into(g, w, nrow, trow, ntan, e, mu, imp, wa, reg, act, ws, nws, rws, jac, mass,
                     inertia, True, (sc, cnt, ver, mono, q, over, bst), *extra)  # fmt: skip
            best = min(best, cycles() - start)
        return best

    return fewest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", required=True, help="git revision or src folder")
    parser.add_argument("--case", default="sliding", choices=("sliding", "sticking"))
    parser.add_argument("--n", type=int, default=300, help="landings (1 to 10000)")
    args = parser.parse_args()
    if not 1 <= args.n <= 10_000:
        parser.error(f"--n must be between 1 and 10000, got {args.n}")
    kernels = [other_kernel(source_of(args.against)), this_kernel]
    timers = [timer(kernel) for kernel in kernels]
    rng = np.random.default_rng(1)
    k = 4
    tangential = np.ones(k, dtype=np.int64)
    nrow, trow, ntan, m = _layout(2 * tangential)
    body, points, normals, e, mu = box(rng, args.n, *((0.2, 3.0) if args.case == "sliding"
                                                      else (1.5, 0.8)))  # fmt: skip
    total = np.zeros(2)
    for i in range(args.n):
        g, w, jac, *_ = this_kernel.assemble(
            body["mass"][i], body["inertia_com"][i], body["position_com"][i],
            body["velocity_com"][i], body["angular_velocity"][i], 1.0, np.eye(3), np.zeros(3),
            np.zeros(3), np.zeros(3), False, points[i], normals[i], tangential, m)  # fmt: skip
        for j, (kernel, fewest) in enumerate(zip(kernels, timers, strict=True)):
            spaces = (kernel.workspace(k, m), kernel.newton_workspace(k, m),
                      kernel.regime_workspace(k, m))  # fmt: skip
            out = (np.empty(m), np.empty(m), np.empty(k, np.int8), np.empty(k, np.bool_))
            fewest(g, w, nrow, trow, ntan, e[i], mu[i], jac, body["mass"][i],
                   body["inertia_com"][i], *spaces, *out, 1)  # fmt: skip  (compiled, warm)
            total[j] += fewest(g, w, nrow, trow, ntan, e[i], mu[i], jac, body["mass"][i],
                               body["inertia_com"][i], *spaces, *out, 15)  # fmt: skip
    if not total.min() > 0:
        sys.exit("no cycle counter on this processor (LLVM's readcyclecounter gave 0)")
    print(f"{args.case}, {args.n} landings: other ({args.against}) {total[0] / args.n:.0f}, "
          f"this {total[1] / args.n:.0f} cycles per landing (fewest of 15 each); "
          f"ratio {total[0] / total[1]:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()

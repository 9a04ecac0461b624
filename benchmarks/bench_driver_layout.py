"""The one-contact batch driver's one build against builds typed by the arrays' layouts.

Since issue 35 (2026-12-03, fifth session), :func:`carnot.batch.compiled.run` is compiled
once per kernel, for :data:`carnot.batch.compiled.SIGNATURE`: every input of any layout
(``A``), so that a value broadcast to every impact, a strided view and a contiguous array
take the same build instead of compiling the driver and its block again (the Coulomb
kernel: 7-10 s a combination). The price to look for is in the gathers, which now read
contiguous inputs through their strides. Here the same ``run`` is also compiled for the
exact layouts of contiguous inputs (``C``, no cache), and both run the same random two-body
impacts, all inputs contiguous (the case the ``A`` build could lose), alternately pass after
pass on all cores: each pass's pair sees the same machine. Prints, per law and size, both
rates (best pass), the ratio of the bests and the median of the passes' ratios.

Run: ``.venv/bin/python benchmarks/bench_driver_layout.py [--passes 9]`` (compiles each
law's ``C`` build first: about a minute).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numba
import numpy as np
from scipy.spatial.transform import Rotation

from carnot.batch.compiled import driver, hypothesis, prepared
from carnot.batch.pipeline import FLOAT_WIDTH, INT_WIDTH


def arguments(law: str, n: int, seed: int = 7) -> tuple:
    """``run``'s arguments for ``n`` random two-body impacts (all inputs contiguous, read-only;
    the outputs fresh)."""
    rng = np.random.default_rng(seed)

    def body() -> list[np.ndarray]:
        mass = 10 ** rng.uniform(-1, 1, n)
        rot = Rotation.random(n, random_state=rng).as_matrix()
        moments = rng.uniform(0.5, 1.0, (n, 3)) * mass[:, None] * 0.01
        inertia = np.einsum("nij,nj,nkj->nik", rot, moments, rot)
        return [mass, inertia, rng.uniform(-1, 1, (n, 3)), rng.normal(size=(n, 3)),
                rng.normal(size=(n, 3))]  # fmt: skip

    inputs = [*body(), *body()]
    rest = [rng.uniform(-1, 1, (n, 3)), rng.normal(size=(n, 3)), rng.uniform(0, 1, n),
            rng.uniform(0, 1, n)]  # fmt: skip
    for a in (*inputs, *rest):
        a.flags.writeable = False
    return (*inputs, 1.0, *rest, np.empty((n, FLOAT_WIDTH)),
            np.empty((n, INT_WIDTH), dtype=np.int8), hypothesis(law))  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--passes", type=int, default=9)
    options = parser.parse_args()
    print(f"{'law':16} {'impacts':>9} {'one build (A)':>15} {'by layout (C)':>15} "
          f"{'ratio of bests':>15} {'median ratio':>13}")  # fmt: skip
    for law, sizes in (("frictionless", (10**5, 10**6)), ("stick", (10**5, 10**6)),
                       ("coulomb_newton", (10**4, 10**5))):  # fmt: skip
        kernel = driver(law, True)
        one = prepared(kernel)
        typed = numba.njit(parallel=True, nogil=True, error_model="numpy")(kernel.py_func)
        for n in sizes:
            args = arguments(law, n)
            one(*args), typed(*args)  # (compiled, warm)
            rates: dict[str, list[float]] = {"A": [], "C": []}
            for k in range(options.passes):  # (the order alternates: neither always first)
                for name, fn in (("A", one), ("C", typed))[:: 1 if k % 2 else -1]:
                    began = time.perf_counter()
                    fn(*args)
                    rates[name].append(n / (time.perf_counter() - began))
            ratios = [a / c for a, c in zip(rates["A"], rates["C"], strict=True)]
            best_a, best_c = max(rates["A"]), max(rates["C"])
            print(f"{law:16} {n:9d} {best_a / 1e6:12.2f} M/s {best_c / 1e6:12.2f} M/s "
                  f"{best_a / best_c:15.3f} {statistics.median(ratios):13.3f}")  # fmt: skip


if __name__ == "__main__":
    main()

"""The compiled backend: one fused loop over the impacts of a batch (Numba).

:func:`driver` compiles :func:`run` for one contact law: every iteration reads one impact's
inputs, calls the pipeline (:func:`carnot.batch.pipeline.impact`, compiled for scalars by
:func:`carnot.batch.ops.specialize`) and writes one row of floats and one row of small
integers. Nothing else touches memory: no temporary arrays, one pass over the inputs and one
over the outputs, which is what the roofline of ``benchmarks/bench_batch.py`` compares with.
With ``parallel=True`` the loop is split over the cores (``numba.prange``); the serial build
releases the GIL, for callers that run their own threads.
"""

from __future__ import annotations

import functools
import sys
import types
from collections.abc import Callable
from typing import Any

import numba

from carnot.batch.ops import source_digest, specialize

impact: Any = None  # bound per law by driver()
prange = numba.prange


def run(mass_a, inertia_a, x_a, v_a, omega_a, mass_b, inertia_b, x_b, v_b,  # type: ignore[no-untyped-def]
        omega_b, movable_b, point, normal, e, mu, out_float, out_int):  # fmt: skip
    """Row ``i`` of ``out_float`` and ``out_int`` from impact ``i`` of the ``(N, ...)`` inputs
    (see :func:`carnot.batch.pipeline.impact` for the arguments and the columns)."""
    for i in prange(out_float.shape[0]):
        # entries read directly: a row view (inertia_a[i]) would be reference-counted, an
        # atomic update of shared memory per impact that the two cores would fight over
        floats, ints = impact(
            mass_a[i], (inertia_a[i, 0, 0], inertia_a[i, 0, 1], inertia_a[i, 0, 2],
                        inertia_a[i, 1, 0], inertia_a[i, 1, 1], inertia_a[i, 1, 2],
                        inertia_a[i, 2, 0], inertia_a[i, 2, 1], inertia_a[i, 2, 2]),
            (x_a[i, 0], x_a[i, 1], x_a[i, 2]), (v_a[i, 0], v_a[i, 1], v_a[i, 2]),
            (omega_a[i, 0], omega_a[i, 1], omega_a[i, 2]),
            mass_b[i], (inertia_b[i, 0, 0], inertia_b[i, 0, 1], inertia_b[i, 0, 2],
                        inertia_b[i, 1, 0], inertia_b[i, 1, 1], inertia_b[i, 1, 2],
                        inertia_b[i, 2, 0], inertia_b[i, 2, 1], inertia_b[i, 2, 2]),
            (x_b[i, 0], x_b[i, 1], x_b[i, 2]), (v_b[i, 0], v_b[i, 1], v_b[i, 2]),
            (omega_b[i, 0], omega_b[i, 1], omega_b[i, 2]), movable_b,
            (point[i, 0], point[i, 1], point[i, 2]),
            (normal[i, 0], normal[i, 1], normal[i, 2]), e[i], mu[i])  # fmt: skip
        for k in range(len(floats)):
            out_float[i, k] = floats[k]
        for k in range(len(ints)):
            out_int[i, k] = ints[k]


@functools.cache
def driver(law: str, parallel: bool) -> Callable[..., Any]:
    """:func:`run` compiled for the contact law ``law`` (a key of ``carnot.batch.ops.LAWS``),
    on all cores or serial; its cache entry is named after both and after the digests of the
    sources (``run__parallel__impact__stick__...``), so that entries never mix or go stale."""
    namespace = dict(globals())
    impact_fn = specialize("numba", law).impact
    namespace["impact"] = impact_fn
    copy = types.FunctionType(run.__code__, namespace, "run", run.__defaults__)
    copy.__module__ = __name__
    # the pipeline's name carries its law and the formulas' digest; add this file's
    digest = source_digest([sys.modules[__name__]])
    copy.__qualname__ = (f"run__{'parallel' if parallel else 'serial'}__"
                         f"{impact_fn.py_func.__qualname__}__{digest}")  # fmt: skip
    return numba.njit(parallel=parallel, cache=True, nogil=True,
                      error_model="numpy")(copy)  # fmt: skip

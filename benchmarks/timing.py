"""Timing helpers shared by the benchmark scripts (run from this folder's scripts, which
import it as ``timing``)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def timed(fn: Callable[[], object], repeat: int, warm_up: int = 0) -> list[float]:
    """Seconds of ``repeat`` calls of ``fn``, after ``warm_up`` untimed ones."""
    for _ in range(warm_up):
        fn()
    out = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        out.append(time.perf_counter() - start)
    return out


def summary(samples: list[float]) -> tuple[float, float]:
    """Median and interquartile range (s)."""
    q = statistics.quantiles(samples, n=4)
    return statistics.median(samples), q[2] - q[0]


def best_of(fn: Callable[[], object], repeat: int) -> float:
    """The shortest of ``repeat`` calls (s): for whole batches, where noise only adds."""
    return min(timed(fn, repeat))

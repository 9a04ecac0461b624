"""Memory of a long sweep of short simulations in one process (issue 35's acceptance: after
the last of 10^4 rows within 10% of what it was after the first 1000).

Each scene is a ``carnot sweep`` of simulations computed chunk after chunk in this process
(:meth:`carnot.sweep.Sweep.chunk`, the threads route's call, 100 rows a chunk), the swept
value a body's mass, so that every row simulates a body no earlier row had (the worst case
for a cache of bodies: one kept by identity, or by value without a bound, grows by a body a
row):

* ``ball``: a ball dropped on a floor (e = 0.8, 0.6 s: the lean event loop, two bounces);
* ``brick``: a square bar (moments A, A, C: a closed-form flight, regular precession; not
  ``c I``, so the general loop, its inertia turned at every impact) dropped tilted and
  spinning onto a floor (e = 0.5, 0.4 s: five impacts).

After the first 1000 rows and after the last, the resident set size (``/proc/self/statm``;
``ru_maxrss``, the peak, where there is no ``/proc``) and the Python heap that
:mod:`tracemalloc` sees (``--tracemalloc``: slower) are printed, with the entries in
``carnot.simulate.impacts``' caches, against the 10% bound.

Run: ``.venv/bin/python benchmarks/bench_sweep_memory.py [--rows N] [--scene ball|brick|both]
[--tracemalloc]``; exit status 1 when a scene's memory after the last row exceeds the bound.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import resource
import sys
import time
import tracemalloc

import numpy as np

from carnot.simulate import impacts
from carnot.single import inertia_factor
from carnot.sweep import make_plan, prepare_sweep

FLOOR = {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}}
CHUNK = 100
BOUND = 0.10


def ball() -> dict:
    return {"format": 1, "simulation": {"duration": 0.6, "gravity": [0.0, -9.81, 0.0]},
            "bodies": {"ball": {"mass": 0.1, "shape": "sphere", "radius": 0.05,
                                "position": [0.0, 0.3, 0.0]}, "floor": FLOOR},
            "pairs": [{"a": "ball", "b": "floor", "restitution": 0.8}]}  # fmt: skip


def brick() -> dict:
    th = 0.3
    return {"format": 1, "simulation": {"duration": 0.4, "gravity": [0.0, -9.81, 0.0]},
            "bodies": {"ball": {"mass": 0.1, "shape": "box", "size": [0.08, 0.04, 0.04],
                                "position": [0.0, 0.2, 0.0],
                                "orientation": [np.cos(th / 2), 0.3 * np.sin(th / 2),
                                                0.0, 0.95 * np.sin(th / 2)],
                                "angular_velocity": [1.0, 2.0, 3.0]}, "floor": FLOOR},
            "pairs": [{"a": "ball", "b": "floor", "restitution": 0.5}]}  # fmt: skip


def rss_bytes() -> int:
    """The resident set size now (bytes), or the peak where ``/proc`` is missing."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:  # (macOS: the peak, in bytes there)
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return peak if sys.platform == "darwin" else peak * 1024


def cache_entries() -> str:
    """The entries in the simulation's caches of validated parts (and the short path's
    inertia factors, kept for the last 4096 inertias)."""
    parts = []
    for name in ("_template", "_spherical", "_template_of", "_oriented", "_plane_contact",
                 "_plane_contact_of", "_fixed", "fixed_body"):  # (today's and before)
        fn = getattr(impacts, name, None)
        if fn is not None and hasattr(fn, "cache_info"):
            info = fn.cache_info()
            parts.append(f"{name} {info.currsize}/{info.maxsize}")
    info = inertia_factor.cache_info()  # (the short path's inertia factors)
    parts.append(f"single.inertia_factor {info.currsize}/{info.maxsize}")
    return ", ".join(parts)


def measure(name: str, scene: dict, rows: int, traced: bool) -> tuple[str, bool]:
    """The sweep of ``rows`` rows of ``scene``: its row of the table, and whether it is
    within the bound."""
    plan = make_plan(vary=[f"bodies.ball.mass=0.05:0.15:{rows}"])
    sweep = prepare_sweep(scene, plan, f"<{name}>", ["impacts", "energy_final"])
    marks: dict[int, tuple[int, int]] = {}
    first = min(1000, rows)
    start = time.perf_counter()
    events = 0
    for lo in range(0, rows, CHUNK):
        hi = min(lo + CHUNK, rows)
        chunk = sweep.chunk(lo, hi, parallel=False)
        events += int(np.nansum(chunk.columns["impacts"]))
        if hi in (first, rows):
            gc.collect()
            heap = tracemalloc.get_traced_memory()[0] if traced else 0
            marks[hi] = (rss_bytes(), heap)
            print(f"  {name}: after {hi:>6} rows  RSS {marks[hi][0] / 2**20:8.1f} MiB"
                  + (f"  traced heap {heap / 2**20:7.2f} MiB" if traced else "")
                  + f"  ({cache_entries()})", flush=True)  # fmt: skip
    seconds = time.perf_counter() - start
    (rss0, heap0), (rss1, heap1) = marks[first], marks[rows]
    growth = rss1 / rss0 - 1.0
    ok = growth <= BOUND
    return (f"| {name} | {rows} | {seconds:.1f} | {events} | {rss0 / 2**20:.1f} | "
            f"{rss1 / 2**20:.1f} | {100 * growth:+.1f}% | "
            + (f"{(heap1 - heap0) / 2**10:+.0f} KiB | " if traced else "")
            + ("within" if ok else "OVER") + f" {100 * BOUND:.0f}% |"), ok  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=10_000)
    parser.add_argument("--scene", choices=("ball", "brick", "both"), default="both")
    parser.add_argument("--tracemalloc", action="store_true", help="the Python heap too")
    args = parser.parse_args()
    print(f"python {platform.python_version()}, numpy {np.__version__}, "
          f"{os.cpu_count()} cpus, {platform.machine()}; chunks of {CHUNK} rows")
    if args.tracemalloc:
        tracemalloc.start()
    scenes = {"ball": ball, "brick": brick}
    names = list(scenes) if args.scene == "both" else [args.scene]
    results = [measure(name, scenes[name](), args.rows, args.tracemalloc) for name in names]
    print(f"\n| scene | rows | seconds | impacts | RSS after {min(1000, args.rows)} rows (MiB) "
          "| after the last (MiB) | growth | "
          + ("traced heap growth | " if args.tracemalloc else "") + "bound |\n| --- |"
          + " ---: |" * (7 if args.tracemalloc else 6) + " --- |")  # fmt: skip
    for row, _ in results:
        print(row)
    sys.exit(0 if all(ok for _, ok in results) else 1)


if __name__ == "__main__":
    main()

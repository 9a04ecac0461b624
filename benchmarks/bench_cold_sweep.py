"""The first sweep on a cold compile cache (issue 35, item 2): whole processes, each with an
empty ``NUMBA_CACHE_DIR`` of its own, against ``python -c "import numpy, scipy.linalg"`` in
the same run.

* a 100-row sweep of one point impact: it takes the ``solve_impact`` loop (at most
  ``carnot.sweep.UNCOMPILED_ROWS`` rows), so no kernel compiles; target <= 3 s;
* the same 100 rows forced through the batch kernel (``--compiled``): what the threshold
  saves; the compile line appears on stderr;
* 2000 rows (above the threshold), cold and then warm (the cache the first run filled): the
  compile's cost once, and what a warm cache costs.

Run: ``.venv/bin/python benchmarks/bench_cold_sweep.py``.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BALL = str(ROOT / "examples" / "ball_on_floor.toml")


def run(args: list[str], cache: str) -> tuple[float, str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "OPENBLAS_NUM_THREADS": "1"}
    env.pop("CARNOT_QUIET_COMPILE", None)
    began = time.perf_counter()
    done = subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True,
                          check=True)  # fmt: skip
    return time.perf_counter() - began, done.stderr.strip()


def sweep(rows: int, out: str, *extra: str) -> list[str]:
    return ["-m", "carnot.cli", "sweep", BALL, "--vary", f"contacts.0.restitution=0:1:{rows}",
            "--out", out, "--workers", "1", *extra]  # fmt: skip


def main() -> None:
    print(f"python {platform.python_version()}, {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        base, _ = run(["-c", "import numpy, scipy.linalg"], f"{tmp}/c0")
        print(f"baseline (import numpy, scipy.linalg): {base:.2f} s")
        t, err = run(sweep(100, f"{tmp}/a.csv"), f"{tmp}/c1")
        print(f"100 rows, cold cache, default route: {t:.2f} s (target <= 3 s)"
              f"{'; stderr: ' + err if err else ''}")  # fmt: skip
        t, err = run(sweep(100, f"{tmp}/b.csv", "--compiled"), f"{tmp}/c2")
        print(f"100 rows, cold cache, the batch kernel forced: {t:.2f} s; stderr: {err!r}")
        t, err = run(sweep(2000, f"{tmp}/c.csv"), f"{tmp}/c3")
        print(f"2000 rows, cold cache (the kernel compiles): {t:.2f} s")
        t, _ = run(sweep(2000, f"{tmp}/d.csv"), f"{tmp}/c3")
        print(f"2000 rows, warm cache: {t:.2f} s")


if __name__ == "__main__":
    main()

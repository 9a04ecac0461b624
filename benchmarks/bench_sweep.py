"""``carnot sweep`` end to end: 10^6 impacts to Parquet in a new process (target: < 5 s on a
2-core machine), against the baseline of writing the same bytes with pyarrow alone.

Run from the repository root: ``.venv/bin/python benchmarks/bench_sweep.py [ROWS]``. Prints
the wall time of each run of the command (start-up, imports, Numba's first compilation or
its cache, the sweep, the file), the sweep's own time as it reports it, the peak resident
memory of the process against the file's size, and the time pyarrow takes to write the very
table that came out (read back, written again, in this process).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = ROOT / "examples" / "ball_on_floor.toml"


def run_command(out: Path, rows: int) -> tuple[float, str, int]:
    """Wall seconds of one ``carnot sweep`` in a new process, its output line, and the peak
    RSS of that process (KiB)."""
    side = int(round(rows**0.5))
    cmd = [sys.executable, "-m", "carnot.cli", "sweep", str(SCENARIO),
           "--vary", f"contacts.0.restitution=0:1:{side}",
           "--vary", f"bodies.ball.velocity.2=-0.5:-5:{rows // side}",
           "--out", str(out)]  # fmt: skip
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(done.stderr)
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return wall, done.stdout.strip(), max(peak, before)


def baseline(out: Path) -> tuple[float, int]:
    """Seconds pyarrow alone takes to write the same table (same options), and its bytes."""
    import pyarrow.parquet as pq

    table = pq.read_table(out)
    again = out.with_name("baseline.parquet")
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        pq.write_table(table, again, compression="snappy", row_group_size=16384)
        best = min(best, time.perf_counter() - start)
    return best, table.nbytes


def main() -> None:
    rows = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    print(f"carnot sweep, {rows:,} impacts to Parquet, {os.cpu_count()} CPUs")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "sweep.parquet"
        walls = []
        for attempt in range(3):
            wall, line, peak_kib = run_command(out, rows)
            walls.append(wall)
            print(f"  run {attempt + 1}: {wall:5.2f} s end to end   [{line}]")
        size = out.stat().st_size
        write, nbytes = baseline(out)
        best = min(walls)
        print(f"  best end to end: {best:.2f} s = {rows / best / 1e6:.2f} million impacts/s "
              f"(target < 5 s: {'met' if best < 5 else 'MISSED'})")  # fmt: skip
        print(f"  file: {size / 2**20:.1f} MiB on disk, {nbytes / 2**20:.1f} MiB in Arrow; "
              f"peak RSS of the command: {peak_kib / 1024:.0f} MiB")  # fmt: skip
        print(
            f"  baseline, pyarrow alone writing the same table: {write:.2f} s "
            f"({nbytes / write / 2**20:.0f} MiB/s, {rows / write / 1e6:.2f} million rows/s)"
        )
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import carnot.cli, carnot.sweep, pyarrow.parquet"],
                       check=True)  # fmt: skip
        print(
            f"  of which start-up (Python, carnot, pyarrow imports): "
            f"{time.perf_counter() - start:.2f} s"
        )


if __name__ == "__main__":
    main()

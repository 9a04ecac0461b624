"""Instructions per ``solve_impact`` call of the 4-corner 3D Coulomb box landing (issue 14's
1 ms case, ``bench_several.py``'s), sticking (mu 1.5) and sliding (mu 0.2), counted by
Valgrind (``cachegrind``, no cache simulation): a measure that the other programs sharing a
machine do not change, where wall-clock medians on a loaded 2-core machine move by 2x from one
run to the next. Each count is ``(run with N calls - run with none) / N`` (the import and the
scenario's loading cancel), with hash randomization and address-space randomization off; what
remains varies by some 10 million instructions a run, about 2 % at N = 100. Times follow at
the machine's rate of instructions (about 4 per ns on this one, quiet: 4.4 M instructions was
1.04 ms).

Run: ``.venv/bin/python benchmarks/instructions_several.py [--n 100] [SRC ...]`` (each ``SRC`` a
package's ``src`` folder, e.g. another worktree's, for a baseline in the same run; this tree's
by default).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

CALLS = """
import sys
from dataclasses import replace
from carnot import solve_impact
from carnot.io.scenario import load_scenario
box = load_scenario(sys.argv[1])
case = replace(box, contacts=[replace(c, friction=float(sys.argv[2])) for c in box.contacts])
for _ in range(3):
    solve_impact(case)
for _ in range(int(sys.argv[3])):
    solve_impact(case)
"""


def count(src: Path, mu: float, calls: int) -> int:
    """Instructions of one process running ``calls`` solves (Valgrind's ``I refs``)."""
    env = dict(os.environ, PYTHONPATH=str(src), PYTHONHASHSEED="0")
    command = ["valgrind", "--tool=cachegrind", "--cache-sim=no",
               "--cachegrind-out-file=/dev/null", sys.executable, "-c", CALLS,
               str(HERE.parent / "examples" / "box_lands_flat.toml"), str(mu), str(calls)]
    if shutil.which("setarch"):
        command = ["setarch", "-R", *command]  # the same addresses every run
    out = subprocess.run(command, env=env, capture_output=True, text=True, check=True).stderr
    match = re.search(r"I\s+refs:\s+([\d,]+)", out)
    if match is None:
        raise RuntimeError(f"no instruction count from valgrind: {out[-500:]}")
    return int(match.group(1).replace(",", ""))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100, help="calls per count")
    parser.add_argument("src", nargs="*", default=[str(HERE.parent / "src")])
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        sys.exit("valgrind is needed (apt-get install valgrind)")
    print(f"{'src':40s} {'sticks (mu 1.5)':>18s} {'slides (mu 0.2)':>18s}")
    for src in args.src:
        per_call = [(count(Path(src), mu, args.n) - count(Path(src), mu, 0)) / args.n
                    for mu in (1.5, 0.2)]  # fmt: skip
        print(f"{src[-40:]:40s} {per_call[0] / 1e6:12.2f} M ins {per_call[1] / 1e6:12.2f} M ins")


if __name__ == "__main__":
    main()

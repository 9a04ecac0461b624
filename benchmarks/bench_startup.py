"""Start-up: whole-process wall time of everyday commands against NumPy's own.

``carnot --help`` and ``carnot solve`` of one impact are paid for mostly in imports, so each
is timed as a user meets it, a fresh interpreter from exec to exit, and compared with
``python -c "import numpy, scipy.linalg"`` (what any solver built on them pays before its
first line), ``python -c "import numpy"`` and ``python -c pass`` (Python itself), all
measured in the same run. Each command runs once per round, the rounds alternate the
commands so that a slow minute of the machine falls on all of them, and the best of the
rounds is reported (noise only adds).

Compiled bytecode is kept as an installed package keeps it: the processes write and read
theirs under a temporary ``PYTHONPYCACHEPREFIX`` (filled by an untimed first run), whatever
``PYTHONDONTWRITEBYTECODE`` says; ``--no-cache`` times them compiling every carnot module
from source instead (NumPy's and SciPy's bytecode as installed), as a process does where
bytecode may not be written.

``--against REV`` also times the commands of the package as it was at git revision ``REV``
(exported to a temporary folder), alternating with this tree, so that a change is compared
with what it replaced in the same run (``--against 305f823``: before the lazy imports).

Targets (issue 35): ``carnot --help`` within 0.2 s; ``carnot solve`` of one point impact
within 1.3x the NumPy and SciPy baseline.

Run: ``make bench`` or ``.venv/bin/python benchmarks/bench_startup.py [--rounds N] [--against REV]
[--no-cache]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

from timing import best_of

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

#: The commands after the carnot module, as a user types them after ``carnot``.
COMMANDS = {
    "carnot --help": ["--help"],
    "carnot solve ball_on_floor.toml": ["solve", str(EXAMPLES / "ball_on_floor.toml")],
    "carnot solve box_lands_flat.toml": ["solve", str(EXAMPLES / "box_lands_flat.toml")],
}
BASELINE = "python -c 'import numpy, scipy.linalg'"
PYTHON = "python -c pass"
NUMPY = "python -c 'import numpy'"


def _env(src: Path, cache: Path | None) -> dict[str, str]:
    """This environment with the package tree ``src`` first on the path, and bytecode kept
    under ``cache`` (None: carnot's compiled from source, nothing written)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(src), *filter(None, [env.get("PYTHONPATH")])])
    if cache is None:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        env.pop("PYTHONPYCACHEPREFIX", None)
    else:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(cache)
    return env


def _runs(trees: dict[str, Path], cache: Path | None
          ) -> dict[str, tuple[list[str], dict[str, str]]]:
    """Each timed process's argv and environment, by row name (a row per command and tree;
    the baselines with this tree's path, which they do not read)."""
    now = _env(trees["now"], cache)
    runs = {PYTHON: ([sys.executable, "-c", "pass"], now),
            NUMPY: ([sys.executable, "-c", "import numpy"], now),
            BASELINE: ([sys.executable, "-c", "import numpy, scipy.linalg"], now)}  # fmt: skip
    for tree, src in trees.items():
        for name, args in COMMANDS.items():
            # -m carnot.cli: the module the console script calls, from the tree on the path
            row = name if tree == "now" else f"{name} ({tree})"
            runs[row] = ([sys.executable, "-m", "carnot.cli", *args], _env(src, cache))
    return runs


def measure(trees: dict[str, Path], rounds: int, cache: Path | None) -> dict[str, float]:
    """The best wall time (s) of each row over ``rounds`` rounds, each running every row."""
    runs = _runs(trees, cache)
    for argv, env in runs.values():  # once untimed: a failure stops here, the caches fill
        subprocess.run(argv, env=env, check=True, capture_output=True)
    best = dict.fromkeys(runs, float("inf"))
    for _ in range(rounds):
        for name, (argv, env) in runs.items():
            seconds = best_of(lambda argv=argv, env=env: subprocess.run(
                argv, env=env, check=True, capture_output=True), 1)  # fmt: skip
            best[name] = min(best[name], seconds)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7, help="runs of each command (best of)")
    parser.add_argument("--against", metavar="REV", help="also time the package at REV")
    parser.add_argument("--no-cache", action="store_true",
                        help="compile carnot's modules in every process (no bytecode kept)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"now": ROOT / "src"}
        if args.against:
            archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.against, "src"],
                                     check=True, capture_output=True).stdout  # fmt: skip
            subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
            trees[args.against] = Path(tmp) / "src"
        cache = None if args.no_cache else Path(tmp) / "pycache"
        best = measure(trees, args.rounds, cache)
    import numpy  # here: only for the version line (the timed processes import their own)

    print(f"python {platform.python_version()}, numpy {numpy.__version__}, "
          f"{os.cpu_count()} cpus, {platform.machine()}; best of {args.rounds}, "
          f"{'no bytecode kept' if args.no_cache else 'bytecode kept'}")  # fmt: skip
    base = best[BASELINE]
    print(f"{'whole process':<44} {'wall':>9} {'/ baseline':>11} {'- python':>10}")
    for name, seconds in best.items():
        print(f"{name:<44} {seconds * 1e3:>6.0f} ms {seconds / base:>10.2f}x "
              f"{(seconds - best[PYTHON]) * 1e3:>7.0f} ms")  # fmt: skip


if __name__ == "__main__":
    main()

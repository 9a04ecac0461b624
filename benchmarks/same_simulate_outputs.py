"""Whether ``carnot simulate FILE`` and ``carnot simulate FILE --json`` print the same bytes
with this tree as with the package at git revision ``REV``: on ``examples/simulate/*.toml``
and on the scenes of ``bench_simulate.py`` (elastic ball, die edge on, die in 3D for 100 s and
3 s, Housner's rocking block), each run by the CLI in its own process (stdout, exit status and
stderr compared).

Run: ``.venv/bin/python benchmarks/same_simulate_outputs.py REV``; exit status 1 when any
output differs.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_simulate import ball_scene, die3d_scene, die_scene, rocking_scene

HERE = Path(__file__).resolve().parent


def outputs(src: str, files: list[Path]) -> dict[str, bytes]:
    """Each file's table and JSON output (stdout, exit status, stderr) with the package in
    ``src``."""
    env = dict(os.environ, PYTHONPATH=src)
    out = {}
    for f in files:
        for extra in ([], ["--json"]):
            run = subprocess.run([sys.executable, "-m", "carnot.cli", "simulate", str(f), *extra],
                                 env=env, capture_output=True, cwd=str(f.parent))  # fmt: skip
            out[f"{f.name} {' '.join(extra)}"] = (run.stdout + b"\n--rc %d--\n" % run.returncode
                                                   + run.stderr)  # fmt: skip
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("revision")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        files = sorted((HERE.parent / "examples" / "simulate").glob("*.toml"))
        for name, scene in (("ball", ball_scene(2000)), ("die", die_scene(100.0)),
                            ("die3d", die3d_scene(100.0)), ("die3d_short", die3d_scene(3.0)),
                            ("rocking", rocking_scene(3.0))):  # fmt: skip
            path = Path(tmp) / f"{name}.json"
            path.write_text(json.dumps(scene))
            files.append(path)
        archive = subprocess.run(["git", "-C", str(HERE.parent), "archive", args.revision,
                                  "src"], check=True, capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        before = outputs(str(Path(tmp) / "src"), files)
        now = outputs(str(HERE.parent / "src"), files)
    differ = [key for key in before if before[key] != now[key]]
    for key in before:
        print(f"{'DIFFERENT' if key in differ else 'same':<9}  {key} ({len(now[key])} bytes)")
    print(f"\n{len(before) - len(differ)} of {len(before)} outputs byte for byte the same as "
          f"at {args.revision}")  # fmt: skip
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()

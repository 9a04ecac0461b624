"""C callbacks compiled by child processes (issue 33 item 5): a child writes Numba's cache,
this process then finds the callback there (``cached``) and loads it instead of compiling;
a child that fails leaves nothing behind and the callback is still built here. A module of
two small callbacks stands in for the multi-contact kernel's three (whose children take
20 s: ``benchmarks/bench_cold_compile.py multi_impacts`` times them)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

MODULE = '''
import numba

SIGNATURE = numba.types.float64(numba.types.float64)


def twice(x):
    return 2.0 * x


def broken(x):
    return undefined_name * x  # (fails to compile: a child that fails)


def build_solvers(names):
    for name in names:
        numba.cfunc(SIGNATURE, cache=True)(globals()[name])
'''

PARENT = '''
import json, sys
import numba
import callbacks
from carnot.batch import compile_apart

before = {n: compile_apart.cached(getattr(callbacks, n), callbacks.SIGNATURE)
          for n in ("twice", "broken")}
children = compile_apart.start_children("callbacks", ["twice", "broken"])
compile_apart.wait_for(children)
codes = [c.returncode for c in children]
after = {n: compile_apart.cached(getattr(callbacks, n), callbacks.SIGNATURE)
         for n in ("twice", "broken")}
built = numba.cfunc(callbacks.SIGNATURE, cache=True)(callbacks.twice)
print(json.dumps({"before": before, "after": after, "codes": codes,
                  "hits": built.cache_hits, "value": built.ctypes(1.5)}))
'''


def test_a_child_compiles_into_the_cache_and_this_process_loads_it(tmp_path: Path) -> None:
    (tmp_path / "callbacks.py").write_text(textwrap.dedent(MODULE))
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}  # fmt: skip
    done = subprocess.run([sys.executable, "-c", PARENT], env=env, capture_output=True,
                          text=True, timeout=120, cwd=tmp_path, check=True)  # fmt: skip
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["before"] == {"twice": False, "broken": False}
    assert report["codes"][0] == 0 and report["codes"][1] != 0  # the broken child fails
    assert report["after"] == {"twice": True, "broken": False}
    assert report["hits"] == 1  # loaded from what the child wrote, not compiled again
    assert report["value"] == 3.0

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



def _build_seen(monkeypatch, first_cached: bool) -> tuple[list[str], list[list[str]]]:  # type: ignore[no-untyped-def]
    """The multi-contact kernel's build with the cache lookup, the children and the
    compiles replaced by records: which callbacks were asked about, which handed out."""
    from carnot.batch import compile_apart
    from carnot.batch import multi_kernel as mk

    asked: list[str] = []
    started: list[list[str]] = []

    def cached(function, signature) -> bool:  # type: ignore[no-untyped-def]
        asked.append(function.__name__)
        return first_cached and function.__name__ == mk.SOLVERS[0]

    def start_children(module: str, names: list[str]) -> list[object]:
        started.append(list(names))
        return []

    monkeypatch.setattr(compile_apart, "cached", cached)
    monkeypatch.setattr(compile_apart, "cores", lambda: 2)
    monkeypatch.setattr(compile_apart, "start_children", start_children)
    monkeypatch.setattr(mk, "_compile_c", lambda name: f"built {name}")
    assert mk._build_solvers(None) == tuple(f"built {n}" for n in mk.SOLVERS)
    return asked, started


def test_a_warm_start_asks_the_cache_about_the_costliest_callback_only(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The lookup loads the machine code it finds, which the build then loads again: where
    the costliest callback is cached (the three are written by one build), the others are
    loaded without being asked; where it is missing, each is asked and the missing ones
    planned (children for the two costliest on two cores, the third here)."""
    from carnot.batch import multi_kernel as mk

    assert _build_seen(monkeypatch, True) == ([mk.SOLVERS[0]], [[]])
    assert _build_seen(monkeypatch, False) == (list(mk.SOLVERS), [list(mk.SOLVERS[:2])])


def test_the_workspaces_types_are_the_compiled_functions_own() -> None:
    """The callbacks' signatures type the workspaces from what their Python functions return
    (``numba.typeof``: no compile); each must be the return type Numba infers when it
    compiles the function, or the entry points' calls would not match the callbacks."""
    import numba

    from carnot.batch import multi_kernel as mk

    args = (numba.types.int64, numba.types.int64)
    for workspace_of in (mk.workspace, mk.newton_workspace, mk.regime_workspace):
        workspace_of.compile(args)
        (compiled,) = (s.return_type for s in workspace_of.nopython_signatures if s.args == args)
        assert mk._returned(workspace_of) == compiled, workspace_of.__name__

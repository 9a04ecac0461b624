"""C callbacks compiled side by side, in processes of their own (issue 33 item 5, issue 35).

Numba compiles on one thread and under one lock per process, so a kernel made of several
large functions compiles in the sum of their times, on one core. Functions compiled as C
callbacks (``numba.cfunc`` with a fixed signature) and called by their address do not link
each other's code: each one's compile is independent of the others', and with
``cache=True`` its machine code is written to Numba's cache, where any process of the same
Python, Numba and source finds it. So the callbacks that a first call needs and the cache
lacks are compiled by child processes at once, one per core, while this process compiles the
rest; it then loads from the cache what a child wrote (a fraction of a second). The
multi-contact kernel's first call (its three regime solvers 18, 18 and 8 s alone on a quiet
core, its entry point 8 s) so took 32 s on two cores against 51 s in one process.

Nothing depends on the children: one that fails, or that cannot write the cache (a read-only
cache directory), leaves its callbacks to this process, which compiles them as it would have
without the children. The children run this package's own code (no input of the user's),
with the caller's environment (the same ``NUMBA_CACHE_DIR``) and the compile notice silenced.

Whether a callback is in the cache is asked of Numba's cache class itself
(:class:`numba.core.caching.FunctionCache`, the one ``cfunc(cache=True)`` uses, its public
``load_overload``): the same index, source stamp and machine key as the compile's.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable, Sequence
from typing import Any

#: The child's program: ``build_solvers(names)`` of the module named first (fixed code: the
#: module's own builder, the callbacks' names as the only arguments).
_CHILD = "import importlib, sys; importlib.import_module(sys.argv[1]).build_solvers(sys.argv[2:])"


def cached(function: Callable[..., Any], signature: Any) -> bool:
    """Whether ``numba.cfunc(signature, cache=True)(function)`` would load its machine code
    from Numba's cache instead of compiling it (Numba's own lookup: the same key).

    >>> cached(len, None)  # (not a function Numba can cache: a built-in)
    False
    """
    from numba.core.caching import FunctionCache
    from numba.core.registry import cpu_target

    try:
        cache = FunctionCache(function)
    except (RuntimeError, TypeError, AttributeError):  # no source file, or not a function
        return False
    return cache.load_overload(signature, cpu_target.target_context) is not None


def cores() -> int:
    """The cores this process may run on (its affinity where the system tells it)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # (macOS, Windows)
        return os.cpu_count() or 1


def start_children(module: str, names: Sequence[str]) -> list[subprocess.Popen[bytes]]:
    """One child process per name, each compiling that callback of ``module`` (its
    ``build_solvers([name])``) into Numba's cache; returns them running."""
    env = {**os.environ, "CARNOT_QUIET_COMPILE": "1"}
    return [subprocess.Popen([sys.executable, "-c", _CHILD, module, name], env=env,
                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)  # fmt: skip
            for name in names]


def wait_for(children: Sequence[subprocess.Popen[bytes]]) -> None:
    """Wait for every child; where this process is interrupted, stop them first."""
    try:
        for child in children:
            child.wait()
    finally:
        for child in children:
            if child.poll() is None:
                child.kill()
                child.wait()


def plan(costs: Sequence[float], missing: Sequence[bool], available: int) -> list[int]:
    """Which callbacks to hand to children: of the ``missing`` ones, the most costly, one
    per core, so long as this process keeps at least one to compile itself (it also
    compiles the entry point meanwhile: on two cores, two children and this process
    measured 32 s against 40 s with one child); none on one core. Indices into ``costs``,
    the most costly first.

    >>> plan([18.0, 18.0, 8.0], [True, True, True], 2)
    [0, 1]
    >>> plan([18.0, 18.0, 8.0], [True, False, True], 8)
    [0]
    >>> plan([18.0, 18.0, 8.0], [False, False, True], 8)
    []
    >>> plan([18.0, 18.0, 8.0], [True, True, True], 1)
    []
    """
    if available < 2:
        return []
    wanted = sorted((i for i, gone in enumerate(missing) if gone), key=lambda i: -costs[i])
    return wanted[:max(0, min(available, len(wanted) - 1))]

"""A line on stderr while a compiled kernel is being compiled (issue 35: compilation people
can see), so that a first batch or sweep does not sit silent for a minute.

Numba compiles a kernel on its first call in a process, or loads it from its cache (the
package's ``__pycache__``, or a user-wide directory where that is read-only; ``NUMBA_CACHE_DIR``
overrides both). Whether the cache will hit is not known before the call without Numba's
private API, so the notice is timed: a kernel that has no compiled signature in this process
and whose first call has not returned after :data:`NOTICE_AFTER` seconds (a cache load takes
well under that) prints one line saying what is compiled and that it is kept for next time.
Set ``CARNOT_QUIET_COMPILE=1`` to silence it.
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Callable
from typing import Any

#: Seconds after which a kernel's first call is announced as compiling.
NOTICE_AFTER = 2.0


def call_announcing(kernel: Any, what: str, *args: Any,
                    prepare: Callable[[Any], Any] | None = None) -> Any:  # fmt: skip
    """``kernel(*args)``; on the kernel's first call in this process (no signature compiled
    yet), a line on stderr if it takes more than :data:`NOTICE_AFTER` seconds. ``prepare``,
    if given, is called on the kernel first at every call (it may compile it, and the time
    counts; later, it returns the kernel once another thread's compile has ended).

    >>> call_announcing(lambda x: x + 1, "a plain function", 1)
    2
    """
    fresh = not getattr(kernel, "signatures", ())
    if not fresh or os.environ.get("CARNOT_QUIET_COMPILE"):
        return (kernel if prepare is None else prepare(kernel))(*args)
    timer = threading.Timer(NOTICE_AFTER, _announce(what))
    timer.daemon = True
    timer.start()
    try:
        return (kernel if prepare is None else prepare(kernel))(*args)
    finally:
        timer.cancel()


def _announce(what: str) -> Callable[[], None]:
    def say() -> None:
        print(f"carnot: compiling {what} (once: kept in Numba's cache for the next runs)",
              file=sys.stderr, flush=True)  # fmt: skip

    return say

"""The multi-contact kernel of another revision against this tree's, in one process.

This 2-core machine's speed moves by up to 2x from one minute to the next, more than most
changes to the kernel gain, so two benchmark processes run one after the other do not
compare. Here the other revision's ``carnot/batch/multi_kernel.py`` (a module of its own:
NumPy, Numba, math and ``carnot.conventions`` only) is loaded beside this tree's, and the two
kernels solve the same impacts as ``bench_batch_multi.py`` (10^6 planar 2-contact
frictionless ones, through the entry point that decides them, ``run_normal``; 10^4 box
landings on 4 corners, 3D Coulomb, sticking and sliding, through ``run``) alternately, pass
after pass: each pass's pair sees the same machine. Prints, per case, both rates (best
pass), the ratio of the bests and the median of the passes' ratios. The entry points'
arguments must mean the same in both revisions (true since issue 14's kernel took its
present form, but for the regime solvers' C callbacks that ``run`` takes last since they are
called by address: :func:`arguments_for`); the answers are checked apart
(``same_answers.py``).

Run: ``.venv/bin/python benchmarks/bench_kernel_ab.py --against REV [--passes 9]
[--cases sliding]`` (``REV`` a git revision or a ``src`` folder; the first run compiles the
other kernel, ~2 minutes; ``--cases``: some of ``planar,sticking,sliding``).
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_batch_multi import block, box  # noqa: E402
from same_answers import source_of  # noqa: E402

from carnot.batch import BatchBodies  # noqa: E402
from carnot.batch import multi_kernel as this_kernel  # noqa: E402
from carnot.batch.multi import multi_impacts  # noqa: E402


def other_kernel(src: Path):  # type: ignore[no-untyped-def]
    """The other revision's kernel module, importable by its own name, loaded from a copy
    of its own (a folder named by the file's hash under the temporary folder), so that
    Numba's cache of it holds only code compiled under that name. The revision's own
    cache was written by ``same_answers.py`` under the package's name, which gives its
    functions the same symbol names as this tree's kernel: a process holding both then
    links one's calls to the other's functions (seen: a corrupted heap, "corrupted size
    vs. prev_size", in the second kernel run after the first)."""
    path = src / "carnot" / "batch" / "multi_kernel.py"
    text = path.read_bytes()
    copy = Path(tempfile.gettempdir()) / f"carnot-ab-{hashlib.sha256(text).hexdigest()[:12]}"
    copy.mkdir(exist_ok=True)
    path = copy / "other_multi_kernel.py"
    if not path.exists() or path.read_bytes() != text:
        path.write_bytes(text)
    spec = importlib.util.spec_from_file_location("other_multi_kernel", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def run_arguments(case: tuple) -> tuple[str, tuple]:  # type: ignore[type-arg]
    """The entry point ``multi_impacts`` hands ``case`` to and its arguments: ``run`` for a
    frictional case; for a frictionless one, ``run_normal`` (its front, which decides every
    impact of these landings: ``G`` is not singular; ``run`` no longer tries that front's
    solver again, so ``run`` on them would time the regime enumeration instead)."""
    body, points, normals, e, mu = case
    seen: dict[str, tuple] = {}  # type: ignore[type-arg]
    originals = {name: getattr(this_kernel, name) for name in ("run", "run_normal")}

    class Keeper:
        """The entry point ``name``, recording its arguments (and, for ``multi``'s first
        call, the dispatcher's own ``signatures`` and ``compile``)."""

        def __init__(self, name: str) -> None:
            self.name = name

        def __call__(self, *args):  # type: ignore[no-untyped-def]
            seen[self.name] = args
            return originals[self.name](*args)

        def __getattr__(self, attribute: str):  # type: ignore[no-untyped-def]
            return getattr(originals[self.name], attribute)

    for name in originals:
        setattr(this_kernel, name, Keeper(name))
    try:
        multi_impacts(BatchBodies(**body), None, points, normals, e, mu)
    finally:
        for name, kernel in originals.items():
            setattr(this_kernel, name, kernel)
    if "run" in seen:
        return "run", seen["run"]
    return "run_normal", seen["run_normal"]


def arguments_for(kernel, entry: str, args: tuple) -> tuple[str, tuple]:  # type: ignore[no-untyped-def,type-arg]
    """The entry point of ``kernel`` for this tree's ``entry`` and its arguments ``args``
    (this tree's, for ``run`` its three C callbacks last: ``impact_solvers``): with that
    kernel's own callbacks (``impact_solvers``, or the one ``impact_solver`` of a revision
    before the regimes were called by address), or without one where its ``run`` calls its
    solvers directly (before they were called by address); ``run`` with this tree's
    callbacks' place where that kernel has no ``run_normal`` (a revision before it)."""
    if entry == "run_normal":
        if hasattr(kernel, "run_normal"):
            return "run_normal", args
        args = (*args, None, None, None)
    if hasattr(kernel, "impact_solvers"):
        return "run", (*args[:-3], *kernel.impact_solvers())
    if hasattr(kernel, "impact_solver"):
        return "run", (*args[:-3], kernel.impact_solver())
    return "run", args[:-3]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", required=True, help="git revision or src folder")
    parser.add_argument("--passes", type=int, default=9, help="alternating passes per case")
    parser.add_argument("--cases", default="planar,sticking,sliding",
                        help="comma-separated, of: planar, sticking, sliding")  # fmt: skip
    args = parser.parse_args()
    wanted = args.cases.split(",")
    unknown = sorted(set(wanted) - {"planar", "sticking", "sliding"})
    if unknown:
        parser.error(f"--cases: unknown case(s) {', '.join(unknown)}; "
                     "choose from planar, sticking, sliding")  # fmt: skip
    other = other_kernel(source_of(args.against))
    print(f"# {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}; other: {args.against}")
    rng = np.random.default_rng(5)  # (bench_batch_multi.py's draws: the same landings)
    cases = {"planar": block(rng, 1_000_000)}
    cases["sticking"] = box(rng, 10_000, 1.5, 0.8)
    cases["sliding"] = box(rng, 10_000, 0.2, 3.0)
    for name, case in cases.items():
        if name not in wanted:
            continue
        entry, kernel_args = run_arguments(case)
        other_entry, other_args = arguments_for(other, entry, kernel_args)
        ours_run, theirs_run = getattr(this_kernel, entry), getattr(other, other_entry)
        count = len(case[3])
        theirs_run(*other_args)  # (compiled and warm)
        ours_run(*kernel_args)
        theirs, ours = [], []
        for _ in range(args.passes):
            start = time.perf_counter()
            theirs_run(*other_args)
            theirs.append(time.perf_counter() - start)
            start = time.perf_counter()
            ours_run(*kernel_args)
            ours.append(time.perf_counter() - start)
        t, o = np.array(theirs), np.array(ours)
        print(f"{name:9s} other {count / t.min() / 1e3:6.1f} k/s, this {count / o.min() / 1e3:6.1f}"
              f" k/s (best of {args.passes}); ratio of the bests {t.min() / o.min():.3f}, median"
              f" of the passes' ratios {float(np.median(t / o)):.3f}")  # fmt: skip


if __name__ == "__main__":
    main()

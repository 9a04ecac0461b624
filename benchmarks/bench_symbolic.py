"""Wall-clock time of the symbolic work: the paper audit and the proofs of section 2.

Measured in one run, each ``--repeat`` times (default 3; the median is reported):

* ``baseline``: ``sympy.simplify`` reducing a fixed moderate expression (rational and
  trigonometric terms) to 0, a SymPy-only workload to divide the other figures by, so that
  they compare across machines and loads;
* ``run_symbolic_audit()``: the four examples of the paper's section 3 derived in closed form
  and every printed formula checked, in this process;
* ``carnot paper --symbolic``: the same through the command line in a fresh process, start-up
  and imports included (target: under 10 s);
* ``prove()``: the whole call, and each identity by its own ``Proof.seconds`` (target: each
  under 30 s).

SymPy's cache is cleared before every in-process repetition, so no run profits from the one
before it (a fresh process starts with an empty cache anyway).

Run: ``make bench`` or ``.venv/bin/python benchmarks/bench_symbolic.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable

import sympy as sp
from sympy.core.cache import clear_cache

from carnot.paper.audit import Verdict
from carnot.paper.symbolic_audit import run_symbolic_audit
from carnot.symbolic.proofs import Proof, prove

AUDIT_TARGET = 10.0  # s, the whole `carnot paper --symbolic`
PROOF_TARGET = 30.0  # s, each identity

a, b, c, x = sp.symbols("a b c x", positive=True)


def baseline() -> sp.Expr:
    """``sympy.simplify`` of a fixed sum that is identically 0."""
    expr = (
        ((a + b) ** 4 - (a - b) ** 4) / (8 * a * b * (a**2 + b**2))
        * (sp.sin(x) ** 2 + sp.cos(x) ** 2)
        + (a**3 - c**3) / (a - c) / (a**2 + a * c + c**2)
        + sp.tan(x) * sp.cos(x) / sp.sin(x)
        + sp.sin(2 * x) / (2 * sp.sin(x) * sp.cos(x))
        - 4
    )  # fmt: skip
    return sp.simplify(expr)


def timed(fn: Callable[[], object], repeat: int, cold: bool = True) -> list[float]:
    """Seconds of each call; SymPy's cache is cleared before each when ``cold``."""
    out = []
    for _ in range(repeat):
        if cold:
            clear_cache()
        start = time.perf_counter()
        fn()
        out.append(time.perf_counter() - start)
    return out


def run_cli(cmd: list[str]) -> None:
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    if "formulas:" not in done.stdout:
        raise RuntimeError(f"unexpected output of {' '.join(cmd)}:\n{done.stdout[-2000:]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of each figure (default 3)")
    repeat = max(1, parser.parse_args().repeat)
    load_start = os.getloadavg()[0]

    assert baseline() == 0
    rows: list[tuple[str, list[float], float | None]] = []
    rows.append(("baseline: sympy.simplify, fixed expression", timed(baseline, 7), None))

    verdicts: list[Verdict] = []

    def audit() -> None:
        verdicts[:] = run_symbolic_audit()[0]

    rows.append(("run_symbolic_audit() (in process)", timed(audit, repeat), AUDIT_TARGET))
    agree = sum(v.verdict == "agrees" for v in verdicts)
    cmd = [sys.executable, "-m", "carnot.cli", "paper", "--symbolic"]
    rows.append(("carnot paper --symbolic (new process)",
                 timed(lambda: run_cli(cmd), repeat, cold=False), AUDIT_TARGET))  # fmt: skip
    startup = [sys.executable, "-c", "import carnot.paper.symbolic_audit"]
    rows.append(("  (python -c 'import ...paper_audit', for scale)",
                 timed(lambda: subprocess.run(startup, check=True), repeat, cold=False),
                 None))  # fmt: skip

    runs: list[list[Proof]] = []

    def prove_all() -> None:
        runs.append(prove())

    rows.append(("prove(): all identities", timed(prove_all, repeat), None))
    for i, proof in enumerate(runs[0]):
        rows.append((f"  proof {proof.id}", [run[i].seconds for run in runs], PROOF_TARGET))

    base = statistics.median(rows[0][1])
    load_end = os.getloadavg()[0]
    print(f"python {platform.python_version()}, sympy {sp.__version__}, {os.cpu_count()} cpus, "
          f"{platform.machine()}; load average {load_start:.2f} at start, {load_end:.2f} at end; "
          f"median of {repeat} runs (baseline: of 7)")  # fmt: skip
    refuted = ", ".join(p.id for p in runs[0] if not p.holds) or "none"
    print(f"audit: {len(verdicts)} formulas, {agree} agree; proofs: "
          f"{sum(p.holds for p in runs[0])} of {len(runs[0])} identities "
          f"(not: {refuted}; expected not: eq16-eq4-labels)")  # fmt: skip
    print(f"{'symbolic work':<50} {'median':>8} {'min-max':>13} {'/ baseline':>11} "
          f"{'target':>13}")  # fmt: skip
    for name, times, target in rows:
        median = statistics.median(times)
        spread = f"{min(times):.2f}-{max(times):.2f}"
        verdict = "" if target is None else (
            f"< {target:.0f} s {'PASS' if median < target else 'MISS'}")  # fmt: skip
        print(f"{name:<50} {median:>6.2f} s {spread:>13} {median / base:>10.1f}x {verdict:>13}")


if __name__ == "__main__":
    main()

"""Shared test helpers."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

import pytest

from carnot import records

# the compile notice (carnot.batch.compile_notice) is tested on its own; elsewhere a worker's
# first compile would add a line to the stderr that the command-line tests read
os.environ.setdefault("CARNOT_QUIET_COMPILE", "1")
# Record.from_fields checks the names and order of the fields it is given, not only their
# number (carnot.records: every producer's fields, checked in every test that reaches it; read
# at each call, so set here whenever the module was imported)
records.CHECK_FIELDS = True

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


@pytest.fixture
def write_scenario(tmp_path: Path):
    """Write scenario text to a file and return its path."""

    def write(text: str, name: str = "scenario.toml") -> Path:
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path

    return write


@pytest.fixture
def example_path():
    """The path of a file in examples/."""

    def path(name: str) -> Path:
        return EXAMPLES / name

    return path


# ----------------------------------------------------- compile each kernel once (issue 35)
# A worker of pytest-xdist compiles every Numba kernel it reaches itself, unless another
# process has already written it to the on-disk cache: two workers reaching the same kernel
# at the same time both compile it (the multi-contact kernel: two to three minutes each).
# The tests that reach each heavy kernel form one unit of work of the scheduler below, so
# that one worker runs them all and compiles the kernel once, while the other worker runs
# the rest. (A test left out of its group still passes: its worker compiles the kernel, or
# loads it from the cache if the group's worker has written it.) The compile report below
# says which kernels compiled in which worker. (Not xdist's ``--dist loadgroup`` with
# ``xdist_group`` marks: it renames the tests through ``item._nodeid``, which pytest 9
# no longer reads, so every test was its own unit.)

#: Group -> the test files (paths from the repository root) and test nodes (a file, "::",
#: the test's name without parameters) that reach the group's kernels: the multi-contact
#: kernel (carnot.batch.multi_kernel's ``run`` and ``solve_rows`` and their solvers), the
#: one-contact batch kernels (carnot.batch.compiled: one per straight-line law, and one for
#: the three Coulomb laws, which takes most of a minute), and the audit's step kernels
#: (carnot.rollout.kernel and ``inplace``) with the 3D slip integrator.
KERNEL_GROUPS: dict[str, tuple[str, ...]] = {
    "multi_kernel": (
        "tests/test_batch_multi.py",
        "tests/test_batch_multi_tilted.py",
        "src/carnot/batch/multi.py",
        "src/carnot/batch/multi_kernel.py",
    ),
    "batch_kernel": (
        "tests/test_batch.py",
        "tests/test_batch_coulomb.py",
        "src/carnot/batch/kernels.py",
        "src/carnot/batch/coulomb.py",
        "tests/test_friction_high.py::test_the_batch_kernel_agrees",
        "tests/test_sweep.py::test_coulomb_friction_in_the_batch_route",
        "tests/test_sweep.py::test_plot_with_regimes",
    ),
    "rollout_kernel": (
        "tests/test_audit.py",
        "tests/test_audit_fast.py",
        "tests/test_audit_coupling.py",
        "tests/test_audit_robot.py",
        "tests/test_audit_real_models.py",
        # (the 3D slip integrator, carnot.laws.slip3d's kernel, which the audit of the Go2
        # reaches too: compiled in both workers, 6-11 s each, before it joined this group)
        "tests/test_friction.py::test_slip_kernel_on_planar_slip_equals_the_linear_closed_form",
    ),
}


def kernel_group(nodeid: str) -> str | None:
    """The group of the test ``nodeid`` (``path::name[params]``), or None.

    >>> kernel_group("tests/test_batch_multi.py::test_x[0.5]")
    'multi_kernel'
    >>> kernel_group("tests/test_sweep.py::test_plot_with_regimes"), kernel_group("tests/a.py::b")
    ('batch_kernel', None)
    """
    path, _, name = nodeid.partition("::")
    test = f"{path}::{name.partition('[')[0]}"
    for group, members in KERNEL_GROUPS.items():
        if path in members or test in members:
            return group
    return None


#: The test files with a fixture computed once for the file or the session (a MuJoCo wheel's
#: orbit, SymPy's audit, a browser): each file is one unit of work, so that one worker
#: computes it (split test by test, both did: the wheel's orbit twice, 6.7 s each).
SHARED_FIXTURES = frozenset(
    f"tests/{path.name}" for path in (ROOT / "tests").glob("test_*.py")
    if 'scope="module"' in (text := path.read_text(encoding="utf-8"))
    or 'scope="session"' in text or 'scope="class"' in text)  # fmt: skip


@pytest.hookimpl(optionalhook=True)  # (pytest-xdist's hook, in the controller)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """xdist's ``load`` scheduling (the default of ``-n``), with each kernel group and each
    file of :data:`SHARED_FIXTURES` one unit of work (the largest units are handed out
    first); another ``--dist`` as asked."""
    if config.getvalue("dist") != "load":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class KernelGroups(LoadScopeScheduling):  # type: ignore[misc]
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.partition("::")[0]
            return kernel_group(nodeid) or (path if path in SHARED_FIXTURES else nodeid)

    return KernelGroups(config, log)


#: Compiles of more than this (s) are reported at the end of the run.
REPORTED_COMPILE = 5.0
_compiles: list[tuple[str, str, float]] = []  # (kernel, test, seconds) in this process
_running = {"test": ""}


def pytest_sessionstart(session: pytest.Session) -> None:
    try:  # (0.3 s a process; a compile in the first test that imports Numba counts too)
        from numba.core import event
    except ImportError:  # pragma: no cover - numba is a dependency
        return

    class Outermost(event.Listener):  # type: ignore[misc]
        """Each outermost compile (a kernel called from Python, with everything it compiles
        inside), with the test that paid for it."""

        depth, began = 0, 0.0

        def on_start(self, ev: Any) -> None:
            self.depth += 1
            if self.depth == 1:
                self.began = time.perf_counter()

        def on_end(self, ev: Any) -> None:
            self.depth -= 1
            seconds = time.perf_counter() - self.began
            if self.depth == 0 and seconds >= REPORTED_COMPILE:
                fn = ev.data["dispatcher"].py_func
                _compiles.append((f"{fn.__module__}.{fn.__qualname__}", _running["test"],
                                  seconds))  # fmt: skip

    event.register("numba:compile", Outermost())


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item: pytest.Item) -> None:
    _running["test"] = item.nodeid


def pytest_sessionfinish(session: pytest.Session) -> None:
    output = getattr(session.config, "workeroutput", None)
    if output is not None:  # an xdist worker: to the controller
        output["carnot_compiles"] = json.dumps(_compiles)
    elif _mypy["process"] is not None:
        text, _ = _mypy["process"].communicate()
        _mypy["text"] = text
        if _mypy["process"].returncode != 0 and session.exitstatus == 0:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED


# ----------------------------------------------------- mypy beside the tests (issue 35)
# `make test` sets CARNOT_MYPY=1: mypy, one process on one core for about half a minute on a
# clean clone, then runs beside the tests instead of before them (the other core idled), its
# output a section of the summary and its failure the run's; `make lint` runs it alone.
_mypy: dict[str, Any] = {"process": None, "text": ""}


def pytest_configure(config: pytest.Config) -> None:
    worker = hasattr(config, "workerinput")
    if os.environ.get("CARNOT_MYPY") == "1" and not worker and _mypy["process"] is None:
        import subprocess
        import sys

        _mypy["process"] = subprocess.Popen(
            [sys.executable, "-m", "mypy", str(ROOT / "src" / "carnot")], cwd=ROOT,
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)  # fmt: skip


@pytest.hookimpl(optionalhook=True)  # (pytest-xdist's hook: the controller, at a worker's end)
def pytest_testnodedown(node: Any, error: Any) -> None:
    compiles = json.loads(getattr(node, "workeroutput", {}).get("carnot_compiles", "[]"))
    _compiles.extend((kernel, f"{node.gateway.id}: {test}", s) for kernel, test, s in compiles)


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if _mypy["process"] is not None:
        terminalreporter.section("mypy src/carnot (beside the tests)")
        terminalreporter.write_line(_mypy["text"].rstrip())
    if not _compiles:
        return
    terminalreporter.section("Numba compiles over 5 s (kernel: worker and test, seconds)")
    for kernel, test, seconds in sorted(_compiles, key=lambda c: (c[0], c[1])):
        terminalreporter.write_line(f"{seconds:6.1f} s  {kernel}  ({test})")

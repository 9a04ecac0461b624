"""Every compiled path's cold compile (issue 35, item 2): whole processes, each family of
Numba entry points in a fresh interpreter with an empty ``NUMBA_CACHE_DIR`` of its own,
against ``python -c "import numpy, scipy.linalg"`` in the same run.

For each family the child process times

* ``import``: the imports its first call needs (carnot's modules, Numba);
* ``cold``: the first call, on an empty cache: compiling every function it reaches, and
  writing them to the cache; ``cpu``: the process's CPU time in that call (Numba compiles
  on one thread: on a loaded machine the wall time grows, the CPU time much less);
* ``warm``: the same call again in the same process (what every later call costs);

and a second child, on the cache the first one filled, times its first call again:

* ``cached``: loading the compiled code from the cache (what the next run pays).

After its first call the child checks that the kernel it names has a compiled signature
(the call did reach the compiled path, not a fallback), and prints how many compiled
signatures each Numba dispatcher of the family's modules holds: a function compiled for
several type signatures (int32 against int64, C against A-order, a read-only array) is
compiled several times over.

Families (every ``numba.njit(cache=True)`` of ``src/carnot``):

* ``batch_frictionless``, ``batch_stick``: the one-contact batch kernel
  (:func:`carnot.batch.point_impacts`) of the two straight-line laws, serial build (fewer
  impacts than ``PARALLEL_MIN``); ``batch_parallel``: the frictionless law's parallel build;
* ``coulomb_newton``, ``coulomb_poisson``, ``coulomb_stronge``: the one-contact kernel of
  each Coulomb law (serial build); ``coulomb_three``: the three in one process (one kernel
  serves them: the hypothesis is its argument);
* ``multi_impacts``: the multi-contact kernel's body route (``multi_kernel.run``);
  ``multi_frictionless``: its frictionless front alone (``multi_kernel.run_normal``: a rod
  landing on its two ends, frictionless, whose ``G`` is not singular);
  ``contact_space_impacts``: its contact-space route (``multi_kernel.solve_rows``: two
  contacts whose ``G`` is singular, which its frictionless front leaves to it);
  ``multi_both``: the two in one process (what a test worker that reaches both pays: their
  regime solvers are shared where their argument types agree);
* ``systems``: the generalized-coordinate batch (:func:`carnot.batch.systems.solve_systems`,
  Coulomb): array code, nothing compiled (a control: ``cold`` is its first call only);
* ``slip3d``: ``solve_impact``'s 3D slip integrator (:mod:`carnot.laws.slip3d`);
* ``corners``: the simulator's corner kernels (:mod:`carnot.simulate.corners`), through a
  rimless wheel;
* ``rollout``: ``carnot audit``'s step kernels (:mod:`carnot.rollout.kernel`, ``inplace``;
  needs MuJoCo: skipped without it).

Target (issue 35): each cold compile <= 30 s.

Run: ``.venv/bin/python benchmarks/bench_cold_compile.py [FAMILY ...] [--signatures]
[--src DIR]`` (all by default; the multi-contact families take minutes each; ``--src``: time
another package tree, e.g. an older revision exported with ``git archive``).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
TARGET = 30.0

_MULTI_BOTH = """
import numpy as np
from carnot.batch import BatchBodies
from carnot.batch.multi import contact_space_impacts, multi_impacts
box = BatchBodies(mass=1.0, inertia_com=np.diag([0.1, 0.2, 0.25]), position_com=[0, 0, 0.1],
                  velocity_com=[0.3, 0.1, -1.0], angular_velocity=[0.2, -0.1, 0.0])
corners = [[-0.2, -0.1, 0.0], [0.2, -0.1, 0.0], [0.2, 0.1, 0.0], [-0.2, 0.1, 0.0]]
g = np.array([[1.0, 1.0], [1.0, 1.0]])  # (singular: left to solve_rows by its front)
"""
_BALL = """
import numpy as np
from carnot.batch import BatchBodies, point_impacts
ball = BatchBodies(mass=1.0, inertia_com=np.diag([0.004, 0.005, 0.006]),
                   position_com=[0.0, 0.0, 0.1], velocity_com=[1.0, 0.5, -2.0],
                   angular_velocity=[0.0, 3.0, 1.0])
"""


def _point(count: int, **options: str) -> str:
    extra = "".join(f", {k}={v}" for k, v in options.items())
    return (f"point_impacts(ball, None, [0.01, 0.0, 0.0], [0.0, 0.0, 1.0], "
            f"np.full({count}, 0.5){extra})")  # fmt: skip


def _coulomb(law: str) -> dict[str, str]:
    return {"setup": _BALL, "call": _point(8, friction="0.3", law=repr(law)),
            "kernel": f"carnot.batch.compiled:driver('coulomb_{law}', False)",
            "modules": "carnot.batch.compiled"}


#: family -> setup (run before the clock starts its first call, timed as "import"), the
#: call, the kernel that must hold a compiled signature after it ("module:expression"),
#: and the modules whose dispatchers are listed.
FAMILIES: dict[str, dict[str, str]] = {
    "batch_frictionless": {
        "setup": _BALL, "call": _point(8),
        "kernel": "carnot.batch.compiled:driver('frictionless', False)",
        "modules": "carnot.batch.compiled"},
    "batch_stick": {
        "setup": _BALL, "call": _point(8, tangential="'stick'"),
        "kernel": "carnot.batch.compiled:driver('stick', False)",
        "modules": "carnot.batch.compiled"},
    "batch_parallel": {
        "setup": _BALL, "call": _point(8192),
        "kernel": "carnot.batch.compiled:driver('frictionless', True)",
        "modules": "carnot.batch.compiled"},
    "coulomb_newton": _coulomb("newton"),
    "coulomb_poisson": _coulomb("poisson"),
    "coulomb_stronge": _coulomb("stronge"),
    "coulomb_three": {  # the three laws in turn: one kernel, its hypothesis an argument
        "setup": _BALL,
        "call": "(" + ", ".join(_point(8, friction="0.3", law=repr(law))
                                for law in ("newton", "poisson", "stronge")) + ")",
        "kernel": "carnot.batch.compiled:driver('coulomb_stronge', False)",
        "modules": "carnot.batch.compiled"},
    "multi_impacts": {
        "setup": """
import numpy as np
from carnot.batch import BatchBodies
from carnot.batch.multi import multi_impacts
box = BatchBodies(mass=1.0, inertia_com=np.diag([0.1, 0.2, 0.25]), position_com=[0, 0, 0.1],
                  velocity_com=[0.3, 0.1, -1.0], angular_velocity=[0.2, -0.1, 0.0])
corners = [[-0.2, -0.1, 0.0], [0.2, -0.1, 0.0], [0.2, 0.1, 0.0], [-0.2, 0.1, 0.0]]
""",
        "call": "multi_impacts(box, None, corners, [[0, 0, 1]] * 4, 0.3, 0.5)",
        "kernel": "carnot.batch.multi_kernel:run", "modules": "carnot.batch.multi_kernel"},
    "multi_frictionless": {
        "setup": """
import numpy as np
from carnot.batch import BatchBodies
from carnot.batch.multi import multi_impacts
rod = BatchBodies(mass=1.0, inertia_com=np.diag([1 / 12, 1 / 12, 1e-3]),
                  position_com=[0, 0, 0], velocity_com=[0, 0, -1.0],
                  angular_velocity=[0.0, 0.5, 0.0])
""",
        "call": "multi_impacts(rod, None, [[-0.5, 0, 0], [0.5, 0, 0]], [[0, 0, 1]] * 2, 0.5)",
        "kernel": "carnot.batch.multi_kernel:run_normal",
        "modules": "carnot.batch.multi_kernel"},
    "contact_space_impacts": {
        "setup": """
import numpy as np
from carnot.batch.multi import contact_space_impacts
g = np.array([[1.0, 1.0], [1.0, 1.0]])  # (singular: left to solve_rows by its front)
""",
        "call": "contact_space_impacts(g, [-1.0, -1.0], [0, 0], "
                "np.array([[0.0, 0.0], [1.0, 1.0]]))",
        "kernel": "carnot.batch.multi_kernel:solve_rows",
        "modules": "carnot.batch.multi_kernel"},
    "multi_both": {
        "setup": _MULTI_BOTH,
        "call": "(multi_impacts(box, None, corners, [[0, 0, 1]] * 4, 0.3, 0.5), "
                "contact_space_impacts(g, [-1.0, -1.0], [0, 0], "
                "np.array([[0.0, 0.0], [1.0, 1.0]])))",
        "kernel": "carnot.batch.multi_kernel:solve_rows",
        "modules": "carnot.batch.multi_kernel"},
    "systems": {
        "setup": """
import numpy as np
from carnot.batch.systems import solve_systems
m = np.broadcast_to(np.array([[2.0, 0.3], [0.3, 1.0]]), (8, 2, 2))
j = np.broadcast_to(np.array([[[1.0, 0.2], [0.0, 1.0], [0.0, 0.0]]]), (8, 1, 3, 2))
n = np.broadcast_to(np.array([[0.0, 1.0, 0.0]]), (8, 1, 3))
""",
        "call": "solve_systems(m, np.tile([0.5, -1.0], (8, 1)), j, n, 0.5, friction=0.4)",
        "kernel": "", "modules": "carnot.batch.systems"},
    "slip3d": {
        "setup": """
from carnot import solve_impact
from carnot.io.scenario import load_scenario
problem = load_scenario(EXAMPLES + '/box_corner_rough_floor.toml')
""",
        "call": "solve_impact(problem)", "kernel": "carnot.laws.slip3d:slip_phase",
        "modules": "carnot.laws.slip3d"},
    "corners": {
        "setup": """
from carnot.cli import main
args = ['simulate', EXAMPLES + '/simulate/rimless_wheel.toml', '--json']
""",
        "call": "main(args)", "kernel": "carnot.simulate.corners:corner_kinematics",
        "modules": "carnot.simulate.corners"},
    "rollout": {
        "setup": """
from carnot.cli import main
args = ['audit', EXAMPLES + '/audit/ball_drop.xml', '--keyframe', 'drop',
        '--restitution', '0.5', '--json']
""",
        "call": "main(args)", "kernel": "carnot.rollout.kernel:step_core",
        "modules": "carnot.rollout.kernel,carnot.rollout.inplace"},
}

#: The child: times the setup, the first and the second call, checks the kernel, lists
#: the dispatchers' signature counts, and prints one JSON line last.
CHILD = r"""
import contextlib, importlib, io, json, sys, time
family = json.loads(sys.argv[1])
EXAMPLES = sys.argv[2]
t0 = time.perf_counter()
exec(family["setup"])
import numba
t1, c1 = time.perf_counter(), time.process_time()
with contextlib.redirect_stdout(io.StringIO()):
    eval(family["call"])
t2, c2 = time.perf_counter(), time.process_time()
with contextlib.redirect_stdout(io.StringIO()):
    eval(family["call"])
t3 = time.perf_counter()
reached = None
if family["kernel"]:
    module, expression = family["kernel"].split(":")
    reached = len(eval(expression, vars(importlib.import_module(module))).signatures)
counts = {}
for name in family["modules"].split(","):
    for key, fn in sorted(vars(importlib.import_module(name)).items()):
        if isinstance(fn, numba.core.dispatcher.Dispatcher) and fn.signatures:
            counts[f"{name}.{key}"] = len(fn.signatures)
print(json.dumps({"import": t1 - t0, "first": t2 - t1, "first_cpu": c2 - c1, "warm": t3 - t2,
                  "reached": reached, "signatures": counts}))
"""


def _child(family: dict[str, str], cache: str, src: Path) -> dict[str, object]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "OPENBLAS_NUM_THREADS": "1",
           "CARNOT_QUIET_COMPILE": "1"}  # fmt: skip
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(src),
                                                      env.get("PYTHONPATH")]))  # fmt: skip
    done = subprocess.run([sys.executable, "-c", CHILD, json.dumps(family), str(EXAMPLES)],
                          env=env, capture_output=True, text=True)  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"{family['call']}: exit {done.returncode}\n{done.stderr[-2000:]}")
    result: dict[str, object] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def _baseline() -> float:
    best = float("inf")
    for _ in range(3):
        began = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import numpy, scipy.linalg"], check=True)
        best = min(best, time.perf_counter() - began)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("families", nargs="*", metavar="FAMILY",
                        help=f"families to measure (default: all): {', '.join(FAMILIES)}")
    parser.add_argument("--src", type=Path, default=ROOT / "src",
                        help="the package tree to time (default: this checkout's src)")
    parser.add_argument("--signatures", action="store_true",
                        help="list each dispatcher's number of compiled signatures")
    opts = parser.parse_args()
    names = opts.families or list(FAMILIES)
    unknown = sorted(set(names) - set(FAMILIES))
    if unknown:
        parser.error(f"unknown family {unknown[0]!r}: choose from {', '.join(FAMILIES)}")
    print(f"python {platform.python_version()}, {os.cpu_count()} cores, package {opts.src}")
    with tempfile.TemporaryDirectory() as tmp:
        print(f"baseline (python -c 'import numpy, scipy.linalg', best of 3): "
              f"{_baseline():.2f} s")  # fmt: skip
        print(f"{'family':24} {'import':>7} {'cold':>8} {'cpu':>8} {'warm':>8} {'cached':>7}"
              "  target")  # fmt: skip
        over = []
        for name in names:
            if name == "rollout" and importlib.util.find_spec("mujoco") is None:
                print(f"{name:24} skipped (needs the mujoco extra)")
                continue
            cache = f"{tmp}/{name}"
            cold = _child(FAMILIES[name], cache, opts.src)
            again = _child(FAMILIES[name], cache, opts.src)
            if cold["reached"] == 0:  # (a wrong family: said, and the others measured)
                print(f"{name:24} did not compile {FAMILIES[name]['kernel']}")
                continue
            first = float(cold["first"])  # type: ignore[arg-type]
            verdict = "-" if not FAMILIES[name]["kernel"] else (
                "met" if first <= TARGET else "NOT MET")  # fmt: skip
            if verdict == "NOT MET":
                over.append(name)
            print(f"{name:24} {cold['import']:6.2f}s {first:7.2f}s {cold['first_cpu']:7.2f}s "
                  f"{cold['warm']:7.4f}s "
                  f"{again['first']:6.2f}s  {verdict}", flush=True)  # fmt: skip
            counts: dict[str, int] = cold["signatures"]  # type: ignore[assignment]
            several = ", ".join(f"{fn.rsplit('.', 1)[1]} {n}" for fn, n in counts.items()
                                if n > 1)  # fmt: skip
            if counts:  # (module-level dispatchers only: the batch kernels are built per law)
                print(f"    {len(counts)} dispatchers compiled, {sum(counts.values())} signatures;"
                      f" more than one: {several or 'none'}")  # fmt: skip
            if opts.signatures:
                for fn, n in counts.items():
                    print(f"    {n} x {fn}")
        print(f"over {TARGET:.0f} s: {', '.join(over) or 'none'}")


if __name__ == "__main__":
    main()

"""Start-up: what a fresh process imports to load carnot, print the command line's help and
solve one point impact.

A command pays at start-up for every module it imports, used or not: SciPy's integrators
alone cost more than NumPy (0.25 s), SymPy, Matplotlib, Numba, pyarrow, Dask and MuJoCo as
much again each. Each is imported by the function that needs it; these tests run a new
interpreter (``sys.modules`` of this one holds whatever other tests imported) and fail when a
module-level import brings one back. Timings: ``benchmarks/bench_startup.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from conftest import EXAMPLES, ROOT

#: Imported by none of the impacts below: the dispersion law's integrator, the linear program
#: and root finder of several contacts, the symbolic, plotting, compiled and sweep stacks.
NOT_FOR_ONE_IMPACT = (
    "scipy.integrate",
    "scipy.optimize",
    "scipy.special",
    "sympy",
    "matplotlib",
    "numba",
    "pyarrow",
    "dask",
    "mujoco",
    "tqdm",
    "jax",
)

#: Prints the heavy modules (of ``NOT_FOR_ONE_IMPACT``, and NumPy and SciPy) the process holds.
_REPORT = (
    "import sys, json\n"
    "heavy = {heavy!r} + ('numpy', 'scipy')\n"
    "print(json.dumps(sorted(m for m in heavy if m in sys.modules)))\n"
)


def _imported(code: str) -> list[str]:
    """The heavy modules a fresh interpreter holds after running ``code`` (this tree's
    package first on the path, whatever is installed)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), *filter(None, [env.get("PYTHONPATH")])])
    script = code + "\n" + _REPORT.format(heavy=NOT_FOR_ONE_IMPACT)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env=env, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


def test_import_carnot_imports_no_numpy() -> None:
    """``import carnot`` binds its public names when first read (PEP 562)."""
    assert _imported("import carnot\nassert carnot.__version__") == []


def test_help_and_version_import_no_numpy() -> None:
    """``carnot --help``, ``--version`` and each command's ``--help``: argparse only."""
    code = (
        "import contextlib, io\n"
        "from carnot.cli import build_parser, main\n"
        "commands = [[]] + [[c] for c in ('solve', 'paper', 'prove', 'derive', 'sweep',\n"
        "                                 'from-mjcf', 'audit', 'simulate', 'explore')]\n"
        "for argv in [['--version']] + [c + ['--help'] for c in commands]:\n"
        "    with contextlib.redirect_stdout(io.StringIO()):\n"
        "        try:\n"
        "            main(argv)\n"
        "        except SystemExit as done:\n"
        "            assert done.code == 0, (argv, done.code)\n"
    )
    assert _imported(code) == []


def test_the_console_module_help_imports_no_numpy() -> None:
    """As ``python -m carnot.cli --help`` runs it (the module the entry point calls)."""
    code = (
        "import contextlib, io, runpy, sys\n"
        "sys.argv = ['carnot', '--help']\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n"
        "        runpy.run_module('carnot.cli', run_name='__main__')\n"
        "    except SystemExit as done:\n"
        "        assert done.code == 0, done.code\n"
    )
    assert _imported(code) == []


def test_one_frictionless_point_impact_imports_numpy_only() -> None:
    """``carnot.solve_impact`` of a ball on a floor, built in Python: NumPy, and no SciPy (the
    multiple-impact laws' linear algebra is imported for several contacts only)."""
    code = (
        "from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact\n"
        "ball = RigidBody(name='ball', mass=0.5, inertia_com=[[0.002, 0, 0], [0, 0.002, 0],\n"
        "                 [0, 0, 0.002]], position_com=[0, 0, 0.1], velocity_com=[1, 0, -3])\n"
        "contact = PointContact(a='ball', b='floor', point=[0, 0, 0], normal=[0, 0, 1],\n"
        "                       restitution=0.6)\n"
        "bodies = {'ball': ball, 'floor': FixedBody(name='floor')}\n"
        "res = solve_impact(ImpactProblem(bodies=bodies, contacts=[contact]))\n"
        "assert abs(res.energy.dissipated - 1.44) < 1e-12, res.energy.dissipated\n"
    )
    assert _imported(code) == ["numpy"]


@pytest.mark.parametrize(
    ("example", "heavy"),
    [("ball_on_floor.toml", ["numpy"]), ("box_lands_flat.toml", ["numpy", "scipy"])],
)
def test_carnot_solve_of_an_example_imports_only_what_it_uses(example: str, heavy) -> None:
    """``carnot solve FILE`` and ``--json``: one point impact (a ball: NumPy only) and a box
    landing flat on four rough corners (the simultaneous law: SciPy's linear algebra too)."""
    path = str(EXAMPLES / example)
    code = (
        "import contextlib, io\n"
        "from carnot.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    assert main(['solve', {path!r}]) == 0\n"
        f"    assert main(['solve', {path!r}, '--json']) == 0\n"
    )
    assert _imported(code) == heavy


def test_a_bad_file_is_refused_without_the_solvers(write_scenario) -> None:
    """Bad input: one line, status 2, and no solver imported to say so."""
    bad = write_scenario("format = 1\n[bodies.b]\nmass = -1.0\n")
    code = (
        "import contextlib, io\n"
        "from carnot.cli import main\n"
        "err = io.StringIO()\n"
        "with contextlib.redirect_stderr(err):\n"
        f"    assert main(['solve', {str(bad)!r}]) == 2\n"
        f"assert err.getvalue() == 'carnot: error: {bad}: bodies.b.mass: must be > 0, "
        "got -1.0\\n', err.getvalue()\n"
    )
    assert _imported(code) == ["numpy"]


def test_the_public_names_resolve_when_read() -> None:
    """``from carnot import X``, ``carnot.X``, ``dir`` and ``from carnot import *`` as before
    the names became lazy; an unknown name is still an AttributeError."""
    import carnot
    import carnot.model
    import carnot.result
    import carnot.solve

    assert carnot.solve_impact is carnot.solve.solve_impact
    assert carnot.RigidBody is carnot.model.RigidBody
    assert carnot.ImpactResult is carnot.result.ImpactResult
    assert set(carnot.__all__) <= set(dir(carnot))
    names: dict[str, object] = {}
    exec("from carnot import *", names)
    assert set(carnot.__all__) <= set(names)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        carnot.nothing  # noqa: B018

"""The compile cache where the package directory is read-only (issue 35: a system install, a
container): Numba cannot write the package's ``__pycache__``, keeps the kernels in the
user-wide cache instead (``$XDG_CACHE_HOME/numba``, else ``~/.cache/numba``), and the next
process loads them from there instead of compiling again.

The real package is copied into a temporary directory made read-only; as root (whom file
permissions do not stop) each package directory also gets a plain file named
``__pycache__``, so that the directory cannot be created whoever runs the test. Two fresh
processes then run the one-contact batch kernel (the frictionless law: a short compile),
with ``NUMBA_CACHE_DIR`` unset and ``HOME`` and ``XDG_CACHE_HOME`` in the temporary
directory."""

from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import carnot

#: The child: a ball (1 kg) dropped at 2 m/s on a floor, e = 0.5 (it leaves at 1 m/s and
#: 1.5 J is dissipated), through the compiled kernel; then where the kernel's cache is, and
#: its cache hits and misses in this process.
CHILD = """
import json
import numpy as np
import carnot
from carnot.batch import BatchBodies, point_impacts
from carnot.batch.compiled import driver
ball = BatchBodies(mass=1.0, inertia_com=np.eye(3) * 0.004, position_com=[0, 0, 0.1],
                   velocity_com=[0, 0, -2.0])
out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], np.array([0.5, 0.5]), backend="numba",
                    parallel=False)
stats = driver("frictionless", False).stats
print(json.dumps({"package": carnot.__file__, "velocity": out.velocity_a[:, 2].tolist(),
                  "dissipated": out.dissipated.tolist(), "cache": stats.cache_path,
                  "hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values())}))
"""


def _read_only_copy(root: Path) -> Path:
    """``src/carnot`` copied under ``root/site``, every directory and file read-only."""
    site = root / "site"
    package = site / "carnot"
    shutil.copytree(Path(carnot.__file__).parent, package,
                    ignore=shutil.ignore_patterns("__pycache__"))  # fmt: skip
    folders = [package, *(p for p in package.rglob("*") if p.is_dir())]
    if os.geteuid() == 0:  # (root writes through permissions: a file where the folder goes)
        for folder in folders:
            (folder / "__pycache__").write_text("not a folder\n", encoding="utf-8")
    for path in [*package.rglob("*"), package, site]:
        mode = path.stat().st_mode
        path.chmod(mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    return site


def _run(site: Path, home: Path) -> dict[str, object]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "PYTHON"))}
    env.update(PYTHONPATH=str(site), HOME=str(home), XDG_CACHE_HOME=str(home / "cache"),
               PYTHONDONTWRITEBYTECODE="1", CARNOT_QUIET_COMPILE="1")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True,
                          text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    result: dict[str, object] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def test_a_read_only_package_caches_in_the_user_wide_directory(tmp_path: Path) -> None:
    site = _read_only_copy(tmp_path)
    home = tmp_path / "home"
    home.mkdir()
    try:
        first = _run(site, home)
        second = _run(site, home)
    finally:  # (writable again, so that pytest can remove the copy)
        for path in [site, *site.rglob("*")]:
            path.chmod(path.stat().st_mode | stat.S_IWUSR)
    for run in (first, second):
        assert Path(str(run["package"])).is_relative_to(site)  # the copy, not the checkout
        # Newton's e on a fixed floor: v'' = -e v' = 1 m/s; E_d = (1 - e^2) m v'^2 / 2
        assert run["velocity"] == [1.0, 1.0]
        assert run["dissipated"] == [1.5, 1.5]
        assert Path(str(run["cache"])).is_relative_to(home / "cache" / "numba")
    assert first["misses"] > 0 and first["hits"] == 0  # compiled, and written
    assert second["hits"] > 0 and second["misses"] == 0  # loaded: nothing compiled
    assert list((home / "cache" / "numba").rglob("*.nbi"))
    assert not [p for p in site.rglob("*") if p.suffix in (".nbi", ".nbc")]

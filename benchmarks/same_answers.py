"""Same answers as another revision: random box landings (issue 14's speed work must not change
any answer) through ``carnot.batch.multi_impacts`` and through ``carnot.solve_impact``, with
this tree and with the package at ``--against`` (a git revision, exported once to a folder
under the system's temporary directory and kept there, so that Numba's cache of its kernel
survives between runs; or the path of a ``src`` folder), each in its own process.

Cases (:func:`bench_batch_multi.box`, the benchmark's inputs): the box landing flat on four
corners, sticking (mu 1.5, sliding at up to 0.8 m/s) and sliding (mu 0.2, up to 3 m/s), and the
same box tilted (a random rotation about the vertical and a small tilt, so that corners lift
and the regimes mix). Compared row by row: every contact's regime, every flag, and the
velocities after (batch and API) to ``--tol`` m/s; the impulses where they are unique.
Exits 1 on any difference.

Run: ``.venv/bin/python benchmarks/same_answers.py --against main [--n 2000] [--api 2000]``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def cases(n: int) -> dict[str, tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray,
                                     np.ndarray]]:  # fmt: skip
    """The inputs, the same in every process (fixed seeds)."""
    sys.path.insert(0, str(HERE))
    from bench_batch_multi import box

    out = {}
    for name, mu, slide, seed in (("sticking", 1.5, 0.8, 11), ("sliding", 0.2, 3.0, 12),
                                  ("tilted sticking", 1.5, 0.8, 13),
                                  ("tilted sliding", 0.2, 3.0, 14)):  # fmt: skip
        rng = np.random.default_rng(seed)
        body, points, normals, e, mus = box(rng, n, mu, slide)
        if name.startswith("tilted"):
            # lift the corners a little: a rotation of the contact normals (the ground's
            # normal seen from the box) by up to 0.05 rad, so a corner or two separates
            axis = rng.normal(size=(n, 3))
            axis[:, 2] = 0.0
            axis /= np.linalg.norm(axis, axis=1, keepdims=True)
            angle = rng.uniform(0.0, 0.05, n)
            up = np.array([0.0, 0.0, 1.0])
            tilt = (up * np.cos(angle)[:, None] + np.cross(axis, up) * np.sin(angle)[:, None])
            normals = np.repeat(tilt[:, None, :], points.shape[1], axis=1)
        out[name] = (body, points, normals, e, mus)
    return out


def dump(path: str, n: int, api: int, only: str = "") -> None:
    """This process's package on the cases, into ``path`` (NumPy's npz)."""
    from carnot import solve_impact
    from carnot.batch import BatchBodies
    from carnot.batch.multi import multi_impacts

    sys.path.insert(0, str(HERE))
    from bench_batch_multi import landing_problem

    arrays: dict[str, np.ndarray] = {}
    for name, (body, points, normals, e, mu) in cases(n).items():
        if only and not any(item == name for item in only.split(",")) and only not in name:
            continue
        out = multi_impacts(BatchBodies(**body), None, points, normals, e, mu)
        key = name.replace(" ", "_")
        arrays[f"{key}.regime"] = out.regime
        arrays[f"{key}.velocity"] = np.concatenate([out.velocity_a, out.angular_velocity_a],
                                                   axis=1)  # fmt: skip
        arrays[f"{key}.impulse"] = out.impulse.reshape(n, -1)
        arrays[f"{key}.flags"] = np.stack(
            [out.statically_indeterminate, out.multiple_solutions, out.no_solution,
             out.separating_contact_approaches, out.uniqueness_verified,
             out.by_reference], axis=1)  # fmt: skip
        regimes, flags, velocity = [], [], []
        for i in range(min(api, n)):
            res = solve_impact(landing_problem((body, points, normals, e, mu), i))
            regimes.append("/".join(c.regime for c in res.contacts))
            flags.append("/".join(sorted(res.flag_codes())))
            after = res.bodies["body"]
            velocity.append(np.concatenate([after.velocity_after, after.angular_velocity_after]))
        arrays[f"{key}.api_regime"] = np.array(regimes)
        arrays[f"{key}.api_flags"] = np.array(flags)
        arrays[f"{key}.api_velocity"] = np.array(velocity).reshape(-1, 6)
    np.savez(path, **arrays)


def source_of(against: str) -> Path:
    """The ``src`` folder of ``against`` (a folder, or a git revision exported once)."""
    if Path(against).is_dir():
        return Path(against).resolve()
    rev = subprocess.run(["git", "-C", str(HERE.parent), "rev-parse", against], check=True,
                         capture_output=True, text=True).stdout.strip()  # fmt: skip
    folder = Path(tempfile.gettempdir()) / f"carnot-against-{rev[:12]}"
    if not (folder / "src").is_dir():
        folder.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "-C", str(HERE.parent), "archive", rev, "src"],
                                 check=True, capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder / "src"


def compare(a: np.lib.npyio.NpzFile, b: np.lib.npyio.NpzFile, tol: float) -> bool:
    same = True
    for key in sorted(a.files):
        x, y = a[key], b[key]
        if x.dtype.kind in "fc":
            diff = float(np.max(np.abs(x - y))) if x.size else 0.0
            if key.endswith(".impulse"):  # unique impulses only: where no row is indeterminate
                flags = a[key.replace(".impulse", ".flags")]
                keep = ~flags[:, 0]
                diff = float(np.max(np.abs(x[keep] - y[keep]))) if keep.any() else 0.0
            ok = diff <= tol
            print(f"  {key:34s} max |difference| {diff:.1e}  {'same' if ok else 'DIFFERENT'}")
        else:
            unequal = int(np.sum(np.any((x != y).reshape(len(x), -1), axis=1)))
            ok = unequal == 0
            print(f"  {key:34s} {unequal} of {len(x)} rows differ  {'same' if ok else 'DIFFERENT'}")
        same = same and ok
    return same


def batch_against_api(a: np.lib.npyio.NpzFile, tol: float) -> None:
    """Within one tree: the rows whose batch answer is not ``solve_impact``'s (regimes, the
    flags both report, velocities to ``tol``), per case (only the rows solved by both)."""
    names = {0: "separate", 1: "frictionless", 2: "stick", 3: "slip"}
    flag_names = ("statically_indeterminate", "multiple_solutions", "no_solution",
                  "separating_contact_approaches")  # fmt: skip
    for key in sorted({f.split(".")[0] for f in a.files}):
        api_regime = a[f"{key}.api_regime"]
        count = len(api_regime)
        regime = ["/".join(names[int(r)] for r in row) for row in a[f"{key}.regime"][:count]]
        flags = ["/".join(sorted(n for n, f in zip(flag_names, row, strict=False) if f))
                 for row in a[f"{key}.flags"][:count]]  # fmt: skip
        api_flags = ["/".join(sorted(f for f in row.split("/") if f in flag_names))
                     for row in a[f"{key}.api_flags"]]  # fmt: skip
        dv = np.max(np.abs(a[f"{key}.velocity"][:count] - a[f"{key}.api_velocity"]), axis=1)
        differ = [i for i in range(count) if regime[i] != api_regime[i]
                  or flags[i] != api_flags[i] or dv[i] > tol]  # fmt: skip
        by_ref = int(np.sum(a[f"{key}.flags"][:, 5]))
        print(f"  {key:18s} batch vs solve_impact: {len(differ)} of {count} rows differ "
              f"{differ[:12]}; by_reference {by_ref} of {len(a[f'{key}.regime'])}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default="main", help="git revision or src folder")
    parser.add_argument("--n", type=int, default=2000, help="batch rows per case")
    parser.add_argument("--api", type=int, default=2000, help="solve_impact calls per case")
    parser.add_argument("--tol", type=float, default=1e-12, help="velocities, m/s")
    parser.add_argument("--cases", default="",
                        help="only the cases whose name holds this, or named exactly in this "
                             "comma-separated list (e.g. 'sticking,sliding': not tilted)")
    parser.add_argument("--keep", help="keep the two processes' answers in this folder")
    parser.add_argument("--dump", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.dump:
        dump(args.dump, args.n, args.api, args.cases)
        return
    trees = {"this tree": HERE.parent / "src", args.against: source_of(args.against)}
    with tempfile.TemporaryDirectory() as scratch:
        tmp = args.keep or scratch
        files = []
        for label, src in trees.items():
            path = os.path.join(tmp, f"{len(files)}.npz")
            env = dict(os.environ, PYTHONPATH=str(src))
            subprocess.run([sys.executable, __file__, "--dump", path, "--n", str(args.n),
                            "--api", str(args.api), "--cases", args.cases], check=True,
                           env=env)  # fmt: skip
            print(f"{label}: {src}")
            files.append(np.load(path))
            batch_against_api(files[-1], 1e-9)
        same = compare(files[0], files[1], args.tol)
    print("same answers" if same else "ANSWERS DIFFER")
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()

"""Unitree H1's crumpling landing (issue 33): the contact problems of its audit, saved as test
data, and the iterative solver measured on them.

The model: ``unitree_robots/h1/scene.xml`` of unitree_mujoco (commit c598f10, BSD-3-Clause),
dropped from ``qpos0`` with its free joint lifted 0.3 m, 1.5 s of MuJoCo's own rollout and
``carnot audit``'s rigid references (``RigidSettings()``: e = 0, the geoms' friction, the
contacts coupled to each episode's pair, every contact within the largest geom margin, joint
limits on). Its 62 episodes give 30 contact problems that the iterative solver answers (the
others are enumerated); with the default 10000 iterations, six used to end ``not_converged``
(eight episodes), three more needed 7000 to 8100.

Writing the data (the model exported first, e.g. ``git --git-dir=.../unitree_mujoco archive
c598f10 unitree_robots/h1 | tar -x -C /tmp/unitree``)::

    .venv/bin/python benchmarks/h1_crumple.py --model /tmp/unitree/unitree_robots/h1/scene.xml \\
        --write tests/data/h1_crumple

writes one ``.npz`` a problem (arrays only: ``np.load(path, allow_pickle=False)``): ``G``
(``delassus``), ``w_before``, ``q`` (De Saxce's form, restitution included), each contact's
``normal`` row, ``tangents`` (-1 where absent), ``friction``, ``restitution``, the held rows
and their targets, the contacts' ``names``, and the state it came from (``qpos``, ``qvel``,
the episode's ``pair``, ``time``) with ``provenance``. Measuring the saved problems (no
MuJoCo needed)::

    .venv/bin/python benchmarks/h1_crumple.py --data tests/data/h1_crumple [--rounds 3]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from carnot.laws.multiple import ContactRows, HeldRows
from carnot.solvers.iterative import solve_iterative
from carnot.solvers.problem import contact_problem, fc3d_error

PROVENANCE = (
    "Unitree H1, unitree_mujoco commit c598f10, unitree_robots/h1/scene.xml (BSD-3-Clause); "
    "qpos0 with the free joint lifted 0.3 m, qvel 0, 1.5 s of MuJoCo 4.0.0's rollout; the "
    "contact problem of carnot audit's rigid reference (RigidSettings(): e = 0, the geoms' "
    "friction, scope coupled, gap the largest geom margin, limits on) at the episode's "
    "qpos_before and qvel_before"
)


def capture(model_path: str) -> list[dict[str, Any]]:
    """Every contact problem the audit's references hand to the iterative solver, with the
    state and the episode's pair it came from, and how the solver did then."""
    import mujoco

    import carnot.several as several
    from carnot.rollout import RigidSettings, audit_model
    from carnot.rollout.audit import EnergyAudit

    records: list[dict[str, Any]] = []
    current: dict[str, Any] = {}
    original_resolve = several.resolve
    original_solved = EnergyAudit._solved

    def solved(self: Any, episode: Any, settings: Any, problem: Any, solve: Any) -> Any:
        current["episode"] = episode
        current["names"] = [c.name for c in problem.contacts]
        return original_solved(self, episode, settings, problem, solve)

    def resolve(g: Any, w: Any, contacts: Any, held: Any = None, options: Any = None) -> Any:
        t0 = time.perf_counter()
        out = original_resolve(g, w, contacts, held, options)
        spent = time.perf_counter() - t0
        cert = out.certificate
        if cert is not None and cert.solver == "iterative":
            e = current["episode"]
            records.append({"g": np.asarray(g.toarray() if hasattr(g, "toarray") else g),
                            "w": np.array(w), "contacts": tuple(contacts), "held": held,
                            "names": list(current.get("names", [])),
                            "qpos": np.array(e.qpos_before), "qvel": np.array(e.qvel_before),
                            "pair": tuple(e.pair), "time": float(e.start),
                            "converged": cert.converged, "residual": cert.residual,
                            "iterations": cert.iterations, "seconds": spent})  # fmt: skip
        return out

    several.resolve = resolve
    EnergyAudit._solved = solved
    try:
        model = mujoco.MjModel.from_xml_path(model_path)
        qpos = model.qpos0.copy()
        qpos[2] += 0.3
        audit_model(model_path, duration=1.5, qpos=qpos.tolist(), rigid=RigidSettings())
    finally:
        several.resolve = original_resolve
        EnergyAudit._solved = original_solved
    # the same problem solved for several episodes (feet landing at once): kept once
    unique: dict[bytes, dict[str, Any]] = {}
    for r in records:
        unique.setdefault(r["g"].tobytes() + r["w"].tobytes(), r)
    return list(unique.values())


def write(records: list[dict[str, Any]], folder: Path, min_iterations: int) -> list[Path]:
    """The problems that did not converge, or took at least ``min_iterations``, one ``.npz``
    each (module docstring)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for r in records:
        if r["converged"] and r["iterations"] < min_iterations:
            continue
        contacts: tuple[ContactRows, ...] = r["contacts"]
        held: HeldRows | None = r["held"]
        problem = contact_problem(r["g"], r["w"], contacts, held)
        tangents = np.full((len(contacts), 2), -1, dtype=np.int64)
        for k, c in enumerate(contacts):
            tangents[k, : len(c.tangents)] = c.tangents
        floor = sum("floor" in n for n in r["names"])
        kind = "floor" if floor == len(r["names"]) else ("self" if floor == 0 else "mixed")
        name = f"h1_t{r['time']:.3f}_{kind}_{len(contacts)}c.npz"
        path = folder / name
        np.savez_compressed(
            path, delassus=r["g"], w_before=r["w"], q=problem.q,
            normal=np.array([c.normal for c in contacts], dtype=np.int64), tangents=tangents,
            friction=np.array([c.friction for c in contacts]),
            restitution=np.array([c.restitution for c in contacts]),
            held_rows=np.array(held.rows if held else (), dtype=np.int64),
            held_target=np.array(held.target if held else (), dtype=float),
            names=np.array(r["names"], dtype=str), qpos=r["qpos"], qvel=r["qvel"],
            pair=np.array(r["pair"], dtype=str), time=np.array(r["time"]),
            provenance=np.array(PROVENANCE),
            before=np.array(json.dumps({"converged": r["converged"],
                                        "residual": r["residual"],
                                        "iterations": r["iterations"]})),
        )  # fmt: skip
        paths.append(path)
    return paths


def load(path: Path) -> tuple[np.ndarray, np.ndarray, list[ContactRows], HeldRows | None]:
    """``G``, ``w'``, the contacts and the held rows of a saved problem."""
    data = np.load(path, allow_pickle=False)
    contacts = [ContactRows(normal=int(n), tangents=tuple(int(t) for t in ts if t >= 0),
                            friction=float(f), restitution=float(e))
                for n, ts, f, e in zip(data["normal"], data["tangents"], data["friction"],
                                       data["restitution"], strict=True)]  # fmt: skip
    rows = tuple(int(i) for i in data["held_rows"])
    target = tuple(float(t) for t in data["held_target"])
    held = HeldRows(rows=rows, target=target) if rows else None
    return data["delassus"], data["w_before"], contacts, held


def measure(folder: Path, rounds: int, max_iterations: int) -> list[dict[str, Any]]:
    """The iterative solver on each saved problem: iterations, best time of ``rounds``, the
    certificate's residual."""
    out = []
    for path in sorted(folder.glob("*.npz")):
        g, w, contacts, held = load(path)
        problem = contact_problem(g, w, contacts, held)
        best = float("inf")
        for _ in range(rounds):
            t0 = time.perf_counter()
            answer = solve_iterative(problem, max_iterations=max_iterations)
            best = min(best, time.perf_counter() - t0)
        out.append({"problem": path.name, "rows": int(g.shape[0]),
                    "rank": int(np.linalg.matrix_rank(g)),
                    "converged": answer.converged, "iterations": answer.iterations,
                    "newton_steps": answer.newton_steps, "seconds": round(best, 4),
                    "residual": fc3d_error(problem, answer.impulses)})  # fmt: skip
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", help="H1's scene.xml: capture the problems (MuJoCo)")
    parser.add_argument("--write", type=Path, help="with --model: write them here")
    parser.add_argument("--min-iterations", type=int, default=5000,
                        help="with --write: those taking this many too (5000)")  # fmt: skip
    parser.add_argument("--data", type=Path, help="measure the saved problems here")
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--max-iterations", type=int, default=10000)
    args = parser.parse_args()
    if args.model:
        records = capture(args.model)
        for r in records:
            print(f"t={r['time']:.3f} {r['pair']} rows={r['g'].shape[0]} "
                  f"contacts={len(r['contacts'])} converged={r['converged']} "
                  f"residual={r['residual']:.2e} iterations={r['iterations']} "
                  f"{r['seconds']:.3f} s")  # fmt: skip
        if args.write:
            for path in write(records, args.write, args.min_iterations):
                print("wrote", path)
    if args.data:
        for row in measure(args.data, args.rounds, args.max_iterations):
            print(json.dumps(row))


if __name__ == "__main__":
    main()

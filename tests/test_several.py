"""Several contacts at once through the whole pipeline (solve_impact on free bodies): the
published closed forms of issue 14, each checked by the theorem against the direct kinetic
energy difference as well.

Sources: the three-ball chain (Newton's cradle) under the simultaneous (generalized Newton)
law, ``((1 - 2e)/3, (1 + e)/3, (1 + e)/3) v``, and under the sequential law with e = 1,
``(0, 0, 1) v`` (Glocker, *Set-Valued Force Laws*, 2001, section 7; Ceanga and Hurmuzlu,
J. Appl. Mech. 68, 2001); a ball striking two touching balls at +-30 degrees,
``v_A'' = (2 - 3e)/5 v`` (the same generalized Newton law; Glocker 2001); Housner's rocking
block landing on its other corner, ``omega''/omega' = 1 - 3/2 sin^2 alpha`` (Housner, Bull.
Seism. Soc. Am. 53, 1963), the old corner separating with no impulse.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.errors import InputError
from carnot.laws.multiple import MULTIPLE_IMPACT_LAWS
from carnot.laws.registry import MULTIPLE_IMPACT_NAMES


def _ball(name: str, x: float, vx: float = 0.0, y: float = 0.0, m: float = 1.0) -> RigidBody:
    return RigidBody(name=name, mass=m, inertia_com=np.eye(3) * 0.4 * m * 0.5**2,
                     position_com=[x, y, 0.0], velocity_com=[vx, 0.0, 0.0])  # fmt: skip


def _cradle(e: float, law: str, v: float = 2.0) -> ImpactProblem:
    balls = {"A": _ball("A", 0.0, v), "B": _ball("B", 1.0), "C": _ball("C", 2.0)}
    contacts = [
        PointContact(a="B", b="A", point=[0.5, 0, 0], normal=[1, 0, 0], restitution=e,
                     where="contacts[0]", name="AB"),
        PointContact(a="C", b="B", point=[1.5, 0, 0], normal=[1, 0, 0], restitution=e,
                     where="contacts[1]", name="BC"),
    ]  # fmt: skip
    return ImpactProblem(bodies=balls, contacts=contacts, multiple_impact=law)


def _check_ledger(res) -> None:  # type: ignore[no-untyped-def]
    en = res.energy
    assert en.dissipated == pytest.approx(en.dissipated_theorem, rel=1e-12, abs=1e-12 * en.before)


@pytest.mark.parametrize("e", [0.0, 0.3, 0.5, 1.0])
def test_three_ball_cradle_simultaneous(e: float) -> None:
    v = 2.0
    res = solve_impact(_cradle(e, "simultaneous", v))
    got = [res.bodies[n].velocity_after[0] for n in "ABC"]
    assert got == pytest.approx([(1 - 2 * e) / 3 * v, (1 + e) / 3 * v, (1 + e) / 3 * v],
                                rel=1e-12, abs=1e-12)  # fmt: skip
    assert res.multiple_impact == "simultaneous"
    assert res.complementarity_residual is not None and res.complementarity_residual < 1e-12
    assert [c.active for c in res.contacts] == [True, True]
    _check_ledger(res)


def test_three_ball_cradle_sequential_sends_the_last_ball() -> None:
    res = solve_impact(_cradle(1.0, "sequential", 2.0))
    got = [res.bodies[n].velocity_after[0] for n in "ABC"]
    assert got == pytest.approx([0.0, 0.0, 2.0], abs=1e-12)
    assert len(res.stages) == 2 and res.stages[0].contacts == ("contacts[0]",)
    assert sum(s.dissipated for s in res.stages) == pytest.approx(0.0, abs=1e-12)
    _check_ledger(res)


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_ball_striking_two_touching_balls(e: float) -> None:
    """Equal balls of radius 0.5: B and C touch each other and A's path is their bisector, so
    A meets each at 30 degrees from its velocity."""
    v, r = 1.0, 0.5
    dy = r  # B and C at y = +-r; A at distance 2r from each: x = -2r cos 30
    ax = -2 * r * math.cos(math.radians(30))
    balls = {"A": _ball("A", ax, v), "B": _ball("B", 0.0, y=dy), "C": _ball("C", 0.0, y=-dy)}
    contacts = []
    for k, (name, y) in enumerate((("B", dy), ("C", -dy))):
        centre_a, centre_b = np.array([ax, 0.0, 0.0]), np.array([0.0, y, 0.0])
        normal = (centre_b - centre_a) / np.linalg.norm(centre_b - centre_a)
        contacts.append(PointContact(a=name, b="A", point=centre_a + r * normal, normal=normal,
                                     restitution=e, where=f"contacts[{k}]"))  # fmt: skip
    res = solve_impact(ImpactProblem(bodies=balls, contacts=contacts))
    assert res.bodies["A"].velocity_after[0] == pytest.approx((2 - 3 * e) / 5 * v, rel=1e-12,
                                                               abs=1e-12)  # fmt: skip
    _check_ledger(res)


@pytest.mark.parametrize("alpha_deg", [10.0, 20.0, 30.0])
def test_housner_block_lands_on_its_other_corner(alpha_deg: float) -> None:
    """A block of width 2b and height 2h (tan alpha = b/h) rocks about its left corner and
    lands on its right one: e = 0 there, friction high enough to stick at both corners."""
    alpha = math.radians(alpha_deg)
    h = 1.0
    b = h * math.tan(alpha)
    m = 3.0
    omega = -0.8  # rotating clockwise about the left corner (0, 0): the right corner descends
    inertia = m * (b * b + h * h) / 3.0  # about the centre, for a 2b x 2h block (about z)
    centre = np.array([b, h, 0.0])
    velocity = np.cross([0.0, 0.0, omega], centre)
    block = RigidBody(name="block", mass=m, inertia_com=np.diag([inertia, inertia, inertia]),
                      position_com=centre, velocity_com=velocity,
                      angular_velocity=[0, 0, omega])  # fmt: skip
    corners = [PointContact(a="block", b="ground", point=[x, 0, 0], normal=[0, 1, 0],
                            restitution=0.0, friction=10.0, where=f"contacts[{k}]")
               for k, x in enumerate((0.0, 2 * b))]  # fmt: skip
    res = solve_impact(ImpactProblem(bodies={"block": block, "ground": FixedBody(name="ground")},
                                     contacts=corners))  # fmt: skip
    ratio = res.bodies["block"].angular_velocity_after[2] / omega
    assert ratio == pytest.approx(1 - 1.5 * math.sin(alpha) ** 2, rel=1e-10)
    old, new = res.contacts
    assert old.regime == "separate" and old.active is False
    assert np.linalg.norm(old.impulse) <= 1e-12 * np.linalg.norm(new.impulse)
    assert new.normal_impulse > 0
    assert "negative_normal_impulse" not in res.flag_codes()
    _check_ledger(res)


def test_frictional_laws_of_several_contacts_are_refused_with_the_field() -> None:
    p = _cradle(0.5, "sequential")
    rough = [PointContact(a=c.a, b=c.b, point=c.point, normal=c.normal, restitution=0.5,
                          friction=0.2 * k, where=c.where)
             for k, c in enumerate(p.contacts)]  # fmt: skip
    with pytest.raises(InputError, match=r"contacts\[1\]\.friction: must be frictionless with "
                                         r"multiple_impact = 'sequential'"):  # fmt: skip
        solve_impact(ImpactProblem(bodies=p.bodies, contacts=rough, multiple_impact="sequential"))
    with pytest.raises(InputError, match="multiple_impact: must be one of"):
        ImpactProblem(bodies=p.bodies, contacts=p.contacts, multiple_impact="bogus")


def test_the_registry_names_the_laws_that_exist() -> None:
    assert MULTIPLE_IMPACT_NAMES == tuple(MULTIPLE_IMPACT_LAWS)


def test_scenario_files_and_json_of_several_contacts(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """The section-6 keys through the loader and the result file: ``multiple_impact``, contact
    ``name``; ``active``, ``regime``, ``stages`` and the residual out (the cradle's closed
    forms again, read from the shipped example)."""
    import json

    from conftest import EXAMPLES

    from carnot.io.results import result_to_dict
    from carnot.io.scenario import load_scenario, parse_text

    text = (EXAMPLES / "newtons_cradle.toml").read_text()
    problem = load_scenario(EXAMPLES / "newtons_cradle.toml")
    assert [c.name for c in problem.contacts] == ["1-2", "2-3"]
    d = result_to_dict(solve_impact(problem))
    assert d["multiple_impact"] == "simultaneous" and d["complementarity_residual"] < 1e-12
    assert [c["active"] for c in d["contacts"]] == [True, True]
    assert [c["name"] for c in d["contacts"]] == ["1-2", "2-3"]
    velocities = [d["bodies"][b]["velocity"][0] for b in ("ball1", "ball2", "ball3")]
    assert velocities == pytest.approx([-1 / 3, 2 / 3, 2 / 3], abs=1e-12)  # e = 1, v = 1
    seq = parse_text(text.replace('multiple_impact = "simultaneous"',
                                  'multiple_impact = "sequential"'), "cradle.toml")  # fmt: skip
    d = json.loads(json.dumps(result_to_dict(solve_impact(parse_scenario_data(seq)))))
    assert [d["bodies"][b]["velocity"][0] for b in ("ball1", "ball2", "ball3")] == pytest.approx(
        [0.0, 0.0, 1.0], abs=1e-12)  # fmt: skip
    assert [st["contacts"] for st in d["stages"]] == [["contacts[0]"], ["contacts[1]"]]
    assert sum(st["dissipated"] for st in d["stages"]) == pytest.approx(0.0, abs=1e-15)


def parse_scenario_data(data: object) -> ImpactProblem:
    from carnot.io.scenario import parse_scenario

    return parse_scenario(data, "cradle.toml")


def test_block_example_lands_on_its_other_corner() -> None:
    from conftest import EXAMPLES

    from carnot.io.scenario import load_scenario

    res = solve_impact(load_scenario(EXAMPLES / "block_on_two_corners.toml"))
    alpha = math.atan(0.25)
    assert res.bodies["block"].angular_velocity_after[2] / -0.8 == pytest.approx(
        1 - 1.5 * math.sin(alpha) ** 2, rel=1e-10)  # fmt: skip
    assert [c.regime for c in res.contacts] == ["separate", "stick"]


def test_two_frictional_contacts_at_one_point_at_rest() -> None:
    """Found by the fuzz test: two sticking-capable contacts at the same point, where the body
    is at rest (it pivots about it), need no impulse; the answer is zero, not a LinAlgError
    (the friction-capacity weights divided by a zero impulse)."""
    block = RigidBody(name="block", mass=3.0, inertia_com=np.eye(3) * 0.5,
                      position_com=[0.25, 1.0, 0.0], velocity_com=[0.8, -0.2, 0.0],
                      angular_velocity=[0, 0, -0.8])  # fmt: skip
    corners = [PointContact(a="block", b="ground", point=[0, 0, 0], normal=[0, 1, 0],
                            restitution=0.0, friction=2.0, where=f"contacts[{k}]")
               for k in range(2)]  # fmt: skip
    res = solve_impact(ImpactProblem(bodies={"block": block, "ground": FixedBody(name="ground")},
                                     contacts=corners))  # fmt: skip
    assert all(np.linalg.norm(c.impulse) == 0.0 for c in res.contacts)
    assert res.energy.dissipated == pytest.approx(0.0, abs=1e-15)


def _housner_system(law: str, friction: float) -> tuple[object, object]:
    """Housner's block (2b x 2h, alpha = 20 degrees) rocking about its left corner, landing on
    its right one (e = 0): as a system in (x, y, theta) of the centre, and as a free body."""
    from carnot.model.system import System, SystemContact, SystemProblem

    alpha, h, m, omega = math.radians(20.0), 1.0, 3.0, -0.8
    b = h * math.tan(alpha)
    inertia = m * (b * b + h * h) / 3.0
    centre = np.array([b, h, 0.0])
    velocity = np.cross([0.0, 0.0, omega], centre)
    contacts, corners = [], []
    for k, x in enumerate((0.0, 2 * b)):
        r = np.array([x, 0.0, 0.0]) - centre
        jac = [[1.0, 0.0, -r[1]], [0.0, 1.0, r[0]], [0.0, 0.0, 0.0]]
        contacts.append(SystemContact(jacobian=jac, normal=[0, 1, 0], point=[x, 0, 0],
                                      restitution=0.0, friction=friction,
                                      where=f"contacts[{k}]"))  # fmt: skip
        corners.append(PointContact(a="block", b="ground", point=[x, 0, 0], normal=[0, 1, 0],
                                    restitution=0.0, friction=friction,
                                    where=f"contacts[{k}]"))  # fmt: skip
    system = System(mass_matrix=np.diag([m, m, inertia]),
                    velocity=[velocity[0], velocity[1], omega],
                    coordinates=("x", "y", "theta"))  # fmt: skip
    block = RigidBody(name="block", mass=m, inertia_com=np.eye(3) * inertia,
                      position_com=centre, velocity_com=velocity,
                      angular_velocity=[0, 0, omega])  # fmt: skip
    return (
        SystemProblem(system=system, contacts=contacts, multiple_impact=law),
        ImpactProblem(bodies={"block": block, "ground": FixedBody(name="ground")},
                      contacts=corners, multiple_impact=law),
    )  # fmt: skip


@pytest.mark.parametrize(("law", "friction"), [("simultaneous", 10.0), ("simultaneous", 0.0),
                                               ("sequential", 0.0)])  # fmt: skip
def test_several_contacts_of_a_system_equal_the_free_body_answer(law: str, friction: float) -> None:
    """The same multiple-impact law through solve_system (generalized coordinates) and through
    free bodies (two front ends, issue 15, joined by several contacts, issue 14); sticking,
    Housner's published ratio 1 - 3/2 sin^2 alpha."""
    as_system, as_bodies = _housner_system(law, friction)
    res, ref = solve_impact(as_system), solve_impact(as_bodies)  # type: ignore[arg-type]
    omega_after = res.system.velocity_after[2]
    assert omega_after == pytest.approx(ref.bodies["block"].angular_velocity_after[2], rel=1e-10)
    for mine, theirs in zip(res.contacts, ref.contacts, strict=True):
        assert mine.regime == theirs.regime
        np.testing.assert_allclose(mine.impulse, theirs.impulse, rtol=0, atol=1e-10)
    assert res.energy.dissipated == pytest.approx(ref.energy.dissipated, rel=1e-10)
    if friction > 0:
        ratio = omega_after / -0.8
        assert ratio == pytest.approx(1 - 1.5 * math.sin(math.radians(20.0)) ** 2, rel=1e-10)
    assert res.multiple_impact == law and res.contacts[0].regime == "separate"
    _check_ledger(res)


def _meets_coulombs_law(result, mu: float, e: float = 0.0) -> float:  # type: ignore[no-untyped-def]
    """The largest violation (N s or m/s) of the simultaneous law's conditions at each
    contact, read from the result's impulses and velocities alone (apart from every
    solver): ``P_n >= 0``, ``|P_t| <= mu P_n``, ``w_n'' + e w_n' >= 0`` with complementarity,
    and a slipping contact's ``P_t = -mu P_n w_t'' / |w_t''|``."""
    worst = 0.0
    for c in result.contacts:
        n = np.asarray(c.normal)
        p = np.asarray(c.impulse)
        p_n = float(p @ n)
        p_t = p - p_n * n
        w1, w2 = np.asarray(c.relative_velocity_before), np.asarray(c.relative_velocity_after)
        gap = float(w2 @ n) + e * min(float(w1 @ n), 0.0)
        slip = w2 - float(w2 @ n) * n
        worst = max(worst, -p_n, float(np.linalg.norm(p_t)) - mu * p_n, -gap, abs(gap * p_n))
        if np.linalg.norm(slip) > 1e-9:
            worst = max(worst, float(np.linalg.norm(p_t + mu * p_n * slip / np.linalg.norm(slip))))
    return worst


def test_a_box_sliding_on_four_corners_has_a_family_of_answers_and_says_so() -> None:
    """The box of examples/box_lands_flat.toml with mu = 0.2: it slides on its four corners
    after the impact. Their normal impulses have one free split (four coplanar corners, three
    equations), and with friction each split moves the box differently: the law holds a family
    of answers. Two solvers find two of them, each meeting the law's conditions (checked here
    from their impulses and velocities alone) with different E_d; the enumeration says
    ``multiple_solutions`` and does not claim the velocities unique, and its message does not
    point to an `alternatives` list it does not have."""
    from carnot.io.scenario import load_scenario

    base = load_scenario(ROOT / "examples" / "box_lands_flat.toml")
    box = dataclasses.replace(base, contacts=[dataclasses.replace(c, friction=0.2)
                                              for c in base.contacts])  # fmt: skip
    first = solve_impact(box, solver="enumerate")
    other = solve_impact(box, solver="iterative")
    for r in (first, other):
        assert _meets_coulombs_law(r, 0.2) < 1e-12
        assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, abs=1e-12)
    assert abs(first.energy.dissipated - other.energy.dissipated) > 1e-6  # two answers
    assert first.solver is not None and first.solver.velocities_unique is False
    assert other.solver is not None and other.solver.velocities_unique is not True
    flags = {f.code: f for f in first.warnings}
    assert "multiple_solutions" in flags and not first.alternatives
    assert "alternatives" not in flags["multiple_solutions"].message
    # the family is a curve along which the slip directions turn: its range of E_d is not
    # computed, and the certificate does not present the one answer's E_d as the range
    assert first.solver.dissipated_range is None and other.solver.dissipated_range is None


def test_the_range_of_e_d_of_a_unique_answer_is_its_e_d() -> None:
    """Where the velocities are unique (the frictionless box landing flat: its impulses are
    not, its motion is), the certificate's ``dissipated_range`` is the one E_d, the direct
    energy difference to round-off, by both solvers; in the JSON as a pair."""
    from carnot.io.results import result_to_dict
    from carnot.io.scenario import load_scenario

    box = load_scenario(ROOT / "examples" / "box_lands_flat.toml")
    box = dataclasses.replace(box, contacts=[dataclasses.replace(c, friction=0.0)
                                             for c in box.contacts])  # fmt: skip
    for solver in ("enumerate", "iterative"):
        res = solve_impact(box, solver=solver)
        assert res.solver is not None and res.solver.velocities_unique is True
        low, high = res.solver.dissipated_range
        assert low == high == pytest.approx(res.energy.dissipated, rel=1e-12)
        entry = result_to_dict(res)["solver"]["dissipated_range"]
        assert entry == [low, high]


def test_the_range_of_e_d_over_a_sliding_box_s_family_is_its_extremes() -> None:
    """The box of examples/box_lands_flat.toml sliding on its four corners (mu = 0.2): its
    answers form a curve (each split of the normal impulses sets another yaw, so other slip
    directions). Traced (``trace_families``), the certificate's ``dissipated_range`` holds
    both solvers' answers, and its ends are the least and the most E_d that SciPy's SLSQP
    finds over the law's conditions written here from the box's own mass, inertia and
    corners (a route that shares nothing with carnot's: P_n and the slip angles as unknowns,
    ``u_n'' = 0`` and each slip along its angle, ``P_n >= 0``, the slip speeds >= 0), to 1e-11
    relative. Without ``trace_families`` the range is not claimed."""
    from scipy.optimize import minimize

    from carnot.io.scenario import load_scenario
    from carnot.solvers.options import SolverOptions

    mu = 0.2
    base = load_scenario(ROOT / "examples" / "box_lands_flat.toml")
    box = dataclasses.replace(base, contacts=[dataclasses.replace(c, friction=mu)
                                              for c in base.contacts])  # fmt: skip
    traced = solve_impact(box, solver=SolverOptions(name="enumerate", trace_families=True))
    other = solve_impact(box, solver="iterative")
    low, high = traced.solver.dissipated_range
    assert high - low > 1e-4  # a family: E_d spans an interval
    for r in (traced, other):
        assert low - 1e-12 <= r.energy.dissipated <= high + 1e-12
    # the law's conditions from the box's data (a 2 kg, 0.4 x 0.3 x 0.2 m box, its centre 0.1
    # m above the floor; its corners 0.1 m below the centre)
    m, (a, b, c) = 2.0, (0.4, 0.3, 0.2)
    inertia = np.diag([b * b + c * c, a * a + c * c, a * a + b * b]) * m / 12.0
    v0, w0 = np.array([0.8, 0.3, -1.0]), np.array([0.0, 0.0, 0.4])
    arms = [np.array(ct.point) - np.array([0.0, 0.0, 0.1]) for ct in box.contacts]

    def after(z: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
        pn, th = z[:4], z[4:]
        forces = [np.array([-mu * p * np.cos(t), -mu * p * np.sin(t), p])
                  for p, t in zip(pn, th, strict=True)]  # fmt: skip
        v = v0 + sum(forces) / m
        w = w0 + np.linalg.solve(inertia, sum(np.cross(r, f) for r, f in zip(arms, forces,
                                                                                strict=True)))
        return v, w, [v + np.cross(w, r) for r in arms]

    def e_d(z: np.ndarray) -> float:
        v, w, _ = after(z)
        before = 0.5 * m * v0 @ v0 + 0.5 * w0 @ inertia @ w0
        return float(before - 0.5 * m * v @ v - 0.5 * w @ inertia @ w)

    def equalities(z: np.ndarray) -> np.ndarray:
        # three corners' u_n'' = 0 (the fourth's follows: the corners are coplanar, and a
        # redundant equality stalls SLSQP), each slip along its angle
        _, _, u = after(z)
        return np.array([ui[2] for ui in u[:3]] + [np.cos(t) * ui[1] - np.sin(t) * ui[0]
                                                   for t, ui in zip(z[4:], u, strict=True)])

    def inequalities(z: np.ndarray) -> np.ndarray:  # each slip speed >= 0 (P_n >= 0: bounds)
        _, _, u = after(z)
        return np.array([np.cos(t) * ui[0] + np.sin(t) * ui[1]
                         for t, ui in zip(z[4:], u, strict=True)])  # fmt: skip

    start = np.concatenate([[ct.impulse[2] for ct in traced.contacts],
                            [math.atan2(-ct.impulse[1], -ct.impulse[0]) for ct in traced.contacts]])
    # P_n >= 0 as bounds, which SLSQP keeps exactly (the least E_d has a corner's P_n = 0:
    # as a constraint, its iterates crossed to -7e-13 and its line search stalled there on
    # some BLAS kernels); ftol, SLSQP's accuracy goal both for the change in E_d and for the
    # sum of the constraints' violations, 1e-13: above the round-off of the seven
    # equalities' sum (4e-16 each, for slips of 1 m/s), where 1e-15 was not, and 1e-2 of
    # the 1e-11 relative (1.3e-11 J) that the ends are checked to
    ends = []
    for sign in (1.0, -1.0):
        res = minimize(lambda z, s=sign: s * e_d(z), start, method="SLSQP",
                       bounds=[(0.0, None)] * 4 + [(None, None)] * 4,
                       constraints=[{"type": "eq", "fun": equalities},
                                    {"type": "ineq", "fun": inequalities}],
                       options={"ftol": 1e-13, "maxiter": 500})  # fmt: skip
        assert res.success, res.message
        assert np.abs(equalities(res.x)).max() < 1e-10 and inequalities(res.x).min() > -1e-10
        assert res.x[:4].min() >= 0.0
        assert abs(after(res.x)[2][3][2]) < 1e-10  # the fourth corner at rest too
        ends.append(e_d(res.x))
    assert ends[0] == pytest.approx(low, rel=1e-11) and ends[1] == pytest.approx(high, rel=1e-11)
    plain = solve_impact(box, solver="enumerate")
    assert plain.solver.dissipated_range is None


def test_the_command_line_traces_a_family_and_refuses_a_bad_switch(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    """``carnot solve --trace-families`` prints the range of E_d over the sliding box's family;
    ``[solver] trace_families`` that is not a boolean exits 2 with one line naming it."""
    from carnot.cli import main

    text = (ROOT / "examples" / "box_lands_flat.toml").read_text()
    sliding = tmp_path / "sliding.toml"
    sliding.write_text(text.replace("friction = 1.5", "friction = 0.2"))
    assert main(["solve", str(sliding), "--trace-families", "--solver", "enumerate"]) == 0
    out = capsys.readouterr().out
    assert "E_d over the answers from 1.30254 to 1.30326 J" in out
    bad = tmp_path / "bad.toml"
    bad.write_text(text + "\n[solver]\ntrace_families = 1\n")
    assert main(["solve", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "solver.trace_families: must be true or false, got 1" in err[0]

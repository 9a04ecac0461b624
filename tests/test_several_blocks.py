"""Several contacts in independent groups (contacts sharing no degree of freedom: a zero
Delassus block): each group's answer is the one it has alone, under every multiple-impact law.

Published closed forms checked in the scenes as well: the three-ball chain (Newton's cradle)
under the simultaneous (generalized Newton) law, ``((1 - 2e)/3, (1 + e)/3, (1 + e)/3) v``, and
under the sequential law with e = 1, ``(0, 0, 1) v`` (Glocker, *Set-Valued Force Laws*, 2001,
section 7; Ceanga and Hurmuzlu, J. Appl. Mech. 68, 2001); a frictionless body landing on a
floor at several points, each with Newton's ``w_n'' = -e w_n'``, leaves with its vertical
velocity reversed times ``e`` and its horizontal velocity kept (Glocker 2001, ch. 7: the
generalized Newton law is solved by the common restitution when the contacts' normal velocities
are equal; a ball dropped into a symmetric V-groove and a box landing flat); a box landing flat
that sticks stops entirely (examples/box_lands_flat.toml; Pfeiffer and Glocker, *Multibody
Dynamics with Unilateral Contacts*, 1996). Each outcome is checked by the theorem against the
direct kinetic energy difference too.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.laws.multiple import MULTIPLE_IMPACT_LAWS, ContactRows, resolve_simultaneous
from carnot.model.contacts import PointConstraint
from carnot.model.free_bodies import assemble
from carnot.several import MESSAGES, independent_groups, resolve_several

Group = tuple[dict[str, RigidBody], list[PointContact]]


def _box(name: str, x: float, *, v=(0.0, 0.0, -1.0), omega=(0.0, 0.0, 0.0), e: float = 0.0,
         mu: float = 0.0) -> Group:  # fmt: skip
    """A 2 kg box, 0.4 x 0.3 x 0.2 m, on its four bottom corners (a floor at z = 0)."""
    m, (a, b, c) = 2.0, (0.4, 0.3, 0.2)
    inertia = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    body = RigidBody(name=name, mass=m, inertia_com=inertia, position_com=[x, 0, c / 2],
                     velocity_com=list(v), angular_velocity=list(omega))  # fmt: skip
    corners = ((1, 1), (-1, 1), (-1, -1), (1, -1))
    contacts = [PointContact(a=name, b="floor", point=[x + sx * a / 2, sy * b / 2, 0.0],
                             normal=[0, 0, 1], restitution=e, friction=mu, where=f"{name}-{k}")
                for k, (sx, sy) in enumerate(corners)]  # fmt: skip
    return {name: body}, contacts


def _groove_ball(name: str, x: float, *, v=(0.3, 0.0, -2.0), e: float = 0.5,
                 mu: float = 0.0) -> Group:  # fmt: skip
    """A 1 kg ball of radius 0.1 m dropped into a V-groove (walls 40 degrees from vertical)."""
    r, m, t = 0.1, 1.0, math.radians(40.0)
    centre = np.array([x, 0.0, 0.5])
    body = RigidBody(name=name, mass=m, inertia_com=np.eye(3) * 0.4 * m * r * r,
                     position_com=centre, velocity_com=list(v))  # fmt: skip
    contacts = []
    for k, s in enumerate((1, -1)):
        n = np.array([0.0, -s * math.cos(t), math.sin(t)])
        contacts.append(PointContact(a=name, b="floor", point=centre - r * n, normal=n,
                                     restitution=e, friction=mu, where=f"{name}-{k}"))  # fmt: skip
    return {name: body}, contacts


def _cradle(y: float, *, v: float = 2.0, e: float = 1.0) -> Group:
    """Three touching unit balls in a row along x, the first moving at ``v``."""
    bodies = {n: RigidBody(name=n, mass=1.0, inertia_com=np.eye(3) * 0.1,
                           position_com=[k, y, 5.0], velocity_com=[v if k == 0 else 0.0, 0, 0])
              for k, n in enumerate("ABC")}  # fmt: skip
    contacts = [PointContact(a="B", b="A", point=[0.5, y, 5.0], normal=[1, 0, 0],
                             restitution=e, where="AB"),
                PointContact(a="C", b="B", point=[1.5, y, 5.0], normal=[1, 0, 0],
                             restitution=e, where="BC")]  # fmt: skip
    return bodies, contacts


def _lone_ball(vz: float) -> Group:
    ball = RigidBody(name="lone", mass=1.0, inertia_com=np.eye(3) * 0.004,
                     position_com=[5.0, 0, 0.1], velocity_com=[0, 0, vz])  # fmt: skip
    contact = PointContact(a="lone", b="floor", point=[5.0, 0, 0], normal=[0, 0, 1],
                           restitution=0.5, where="lone-0")  # fmt: skip
    return {"lone": ball}, [contact]


def _problem(*groups: Group, law: str = "simultaneous") -> ImpactProblem:
    bodies: dict = {"floor": FixedBody(name="floor")}
    contacts: list[PointContact] = []
    for b, c in groups:
        bodies.update(b)
        contacts.extend(c)
    return ImpactProblem(bodies=bodies, contacts=contacts, multiple_impact=law)


def _ledger_closes(res) -> None:  # type: ignore[no-untyped-def]
    en = res.energy
    assert en.dissipated == pytest.approx(en.dissipated_theorem, rel=1e-12, abs=1e-12 * en.before)


def _same_as_alone(both, alone, group: Group, flags: bool = True) -> None:  # type: ignore[no-untyped-def]
    """The group's bodies and contacts in ``both`` are those of ``alone`` (to 1e-12), and its
    flags (``flags``: an alternative carries the other groups' first answers' flags)."""
    bodies, contacts = group
    for name in bodies:
        for key in ("velocity_after", "angular_velocity_after"):
            got, ref = getattr(both.bodies[name], key), getattr(alone.bodies[name], key)
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12, err_msg=f"{name} {key}")
    by_where = {c.where: c for c in both.contacts}
    for ref in alone.contacts:
        got = by_where[ref.where]
        np.testing.assert_allclose(got.impulse, ref.impulse, rtol=0, atol=1e-12)
        assert (got.regime, got.active) == (ref.regime, ref.active)
    mine = {c.where for c in contacts}
    if flags:  # the law's flags (the energy ones are the whole problem's)
        codes = sorted(f.code for f in both.warnings
                       if f.code in MESSAGES and set(f.where.split(", ")) <= mine)  # fmt: skip
        assert codes == sorted(c for c in alone.flag_codes() if c in MESSAGES)


_SCENES = {
    "box+groove": (_box("box", 0.0, omega=(0.5, 0.2, 0.0), e=0.3), _groove_ball("ball", 3.0)),
    "cradle+groove": (_cradle(4.0, e=1.0), _groove_ball("ball", 3.0, e=0.8)),
}


@pytest.mark.parametrize("law", ["simultaneous", "sequential", "dispersion"])
@pytest.mark.parametrize("scene", sorted(_SCENES))
def test_each_group_gets_its_answer_alone(scene: str, law: str) -> None:
    groups = _SCENES[scene]
    both = solve_impact(_problem(*groups, law=law))
    alone = [solve_impact(_problem(g, law=law)) for g in groups]
    for group, res in zip(groups, alone, strict=True):
        _same_as_alone(both, res, group)
    assert both.complementarity_residual == max(r.complementarity_residual for r in alone)
    assert len(both.stages) == sum(len(r.stages) for r in alone)
    assert [s.index for s in both.stages] == list(range(len(both.stages)))
    _ledger_closes(both)
    # the published answers of the groups (module docstring); the sequential law hits one wall
    # of the groove first, so the ball's is the simultaneous law's (and the symmetric LZB's)
    if law != "sequential":
        e_ball = groups[1][1][0].restitution
        np.testing.assert_allclose(both.bodies["ball"].velocity_after, [0.3, 0.0, 2.0 * e_ball],
                                   atol=1e-9)  # fmt: skip
    if scene == "cradle+groove" and law != "dispersion":
        expected = [0.0, 0.0, 2.0] if law == "sequential" else [-2 / 3, 4 / 3, 4 / 3]
        got = [both.bodies[n].velocity_after[0] for n in "ABC"]
        assert got == pytest.approx(expected, abs=1e-12)


def test_coulomb_groups_and_their_alternatives() -> None:
    """A box landing flat while sliding, mu = 0.2 (several outcomes: ``multiple_solutions``),
    beside a ball in a rough groove: the box's outcomes are its outcomes alone (with
    4 x 3 regimes it is not verified by default, so no alternatives are listed), the ball at its
    one answer in each."""
    box = _box("box", 0.0, v=(0.8, 0.3, -1.0), omega=(0.0, 0.0, 0.4), mu=0.2)
    ball = _groove_ball("ball", 3.0, v=(0.3, 0.2, -2.0), mu=0.3)
    both = solve_impact(_problem(box, ball))
    box_alone, ball_alone = solve_impact(_problem(box)), solve_impact(_problem(ball))
    _same_as_alone(both, box_alone, box)
    _same_as_alone(both, ball_alone, ball)
    assert "multiple_solutions" in box_alone.flag_codes()
    assert not ball_alone.alternatives
    assert len(both.alternatives) == len(box_alone.alternatives)
    for combined, ref in zip(both.alternatives, box_alone.alternatives, strict=True):
        _same_as_alone(combined, ref, box, flags=False)
        _same_as_alone(combined, ball_alone, ball, flags=False)
        _ledger_closes(combined)


def test_sticking_box_beside_a_rough_groove_stops() -> None:
    box = _box("box", 0.0, v=(0.8, 0.3, -1.0), omega=(0.0, 0.0, 0.4), mu=1.5)
    both = solve_impact(_problem(box, _groove_ball("ball", 3.0, mu=0.3)))
    assert np.max(np.abs(both.bodies["box"].velocity_after)) < 1e-12
    assert np.max(np.abs(both.bodies["box"].angular_velocity_after)) < 1e-12
    flagged = [f for f in both.warnings if f.code == "statically_indeterminate"]
    assert [f.where for f in flagged] == ["box-0, box-1, box-2, box-3"]


def test_sequential_ties_are_per_group() -> None:
    """Two balls each in its own symmetric groove: each has a tie (its two walls approach
    equally fast), none across the grooves. The alternatives: each order of one groove, the
    other at its first; the first answer listed once."""
    a, b = _groove_ball("a", 0.0, e=1.0), _groove_ball("b", 3.0, e=1.0)
    both = solve_impact(_problem(a, b, law="sequential"))
    alone = [solve_impact(_problem(g, law="sequential")) for g in (a, b)]
    assert all(len(r.alternatives) == 2 for r in alone)
    assert len(both.alternatives) == 3
    ties = [f.where for f in both.warnings if f.code == "sequential_tie"]
    assert ties == ["a-0, a-1", "b-0, b-1"]
    combos = [(0, 0), (1, 0), (0, 1)]  # (order of groove a, order of groove b)
    for combined, (i, j) in zip(both.alternatives, combos, strict=True):
        _same_as_alone(combined, alone[0].alternatives[i], a, flags=False)
        _same_as_alone(combined, alone[1].alternatives[j], b, flags=False)


def test_dispersion_no_longer_depends_on_an_unrelated_group() -> None:
    """The LZB law on a box landing flat took its stopping test and tolerances from every
    contact it was given: with a ball barely touching the floor elsewhere, the box's outcome
    changed by 0.35 m/s and 1.1 rad/s, unflagged (before the groups were split)."""
    box = _box("box", 0.0, v=(0.8, 0.3, -1.0), omega=(0.0, 0.0, 0.4))
    alone = solve_impact(_problem(box, law="dispersion"))
    for other in (_lone_ball(-0.01), _lone_ball(-30.0), _cradle(4.0, v=10.0, e=0.5)):
        both = solve_impact(_problem(box, other, law="dispersion"))
        _same_as_alone(both, alone, box)
    lone = both = solve_impact(_problem(box, _lone_ball(-0.01), law="dispersion"))
    # one contact alone under the LZB law: Newton's w'' = -e w' (Liu, Zhao, Brogliato 2008)
    assert lone.bodies["lone"].velocity_after[2] == pytest.approx(0.005, rel=1e-9)
    _ledger_closes(both)


def test_more_regimes_in_all_than_the_cap_but_not_per_group() -> None:
    """Four boxes landing flat, frictionless: 2^16 regimes in all (over the cap of 4096), 16
    per box. Each leaves with ``-e`` times its vertical velocity, its horizontal one kept."""
    boxes = [_box(f"box{k}", 2.0 * k, v=(0.1 * k, 0.2, -1.0 - k), e=0.25 * k) for k in range(4)]
    res = solve_impact(_problem(*boxes))
    for k in range(4):
        np.testing.assert_allclose(res.bodies[f"box{k}"].velocity_after,
                                   [0.1 * k, 0.2, 0.25 * k * (1.0 + k)], atol=1e-12)  # fmt: skip
    assert res.complementarity_residual < 1e-12
    _ledger_closes(res)


def test_a_held_group_without_contacts() -> None:
    """A ball fastened at its centre beside a box landing flat: its group has held rows only,
    and the fastening stops its centre (the paper's section 3.3), whatever the law."""
    box = _box("box", 0.0, omega=(0.5, 0.2, 0.0), e=0.3)
    held = RigidBody(name="held", mass=1.5, inertia_com=np.eye(3) * 0.01,
                     position_com=[0, 6.0, 1.0], velocity_com=[1.0, -2.0, 0.5],
                     angular_velocity=[0, 0, 3.0])  # fmt: skip
    fasten = PointConstraint(kind="fasten", body="held", point=[0, 6.0, 1.0],
                             where="constraints[0]")  # fmt: skip
    for law in MULTIPLE_IMPACT_LAWS:
        p = _problem(box, law=law)
        problem = ImpactProblem(bodies={**p.bodies, "held": held}, contacts=p.contacts,
                                constraints=[fasten], multiple_impact=law)  # fmt: skip
        res = solve_impact(problem)
        np.testing.assert_allclose(res.bodies["held"].velocity_after, 0.0, atol=1e-12)
        np.testing.assert_allclose(res.bodies["held"].angular_velocity_after, [0, 0, 3.0],
                                   atol=1e-12)  # fmt: skip
        _same_as_alone(res, solve_impact(_problem(box, law=law)), box)


def test_one_group_is_the_law_on_the_whole_space() -> None:
    """One group: the law's impulses on the whole contact space, bit for bit."""
    box = _box("box", 0.0, v=(0.8, 0.3, -1.0), omega=(0.0, 0.0, 0.4), mu=1.5)
    problem = _problem(box)
    items = list(problem.contacts)
    space = assemble(problem, items, [c.rows() for c in items]).space
    assert independent_groups(space, range(len(items))) == ((0, 1, 2, 3),)
    impulses, several = resolve_several(items, space, "simultaneous", [])
    rows = np.arange(space.size)
    contacts = [ContactRows(normal=3 * k, tangents=(3 * k + 1, 3 * k + 2), friction=1.5,
                            name=c.where) for k, c in enumerate(items)]  # fmt: skip
    direct = resolve_simultaneous(space.delassus(rows), space.row_velocities(space.u_before),
                                  contacts)  # fmt: skip
    assert impulses.tobytes() == direct.impulses.tobytes()
    assert several.residual == direct.residual


@pytest.mark.parametrize("law", ["simultaneous", "sequential", "dispersion"])
def test_system_in_generalized_coordinates_splits_the_same_way(law: str) -> None:
    """Four unit beads on a wire: bead 1 strikes bead 2 resting on a stop (a chain of two
    contacts), beads 3 and 4 likewise on their own stop, at another speed. Each pair is the
    two-ball cradle on a wall; its answer is its answer alone."""
    from carnot.model.system import System, SystemContact, SystemProblem

    def contact(row: list[float], where: str) -> SystemContact:
        return SystemContact(jacobian=[row, [0.0] * 4, [0.0] * 4], normal=[1, 0, 0],
                             restitution=0.7, where=where)  # fmt: skip

    first = [contact([0, -1.0, 0, 0], "stop-2"), contact([-1.0, 1.0, 0, 0], "1-2")]
    second = [contact([0, 0, 0, -1.0], "stop-4"), contact([0, 0, -1.0, 1.0], "3-4")]
    system = System(mass_matrix=np.eye(4), velocity=[1.0, 0.0, 2.5, 0.0])
    both = solve_impact(SystemProblem(system=system, contacts=first + second,
                                      multiple_impact=law))  # fmt: skip
    for part, cols in ((first, [0, 1]), (second, [2, 3])):
        alone = solve_impact(SystemProblem(system=system, contacts=part, multiple_impact=law))
        assert both.system is not None and alone.system is not None
        got, ref_q = both.system.velocity_after[cols], alone.system.velocity_after[cols]
        np.testing.assert_allclose(got, ref_q, rtol=0, atol=1e-12)
        by_where = {c.where: c for c in both.contacts}
        for ref in alone.contacts:
            np.testing.assert_allclose(by_where[ref.where].impulse, ref.impulse, atol=1e-12)
    _ledger_closes(both)

"""A box landing on four corners on a tilted ground (mu 1.5): the multi-contact batch equals
``solve_impact`` where their root finders used to part ways (issue 14).

The first three landings are rows 7, 66 and 92 of ``benchmarks/same_answers.py``'s "tilted
sticking" case with ``--n 100`` (``benchmarks/tilt_differences.py`` lists them): the
slip-angle system of a regime with three corners slipping is ill-conditioned there
(Jacobian condition 1e3-1e4), and the kernel's Newton/Broyden iteration and the reference's
MINPACK ``hybr`` reached different roots from the same start (one converged in 56-60 steps
where the other stalled), so the batch and ``solve_impact`` reported different regimes, each
a genuine solution of the law (the problem has several). The kernel then handed such an
impact to the reference law; now the reference runs the kernel's iteration step for step
(``simultaneous.newton_broyden``), and the kernel answers these itself. The fourth is row
136 with ``--n 200``: there the reference's own answer changed with the last bit of ``G``
(the kernel's assembly and ``solve_impact``'s differ by 4e-16); the batch's reference rows are
now solved on ``solve_impact``'s ``G``.

Each answer is also checked here from first principles, apart from both solvers: the
Newton-Euler impulse equations of the box (``m dv = sum P``, ``J dom = sum r x P``) and, at
each corner, Newton's restitution as a complementarity (``0 <= P_n ⟂ u_n'' + e u_n' >= 0``)
and Coulomb's law at impact with the circular cone (``|P_t| <= mu P_n``; ``P_t = -mu P_n
u_t''/|u_t''|`` where the corner slips after): Glocker, *Set-Valued Force Laws*, Springer
2001, ch. 7; Pfeiffer and Glocker, *Multibody Dynamics with Unilateral Contacts*, 1996.
"""

from __future__ import annotations

import numpy as np
import pytest

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.batch import BatchBodies
from carnot.batch.multi import REGIME_NAMES, multi_impacts

MASS = 2.0
INERTIA = MASS / 12.0 * np.diag([0.3**2 + 0.2**2, 0.4**2 + 0.2**2, 0.4**2 + 0.3**2])
CENTRE = np.array([0.0, 0.0, 0.1])
CORNERS = np.array([[0.2, 0.15, 0.0], [0.2, -0.15, 0.0], [-0.2, 0.15, 0.0],
                    [-0.2, -0.15, 0.0]])  # fmt: skip
MU = 1.5
#: (velocity, angular velocity, ground normal, restitution) of the three landings
LANDINGS = [
    ([0.508326039591692, -0.1460266676963622, -0.21245389527483116],
     [-0.044277748308872746, 0.06512073762770379, -0.4955026758788875],
     [-0.014402517434351602, -0.003541811327575948, 0.9998900054826396], 0.8879982599767628),
    ([-0.7311933774699318, 0.38986225963710974, -0.7141270159941249],
     [-0.09442457613820397, -0.007709759169162434, 0.36133170238956736],
     [-0.005980781206789113, 0.035242184010457894, 0.9993609051400447], 0.4514308299655275),
    ([-0.3870119289556586, -0.1234661320863275, -0.4132452415629069],
     [-0.02943195949308184, 0.04014805771543842, 0.10756342892737425],
     [-0.03898865041508206, -0.010815935961323742, 0.9991811150477631], 0.25020930416065357),
    ([0.5093093774819353, -0.10298821347175058, -0.4843236343860031],
     [0.08152528911458481, -0.02317263409017214, -0.3049380036726065],
     [0.01191547793145868, -0.007521760229749648, 0.9999007173258309], 0.46239290783420794),
]  # fmt: skip
#: Flat box landings (the ground's normal vertical, mu 1.5) whose slip-angle iteration took
#: more than 30 steps in some regime: rows 1832, 1964, 3580 and 6601 of
#: ``benchmarks/bench_batch_multi.py``'s sticking case (10000 rows). The batch left them to
#: the reference law then (0.1-0.3 s each, most of that batch's time); the reference now runs
#: the kernel's iteration, and the kernel answers them itself.
SLOW_FLAT = [
    ([-0.06631383209873365, 0.6590296302812582, -0.38711771398284234],
     [-0.08521814581650836, 0.056199396919230885, 0.024869511806553057],
     [0.0, 0.0, 1.0], 0.14500904791445557),
    ([-0.041450087182210105, -0.3998631143689975, -0.26816370145114354],
     [0.006958617479838592, 0.08600174130225285, 0.37290317576219867],
     [0.0, 0.0, 1.0], 0.011413427041197965),
    ([0.14014816952648634, -0.547150950304605, -0.2070525748908747],
     [0.054534120349951004, 0.09761603989375292, -0.023363610887064845],
     [0.0, 0.0, 1.0], 0.7528747012560296),
    ([-0.07721951013505568, -0.6833410737454462, -0.4576322338327232],
     [-0.06701625012005707, -0.016815051406935046, -0.41229165497879383],
     [0.0, 0.0, 1.0], 0.01845891145410028),
]  # fmt: skip


def _law_violation(v0: np.ndarray, om0: np.ndarray, v1: np.ndarray, om1: np.ndarray,
                   impulses: np.ndarray, normal: np.ndarray, e: float) -> float:  # fmt: skip
    """The largest violation (m/s; impulses divided by the mass) of the impulse equations and
    of each corner's restitution and Coulomb conditions, by an answer ``(v1, om1, impulses)``
    (impulses world, what the box receives at each corner)."""
    n = normal / np.linalg.norm(normal)
    scale = float(np.max(np.abs(np.concatenate([v0, om0]))))
    worst = float(np.max(np.abs(MASS * (v1 - v0) - impulses.sum(axis=0)))) / MASS
    moment = sum(np.cross(p - CENTRE, imp) for p, imp in zip(CORNERS, impulses, strict=True))
    worst = max(worst, float(np.max(np.abs(INERTIA @ (om1 - om0) - moment))) / MASS)
    for p, imp in zip(CORNERS, impulses, strict=True):
        r = p - CENTRE
        u0, u1 = v0 + np.cross(om0, r), v1 + np.cross(om1, r)
        p_n = float(imp @ n) / MASS
        p_t = (imp - (imp @ n) * n) / MASS
        if u0 @ n > 1e-9 * scale:  # separating before: no impulse
            worst = max(worst, float(np.max(np.abs(imp))) / MASS)
            continue
        worst = max(worst, abs(min(p_n, float(u1 @ n + e * (u0 @ n)))))
        worst = max(worst, float(np.linalg.norm(p_t)) - MU * p_n)
        slip = u1 - (u1 @ n) * n
        if np.linalg.norm(slip) > 1e-9 * scale:
            worst = max(worst, float(np.max(np.abs(p_t + MU * p_n * slip / np.linalg.norm(slip)))))
    return worst


@pytest.mark.parametrize("landings", [LANDINGS, SLOW_FLAT], ids=["tilted", "slow_flat"])
def test_landings_batch_equals_solve_impact_and_each_answer_holds(landings: list) -> None:  # type: ignore[type-arg]
    v = np.array([row[0] for row in landings])
    om = np.array([row[1] for row in landings])
    normals = np.array([[row[2]] * 4 for row in landings])
    e = np.array([[row[3]] * 4 for row in landings])
    batch = BatchBodies(mass=MASS, inertia_com=INERTIA, position_com=CENTRE, velocity_com=v,
                        angular_velocity=om)  # fmt: skip
    out = multi_impacts(batch, None, CORNERS, normals, e, MU)
    if landings is SLOW_FLAT:
        assert not out.by_reference.any()  # the kernel's own answers
    for i, (vel, spin, normal, rest) in enumerate(landings):
        contacts = [PointContact(a="body", b="ground", point=p, normal=normal, restitution=rest,
                                 friction=MU, where=f"contacts[{k}]")
                    for k, p in enumerate(CORNERS)]  # fmt: skip
        body = RigidBody(name="body", mass=MASS, inertia_com=INERTIA, position_com=CENTRE,
                         velocity_com=vel, angular_velocity=spin)  # fmt: skip
        res = solve_impact(ImpactProblem(bodies={"body": body, "ground": FixedBody(name="ground")},
                                         contacts=contacts))  # fmt: skip
        after = res.bodies["body"]
        assert [REGIME_NAMES[int(r)] for r in out.regime[i]] == [c.regime for c in res.contacts]
        flags = set(res.flag_codes())
        for name in ("statically_indeterminate", "multiple_solutions", "no_solution"):
            assert bool(getattr(out, name)[i]) == (name in flags), name
        assert not out.uniqueness_verified[i]  # four 3D frictional corners: not verified
        assert np.allclose(out.velocity_a[i], after.velocity_after, rtol=0, atol=1e-9)
        assert np.allclose(out.angular_velocity_a[i], after.angular_velocity_after, rtol=0,
                           atol=1e-9)  # fmt: skip
        # each answer a solution of the law, checked from first principles
        v0, om0 = np.array(vel), np.array(spin)
        api = np.array([c.impulse for c in res.contacts])
        assert _law_violation(v0, om0, after.velocity_after, after.angular_velocity_after, api,
                              np.array(normal), rest) <= 1e-9  # fmt: skip
        assert _law_violation(v0, om0, out.velocity_a[i], out.angular_velocity_a[i],
                              out.impulse[i], np.array(normal), rest) <= 1e-9  # fmt: skip
        assert res.energy.dissipated_theorem == pytest.approx(res.energy.dissipated, rel=1e-12)
    # the mixed regimes this case is about: corners slipping beside one sticking or lifting
    assert {"slip", "stick"}.issubset({REGIME_NAMES[int(r)] for r in out.regime.ravel()})


def test_the_checker_sees_a_wrong_answer() -> None:
    """The first-principles check is not vacuous: the batch's answer with one corner's
    tangential impulse turned by 0.1 rad about the normal fails it."""
    vel, spin, normal, rest = LANDINGS[1]
    batch = BatchBodies(mass=MASS, inertia_com=INERTIA, position_com=CENTRE,
                        velocity_com=np.array([vel]), angular_velocity=np.array([spin]))
    out = multi_impacts(batch, None, CORNERS, np.array([[normal] * 4]), rest, MU)
    n = np.array(normal) / np.linalg.norm(normal)
    imp = out.impulse[0].copy()
    k = int(np.argmax(np.linalg.norm(imp - np.outer(imp @ n, n), axis=1)))
    t = imp[k] - (imp[k] @ n) * n
    turned = t * np.cos(0.1) + np.cross(n, t) * np.sin(0.1)
    imp[k] = imp[k] - t + turned
    v0, om0 = np.array(vel), np.array(spin)
    assert _law_violation(v0, om0, out.velocity_a[0], out.angular_velocity_a[0], out.impulse[0],
                          np.array(normal), rest) <= 1e-9  # fmt: skip
    assert _law_violation(v0, om0, out.velocity_a[0], out.angular_velocity_a[0], imp,
                          np.array(normal), rest) > 1e-4  # fmt: skip

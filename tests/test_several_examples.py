"""The several-contact examples (issue 14, item 6) against their published closed forms, each
through the whole pipeline (scenario file -> solve_impact), with the theorem checked against
the direct kinetic-energy difference in every law.

Sources:

* Newton's cradle of n equal balls, simultaneous law (Moreau/Glocker generalized Newton: every
  contact active, ``w'' = -e w'``, momentum kept): ``v1'' = (1 - (n-1) e)/n v``, the others
  ``(1 + e)/n v`` (Glocker, *Set-Valued Force Laws*, Springer 2001, ch. 7; for n = 3 the
  ``((1-2e)/3, (1+e)/3, (1+e)/3) v`` of issue 14); sequential law with e = 1: ``(0, ..., 0, v)``
  (Ceanga and Hurmuzlu, J. Appl. Mech. 68 (2001) 575-583); dispersion law with e = 1: the
  compliant chain ``F = k delta^p`` (Liu, Zhao and Brogliato, Proc. R. Soc. A 464 (2008)
  3193-3211, section 3: the law *is* that dynamics in impulse space), checked here against
  a time-domain integration of the compliant chain in body coordinates (SciPy), the second
  route. (The published tables of Liu, Zhao and Brogliato, Proc. R. Soc. A 465 (2009) 1-23,
  were not available to us: they are not checked.)
* A planar rigid body struck at one frictionless point: Newton's law along the normal, the
  tangential momentum kept (Stronge, *Impact Mechanics*, CUP 2000, ch. 2): for a 2b x 2h block
  rocking onto its other corner, ``omega''/omega' = (1 - 2 tan^2 a)/(1 + 4 tan^2 a)`` with e = 0,
  the old corner separating while ``tan^2 a < 1/2``; beyond it both corners stay (generalized
  Newton), the rotation stops and the block slides.
* Housner, Bull. Seism. Soc. Am. 53 (1963) 403-417: the same landing without slip,
  ``omega''/omega' = 1 - 3/2 sin^2 a``.
* A ball into a frictionless V-groove (walls' normals at +-theta from the vertical), generalized
  Newton law: both walls active, the ball's velocity is reversed times e while
  ``|u|/v <= tan theta`` (u across, v down), each wall's impulse ``m (1+e) v / (2 cos theta)``
  when it falls straight; beyond, the far wall separates and the near wall alone acts (Newton
  at one frictionless contact).
* A box landing flat on four corners with e = 0 and friction enough to stick: every corner
  stops, so ``u'' = 0``, the floor's impulse is ``-m v'`` and its moment about the centre
  ``-J omega'``, ``E_d = E'``; the four normal impulses are not unique (statically
  indeterminate), the motion is (Pfeiffer and Glocker, *Multibody Dynamics with Unilateral
  Contacts*, Wiley 1996, ch. 7).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from conftest import EXAMPLES
from scipy.integrate import solve_ivp

from carnot import ImpactProblem, RigidBody, solve_impact
from carnot.io.scenario import load_scenario, parse_scenario, parse_text
from carnot.result import ImpactResult


def _checked(res: ImpactResult) -> ImpactResult:
    """The theorem against the direct difference (1e-12 of E'), each stage's ledger summing to
    the total, momentum kept."""
    en = res.energy
    assert abs(en.dissipated - en.dissipated_theorem) <= 1e-12 * en.before
    if res.stages:
        assert sum(s.dissipated for s in res.stages) == pytest.approx(
            en.dissipated_theorem, abs=1e-12 * en.before)  # fmt: skip
    assert res.momentum.linear_residual < 1e-12
    return res


def _cradle(n: int, e: float, law: str) -> ImpactProblem:
    name = "newtons_cradle.toml" if n == 3 else f"newtons_cradle_{n}.toml"
    text = (EXAMPLES / name).read_text()
    assert text.count("restitution = 1.0") == n - 1
    data = parse_text(text.replace("restitution = 1.0", f"restitution = {e!r}"), name)
    problem = parse_scenario(data, name)
    return replace(problem, multiple_impact=law)


def _velocities(res: ImpactResult, n: int) -> list[float]:
    return [float(res.bodies[f"ball{k}"].velocity_after[0]) for k in range(1, n + 1)]


@pytest.mark.parametrize("n", [3, 5])
@pytest.mark.parametrize("e", [0.0, 0.4, 1.0])
def test_cradle_simultaneous_closed_form(n: int, e: float) -> None:
    v = 1.0
    res = _checked(solve_impact(_cradle(n, e, "simultaneous")))
    expected = [(1 - (n - 1) * e) / n * v] + [(1 + e) / n * v] * (n - 1)
    assert _velocities(res, n) == pytest.approx(expected, rel=1e-12, abs=1e-12)
    assert all(c.active for c in res.contacts)
    # each contact passes on the momentum of the balls beyond it: m (n - k)(1 + e) v / n
    m = 0.1
    for k, c in enumerate(res.contacts, start=1):
        assert c.normal_impulse == pytest.approx(m * (n - k) * (1 + e) * v / n, rel=1e-12)
    assert res.energy.dissipated == pytest.approx(
        0.5 * m * v * v * (1 - e * e) * (n - 1) / n, rel=1e-12, abs=1e-15)  # fmt: skip


@pytest.mark.parametrize("n", [3, 5])
def test_cradle_sequential_elastic_sends_the_last_ball(n: int) -> None:
    res = _checked(solve_impact(_cradle(n, 1.0, "sequential")))
    assert _velocities(res, n) == pytest.approx([0.0] * (n - 1) + [1.0], abs=1e-12)
    assert [s.contacts for s in res.stages] == [(f"contacts[{k}]",) for k in range(n - 1)]


def _compliant_chain(n: int, v: float, exponent: float) -> np.ndarray:
    """Equal balls (0.1 kg) in a row with contacts ``F = delta^p`` integrated in time in body
    coordinates until all are apart and none catches up: the final velocities."""
    mass = 0.1

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        x, vel = y[:n], y[n:]
        force = np.maximum(x[:-1] - x[1:], 0.0) ** exponent
        acc = np.zeros(n)
        acc[:-1] -= force
        acc[1:] += force
        return np.concatenate([vel, acc / mass])

    y0 = np.zeros(2 * n)
    y0[n] = v
    t_end = 60.0 * (mass / v ** (exponent - 1)) ** (1 / (exponent + 1))
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-12, atol=1e-15)
    x, vel = sol.y[:n, -1], sol.y[n:, -1]
    assert np.all(np.diff(x) > 0.0) and np.all(np.diff(vel) >= 0.0)
    return vel


@pytest.mark.parametrize("n", [3, 5])
def test_cradle_dispersion_elastic_equals_the_compliant_chain(n: int) -> None:
    res = _checked(solve_impact(_cradle(n, 1.0, "dispersion")))
    assert _velocities(res, n) == pytest.approx(_compliant_chain(n, 1.0, 1.5), abs=1e-6)
    # elastic: nothing lost, to the integration's tolerance (rtol 1e-12), not to round-off
    assert res.energy.dissipated == pytest.approx(0.0, abs=1e-10 * res.energy.before)
    assert len(res.stages) >= 2


# ------------------------------------------------------------------------------ block


def _block(tan_alpha: float, friction: float) -> ImpactProblem:
    """The examples' block (h = 1 m) rocking about its left corner at -0.8 rad/s."""
    problem = load_scenario(EXAMPLES / "block_on_two_corners_frictionless.toml")
    h, omega, m = 1.0, -0.8, 3.0
    b = h * tan_alpha
    centre = np.array([b, h, 0.0])
    inertia = m * (b * b + h * h) / 3.0
    block = RigidBody(name="block", mass=m, inertia_com=np.eye(3) * inertia,
                      position_com=centre, velocity_com=np.cross([0, 0, omega], centre),
                      angular_velocity=[0, 0, omega])  # fmt: skip
    corners = [replace(c, point=np.array([x, 0.0, 0.0]), friction=friction)
               for c, x in zip(problem.contacts, (0.0, 2 * b), strict=True)]  # fmt: skip
    return replace(problem, bodies={**problem.bodies, "block": block}, contacts=corners)


def test_block_example_frictionless() -> None:
    problem = load_scenario(EXAMPLES / "block_on_two_corners_frictionless.toml")
    block = problem.bodies["block"]
    assert isinstance(block, RigidBody) and block.mass == 3.0
    assert [c.friction for c in problem.contacts] == [0.0, 0.0]
    res = _checked(solve_impact(problem))
    t = 0.25
    after = res.bodies["block"]
    assert after.angular_velocity_after[2] / -0.8 == pytest.approx(
        (1 - 2 * t * t) / (1 + 4 * t * t), rel=1e-12)  # fmt: skip
    assert after.velocity_after[0] == pytest.approx(0.8, rel=1e-12)  # no friction: kept
    assert [c.regime for c in res.contacts] == ["separate", "frictionless"]
    assert [c.active for c in res.contacts] == [False, True]


@pytest.mark.parametrize("tan_alpha", [0.1, 0.25, 0.6])
def test_block_frictionless_one_corner(tan_alpha: float) -> None:
    res = _checked(solve_impact(_block(tan_alpha, 0.0)))
    ratio = res.bodies["block"].angular_velocity_after[2] / -0.8
    t2 = tan_alpha**2
    assert ratio == pytest.approx((1 - 2 * t2) / (1 + 4 * t2), rel=1e-11)
    assert res.contacts[0].active is False and res.contacts[0].normal_impulse == 0.0


@pytest.mark.parametrize("tan_alpha", [0.8, 1.0, 1.5])
def test_block_frictionless_both_corners_beyond_the_bound(tan_alpha: float) -> None:
    """tan^2 a > 1/2: the old corner would be pulled down, so both stay: the rotation stops and
    the centre slides on at its horizontal velocity, omega' h."""
    res = _checked(solve_impact(_block(tan_alpha, 0.0)))
    after = res.bodies["block"]
    assert after.angular_velocity_after[2] == pytest.approx(0.0, abs=1e-12)
    assert after.velocity_after[1] == pytest.approx(0.0, abs=1e-12)
    assert after.velocity_after[0] == pytest.approx(0.8 * 1.0, rel=1e-12)
    assert all(c.active and c.normal_impulse > 0 for c in res.contacts)


@pytest.mark.parametrize("tan_alpha", [0.1, 0.25, 0.5])
def test_block_with_friction_is_housner(tan_alpha: float) -> None:
    res = _checked(solve_impact(_block(tan_alpha, 10.0)))
    ratio = res.bodies["block"].angular_velocity_after[2] / -0.8
    sin2 = tan_alpha**2 / (1 + tan_alpha**2)
    assert ratio == pytest.approx(1 - 1.5 * sin2, rel=1e-10)
    assert [c.regime for c in res.contacts] == ["separate", "stick"]


# ------------------------------------------------------------------------------ V-groove

M_BALL, COS, SIN = 0.2, 0.8, 0.6


def test_v_groove_example() -> None:
    problem = load_scenario(EXAMPLES / "ball_into_v_groove.toml")
    ball = problem.bodies["ball"]
    assert isinstance(ball, RigidBody) and ball.mass == M_BALL
    e, v = 0.5, 2.0
    assert [c.restitution for c in problem.contacts] == [e, e]
    np.testing.assert_allclose(problem.contacts[0].normal, [SIN, COS, 0.0], rtol=1e-15)
    res = _checked(solve_impact(problem))
    np.testing.assert_allclose(res.bodies["ball"].velocity_after, [0.0, e * v, 0.0],
                               atol=1e-12)  # fmt: skip
    for c in res.contacts:
        assert c.normal_impulse == pytest.approx(M_BALL * (1 + e) * v / (2 * COS), rel=1e-12)
    assert res.energy.dissipated == pytest.approx(0.5 * M_BALL * v * v * (1 - e * e), rel=1e-12)


@pytest.mark.parametrize("slant", [0.0, 0.3, 0.7, 0.76, 1.0, 1.3])
def test_v_groove_slanted_arrival(slant: float) -> None:
    """Ball arriving at (u, -v), u = slant v: reversed times e while u/v <= tan theta = 3/4;
    beyond, only the right wall (normal (-3/5, 4/5)) acts, by Newton's law alone."""
    e, v = 0.5, 2.0
    problem = load_scenario(EXAMPLES / "ball_into_v_groove.toml")
    ball = problem.bodies["ball"]
    assert isinstance(ball, RigidBody)
    velocity = np.array([slant * v, -v, 0.0])
    problem = replace(problem, bodies={**problem.bodies,
                                       "ball": replace(ball, velocity_com=velocity)})  # fmt: skip
    res = _checked(solve_impact(problem))
    after = res.bodies["ball"].velocity_after
    if slant <= SIN / COS:
        np.testing.assert_allclose(after, -e * velocity, atol=1e-12)
        assert all(c.active for c in res.contacts)
    else:
        n = np.array([-SIN, COS, 0.0])
        np.testing.assert_allclose(after, velocity - (1 + e) * (n @ velocity) * n, atol=1e-12)
        assert [c.active for c in res.contacts] == [False, True]


# ------------------------------------------------------------------------------ box


def test_box_lands_flat_and_stops() -> None:
    problem = load_scenario(EXAMPLES / "box_lands_flat.toml")
    box = problem.bodies["box"]
    assert isinstance(box, RigidBody) and box.mass == 2.0
    assert [c.friction for c in problem.contacts] == [1.5] * 4
    assert [c.restitution for c in problem.contacts] == [0.0] * 4
    res = _checked(solve_impact(problem))
    after = res.bodies["box"]
    scale = 1.0
    np.testing.assert_allclose(after.velocity_after, 0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(after.angular_velocity_after, 0.0, atol=1e-11 * scale)
    total = sum(np.asarray(c.impulse) for c in res.contacts)
    np.testing.assert_allclose(total, -box.mass * np.asarray(box.velocity_com), atol=1e-12)
    moment = sum(np.cross(np.asarray(c.point) - box.position_com, c.impulse)
                 for c in res.contacts)  # fmt: skip
    np.testing.assert_allclose(moment, -box.inertia_com @ box.angular_velocity, atol=1e-12)
    assert res.energy.dissipated == pytest.approx(res.energy.before, rel=1e-12)
    assert res.flag_codes() == ["statically_indeterminate"]
    for c in res.contacts:
        assert c.regime == "stick" and c.normal_impulse >= 0.0
        assert np.linalg.norm(c.tangential_impulse) <= 1.5 * c.normal_impulse * (1 + 1e-12)


def test_box_frictionless_vertical_drop_stops_every_corner() -> None:
    """The same box falling straight (no slide, no spin) on a frictionless floor, e = 0."""
    problem = load_scenario(EXAMPLES / "box_lands_flat.toml")
    box = problem.bodies["box"]
    assert isinstance(box, RigidBody)
    still = replace(box, velocity_com=np.array([0.0, 0.0, -1.0]), angular_velocity=np.zeros(3))
    corners = [replace(c, friction=0.0) for c in problem.contacts]
    res = _checked(solve_impact(replace(problem, bodies={**problem.bodies, "box": still},
                                        contacts=corners)))  # fmt: skip
    np.testing.assert_allclose(res.bodies["box"].velocity_after, 0.0, atol=1e-12)
    assert sum(c.normal_impulse for c in res.contacts) == pytest.approx(2.0, rel=1e-12)
    assert res.flag_codes() == ["statically_indeterminate"]


# ------------------------------------------------------------------------------ plot


def test_plot_of_the_laws_draws_the_closed_forms(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """The bars of the cradle's plot are the published outgoing velocities (simultaneous and
    sequential), and the CLI writes the picture."""
    from carnot.cli import main
    from carnot.plot_several import plot_laws

    problem = load_scenario(EXAMPLES / "newtons_cradle_5.toml")
    fig = plot_laws(problem)
    ax_v = fig.axes[0]
    heights = [p.get_height() for p in ax_v.patches]
    simultaneous, sequential = heights[:5], heights[5:10]
    assert simultaneous == pytest.approx([-0.6, 0.4, 0.4, 0.4, 0.4], abs=1e-12)
    assert sequential == pytest.approx([0.0, 0.0, 0.0, 0.0, 1.0], abs=1e-12)
    out = tmp_path / "cradle.png"
    assert main(["solve", str(EXAMPLES / "newtons_cradle_5.toml"), "--plot", str(out)]) == 0
    assert out.stat().st_size > 1000


def test_plot_of_a_frictional_problem_names_the_laws_it_cannot_use() -> None:
    from carnot.plot_several import laws_side_by_side

    cmp = laws_side_by_side(load_scenario(EXAMPLES / "block_on_two_corners.toml"))
    assert list(cmp.results) == ["simultaneous"]
    assert set(cmp.refused) == {"sequential", "dispersion"}
    assert all("friction" in reason for reason in cmp.refused.values())


def test_plot_needs_several_contacts() -> None:
    from carnot.errors import InputError
    from carnot.plot_several import laws_side_by_side

    with pytest.raises(InputError, match="plot: compares the multiple-impact laws"):
        laws_side_by_side(load_scenario(EXAMPLES / "ball_on_floor.toml"))


def test_plot_of_the_laws_for_a_system_in_generalized_coordinates() -> None:
    """The three-ball cradle as a system (coordinates x1, x2, x3; M = m I): the bars are the
    coordinates' rates, the published ``((1-2e)/3, (1+e)/3, (1+e)/3) v`` and ``(0, 0, v)``."""
    from carnot.model.system import System, SystemContact, SystemProblem
    from carnot.plot_several import plot_laws

    e, v = 0.5, 2.0
    contacts = [SystemContact(jacobian=[[-1.0 if j == k else 1.0 if j == k + 1 else 0.0
                                         for j in range(3)], [0.0] * 3, [0.0] * 3],
                              normal=[1.0, 0.0, 0.0], restitution=e, where=f"contacts[{k}]")
                for k in range(2)]  # fmt: skip
    system = System(mass_matrix=np.eye(3) * 0.1, velocity=[v, 0.0, 0.0],
                    coordinates=("x1", "x2", "x3"))  # fmt: skip
    fig = plot_laws(SystemProblem(system=system, contacts=contacts))
    heights = [p.get_height() for p in fig.axes[0].patches]
    assert heights[:3] == pytest.approx([(1 - 2 * e) / 3 * v, (1 + e) / 3 * v, (1 + e) / 3 * v],
                                        abs=1e-12)  # fmt: skip
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == ["x1", "x2", "x3"]

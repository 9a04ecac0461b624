"""Systems from MuJoCo models (carnot.model.mjcf, the extra carnot[mujoco]) against closed forms.

* A solid sphere on a rough plane (tests/models/ball_on_plane.xml): gross slip
  ``P_t = -mu P_n`` when ``mu (1 + e) |v_n| < (2/7) |w_t|``, else it leaves rolling with
  ``v'' = 5/7 v`` (Brach, *Mechanical Impact Dynamics*, Wiley 1991, ch. 4; Cross, Am. J. Phys.
  70, 2002). MuJoCo's free joint has 6 coordinates (its angular velocity in body axes).
* A planar two-link arm striking a table with its tip (tests/models/two_link_arm.xml): the
  textbook mass matrix of the 2R arm (Spong, Hutchinson and Vidyasagar, *Robot Modeling and
  Control*, Wiley 2006, section 7.3: ``M11 = m1 c1^2 + m2 (l1^2 + c2^2 + 2 l1 c2 cos q2) + I1 +
  I2``, ``M12 = m2 (c2^2 + l1 c2 cos q2) + I2``, ``M22 = m2 c2^2 + I2``) and the frictionless
  Newton impact in closed form, ``q'' = q' - (1 + e) (n.J q') M^-1 J^T n / (n^T J M^-1 J^T n)``,
  ``E_d = 1/2 (1 - e^2) (n.J q')^2 / (n^T J M^-1 J^T n)``.
"""

from __future__ import annotations

import json
import math
import sys
import tomllib
from pathlib import Path

import mujoco  # (the extra is in requirements.lock: these tests must run)
import numpy as np
import pytest
from chains import Chain

from carnot import ImpactProblem, InputError, PointConstraint, PointContact, solve_impact
from carnot.cli import main
from carnot.io.system_scenario import parse_system_scenario, system_scenario_toml
from carnot.model.mjcf import mjcf_problem

MODELS = Path(__file__).parent / "models"
BALL = MODELS / "ball_on_plane.xml"
ARM = MODELS / "two_link_arm.xml"


def _sphere_expected(v: np.ndarray, omega: np.ndarray, mu: float, e: float, radius: float):
    """Post-impact (v, omega) of a solid sphere (m = 1, I = 2/5 m R^2) on a plane z = 0."""
    r = np.array([0.0, 0.0, -radius])
    w_t = (v + np.cross(omega, r))[:2]
    p_n = (1 + e) * abs(v[2])
    if mu * p_n < (2 / 7) * np.linalg.norm(w_t):
        p_t = -mu * p_n * w_t / np.linalg.norm(w_t)
    else:  # rolling: the tangential impulse that stops the slip, m (2/7) w_t
        p_t = -(2 / 7) * w_t
    impulse = np.array([p_t[0], p_t[1], p_n])
    inertia = 0.4 * radius**2
    return v + impulse, omega + np.cross(r, impulse) / inertia


@pytest.mark.parametrize(("key", "regime"), [("slip", "slip"), ("roll", "slip-stick")])
def test_ball_on_a_rough_plane(key: str, regime: str) -> None:
    e = 0.5
    problem = mjcf_problem(BALL, keyframe=key, restitution=e)
    contact = problem.contacts[0]
    assert contact.friction == pytest.approx(0.1)  # from the geoms
    assert contact.normal.tolist() == [0.0, 0.0, 1.0] and contact.name == "ball/floor"
    r = solve_impact(problem)
    q1 = problem.system.velocity
    v_exp, om_exp = _sphere_expected(q1[:3], q1[3:], 0.1, e, 0.1)
    assert np.allclose(r.system.velocity_after[:3], v_exp, rtol=0, atol=1e-12)
    assert np.allclose(r.system.velocity_after[3:], om_exp, rtol=0, atol=1e-10)
    assert r.contacts[0].regime == regime
    assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, rel=1e-12)


def _arm_closed_form(q: np.ndarray, rate: np.ndarray, e: float):
    l1, l2, m1, m2, c1, c2, i1, i2, radius = 0.5, 0.4, 1.0, 0.6, 0.25, 0.2, 0.02, 0.01, 0.02
    cos2 = math.cos(q[1])
    mass = np.array([
        [m1 * c1**2 + m2 * (l1**2 + c2**2 + 2 * l1 * c2 * cos2) + i1 + i2,
         m2 * (c2**2 + l1 * c2 * cos2) + i2],
        [m2 * (c2**2 + l1 * c2 * cos2) + i2, m2 * c2**2 + i2],
    ])  # fmt: skip
    # rotation about y turns x towards -z: a link at angle a points along (cos a, 0, -sin a)
    elbow = l1 * np.array([math.cos(q[0]), -math.sin(q[0])])
    tip = elbow + l2 * np.array([math.cos(q[0] + q[1]), -math.sin(q[0] + q[1])])
    point = tip - [0.0, radius]  # the tip ball's lowest point (x, z), relative to the shoulder
    # y x (dx, 0, dz) = (dz, 0, -dx): each column of the point's (x, z) Jacobian
    jac = np.array([[point[1], point[1] - elbow[1]], [-point[0], -(point[0] - elbow[0])]])
    n = np.array([0.0, 1.0])  # +z
    g = n @ jac @ np.linalg.solve(mass, jac.T @ n)
    w_n = n @ jac @ rate
    after = rate - (1 + e) * w_n * np.linalg.solve(mass, jac.T @ n) / g
    return mass, after, 0.5 * (1 - e**2) * w_n**2 / g


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_two_link_arm_strikes_a_table(e: float) -> None:
    problem = mjcf_problem(ARM, keyframe="strike", restitution=e)
    mass, after, dissipated = _arm_closed_form(np.array([0.5, 0.7]), np.array([2.0, 1.5]), e)
    assert np.allclose(problem.system.mass_matrix, mass, rtol=1e-12, atol=0)
    assert problem.system.coordinates == ("shoulder", "elbow")
    assert problem.contacts[0].friction == 0.0  # condim 1
    r = solve_impact(problem)
    assert np.allclose(r.system.velocity_after, after, rtol=0, atol=1e-9)
    assert r.energy.dissipated == pytest.approx(dissipated, rel=1e-8, abs=1e-12)
    assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, rel=0, abs=1e-12)
    assert r.warnings == ()  # the out-of-plane row of the planar arm is silent


def test_from_mjcf_writes_a_scenario_that_solves_the_same(tmp_path, capsys) -> None:
    out = tmp_path / "arm.toml"
    args = ["from-mjcf", str(ARM), "--keyframe", "strike", "--restitution", "0.5"]
    assert main([*args, "-o", str(out)]) == 0
    assert main(args) == 0
    assert capsys.readouterr().out == out.read_text()
    assert "[system]" in out.read_text() and 'name = "tip/table"' in out.read_text()
    assert main(["solve", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    direct = solve_impact(mjcf_problem(ARM, keyframe="strike", restitution=0.5))
    assert data["system"]["velocity"] == direct.system.velocity_after.tolist()
    assert data["system"]["coordinates"] == ["shoulder", "elbow"]


def test_mjcf_errors(tmp_path, capsys) -> None:
    with pytest.raises(InputError, match="unknown keyframe"):
        mjcf_problem(ARM, keyframe="nope")
    with pytest.raises(InputError, match="qvel: must be 2 finite numbers"):
        mjcf_problem(ARM, keyframe=0, qvel=[1.0])
    with pytest.raises(InputError, match="has no approaching contact"):
        mjcf_problem(ARM, keyframe="strike", qvel=[-2.0, -1.5])  # moving away
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body></mujoco>")
    assert main(["from-mjcf", str(bad)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "cannot read the MJCF model" in err


def test_without_the_extra_the_command_says_how_to_install_it(monkeypatch, capsys) -> None:
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco now raises ImportError
    assert main(["from-mjcf", str(ARM), "--keyframe", "strike"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and 'pip install "carnot[mujoco]"' in err


# ------------------------------------------------------------------ equality constraints
# The same arm with its elbow made by an equality constraint (carnot.model.mjcf module
# docstring): the forearm is a free body (6 coordinates) held by a connect (a ball joint at
# the elbow: the hinge's impact, Spong's closed form above) or a weld (one rigid body about
# the shoulder); or the hinge arm with a joint equality coupling the elbow to the shoulder.

CONNECT = MODELS / "arm_elbow_connect.xml"
WELD = MODELS / "arm_elbow_weld.xml"
L1, M1, C1, I1, M2, C2, I2 = 0.5, 1.0, 0.25, 0.02, 0.6, 0.2, 0.01


def _free_forearm_state(q1: float, q2: float, rate1: float, rate2: float):
    """qpos, qvel of the arm with a free forearm at joint angles ``(q1, q2)`` and rates: the
    forearm's origin at the elbow, turned by ``q1 + q2`` about y; its free joint's linear
    velocity (world axes) is the elbow's, its angular velocity (body axes) ``(0, rate1 +
    rate2, 0)``."""
    turn = q1 + q2
    elbow = [L1 * math.cos(q1), 0.0, 1.0 - L1 * math.sin(q1)]
    quat = [math.cos(turn / 2), 0.0, math.sin(turn / 2), 0.0]
    v_elbow = [-L1 * math.sin(q1) * rate1, 0.0, -L1 * math.cos(q1) * rate1]
    return [q1, *elbow, *quat], [rate1, *v_elbow, 0.0, rate1 + rate2, 0.0]


def _mujoco_equality_rows(path: Path, qpos, qvel) -> np.ndarray:
    """MuJoCo's own constraint Jacobian rows of the model's equalities (dense ``efc_J``)."""
    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = qpos, qvel
    mujoco.mj_forward(model, data)
    jac = np.asarray(data.efc_J).reshape(data.nefc, model.nv)
    return jac[np.asarray(data.efc_type) == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)]


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_connect_elbow_is_the_hinge_arm(e: float) -> None:
    """A connect at the elbow (a pin with three rows) on the free forearm: the planar arm's
    closed-form impact (Spong's M), the forearm's out-of-plane motion left at zero."""
    qpos, qvel = _free_forearm_state(0.5, 0.7, 2.0, 1.5)
    problem = mjcf_problem(CONNECT, qpos=qpos, qvel=qvel, restitution=e)
    (pin,) = problem.constraints
    assert pin.kind == "pin" and pin.name == "elbow" and pin.angular_jacobian is None
    # the rows are MuJoCo's own constraint Jacobian for the connect (J_1(p_1) - J_2(p_2))
    assert np.allclose(pin.jacobian, _mujoco_equality_rows(CONNECT, qpos, qvel), atol=1e-14)
    _, after, dissipated = _arm_closed_form(np.array([0.5, 0.7]), np.array([2.0, 1.5]), e)
    r = solve_impact(problem)
    q = r.system.velocity_after
    assert q[0] == pytest.approx(after[0], abs=1e-12)
    assert q[5] == pytest.approx(after[0] + after[1], abs=1e-12)  # the forearm's y rate
    assert np.allclose(q[1:4], _free_forearm_state(0.5, 0.7, after[0], 0.0)[1][1:4], atol=1e-12)
    assert np.allclose(q[[2, 4, 6]], 0.0, atol=1e-12)  # nothing out of the x-z plane
    assert r.energy.dissipated == pytest.approx(dissipated, rel=1e-10, abs=1e-14)
    assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, rel=0, abs=1e-12)
    held = r.constraints[0]
    assert np.allclose(held.relative_velocity_after, 0.0, atol=1e-12)
    assert r.warnings == ()


def test_weld_elbow_is_one_rigid_body_about_the_shoulder() -> None:
    """A weld (a pin with six rows) makes the bent arm one rigid body turning about the
    shoulder: one degree of freedom, so Newton's ``w_n'' = -e w_n`` gives ``rate'' = -e
    rate`` and ``E_d = 1/2 (1 - e^2) I_O rate^2``, with ``I_O`` the moment of inertia about
    the shoulder by the parallel-axis theorem."""
    e, rate, q2 = 0.5, 2.0, 0.7
    qpos, qvel = _free_forearm_state(0.5, q2, rate, 0.0)
    problem = mjcf_problem(WELD, qpos=qpos, qvel=qvel, restitution=e)
    (weld,) = problem.constraints
    assert weld.kind == "pin" and weld.angular_jacobian is not None
    rows = _mujoco_equality_rows(WELD, qpos, qvel)
    assert np.allclose(weld.jacobian, rows[:3], atol=1e-14)  # the weld's translation rows
    # MuJoCo's rotation rows are a (torque-scaled) quaternion form: the same row space
    both = np.vstack([weld.angular_jacobian, rows[3:]])
    assert np.linalg.matrix_rank(both, tol=1e-9) == 3
    r = solve_impact(problem)
    q = r.system.velocity_after
    assert q[0] == pytest.approx(-e * rate, abs=1e-12) and q[5] == pytest.approx(-e * rate)
    inertia_o = I1 + M1 * C1**2 + I2 + M2 * (L1**2 + C2**2 + 2 * L1 * C2 * math.cos(q2))
    assert r.energy.before == pytest.approx(0.5 * inertia_o * rate**2, rel=1e-13)
    assert r.energy.dissipated == pytest.approx(
        0.5 * (1 - e**2) * inertia_o * rate**2, rel=1e-12
    )
    assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, rel=0, abs=1e-12)
    assert np.linalg.norm(r.constraints[0].moment) > 0  # the weld holds the bend
    assert r.warnings == ()
    # the [system] file keeps the weld's angular rows ([[constraints]] angular_jacobian)
    text = system_scenario_toml(problem)
    assert "angular_jacobian = [" in text
    again = solve_impact(parse_system_scenario(tomllib.loads(text)))
    assert again.system.velocity_after.tolist() == q.tolist()


@pytest.mark.parametrize(
    "polycoef", ["0.45 0.5 0 0 0", "0.5 0.3 0.2 0 0"], ids=["linear", "quadratic"]
)
def test_joint_equality_couples_the_elbow(tmp_path: Path, polycoef: str) -> None:
    """``elbow = p(shoulder)``: at ``shoulder = 0.5`` both polynomials give ``elbow = 0.7``
    and slope ``p' = 0.5``, so the arm has one degree of freedom ``s = (1, 0.5)``: Newton's
    ``rate'' = -e rate`` and ``E_d = 1/2 (1 - e^2) (s^T M s) rate^2`` (Spong's M)."""
    text = ARM.read_text().replace(
        "</worldbody>",
        f'</worldbody><equality><joint name="couple" joint1="elbow" joint2="shoulder" '
        f'polycoef="{polycoef}"/></equality>',
    )
    path = tmp_path / "coupled.xml"
    path.write_text(text)
    e, rate = 0.5, 2.0
    qpos, qvel = [0.5, 0.7], [rate, 0.5 * rate]
    problem = mjcf_problem(path, qpos=qpos, qvel=qvel, restitution=e)
    (couple,) = problem.constraints
    assert couple.jacobian[0].tolist() == pytest.approx([-0.5, 1.0], abs=1e-15)
    # MuJoCo's joint-equality row (elbow' - p'(shoulder) shoulder')
    assert np.allclose(couple.jacobian[:1], _mujoco_equality_rows(path, qpos, qvel), atol=1e-14)
    mass, _, _ = _arm_closed_form(np.array(qpos), np.array(qvel), e)
    s = np.array([1.0, 0.5])
    r = solve_impact(problem)
    assert np.allclose(r.system.velocity_after, -e * rate * s, rtol=0, atol=1e-12)
    assert r.energy.dissipated == pytest.approx(0.5 * (1 - e**2) * (s @ mass @ s) * rate**2,
                                                rel=1e-12)  # fmt: skip
    assert r.warnings == ()


def test_equalities_fasten_ignore_and_errors(tmp_path: Path, capsys) -> None:
    qpos, qvel = _free_forearm_state(0.5, 0.7, 2.0, 1.5)
    assert mjcf_problem(CONNECT, qpos=qpos, qvel=qvel, equality="ignore").constraints == ()
    fastened = mjcf_problem(CONNECT, qpos=qpos, qvel=qvel, equality="fasten")
    assert fastened.constraints[0].kind == "fasten"
    # a pin must hold before the impact; a fastening imposes it (here: it held already)
    broken = [*qvel[:3], qvel[3] + 0.1, *qvel[4:]]
    with pytest.raises(InputError, match=r"constraints\[0\]: a pin needs zero relative"):
        solve_impact(mjcf_problem(CONNECT, qpos=qpos, qvel=broken))
    ok = solve_impact(fastened)
    assert ok.energy.dissipated == pytest.approx(
        solve_impact(mjcf_problem(CONNECT, qpos=qpos, qvel=qvel)).energy.dissipated, rel=1e-12
    )
    with pytest.raises(InputError, match="equality: must be one of pin, fasten, ignore"):
        mjcf_problem(CONNECT, qpos=qpos, qvel=qvel, equality="hold")
    tendon = tmp_path / "tendon.xml"
    tendon.write_text(
        ARM.read_text().replace(
            "</worldbody>",
            '</worldbody><tendon><fixed name="t"><joint joint="shoulder" coef="1"/></fixed>'
            '</tendon><equality><tendon name="lock" tendon1="t"/></equality>',
        )
    )
    assert mjcf_problem(tendon, keyframe="strike", equality="ignore").constraints == ()
    # a tendon equality: MuJoCo's own row, which for a fixed tendon is its coefficient at its
    # joint's dof (the model's wrap_prm, read apart); fastened, it holds the shoulder (the
    # tendon's one joint) still after the impact
    locked = mjcf_problem(tendon, keyframe="strike", equality="fasten")
    model = mujoco.MjModel.from_xml_path(str(tendon))
    expected = np.zeros(model.nv)
    expected[model.jnt_dofadr[model.wrap_objid[0]]] = model.wrap_prm[0]
    assert locked.constraints[0].jacobian[0].tolist() == expected.tolist()
    after = solve_impact(locked).system.velocity_after
    assert abs(after[0]) < 1e-12 < abs(locked.system.velocity[0])


def test_from_mjcf_qpos_qvel_flags(tmp_path: Path, capsys) -> None:
    qpos, qvel = _free_forearm_state(0.5, 0.7, 2.0, 1.5)
    out = tmp_path / "loop.toml"
    args = ["from-mjcf", str(CONNECT), "--qpos", *map(repr, qpos), "--qvel", *map(repr, qvel)]
    assert main([*args, "--restitution", "0.5", "-o", str(out)]) == 0
    text = out.read_text()
    assert '[[constraints]]\ntype = "pin"\nname = "elbow"' in text
    assert main(["solve", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    direct = solve_impact(mjcf_problem(CONNECT, qpos=qpos, qvel=qvel, restitution=0.5))
    assert data["system"]["velocity"] == direct.system.velocity_after.tolist()
    assert data["constraints"][0]["name"] == "elbow"
    # lengths checked against the model: nq = 8, nv = 7
    assert main([*args[:2], "--qpos", "0.5", "0.7"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "qpos: must be 8 finite numbers (model.nq = 8)" in err
    assert main([*args[:-1]]) == 2
    assert "qvel: must be 7 finite numbers (model.nv = 7); 6 numbers" in capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:
        main([*args, "--equality", "weld"])
    assert stop.value.code == 2 and "invalid choice" in capsys.readouterr().err


# A closed loop: a five-bar linkage (four links hinged in a row from the origin, the last
# one's tip held to the ground by a connect: two degrees of freedom), built as MuJoCo's tree
# of hinges closed by the connect, and as four free rigid bodies joined by five pins
# (tests/chains.py): two independent front ends that must agree, under Newton, Coulomb slip
# and sticking.

LOOP = Chain(masses=[1.0, 0.8, 1.2, 0.7], lengths=[0.6, 0.9, 0.7, 0.5],
             angles=[1.2, 0.1, -0.8, -1.9], rates=[0.0] * 4)  # fmt: skip
BALL_ON_LINK2, BALL_RADIUS = 0.45, 0.03


def _five_bar_xml() -> str:
    """Links along their body x axes, hinges about z, turned by the relative angles (the
    model is defined in the closed configuration); a massless ball under link 2's middle
    touches a plane (normal +y)."""
    c = LOOP
    rel = np.diff(c.angles, prepend=0.0)
    ball = c.point(1, BALL_ON_LINK2) - [0.0, BALL_RADIUS, 0.0]
    body = ""
    for k in reversed(range(4)):
        m, length = c.masses[k], c.lengths[k]
        i = m * length**2 / 12
        pos = "0 0 0" if k == 0 else f"{c.lengths[k - 1]!r} 0 0"
        ball_geom = (f'<geom name="ball" type="sphere" size="{BALL_RADIUS}" mass="0" '
                     f'pos="{BALL_ON_LINK2} 0 0"/>' if k == 1 else "")  # fmt: skip
        body = (
            f'<body name="link{k + 1}" pos="{pos}" euler="0 0 {float(rel[k])!r}">'
            f'<joint name="j{k + 1}" type="hinge" axis="0 0 1"/>'
            f'<inertial pos="{length / 2!r} 0 0" mass="{m}" '
            f'diaginertia="{0.01 * i!r} {i!r} {i!r}"/>'
            f"{ball_geom}{body}</body>"
        )
    return (
        '<mujoco><compiler angle="radian"/><option gravity="0 0 0"/>'
        '<default><geom contype="1" conaffinity="1" margin="0.001"/></default><worldbody>'
        f'<geom name="floor" type="plane" size="3 3 0.1" '
        f'pos="{float(ball[0])!r} {float(ball[1])!r} 0" '
        f'zaxis="0 1 0"/>{body}</worldbody><equality>'
        f'<connect name="loop" body1="link4" body2="world" anchor="{c.lengths[3]!r} 0 0"/>'
        f"</equality></mujoco>"
    )


def _five_bar_rates() -> np.ndarray:
    """Absolute link rates in the two degrees of freedom (the null space of the tip's x-y
    Jacobian) that move link 2's ball at (0.5, -1) m/s: down and sliding."""
    null = np.linalg.svd(LOOP.jacobian(3, LOOP.lengths[3])[:2])[2][-2:].T
    ball = LOOP.jacobian(1, BALL_ON_LINK2)[:2]
    return null @ np.linalg.solve(ball @ null, [0.5, -1.0])


@pytest.mark.parametrize(
    "law",
    [{"restitution": 0.5}, {"restitution": 0.3, "friction": 0.2},
     {"restitution": 0.0, "friction": 0.5, "tangential": "stick"}],
    ids=["newton", "coulomb", "stick"],
)  # fmt: skip
def test_five_bar_closed_by_connect_equals_free_bodies_with_pins(tmp_path, law) -> None:
    path = tmp_path / "five_bar.xml"
    path.write_text(_five_bar_xml())
    rates = _five_bar_rates()
    problem = mjcf_problem(path, qpos=[0.0] * 4, qvel=np.diff(rates, prepend=0.0),
                           friction=law.get("friction", 0.0), restitution=law["restitution"],
                           tangential=law.get("tangential", "slip"))  # fmt: skip
    assert [k.name for k in problem.constraints] == ["loop"]
    mj = solve_impact(problem)
    chain = Chain(masses=LOOP.masses, lengths=LOOP.lengths,
                  angles=LOOP.angles, rates=list(rates))  # fmt: skip
    ball = chain.point(1, BALL_ON_LINK2) - [0.0, BALL_RADIUS, 0.0]
    loop = PointConstraint(kind="pin", body="link4", point=chain.point(3, chain.lengths[3]),
                           where="constraints[4]")  # fmt: skip
    free = solve_impact(
        ImpactProblem(
            bodies=chain.bodies(),
            contacts=[PointContact(a="link2", b="ground", point=ball, normal=[0, 1, 0], **law)],
            constraints=[*chain.joint_pins(), loop],
        )
    )
    after = np.cumsum(mj.system.velocity_after)  # hinge rates to absolute link rates
    for k in range(4):
        assert after[k] == pytest.approx(
            free.bodies[f"link{k + 1}"].angular_velocity_after[2], abs=1e-10
        )
    assert np.allclose(mj.contacts[0].impulse, free.contacts[0].impulse, atol=1e-10)
    assert mj.contacts[0].regime == free.contacts[0].regime
    for key in ("before", "after", "dissipated", "dissipated_theorem"):
        assert getattr(mj.energy, key) == pytest.approx(getattr(free.energy, key), abs=1e-10)
    assert mj.energy.dissipated == pytest.approx(
        mj.energy.dissipated_theorem, abs=1e-12 * mj.energy.before
    )
    # the loop's impulse at the ground anchor: the free bodies' pin to the ground
    assert np.allclose(mj.constraints[0].impulse, free.constraints[4].impulse, atol=1e-10)


def test_shipped_connect_example_is_the_hinge_arm() -> None:
    """examples/mjcf/arm_elbow_connect.xml at its keyframe: the hinge arm's closed form."""
    example = Path(__file__).resolve().parents[1] / "examples" / "mjcf" / "arm_elbow_connect.xml"
    r = solve_impact(mjcf_problem(example, keyframe="strike", restitution=0.5))
    _, after, dissipated = _arm_closed_form(np.array([0.5, 0.7]), np.array([2.0, 1.5]), 0.5)
    q = r.system.velocity_after
    assert [q[0], q[5]] == pytest.approx([after[0], after[0] + after[1]], abs=1e-12)
    assert r.energy.dissipated == pytest.approx(dissipated, rel=1e-10)
    assert [k.name for k in r.constraints] == ["elbow"] and r.warnings == ()


def _problem_digest(problem) -> list:
    """Every number and name of a system problem, for a comparison bit for bit."""
    items = [(c.name, c.where, c.jacobian.tobytes(), c.normal.tobytes(), c.friction,
              c.tangential) for c in problem.contacts]  # fmt: skip
    items += [(c.name, c.kind, c.jacobian.tobytes(),
               None if c.angular_jacobian is None else c.angular_jacobian.tobytes())
              for c in problem.constraints]  # fmt: skip
    system = problem.system
    return [system.mass_matrix.tobytes(), system.velocity.tobytes(), items]


@pytest.mark.parametrize("model_name, keyframe, equality",
                         [("go2_drop.xml", "home", "pin"), ("quadruped_drop.xml", "drop", "fasten"),
                          ("humanoid_drop.xml", "drop", "pin")])  # fmt: skip
def test_position_stage_is_the_whole_forward(model_name: str, keyframe: str,
                                             equality: str, monkeypatch) -> None:  # fmt: skip
    """The problem is built after MuJoCo's position stage (``mj_fwdPosition``) alone: the
    same problem, bit for bit, as after the whole ``mj_forward`` (the route it replaces), in
    states along a drop of 1.5 s (Go2's feet, limits and self-contacts; the dm_control
    quadruped's tendon equalities; the humanoid's feet and hands)."""
    import carnot.model.mjcf as mjcf

    model = mujoco.MjModel.from_xml_path(str(MODELS / model_name))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY,
                                                               keyframe))  # fmt: skip
    states = []
    for step in range(int(1.5 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        if step % 20 == 0:
            states.append((data.qpos.copy(), data.qvel.copy()))

    def made(qpos: np.ndarray, qvel: np.ndarray) -> list | str:
        try:
            return _problem_digest(mjcf_problem(model, qpos=qpos, qvel=qvel, resting=True,
                                                equality=equality, gap=1e-3))  # fmt: skip
        except InputError as err:
            return str(err)

    compared = 0
    for qpos, qvel in states:
        ours = made(qpos, qvel)
        with monkeypatch.context() as m:
            m.setattr(mjcf.load_mujoco(), "mj_fwdPosition", mujoco.mj_forward)
            whole = made(qpos, qvel)
        assert ours == whole
        compared += not isinstance(ours, str)
    assert compared >= 5


WALKER = MODELS / "dm_control" / "walker.xml"


def test_dm_controls_walker_standing_on_its_feet_is_struck_at_them(tmp_path: Path) -> None:
    """dm_control's planar walker (tests/models/dm_control/walker.xml, unchanged) in its
    reference pose stands on its two feet at a distance of round-off (2e-17 m) from the
    floor, and its margins are 0, so MuJoCo reports no contact there; ``carnot from-mjcf``
    finds the four contacts within its gap (each foot's capsule ends) from a copy of the
    model with its margins raised to the gap. Dropped at 1 m/s, plastic, sticking: the
    answer is Gauss's least constraint with every contact closed, computed apart from MuJoCo's
    ``M`` and point Jacobians (``u'' = u' - M^-1 J^T (J M^-1 J^T)^+ J u'``), here every
    velocity zero: the floor's impulses sum to the walker's momentum and E_d is all its
    kinetic energy. The model handed in as an ``MjModel`` keeps MuJoCo's own contacts."""
    qvel = [-1.0] + [0.0] * 8  # rootz first
    out = tmp_path / "walker.toml"
    assert main(["from-mjcf", str(WALKER), "--qvel", *map(str, qvel), "-o", str(out)]) == 0
    problem = parse_system_scenario(tomllib.loads(out.read_text()))
    assert sorted(c.where for c in problem.contacts) == [f"contacts[{k}]" for k in range(4)]
    result = solve_impact(problem)
    model = mujoco.MjModel.from_xml_path(str(WALKER))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert data.ncon == 0  # MuJoCo's own margins leave the standing feet out
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    rows = []
    for c in problem.contacts:  # each contact's three rows at its point on its foot
        body = model.geom_bodyid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM,
                                                   c.name.split("/")[0])]  # fmt: skip
        jac = np.zeros((3, model.nv))
        mujoco.mj_jac(model, data, jac, None, np.asarray(c.point, dtype=float), body)
        rows.append(jac)
    j = np.vstack(rows)
    u = np.array(qvel)
    m_inv = np.linalg.inv(mass)
    expected = u - m_inv @ j.T @ np.linalg.pinv(j @ m_inv @ j.T, rcond=1e-12) @ j @ u
    assert np.allclose(result.system.velocity_after, expected, rtol=0, atol=1e-12)
    assert np.abs(expected).max() < 1e-12
    total = float(np.sum(model.body_mass))
    assert sum(c.normal_impulse for c in result.contacts) == pytest.approx(total, rel=1e-12)
    assert result.energy.dissipated == pytest.approx(0.5 * u @ mass @ u, rel=1e-12)
    assert result.energy.dissipated_theorem == pytest.approx(result.energy.dissipated, rel=1e-12)
    with pytest.raises(InputError, match="no approaching contact"):
        mjcf_problem(model, qvel=qvel)


def test_from_mjcf_refuses_a_gap_that_is_not_a_distance(capsys) -> None:  # type: ignore[no-untyped-def]
    for bad in ("-1", "nan"):
        assert main(["from-mjcf", str(WALKER), "--qvel", "-1", *["0"] * 8, "--gap", bad]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "gap: must be a finite distance >= 0 (m)" in err, err

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
from pathlib import Path

import mujoco  # noqa: F401  (the extra is in requirements.lock: these tests must run)
import numpy as np
import pytest

from carnot import InputError, solve_impact
from carnot.cli import main
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

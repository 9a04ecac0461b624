"""Systems in motion from MJCF (carnot.hybrid.mjcf, DESIGN.md section 10): MuJoCo's own M and
bias forces, checked against the closed form of the planar two-link arm; the flow's energy
and the ledger; a strike against ``carnot from-mjcf`` at the same state and the closed form
of a single frictionless contact; the geom pairs against MuJoCo's own collision; bad input.

The arm (tests/models/two_link_arm.xml): hinges about y, so that ``q`` positive turns a link
from +x down towards -z; link k has mass m_k, centre of mass c_k from its joint, inertia I_k
about y at its centre of mass, length l_1 (the elbow) and l_2 (the tip ball, massless).

    M11 = I1 + I2 + m1 c1^2 + m2 (l1^2 + c2^2 + 2 l1 c2 cos q2)
    M12 = I2 + m2 (c2^2 + l1 c2 cos q2),       M22 = I2 + m2 c2^2
    h1  = -m2 l1 c2 sin q2 (2 q1' q2' + q2'^2) - g (m1 c1 cos q1 + m2 (l1 cos q1 + c2 cos(q1 + q2)))
    h2  =  m2 l1 c2 sin q2 q1'^2 - g m2 c2 cos(q1 + q2)
    V   =  g (m1 (z0 - c1 sin q1) + m2 (z0 - l1 sin q1 - c2 sin(q1 + q2)))

(Spong, Hutchinson and Vidyasagar, *Robot Modeling and Control*, 2006, section 7.4, with the
angles measured downwards.) A frictionless strike of the tip on the table (normal +z) with
restitution e, ``j = d z_tip / d q = -(l1 cos q1 + l2 cos(q1 + q2), l2 cos(q1 + q2))``:

    q'+ = q'- - (1 + e) (j . q'-) M^-1 j / (j M^-1 j)
"""  # noqa: E501

from __future__ import annotations

import copy
import json
import math
import sys
from pathlib import Path

import mujoco  # (the extra is in requirements.lock: these tests must run)
import numpy as np
import pytest

from carnot import InputError, solve_impact
from carnot.cli import main
from carnot.hybrid.mjcf import colliding_pairs, mjcf_model
from carnot.hybrid.simulate import simulate
from carnot.hybrid.strike import Law, strike
from carnot.model.mjcf import mjcf_problem

ROOT = Path(__file__).resolve().parent.parent
ARM = ROOT / "tests" / "models" / "two_link_arm.xml"
EXAMPLE = ROOT / "examples" / "motion" / "arm_strikes_table.xml"
M1, M2, C1, C2, I1, I2, L1, L2, G, Z0 = 1.0, 0.6, 0.25, 0.2, 0.02, 0.01, 0.5, 0.4, 9.81, 1.0


def arm_mass(q: np.ndarray) -> np.ndarray:
    c = math.cos(q[1])
    m12 = I2 + M2 * (C2**2 + L1 * C2 * c)
    return np.array([[I1 + I2 + M1 * C1**2 + M2 * (L1**2 + C2**2 + 2 * L1 * C2 * c), m12],
                     [m12, I2 + M2 * C2**2]])  # fmt: skip


def arm_bias(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    s, c1, c12 = math.sin(q[1]), math.cos(q[0]), math.cos(q[0] + q[1])
    return np.array([
        -M2 * L1 * C2 * s * (2 * qd[0] * qd[1] + qd[1] ** 2)
        - G * (M1 * C1 * c1 + M2 * (L1 * c1 + C2 * c12)),
        M2 * L1 * C2 * s * qd[0] ** 2 - G * M2 * C2 * c12,
    ])  # fmt: skip


def arm_potential(q: np.ndarray) -> float:
    s1, s12 = math.sin(q[0]), math.sin(q[0] + q[1])
    return G * (M1 * (Z0 - C1 * s1) + M2 * (Z0 - L1 * s1 - C2 * s12))


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_mass_and_bias_are_mujocos_own_and_the_closed_form() -> None:
    motion = mjcf_model(ARM)
    mech = motion.model.mechanism
    model = mujoco.MjModel.from_xml_path(str(ARM))  # MuJoCo apart: its own model and data
    data = mujoco.MjData(model)
    rng = np.random.default_rng(34)
    for _ in range(20):
        q, qd = rng.uniform(-math.pi, math.pi, 2), rng.uniform(-5, 5, 2)
        data.qpos[:], data.qvel[:] = q, qd
        mujoco.mj_forward(model, data)
        full = np.zeros((2, 2))
        mujoco.mj_fullM(model, data, full)
        np.testing.assert_allclose(mech.mass(q), full, rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(mech.bias(q, qd), data.qfrc_bias - data.qfrc_passive,
                                   rtol=1e-14, atol=1e-13)  # fmt: skip
        np.testing.assert_allclose(mech.mass(q), arm_mass(q), rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(mech.bias(q, qd), arm_bias(q, qd), rtol=1e-12, atol=1e-12)
        x = np.concatenate([q, qd])
        np.testing.assert_allclose(mech.flow(x)[2:], -np.linalg.solve(arm_mass(q), arm_bias(q, qd)),
                                   rtol=1e-11, atol=1e-11)  # fmt: skip
        # the energy: MuJoCo's potential against the closed form, the kinetic against MuJoCo's
        assert mech.potential(q) == pytest.approx(arm_potential(q), rel=1e-13, abs=1e-13)
        kinetic = motion.model.kinetic(x)
        model_e = copy.copy(model)
        model_e.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
        data_e = mujoco.MjData(model_e)
        data_e.qpos[:], data_e.qvel[:] = q, qd
        mujoco.mj_forward(model_e, data_e)
        assert kinetic == pytest.approx(float(data_e.energy[1]), rel=1e-13)


def test_the_flow_keeps_its_energy_and_the_ledger_closes_across_strikes() -> None:
    motion = mjcf_model(ARM)  # qpos0 at rest: the arm falls from the horizontal
    model = motion.model
    flight = simulate(model, motion.state, 0.3)  # the first strike is at 0.334 s
    assert flight.ended == "duration" and not flight.events
    assert abs(flight.energy["residual"]) < 1e-11 * abs(flight.energy["initial"])
    assert flight.final[0] > 0.5  # it did fall
    run = simulate(model, motion.state, 2.0, Law(restitution=0.5))
    impacts = [e for e in run.events if e.kind == "impact"]
    assert len(impacts) == 5 and run.ended == "duration"
    assert impacts[0].time == pytest.approx(0.3337, abs=1e-4)
    assert abs(run.energy["residual"]) < 1e-11 * abs(run.energy["initial"])
    for e in impacts:  # each strike: the theorem, and the tip on the table
        led = e.strike.result.energy
        assert led.dissipated == pytest.approx(led.dissipated_theorem, rel=1e-10)
        assert abs(model.guards[0].function(e.state)) < 1e-12


def test_a_strike_is_from_mjcfs_and_the_closed_form(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    motion = mjcf_model(ARM, keyframe="strike")
    x = motion.state
    guard = motion.model.guards[0]
    e = 0.5
    ours = strike(motion.model, guard, x, Law(restitution=e))
    # the same route: carnot from-mjcf at that state, written out and solved by carnot solve
    scenario = tmp_path / "strike.toml"
    code, _, _ = run_cli(capsys, "from-mjcf", str(ARM), "--keyframe", "strike",
                         "--restitution", str(e), "-o", str(scenario))  # fmt: skip
    assert code == 0
    code, out, _ = run_cli(capsys, "solve", str(scenario), "--json")
    assert code == 0
    theirs = np.array(json.loads(out)["system"]["velocity"])
    np.testing.assert_allclose(ours.x_after[2:], theirs, rtol=1e-14, atol=1e-14)
    direct = solve_impact(mjcf_problem(ARM, keyframe="strike", restitution=e))
    assert ours.result.energy.dissipated == pytest.approx(direct.energy.dissipated, rel=1e-14)
    # the closed form of one frictionless contact
    q, qd = x[:2], x[2:]
    j = -np.array([L1 * math.cos(q[0]) + L2 * math.cos(q[0] + q[1]), L2 * math.cos(q[0] + q[1])])
    minv_j = np.linalg.solve(arm_mass(q), j)
    closed = qd - (1 + e) * (j @ qd) * minv_j / (j @ minv_j)
    np.testing.assert_allclose(ours.x_after[2:], closed, rtol=1e-12)
    np.testing.assert_allclose(ours.x_after[:2], q, rtol=0, atol=0)
    # the guard's gradient (central differences of MuJoCo's distance) is the contact's row
    np.testing.assert_allclose(guard.gradient(x)[:2], j, rtol=1e-8)
    assert ours.flags == ()


def test_a_contact_that_stays_closed_is_held_in_the_flow(capsys: pytest.CaptureFixture[str]
                                                         ) -> None:  # fmt: skip
    """The plastic strike leaves the tip on the table: it is held there (frictionless: its
    normal row only) until the table's force falls to zero, the arm swinging on; the tip
    flies, strikes again and is held again. While held, the tip's gap stays zero."""
    code, out, _ = run_cli(capsys, "simulate", str(ARM), "--keyframe", "strike",
                           "--duration", "1", "--json")  # fmt: skip
    d = json.loads(out)
    assert code == 0 and d["ended"] == "duration"
    assert [ev["kind"] for ev in d["events"]] == ["impact", "contact_start", "contact_end",
                                                  "impact", "contact_start"]  # fmt: skip
    assert all(ev.get("contacts") == ["tip/table"] for ev in d["events"][1:3])
    motion = mjcf_model(ARM, keyframe="strike")
    guard = motion.model.guards[0]
    released = d["events"][2]
    x = np.concatenate([released["system"]["q"], released["system"]["qdot"]])
    assert abs(guard.function(x)) < 1e-11  # held on the table up to its release
    assert abs(d["energy"]["residual"]) < 1e-11 * d["energy"]["initial"]


def test_the_example_strikes_the_table_and_the_elbow_stop(capsys: pytest.CaptureFixture[str]
                                                          ) -> None:  # fmt: skip
    code, out, _ = run_cli(capsys, "simulate", str(EXAMPLE), "--keyframe", "swing",
                           "--duration", "3", "--restitution", "0", "--json", "--saltation")
    d = json.loads(out)
    assert code == 0 and d["ended"] == "duration"
    guards = [ev.get("guard") for ev in d["events"]]
    # the tip held on the table, the elbow strikes its stop with the tip taking part, and the
    # arm rests on both (no saltation matrix through a held contact's strike)
    assert guards == ["elbow lower stop", "tip/table", None, "elbow lower stop", None]
    assert all(len(ev["saltation"]) == 4 for ev in d["events"][:2])
    assert [c["name"] for c in d["events"][3]["contacts"]] == ["tip/table", "limit elbow"]
    assert np.allclose(d["final"]["system"]["qdot"], 0.0, atol=1e-12)
    assert abs(d["energy"]["residual"]) < 1e-11 * d["energy"]["initial"]
    # the elbow stop: one frictionless row on the coordinates (the joint-impact closed form)
    motion = mjcf_model(EXAMPLE, keyframe="swing")
    stop = next(g for g in motion.model.guards if g.name == "elbow lower stop")
    event = d["events"][0]
    q, qd = np.array(event["system"]["q_before"]), np.array(event["system"]["qdot_before"])
    n = np.array([0.0, 1.0])  # g = q2 - lo >= 0
    minv_n = np.linalg.solve(arm_mass(q), n)
    closed = qd - (n @ qd) * minv_n / (n @ minv_n)
    np.testing.assert_allclose(event["system"]["qdot"], closed, rtol=1e-12, atol=1e-13)
    assert stop.function(np.concatenate([q, qd])) == pytest.approx(0.0, abs=1e-12)
    # the file's own restitution (its custom numeric) when the command gives none
    assert motion.law.restitution == 0.6


def test_the_pairs_are_those_mujoco_collides() -> None:
    xml = """<mujoco><worldbody><geom name="floor" type="plane" size="5 5 .1"/>
      <body name="a" pos="0 0 1"><joint type="slide" axis="0 0 1"/>
        <geom name="ga" type="sphere" size=".1"/>
        <body name="b" pos=".5 0 0"><joint type="hinge" axis="0 1 0"/>
          <geom name="gb" type="sphere" size=".1"/>
          <body name="c" pos=".5 0 0"><joint type="hinge" axis="0 1 0"/>
            <geom name="gc" type="sphere" size=".1"/>
            <body name="w" pos=".5 0 0"><geom name="gw" type="sphere" size=".1"/></body>
          </body></body></body>
      <body name="d" pos="2 0 1"><joint type="slide" axis="1 0 0"/>
        <geom name="gd" type="capsule" size=".1 .2" contype="2" conaffinity="2"/></body>
      </worldbody>
      <contact><exclude body1="c" body2="a"/><pair geom1="gd" geom2="floor"/></contact>
    </mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    ours = colliding_pairs(mujoco, model)
    wide = copy.copy(model)  # MuJoCo's own collision, every margin wide enough to see them all
    wide.geom_margin[:] = 50.0
    wide.pair_margin[:] = 50.0
    data = mujoco.MjData(wide)
    mujoco.mj_forward(wide, data)
    theirs = sorted({(int(min(g)), int(max(g))) for g in data.contact.geom})
    assert list(ours) == theirs
    assert (1, 3) not in ours and (2, 3) not in ours and (0, 5) in ours  # exclude, parent, pair


def _write(tmp_path: Path, body: str) -> str:
    path = tmp_path / "bad.xml"
    path.write_text(f"<mujoco><worldbody>{body}</worldbody></mujoco>")
    return str(path)


@pytest.mark.parametrize(("body", "args", "words"), [
    ('<body pos="0 0 1"><joint name="swing" type="hinge" axis="0 1 0"/>'
     '<geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02"/></body>', ("--duration", "1"),
     "has nothing to strike"),
    ('<geom type="plane" size="1 1 .1"/><body pos="0 0 0.05"><joint type="slide" axis="0 0 1"/>'
     '<geom type="sphere" size="0.1"/></body>', ("--duration", "1"), "overlapping by 0.05 m"),
    ('<geom type="plane" size="1 1 .1"/><body pos="0 0 1"><joint type="slide" axis="0 0 1"/>'
     '<geom type="sphere" size="0.1"/></body>', (), "--duration: is required"),
    ('<geom type="plane" size="1 1 .1"/><body pos="0 0 1"><joint type="slide" axis="0 0 1"/>'
     '<geom type="sphere" size="0.1"/></body>', ("--duration", "1", "--keyframe", "up"),
     "keyframe: unknown keyframe"),
    ('<geom type="plane" size="1 1 .1"/><body pos="0 0 1"><joint type="slide" axis="0 0 1"/>'
     '<geom type="sphere" size="0.1"/></body>', ("--duration", "1", "--restitution", "2"),
     "--restitution: must be in [0, 1]"),
])  # fmt: skip
def test_bad_mjcf_input_exits_2_with_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                              body: str, args: tuple[str, ...], words: str) -> None:
    code, out, err = run_cli(capsys, "simulate", _write(tmp_path, body), *args)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert words in err


def test_mjcf_options_on_a_scenario_file_are_refused(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "simulate", "examples/motion/rimless_wheel.toml",
                             "--keyframe", "0")  # fmt: skip
    assert code == 2 and "--keyframe: is for an MJCF model" in err


def test_a_ball_dropped_on_a_slide_bounces_as_newton_says(tmp_path: Path) -> None:
    """A ball on a vertical slide dropped from h onto a plane: strikes at sqrt(2 h / g), then
    every 2 e^k sqrt(2 h / g); each takes (1 - e^2) of the kinetic energy. (condim 1: with
    friction, a contact whose tangential rows are both zero makes solve_impact's sticking
    ratio singular, by from-mjcf's route too.)"""
    path = _write(tmp_path, '<geom type="plane" size="1 1 .1" condim="1"/><body pos="0 0 1.1">'
                  '<joint type="slide" axis="0 0 1"/>'
                  '<geom type="sphere" size="0.1" mass="2" condim="1"/></body>')  # fmt: skip
    motion = mjcf_model(path, restitution=0.8)
    run = simulate(motion.model, motion.state, 1.5, motion.law)
    t0 = math.sqrt(2 * 1.0 / 9.81)
    times = [e.time for e in run.events]
    expected = [t0 + 2 * t0 * sum(0.8**k for k in range(1, i + 1)) for i in range(len(times))]
    assert len(times) >= 2
    np.testing.assert_allclose(times, expected, rtol=1e-11)
    first = run.events[0].strike.result.energy
    assert first.dissipated == pytest.approx((1 - 0.8**2) * 2 * 9.81 * 1.0, rel=1e-11)


def test_without_the_extra_simulate_says_how_to_install_it(monkeypatch: pytest.MonkeyPatch,
                                                           capsys: pytest.CaptureFixture[str]
                                                           ) -> None:  # fmt: skip
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco now raises ImportError
    code, out, err = run_cli(capsys, "simulate", str(ARM), "--duration", "1")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert 'pip install "carnot[mujoco]"' in err


@pytest.mark.parametrize("friction", [0.0, 0.3])
def test_dry_joint_friction_is_said_to_be_left_out(tmp_path: Path, friction: float) -> None:
    """MuJoCo's dry joint friction (``frictionloss``, a constraint of its solver, as in
    dm_control's finger) is not in carnot's flow: a model that has some says so in its notes
    (the motion and the ledger are without it), one that has none does not."""
    path = _write(tmp_path, '<geom type="plane" size="1 1 .1"/><body pos="0 0 1">'
                  f'<joint type="slide" axis="0 0 1" frictionloss="{friction}"/>'
                  '<geom type="sphere" size="0.1"/></body>')  # fmt: skip
    notes = mjcf_model(path).model.notes
    assert ("frictionloss" in notes) == (friction > 0), notes


_CART = """<mujoco><option>{flags}</option><worldbody>
  <geom name="rail" type="capsule" pos="0 .07 1" zaxis="1 0 0" size="0.02 2"/>
  <body name="cart" pos="0 0 1">
    <joint name="slider" type="slide" axis="1 0 0" limited="true" range="-1 1"/>
    <geom name="cart" type="box" size="0.2 0.15 0.1" mass="2"/>
  </body></worldbody>
  <equality><joint joint1="slider" active="{active}"/></equality>
  <keyframe><key name="push" qpos="0.5" qvel="2"/></keyframe></mujoco>"""


def test_the_models_flags_turn_contacts_limits_and_equalities_off(tmp_path: Path) -> None:
    """MuJoCo's ``<flag contact="disable"/>`` (dm_control's cart-pole, whose cart overlaps its
    rails) leaves no geom pair to strike, ``equality="disable"`` no equality to refuse, and
    ``limit="disable"`` no stop: as MuJoCo moves the model. The cart then strikes its
    slider's stop plastically (e = 0): E_d = m v^2 / 2 at t = (1 - 0.5) / v."""
    path = tmp_path / "cart.xml"
    path.write_text(_CART.format(flags='<flag contact="disable" equality="disable"/>',
                                 active="true"))  # fmt: skip
    run = simulate_file(str(path), "push", 1.0)
    impacts = [e for e in run.events if e.kind == "impact"]
    assert impacts[0].strike is not None and impacts[0].strike.guard.name == "slider upper stop"
    assert impacts[0].time == pytest.approx(0.25, rel=1e-12)
    energy = impacts[0].strike.result.energy
    assert energy.dissipated == pytest.approx(0.5 * 2.0 * 2.0**2, rel=1e-12)
    assert energy.dissipated_theorem == pytest.approx(energy.dissipated, rel=1e-12)
    path.write_text(_CART.format(flags="", active="false"))  # contacts on: the cart overlaps
    with pytest.raises(InputError, match="overlapping"):
        simulate_file(str(path), "push", 1.0)
    path.write_text(_CART.format(flags='<flag contact="disable"/>', active="true"))
    with pytest.raises(InputError, match="is not held in motion yet"):
        simulate_file(str(path), "push", 1.0)
    path.write_text(_CART.format(flags='<flag contact="disable" limit="disable"/>',
                                 active="false"))  # fmt: skip
    with pytest.raises(InputError, match="has nothing to strike"):
        simulate_file(str(path), "push", 1.0)


def simulate_file(path: str, keyframe: str, duration: float):  # type: ignore[no-untyped-def]
    """``carnot simulate path --keyframe K --duration T``'s run (carnot.hybrid)."""
    motion = mjcf_model(path, keyframe=keyframe)
    return simulate(motion.model, motion.state, duration, motion.law)

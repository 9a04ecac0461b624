"""Systems in motion from MJCF with free and ball joints (``nq != nv``; carnot.hybrid.mjcf):
the quaternions' rates against MuJoCo's own integrator, a free sphere dropped on a plane
against the closed form, a free box striking on a corner against carnot's own free-body
simulator (a route that shares nothing with MuJoCo's), a spherical pendulum's invariants, a
hinge's stop on a free base against the joint-impact closed form, the Go2's landing with
its dampers in the ledger, the example of docs/motion.md, and the refusals of what is not
built for them yet (their saltation matrices: tests/test_hybrid_mjcf_saltation.py).

MuJoCo's conventions (its documentation, "Computation": ``qpos`` of a free joint is the
body's position and unit quaternion ``[w, x, y, z]``, ``qvel`` its linear velocity in world
axes and its angular velocity in the body's axes; a ball joint's ``qvel`` is its angular
velocity in the child body's axes) are checked here numerically, not assumed:
``mj_integratePos(q, v, h)`` moves ``q`` along ``v`` for a time ``h``, so
``(integratePos(q, v, h) - integratePos(q, v, -h)) / 2h -> q'`` as ``h -> 0`` (central
differences: their error is ``O(h^2)``).

A ball dropped from rest, its bottom ``h`` above a plane, with restitution ``e`` under
gravity ``g`` (Newton's law of restitution; e.g. Stronge, *Impact Mechanics*, 2000): the
first strike at ``t1 = sqrt(2 h / g)``, approached at ``v1 = g t1``; the k-th rebound
leaves at ``e^k v1`` and flies ``2 e^k v1 / g``; each strike takes ``(1 - e^2)`` of the
kinetic energy it meets. A sphere's spin about its centre is constant in flight (its inertia
is isotropic) and, frictionless, through each strike: its orientation is
``q(t) = q0 (x) exp(w t / 2)`` (body axes).

A spherical pendulum (a ball joint at a fixed pivot) keeps its energy and its angular
momentum about the vertical, ``L_z`` (gravity's torque about the pivot is horizontal: the
Lagrangian does not change under a turn about the vertical; e.g. Goldstein, *Classical
Mechanics*, 3rd ed., 2002, on the spherical pendulum). With a ball joint at the world,
MuJoCo's ``M v`` is that momentum in the body's axes: ``L = R(q) M v``.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path

import mujoco  # (the extra is in requirements.lock: these tests must run)
import numpy as np
import pytest

from carnot.cli import main
from carnot.errors import InputError
from carnot.hybrid.cycle import find_cycle
from carnot.hybrid.mjcf import cone_angle, mjcf_model, quaternion_rate
from carnot.hybrid.simulate import simulate

ROOT = Path(__file__).resolve().parent.parent
SPHERE = ROOT / "tests" / "models" / "free_sphere_drop.xml"
BOX = ROOT / "tests" / "models" / "free_box_corner.xml"
PENDULUM = ROOT / "tests" / "models" / "ball_pendulum.xml"
FLAP = ROOT / "tests" / "models" / "free_base_flap.xml"
G = 9.81


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def quat_exp(q0: np.ndarray, w: np.ndarray, t: float) -> np.ndarray:
    """``q0 (x) exp(w t / 2)``: ``q0`` turned at the constant body-axes rate ``w`` for ``t``."""
    angle = float(np.linalg.norm(w)) * t
    axis = w / np.linalg.norm(w)
    turn = np.array([math.cos(angle / 2), *(math.sin(angle / 2) * axis)])
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, q0, turn)
    return out


def rotation(q: np.ndarray) -> np.ndarray:
    """The rotation matrix (body axes to world) of the unit quaternion ``q``."""
    out = np.zeros(9)
    mujoco.mju_quat2Mat(out, q / np.linalg.norm(q))
    return out.reshape(3, 3)


def test_the_position_rate_is_mujocos_integrate_pos(tmp_path: Path) -> None:
    """A hinge, a free joint and a ball joint in one model, at random states: the flow's
    ``q'`` against MuJoCo's own integrator, and the rate with the body-axes angular velocity
    taken for world axes (the wrong frame) far off, so that the check can tell them apart."""
    xml = """<mujoco><worldbody><geom type="plane" size="1 1 .1"/>
      <body pos="0 0 1"><freejoint/><geom type="box" size=".1 .2 .3" mass="2"/>
        <body pos="0 0 -.5"><joint type="ball"/><geom type="capsule" fromto="0 0 0 .3 .1 -.4"
          size=".05"/>
          <body pos=".3 .1 -.4"><joint type="hinge" axis="0 1 0"/><geom size=".05"/></body>
        </body></body></worldbody></mujoco>"""
    path = tmp_path / "rate_check.xml"
    model = mujoco.MjModel.from_xml_string(xml)
    assert (model.nq, model.nv) == (12, 10)
    path.write_text(xml)
    mech = mjcf_model(path).model.mechanism
    rng = np.random.default_rng(34)
    for _ in range(10):
        q = np.array(model.qpos0)
        q[3:7], q[7:11], q[11] = rng.normal(size=4), rng.normal(size=4), rng.normal()
        q[3:7] /= np.linalg.norm(q[3:7])
        q[7:11] /= np.linalg.norm(q[7:11])
        v = rng.normal(size=model.nv)
        ours = mech.position_rate(q, v)
        h = 1e-5
        up, down = q.copy(), q.copy()
        mujoco.mj_integratePos(model, up, v, h)
        mujoco.mj_integratePos(model, down, v, -h)
        np.testing.assert_allclose(ours, (up - down) / (2 * h), rtol=0, atol=1e-9)
        # the forward difference converges to it as h -> 0, linearly
        errors = []
        for step in (1e-3, 1e-4, 1e-5):
            ahead = q.copy()
            mujoco.mj_integratePos(model, ahead, v, step)
            errors.append(float(np.max(np.abs((ahead - q) / step - ours))))
        assert errors[2] < 2e-5 and errors[1] / errors[2] > 5 and errors[0] / errors[1] > 5
        # the wrong frame: 1/2 (0, w) (x) q, the same numbers w read as world axes (the
        # right rate in world axes is 1/2 (0, R w) (x) q = 1/2 q (x) (0, w))
        wrong = np.zeros(4)
        mujoco.mju_mulQuat(wrong, np.array([0.0, *v[3:6]]), q[3:7])
        assert np.max(np.abs(0.5 * wrong - ours[3:7])) > 1e-3
    # the hinge's rate is its velocity, bit for bit
    assert ours[11] == v[9]


def test_a_free_sphere_dropped_bounces_as_the_closed_form(capsys: pytest.CaptureFixture[str]
                                                          ) -> None:  # fmt: skip
    code, out, _ = run_cli(capsys, "simulate", str(SPHERE), "--duration", "1.3", "--json")
    d = json.loads(out)
    assert code == 0 and d["ended"] == "duration"
    e, h = 0.5, 1.0  # the file's carnot_restitution; the bottom 1 m up
    t1 = math.sqrt(2 * h / G)
    v1 = G * t1
    impacts = [ev for ev in d["events"] if ev["kind"] == "impact"]
    assert len(impacts) == 5  # at 0.45, 0.90, 1.13, 1.24, 1.30 s
    times = [t1 + sum(2 * e**k * v1 / G for k in range(1, i + 1)) for i in range(5)]
    np.testing.assert_allclose([ev["time"] for ev in impacts], times, rtol=1e-12)
    for k, ev in enumerate(impacts):
        before, after = ev["system"]["qdot_before"], ev["system"]["qdot"]
        assert len(ev["system"]["q"]) == 7 and len(after) == 6
        assert before[2] == pytest.approx(-(e**k) * v1, rel=1e-11)
        assert after[2] == pytest.approx(e ** (k + 1) * v1, rel=1e-11)
        assert ev["system"]["q"] == ev["system"]["q_before"]  # the strike moves no position
        assert ev["energy"]["dissipated"] == pytest.approx(
            (1 - e**2) * 0.5 * 2.0 * (e**k * v1) ** 2, rel=1e-11)  # fmt: skip
    energy = d["energy"]
    assert abs(energy["residual"]) < 1e-12 * energy["initial"]
    assert d["model"]["coordinates"][:4] == ["ball.x", "ball.y", "ball.z", "ball.qw"]


def test_a_thrown_spinning_sphere_keeps_its_spin_and_its_quaternion_turns() -> None:
    motion = mjcf_model(SPHERE, keyframe="thrown")
    run = simulate(motion.model, motion.state, 1.3, motion.law)
    assert run.ended == "duration" and len(run.events) == 5
    q0, v0 = motion.state[:7], motion.state[7:]
    t1 = math.sqrt(2.0 / G)
    assert run.events[0].time == pytest.approx(t1, rel=1e-12)
    for ev in run.events:  # frictionless: the slide and the spin go on through each strike
        q, v = ev.state[:7], ev.state[7:]
        np.testing.assert_allclose(v[[0, 1, 3, 4, 5]], v0[[0, 1, 3, 4, 5]], rtol=1e-12)
        np.testing.assert_allclose(q[:2], v0[:2] * ev.time, rtol=1e-10)
        np.testing.assert_allclose(q[3:], quat_exp(q0[3:], v0[3:], ev.time), atol=1e-10)
        assert abs(np.linalg.norm(q[3:]) - 1) < 1e-11
    assert abs(run.energy["residual"]) < 1e-12 * run.energy["initial"]


def _free_body_scenario(path: Path, motion_state: np.ndarray, duration: float) -> str:
    """The box of free_box_corner.xml as a free-body scenario (DESIGN.md section 8):
    the same mass and edges (carnot's solid-box inertia), state (the angular velocity in
    world axes, ``R w_body``), gravity along -z, the plane z = 0, e = 0.5, frictionless."""
    q, v = motion_state[:7], motion_state[7:]
    w = rotation(q[3:]) @ v[3:]

    def vec(a: np.ndarray) -> str:
        return "[" + ", ".join(repr(float(x)) for x in a) + "]"

    path.write_text(f"""format = 1
[simulation]
duration = {duration}
gravity = [0.0, 0.0, -9.81]
[bodies.box]
mass = 1.5
shape = "box"
size = [0.4, 0.2, 0.1]
position = {vec(q[:3])}
orientation = {vec(q[3:])}
velocity = {vec(v[:3])}
angular_velocity = {vec(w)}
[bodies.floor]
fixed = true
plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}
[[pairs]]
a = "box"
b = "floor"
restitution = 0.5
friction = 0.0
""")
    return str(path)


def test_a_spinning_box_strikes_on_its_corners_as_the_free_body_simulator(tmp_path: Path
                                                                          ) -> None:  # fmt: skip
    """Four corner strikes in 0.4 s: their times and the velocities after each, from MuJoCo's
    M and contacts against carnot's own free-body simulator (its flight, its gaps, its
    impact), with MuJoCo's inertia checked against the solid box's first."""
    motion = mjcf_model(BOX, keyframe="spin")
    model = mujoco.MjModel.from_xml_path(str(BOX))
    a, b, c = 0.4, 0.2, 0.1
    np.testing.assert_allclose(model.body_inertia[1],
                               [1.5 * (b * b + c * c) / 12, 1.5 * (a * a + c * c) / 12,
                                1.5 * (a * a + b * b) / 12], rtol=1e-12)  # fmt: skip
    duration = 0.4
    run = simulate(motion.model, motion.state, duration, motion.law)
    ours = [e for e in run.events if e.kind == "impact"]
    assert len(ours) == 4 and run.ended == "duration"
    assert abs(run.energy["residual"]) < 1e-9 * run.energy["initial"]
    for e in ours:  # each a strike of one corner: one contact
        assert len(e.strike.result.contacts) == 1
    scenario = _free_body_scenario(tmp_path / "box.toml", motion.state, duration)
    with contextlib.redirect_stdout(io.StringIO()) as buf:
        assert main(["simulate", scenario, "--json"]) == 0
    theirs = [ev for ev in json.loads(buf.getvalue())["events"] if ev["kind"] == "impact"]
    assert len(theirs) == 4
    for e, ev in zip(ours, theirs, strict=True):
        assert e.time == pytest.approx(ev["time"], abs=1e-10)
        box = ev["bodies"]["box"]
        q, v = e.state[:7], e.state[7:]
        np.testing.assert_allclose(v[:3], box["velocity"], rtol=0, atol=1e-8)
        np.testing.assert_allclose(rotation(q[3:]) @ v[3:], box["angular_velocity"], rtol=0,
                                   atol=1e-8)  # fmt: skip


def test_a_spherical_pendulum_keeps_its_energy_and_its_vertical_momentum() -> None:
    motion = mjcf_model(PENDULUM, keyframe="swirl")
    mech = motion.model.mechanism
    assert (mech.nq, mech.n) == (4, 3)

    def l_z(x: np.ndarray) -> float:
        return float((rotation(x[:4]) @ (mech.mass(x[:4]) @ x[4:]))[2])

    run = simulate(motion.model, motion.state, 3.0, motion.law)
    assert run.ended == "duration" and not run.events  # the bob never reaches the floor
    assert abs(run.energy["residual"]) < 1e-10 * run.energy["initial"]
    assert l_z(run.final) == pytest.approx(l_z(motion.state), rel=1e-10)
    assert abs(np.linalg.norm(run.final[:4]) - 1) < 1e-11
    assert abs(run.final[0] - motion.state[0]) > 1e-2  # it did swing
    # the flow's quaternion rate is mj_integratePos's, at the pendulum's own state
    x = run.final
    up, down = np.array(x[:4]), np.array(x[:4])
    mujoco.mj_integratePos(mech.model, up, x[4:], 1e-5)
    mujoco.mj_integratePos(mech.model, down, x[4:], -1e-5)
    np.testing.assert_allclose(mech.flow(x)[:4], (up - down) / 2e-5, rtol=0, atol=1e-9)
    np.testing.assert_allclose(mech.flow(x)[:4], quaternion_rate(x[:4], x[4:]), rtol=1e-15)


def test_periodic_orbits_are_refused_in_one_line_and_saltation_is_built(
        capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    code, out, err = run_cli(capsys, "cycle", str(SPHERE))
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert "free joint 'ball'" in err and "not supported yet" in err
    assert "saltation" not in err  # (built: tests/test_hybrid_mjcf_saltation.py)
    code, out, err = run_cli(capsys, "cycle", str(PENDULUM))
    assert code == 2 and "ball joint 'pivot'" in err and "not supported yet" in err
    motion = mjcf_model(SPHERE)
    with pytest.raises(InputError, match="periodic orbits are not supported yet"):
        find_cycle(motion.model, motion.state, motion.law)
    # --saltation: each strike's matrix in the tangent chart, 2 nv = 12 numbers a side
    run = simulate(motion.model, motion.state, 1.0, motion.law, saltation=True)
    impacts = [e for e in run.events if e.kind == "impact"]
    assert impacts and all(e.saltation is not None and e.saltation.shape == (12, 12)
                           for e in impacts)  # fmt: skip
    code, out, err = run_cli(capsys, "simulate", str(PENDULUM), "--keyframe", "swirl",
                             "--duration", "1", "--saltation")  # fmt: skip
    assert code == 0 and err == ""
    # a hinge model's MJCF file is cycled (tests/test_hybrid_mjcf_cycle.py): the arm at rest
    # horizontal falls for longer than --max-period, and no orbit is found, said so
    code, out, err = run_cli(capsys, "cycle", str(ROOT / "tests" / "models" / "two_link_arm.xml"),
                             "--max-period", "0.01")  # fmt: skip
    assert code == 0 and err == "" and "no periodic orbit found" in out and "no_return" in out


def test_a_free_joint_resting_on_the_plane_is_held_there(tmp_path: Path) -> None:
    """The sphere laid on the frictionless plane at rest: pressed by gravity, its contact is
    held from the start (its normal row only, condim 1), and it stays at rest."""
    xml = SPHERE.read_text().replace('pos="0 0 1.1"', 'pos="0 0 0.1"')
    path = tmp_path / "resting.xml"
    path.write_text(xml)
    motion = mjcf_model(path)
    run = simulate(motion.model, motion.state, 1.0, motion.law)
    assert run.ended == "duration" and [e.kind for e in run.events] == ["contact_start"]
    assert run.events[0].flags == ("ball/floor",)
    np.testing.assert_allclose(run.final, motion.state, rtol=0, atol=1e-13)
    # M of a free sphere: diag(m, m, m, I, I, I), I = 2/5 m R^2
    i = 0.4 * 2.0 * 0.1**2
    np.testing.assert_allclose(motion.model.mechanism.mass(motion.state[:7]),
                               np.diag([2.0, 2.0, 2.0, i, i, i]), rtol=1e-12, atol=1e-15)


def test_the_example_box_strikes_the_table_corner_by_corner(capsys: pytest.CaptureFixture[str]
                                                            ) -> None:  # fmt: skip
    """examples/motion/box_drops_on_table.xml as docs/motion.md shows it: four corner strikes
    in 0.3 s, at the times the page prints; run for 1 s, its corners' chatter closes and it
    is held on one corner (0.4875 s), then an edge, then flat on its four corners (0.6933
    s), where it slides on over the frictionless table, spinning about the vertical; the
    ledger closed."""
    example = str(ROOT / "examples" / "motion" / "box_drops_on_table.xml")
    code, out, _ = run_cli(capsys, "simulate", example, "--keyframe", "tilted",
                           "--duration", "0.3", "--json")  # fmt: skip
    d = json.loads(out)
    assert code == 0 and d["ended"] == "duration"
    np.testing.assert_allclose([ev["time"] for ev in d["events"]],
                               [0.262798315525, 0.277449834999, 0.291030890932, 0.299536188282],
                               rtol=0, atol=1e-11)  # fmt: skip
    assert abs(d["energy"]["residual"]) < 1e-12 * d["energy"]["initial"]
    motion = mjcf_model(example, keyframe="tilted")
    assert motion.law.restitution == 0.4 and motion.quaternion_joints == ("free joint 'box'",)
    run = simulate(motion.model, motion.state, 1.0, motion.law)
    assert run.ended == "duration" and len(run.events) > 20
    starts = [e for e in run.events if e.kind == "contact_start"]
    assert [e.held[0].points for e in starts] == [1, 2, 4]
    assert starts[0].time == pytest.approx(0.4875, abs=1e-4)
    assert starts[-1].time == pytest.approx(0.6933, abs=1e-4)
    flat = starts[-1].state
    # flat on the table (frictionless): no vertical speed, no tilting, and the horizontal
    # velocity and the spin about the vertical those it was held with
    assert run.final[2] == pytest.approx(flat[2], abs=1e-12)
    np.testing.assert_allclose(run.final[7:], flat[7:], rtol=0, atol=1e-10)
    assert abs(flat[9]) < 1e-12 and abs(flat[10]) < 1e-10 and abs(flat[11]) < 1e-10
    assert abs(run.energy["residual"]) < 1e-12 * run.energy["initial"]


def test_the_go2_lands_on_its_front_feet_and_its_dampers_are_in_the_ledger() -> None:
    """Unitree Go2 (tests/models/go2_drop.xml: a free base, twelve hinges with ranges and
    dampers), dropped nose-down: both front feet strike together at 0.014 s (the audit's
    "touch" keyframe is MuJoCo's own state then, 7 of its steps in), the strike is solved on
    the 18 velocities, and the ledger closes with the joints' dampers' work counted (without
    it the residual would be that work: 1.3e-7 J at the first strike, 0.56 J at the end)."""
    go2 = ROOT / "tests" / "models" / "go2_drop.xml"
    motion = mjcf_model(go2, keyframe="drop")
    assert (motion.model.nq, motion.model.n) == (19, 18)
    run = simulate(motion.model, motion.state, 0.3, motion.law)
    first = run.events[0]
    assert first.kind == "impact" and [c.name for c in first.strike.result.contacts] == [
        "FL/floor", "FR/floor"]  # fmt: skip
    assert first.time == pytest.approx(0.014, abs=2e-5)
    # MuJoCo's semi-implicit Euler (step dt) leaves a fall of N steps g dt t / 2 below the
    # exact one at t = N dt (z_N = z_0 + v_0 t - g dt^2 N (N + 1) / 2): the base's height
    # at the strike against the "touch" keyframe's, 7 steps of 2 ms in
    model = mujoco.MjModel.from_xml_path(str(go2))
    touch = model.key_qpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "touch")]
    dt = float(model.opt.timestep)
    lag = first.strike.x_before[2] - touch[2]
    assert lag == pytest.approx(G * dt * first.time / 2, rel=0.05)
    # the feet are held after their strikes (sticking or sliding, mu = 1); a sliding foot's
    # normal force then grows without bound as its slip turns (Painleve's paradox: its
    # force's coefficient in its own gap's acceleration falls from 1 to 0.46 in 0.3 ms), and
    # the run stops there, flagged, its ledger closed
    assert run.ended == "stop" and run.events[-1].flags[0] == "held_singular"
    assert run.time == pytest.approx(0.0235, abs=2e-4)
    energy = run.energy
    assert 0.1 < energy["dampers"] < 1.0  # (the knees damped as the legs fold: 0.56 J)
    assert abs(energy["residual"]) < 1e-12 * energy["initial"]


def test_a_phase_portrait_of_a_free_joint_is_refused() -> None:
    """``plot_run`` draws each coordinate against its rate: with a quaternion among the
    positions there is no such pair, and it says so rather than drawing the wrong ones."""
    from carnot.hybrid.plot import plot_run

    motion = mjcf_model(SPHERE)
    run = simulate(motion.model, motion.state, 0.1, motion.law)
    with pytest.raises(InputError, match="phase portraits are not supported yet"):
        plot_run(run)


def test_a_hinge_on_a_free_base_strikes_and_holds_its_stop(tmp_path: Path) -> None:
    """tests/models/free_base_flap.xml: a flap hinged to a free-floating base, its hinge's
    position at qpos[7] but its velocity at qvel[6]. The stop is struck where qpos[7] reaches
    the bound, by one frictionless row on the velocities (the joint-impact closed form,
    DESIGN.md section 10's stops):

        v+ = v- - (1 + e) (r . v-) M^-1 r / (r M^-1 r),   r = d g / d qvel = e_6

    and, plastic with the range in degrees (MJCF's default unit: +-0.0087 rad), the flap
    chatters to rest on its stop and is held there by the flow while the stop pushes."""
    motion = mjcf_model(FLAP, keyframe="flap")
    e = motion.law.restitution
    assert e == 0.5
    run = simulate(motion.model, motion.state, 0.5, motion.law)
    first = run.events[0]
    assert first.kind == "impact" and first.strike.guard.name == "hinge lower stop"
    before, after = first.strike.x_before, first.strike.x_after
    assert before[7] == pytest.approx(-0.5, abs=1e-12)  # the hinge's position, not qpos[6]
    mass = motion.model.mechanism.mass(before[:8])
    r = np.zeros(7)
    r[6] = 1.0
    v = before[8:]
    minv_r = np.linalg.solve(mass, r)
    closed = v - (1 + e) * (r @ v) * minv_r / (r @ minv_r)
    np.testing.assert_allclose(after[8:], closed, rtol=1e-12, atol=1e-13)
    np.testing.assert_array_equal(after[:8], before[:8])
    assert abs(run.energy["residual"]) < 1e-12 * run.energy["initial"]
    # plastic, the range in degrees: strikes, then the flap held at a stop
    degrees = tmp_path / "flap_degrees.xml"
    degrees.write_text(FLAP.read_text().replace('<compiler angle="radian"/>', ""))
    motion = mjcf_model(degrees, keyframe="flap", restitution=0.0)
    run = simulate(motion.model, motion.state, 1.0, motion.law)
    assert [ev.kind for ev in run.events] == ["impact", "impact", "contact_start"]
    assert run.ended == "duration" and run.events[2].flags == ("hinge upper stop",)
    assert run.final[7] == pytest.approx(math.radians(0.5), abs=1e-12)  # held there to the end
    assert abs(run.energy["residual"]) < 1e-12 * run.energy["initial"]


CONE = ROOT / "tests" / "models" / "ball_cone.xml"


def test_a_ball_joints_cone_is_mujocos_limit_distance_and_its_gradient() -> None:
    """The cone's gap ``g = r - theta`` is MuJoCo's own ``efc_pos`` of the joint's limit row,
    and that row (``efc_J``) is ``-n``, the rotation's axis, at poses past the cone (where
    MuJoCo instantiates it); the gradient is that of central differences of the gap, with
    no part along the quaternion (the gap sees it normalized)."""
    motion = mjcf_model(CONE)
    guard = next(g for g in motion.model.guards if g.name == "pivot cone")
    model = mujoco.MjModel.from_xml_path(str(CONE))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    for _ in range(5):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        theta = rng.uniform(0.85, 3.0)
        quat = np.array([math.cos(theta / 2), *(math.sin(theta / 2) * axis)])
        data.qpos[:] = quat
        mujoco.mj_forward(model, data)
        assert data.nefc == 1
        x = np.concatenate([quat, np.zeros(3)])
        assert guard.function(x) == pytest.approx(float(data.efc_pos[0]), abs=1e-12)
        rows = guard.rows(x)
        np.testing.assert_allclose(rows.normal, data.efc_J[:3], atol=1e-12)
        scaled = np.concatenate([1.7 * quat, rng.normal(size=3)])  # not unit: normalized
        grad = guard.gradient(scaled)
        assert abs(grad[:4] @ scaled[:4]) < 1e-12
        h = 1e-6
        for j in range(4):
            up, down = scaled.copy(), scaled.copy()
            up[j] += h
            down[j] -= h
            fd = (guard.function(up) - guard.function(down)) / (2 * h)
            assert grad[j] == pytest.approx(fd, abs=1e-8)


def test_a_ball_joint_swinging_in_a_plane_strikes_its_cone_as_a_hinge_its_stop(tmp_path: Path
                                                                            ) -> None:  # fmt: skip
    """The same rod on a hinge about y with the range +-0.8 rad (a second route: the stop's
    constant row on one coordinate, carnot's own strike, no quaternion) swings as the ball
    joint does in the x-z plane: the strikes at the same times, the same rates after."""
    hinge = tmp_path / "hinge.xml"
    hinge.write_text(CONE.read_text()
                     .replace('type="ball" range="0 0.8"',
                              'type="hinge" axis="0 1 0" range="-0.8 0.8"')
                     .replace('qpos="0.968912421710645 0 0.247403959254523 0" qvel="0 5 0"',
                              'qpos="0.5" qvel="5"')
                     .replace('qpos="0.955336489125606 0.295520206661340 0 0" qvel="4 1.5 0"',
                              'qpos="0" qvel="0"'))  # fmt: skip
    ball = mjcf_model(CONE, keyframe="plane", restitution=0.5)
    plain = mjcf_model(hinge, keyframe="plane", restitution=0.5)
    run = simulate(ball.model, ball.state, 1.0, ball.law)
    other = simulate(plain.model, plain.state, 1.0, plain.law)
    assert [ev.kind for ev in run.events] == ["impact", "impact"]
    assert [ev.kind for ev in other.events] == ["impact", "impact"]
    assert run.events[0].strike.guard.name == "pivot cone"
    for a, b in zip(run.events, other.events, strict=True):
        assert a.time == pytest.approx(b.time, abs=1e-10)
        np.testing.assert_allclose(a.strike.x_after[4:], [0.0, b.strike.x_after[1], 0.0],
                                   atol=1e-9)  # fmt: skip
    assert run.events[0].strike.x_after[5] == pytest.approx(
        -0.5 * run.events[0].strike.x_before[5], rel=1e-12)
    assert abs(run.energy["residual"]) < 1e-11 * run.energy["initial"]


@pytest.mark.parametrize("e", [0.5, 0.0])
def test_a_swirling_rod_strikes_its_cone_and_is_held_there(e: float) -> None:
    """Tilted about x, turning about x towards the cone and about y across it: the strike is
    the joint-impact closed form on the cone's row ``r = -n`` (the rotation's axis at the
    strike),

        v+ = v- - (1 + e) (r . v-) M^-1 r / (r M^-1 r),

    and the rod, pressed outwards by its swirl, chatters (e = 0.5) or at once (plastic) comes
    to rest against the cone, where the flow holds it: its angle stays the cone's to the
    integrator's tolerance (the gap's acceleration carries the axis' turning, ``-cot(theta /
    2) |w_perp|^2 / 2``: without it the hold would drift off), and the ledger closes."""
    motion = mjcf_model(CONE, keyframe="cone", restitution=e)
    run = simulate(motion.model, motion.state, 1.0, motion.law)
    first = run.events[0]
    assert first.kind == "impact" and first.strike.guard.name == "pivot cone"
    q, v = first.strike.x_before[:4], first.strike.x_before[4:]
    assert cone_angle(q) == pytest.approx(0.8, abs=1e-12)
    quat = q / np.linalg.norm(q) * (1.0 if q[0] >= 0 else -1.0)
    r = -quat[1:] / np.linalg.norm(quat[1:])
    minv_r = np.linalg.solve(motion.model.mechanism.mass(q), r)
    closed = v - (1 + e) * (r @ v) * minv_r / (r @ minv_r)
    np.testing.assert_allclose(first.strike.x_after[4:], closed, atol=1e-12)
    assert "contact_start" in [ev.kind for ev in run.events]
    if e == 0.0:
        assert [ev.kind for ev in run.events] == ["impact", "contact_start"]
    assert run.ended == "duration"
    assert cone_angle(run.final[:4]) == pytest.approx(0.8, abs=1e-10)
    assert abs(run.energy["residual"]) < 1e-11 * run.energy["initial"]

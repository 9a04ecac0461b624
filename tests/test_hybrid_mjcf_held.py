"""MJCF geom contacts held in the flow (carnot.hybrid.mjcf's pair rows, carnot.hybrid.flow's
held_solution, carnot.hybrid.simulate): a contact that stays closed after its strike, or from
the start, is held on MuJoCo's contact points, sticking while each point's ``|F_t| <= mu F_n``
(the Euclidean norm of its two tangential components), sliding against Coulomb's force
``-mu F_n v_t / |v_t|`` otherwise, the friction's work booked as ``sliding``.

Closed forms, for a solid sphere (m, R, I = 2/5 m R^2) and a box on a plane, gravity g:

* the bowling-ball problem (Routh, *Dynamical of a System of Rigid Bodies*, elementary part,
  1905, art. 149 ff.; Kleppner and Kolenkow, *An Introduction to Mechanics*, 2nd ed., 2014,
  example 7.11): a sphere launched at v0 without spin slides while its slip velocity
  ``u = v + w x r`` decays along a straight line at ``(7/2) mu g``: for ``t = 2 |u0| / (7 mu g)``;
  then it rolls at ``v0 - (2/7) |u0| u0 / |u0|`` (``5 v0 / 7`` without spin), friction taking
  ``m |u0|^2 / 7``; a spin about the normal is kept (no torsional friction);
* on an incline at ``a``, from rest: it rolls down at ``(5/7) g sin a`` where ``mu >= (2/7)
  tan a``, else slides at ``g (sin a - mu cos a)``, spinning up at ``5 mu g cos a / (2 R)``;
* a box sliding flat decelerates at ``mu g`` (each corner's slip the same): it stops after
  ``v0 / (mu g)`` s and ``v0^2 / (2 mu g)`` m, friction taking ``m v0^2 / 2``, and stays;
  frictionless on an incline, it slides down at ``g sin a``;
* dropped flat from h with restitution e, a ball or a box strikes at ``t_1 = sqrt(2 h / g)``
  and then after flights of ``2 e^k v_1 / g``: the series accumulates at
  ``t_1 + 2 e v_1 / (g (1 - e))``, where the chatter is closed (within ``1e-7 e / (1 - e)``
  s) and the contact held.

A box flat on a table is held on four corners, three independent rows of normal force (and
three of friction): its forces are not unique, carnot takes those of least norm (here each
corner's share, ``m g / 4``), and the motion is (the held system's null space has no part in
the accelerations: ``HeldSolution.unique``).

Two more routes: the sphere is also a disk of the same mass and inertia rolling in the plane
(a point on a plane held by the planar machinery, carnot.hybrid.guards.plane_guard, its
contact point ``(x + R theta, y - R)``); and MuJoCo's own soft simulation with a stiff
``solref`` and an elliptic cone (1e-4 s steps) rolls and stops the same way, to its softness.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
import sympy as sp

from carnot.hybrid.flow import Hold, held_points, held_solution, slide_direction
from carnot.hybrid.guards import motion_model, plane_guard
from carnot.hybrid.mechanism import Body, Mechanism, compile_mechanism
from carnot.hybrid.mjcf import mjcf_model
from carnot.hybrid.simulate import simulate
from carnot.hybrid.strike import Law

MODELS = Path(__file__).resolve().parent / "models"
BALL = MODELS / "bowling_ball.xml"
BOX = MODELS / "box_on_table.xml"
INCLINE = MODELS / "box_on_incline.xml"
BALL_INCLINE = MODELS / "ball_on_incline.xml"
TALL = MODELS / "tall_box.xml"
G = 9.81


def closes(run: object, rel: float = 1e-12) -> bool:
    energy = run.energy  # type: ignore[attr-defined]
    return abs(energy["residual"]) < rel * max(1.0, abs(energy["initial"]))


def test_a_bowling_ball_slides_then_rolls_at_five_sevenths() -> None:
    m, r, mu, v0 = 2.0, 0.1, 0.2, 3.0
    motion = mjcf_model(BALL, keyframe="launch")
    run = simulate(motion.model, motion.state, 1.5, motion.law)
    assert run.ended == "duration"
    assert [e.kind for e in run.events] == ["contact_start", "stick"]
    start, stick = run.events
    assert start.flags == ("ball/floor", "sliding") and stick.flags == ("ball/floor", "sticking")
    t = 2 * v0 / (7 * mu * G)
    assert stick.time == pytest.approx(t, abs=1e-12)
    assert stick.state[0] == pytest.approx(v0 * t - mu * G * t**2 / 2, abs=1e-12)
    np.testing.assert_allclose(stick.state[7:10], [5 * v0 / 7, 0.0, 0.0], atol=1e-12)
    assert stick.state[11] == pytest.approx(5 * v0 / 7 / r, rel=1e-12)  # w_y = v / R: rolling
    assert run.energy["sliding"] == pytest.approx(m * v0**2 / 7, rel=1e-12)
    # rolling on: the held point sticks with no force, at the same speed
    assert run.final[0] == pytest.approx(stick.state[0] + 5 * v0 / 7 * (1.5 - t), abs=1e-11)
    np.testing.assert_allclose(run.final[7:], stick.state[7:], atol=1e-11)
    assert run.final[2] == pytest.approx(r, abs=1e-13) and closes(run)


def test_a_ball_with_sidespin_slips_along_a_straight_line_and_keeps_its_spin() -> None:
    """Launched at (1.8, 2.4) m/s with w = (4, -3, 5) rad/s: its slip velocity u0 = v + w x r
    = (2.1, 2.8), |u0| = 3.5 m/s, not along v, decays along u0 (the friction follows it, not
    a sign); it rolls at (1.2, 1.6) after 2 |u0| / (7 mu g), its spin about z kept."""
    m, r, mu = 2.0, 0.1, 0.2
    motion = mjcf_model(BALL, keyframe="oblique")
    run = simulate(motion.model, motion.state, 1.0, motion.law)
    assert [e.kind for e in run.events] == ["contact_start", "stick"]
    u0 = np.array([2.1, 2.8])
    t = 2 * float(np.linalg.norm(u0)) / (7 * mu * G)
    stick = run.events[1]
    assert stick.time == pytest.approx(t, abs=1e-12)
    np.testing.assert_allclose(stick.state[7:9], [1.2, 1.6], atol=1e-12)
    assert run.energy["sliding"] == pytest.approx(m * float(u0 @ u0) / 7, rel=1e-12)
    # the world angular velocity (MuJoCo's is in the ball's axes): rolling, its z part kept
    quat = stick.state[3:7]
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat)
    omega = rot.reshape(3, 3) @ stick.state[10:13]
    contact = stick.state[7:10] + np.cross(omega, [0.0, 0.0, -r])
    np.testing.assert_allclose(contact, 0.0, atol=1e-11)
    assert omega[2] == pytest.approx(5.0, abs=1e-11)
    assert closes(run)


def test_the_planar_disk_route_rolls_the_same() -> None:
    """The same sphere as a disk in the x-y plane (its mass and inertia 2/5 m R^2), its
    contact point (x + R theta, y - R) held on the ground by the planar machinery: the same
    stick time, speed and friction's work as the MJCF sphere's, each to 1e-12."""
    m, r, mu, v0 = 2.0, 0.1, 0.2, 3.0
    x, y, th = sp.symbols("x y theta")
    mech = compile_mechanism(Mechanism(
        floating=(x, y, th), coordinates=(x, y, th), embedding=(x, y, th),
        bodies=(Body(mass=m, position=(x, y), inertia=0.4 * m * r**2, angle=th),),
        points={"contact": (x + r * th, y - r)}, gravity=(0, -G)), {})  # fmt: skip
    disk = motion_model(mech, [plane_guard(mech, "contact", name="floor")],
                        coordinates=("x", "y", "theta"), total_mass=m)  # fmt: skip
    planar = simulate(disk, np.array([0.0, r, 0.0, v0, 0.0, 0.0]), 1.5, Law(friction=mu))
    motion = mjcf_model(BALL, keyframe="launch")
    ours = simulate(motion.model, motion.state, 1.5, motion.law)
    assert [e.kind for e in planar.events] == [e.kind for e in ours.events]
    assert planar.events[1].time == pytest.approx(ours.events[1].time, abs=1e-12)
    assert planar.events[1].state[3] == pytest.approx(ours.events[1].state[7], abs=1e-12)
    # rolling on: the planar point's rows are exact, the MJCF pair's tangent bias is a
    # difference along the flow (carnot.hybrid.mjcf.HOLD_STEP) whose round-off, 5e-12 m/s^2
    # here (2/7 of it the ball's acceleration), moves with the state's last bits: over the
    # 1.06 s the speed drifts by up to 3e-12 m/s (launches an ulp apart, either BLAS)
    assert planar.final[3] == pytest.approx(ours.final[7], abs=1e-11)
    assert -planar.final[5] == pytest.approx(ours.final[11], abs=1e-10)  # (theta turns about -z)
    assert planar.energy["sliding"] == pytest.approx(ours.energy["sliding"], rel=1e-12)


@pytest.mark.parametrize("mu", [0.2, 0.05])
def test_a_ball_on_an_incline_rolls_or_slides_from_rest(mu: float) -> None:
    """(2/7) tan 0.4 = 0.1208: with mu = 0.2 the sticking force is inside the cone and the
    ball rolls, the contact point moving over the ball (the rows' bias by differences along
    the flow carries the rolling); with mu = 0.05 it slides from rest, the slide's direction
    found where the slip grows (here straight downhill), and spins up."""
    a, r = 0.4, 0.1
    motion = mjcf_model(BALL_INCLINE, friction=mu)
    run = simulate(motion.model, motion.state, 1.0, motion.law)
    assert run.ended == "duration" and [e.kind for e in run.events] == ["contact_start"]
    down = np.array([math.cos(a), 0.0, -math.sin(a)])
    rolls = mu >= 2 / 7 * math.tan(a)
    assert run.events[0].flags[1] == ("sticking" if rolls else "sliding")
    acc = 5 / 7 * G * math.sin(a) if rolls else G * (math.sin(a) - mu * math.cos(a))
    assert float(run.final[7:10] @ down) == pytest.approx(acc, abs=1e-11)
    assert float((run.final[:3] - motion.state[:3]) @ down) == pytest.approx(acc / 2, abs=1e-11)
    spin = acc / r if rolls else 5 * mu * G * math.cos(a) / (2 * r)
    assert run.final[11] == pytest.approx(spin, abs=1e-10)
    assert closes(run, 1e-11)


def test_a_box_slides_flat_to_a_stop_on_its_four_corners() -> None:
    m, mu, v0 = 1.5, 0.3, 2.0
    for key, direction in (("slide", np.array([1.0, 0.0])), ("oblique", np.array([0.6, 0.8]))):
        motion = mjcf_model(BOX, keyframe=key)
        run = simulate(motion.model, motion.state, 1.2, motion.law)
        assert [e.kind for e in run.events] == ["contact_start", "stick"], key
        start, stick = run.events
        assert start.held[0].points == 4 and start.flags[1] == "sliding"
        assert stick.time == pytest.approx(v0 / (mu * G), abs=1e-12)
        np.testing.assert_allclose(stick.state[:2], v0**2 / (2 * mu * G) * direction,
                                   atol=1e-12)  # fmt: skip
        assert run.energy["sliding"] == pytest.approx(m * v0**2 / 2, rel=1e-12)
        np.testing.assert_allclose(run.final, stick.state, atol=1e-12)  # and it stays
        assert closes(run)
    # held sticking: 12 rows (4 normal, 8 tangent) of rank 6, the least-norm forces m g / 4
    # on each corner and no friction; the motion unique (none of the null space moves it)
    hold = run.events[-1].held
    solution = held_solution(motion.model, hold, run.final)
    assert solution.rows.shape == (12, 6) and np.linalg.matrix_rank(solution.rows) == 6
    assert solution.unique and solution.rank == 6 + 6
    np.testing.assert_allclose(solution.normal[0], m * G / 4, rtol=1e-12)
    np.testing.assert_allclose(solution.tangent[0], 0.0, atol=1e-12)
    np.testing.assert_allclose(solution.flow[7:], 0.0, atol=1e-12)


def test_resting_bodies_stay_at_rest() -> None:
    for path in (BALL, BOX):
        motion = mjcf_model(path, keyframe="rest")
        run = simulate(motion.model, motion.state, 3.0, motion.law)
        assert run.ended == "duration" and [e.kind for e in run.events] == ["contact_start"]
        assert run.events[0].flags[1] == "sticking"
        # (the least-norm solve's round-off on the box's four corners: 1e-13 rad/s, 1e-13 m
        # and 1.4e-12 J after 3 s; the ball's one point 5e-14)
        np.testing.assert_allclose(run.final, motion.state, rtol=0, atol=1e-12)
        assert run.energy["sliding"] == 0.0 and closes(run, 1e-11)


def test_a_frictionless_box_slides_down_an_incline_at_g_sin_a() -> None:
    a, m, duration = 0.3, 1.0, 1.0
    motion = mjcf_model(INCLINE)
    run = simulate(motion.model, motion.state, duration, motion.law)
    assert run.ended == "duration" and [e.kind for e in run.events] == ["contact_start"]
    assert run.events[0].flags == ("box/incline",) and run.events[0].held[0].points == 4
    down = np.array([math.cos(a), 0.0, -math.sin(a)])
    np.testing.assert_allclose(run.final[7:10], G * math.sin(a) * duration * down, atol=1e-12)
    shift = run.final[:3] - motion.state[:3]
    np.testing.assert_allclose(shift, G * math.sin(a) * duration**2 / 2 * down, atol=1e-12)
    np.testing.assert_allclose(run.final[3:7], motion.state[3:7], atol=1e-13)  # no tilting
    solution = held_solution(motion.model, run.events[0].held, run.final)
    np.testing.assert_allclose(solution.normal[0], m * G * math.cos(a) / 4, rtol=1e-12)
    assert solution.unique and closes(run)


@pytest.mark.parametrize("path", [BALL, BOX])
def test_dropped_flat_it_chatters_to_its_accumulation_and_is_held(path: Path) -> None:
    """Dropped from 0.5 m (the ball) or 0.2 m (the box) with e = 0.5: its strikes at
    Newton's times, the chatter closed at the accumulation time, then held at rest: no
    contact_persists (the box on its four corners, each struck at once)."""
    e = 0.5
    motion = mjcf_model(path, keyframe="drop", restitution=e)
    run = simulate(motion.model, motion.state, 1.5, motion.law)
    assert run.ended == "duration" and run.events[-1].kind == "contact_start"
    assert all(ev.kind == "impact" for ev in run.events[:-1])
    h = float(motion.model.guards[0].function(motion.state))
    t1 = math.sqrt(2 * h / G)
    times = [ev.time for ev in run.events[:-1]]
    expected = t1 + np.concatenate([[0.0], np.cumsum(2 * e ** np.arange(1, 6) * t1)])
    np.testing.assert_allclose(times[:6], expected, atol=1e-11)
    accumulation = t1 + 2 * e * t1 / (1 - e)
    assert run.events[-1].time == pytest.approx(accumulation, abs=1e-7 * e / (1 - e) + 1e-12)
    assert run.events[-1].held[0].points == (1 if path == BALL else 4)
    np.testing.assert_allclose(run.final[7:], 0.0, atol=1e-12)
    assert closes(run)


@pytest.mark.parametrize(("path", "key", "closed"), [
    (BALL, "launch", lambda run: run.final[7]),   # the rolling speed
    (BOX, "slide", lambda run: run.final[0]),     # where it stopped
    (BALL, "oblique", lambda run: run.final[8]),  # the rolling velocity's y part
])  # fmt: skip
def test_mujoco_own_soft_simulation_agrees(path: Path, key: str, closed) -> None:  # type: ignore[no-untyped-def]
    """MuJoCo's own simulation (soft contacts: solref (1 ms, 1), an elliptic cone, 1e-4 s
    steps) rolls the ball and stops the box where carnot's rigid flow does, to its
    softness (2e-4 of the value)."""
    motion = mjcf_model(path, keyframe=key)
    ours = closed(simulate(motion.model, motion.state, 1.0, motion.law))
    model = mujoco.MjModel.from_xml_path(str(path))
    model.opt.timestep = 1e-4
    model.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    model.geom_solref[:] = [0.001, 1.0]
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY,
                                                                key))  # fmt: skip
    for _ in range(10000):
        mujoco.mj_step(model, data)

    class Theirs:
        final = np.concatenate([data.qpos, data.qvel])

    assert closed(Theirs) == pytest.approx(ours, rel=2e-4)


def test_the_slip_direction_follows_the_slip_velocity() -> None:
    """``d = v_t / |v_t|`` in the plane of the tangents (not a sign per row), smooth through
    the slide's stop (``v_t`` reversing along the reference keeps ``d``), and the planar
    rule ``d = s`` with one tangent row."""
    u = np.array([0.6, 0.8])
    np.testing.assert_allclose(slide_direction(u, np.array([0.8, 0.6]), 0.0), [0.8, 0.6])
    np.testing.assert_allclose(slide_direction(u, -1e-9 * u, 1e-12), u)
    assert slide_direction(np.array([-1.0]), np.array([2.0]), 1e-10).tolist() == [-1.0]
    assert Hold(index=0, slip=-1).reference(0).tolist() == [-1.0]


def _box_moving(qvel: list[float]) -> tuple[object, np.ndarray]:
    motion = mjcf_model(BOX, keyframe="rest")
    x = motion.state.copy()
    x[7:] = qvel
    return motion, x


def test_a_sliding_spinning_box_pivots_on_a_corner_and_stops() -> None:
    """Flat on the table at 0.3 m/s along x, spinning at 8 rad/s about z: all four corners
    slide (the least-norm forces made non-negative keep them pressed where the plain least
    norm would pull one), then one corner stops and sticks while the others slide about it
    (``sticking and sliding``), then all stick at once: friction takes the whole kinetic
    energy, m v^2 / 2 + I_z w^2 / 2, I_z = m (a^2 + b^2) / 12."""
    m = 1.5
    motion, x = _box_moving([0.3, 0.0, 0.0, 0.0, 0.0, 8.0])
    run = simulate(motion.model, x, 1.0, motion.law)  # type: ignore[attr-defined]
    assert run.ended == "duration"
    assert [(e.kind, e.flags[1]) for e in run.events] == [
        ("contact_start", "sliding"), ("stick", "sticking and sliding"), ("stick", "sticking")]
    kinetic = m * 0.3**2 / 2 + m * (0.4**2 + 0.2**2) / 12 * 8.0**2 / 2
    assert run.energy["sliding"] == pytest.approx(kinetic, rel=1e-12)
    np.testing.assert_allclose(run.final[7:], 0.0, atol=1e-12)
    assert closes(run)


def test_what_is_not_held_yet_stops_the_run_flagged() -> None:
    """At 1 m/s and 5 rad/s a corner stops whose force is outside its cone while sticking
    and which turns back when it slides from rest (its slip's acceleration against any
    direction it is made to slide in): no regime of the least-norm forces holds, and the
    run stops there (``contact_persists``), at the corner's stop, its ledger closed. A box
    rocking on an edge strikes at once and rocks to rest."""
    motion, x = _box_moving([1.0, 0.0, 0.0, 0.0, 0.0, 5.0])
    run = simulate(motion.model, x, 1.0, motion.law)  # type: ignore[attr-defined]
    assert run.ended == "stop" and run.events[-1].flags == ("contact_persists", "box/table")
    assert [e.kind for e in run.events] == ["contact_start", "stop"]  # (no slides tried)
    assert run.time == pytest.approx(0.3266, abs=1e-4) and closes(run)
    points = held_points(motion.model, run.events[-1].held[0], run.final)  # type: ignore[attr-defined]
    slips = sorted(float(np.linalg.norm(p.tangents()[0] @ run.final[7:])) for p in points)  # type: ignore[index]
    assert slips[0] <= 1e-9 < 0.1 < slips[1]  # (m/s) one corner stopped, three sliding
    motion, x = _box_moving([0.0, 0.0, 0.0, 3.0, 0.0, 0.0])
    run = simulate(motion.model, x, 1.0, motion.law)  # type: ignore[attr-defined]
    assert run.events[0].kind == "impact" and run.events[0].time == 0.0
    assert run.ended == "rest" and closes(run)


def test_the_rows_bias_is_the_contact_points_not_a_material_points() -> None:
    """A sphere on a plane, moving and spinning (w = (4, -3, 5) rad/s): its gap is z - R and
    its slip velocity v + w x (-R z), both linear in qvel with rows that do not change as it
    turns, so the held rows' biases (the difference along the flow) are zero; MuJoCo's
    mj_jacDot, the material point's, gives the normal bias R |w_perp|^2 = 2.5 m/s^2 instead
    (the curvature term a rolling contact does not have)."""
    motion = mjcf_model(BALL, keyframe="oblique")
    (point,) = motion.model.guards[0].rows(motion.state)  # type: ignore[misc]
    assert point.normal_bias == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(point.tangent_bias, 0.0, atol=1e-9)
    np.testing.assert_allclose(point.normal, [0, 0, 1, 0, 0, 0], atol=1e-15)
    model = mujoco.MjModel.from_xml_path(str(BALL))
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = motion.state[:7], motion.state[7:]
    mujoco.mj_forward(model, data)
    jacp = np.zeros((3, 6))
    mujoco.mj_jacDot(model, data, jacp, None, np.array([0.0, 0.0, 0.0]), 1)
    assert float(jacp[2] @ data.qvel) == pytest.approx(0.1 * (4.0**2 + 3.0**2), rel=1e-12)


def test_a_tall_box_pushed_tips_over_its_front_edge_and_falls_on_its_side() -> None:
    """Pushed at 1.5 m/s with mu h > b, no pushing forces hold its four corners: it is held
    on those that push, its front edge (two points), slides and tips over it, sticks and
    slips, falls on its side (a strike) and comes to rest there, lying flat (turned a
    quarter about y, its centre at the half width); the ledger closed."""
    motion = mjcf_model(TALL, keyframe="push")
    # (to 0.6 s: it sticks lying flat at 0.589 s; each further 0.1 s at rest cost 4.5 s)
    run = simulate(motion.model, motion.state, 0.6, motion.law)
    assert run.ended == "duration"
    first, last = run.events[0], run.events[-1]
    assert first.kind == "contact_start" and first.held[0].points == 2
    np.testing.assert_allclose(first.held[0].anchors, [[0.05, -0.05, -0.2], [0.05, 0.05, -0.2]],
                               atol=1e-12)  # the front edge  # fmt: skip
    assert any(e.kind == "impact" for e in run.events)
    assert last.kind == "stick" and last.held[0].points == 4
    assert run.final[2] == pytest.approx(0.05, abs=1e-12)
    assert abs(run.final[3]) == pytest.approx(math.sqrt(0.5), abs=1e-9)
    assert abs(run.final[5]) == pytest.approx(math.sqrt(0.5), abs=1e-9)
    np.testing.assert_allclose(run.final[7:], 0.0, atol=1e-12)
    assert closes(run, 1e-11)


_BAR = """<mujoco><worldbody><geom name="floor" type="plane" size="2 2 .1"/>
  <body name="bar" pos="0 0 0.2">
    <joint name="z" type="slide" axis="0 0 1"/><joint name="x" type="slide" axis="1 0 0"/>
    <joint name="pitch" type="hinge" axis="0 1 0"/>
    <geom name="bar" type="capsule" fromto="-0.3 0 0 0.3 0 0" size="0.02" contype="0"
          conaffinity="0" mass="1"/>
    <geom name="left" type="sphere" pos="-0.3 0 -0.1" size="0.05" mass="0.1"/>
    <geom name="right" type="sphere" pos="0.3 0 -0.1" size="0.05" mass="0.1"/>
  </body></worldbody>
  <keyframe><key name="drop" qpos="0 0 0" qvel="-1 0.3 0"/></keyframe></mujoco>"""


def test_feet_landing_together_are_all_held_not_one(tmp_path: Path) -> None:
    """A bar on two sphere feet (two pairs of geoms) lands flat: the strike finds one pair,
    and the other, in the same impact, ends closed and at rest too (as Unitree G1's eight
    foot spheres). Both are held; before, the second started the next leg a round-off below
    the floor, where no strike is found, and the bar pivoted through the floor on the first
    (pitch 1.3 rad and z = -0.41 m after 0.5 s). Plastic and sticking (MuJoCo's mu = 1 >= the
    0.3 / 1 the strike needs): the bar stops where it lands, its ledger closed."""
    path = tmp_path / "bar.xml"
    path.write_text(_BAR)
    motion = mjcf_model(str(path), keyframe="drop")
    run = simulate(motion.model, motion.state, 0.5, motion.law)
    assert run.ended == "duration" and closes(run)
    kinds = [(e.kind, e.flags[:1]) for e in run.events]
    assert kinds == [("impact", ()), ("contact_start", ("left/floor",)),
                     ("contact_start", ("right/floor",))]  # fmt: skip
    # the feet 0.05 m above the floor, falling at 1 m/s: h = t + g t^2 / 2
    landing = math.sqrt(1.0 + 2 * G * 0.05)  # (m/s, the speed at the floor)
    t = run.events[0].time
    assert t == pytest.approx((landing - 1.0) / G, rel=1e-10)
    z, x, pitch = run.events[-1].state[:3]
    assert z == pytest.approx(-0.05, abs=1e-12) and abs(pitch) <= 1e-12
    assert x == pytest.approx(0.3 * t, abs=1e-12)  # (it stuck where it landed)
    assert run.energy["impacts"] == pytest.approx(0.5 * 1.2 * (landing**2 + 0.3**2), rel=1e-10)

"""``carnot audit`` (carnot.rollout): the exact per-step energy audit of MuJoCo rollouts.

References:
* MuJoCo's integrators: ``mj_EulerSkip`` and ``mj_implicitSkip`` in ``src/engine/
  engine_forward.c`` (google-deepmind/mujoco): ``(M - h D) qacc = qfrc_smooth +
  qfrc_constraint``, ``qvel += h qacc``; ``mj_energyPos``/``mj_energyVel`` in
  ``engine_sensor.c``: ``E = sum -m_i g . x_i + springs + 1/2 qvel^T M qvel``.
* A rigid ball on a plane, Newton's law: ``E_d = 1/2 m (1 - e^2) v_n^2``; a solid sphere
  sliding without spin that leaves rolling loses ``1/2 (2/7) m v_t^2`` more (Brach, *Mechanical
  Impact Dynamics*, Wiley 1991, ch. 4; Cross, Am. J. Phys. 70, 2002).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
from test_mjcf import _arm_closed_form

from carnot import InputError
from carnot.cli import main
from carnot.io.rollout_report import report_to_dict
from carnot.rollout import EnergyAudit, RigidSettings, audit_model, audit_recording

EXAMPLES = Path(__file__).parent.parent / "examples" / "audit"
MODELS = Path(__file__).parent / "models"
BALL = EXAMPLES / "ball_drop.xml"

PENDULUM = """<mujoco><option timestep="0.002" integrator="{integrator}"/>
<worldbody><body name="a" pos="0 0 1">
 <joint name="j1" type="hinge" axis="0 1 0" damping="{damping}"/>
 <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.03" mass="1"/>
 <body name="b" pos="0.5 0 0"><joint name="j2" type="hinge" axis="0 1 0" damping="{damping}"/>
  <geom type="capsule" fromto="0 0 0 0.4 0 0.1" size="0.02" mass="0.6"/></body></body>
 <body name="top" pos="1 1 1"><freejoint/><geom type="box" size="0.1 0.05 0.02" mass="0.5"/></body>
</worldbody></mujoco>"""


def _pendulum(integrator: str, damping: float = 0.0, box: bool = True):
    """A double pendulum and a tumbling box in free flight: no contact, M(q) changing."""
    xml = PENDULUM.format(integrator=integrator, damping=damping)
    if not box:
        xml = xml[: xml.index('<body name="top"')] + "</worldbody></mujoco>"
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qvel[:] = [2.0, -3.0, 0.1, 0.2, 1.0, 3.0, -5.0, 7.0][: model.nv]
    return model, data


def _run(model, data, steps: int, **kw):
    audit = EnergyAudit(model, data, **kw)
    for _ in range(steps):
        mujoco.mj_step(model, data)
        audit.observe()
    return audit.finish()


@pytest.mark.parametrize(
    ("integrator", "damping"),
    [("Euler", 0.0), ("Euler", 0.3), ("implicitfast", 0.3), ("implicit", 0.3)],
)
def test_no_contact_residual_is_round_off(integrator: str, damping: float) -> None:
    # implicitfast's implicit gyroscopic term of a free body is not split out (below)
    model, data = _pendulum(integrator, damping, box=integrator != "implicitfast")
    steps = _run(model, data, 300).steps
    assert steps.exact and steps.integrator == integrator.lower() and not steps.reason
    scale = float(np.max(steps.kinetic))
    assert steps.max_abs_residual < 1e-13 * scale
    # the identity per step: kinetic[k+1] - kinetic[k] = works + mass_change + residual
    works = sum(steps.work.values())
    assert np.allclose(np.diff(steps.kinetic), works + steps.mass_change + steps.residual,
                       rtol=0, atol=1e-12 * scale)  # fmt: skip
    # the integrator's own term is there, reported (M changes with the elbow angle)
    assert np.max(np.abs(steps.mass_change)) > 1e-6
    if damping:  # the implicit damping term is work done, taken apart from the rest
        assert np.sum(steps.work["passive"]) + np.sum(steps.work["implicit"]) < 0
    # MuJoCo's energy: E[-1] - E[0] = all the works + mass change + potential change
    total = np.sum(works + steps.mass_change + steps.residual)
    assert steps.energy[-1] - steps.energy[0] == pytest.approx(
        total + steps.potential[-1] - steps.potential[0], abs=1e-12 * scale
    )


def test_implicitfast_free_body_term_shows_in_the_residual() -> None:
    model, data = _pendulum("implicitfast", 0.3)
    steps = _run(model, data, 100).steps
    assert steps.exact and "mjd_freeMhat" in steps.reason
    assert steps.max_abs_residual > 1e-9  # reported, not hidden


def test_gravity_work_against_the_potential_energy() -> None:
    """Free fall under semi-implicit Euler: gravity's work per step is m g h (v0 + v1)/2,
    the potential drop m g h v1 (the position moves with v1): their difference is the
    integrator's own m g^2 h^2 / 2 per step."""
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><option timestep="0.01"/><worldbody><body pos="0 0 5"><freejoint/>'
        '<geom type="sphere" size="0.1" mass="2"/></body></worldbody></mujoco>'
    )
    data = mujoco.MjData(model)
    steps = _run(model, data, 50).steps
    g, h, m = 9.81, 0.01, 2.0
    drop = -np.diff(steps.potential)
    assert np.allclose(steps.work["gravity"] - drop, -m * g**2 * h**2 / 2, rtol=1e-9, atol=0)


def test_rk4_is_reported_unsupported_not_silently_wrong(capsys) -> None:
    model, data = _pendulum("RK4")
    report = _run(model, data, 20)
    assert not report.steps.exact and "RK4" in report.steps.reason
    assert np.all(np.isnan(report.steps.residual))
    assert np.all(np.isnan(report.steps.work["gravity"]))
    out = report_to_dict(report)["steps"]
    assert out["exact"] is False and "no exact per-step split" in out["unsupported"]
    assert out["residual"][0] is None and out["max_abs_residual"] is None


def test_observe_must_follow_every_step() -> None:
    model, data = _pendulum("Euler")
    audit = EnergyAudit(model, data)
    mujoco.mj_step(model, data)
    mujoco.mj_step(model, data)
    with pytest.raises(InputError, match="must follow every mj_step"):
        audit.observe()


@pytest.fixture(scope="module")
def ball_report():
    return audit_model(BALL, keyframe="drop", duration=0.8, rigid=RigidSettings(restitution=0.5))


def test_ball_drop_episode_energy_equals_mujocos_energy_drop(ball_report) -> None:
    s = ball_report.steps
    assert s.exact and len(ball_report.episodes) >= 2
    for e in ball_report.episodes:
        assert e.complete and e.pair == ("floor", "ball")
        i0, i1 = (int(round(t / s.timestep)) for t in (e.start, e.end))
        # MuJoCo's mj_energy at both ends of the episode
        assert e.energy_lost == pytest.approx(s.energy[i0] - s.energy[i1], abs=1e-12)
        # the audit's terms over the episode: every work, the M change, the potential
        audited = -sum(float(np.sum(w[i0:i1])) for w in s.work.values())
        audited -= float(np.sum(s.mass_change[i0:i1]) + s.potential[i1] - s.potential[i0])
        assert audited == pytest.approx(e.energy_lost, abs=1e-11 * e.energy_before)
        # nearly all of it is the contact's own work (the rest: the integrator's drift)
        assert -e.contact_work == pytest.approx(e.energy_lost, abs=0.005 * e.energy_before)
        # the pair's normal velocity from the contact rows = the ball's vertical velocity
        assert e.normal_velocity_before == pytest.approx(e.qvel_before[2], rel=1e-12)
        assert e.normal_velocity_after == pytest.approx(e.qvel_after[2], rel=1e-9)
        assert e.effective_restitution == pytest.approx(-e.qvel_after[2] / e.qvel_before[2])


def test_ball_drop_rigid_reference_is_the_closed_form(ball_report) -> None:
    """The ball slides without spin (v_t = 0.5 m/s) and sticks (mu (1 + e) |v_n| >
    m* v_t): E_d = 1/2 m (1 - e^2) v_n^2 + 1/2 m* v_t^2, m* = 1 / (1/m + r^2 / I) the
    tangential effective mass at the contact point, lever arm r (2/7 m for r = R: Brach 1991).
    MuJoCo's contact point lies midway through the overlap: r = z_ball - z_point."""
    e_n, m, radius = 0.5, 1.0, 0.1
    first = ball_report.episodes[0]
    v = first.qvel_before
    assert np.allclose(v[3:], 0) and v[0] == pytest.approx(0.5)
    lever = first.qpos_before[2] - first.point[2]
    assert 0.09 < lever < radius
    m_t = 1 / (1 / m + lever**2 / (0.4 * m * radius**2))
    expected = 0.5 * m * (1 - e_n**2) * v[2] ** 2 + 0.5 * m_t * v[0] ** 2
    assert first.rigid_dissipated == pytest.approx(expected, rel=1e-12)
    assert first.rigid_restitution == pytest.approx(e_n, rel=1e-12)
    assert first.rigid_tangential_restitution == pytest.approx(0.0, abs=1e-12)  # rolling
    rigid = first.rigid
    assert rigid.energy.dissipated == pytest.approx(rigid.energy.dissipated_theorem, rel=1e-12)


def test_tangential_velocity_from_the_friction_rows() -> None:
    """Pyramidal and elliptic rows give the same slip velocity, that of the contact point
    v + omega x r (r = -R z) of a sphere sliding with spin."""
    for cone in ("pyramidal", "elliptic"):
        xml = BALL.read_text().replace('integrator="Euler"', f'integrator="Euler" cone="{cone}"')
        model = mujoco.MjModel.from_xml_string(xml)
        data = mujoco.MjData(model)
        data.qpos[:3] = [0, 0, 0.1005]
        data.qvel[:] = [1.0, -0.5, -2.0, 3.0, 2.0, 1.0]  # angular: body axes = world here
        report = _run(model, data, 30, min_speed=0.01)
        first = report.episodes[0]
        v = first.qvel_before[:3]
        omega = np.zeros(3)  # MuJoCo's free joint: angular velocity in body axes
        mujoco.mju_rotVecQuat(omega, first.qvel_before[3:], first.qpos_before[3:])
        point = v + np.cross(omega, first.point - first.qpos_before[:3])
        assert np.allclose(first.tangential_velocity_before, [point[0], point[1], 0.0],
                           rtol=0, atol=1e-12), cone  # fmt: skip


def test_constraint_groups_split_the_constraint_work() -> None:
    """A hinge hitting its limit while its tip strikes the floor: one group each, summing to
    the constraint work."""
    xml = """<mujoco><option timestep="0.001"/><worldbody>
    <geom name="floor" type="plane" size="1 1 .1"/>
    <body pos="0 0 0.3">
     <joint name="hinge" type="hinge" axis="0 1 0" range="-30 80" limited="true"/>
     <geom name="arm" type="capsule" fromto="0 0 0 0.25 0 0" size="0.02" mass="1"/></body>
    <body pos="0.6 0 0.5"><freejoint/>
     <geom name="ball" type="sphere" size="0.05" mass="0.3"/></body>
    </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qvel[0] = 4.0
    steps = _run(model, data, 600).steps
    assert set(steps.by_constraint) == {"joint limit hinge", "contact floor/ball"}
    assert sum(steps.by_constraint.values()) == pytest.approx(
        float(np.sum(steps.work["constraints"])), rel=1e-12
    )


def test_a_recorded_rollout_replays_to_the_same_audit(tmp_path) -> None:
    model = mujoco.MjModel.from_xml_path(str(BALL))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    qpos, qvel, warm = [], [], []
    for _ in range(600):
        qpos.append(data.qpos.copy())
        qvel.append(data.qvel.copy())
        warm.append(data.qacc_warmstart.copy())
        mujoco.mj_step(model, data)
    qpos.append(data.qpos.copy())
    qvel.append(data.qvel.copy())
    warm.append(data.qacc_warmstart.copy())
    path = tmp_path / "drop.npz"
    np.savez(path, qpos=np.array(qpos), qvel=np.array(qvel), qacc_warmstart=np.array(warm))
    replay = audit_recording(BALL, path)
    live = audit_model(BALL, keyframe="drop", duration=0.6)
    assert replay.steps.max_abs_residual < 1e-12 * replay.steps.energy[0]
    assert np.allclose([e.start for e in replay.episodes], [e.start for e in live.episodes])
    assert replay.episodes[0].energy_lost == pytest.approx(live.episodes[0].energy_lost, abs=1e-12)


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        ({"qpos": np.zeros((3, 7))}, "qvel: is missing"),
        ({"qpos": np.zeros((3, 7)), "qvel": np.zeros((3, 5))}, "qvel: must be 3 x 6 numbers"),
        ({"qpos": np.zeros((3, 7)), "qvel": np.zeros((3, 6)), "forces": np.zeros(3)},
         "forces: is not a recording array"),
        ({"qpos": np.zeros((3, 7)), "qvel": np.full((3, 6), np.nan)}, "must be finite"),
        ({"qpos": np.zeros((3, 7)), "qvel": np.zeros((3, 6)), "time": [0, 0.5, 1.0]},
         "must advance by the model's timestep"),
        ({"qpos": np.array([{"a": 1}] * 3, dtype=object), "qvel": np.zeros((3, 6))},
         "not a readable .npz recording"),
    ],
)  # fmt: skip
def test_bad_recordings_are_refused(tmp_path, arrays, message) -> None:
    path = tmp_path / "bad.npz"
    np.savez(path, **arrays)
    with pytest.raises(InputError, match=message):
        audit_recording(BALL, path)


def test_cli_json_as_the_issue_spells_it(tmp_path, capsys) -> None:
    plot = tmp_path / "audit.png"
    args = ["audit", str(BALL), "--keyframe", "drop", "--duration", "0.6",
            "--restitution", "0.5", "--json", "--plot", str(plot)]  # fmt: skip
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["format"] == 1 and set(data) >= {"episodes", "steps"}
    first = data["episodes"][0]
    assert set(first) >= {"start", "end", "pair", "energy_lost", "effective_restitution", "rigid"}
    assert first["pair"] == ["floor", "ball"] and first["rigid"]["format"] == 1
    assert first["rigid"]["energy"]["dissipated"] > 0
    assert data["steps"]["exact"] is True and plot.stat().st_size > 10_000
    assert main(["audit", str(BALL), "--keyframe", "drop", "--duration", "0.5"]) == 0
    assert "Impact episodes" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--restitution", "2"], "restitution: must be in [0, 1]"),
        (["--law", "hertz"], "law: must be one of newton"),
        (["--multiple-impact", "all"], "multiple_impact: must be one of simultaneous"),
        (["--duration", "-1"], "duration: must be a finite number"),
        (["--keyframe", "nope"], "unknown keyframe"),
        (["--rollout", "x.npz", "--duration", "1"], "--rollout: replays a recording"),
    ],
)
def test_cli_bad_input_is_one_line(extra, message, capsys) -> None:
    assert main(["audit", str(BALL), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_without_the_extra_the_command_says_how_to_install_it(monkeypatch, capsys) -> None:
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco now raises ImportError
    assert main(["audit", str(BALL)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and 'pip install "carnot[mujoco]"' in err


def test_rk4_still_finds_the_episodes_and_mujocos_energy() -> None:
    xml = BALL.read_text().replace('integrator="Euler"', 'integrator="RK4"')
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    report = _run(model, data, 600)
    (first,) = report.episodes
    s = report.steps
    i0, i1 = (int(round(t / s.timestep)) for t in (first.start, first.end))
    assert first.energy_lost == pytest.approx(s.energy[i0] - s.energy[i1], abs=1e-12)
    assert 0 < first.effective_restitution < 1 and first.normal_velocity_before < -4


def test_a_frictionless_arm_strikes_the_table() -> None:
    """condim 1: one row per contact, no tangential restitution. The episode opens at the
    keyframe (the tip touches the table, within the margin): the rigid reference is the
    textbook 2R arm's Newton impact (Spong, Hutchinson and Vidyasagar 2006; the closed form
    of tests/test_mjcf.py)."""
    e_n = 0.5
    report = audit_model(MODELS / "two_link_arm.xml", keyframe="strike", duration=0.05,
                         rigid=RigidSettings(restitution=e_n))  # fmt: skip
    first = report.episodes[0]
    assert first.pair == ("table", "tip") and first.tangential_restitution is None
    assert first.start == 0.0 and first.qpos_before.tolist() == [0.5, 0.7]
    _, after, dissipated = _arm_closed_form(first.qpos_before, first.qvel_before, e_n)
    assert first.rigid_dissipated == pytest.approx(dissipated, rel=1e-8)
    assert np.allclose(first.rigid.system.velocity_after, after, rtol=0, atol=1e-9)
    assert first.rigid_restitution == pytest.approx(e_n, rel=1e-9)
    assert first.steps > 1 and first.energy_lost > 0


def test_the_cradle_reference_under_the_sequential_law() -> None:
    """Five equal balls, e = 1, the pairwise (sequential) law: the striker's velocity passes
    down the chain and only the last ball leaves (Newton's cradle; Herrmann and Seitz, Am.
    J. Phys. 50, 1982). The reference takes the four contacts touching at rest at once."""
    report = audit_model(
        EXAMPLES / "newtons_cradle.xml",
        keyframe="strike",
        duration=0.013,
        rigid=RigidSettings(restitution=1.0, multiple_impact="sequential"),
    )
    first = report.episodes[0]
    assert first.pair == ("ball1", "ball2") and len(first.rigid.contacts) == 4
    v = first.qvel_before[0]
    assert np.allclose(first.rigid.system.velocity_after, [0, 0, 0, 0, v], rtol=0, atol=1e-12)
    # MuJoCo's soft chain loses energy, and the pairs' works add up to the loss
    s = report.steps
    assert s.energy[-1] < s.energy[0]
    assert sum(s.by_constraint.values()) == pytest.approx(float(np.sum(s.work["constraints"])))


def test_cli_replays_a_recording(tmp_path, capsys) -> None:
    model = mujoco.MjModel.from_xml_path(str(BALL))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    qpos, qvel = [data.qpos.copy()], [data.qvel.copy()]
    for _ in range(500):
        mujoco.mj_step(model, data)
        qpos.append(data.qpos.copy())
        qvel.append(data.qvel.copy())
    path = tmp_path / "run.npz"
    np.savez(path, qpos=np.array(qpos), qvel=np.array(qvel))
    assert main(["audit", str(BALL), "--rollout", str(path), "--json"]) == 0
    data_out = json.loads(capsys.readouterr().out)
    (first,) = data_out["episodes"]
    assert first["pair"] == ["floor", "ball"] and first["start"] == pytest.approx(0.452)
    # without the warm starts the solver's answers differ slightly: the residual says so
    assert 0 <= data_out["steps"]["max_abs_residual"] < 1e-6

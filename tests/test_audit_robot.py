"""``carnot audit`` and ``carnot from-mjcf`` on jointed robots (issue 36): the model's own
constraints in the references, the options both commands share, readable output.

Independent routes: MuJoCo's own mass matrix (``mj_fullM``) and constraint rows (``efc_J``,
``efc_type``, ``efc_force``, dense), solved here with NumPy; Newton's law for one unilateral
row ``r`` with ``G = r M^-1 r^T``: ``P = -(1 + e) r q' / G``, ``q'' = q' + M^-1 r^T P`` (the
paper's eq. 5 in generalized coordinates; Brogliato, *Nonsmooth Mechanics*, 3rd ed., section
6.2). The per-step works: ``h f_r (J_r (v0 + v1)) / 2`` (tests/test_audit.py's theorem).
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from pathlib import Path

import mujoco
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from robots import mujoco_state as _mujoco_state

from carnot import InputError, solve_impact
from carnot.cli import main
from carnot.io.rollout_report import format_report, report_to_dict
from carnot.io.system_scenario import parse_system_scenario
from carnot.model.mjcf import mjcf_problem
from carnot.plot_rollout import plot_audit
from carnot.result import Flag
from carnot.rollout import EnergyAudit, RigidSettings, audit_model, audit_recording

MODELS = Path(__file__).parent / "models"
LEG = MODELS / "leg_drop.xml"  # slides (height, sway), damped hip and knee, knee limit, servo
BALL = MODELS / "ball_on_plane.xml"
CONNECT = MODELS / "arm_elbow_connect.xml"

#: leg_drop.xml lifted clear of the floor, its knee past its upper limit (-10 deg) and
#: turning further into it: the only constraint row is the knee's limit.
KNEE_QPOS = [0.3, 0.0, 0.2, -0.17]
KNEE_QVEL = [-0.5, 0.3, 0.4, 1.2]


def test_a_joint_limit_is_a_unilateral_row_as_mujoco_has_it() -> None:
    model, data, mass = _mujoco_state(LEG, KNEE_QPOS, KNEE_QVEL)
    assert list(data.efc_type) == [int(mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)]
    row = np.array(data.efc_J).reshape(data.nefc, model.nv)[0]
    q = np.array(KNEE_QVEL)
    e = 0.5
    g = row @ np.linalg.solve(mass, row)
    impulse = -(1 + e) * (row @ q) / g
    expected = q + np.linalg.solve(mass, row) * impulse
    problem = mjcf_problem(LEG, qpos=KNEE_QPOS, qvel=KNEE_QVEL, restitution=e)
    (limit,) = problem.contacts
    assert limit.name == "limit knee" and limit.friction == 0.0
    assert limit.jacobian[0].tolist() == row.tolist() and not limit.jacobian[1:].any()
    r = solve_impact(problem)
    assert np.allclose(r.system.velocity_after, expected, rtol=0, atol=1e-10)
    assert row @ r.system.velocity_after == pytest.approx(-e * (row @ q), abs=1e-12)
    kinetic = 0.5 * q @ mass @ q - 0.5 * expected @ mass @ expected
    assert r.energy.dissipated == pytest.approx(kinetic, rel=1e-10)
    with pytest.raises(InputError, match="has no approaching contact"):
        mjcf_problem(LEG, qpos=KNEE_QPOS, qvel=KNEE_QVEL, limits=False)
    # turning out of the limit: not a contact of the impact
    with pytest.raises(InputError, match="has no approaching contact"):
        mjcf_problem(LEG, qpos=KNEE_QPOS, qvel=[*KNEE_QVEL[:3], -1.2])


def _condim_one(tmp_path: Path) -> Path:
    path = tmp_path / "ball_condim1.xml"
    path.write_text(BALL.read_text().replace('friction="0.1"', 'friction="0.1" condim="1"'))
    return path


def test_condim_one_stays_frictionless_under_every_option(tmp_path: Path, capsys) -> None:
    path = _condim_one(tmp_path)
    # keyframe "slip": 1 kg ball, w_n = -1 m/s, sliding at (2, 0.5) m/s and spinning:
    # frictionless, only the normal velocity changes, to -e w_n (Newton)
    for options in ({}, {"tangential": "stick"}, {"friction": 0.5},
                    {"tangential": "stick", "friction": 0.5}):  # fmt: skip
        problem = mjcf_problem(path, keyframe="slip", restitution=0.5, **options)
        (contact,) = problem.contacts
        assert (contact.friction, contact.tangential) == (0.0, "slip"), options
        after = solve_impact(problem).system.velocity_after
        assert after.tolist() == pytest.approx([2.0, 0.5, 0.5, 0, 0, 3.0], abs=1e-12)
    out = tmp_path / "ball.toml"
    args = ["from-mjcf", str(path), "--keyframe", "slip", "--tangential", "stick", "-o", str(out)]
    assert main(args) == 0
    (contact,) = parse_system_scenario(tomllib.loads(out.read_text())).contacts
    assert (contact.friction, contact.tangential) == (0.0, "slip")
    # the audit's reference too: a ball dropped on the condim-1 plane keeps its slip
    dropped = tmp_path / "drop.xml"
    dropped.write_text(path.read_text().replace('qpos="0 0 0.1 1 0 0 0" qvel="2.0 0.5 -1.0',
                                                'qpos="0 0 0.15 1 0 0 0" qvel="2.0 0.5 -1.0'))
    report = audit_model(dropped, keyframe="slip", duration=0.1,
                         rigid=RigidSettings(tangential="stick", friction=0.5))  # fmt: skip
    (episode,) = report.episodes
    before = episode.qvel_before
    after = episode.rigid.system.velocity_after
    assert np.allclose(after[[0, 1, 3, 4, 5]], before[[0, 1, 3, 4, 5]], atol=1e-12)
    assert episode.tangential_note == "frictionless"


def test_negative_numbers_in_any_form_numpy_prints(tmp_path: Path, capsys) -> None:
    """``--qvel 0 0 -1e-5``: argparse's own pattern takes ``-1e-5`` for an option."""
    qvel = [2.0, 0.5, -1e-5, -1.5e-3, 0.0, -3.0]
    printed = ["2.", "5.e-01", "-1e-05", "-1.5E-03", "0", "-3"]  # as NumPy may print them
    assert [float(x) for x in printed] == qvel
    out = tmp_path / "ball.toml"
    assert main(["from-mjcf", str(BALL), "--keyframe", "slip", "--qvel", *printed,
                 "-o", str(out)]) == 0  # fmt: skip
    problem = parse_system_scenario(tomllib.loads(out.read_text()))
    assert problem.system.velocity.tolist() == qvel
    # -inf and -nan are numbers too: refused as values (one line, status 2), not as options
    capsys.readouterr()
    assert main(["from-mjcf", str(BALL), "--qvel", "0", "0", "-inf", "0", "0", "0"]) == 2
    assert "qvel: must be 6 finite numbers" in capsys.readouterr().err
    assert main(["audit", str(BALL), "--qvel", "0", "0", "-1e-2", "0", "0", "-nan"]) == 2
    assert "qvel: must be 6 finite numbers" in capsys.readouterr().err
    # the audit's start: the same rollout from --qpos/--qvel as from the keyframe's state
    key = mujoco.MjModel.from_xml_path(str(LEG)).key("drop")
    given = audit_model(LEG, duration=0.05, qpos=key.qpos.tolist(), qvel=key.qvel.tolist())
    keyed = audit_model(LEG, keyframe="drop", duration=0.05)
    # (the same start; the keyframe also sets the servo's target, which --qpos does not)
    assert given.steps.energy[0] == keyed.steps.energy[0]


def _leg_recording(tmp_path: Path, *, ctrl: bool) -> tuple[Path, Path]:
    model = mujoco.MjModel.from_xml_path(str(LEG))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    arrays: dict[str, list[np.ndarray]] = {"qpos": [], "qvel": [], "qacc_warmstart": [],
                                           "ctrl": []}  # fmt: skip
    for k in range(41):
        data.ctrl[:] = -0.3 + 0.5 * math.sin(40 * k * model.opt.timestep)  # a servo's target
        for name in arrays:
            arrays[name].append(getattr(data, name).copy())
        mujoco.mj_step(model, data)
    if not ctrl:
        del arrays["ctrl"]
    out = tmp_path / ("with_ctrl.npz" if ctrl else "without_ctrl.npz")
    np.savez(out, **{k: np.array(v) for k, v in arrays.items()})
    return LEG, out


def test_a_replay_without_ctrl_on_a_model_with_actuators_warns(tmp_path: Path, capsys) -> None:
    full = audit_recording(*_leg_recording(tmp_path, ctrl=True))
    assert full.warnings == () and full.steps.max_abs_residual < 1e-12
    lacking = audit_recording(*_leg_recording(tmp_path, ctrl=False))
    (warning,) = lacking.warnings
    assert "no ctrl but the model has 1 actuator(s)" in warning
    # what it warns of: MuJoCo's step with ctrl = 0 is not the recorded one
    assert lacking.steps.max_abs_residual > 1e-3
    assert report_to_dict(lacking)["warnings"] == [warning]
    assert format_report(lacking).splitlines()[2] == f"  warning: {warning}"
    model, recording = _leg_recording(tmp_path, ctrl=False)
    assert main(["audit", str(model), "--rollout", str(recording), "--json"]) == 0
    assert f"carnot: warning: {warning}" in capsys.readouterr().err


def _arm_free_forearm(q1: float, q2: float, rate1: float, rate2: float):
    """tests/test_mjcf.py's state of the arm with a free forearm (elbow connect held)."""
    turn = q1 + q2
    elbow = [0.5 * math.cos(q1), 0.0, 1.0 - 0.5 * math.sin(q1)]
    quat = [math.cos(turn / 2), 0.0, math.sin(turn / 2), 0.0]
    v_elbow = [-0.5 * math.sin(q1) * rate1, 0.0, -0.5 * math.cos(q1) * rate1]
    return [q1, *elbow, *quat], [rate1, *v_elbow, 0.0, rate1 + rate2, 0.0]


def test_a_soft_equality_drifts_and_the_pin_states_its_tolerance() -> None:
    """MuJoCo's connect is soft: falling onto the table, the elbow's anchors drift apart at
    8.7 mm/s by the tip's impact. carnot's pin (round-off) refuses that state; a pin to a
    stated drift checks it and imposes the equality, as a fastening does."""
    qpos, qvel = _arm_free_forearm(0.3, 0.7, 2.0, 1.5)
    runs = {
        name: audit_model(CONNECT, duration=0.12, qpos=qpos, qvel=qvel, rigid=settings)
        for name, settings in (("strict", RigidSettings()),
                               ("loose", RigidSettings(drift=1e-3)),
                               ("pinned", RigidSettings(drift=0.05)),
                               ("fasten", RigidSettings(equality="fasten")))
    }  # fmt: skip
    (strict,), (loose,) = runs["strict"].episodes, runs["loose"].episodes
    (pinned,), (fasten,) = runs["pinned"].episodes, runs["fasten"].episodes
    assert strict.rigid is None and "a pin needs zero relative velocity" in strict.rigid_error
    assert loose.rigid is None and "equality 'elbow': drifts by |J q'| = 0.00" in loose.rigid_error
    # the drift, measured apart: the connect's rows (MuJoCo's efc_J) times q'
    model, data, _ = _mujoco_state(CONNECT, pinned.qpos_before, pinned.qvel_before)
    rows = np.array(data.efc_J).reshape(data.nefc, model.nv)[np.asarray(data.efc_type) == 0]
    drift = float(np.linalg.norm(rows @ pinned.qvel_before))
    assert 1e-3 < drift < 0.05
    assert f"{drift:.3g} m/s" in loose.rigid_error
    assert pinned.rigid_dissipated == fasten.rigid_dissipated
    assert np.array_equal(pinned.rigid.system.velocity_after, fasten.rigid.system.velocity_after)
    assert np.allclose(rows @ pinned.rigid.system.velocity_after, 0.0, atol=1e-12)
    assert "not computed" in format_report(runs["strict"])
    assert strict.rigid_verdict.startswith("no reference: constraints[0]: a pin needs")


def test_each_episodes_energy_split_against_mujocos_rows() -> None:
    """The split of each episode's loss, against MuJoCo's own rows and forces stepped here."""
    model = mujoco.MjModel.from_xml_path(str(LEG))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    audit = EnergyAudit(model, data)
    h = model.opt.timestep
    limits, actuators, passive = [], [], []
    for _ in range(30):
        v0 = data.qvel.copy()
        mujoco.mj_step(model, data)  # leaves the start-of-step forward quantities in data
        v1 = data.qvel.copy()
        jv = np.zeros(data.nefc)
        if data.nefc:
            mujoco.mj_mulJacVec(model, data, jv, v0 + v1)
        limit = np.asarray(data.efc_type) == int(mujoco.mjtConstraint.mjCNSTR_LIMIT_JOINT)
        limits.append(0.5 * h * float(data.efc_force[limit] @ jv[limit]))
        actuators.append(0.5 * h * float(data.qfrc_actuator @ (v0 + v1)))
        passive.append(0.5 * h * float(data.qfrc_passive @ (v0 + v1)))
        audit.observe()
    report = audit.finish()
    (episode,) = [e for e in report.episodes if e.pair == ("floor", "foot")]
    steps = slice(episode.first_step, episode.first_step + episode.steps)
    split = episode.split
    assert split["limits"] == pytest.approx(-sum(limits[steps]), rel=1e-12)
    assert split["limits"] > 1.0  # the knee folds into its limit: most of the loss
    assert split["actuators"] == pytest.approx(-sum(actuators[steps]), rel=1e-12)
    # damping: qfrc_passive's work and the implicit damping (implicitfast: qDeriv)
    implicit = report.steps.work["implicit"][steps].sum()
    assert split["damping"] == pytest.approx(-sum(passive[steps]) - implicit, rel=1e-12)
    assert split["pair"] == -episode.contact_work
    assert sum(split.values()) == pytest.approx(episode.energy_lost, rel=1e-12)
    # the rest: gravity against the potential's drop and M's change against Coriolis, small
    assert abs(split["rest"]) < 0.02 * episode.energy_lost
    table = format_report(report)
    assert "Where each episode's energy went" in table
    data_out = report_to_dict(report)["episodes"]
    assert data_out[0]["energy_split"]["limits"] == split["limits"]


def test_the_table_says_why_instead_of_printing_round_off() -> None:
    report = audit_model(LEG, keyframe="drop", duration=0.06, rigid=RigidSettings())
    foot = next(e for e in report.episodes if e.pair == ("floor", "foot"))
    # no slip before: the ratio would divide by round-off
    still = dataclasses.replace(foot, tangential_velocity_before=np.array([3e-9, 0.0, 0.0]))
    assert still.tangential_restitution is None and still.tangential_note == "no slip before"
    # a reference the law found no answer for: its verdict, not E_d 0 and e -1
    failed = dataclasses.replace(foot, rigid=dataclasses.replace(foot.rigid, warnings=(
        Flag(code="no_solution", where="contacts", message="no impulse meets the law"),)))
    shown = dataclasses.replace(report, episodes=(still, failed))
    lines = format_report(shown).splitlines()
    header = next(k for k, line in enumerate(lines) if line.lstrip().startswith("pair"))
    assert "flags" in lines[header]
    assert "— (no slip before)" in lines[header + 2]
    assert "no rigid answer" in lines[header + 3] and "no_solution" in lines[header + 3]
    assert " -1 " not in lines[header + 3]
    assert f"  floor/foot at {failed.start:.4f} s: no rigid answer (no_solution)" in lines
    episode = report_to_dict(shown)["episodes"][1]
    assert episode["rigid_verdict"] == "no rigid answer (no_solution)"
    assert episode["rigid_flags"] == ["no_solution"]
    assert report_to_dict(shown)["episodes"][0]["tangential_note"] == "no slip before"


def test_sticking_answers_that_are_not_unique_say_so() -> None:
    """The leg's shin lands while the foot sticks: the simultaneous law allows several
    answers (``multiple_solutions``); the table's flags and the JSON say so."""
    report = audit_model(LEG, keyframe="drop", duration=0.06,
                         rigid=RigidSettings(tangential="stick"))  # fmt: skip
    several = [e for e in report.episodes if "multiple_solutions" in e.rigid_flags]
    assert several
    for e in several:
        assert e.rigid_unique is False and e.rigid.alternatives
        low, high = e.rigid_dissipated_range
        values = [r.energy.dissipated for r in (e.rigid, *e.rigid.alternatives)]
        assert (low, high) == (min(values), max(values))
        # the law's own range (the theorem's E_d of each regime it found), against the
        # answers' direct energy differences
        span = e.rigid.solver.dissipated_range
        assert span == pytest.approx((low, high), rel=1e-9, abs=1e-12)
    table = format_report(report)
    assert "not unique (E_d" in table  # with the range of E_d over the answers
    entry = report_to_dict(report)["episodes"][report.episodes.index(several[0])]
    assert entry["rigid_unique"] is False and entry["rigid"]["solver"]["velocities_unique"] is False


def test_the_options_rebuild_a_reference_with_from_mjcf(tmp_path: Path, capsys) -> None:
    """An episode's reference rebuilt from its qpos_before and qvel_before by from-mjcf with
    the audit's options (--gap, --resting, --tangential) is the same problem and answer."""
    assert main(["audit", str(LEG), "--keyframe", "drop", "--duration", "0.06", "--json",
                 "--gap", "0.001", "--tangential", "stick"]) == 0  # fmt: skip
    data = json.loads(capsys.readouterr().out)
    assert data["rigid_law"]["gap"] == 0.001 and data["rigid_law"]["limits"] is True
    episode = data["episodes"][0]
    out = tmp_path / "reference.toml"
    qpos = [repr(x) for x in episode["qpos_before"]]
    qvel = [repr(x) for x in episode["qvel_before"]]
    assert main(["from-mjcf", str(LEG), "--qpos", *qpos, "--qvel", *qvel, "--gap", "0.001",
                 "--resting", "--tangential", "stick", "-o", str(out)]) == 0  # fmt: skip
    rebuilt = solve_impact(parse_system_scenario(tomllib.loads(out.read_text())))
    assert rebuilt.energy.dissipated == pytest.approx(
        episode["rigid"]["energy"]["dissipated"], rel=1e-9
    )


def test_the_episode_plot_stays_legible_with_100_episodes() -> None:
    report = audit_model(LEG, keyframe="drop", duration=0.06, rigid=RigidSettings())
    first = report.episodes[0]
    pairs = [("floor", f"foot{k % 12}") for k in range(100)]
    many = tuple(dataclasses.replace(first, pair=p, start=0.005 * k)
                 for k, p in enumerate(pairs))  # fmt: skip
    for episodes in (many, many[:20]):
        fig = plot_audit(dataclasses.replace(report, episodes=episodes))
        renderer = FigureCanvasAgg(fig).get_renderer()
        fig.draw(renderer)
        axis = fig.axes[1]
        low, high = axis.get_xlim()  # the ticks drawn (the locator's may lie beyond)
        shown = [t for t, x in zip(axis.get_xticklabels(), axis.get_xticks(), strict=True)
                 if t.get_text() and low <= x <= high]  # fmt: skip
        boxes = [t.get_window_extent(renderer) for t in shown]
        assert boxes
        for a, b in zip(boxes, boxes[1:], strict=False):  # left to right, none overlapping
            assert a.x1 <= b.x0 + 0.5, (len(episodes), a, b)
        legend = axis.get_legend()
        assert legend is not None and len(legend.get_texts()) <= 9
        assert all(box.x0 >= 0 and box.x1 <= fig.bbox.width for box in boxes), boxes

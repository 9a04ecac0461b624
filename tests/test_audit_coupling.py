"""The rigid reference of an audit episode solves only the contacts coupled to the episode's
pair (``carnot.model.coupling``; ``RigidSettings.scope``).

References:
* Decoupling: with the Delassus operator ``G`` block diagonal, ``w'' = w' + G Lambda`` and
  the contact-wise complementarity conditions split block by block, so the simultaneous law's
  solutions are the products of the blocks' (Cottle, Pang and Stone, *The Linear
  Complementarity Problem*, 1992, section 1.1; Glocker, *Set-Valued Force Laws*, Springer
  2001, ch. 7): the coupled part alone gives the whole scene's impulses and velocities there.
* A ball striking the top of a stack resting on a fixed floor, frictionless, simultaneous
  Newton law (Glocker 2001, ch. 7; Moreau 1988): every contact of the stack is closed at
  rest (``w_n' = 0``, so ``w_n'' >= 0``) and the floor cannot move, so the stack stays at
  rest and the ball rebounds at ``e v``: ``E_d = 1/2 m (1 - e^2) v^2``. A ball dropped on the
  floor alone: the same closed form (Brach, *Mechanical Impact Dynamics*, Wiley 1991, ch. 4).
"""

from __future__ import annotations

import dataclasses
import json

import mujoco
import numpy as np
import pytest

from carnot import InputError
from carnot.cli import main
from carnot.model.coupling import coupled_items, coupled_parts, coupled_problem
from carnot.model.mjcf import mjcf_problem
from carnot.model.system import motion_rows
from carnot.rollout import EnergyAudit, RigidSettings
from carnot.solve import solve_impact

E_N = 0.5
V_BALL, M_BALL = 2.0, 0.5  # the ball striking the stack (m/s down, kg)
V_DROP, M_DROP = 3.0, 1.0  # a ball striking the floor elsewhere, at the same instant

# box A on the floor, box B on A, the ball on B (touching: 1e-7 m of overlap), a sphere at
# rest on the floor and a ball striking the floor elsewhere
PILE = f"""<mujoco><option timestep="0.001"/><worldbody>
<geom name="floor" type="plane" size="3 3 .1"/>
<body pos="0 0 0.05"><freejoint/><geom name="boxA" type="box" size=".1 .1 .05" mass="2"/></body>
<body pos="0 0 0.15"><freejoint/><geom name="boxB" type="box" size=".08 .08 .05" mass="1"/></body>
<body pos="0 0 0.2999999"><freejoint/><geom name="ball" size="0.1" mass="{M_BALL}"/></body>
<body pos="1 0 0.1"><freejoint/><geom name="rest" size="0.1" mass="1"/></body>
<body pos="-1 0 0.0999999"><freejoint/><geom name="drop" size="0.1" mass="{M_DROP}"/></body>
</worldbody></mujoco>"""


def _pile(friction: float | None = 0.0):
    model = mujoco.MjModel.from_xml_string(PILE)
    qvel = np.zeros(model.nv)
    qvel[2 * 6 + 2], qvel[4 * 6 + 2] = -V_BALL, -V_DROP  # the ball's and the drop's v_z
    problem = mjcf_problem(model, qpos=model.qpos0.tolist(), qvel=qvel.tolist(),
                           restitution=E_N, friction=friction, resting=True)  # fmt: skip
    return model, problem


def test_the_parts_are_the_blocks_of_the_delassus_operator() -> None:
    """The stack's three pairs (4 + 4 corners, the ball) are one part; the resting sphere and
    the other ball are parts of their own: G_ij = J_i M^-1 J_j^T is zero between parts and
    links each item of the stack to the others."""
    _, problem = _pile()
    names = [c.name for c in problem.contacts]
    parts = coupled_parts(problem)
    by_name = sorted(sorted({names[i] for i in part}) for part in parts)
    assert by_name == [["boxA/floor", "boxB/ball", "boxB/boxA"], ["drop/floor"], ["rest/floor"]]
    stack = next(p for p in parts if len(p) > 1)
    assert len(stack) == 9  # every corner of both boxes and the ball
    j = [motion_rows(item) for item in problem.items]
    inverse = problem.system.mass_matrix_inv
    label = {i: k for k, part in enumerate(parts) for i in part}
    for a in range(len(j)):
        for b in range(len(j)):
            block = j[a] @ inverse @ j[b].T
            if label[a] != label[b]:
                assert not np.any(block), (names[a], names[b])
    # within the stack: the graph of nonzero blocks reaches every item from the ball
    reached, frontier = {stack[-1]}, [stack[-1]]
    while frontier:
        a = frontier.pop()
        for b in stack:
            if b not in reached and np.any(j[a] @ inverse @ j[b].T):
                reached.add(b)
                frontier.append(b)
    assert reached == set(stack)


def test_a_ball_on_a_stack_alone_and_in_the_scene() -> None:
    """The closed form (module docstring) from the stack's part alone, and the whole scene's
    answer on that part's contacts and coordinates to 1e-10; the scene's E_d adds the other
    ball's own closed form."""
    _, problem = _pile()
    seeds = [k for k, c in enumerate(problem.contacts) if c.name == "boxB/ball"]
    part = coupled_problem(problem, seeds)
    assert len(part.contacts) == 9 and len(problem.contacts) == 11
    alone, scene = solve_impact(part), solve_impact(problem)
    assert alone.system is not None and scene.system is not None
    after = alone.system.velocity_after.reshape(-1, 6)
    assert np.allclose(after[:2], 0.0, rtol=0, atol=1e-12)  # the stack stays at rest
    assert np.allclose(after[2], [0, 0, E_N * V_BALL, 0, 0, 0], rtol=0, atol=1e-12)
    assert np.allclose(after[4], [0, 0, -V_DROP, 0, 0, 0], rtol=0, atol=0)  # not solved
    closed = 0.5 * M_BALL * (1 - E_N**2) * V_BALL**2
    assert alone.energy.dissipated == pytest.approx(closed, rel=1e-12)
    assert alone.energy.dissipated_theorem == pytest.approx(closed, rel=1e-12)
    drop = 0.5 * M_DROP * (1 - E_N**2) * V_DROP**2
    assert scene.energy.dissipated == pytest.approx(closed + drop, rel=1e-12)
    # the part's contacts: the same impulses and shares of E_d in the whole scene
    whole = {o.where: o for o in scene.contacts}
    for mine in alone.contacts:
        other = whole[mine.where]
        assert np.allclose(mine.impulse, other.impulse, rtol=0, atol=1e-10)
        assert mine.dissipated == pytest.approx(other.dissipated, rel=0, abs=1e-10)
        assert np.allclose(mine.relative_velocity_after, other.relative_velocity_after,
                           rtol=0, atol=1e-10)  # fmt: skip
    moved = slice(0, 18)  # the stack's coordinates: boxes A, B and the ball
    assert np.allclose(alone.system.velocity_after[moved], scene.system.velocity_after[moved],
                       rtol=0, atol=1e-10)  # fmt: skip


# A torso sliding on a vertical rail with two hinged legs, both feet on the floor (touching:
# 1e-7 m of overlap), a ball resting elsewhere: the feet are two branches of one tree
LEGS = """<mujoco><worldbody><geom name="floor" type="plane" size="3 3 .1"/>
<body pos="0 0 0.4499999"><joint name="lift" type="slide" axis="0 0 1"/>
 <geom type="box" size="0.3 0.05 0.05" mass="3"/>
 <body pos="-0.25 0 0"><joint name="left" type="hinge" axis="0 1 0"/>
  <geom name="footL" type="capsule" fromto="0 0 0 0 0 -0.4" size="0.05" mass="0.5"/></body>
 <body pos="0.25 0 0"><joint name="right" type="hinge" axis="0 1 0"/>
  <geom name="footR" type="capsule" fromto="0 0 0 0 0 -0.4" size="0.05" mass="0.5"/></body>
</body>
<body pos="2 0 0.0999999"><freejoint/><geom name="ball" size="0.1" mass="1"/></body>
</worldbody></mujoco>"""


def test_two_branches_of_a_tree_are_one_part() -> None:
    """The feet move the rail's coordinate both: one part, coupled (G between them is not
    zero); the ball is apart. The whole problem's answer on the legs' part is the part's.
    Both routes to the parts (the graph's components, the part grown from a seed) agree for
    every seed, here and on the pile."""
    model = mujoco.MjModel.from_xml_string(LEGS)
    qvel = np.zeros(model.nv)
    qvel[:3] = [-1.0, 0.5, -0.2]  # the torso falls, the legs swing
    problem = mjcf_problem(model, qpos=model.qpos0.tolist(), qvel=qvel.tolist(),
                           restitution=E_N, resting=True)  # fmt: skip
    assert [c.name for c in problem.contacts] == ["footL/floor", "footR/floor", "ball/floor"]
    assert coupled_parts(problem) == ((0, 1), (2,))
    j = [c.jacobian for c in problem.contacts]
    assert np.any(j[0] @ problem.system.mass_matrix_inv @ j[1].T)
    alone, scene = solve_impact(coupled_problem(problem, [1])), solve_impact(problem)
    assert len(alone.contacts) == 2
    for mine, other in zip(alone.contacts, scene.contacts, strict=False):
        assert np.allclose(mine.impulse, other.impulse, rtol=0, atol=1e-10)
    assert np.allclose(alone.system.velocity_after, scene.system.velocity_after, rtol=0,
                       atol=1e-10)  # fmt: skip
    assert alone.energy.dissipated == pytest.approx(scene.energy.dissipated, rel=1e-12)
    for case in (problem, _pile()[1]):
        parts = coupled_parts(case)
        for seed in range(len(case.items)):
            part = next(p for p in parts if seed in p)
            assert np.flatnonzero(coupled_items(case, [seed])).tolist() == list(part)


def test_coupled_problem_refuses_bad_seeds() -> None:
    _, problem = _pile()
    with pytest.raises(InputError, match="seeds: must be indices of the problem's 11 items"):
        coupled_problem(problem, [11])
    with pytest.raises(InputError, match="seeds"):
        coupled_problem(problem, [])


# Two balls fall, one onto a sphere resting on the floor (off centre: it slides, so friction
# acts), one onto the floor; a box rests elsewhere. MuJoCo's friction (1 by default).
SCENE = """<mujoco><option timestep="0.001"/><worldbody>
<geom name="floor" type="plane" size="3 3 .1"/>
<body pos="0 0 0.0999"><freejoint/><geom name="base" size="0.1" mass="2"/></body>
<body pos="0.03 0 0.32"><freejoint/><geom name="ball" size="0.1" mass="0.5"/></body>
<body pos="-1 0 0.13"><freejoint/><geom name="drop" size="0.1" mass="1"/></body>
<body pos="1 0 0.0499"><freejoint/><geom name="box" type="box" size="0.1 0.1 0.05"/></body>
</worldbody></mujoco>"""


def _scene_rollout() -> EnergyAudit:
    """SCENE's two balls dropped, 120 steps audited (no rigid references yet)."""
    model = mujoco.MjModel.from_xml_string(SCENE)
    data = mujoco.MjData(model)
    data.qvel[6 + 2], data.qvel[12 + 2], data.qvel[6] = -2.0, -2.5, 0.3
    audit = EnergyAudit(model, data)
    for _ in range(120):
        mujoco.mj_step(model, data)
        audit.observe()
    return audit


@pytest.mark.parametrize("friction", [None, 0.02, 0.0])  # sticking, slipping, frictionless
def test_the_episodes_coupled_reference_is_the_scenes(friction: float | None) -> None:
    """Each episode of a rollout: the coupled reference's rigid fields and its contacts'
    impulses equal the whole scene's to 1e-10; its E_d is the scene's less what the other
    parts dissipate."""
    audit = _scene_rollout()
    episodes = audit.finish().episodes
    assert {e.pair for e in episodes} >= {("base", "ball"), ("floor", "drop")}
    settings = RigidSettings(restitution=E_N, friction=friction)
    wide = dataclasses.replace(settings, scope="scene")
    checked, regimes = 0, set()
    for episode in episodes:
        mine, scene = audit._with_rigid(episode, settings), audit._with_rigid(episode, wide)
        assert mine.rigid_error == "" and scene.rigid_error == "", episode.pair
        assert len(mine.rigid.contacts) < len(scene.rigid.contacts)
        assert mine.rigid_normal_velocity_after == pytest.approx(
            scene.rigid_normal_velocity_after, rel=0, abs=1e-10)  # fmt: skip
        if mine.rigid_tangential_velocity_after is not None:
            tangential = scene.rigid_tangential_velocity_after
            assert np.allclose(mine.rigid_tangential_velocity_after, tangential, rtol=0, atol=1e-10)
        whole = {o.where: o for o in scene.rigid.contacts}
        ours = {o.where for o in mine.rigid.contacts}
        for o in mine.rigid.contacts:
            assert np.allclose(o.impulse, whole[o.where].impulse, rtol=0, atol=1e-10)
            regimes.add(o.regime)
        others = sum(o.dissipated for w, o in whole.items() if w not in ours)
        assert mine.rigid_dissipated == pytest.approx(scene.rigid_dissipated - others,
                                                      rel=1e-12, abs=1e-12)  # fmt: skip
        checked += 1
    assert checked >= 2
    assert {None: "stick", 0.02: "slip", 0.0: "frictionless"}[friction] in regimes


def test_scope_is_checked_and_reported(tmp_path, capsys) -> None:
    with pytest.raises(InputError, match="scope: must be one of coupled, scene, got 'all'"):
        RigidSettings(scope="all")
    path = tmp_path / "scene.xml"
    path.write_text(SCENE)
    assert main(["audit", str(path), "--duration", "0.05", "--json", "--rigid-scope",
                 "scene"]) == 0  # fmt: skip
    document = json.loads(capsys.readouterr().out)
    assert document["rigid_law"]["scope"] == "scene"
    assert main(["audit", str(path), "--duration", "0.05", "--rigid-scope", "all"]) == 2
    assert "scope: must be one of coupled, scene" in capsys.readouterr().err


def test_a_reused_mjdata_builds_the_same_problem() -> None:
    """``mjcf_problem(..., data=...)`` (the audit's references reuse one MjData): the same
    contacts, Jacobians and mass matrix as with a new MjData, after another state."""
    model = mujoco.MjModel.from_xml_string(PILE)
    data = mujoco.MjData(model)
    qvel = np.zeros(model.nv)
    qvel[2 * 6 + 2] = -V_BALL
    kw = {"restitution": E_N, "resting": True, "qvel": qvel.tolist()}
    shifted = model.qpos0.copy()
    shifted[2] += 0.5  # box A lifted: other contacts
    mjcf_problem(model, qpos=shifted.tolist(), data=data, **kw)
    reused = mjcf_problem(model, qpos=model.qpos0.tolist(), data=data, **kw)
    fresh = mjcf_problem(model, qpos=model.qpos0.tolist(), **kw)
    assert [c.name for c in reused.contacts] == [c.name for c in fresh.contacts]
    for a, b in zip(reused.contacts, fresh.contacts, strict=True):
        assert np.array_equal(a.jacobian, b.jacobian) and np.array_equal(a.point, b.point)
    assert np.array_equal(reused.system.mass_matrix, fresh.system.mass_matrix)
    assert reused.system.coordinates == fresh.system.coordinates


def test_dispersion_coupled_reference_is_the_scenes() -> None:
    """Under the dispersion law (an integration to a tolerance: 1e-9 here) as well: the
    contacts elsewhere (the box resting on four corners, the other ball) are independent
    groups of the law of several contacts, so they cannot change the pair's answer."""
    audit = _scene_rollout()
    settings = RigidSettings(restitution=E_N, friction=0.0, multiple_impact="dispersion")
    wide = dataclasses.replace(settings, scope="scene")
    checked = 0
    for episode in audit.finish().episodes:
        mine, scene = audit._with_rigid(episode, settings), audit._with_rigid(episode, wide)
        assert mine.rigid_error == "" and scene.rigid_error == "", episode.pair
        assert not mine.rigid.warnings and not scene.rigid.warnings
        assert len(mine.rigid.contacts) < len(scene.rigid.contacts)
        assert mine.rigid_normal_velocity_after == pytest.approx(
            scene.rigid_normal_velocity_after, rel=0, abs=1e-9)  # fmt: skip
        whole = {o.where: o for o in scene.rigid.contacts}
        for o in mine.rigid.contacts:
            assert np.allclose(o.impulse, whole[o.where].impulse, rtol=0, atol=1e-9)
        checked += 1
    assert checked >= 2


def test_episodes_in_one_state_share_their_coupled_problem(monkeypatch) -> None:
    """The dm_control humanoid dropped from its own pose: its feet land in one step (four
    episodes, one state), and their coupled problem (the whole robot, one part) is made once
    and solved once; every episode's reference equals the problem made apart for its own pair
    (``mjcf_coupled_problem``) and solved apart, bit for bit."""
    from robots import HUMANOID

    import carnot.model.mjcf as mjcf
    from carnot.rollout import audit_model

    made: list[tuple[str, str]] = []
    make = mjcf.mjcf_coupled_problem

    def counted(model, pair, **kw):
        made.append(pair)
        return make(model, pair, **kw)

    monkeypatch.setattr(mjcf, "mjcf_coupled_problem", counted)
    settings = RigidSettings()
    report = audit_model(HUMANOID, keyframe="drop", duration=0.3, rigid=settings)
    monkeypatch.setattr(mjcf, "mjcf_coupled_problem", make)
    states = [(e.qpos_before.tobytes(), e.qvel_before.tobytes()) for e in report.episodes]
    assert max(states.count(s) for s in states) >= 4  # the feet together
    assert len(made) < len(report.episodes)
    model = mujoco.MjModel.from_xml_path(str(HUMANOID))
    checked = 0
    for episode in report.episodes:
        if episode.rigid is None:
            continue
        apart = make(model, episode.pair, qpos=episode.qpos_before.tolist(),
                     qvel=episode.qvel_before.tolist(), restitution=settings.restitution,
                     law=settings.law, tangential=settings.tangential, resting=True,
                     gap=max(float(np.max(model.geom_margin)), 1e-6))  # fmt: skip
        result = solve_impact(apart)
        assert [c.name for c in apart.contacts] == [c.name for c in episode.rigid.contacts]
        assert episode.rigid.energy.dissipated == result.energy.dissipated
        for ours, theirs in zip(episode.rigid.contacts, result.contacts, strict=True):
            assert np.array_equal(ours.impulse, theirs.impulse)
        checked += 1
    assert checked >= 4

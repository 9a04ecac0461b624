"""The audit's fast routes against the routes they replace (issue 17's 2x benchmark).

* The compiled step (``carnot.rollout.kernel.step_sums``) computes ``M0 v1``, the rows'
  ``J v``, gravity's generalized force and the implicit term itself, from MuJoCo's arrays.
  Each is checked here against MuJoCo's own routines, step by step: ``mj_mulM``,
  ``mj_mulJacVec``, ``mj_jacSubtreeCom`` (gravity's force ``J_com^T M_total g``) and the
  joint damping / ``qDeriv`` that ``mj_EulerSkip`` / ``mj_implicitSkip`` take implicitly
  (``engine_forward.c``, google-deepmind/mujoco), on a sparse Jacobian (60 dofs: ten free
  bodies in contact) and a dense one (a hinge chain and a free body).
* The step reads MuJoCo's moving arrays in place (``carnot.rollout.inplace``, the layout of
  ``mjData`` from ``mujoco.introspect``): the tests above run through it; here its report
  must equal the bindings' route's (every field read as a NumPy view), and a layout that
  puts a field elsewhere must be caught and the audit go on through the bindings.
* The rigid references build only the items coupled to the episode's pair
  (``mjcf_coupled_problem``): the problem and the solution must equal those of the whole
  problem cut to the pair's part (``coupled_problem(mjcf_problem(...))``), on the
  benchmark's ten bodies and on the ball drop, whose ``E_d`` stays the closed form
  ``1/2 m (1 - e^2) v_n^2 + 1/2 m* v_t^2`` (Brach, *Mechanical Impact Dynamics*, Wiley
  1991, ch. 4; Cross, Am. J. Phys. 70, 2002: a sphere sliding without spin that sticks, with
  the lever arm to MuJoCo's contact point).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from carnot.model.coupling import coupled_problem
from carnot.model.mjcf import mjcf_coupled_problem, mjcf_problem
from carnot.rollout import EnergyAudit, RigidSettings
from carnot.solve import solve_impact

BALL = Path(__file__).parent.parent / "examples" / "audit" / "ball_drop.xml"


def _ten_bodies() -> tuple[mujoco.MjModel, mujoco.MjData]:
    """benchmarks/bench_audit.py's scene: ten free spheres and boxes falling on a plane and
    on each other (60 dofs: MuJoCo's sparse constraint Jacobian)."""
    model = mujoco.MjModel.from_xml_path(str(BALL.parent / "ten_bodies.xml"))
    data = mujoco.MjData(model)
    data.qvel[0] = 1.0
    return model, data


CHAIN = """<mujoco><option timestep="0.002" integrator="{integrator}" gravity="0.5 -1.2 -9.81"/>
<worldbody><geom name="table" type="plane" pos="0 0 0.45" size="2 2 .1"/>
<body name="a" pos="0 0 1"><joint type="hinge" axis="0 1 0" damping="0.4"/>
 <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.03" mass="1"/>
 <body pos="0.5 0 0"><joint type="hinge" axis="1 0.3 0" damping="0.2"/>
  <geom type="capsule" fromto="0 0 0 0.3 0.1 -0.3" size="0.02" mass="0.6"/></body></body>
<body name="box" pos="0.6 0.6 0.8"><freejoint/><geom type="box" size="0.1 0.05 0.02" mass="0.5"/>
</body></worldbody></mujoco>"""


def _chain(integrator: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """A damped double pendulum swinging onto a table and a box falling, under a tilted
    gravity (8 dofs: a dense Jacobian, ``M`` coupling the chain's dofs, the lower link's
    centre off its tree's: every term of ``J_b``'s walk matters)."""
    model = mujoco.MjModel.from_xml_string(CHAIN.format(integrator=integrator))
    data = mujoco.MjData(model)
    data.qvel[:] = [4.0, -3.0, 0.5, 0.2, -1.0, 3.0, -5.0, 7.0]
    return model, data


@pytest.mark.parametrize(
    ("make", "integrator", "steps"),
    [(_ten_bodies, None, 600), (_chain, "Euler", 300), (_chain, "implicit", 300)],
)
def test_the_compiled_step_equals_mujocos_own_routines(make, integrator, steps) -> None:
    """Per step, from MuJoCo's calls on the same data: ``1/2 v1^T M0 v1`` (``mj_mulM``),
    the constraints' work ``h/2 f . J (v0 + v1)`` (``mj_mulJacVec``), gravity's ``h/2 M g .
    J_com (v0 + v1)`` (``mj_jacSubtreeCom``) and the implicit ``h/2 (D (v1 - v0)) . (v0 +
    v1)`` (Euler: ``D = -diag(dof_damping)``; implicit: ``qDeriv``, densified by
    ``mju_sparse2dense``)."""
    model, data = make() if integrator is None else make(integrator)
    sparse = bool(mujoco.mj_isSparse(model))
    assert sparse == (make is _ten_bodies)  # both layouts of efc_J are exercised
    h, nv = model.opt.timestep, model.nv
    weight = np.array(model.opt.gravity) * float(np.sum(model.body_mass))
    audit = EnergyAudit(model, data)
    assert audit._params is not None  # the step reads MjData in place (carnot.rollout.inplace)
    expected = {"kinetic_end": [], "constraints": [], "gravity": [], "implicit": []}
    v0 = data.qvel.copy()
    rows = 0
    for _ in range(steps):
        mujoco.mj_step(model, data)
        v1 = data.qvel.copy()
        mv, jac_com = np.zeros(nv), np.zeros((3, nv))
        mujoco.mj_mulM(model, data, mv, v1)
        mujoco.mj_jacSubtreeCom(model, data, jac_com, 0)
        jv = np.zeros(data.nefc)
        if data.nefc:
            mujoco.mj_mulJacVec(model, data, jv, v0 + v1)
        rows += data.nefc
        if integrator == "implicit":
            deriv = np.zeros((nv, nv))
            mujoco.mju_sparse2dense(deriv, data.qDeriv, model.D_rownnz, model.D_rowadr,
                                    model.D_colind)  # fmt: skip
        else:
            deriv = -np.diag(model.dof_damping)
        expected["kinetic_end"].append(0.5 * v1 @ mv)
        expected["constraints"].append(0.5 * h * data.efc_force @ jv)
        expected["gravity"].append(0.5 * h * weight @ jac_com @ (v0 + v1))
        expected["implicit"].append(0.5 * h * (deriv @ (v1 - v0)) @ (v0 + v1))
        audit.observe()
        v0 = v1
    assert rows > 0  # contacts were made
    ledger = audit.finish().steps
    got = {
        "kinetic_end": ledger.kinetic[1:] - ledger.mass_change,
        "constraints": ledger.work["constraints"],
        "gravity": ledger.work["gravity"],
        "implicit": ledger.work["implicit"],
    }
    for key, values in expected.items():
        want = np.array(values)
        scale = max(float(np.max(np.abs(want))), 1e-300)
        assert np.max(np.abs(got[key] - want)) <= 1e-12 * scale, key
    if integrator is not None:
        assert np.max(np.abs(expected["implicit"])) > 0  # the damping did work


def _episodes(model, data, steps: int):
    audit = EnergyAudit(model, data)
    for _ in range(steps):
        mujoco.mj_step(model, data)
        audit.observe()
    return audit.finish().episodes


def _whole_route(model, episode, **kw):
    """The route the coupled builder replaces: the whole problem, cut to the pair's part."""
    problem = mjcf_problem(model, qpos=episode.qpos_before.tolist(),
                           qvel=episode.qvel_before.tolist(), **kw)  # fmt: skip
    g1, g2 = episode.pair
    seeds = [k for k, c in enumerate(problem.contacts) if c.name == f"{g2}/{g1}"]
    return coupled_problem(problem, seeds) if seeds else None


def _assert_same(fast, whole) -> None:
    """The same problem item for item, bit for bit, and the same solution."""
    assert fast.title == whole.title and fast.multiple_impact == whole.multiple_impact
    assert np.array_equal(fast.system.mass_matrix, whole.system.mass_matrix)
    assert np.array_equal(fast.system.velocity, whole.system.velocity)
    assert fast.system.coordinates == whole.system.coordinates
    assert [(c.name, c.where) for c in fast.items] == [(c.name, c.where) for c in whole.items]
    for a, b in zip(fast.contacts, whole.contacts, strict=True):
        assert np.array_equal(a.jacobian, b.jacobian) and np.array_equal(a.normal, b.normal)
        assert np.array_equal(a.point, b.point)
        assert (a.friction, a.restitution, a.law, a.tangential) == (
            b.friction, b.restitution, b.law, b.tangential)  # fmt: skip
    one, other = solve_impact(fast), solve_impact(whole)
    after, reference = one.system.velocity_after, other.system.velocity_after
    assert np.max(np.abs(after - reference)) <= 1e-12 * max(np.max(np.abs(reference)), 1.0)
    assert one.energy.dissipated == pytest.approx(other.energy.dissipated, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("friction", [None, 0.0])
def test_the_coupled_builder_equals_the_whole_problem_cut(friction) -> None:
    """The benchmark's 14 episodes (boxes landing on four corners, spheres, the scene's
    resting contacts beside them), with MuJoCo's friction and frictionless."""
    model, data = _ten_bodies()
    episodes = _episodes(model, data, 1500)
    assert len(episodes) >= 10
    reuse = mujoco.MjData(model)
    kw = {"restitution": 0.5, "friction": friction, "gap": 1e-6, "resting": True}
    built = 0
    for episode in episodes:
        whole = _whole_route(model, episode, **kw)
        state = {"qpos": episode.qpos_before.tolist(), "qvel": episode.qvel_before.tolist()}
        fast = mjcf_coupled_problem(model, episode.pair, data=reuse, **state, **kw)
        assert (fast is None) == (whole is None)
        if fast is not None:
            _assert_same(fast, whole)
            built += 1
    assert built >= 10


def test_the_ball_drop_reference_is_the_closed_form_by_both_routes() -> None:
    """The ball drop's episode: the coupled builder's problem equals the whole route's, and
    the audit's reference E_d the closed form (Brach 1991; Cross 2002)."""
    e = 0.5
    model = mujoco.MjModel.from_xml_path(str(BALL))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    audit = EnergyAudit(model, data, rigid=RigidSettings(restitution=e))
    for _ in range(600):
        mujoco.mj_step(model, data)
        audit.observe()
    (episode,) = audit.finish().episodes[:1]
    kw = {"restitution": e, "gap": 1e-6, "resting": True}
    fast = mjcf_coupled_problem(model, episode.pair, qpos=episode.qpos_before.tolist(),
                                qvel=episode.qvel_before.tolist(), **kw)  # fmt: skip
    _assert_same(fast, _whole_route(model, episode, **kw))
    # it slides without spin and sticks: E_d = 1/2 m (1 - e^2) v_n^2 + 1/2 m* v_t^2, m* = 1 /
    # (1/m + r^2 / I) with the lever arm r to MuJoCo's contact point (mid-overlap; 2/7 m at
    # r = R), as tests/test_audit.py
    v, m, radius = episode.qvel_before, 1.0, 0.1
    lever = episode.qpos_before[2] - episode.point[2]
    m_t = 1 / (1 / m + lever**2 / (0.4 * m * radius**2))
    closed = 0.5 * m * (1 - e**2) * v[2] ** 2 + 0.5 * m_t * v[0] ** 2
    assert episode.rigid_dissipated == pytest.approx(closed, rel=1e-12)
    assert solve_impact(fast).energy.dissipated == pytest.approx(closed, rel=1e-12)


def test_the_coupled_builder_without_the_pair() -> None:
    """A pair with no contact in the problem: no problem (the audit reports no reference)."""
    model, data = _ten_bodies()
    episode = _episodes(model, data, 1500)[0]
    state = {"qpos": episode.qpos_before.tolist(), "qvel": episode.qvel_before.tolist()}
    assert mjcf_coupled_problem(model, ("g8", "g9"), resting=True, **state) is None


def _random_spd(rng, size: int) -> np.ndarray:
    a = rng.normal(size=(size, size))
    return a @ a.T + size * np.eye(size)


def test_a_block_diagonal_mass_matrix_is_inverted_and_checked_by_blocks() -> None:
    """``System`` inverts and checks ``M`` block by block (``diagonal_blocks``): the same
    inverse and eigenvalue test as on the whole matrix (NumPy's ``inv``), on MuJoCo's ``M``
    of the ten bodies and of the chain, a random block-diagonal one, one whose blocks
    interleave (a single block then) and one with an indefinite block (refused)."""
    from scipy.linalg import block_diag

    from carnot import InputError
    from carnot.model.system import System, diagonal_blocks

    rng = np.random.default_rng(7)
    cases = []
    for make in (_ten_bodies, lambda: _chain("Euler")):
        model, data = make()
        mujoco.mj_forward(model, data)
        full = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, full)
        cases.append(0.5 * (full + full.T))
    cases.append(block_diag(*(_random_spd(rng, s) for s in (3, 1, 3, 6, 2, 3))))
    mixed = _random_spd(rng, 4)
    mixed[0, 2:] = mixed[2:, 0] = 0.0  # a pattern that is no run of blocks
    cases.append(mixed)
    for m in cases:
        blocks = diagonal_blocks(m)
        assert sorted(np.concatenate([b.ravel() for b in blocks]).tolist()) == list(range(len(m)))
        inverse = System(mass_matrix=m, velocity=np.zeros(len(m))).mass_matrix_inv
        assert np.max(np.abs(inverse - np.linalg.inv(m))) <= 1e-12 * np.max(np.abs(inverse))
    assert len(diagonal_blocks(cases[-2])) == 4 and len(diagonal_blocks(mixed)) == 1
    bad = block_diag(_random_spd(rng, 3), [[1.0, 2.0], [2.0, 1.0]])  # eigenvalues -1, 3
    with pytest.raises(InputError, match="positive definite"):
        System(mass_matrix=bad, velocity=np.zeros(5))


def _audit(model, data, steps: int, *, in_place: bool, wrong=None):  # type: ignore[no-untyped-def]
    audit = EnergyAudit(model, data)
    if not in_place:
        audit._params = None
    elif wrong is not None:  # a layout that puts a moving field elsewhere
        audit._params[wrong] += 8
    for _ in range(steps):
        mujoco.mj_step(model, data)
        audit.observe()
    return audit, audit.finish()


@pytest.mark.parametrize("make", [_ten_bodies, lambda: _chain("implicit")])
def test_reading_in_place_equals_reading_through_the_bindings(make) -> None:
    """The in-place step and the bindings' route give the same report on the same rollout:
    the ledger (to round-off: ``J v1`` summed in another order than ``mj_mulJacVec``), the
    groups' work, the episodes (pairs, times, velocities, states) exactly."""
    from carnot.rollout.inplace import data_fields

    model, data = make()
    assert data_fields(mujoco, data) is not None
    fast, one = _audit(model, data, 600, in_place=True)
    assert fast._params is not None
    model, data = make()
    _, other = _audit(model, data, 600, in_place=False)
    for key in ("time", "energy", "kinetic", "potential", "mass_change"):
        assert np.array_equal(getattr(one.steps, key), getattr(other.steps, key)), key
    for key, work in one.steps.work.items():
        scale = max(float(np.max(np.abs(other.steps.work[key]))), 1e-300)
        assert np.max(np.abs(work - other.steps.work[key])) <= 1e-13 * scale, key
    assert one.steps.by_constraint.keys() == other.steps.by_constraint.keys()
    for key, work in one.steps.by_constraint.items():
        assert work == pytest.approx(other.steps.by_constraint[key], rel=1e-12, abs=1e-15)
    assert len(one.episodes) == len(other.episodes) > 0
    for a, b in zip(one.episodes, other.episodes, strict=True):
        assert (a.pair, a.start, a.end, a.steps) == (b.pair, b.start, b.end, b.steps)
        assert np.array_equal(a.qpos_before, b.qpos_before)
        assert np.array_equal(a.qvel_before, b.qvel_before)
        assert np.array_equal(a.qvel_after, b.qvel_after)
        assert a.normal_velocity_after == pytest.approx(b.normal_velocity_after, abs=1e-13)
        assert a.contact_work == pytest.approx(b.contact_work, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("field", ["at_efc_force", "at_efc_J", "at_contact", "contact_size"])
def test_a_wrong_layout_is_caught_and_the_bindings_take_over(field) -> None:
    """A moving field put 8 bytes off, or ``sizeof(mjContact)`` 8 bytes more (as another
    MuJoCo's layout might): the check at the first step with rows and contacts sees it, and
    the audit reads through the bindings from then on, its report the same as theirs."""
    from carnot.rollout.inplace import param_index

    model, data = _ten_bodies()
    audit, report = _audit(model, data, 400, in_place=True, wrong=param_index(field))
    assert audit._params is None
    model, data = _ten_bodies()
    _, other = _audit(model, data, 400, in_place=False)
    assert np.array_equal(report.steps.residual, other.steps.residual)
    assert [e.pair for e in report.episodes] == [e.pair for e in other.episodes]


def test_the_two_routes_alternate_within_a_rollout() -> None:
    """Steps recorded through the bindings between steps read in place (as after a layout
    check that fails, or steps fed to ``record``): the same report as one route all along
    (the step count, the state, the open episodes handed over each time)."""
    reports = []
    for mixed in (False, True):
        model, data = _ten_bodies()
        audit = EnergyAudit(model, data)
        for k in range(1500):
            mujoco.mj_step(model, data)
            if mixed and (k // 7) % 3 == 1:
                audit._observe_bound()
            else:
                audit.observe()
        reports.append(audit.finish())
    one, other = reports
    assert one.steps.count == other.steps.count == 1500
    assert np.max(np.abs(one.steps.residual - other.steps.residual)) <= 1e-13
    assert [(e.pair, e.start, e.end) for e in one.episodes] == [
        (e.pair, e.start, e.end) for e in other.episodes]  # fmt: skip
    for a, b in zip(one.episodes, other.episodes, strict=True):
        assert np.array_equal(a.qvel_before, b.qvel_before)
        assert np.array_equal(a.qvel_after, b.qvel_after)


def test_a_mass_matrix_seen_again_is_not_checked_again() -> None:
    """``System`` keeps the last few ``M`` checked and inverted by their bytes: the same
    numbers give the same (read-only) arrays as made anew, NumPy's inverse to 1e-12; one entry
    a unit in the last place off is another matrix; an indefinite one is refused each time."""
    from carnot import InputError
    from carnot.model import system as sy

    model, data = _ten_bodies()
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    m = 0.5 * (full + full.T)
    sy._CHECKED.clear()
    first = sy.System(mass_matrix=m, velocity=np.zeros(model.nv))
    again = sy.System(mass_matrix=m.copy(), velocity=np.ones(model.nv))
    assert again.mass_matrix_inv is first.mass_matrix_inv
    assert not again.mass_matrix_inv.flags.writeable
    inverse = np.linalg.inv(m)
    assert np.max(np.abs(again.mass_matrix_inv - inverse)) <= 1e-12 * np.max(np.abs(inverse))
    nudged = m.copy()
    nudged[0, 0] = np.nextafter(nudged[0, 0], 2 * nudged[0, 0])
    other = sy.System(mass_matrix=nudged, velocity=np.zeros(model.nv))
    assert other.mass_matrix_inv is not first.mass_matrix_inv
    assert other.mass_matrix[0, 0] == nudged[0, 0]
    bad = np.diag([1.0, -1.0])
    for _ in range(2):
        with pytest.raises(InputError, match="positive definite"):
            sy.System(mass_matrix=bad, velocity=np.zeros(2))
    for k in range(sy.CHECKED_KEPT + 2):  # the oldest dropped
        sy.System(mass_matrix=np.eye(2) * (k + 1), velocity=np.zeros(2))
    assert len(sy._CHECKED) == sy.CHECKED_KEPT

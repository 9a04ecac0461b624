"""The general route's shortcuts (carnot.solve, carnot.model.system, carnot.outcome) against
the routes they replace, and the system's report against independent computations.

* ``assemble_system`` makes ``W = C J`` once, while it picks the acting rows; the contact
  space would otherwise derive it block by block from the motion rows: the two must agree
  bit for bit, and the blocks must be those of the public :func:`acting_rows`.
* ``System``'s inverse mass matrix (the diagonal blocks' inverses) against NumPy's inverse of
  the whole matrix.
* The outcome reads every item's ``(w, Omega)`` in one product; item by item
  (``ContactSpace.motion_at``) must give the same to 1e-12.
* A system's outcomes carry ``J^T P + J_ang^T M_P`` (computed here from the user's
  Jacobians), and the generalized momentum balance ``M (q'' - q') = sum J^T P`` and the
  ledger (the theorem against the direct kinetic-energy difference) close to 1e-12.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
import pytest

from carnot import solve_impact
from carnot.io.scenario import load_problem, load_scenario
from carnot.model.mjcf import mjcf_coupled_problem
from carnot.model.system import (
    System,
    SystemContact,
    SystemProblem,
    acting_rows,
    assemble_system,
    motion_rows,
)
from carnot.space import ContactSpace

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

#: Ten free bodies over a plane (benchmarks/bench_audit.py's scene): a 60-coordinate system.
SCENE = EXAMPLES / "audit" / "ten_bodies.xml"


def _mjcf_problems() -> list[SystemProblem]:
    """The box (four corners, Coulomb) and the sphere (one contact) of the scene as they land,
    as an audit builds their references; and the box told to stick, and frictionless."""
    model = mujoco.MjModel.from_xml_path(str(SCENE))
    data = mujoco.MjData(model)
    out = []
    for body, geom in ((0, "g0"), (1, "g1")):
        qpos = np.array(model.qpos0)
        qpos[7 * body + 2] = 0.05 if body == 0 else 0.1  # resting on the floor
        qpos[7 * body + 3 : 7 * body + 7] = [1.0, 0, 0, 0]
        qvel = np.zeros(model.nv)
        qvel[6 * body : 6 * body + 6] = [0.3, -0.2, -1.0, 0.4, 0.2, 0.5]
        problem = mjcf_coupled_problem(model, ("floor", geom), qpos=qpos.tolist(),
                                       qvel=qvel.tolist(), restitution=0.5, gap=1e-3,
                                       resting=True, data=data)  # fmt: skip
        assert problem is not None
        out.append(problem)
    box = out[0]
    assert len(box.contacts) == 4 and len(out[1].contacts) == 1
    for tangential, friction in (("stick", 1.0), ("slip", 0.0)):
        contacts = [SystemContact(jacobian=c.jacobian, normal=c.normal, point=c.point,
                                  restitution=c.restitution, friction=friction,
                                  tangential=tangential, name=c.name, where=c.where)
                    for c in box.contacts]  # fmt: skip
        out.append(replace(box, contacts=contacts))
    return out


def _systems() -> list[SystemProblem]:
    examples = [load_problem(p) for p in sorted((EXAMPLES / "systems").glob("*.toml"))]
    assert len(examples) >= 3 and all(isinstance(p, SystemProblem) for p in examples)
    return [*examples, *_mjcf_problems()]


SYSTEMS = _systems()


@pytest.mark.parametrize("problem", SYSTEMS)
def test_assembled_rows_are_the_derived_ones(problem: SystemProblem) -> None:
    space = assemble_system(problem)
    derived = ContactSpace(u_before=space.u_before, mass_matrix=space.mass_matrix,
                           mass_matrix_inv=space.mass_matrix_inv, motion=space.motion,
                           blocks=space.blocks)  # fmt: skip
    assert np.array_equal(space.jacobian, derived.jacobian)  # bit for bit
    for item, law_item, block in zip(problem.items, problem.law_items, space.blocks,
                                     strict=True):  # fmt: skip
        rows = item.rows() if not isinstance(item, SystemContact) else law_item.rows()
        coulomb = isinstance(item, SystemContact) and law_item.slips_with_friction
        public = acting_rows(rows, motion_rows(item), coulomb)
        assert public.roles == block.roles
        assert np.array_equal(public.linear, block.linear)
        assert np.array_equal(public.angular, block.angular)


@pytest.mark.parametrize("problem", SYSTEMS)
def test_inverse_mass_matrix_against_numpy(problem: SystemProblem) -> None:
    m = problem.system.mass_matrix
    again = System(mass_matrix=m, velocity=problem.system.velocity)
    scale = float(np.max(np.abs(np.linalg.inv(m))))
    assert np.max(np.abs(again.mass_matrix_inv - np.linalg.inv(m))) <= 1e-12 * scale


def _free_body_cases() -> list[object]:
    box = load_scenario(EXAMPLES / "box_lands_flat.toml")
    sliding = replace(box, contacts=[replace(c, friction=0.2) for c in box.contacts])
    return [box, sliding, *(load_scenario(p) for p in sorted(EXAMPLES.glob("*.toml")))]


@pytest.mark.parametrize("problem", [*_free_body_cases(), *SYSTEMS])
def test_outcome_motion_item_by_item(problem: object) -> None:
    from carnot.model.free_bodies import assemble

    result = solve_impact(problem)
    if isinstance(problem, SystemProblem):
        space = assemble_system(problem)
        u_after = result.system.velocity_after
    else:
        items = [*problem.contacts, *problem.constraints]  # type: ignore[attr-defined]
        space = assemble(problem, items, [i.rows() for i in items]).space
        u_after = space.u_before + space.velocity_change(result.row_impulses)
    outcomes = [*result.contacts, *result.constraints]
    scale = float(np.max(np.abs(space.motion @ space.u_before))) + 1e-300
    for index, outcome in enumerate(outcomes):
        for u, w, om in ((space.u_before, outcome.relative_velocity_before,
                          outcome.relative_angular_velocity_before),
                         (u_after, outcome.relative_velocity_after,
                          outcome.relative_angular_velocity_after)):  # fmt: skip
            w_item, om_item = space.motion_at(index, u)
            assert np.max(np.abs(w - w_item)) <= 1e-12 * scale
            assert np.max(np.abs(om - om_item)) <= 1e-12 * scale


@pytest.mark.parametrize("problem", SYSTEMS)
def test_system_report_against_its_jacobians(problem: SystemProblem) -> None:
    result = solve_impact(problem)
    outcomes = [*result.contacts, *result.constraints]
    total = np.zeros(problem.system.size)
    for item, outcome in zip(problem.items, outcomes, strict=True):
        expected = item.jacobian.T @ outcome.impulse
        if item.angular_jacobian is not None:
            expected = expected + item.angular_jacobian.T @ outcome.moment
        assert outcome.b is None and outcome.name == (item.name or "")
        assert np.array_equal(outcome.generalized_impulse, expected)
        total += expected
    system, motion = problem.system, result.system
    assert motion is not None
    du = system.mass_matrix @ (motion.velocity_after - system.velocity)
    scale = float(np.linalg.norm(system.mass_matrix @ system.velocity)) + 1e-300
    assert np.linalg.norm(du - total) <= 1e-12 * scale
    e1 = 0.5 * system.velocity @ system.mass_matrix @ system.velocity
    e2 = 0.5 * motion.velocity_after @ system.mass_matrix @ motion.velocity_after
    assert abs((e1 - e2) - result.energy.dissipated_theorem) <= 1e-12 * e1


def _rows_item_by_item(lever: np.ndarray, linear: np.ndarray, angular: np.ndarray,
                       sign: float) -> np.ndarray:  # fmt: skip
    """The closed form of an item's columns of ``W`` row by row in plain floats, as
    ``assemble`` made them before it made every row at once: ``sign [c_lin, r x c_lin +
    c_ang]``."""
    r = lever.tolist()
    out = []
    for lin, ang in zip(linear.tolist(), angular.tolist(), strict=True):
        cross = [r[1] * lin[2] - r[2] * lin[1], r[2] * lin[0] - r[0] * lin[2],
                 r[0] * lin[1] - r[1] * lin[0]]  # fmt: skip
        turned = [sign * (a + b) for a, b in zip(cross, ang, strict=True)]
        out.append([sign * c for c in lin] + turned)
    return np.array(out).reshape(-1, 6)


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.stem)
def test_free_body_rows_item_by_item(path: Path) -> None:
    from carnot.model.free_bodies import assemble, item_sides

    problem = load_scenario(path)
    items = [*problem.contacts, *problem.constraints]
    fb = assemble(problem, items, [i.rows() for i in items])
    space = fb.space
    for k, (item, block) in enumerate(zip(items, space.blocks, strict=True)):
        expected = np.zeros((block.size, space.u_before.size))
        for name_, sign in zip(item_sides(item), (1.0, -1.0), strict=True):
            if name_ is None or name_ not in fb.columns:
                continue
            lever = block.point - problem.bodies[name_].position_com
            expected[:, fb.columns[name_]] = _rows_item_by_item(lever, block.linear,
                                                                block.angular, sign)  # fmt: skip
        assert np.array_equal(space.jacobian[space.slices[k]], expected)  # bit for bit


def test_diagonal_blocks_against_each_rows_last_entry() -> None:
    """The runs of coordinates from each row's last nonzero column found as the maximum
    over the row's columns (the way it was found before), on random sparsity patterns,
    zero rows included."""
    from carnot.model.system import diagonal_blocks

    rng = np.random.default_rng(7)
    for n in (1, 2, 5, 12, 30):
        for density in (0.0, 0.05, 0.2, 0.6):
            m = np.where(rng.random((n, n)) < density, rng.normal(size=(n, n)), 0.0)
            m = m + m.T
            columns = np.arange(n)
            last = np.max(np.where(m != 0.0, columns, columns[:, None]), axis=1)
            ends = np.flatnonzero(np.maximum.accumulate(last) == columns) + 1
            starts = np.concatenate([[0], ends[:-1]])
            runs = sorted((s, e) for s, e in zip(starts.tolist(), ends.tolist(), strict=True))
            found = sorted((int(b[0]), int(b[-1]) + 1) for bs in diagonal_blocks(m)
                           for b in bs)  # fmt: skip
            assert found == runs

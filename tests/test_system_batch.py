"""The vectorized path over many states of one model (carnot.batch.systems) gives the single
impact's answers (carnot.solve_impact on the same SystemProblem) to 1e-12: double pendulums
in random states, frictionless and sticking, one and two contacts."""

from __future__ import annotations

import numpy as np
import pytest
from chains import Chain

from carnot import solve_impact
from carnot.batch.systems import solve_systems
from carnot.errors import InputError
from carnot.model.system import System, SystemContact, SystemProblem


def _states(count: int, seed: int) -> list[Chain]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        angles = rng.uniform(-np.pi + 0.3, -0.3, 2)
        rates = rng.uniform(-3, 3, 2)
        chain = Chain(
            masses=[1.0, 0.8], lengths=[1.0, 0.7], angles=angles.tolist(), rates=rates.tolist()
        )
        if (chain.jacobian(1, 0.7) @ chain.velocity)[1] < -0.05:  # the tip approaches
            out.append(chain)
    return out


@pytest.mark.parametrize(("stick", "two"), [(False, False), (True, False)])
def test_batch_equals_the_single_path(stick: bool, two: bool) -> None:
    """(Two sticking contacts would hold a 2-coordinate system four times over: the single
    path refuses them as contradictory, rightly.)"""
    chains = _states(60, seed=7 + stick + 2 * two)
    places = [(1, 0.7, 0.4)] + ([(0, 1.0, 0.2)] if two else [])
    normals = np.array([[[0.1, 1.0, 0.0]] * len(places)] * len(chains))
    jac = np.array([[c.jacobian(k, d) for k, d, _ in places] for c in chains])
    e = np.array([e for _, _, e in places])
    batch = solve_systems(
        np.array([c.mass_matrix() for c in chains]),
        np.array([c.velocity for c in chains]),
        jac,
        normals,
        e,
        stick=stick,
    )
    for i, chain in enumerate(chains):
        single = solve_impact(
            SystemProblem(
                system=System(mass_matrix=chain.mass_matrix(), velocity=chain.velocity),
                contacts=[
                    SystemContact(
                        jacobian=chain.jacobian(k, d),
                        normal=normals[i, j],
                        restitution=ee,
                        tangential="stick" if stick else "slip",
                    )
                    for j, (k, d, ee) in enumerate(places)
                ],
            )
        )
        scale = float(np.linalg.norm(chain.velocity))
        assert np.allclose(
            batch.velocity_after[i], single.system.velocity_after, rtol=1e-11, atol=1e-12 * scale
        )
        for j, o in enumerate(single.contacts):
            assert np.allclose(
                batch.impulses[i, j],
                o.impulse,
                rtol=1e-11,
                atol=1e-12 * (1 + float(np.linalg.norm(o.impulse))),
            )
        assert batch.energy_before[i] == pytest.approx(single.energy.before, rel=1e-13)
        assert batch.energy_after[i] == pytest.approx(single.energy.after, rel=1e-10, abs=1e-12)
        assert batch.dissipated_theorem[i] == pytest.approx(
            single.energy.dissipated_theorem, rel=1e-10, abs=1e-12
        )


def test_batch_closes_its_ledger_and_refuses_several_contacts() -> None:
    """An ordinary state's ledger closes (the flag is there for nearly singular ones, as the
    single path's ledger_not_closed); several contacts per state are the simultaneous law's
    (a contact may separate), refused here rather than answered by the equalities."""
    ok = solve_systems(np.eye(2)[None] * 2, np.array([[0.3, -1.0]]),
                       np.array([[[[1.0, 0], [0, 1], [0, 0]]]]), np.array([[[0, 1.0, 0]]]), 0.5)
    assert ok.ledger_not_closed.tolist() == [False] and ok.degenerate.tolist() == [False]
    two = np.array([[[[1.0, 0], [0, 1], [0, 0]], [[1.0, 0], [0, 1], [0, 0]]]])
    with pytest.raises(InputError, match="normals: several contacts per state"):
        solve_systems(np.eye(2)[None] * 2, np.array([[0.3, -1.0]]), two,
                      np.array([[[0, 1.0, 0], [0, 1.0, 0]]]), 0.5)

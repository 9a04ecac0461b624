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


# ------------------------------------------------------------------ Coulomb friction


def _single(mass, rate, jac, normal, e, mu, law):
    return solve_impact(
        SystemProblem(
            system=System(mass_matrix=mass, velocity=rate),
            contacts=[SystemContact(jacobian=jac, normal=normal, restitution=e, friction=mu,
                                    law=law)],
        )
    )  # fmt: skip


@pytest.mark.parametrize("law", ["newton", "poisson", "stronge"])
@pytest.mark.parametrize("mu", [0.2, 0.8])
def test_coulomb_batch_equals_the_single_path_planar(law: str, mu: float) -> None:
    """A double pendulum's tip on a tilted floor with Coulomb friction (slip, slip-stick,
    slip-reversal among the states): the planar slip is exact in both paths (its
    out-of-plane tangent, which no motion reaches, takes the same stand-in), so they agree
    to round-off; regimes and the energy-gain flag (Kane and Levinson's paradox, Newton's
    hypothesis only) are the same."""
    from carnot.batch.coulomb import HYPOTHESIS_ENERGY_GAIN
    from carnot.batch.laws import REGIME_NAMES

    chains = _states(40, seed=3)
    normal = np.array([0.1, 1.0, 0.0]) / np.linalg.norm([0.1, 1.0, 0.0])
    mass = np.array([c.mass_matrix() for c in chains])
    rate = np.array([c.velocity for c in chains])
    jac = np.array([[c.jacobian(1, 0.7)] for c in chains])
    batch = solve_systems(mass, rate, jac, np.broadcast_to(normal, (len(chains), 1, 3)), 0.5,
                          friction=mu, law=law)  # fmt: skip
    assert batch.regime is not None and batch.law_flags is not None
    regimes = set()
    for i in range(len(chains)):
        single = _single(mass[i], rate[i], jac[i, 0], normal, 0.5, mu, law)
        scale = float(np.linalg.norm(rate[i]))
        assert np.allclose(batch.velocity_after[i], single.system.velocity_after, rtol=0,
                           atol=1e-12 * scale)  # fmt: skip
        impulse = single.contacts[0].impulse
        assert np.allclose(batch.impulses[i, 0], impulse, rtol=0,
                           atol=1e-12 * (1 + float(np.linalg.norm(impulse))))  # fmt: skip
        assert batch.dissipated_theorem[i] == pytest.approx(
            single.energy.dissipated_theorem, rel=1e-11, abs=1e-12 * single.energy.before
        )
        regime = REGIME_NAMES[int(batch.regime[i])]
        assert regime == single.contacts[0].regime
        regimes.add(regime)
        gain = any(f.code == "energy_gain" for f in single.warnings)
        assert bool(batch.law_flags[i] & HYPOTHESIS_ENERGY_GAIN) == gain
    assert "slip" in regimes and regimes & {"slip-stick", "slip-reversal"}  # phases that change
    gap = batch.energy_before - batch.energy_after - batch.dissipated_theorem
    assert np.all(np.abs(gap) <= 1e-12 * batch.energy_before)
    assert not np.any(batch.ledger_not_closed)


def test_coulomb_batch_equals_the_single_path_3d() -> None:
    """A rigid body in 6 coordinates (v, omega) striking a rough floor at an offset point,
    with a general inertia: its slip direction turns, which both paths integrate (the batch
    at carnot.batch.coulomb.RTOL = 1e-10, the single engine at 1e-12): equal to that
    tolerance times the velocity scale."""
    rng = np.random.default_rng(5)
    a = rng.normal(size=(3, 3))
    mass = np.zeros((6, 6))
    mass[:3, :3] = 1.5 * np.eye(3)
    mass[3:, 3:] = 0.05 * a @ a.T + 0.02 * np.eye(3)
    states, jacobians = [], []
    for _ in range(20):
        r = rng.normal(size=3) * 0.3
        r[1] = -abs(r[1]) - 0.1
        jac = np.hstack([np.eye(3), -np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]],
                                               [-r[1], r[0], 0]])])  # fmt: skip
        rate = np.concatenate([rng.normal(size=3), 3 * rng.normal(size=3)])
        rate[1] -= max((jac @ rate)[1] + 0.5, 0.0)  # the point approaches the floor
        states.append(rate)
        jacobians.append([jac])
    rates, jacs = np.array(states), np.array(jacobians)
    normals = np.broadcast_to([0.0, 1.0, 0.0], (len(rates), 1, 3))
    batch = solve_systems(np.broadcast_to(mass, (len(rates), 6, 6)), rates, jacs, normals, 0.6,
                          friction=0.4, law="stronge")  # fmt: skip
    for i, rate in enumerate(rates):
        single = _single(mass, rate, jacs[i, 0], normals[i, 0], 0.6, 0.4, "stronge")
        assert np.allclose(batch.velocity_after[i], single.system.velocity_after, rtol=0,
                           atol=1e-9 * float(np.linalg.norm(rate)))  # fmt: skip
    assert np.all(batch.dissipated_theorem > 0)  # Stronge's hypothesis never gains


def test_coulomb_batch_input_errors() -> None:
    one = (np.eye(2)[None] * 2, np.array([[0.3, -1.0]]), np.array([[[[1.0, 0], [0, 1], [0, 0]]]]),
           np.array([[[0, 1.0, 0]]]), 0.5)  # fmt: skip
    with pytest.raises(InputError, match="friction: must be >= 0"):
        solve_systems(*one, friction=-0.1)
    with pytest.raises(InputError, match="law: must be one of newton, poisson, stronge"):
        solve_systems(*one, friction=0.1, law="routh")
    # a point mass landing while sliding, mu = 0.1 (gross slip: P_t = -mu P_n, Brach 1991)
    out = solve_systems(*one, friction=0.1)
    assert out.velocity_after[0].tolist() == pytest.approx([0.3 - 0.1 * 1.5, 0.5], abs=1e-15)

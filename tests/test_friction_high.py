"""High-friction 3D impacts (issue 19, defect 6): slip that settles on an invariant direction.

With a slender light body (one principal moment of inertia far below the other two) striking a
much heavier one, ``K_tt`` is nearly singular and, for mu of 2 to 10, the slip direction
relaxes quickly onto an attracting invariant direction along which ``|w_t|`` then changes a
thousand times more slowly (Stronge, *Impact Mechanics*, 2000, section 5.2: invariant
directions of 3D slip). The explicit integrator used to creep along at its stability limit
until it gave up ("the 3D slip integration did not converge", 6.7 % of such impacts); it now
finishes that stretch in closed form (``slip3d.SETTLED``). Checked by independent routes: the
theorem against the direct kinetic-energy difference, the contact works ``-(W_n + W_t)``
against the same, and SciPy's implicit Radau integrator against our stop.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.stats import special_ortho_group

from carnot import ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.cli import main
from carnot.io.scenario import load_scenario
from carnot.laws.friction import ImpactJamError

DATA = Path(__file__).parent / "data" / "reliability"
REPROS = sorted(DATA.glob("slip3d_nonconv_*.toml"))


def _check_ledger(result) -> None:
    """Theorem = direct difference = contact works, to round-off of the energies involved."""
    e = result.energy
    scale = e.before + e.after
    assert abs(e.dissipated - e.dissipated_theorem) <= 1e-9 * scale
    process = result.contacts[0].process
    works = -(process.work_normal + process.work_tangential)
    assert abs(works - e.dissipated) <= 1e-9 * scale
    assert np.all(np.isfinite(result.row_impulses))


@pytest.mark.parametrize("path", REPROS, ids=lambda p: p.stem)
def test_the_reported_high_friction_impacts_solve(path: Path) -> None:
    assert len(REPROS) == 3
    result = solve_impact(load_scenario(path))
    _check_ledger(result)
    assert result.contacts[0].process.friction >= 2


@pytest.mark.parametrize("path", REPROS, ids=lambda p: p.stem)
def test_the_cli_solves_them(path: Path, capsys) -> None:
    assert main(["solve", str(path), "--json"]) == 0
    assert capsys.readouterr().err == ""


def test_the_stop_agrees_with_an_implicit_integrator() -> None:
    """The slip phase of slip3d_nonconv_7_107 integrated again by SciPy's Radau (implicit,
    so the stiff relaxation of the direction costs it nothing): Radau halts where ``w_t``
    reaches 0 (the field is singular there), which must be our stop; the tangential work up
    to it must agree too."""
    result = solve_impact(load_scenario(DATA / "slip3d_nonconv_7_107.toml"))
    process = result.contacts[0].process
    assert process.regime == "slip-stick"
    slip = process.phases[0]
    k, w0, mu = process.k, process.w_before, process.friction

    def field(p: float, y: np.ndarray) -> np.ndarray:
        s = y[:2] / np.linalg.norm(y[:2])
        rate = k[1:, 0] - mu * k[1:, 1:] @ s
        return np.concatenate([rate, -mu * s, [-mu * np.linalg.norm(y[:2])]])

    sol = solve_ivp(field, (0.0, 10 * slip.end), np.concatenate([w0[1:], [0.0, 0.0, 0.0]]),
                    method="Radau", rtol=1e-11, atol=1e-14 * np.linalg.norm(w0))  # fmt: skip
    assert np.linalg.norm(sol.y[:2, -1]) <= 1e-9 * np.linalg.norm(w0)  # it reached the stop
    assert sol.t[-1] == pytest.approx(slip.end, rel=1e-9)
    at_stop = process.samples[np.argmin(np.abs(process.samples[:, 0] - slip.end))]
    assert at_stop[0] == pytest.approx(slip.end, rel=1e-12)
    assert at_stop[5] == pytest.approx(sol.y[4, -1], rel=1e-8)


def _random_body(rng: np.random.Generator, name: str, light: bool) -> RigidBody:
    mass = 10 ** rng.uniform(-1, 1) if light else 10 ** rng.uniform(-1, 11)
    if rng.uniform() < 0.7:  # slender: one principal moment far below the other two
        eps = 10 ** rng.uniform(-6, -1)
        moments = np.array([eps, 1.0, 1.0 + eps * rng.uniform()])
    else:
        moments = np.sort(10 ** rng.uniform(-3, 0, 3))
        moments[2] = min(moments[2], moments[0] + moments[1])
    rot = special_ortho_group.rvs(3, random_state=rng)
    inertia = rot @ np.diag(moments) @ rot.T * mass * rng.uniform(0.1, 3) ** 2
    return RigidBody(name=name, mass=mass, inertia_com=inertia,
                     position_com=rng.uniform(-1.5, 1.5, 3), velocity_com=rng.normal(0, 5, 3),
                     angular_velocity=rng.normal(0, 3, 3))  # fmt: skip


def test_random_high_friction_impacts_all_solve() -> None:
    """300 random two-body impacts, mu in [1, 10], the three hypotheses in turn (fixed seed;
    the old integrator refused about 20 of them). Every one solves, with the ledger closed by
    all three routes."""
    rng = np.random.default_rng(2026)
    regimes: dict[str, int] = {}
    for i in range(300):
        a, b = _random_body(rng, "A", True), _random_body(rng, "B", False)
        normal = rng.normal(size=3)
        point = rng.uniform(-1.5, 1.5, 3)
        if (a.velocity_of_point(point) - b.velocity_of_point(point)) @ normal > 0:
            normal = -normal  # approaching
        contact = PointContact(a="A", b="B", point=point, normal=normal,
                               restitution=rng.uniform(0, 1),
                               law=("newton", "poisson", "stronge")[i % 3],
                               friction=rng.uniform(1, 10))  # fmt: skip
        try:
            result = solve_impact(ImpactProblem(bodies={"A": a, "B": b}, contacts=[contact]))
        except ImpactJamError:  # pragma: no cover - none in this sample; a jam is physics
            regimes["jam"] = regimes.get("jam", 0) + 1
            continue
        _check_ledger(result)
        regime = result.contacts[0].regime
        regimes[regime] = regimes.get(regime, 0) + 1
    assert "jam" not in regimes
    assert regimes.get("slip-stick", 0) > 100 and regimes.get("slip", 0) > 50


@pytest.mark.parametrize("path", REPROS, ids=lambda p: p.stem)
def test_the_batch_kernel_agrees(path: Path) -> None:
    """A second implementation: the batch kernel's Coulomb law (carnot.batch.coulomb, the slip
    on its polar form, its own settling test) through a one-row sweep, against solve_impact."""
    from carnot.io.scenario import read_scenario_data
    from carnot.sweep import make_plan, prepare_sweep

    data = read_scenario_data(path)
    mu = data["contacts"][0]["friction"]
    sweep = prepare_sweep(data, make_plan(vary=[f"contacts.0.friction={mu!r}:{mu!r}:1"]),
                          compiled=True)
    assert sweep.route == "batch"
    row = sweep.chunk(0, 1, parallel=False).columns
    contact = solve_impact(load_scenario(path)).contacts[0]
    batch = np.array([row[f"contacts.0.impulse_{x}"][0] for x in "xyz"])
    # the batch kernel integrates at RTOL 1e-10, over slip phases thousands of impulse scales
    # long here: agreement to 1e-7 (seen: 3e-8 to 7e-8), against 1e-14 for Radau above
    assert np.linalg.norm(batch - contact.impulse) <= 1e-6 * np.linalg.norm(contact.impulse)
    assert row["error"][0] == 0

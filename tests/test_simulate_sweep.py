"""Sweeps of simulations (carnot sweep on a [simulation] scenario): a rocking block's
overturning map under one-sine ground pulses, against published results.

Sources:
- G. W. Housner, "The behavior of inverted pendulum structures during earthquakes", Bull.
  Seismol. Soc. Am. 53 (1963) 403-417: the rocking equation of a rigid block about its
  corners, ``theta'' = -p^2 [sgn(theta) sin(alpha - |theta|) - (a_g/g) cos(alpha - |theta|)]``
  with ``p^2 = 3 g / (4 R)`` for a rectangle, the angular velocity ratio
  ``r = 1 - 3/2 sin^2 alpha`` at each impact (so each impact keeps ``r^2`` of the kinetic
  energy), and the uplift condition: a block at rest starts rocking when the ground
  acceleration exceeds ``g tan alpha`` (also N. Makris and Y. Roussos, Geotechnique 50 (2000)
  243-262).
- J. Zhang and N. Makris, "Rocking response of free-standing blocks under cycloidal pulses",
  J. Eng. Mech. 127 (2001) 473-483: the type-A (one-sine) pulse ``a_g = a_p sin(w_p t)`` on
  ``[0, 2 pi / w_p]``, and the overturning map over ``a_p`` and ``w_p`` that a sweep
  draws; here each point is checked against Housner's equation integrated independently
  (scipy's solve_ivp, with the pulse's own formula).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from carnot.cli import main
from carnot.io.scenario import read_scenario_data
from carnot.io.sweep_files import read_sweep
from carnot.sweep import make_plan, prepare_sweep, run_sweep

pytest.importorskip("pyarrow")

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "simulate" / "rocking_overturning_map.toml"
G = 9.81
B, H = 0.1, 0.5  # half width and half height of the example's block (m)
ALPHA = math.atan(B / H)
R = math.hypot(B, H)
P2 = 3 * G / (4 * R)
RATIO = 1 - 1.5 * math.sin(ALPHA) ** 2


def _scenario(duration: float) -> dict:
    data = read_scenario_data(EXAMPLE)
    data["simulation"]["duration"] = duration
    return data


def _columns(path: Path) -> dict[str, np.ndarray]:
    table = read_sweep(path)
    return {n: table.column(n).to_numpy(zero_copy_only=False) for n in table.column_names}


def _housner(amplitude: float, period: float, duration: float) -> tuple[bool, float, int]:
    """Housner's equation under the one-sine pulse: (overturned, max |theta|, impacts).
    Overturned: |theta| reaches pi/2 (the block lies on its side) or ends past alpha."""
    w = 2 * math.pi / period

    def a_g(t: float) -> float:
        return amplitude * math.sin(w * t) if t <= period else 0.0

    def rhs(t: float, y: np.ndarray) -> list[float]:
        th = y[0]
        s = math.copysign(1.0, th) if th != 0 else math.copysign(1.0, a_g(t))
        u = ALPHA - abs(th)
        return [y[1], -P2 * (s * math.sin(u) - a_g(t) / G * math.cos(u))]

    def crossing(_t: float, y: np.ndarray) -> float:
        return y[0]

    def fallen(_t: float, y: np.ndarray) -> float:
        return abs(y[0]) - math.pi / 2

    crossing.terminal = True  # type: ignore[attr-defined]
    fallen.terminal = True  # type: ignore[attr-defined]
    # at rest until |a_g| = g tan alpha (the sine's first crossing of it)
    t = math.asin(G * math.tan(ALPHA) / amplitude) / w
    y = [math.copysign(1e-300, amplitude), 0.0]  # leaving theta = 0 is not an impact
    top, impacts = 0.0, 0
    while t < duration:
        sol = solve_ivp(rhs, (t, duration), y, events=(crossing, fallen), rtol=1e-11,
                        atol=1e-13, max_step=period / 64)  # fmt: skip
        top = max(top, float(np.max(np.abs(sol.y[0]))))
        if sol.status == 0:
            return abs(sol.y[0, -1]) > ALPHA, top, impacts
        if len(sol.t_events[1]):
            return True, top, impacts
        t = float(sol.t_events[0][0])
        rate = float(sol.y_events[0][0][1])
        impacts += 1
        y = [math.copysign(1e-300, rate), RATIO * rate]
    return abs(y[0]) > ALPHA, top, impacts


def test_uplift_starts_at_g_tan_alpha(tmp_path) -> None:
    """A pulse whose peak is 1 % below g tan alpha leaves the block standing (nothing moves:
    no event after the start, no tilt); 1 % above, a corner lifts (Housner 1963)."""
    threshold = G * B / H
    data = _scenario(0.6)
    data["simulation"]["ground_pulse"]["period"] = 0.5
    plan = make_plan(vary=[f"simulation.ground_pulse.amplitude={0.99 * threshold}:"
                           f"{1.01 * threshold}:2"])  # fmt: skip
    sweep = prepare_sweep(data, plan, str(EXAMPLE), ["uplift", "max_tilt", "impacts"])
    report = run_sweep(sweep, tmp_path / "uplift.parquet", workers=1)
    cols = _columns(tmp_path / "uplift.parquet")
    assert report.route == "simulate" and report.rows == 2 and report.failed == 0
    assert cols["bodies.block.uplift"].tolist() == [False, True]
    assert cols["bodies.block.max_tilt"][0] <= 1e-12 < cols["bodies.block.max_tilt"][1]
    assert set(cols) == {"simulation.ground_pulse.amplitude", "impacts", "bodies.block.uplift",
                         "bodies.block.max_tilt", "warnings", "error"}  # fmt: skip


def test_overturning_map_against_housners_equation(tmp_path) -> None:
    """A small map over amplitude and period: overturned or not, the number of rocking
    impacts and the largest tilt as Housner's equation gives them; every impact keeps
    r^2 of the kinetic energy; E_d by the theorem equals the direct difference; the ledger
    closes."""
    duration = 2.5
    plan = make_plan(vary=["simulation.ground_pulse.amplitude=3:6:2",
                           "simulation.ground_pulse.period=0.3:0.9:2"])  # fmt: skip
    sweep = prepare_sweep(_scenario(duration), plan, str(EXAMPLE))
    run_sweep(sweep, tmp_path / "map.parquet", workers=1)
    cols = _columns(tmp_path / "map.parquet")
    assert not cols["error"].astype(bool).any()
    seen = set()
    for j in range(len(cols["error"])):
        amp = cols["simulation.ground_pulse.amplitude"][j]
        per = cols["simulation.ground_pulse.period"][j]
        over, top, impacts = _housner(amp, per, duration)
        # a decision away from the boundary: the same 1 % either side of this amplitude
        assert _housner(0.99 * amp, per, duration)[0] == over == _housner(1.01 * amp, per,
                                                                          duration)[0]
        seen.add(over)
        assert bool(cols["bodies.block.overturned"][j]) == over
        assert bool(cols["bodies.block.uplift"][j])
        if not over:
            assert cols["impacts"][j] == impacts
            # sampled at every integrator step: the peak between two samples is missed by
            # at most the curvature over a step
            assert cols["bodies.block.max_tilt"][j] == pytest.approx(top, rel=2e-3)
            assert cols["impact_energy_ratio_min"][j] == pytest.approx(RATIO**2, abs=1e-8)
            assert cols["impact_energy_ratio_max"][j] == pytest.approx(RATIO**2, abs=1e-8)
        else:  # lying on its side: its centre of mass B above the ground
            assert cols["bodies.block.final_position_y"][j] == pytest.approx(B, abs=1e-8)
        assert cols["energy_impacts_theorem"][j] == pytest.approx(cols["energy_impacts"][j],
                                                                  rel=1e-9, abs=1e-9)
        assert abs(cols["energy_residual"][j]) <= 1e-8 * cols["energy_initial"][j]
    assert seen == {True, False}  # the map has both sides


def test_processes_threads_and_dask_write_the_same_file(tmp_path) -> None:
    from distributed import Client, LocalCluster

    data = _scenario(0.8)
    plan = make_plan(vary=["simulation.ground_pulse.amplitude=2.5:5:3"])
    sweep = prepare_sweep(data, plan, str(EXAMPLE), ["impacts,uplift", "energy_final"])
    one = run_sweep(sweep, tmp_path / "one.parquet", workers=1, chunk_size=1)
    two = run_sweep(sweep, tmp_path / "two.parquet", workers=2, chunk_size=1)
    assert one.runner == "threads(1)" and two.runner == "processes(2)"
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster, Client(cluster) as client:  # fmt: skip
        run_sweep(sweep, tmp_path / "dask.parquet", client=client, chunk_size=2)
    ref = _columns(tmp_path / "one.parquet")
    for name in ("two", "dask"):
        other = _columns(tmp_path / f"{name}.parquet")
        assert other.keys() == ref.keys()
        for key, values in ref.items():
            np.testing.assert_array_equal(other[key], values)


def test_cli_sweep_of_a_simulation(tmp_path, capsys) -> None:
    out = tmp_path / "map.csv"
    path = tmp_path / "block.toml"
    path.write_text(EXAMPLE.read_text().replace("duration = 4.0", "duration = 0.3"))
    assert main(["sweep", str(path), "--vary", "simulation.ground_pulse.amplitude=1:3:2",
                 "--record", "uplift", "--out", str(out), "--workers", "1"]) == 0
    assert "2 simulations ->" in capsys.readouterr().out
    assert out.read_text().splitlines()[0] == (
        '"simulation.ground_pulse.amplitude","bodies.block.uplift","warnings","error"')


@pytest.mark.parametrize("args, message", [
    (["--record", "angle"], "--record: must name quantities of a simulation"),
    (["--vary", "simulation.ground_pulse.period=-1:1:2"],
     "simulation.ground_pulse.period: must be > 0, got -1.0"),
    (["--vary", "bodies.block.position.1=0:0.5:2"], "bodies.block.position: starts inside"),
    (["--vary", "simulation.ground_pulse.width=0:1:2"], "has no 'width'"),
])  # fmt: skip
def test_bad_sweeps_of_simulations_exit_2_with_one_line(args, message, tmp_path,
                                                        capsys) -> None:  # fmt: skip
    argv = ["sweep", str(EXAMPLE), "--out", str(tmp_path / "x.csv")]
    if "--vary" not in args:
        argv += ["--vary", "simulation.ground_pulse.amplitude=1:3:2"]
    assert main(argv + args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err


def test_record_goes_with_simulations_only(tmp_path, capsys) -> None:
    argv = ["sweep", str(ROOT / "examples" / "ball_on_floor.toml"), "--vary",
            "contacts.0.restitution=0:1:2", "--record", "impacts", "--out",
            str(tmp_path / "x.csv")]  # fmt: skip
    assert main(argv) == 2
    assert "--record: goes with a simulation scenario" in capsys.readouterr().err

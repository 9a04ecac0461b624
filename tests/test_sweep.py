"""Sweeps (carnot.sweep, carnot sweep): plans, the two routes, files, Dask, plots, bad input."""

from __future__ import annotations

import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from carnot.cli import main
from carnot.errors import InputError
from carnot.io.scenario import parse_scenario, read_scenario_data
from carnot.io.sweep_files import read_sweep
from carnot.solve import solve_impact
from carnot.sweep import (
    RANDOM_BLOCK,
    chunk_bounds,
    make_plan,
    prepare_sweep,
    run_sweep,
    sweep_file,
)

ROOT = Path(__file__).resolve().parent.parent
BALL = ROOT / "examples" / "ball_on_floor.toml"
BILLIARDS = ROOT / "examples" / "two_billiard_balls.toml"

ROUGH_ROD = """
format = 1
title = "Rod on a rough floor"
[bodies.rod]
mass = 1.0
shape = "rod"
length = 1.0
radius = 0.01
axis = [0.7071, 0.0, 0.7071]
position = [0.35355, 0.0, 0.35355]
velocity = [1.0, 0.0, -1.0]
[bodies.floor]
fixed = true
[[contacts]]
a = "rod"
b = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
restitution = 0.5
friction = 0.3
"""

STICK_BOX = """
format = 1
[bodies.box]
mass = 2.0
inertia = [[0.02, 0.0, 0.0], [0.0, 0.03, 0.0], [0.0, 0.0, 0.04]]
position = [0.1, 0.05, 0.2]
velocity = [0.5, -0.2, -2.0]
angular_velocity = [1.0, 0.5, -0.3]
[bodies.floor]
fixed = true
[[contacts]]
a = "box"
b = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
restitution = 0.4
tangential = "stick"
friction = 0.8
"""


def _sweep(path: Path | str, **plan):  # type: ignore[no-untyped-def]
    # the compiled routes where the scenario fits them, whatever the rows (the tests' sweeps
    # are small: the uncompiled threshold would send them all to the solve_impact loop)
    return prepare_sweep(read_scenario_data(path), make_plan(**plan), str(path), compiled=True)


def _columns(table) -> dict[str, np.ndarray]:  # type: ignore[no-untyped-def]
    return {n: table.column(n).to_numpy(zero_copy_only=False) for n in table.column_names}


# --- plans -------------------------------------------------------------------------------------


def test_grid_rows_are_the_product_first_key_slowest() -> None:
    plan = make_plan(vary=["contacts.0.restitution=0:1:3", "bodies.ball.velocity.2=-1:-2:2"])
    values = plan.values(0, plan.rows)
    assert plan.rows == 6
    assert values["contacts.0.restitution"].tolist() == [0, 0, 0.5, 0.5, 1, 1]
    assert values["bodies.ball.velocity.2"].tolist() == [-1, -2, -1, -2, -1, -2]


def test_count_one_and_a_range_that_runs_down() -> None:
    plan = make_plan(vary=["contacts.0.restitution=0.9:0.1:5", "bodies.ball.mass=2:9:1"])
    values = plan.values(0, plan.rows)
    assert np.allclose(values["contacts.0.restitution"], [0.9, 0.7, 0.5, 0.3, 0.1])
    assert values["bodies.ball.mass"].tolist() == [2.0] * 5


@pytest.mark.parametrize("chunk", [1, 7, 1000, RANDOM_BLOCK - 1, RANDOM_BLOCK + 3])
def test_monte_carlo_values_do_not_depend_on_the_chunks(chunk: int) -> None:
    plan = make_plan(random=["contacts.0.restitution=uniform(0.2, 0.9)",
                             "bodies.ball.velocity.2=truncnorm(-3, 1, -5, -0.5)"],
                     samples=RANDOM_BLOCK + 500, seed=7)  # fmt: skip
    whole = plan.values(0, plan.rows)
    bounds = chunk_bounds(plan.rows, chunk)
    if len(bounds) > 40:  # a sample of the chunks, the last one among them
        bounds = bounds[:20] + bounds[-20:]
    for start, stop in bounds:
        part = plan.values(start, stop)
        for key in whole:
            np.testing.assert_array_equal(part[key], whole[key][start:stop])
    e = whole["contacts.0.restitution"]
    assert 0.2 <= e.min() and e.max() <= 0.9 and abs(e.mean() - 0.55) < 0.01
    v = whole["bodies.ball.velocity.2"]
    assert -5 <= v.min() and v.max() <= -0.5


def test_seeds_and_distributions() -> None:
    def draw(spec: str, seed: int = 0) -> np.ndarray:
        plan = make_plan(random=[f"bodies.ball.mass={spec}"], samples=20000, seed=seed)
        return plan.values(0, plan.rows)["bodies.ball.mass"]

    assert not np.array_equal(draw("uniform(1, 2)", 0), draw("uniform(1, 2)", 1))
    np.testing.assert_array_equal(draw("uniform(1, 2)", 3), draw("uniform(1, 2)", 3))
    normal = draw("normal(5, 0.5)")
    assert abs(normal.mean() - 5) < 0.02 and abs(normal.std() - 0.5) < 0.02
    logn = draw("lognormal(0, 0.25)")
    assert logn.min() > 0 and abs(np.log(logn).std() - 0.25) < 0.01
    logu = draw("loguniform(0.01, 100)")
    assert 0.01 <= logu.min() and logu.max() <= 100 and abs(np.log10(logu).mean()) < 0.05
    tail = draw("truncnorm(0, 1, 4, 5)")  # far in the upper tail: the mirrored inverse
    assert 4 <= tail.min() and tail.max() <= 5 and tail.mean() < 4.3


def test_grid_and_random_combine_with_common_random_numbers() -> None:
    plan = make_plan(vary=["contacts.0.restitution=0:1:3"],
                     random=["bodies.ball.velocity.0=normal(0, 1)"], samples=4, seed=2)  # fmt: skip
    values = plan.values(0, plan.rows)
    assert plan.rows == 12
    assert values["contacts.0.restitution"].tolist() == [0.0] * 4 + [0.5] * 4 + [1.0] * 4
    v = values["bodies.ball.velocity.0"].reshape(3, 4)
    assert np.array_equal(v[0], v[1]) and np.array_equal(v[0], v[2])  # the same draws


# --- the two routes against solve_impact --------------------------------------------------------


def _problem_of_row(path: Path | str, sweep, values: dict[str, float]):  # type: ignore[no-untyped-def]
    """The scenario with a row's values written into its data, parsed: the second route."""
    import copy

    data = copy.deepcopy(read_scenario_data(path))
    for key, value in values.items():
        node = data
        parts = [int(p) if p.isdigit() else p for p in key.split(".")]
        for part in parts[:-1]:
            node = node.setdefault(part, [0.0, 0.0, 0.0]) if isinstance(node, dict) else node[part]
        node[parts[-1]] = value
        if parts[2] == "inertia":
            data["bodies"][parts[1]]["inertia"][parts[4]][parts[3]] = value
    return parse_scenario(data, str(path))


@pytest.mark.parametrize(
    ("scenario", "plan"),
    [
        (BALL, {"vary": ["contacts.0.restitution=0:1:6", "bodies.ball.velocity.2=-0.5:-4:5",
                         "bodies.ball.mass=0.1:3:3"]}),
        (BILLIARDS, {"random": ["contacts.0.normal.1=uniform(-0.9, -0.1)",
                                "bodies.B.velocity.0=normal(0, 0.5)",
                                "bodies.A.angular_velocity.2=uniform(-20, 20)"],
                     "samples": 300, "seed": 11}),
        ("stick", {"vary": ["bodies.box.inertia.0.1=-0.005:0.005:5",
                            "contacts.0.point.0=-0.05:0.05:4"],
                   "random": ["bodies.box.angular_velocity.2=uniform(-5, 5)"], "samples": 6}),
    ],
    ids=["ball-grid", "billiards-monte-carlo", "stick-inertia-mixed"],
)  # fmt: skip
def test_every_sampled_row_matches_solve_impact(scenario, plan, tmp_path) -> None:  # type: ignore[no-untyped-def]
    if scenario == "stick":
        scenario = tmp_path / "box.toml"
        scenario.write_text(STICK_BOX)
    sweep = _sweep(scenario, **plan)
    assert sweep.route == "batch"
    run_sweep(sweep, tmp_path / "out.parquet", chunk_size=37)
    cols = _columns(read_sweep(tmp_path / "out.parquet"))
    assert len(cols["dissipated"]) == sweep.rows
    # the theorem against the direct difference, every row
    np.testing.assert_allclose(cols["dissipated_theorem"], cols["dissipated"],
                               rtol=1e-9, atol=1e-12 * cols["energy_before"].max())  # fmt: skip
    rows = np.random.default_rng(0).choice(sweep.rows, size=min(25, sweep.rows), replace=False)
    for row in rows:
        values = {k: float(cols[k][row]) for k in sweep.plan.keys}
        result = solve_impact(_problem_of_row(scenario, sweep, values))
        out = result.contacts[0]
        scale = float(np.abs(out.impulse).max()) + 1e-300
        for i, x in enumerate("xyz"):
            assert cols[f"contacts.0.impulse_{x}"][row] == pytest.approx(
                out.impulse[i], abs=1e-10 * scale
            )
        assert cols["contacts.0.regime"][row] == out.regime
        for name, motion in result.bodies.items():
            if motion.fixed:
                continue
            for i, x in enumerate("xyz"):
                assert cols[f"bodies.{name}.velocity_after_{x}"][row] == pytest.approx(
                    motion.velocity_after[i], rel=1e-9, abs=1e-9
                )
                assert cols[f"bodies.{name}.angular_velocity_after_{x}"][row] == pytest.approx(
                    motion.angular_velocity_after[i], rel=1e-9, abs=1e-8)  # fmt: skip
        e = result.energy
        for col, ref in (
            ("energy_before", e.before),
            ("energy_after", e.after),
            ("dissipated", e.dissipated),
            ("lost_velocities", e.lost_velocities),
        ):
            assert cols[col][row] == pytest.approx(ref, rel=1e-9, abs=1e-12 * e.before)
        codes = result.flag_codes()
        for flag in ("not_approaching", "negative_normal_impulse", "friction_insufficient"):
            assert bool(cols[flag][row]) == (flag in codes)


def test_the_solve_route_gives_the_batch_route_s_rows(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Both routes over the same rows (the solve route forced on a batch scenario)."""
    import dataclasses

    sweep = _sweep(BILLIARDS, vary=["contacts.0.restitution=0:1:4"],
                   random=["bodies.B.velocity.1=uniform(-1, 1)"], samples=5)  # fmt: skip
    batch = sweep.chunk(0, sweep.rows)
    solve = dataclasses.replace(sweep, route="solve").chunk(0, sweep.rows)
    assert (batch.route, solve.route) == ("batch", "solve")
    for col in sweep.columns:
        a, b = batch.columns[col.name], solve.columns[col.name]
        if col.kind == "category":
            names_a = [batch.categories[col.name][k] for k in a]
            names_b = [solve.categories[col.name][k] for k in b]
            assert names_a == names_b, col.name
        elif col.kind == "bool":
            assert a.tolist() == b.tolist(), col.name
        else:
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-10, equal_nan=True,
                                       err_msg=col.name)  # fmt: skip


def test_coulomb_friction_in_the_batch_route(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """A rough rod: Coulomb slip, stop, stick and reversal run in the batch kernel, and every
    row checked equals carnot.solve_impact's (the other route), regime names included."""
    scenario = tmp_path / "rod.toml"
    scenario.write_text(ROUGH_ROD)
    sweep = _sweep(scenario, vary=["contacts.0.friction=0:0.9:4",
                                   "bodies.rod.velocity.0=-1.5:1.5:3"])  # fmt: skip
    assert sweep.route == "batch"
    report = run_sweep(sweep, tmp_path / "rod.csv", workers=2, chunk_size=5)
    assert (report.rows, report.chunks, report.route) == (12, 3, "batch")
    table = read_sweep(tmp_path / "rod.csv")
    regimes = table.column("contacts.0.regime").to_pylist()
    assert regimes[:3] == ["frictionless"] * 3 and len(set(regimes)) >= 3
    for row in range(12):
        values = {k: table.column(k)[row].as_py() for k in sweep.plan.keys}
        ref = solve_impact(_problem_of_row(scenario, sweep, values))
        assert table.column("dissipated")[row].as_py() == pytest.approx(ref.energy.dissipated)
        assert regimes[row] == ref.contacts[0].regime
        flags = set((table.column("warnings")[row].as_py() or "").split(",")) - {""}
        assert flags == set(ref.flag_codes()), row


def test_several_contacts_and_constraints_take_the_solve_route(tmp_path, example_path) -> None:  # type: ignore[no-untyped-def]
    path = example_path("paper_fasten_plate.toml")
    data = read_scenario_data(path)
    body = next(n for n, b in data["bodies"].items() if not b.get("fixed"))
    sweep = _sweep(path, vary=[f"bodies.{body}.velocity.2=-1:-2:3"])
    assert sweep.route == "solve"
    run_sweep(sweep, tmp_path / "p.parquet")
    table = read_sweep(tmp_path / "p.parquet")
    assert table.num_rows == 3 and "constraints.0.impulse_x" in table.column_names


# --- running: threads, Dask, files -----------------------------------------------------------


def test_threads_chunk_sizes_and_dask_write_the_same_file(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from distributed import Client, LocalCluster

    sweep = _sweep(BALL, vary=["contacts.0.restitution=0:1:7"], samples=300, seed=5,
                   random=["bodies.ball.velocity.2=uniform(-4, -1)"])  # fmt: skip
    run_sweep(sweep, tmp_path / "one.parquet", workers=1)
    run_sweep(sweep, tmp_path / "threads.parquet", workers=2, chunk_size=97)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                      dashboard_address=None) as cluster, Client(cluster) as client:  # fmt: skip
        report = run_sweep(sweep, tmp_path / "dask.parquet", client=client, chunk_size=256)
    assert report.runner.startswith("dask(") and report.chunks == 9
    one = _columns(pq.read_table(tmp_path / "one.parquet"))
    assert len(one["dissipated"]) == 2100
    for other in ("threads", "dask"):
        cols = _columns(pq.read_table(tmp_path / f"{other}.parquet"))
        assert list(cols) == list(one)
        for name, values in one.items():  # bit for bit (NaN where NaN)
            np.testing.assert_array_equal(cols[name], values, err_msg=f"{other}: {name}")


def test_dask_by_scheduler_address(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:  # fmt: skip
        out = tmp_path / "e.csv"
        code = main(["sweep", str(BALL), "--vary", "contacts.0.restitution=0:1:11",
                     "--out", str(out), "--scheduler", cluster.scheduler_address])  # fmt: skip
    assert code == 0
    assert read_sweep(out).column("contacts.0.restitution").to_pylist()[-1] == 1.0


def test_csv_and_parquet_hold_the_same_rows(tmp_path) -> None:  # type: ignore[no-untyped-def]
    sweep = _sweep(BILLIARDS, vary=["contacts.0.restitution=0:1:5", "bodies.A.velocity.0=1:3:4"])
    run_sweep(sweep, tmp_path / "r.csv")
    run_sweep(sweep, tmp_path / "r.parquet")
    csv, par = read_sweep(tmp_path / "r.csv"), read_sweep(tmp_path / "r.parquet")
    assert csv.column_names == par.column_names == [c.name for c in sweep.columns]
    assert csv.num_rows == par.num_rows == 20
    for name in par.column_names:
        a = par.column(name).to_pylist()
        b = csv.column(name).to_pylist()
        if isinstance(a[0], float):
            np.testing.assert_allclose(np.array(b, dtype=float), np.array(a, dtype=float),
                                       rtol=1e-15, equal_nan=True)  # fmt: skip
        elif name in ("warnings", "error"):  # "" reads back from CSV as null
            assert [x or "" for x in b] == a
        else:
            assert a == b, name
    assert par.column("contacts.0.regime").to_pylist() == ["frictionless"] * 20


def test_memory_stays_bounded_by_the_chunks(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """NumPy's peak (traced) does not grow with the number of rows: 400 000 rows in chunks
    of 8192 need no more than 50 000 do, and far less than the output's 80 MB."""

    def peak(rows: int) -> int:
        sweep = _sweep(BALL, vary=["contacts.0.restitution=0:1:400",
                                   f"bodies.ball.velocity.2=-1:-5:{rows // 400}"])  # fmt: skip
        run_sweep(sweep, tmp_path / "warm.parquet", chunk_size=8192, workers=2)  # compiled
        tracemalloc.start()
        try:
            run_sweep(sweep, tmp_path / "big.parquet", chunk_size=8192, workers=2)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    small, large = peak(50_000), peak(400_000)
    assert pq.read_metadata(tmp_path / "big.parquet").num_rows == 400_000
    assert large < 1.5 * small + 2**20, (small, large)
    assert large < 400_000 * 8 * 25 / 4


def test_a_failed_sweep_leaves_no_file(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # the normal passes through zero half way: found in its chunk, after others were written
    sweep = _sweep(BALL, vary=["contacts.0.normal.2=1:-1:201"])
    out = tmp_path / "x.parquet"
    with pytest.raises(InputError, match=r"row 100 \(contacts.0.normal.2=0\).*normal"):
        run_sweep(sweep, out, chunk_size=10, workers=1)
    assert list(tmp_path.iterdir()) == []


def test_progress_bar_on_request(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    code = main(
        [
            "sweep",
            str(BALL),
            "--vary",
            "contacts.0.restitution=0:1:50",
            "--out",
            str(tmp_path / "e.parquet"),
            "--progress",
            "--chunk-size",
            "10",
        ]
    )
    captured = capsys.readouterr()
    assert code == 0 and "50 impacts ->" in captured.out
    assert "sweep" in captured.err and "50/50" in captured.err


# --- plots -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "plan",
    [["--vary", "contacts.0.restitution=0:1:21"],
     ["--vary", "contacts.0.restitution=0:1:21", "--vary", "bodies.ball.velocity.2=-1:-4:15"],
     ["--random", "contacts.0.restitution=uniform(0, 1)", "--samples", "3000"],
     ["--random", "contacts.0.restitution=uniform(0, 1)", "--random",
      "bodies.ball.velocity.2=uniform(-4, -1)", "--samples", "3000"]],
    ids=["grid-1", "grid-2", "random-1", "random-2"],
)  # fmt: skip
def test_plot_files_are_made(plan, tmp_path) -> None:  # type: ignore[no-untyped-def]
    picture = tmp_path / "e.png"
    code = main(["sweep", str(BALL), *plan, "--out", str(tmp_path / "e.parquet"),
                 "--plot", str(picture)])  # fmt: skip
    assert code == 0
    assert picture.stat().st_size > 10_000 and picture.read_bytes()[:4] == b"\x89PNG"


def test_plot_with_regimes(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from carnot.plot_sweep import plot_sweep

    scenario = tmp_path / "rod.toml"
    scenario.write_text(ROUGH_ROD)
    sweep_file(
        scenario,
        tmp_path / "rod.parquet",
        vary=["contacts.0.friction=0:1:8", "bodies.rod.velocity.0=-2:2:6"],
    )
    fig = plot_sweep(tmp_path / "rod.parquet", tmp_path / "rod.svg")
    assert len(fig.axes) == 4  # two maps and their colour bars
    labels = [t.get_text() for t in fig.axes[3].get_yticklabels()]
    assert "frictionless" in labels and "slip" in labels


# --- bad input: status 2, one line ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--vary", "contacts.0.restitution=0:1.5:4"],
         "contacts[0].restitution: must be in [0, 1], got 1.5"),
        (["--vary", "bodies.bal.mass=1:2:3"], "bodies has no 'bal' (it has: ball, floor)"),
        (["--vary", "contacts.3.restitution=0:1:3"], "index 3 is out of range"),
        (["--vary", "bodies.ball.velocity.3=0:1:3"], "index 3 is out of range"),
        (["--vary", "bodies.ball.shape=0:1:3"], "is not a number, got 'sphere'"),
        (["--vary", "bodies.ball.velocity=0:1:3"], "is not a number (a list"),
        (["--vary", "bodies.floor.mass=1:2:2"], "bodies.floor has no 'mass'"),
        (["--vary", "contacts.0.restitution=0:1:2.5"], "COUNT must be an integer >= 1, got '2.5'"),
        (["--vary", "contacts.0.restitution=0:1:0"], "COUNT must be an integer >= 1, got '0'"),
        (["--vary", "contacts.0.restitution=0:x:3"], "START and STOP must be numbers"),
        (["--vary", "contacts.0.restitution"], "must be KEY=START:STOP:COUNT"),
        (["--vary", "bodies.ball.mass=-1:2:3"], "bodies.ball.mass: must be > 0, got -1.0"),
        (["--vary", "contacts.0.restitution=0:1:3", "--vary", "contacts[0].restitution=0:1:2"],
         "contacts.0.restitution: is varied twice"),
        (["--random", "contacts.0.restitution=beta(1, 2)", "--samples", "3"], "must be DIST(ARGS)"),
        (["--random", "contacts.0.restitution=uniform(1)", "--samples", "3"],
         "uniform takes 2 finite numbers"),
        (["--random", "contacts.0.restitution=uniform(0.9, 0.1)", "--samples", "3"],
         "needs low < high"),
        (["--random", "contacts.0.restitution=normal(0.5, 0.1)", "--samples", "3"],
         "must be in [0, 1], but normal(0.5, 0.1) draws values without that bound"),
        (["--random", "bodies.ball.mass=normal(1, 0.1)", "--samples", "3"], "must be > 0"),
        (["--random", "contacts.0.restitution=uniform(0, 1)"], "--samples: is required"),
        (["--vary", "contacts.0.restitution=0:1:3", "--samples", "3"], "--samples: goes with"),
        (["--random", "contacts.0.restitution=uniform(0, 1)", "--samples", "0"],
         "--samples: must be an integer >= 1"),
        (["--random", "contacts.0.restitution=uniform(0, 1)", "--samples", "x"],
         "must be an integer, got 'x'"),
        ([], "nothing varies"),
        (["--vary", "contacts.0.restitution=0:1:3", "--out", "r.xlsx"],
         "--out: must end in .parquet or .csv, got 'r.xlsx'"),
        (["--vary", "contacts.0.restitution=0:1:3", "--plot", "e.docx"], "--plot: must end in"),
        (["--vary", "contacts.0.restitution=0:1:3", "--chunk-size", "0"], "--chunk-size"),
        (["--vary", "contacts.0.normal.2=1:-1:3"],
         "row 1 (contacts.0.normal.2=0): contacts[0].normal: must be a non-zero vector"),
    ],
)  # fmt: skip
def test_bad_input_is_one_line_and_status_2(args, expected, tmp_path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.chdir(tmp_path)
    if "--out" not in args:
        args = [*args, "--out", "r.parquet"]
    try:
        code = main(["sweep", str(BALL), *args])
    except SystemExit as done:  # argparse's own errors (a non-integer option)
        code = int(done.code or 0)
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("carnot: error: ") and err.count("\n") == 1, err
    assert expected in err, err
    assert not (tmp_path / "r.parquet").exists()


def test_bad_inertia_in_a_range(tmp_path) -> None:  # type: ignore[no-untyped-def]
    scenario = tmp_path / "box.toml"
    scenario.write_text(STICK_BOX)
    with pytest.raises(InputError, match=r"bodies.box.inertia: principal moments"):
        _sweep(scenario, vary=["bodies.box.inertia.2.2=0.04:0.2:3"])


def test_the_command_in_a_real_process(tmp_path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "e.parquet"
    done = subprocess.run(
        [sys.executable, "-m", "carnot.cli", "sweep", str(BALL), "--vary",
         "contacts.0.restitution=0:1:1001", "--out", str(out)],
        capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # no progress bar when stderr is not a terminal
    table = pq.read_table(out, columns=["contacts.0.restitution", "dissipated"])
    e = table.column("contacts.0.restitution").to_numpy()
    # the README's ball: E_d = (1 - e^2) m v_z^2 / 2 with m = 0.5, v_z = -3
    np.testing.assert_allclose(table.column("dissipated").to_numpy(), (1 - e**2) * 2.25,
                               rtol=1e-12, atol=1e-14)  # fmt: skip


def test_a_small_sweep_takes_the_uncompiled_loop_and_says_why(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Up to UNCOMPILED_ROWS rows the solve_impact loop finishes before a cold kernel would
    compile (issue 35): the route says so, and its rows are the kernel's (forced)."""
    from carnot.sweep import UNCOMPILED_ROWS

    data = read_scenario_data(BALL)
    small = prepare_sweep(data, make_plan(vary=["contacts.0.restitution=0:1:100"]))
    assert small.route == "solve" and "before the batch kernel would compile" in small.why_solve
    forced = prepare_sweep(data, make_plan(vary=["contacts.0.restitution=0:1:100"]),
                           compiled=True)  # fmt: skip
    assert forced.route == "batch"
    never = prepare_sweep(data, make_plan(vary=[f"contacts.0.restitution=0:1:"
                                                f"{UNCOMPILED_ROWS['batch'] + 1}"]),
                          compiled=False)  # fmt: skip
    assert never.route == "solve"
    big = prepare_sweep(data, make_plan(vary=[f"contacts.0.restitution=0:1:"
                                              f"{UNCOMPILED_ROWS['batch'] + 1}"]))  # fmt: skip
    assert big.route == "batch"
    a = small.chunk(0, 100).columns
    b = forced.chunk(0, 100).columns
    for name in ("dissipated", "contacts.0.impulse_z", "energy_after"):
        assert np.allclose(a[name], b[name], rtol=1e-12, atol=1e-15), name

"""``carnot sweep`` never writes a row it could not compute as numbers silently (issue 19,
defect 5): values beyond the loader's magnitude bounds are refused like any bad value, and a
row whose results are not finite is written with NaN results, a reason in the ``error``
column, counted in the report and warned about on stderr."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pyarrow.csv as pacsv
import pytest

import carnot.batch
from carnot.cli import main
from carnot.io.scenario import read_scenario_data
from carnot.sweep import NON_FINITE, make_plan, prepare_sweep, run_sweep

ROOT = Path(__file__).resolve().parent.parent
BALL = str(ROOT / "examples" / "ball_on_floor.toml")


@pytest.mark.parametrize(
    "args, field",
    [
        (["--vary", "bodies.ball.velocity.2=-1e200:-1:3"], "bodies.ball.velocity"),
        (["--vary", "bodies.ball.mass=1e-320:1:3"], "bodies.ball.mass"),
        (["--random", "bodies.ball.velocity.0=normal(0, 1e200)", "--samples", "5"],
         "bodies.ball.velocity"),
    ],
)  # fmt: skip
def test_values_beyond_the_bounds_are_refused(args, field, tmp_path, capsys) -> None:
    out = tmp_path / "s.csv"
    assert main(["sweep", BALL, *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and field in err[0] and ("at most 1e+50" in err[0] or ">= 1e-50" in err[0])
    assert not out.exists()


def _poisoned(restitutions: set[float]):
    """The batch kernel, with the energy after of the rows with these restitutions made
    infinite (as an overflow would): the reporting path must catch them whatever produced
    them."""
    kernel = carnot.batch.point_impacts

    def run(a, b, point, normal, restitution, **kwargs):
        out = kernel(a, b, point, normal, restitution, **kwargs)
        e = np.asarray(restitution, dtype=float)
        after = np.array(np.broadcast_to(out.after, e.shape), dtype=float)
        after[np.isin(e, sorted(restitutions))] = np.inf
        return dataclasses.replace(out, after=after)

    return run


def test_a_row_with_a_non_finite_result_is_reported(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setattr(carnot.batch, "point_impacts", _poisoned({0.25, 0.75}))
    out = tmp_path / "s.csv"
    code = main(["sweep", BALL, "--vary", "contacts.0.restitution=0:1:5", "--out", str(out),
                 "--workers", "1", "--compiled"])  # fmt: skip
    assert code == 0
    captured = capsys.readouterr()
    assert "not computed: 2" in captured.out
    assert captured.err.splitlines() == [
        "carnot: warning: 2 of 5 impacts could not be computed: their results are NaN, the "
        "reason in the error column"
    ]
    table = pacsv.read_csv(out)
    errors = [x or "" for x in table.column("error").to_pylist()]
    assert errors == ["", NON_FINITE, "", NON_FINITE, ""]
    for name in ("energy_after", "dissipated", "contacts.0.impulse_z", "energy_before"):
        col = np.array(table.column(name).to_pylist(), dtype=float)
        assert np.all(np.isnan(col[[1, 3]])) and np.all(np.isfinite(col[[0, 2, 4]])), name
    assert table.column("contacts.0.restitution").to_pylist() == [0.0, 0.25, 0.5, 0.75, 1.0]


def test_the_report_counts_failed_rows_and_clean_runs_have_none(tmp_path, monkeypatch) -> None:
    data = read_scenario_data(BALL)
    sweep = prepare_sweep(data, make_plan(vary=["contacts.0.restitution=0:1:7"]), compiled=True)
    clean = run_sweep(sweep, tmp_path / "a.parquet", workers=1)
    assert clean.failed == 0
    monkeypatch.setattr(carnot.batch, "point_impacts", _poisoned({1.0}))
    assert run_sweep(sweep, tmp_path / "b.parquet", workers=1, chunk_size=3).failed == 1

"""The command line end to end."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import carnot
from carnot.cli import main


def test_version(capsys) -> None:
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.strip() == f"carnot {carnot.__version__}"


@pytest.mark.parametrize("command", [[], ["solve"], ["paper"]])
def test_help_on_every_command(command, capsys) -> None:
    with pytest.raises(SystemExit) as done:
        main([*command, "--help"])
    assert done.value.code == 0
    assert "usage: carnot" in capsys.readouterr().out


def test_no_command_prints_help(capsys) -> None:
    assert main([]) == 2
    assert "usage: carnot" in capsys.readouterr().out


def test_solve_table_and_json_in_a_real_process(example_path) -> None:
    """As a user runs it: a separate Python process, the installed entry point's module."""
    path = str(example_path("paper_cylinder_edge.toml"))
    table = subprocess.run(
        [sys.executable, "-m", "carnot.cli", "solve", path], capture_output=True, text=True
    )
    assert table.returncode == 0, table.stderr
    assert "Energy ledger" in table.stdout and "E_d (theorem)" in table.stdout
    as_json = subprocess.run(
        [sys.executable, "-m", "carnot.cli", "solve", path, "--json"],
        capture_output=True, text=True,
    )  # fmt: skip
    assert as_json.returncode == 0, as_json.stderr
    data = json.loads(as_json.stdout)
    # Section 3.1 with m = 2, v'_O = 2, cos(alpha) = 0.8, e = 0.5: P_n = m v (1 + e) cos(alpha).
    assert data["contacts"][0]["normal_impulse"] == pytest.approx(4.8, rel=1e-12)
    assert data["energy"]["dissipated"] == pytest.approx(data["energy"]["dissipated_theorem"])


def test_paper_json(capsys) -> None:
    assert main(["paper", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert len(rows) >= 30
    for row in rows:
        assert {"id", "where", "verdict", "max_rel_diff"} <= set(row)
    assert {r["id"] for r in rows if r["verdict"] == "disagrees"} == {
        "3.1/eq-angular", "3.3/P", "3.3/E_d"
    }  # fmt: skip


def test_paper_table(capsys) -> None:
    assert main(["paper"]) == 0
    out = capsys.readouterr().out
    assert "3 disagree" in out and "corrected form" in out
    assert "max |E_d - E_d(theorem)| / E'" in out

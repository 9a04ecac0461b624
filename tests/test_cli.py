"""The command line end to end."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import pytest

import carnot
from carnot.cli import build_parser, main

CONSOLE_SCRIPT = Path(sys.executable).parent / "carnot"


def test_version(capsys) -> None:
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.strip() == f"carnot {carnot.__version__}"


def _commands() -> list[str]:
    """The sub-commands the parser knows (so that a new one cannot miss its --help test)."""
    (sub,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    return sorted(sub.choices)


def test_the_documented_commands_exist() -> None:
    assert {"solve", "paper"} <= set(_commands())


@pytest.mark.parametrize(
    "command", [[], *([c] for c in _commands())], ids=lambda c: " ".join(c) or "carnot"
)
def test_help_on_every_command(command, capsys) -> None:
    with pytest.raises(SystemExit) as done:
        main([*command, "--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: carnot {' '.join(command)}".rstrip())
    assert "--help" in out


def test_no_command_prints_help(capsys) -> None:
    assert main([]) == 2
    out, err = capsys.readouterr()
    assert "usage: carnot" in out
    assert err.splitlines() == [
        "carnot: error: a command is needed (solve, paper, prove, derive, sweep, from-mjcf, "
        "audit, simulate, cycle, explore; see carnot --help)"
    ]


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


def test_solve_json_scenario_in_process(write_scenario, capsys) -> None:
    """A JSON scenario (same structure as TOML): exit 0, result format 1 on stdout only."""
    scenario = {
        "format": 1,
        "bodies": {"ball": {"mass": 2.0, "shape": "sphere", "radius": 0.1,
                            "position": [0, 0, 0.1], "velocity": [0, 0, -1.0]},
                   "floor": {"fixed": True}},
        "contacts": [{"a": "ball", "b": "floor", "point": [0, 0, 0], "normal": [0, 0, 1],
                      "restitution": 1.0}],
    }  # fmt: skip
    path = write_scenario(json.dumps(scenario), "ball.json")
    assert main(["solve", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    data = json.loads(out)
    assert data["format"] == 1
    # e = 1: the ball comes back with its speed, nothing is dissipated.
    assert data["bodies"]["ball"]["velocity"] == pytest.approx([0, 0, 1.0], abs=1e-15)
    assert abs(data["energy"]["dissipated"]) < 1e-15


@pytest.mark.skipif(not CONSOLE_SCRIPT.exists(), reason="the console script is not installed")
def test_console_script(example_path, write_scenario) -> None:
    """The installed ``carnot`` entry point: version, a solve, and a refusal."""
    version = subprocess.run([str(CONSOLE_SCRIPT), "--version"], capture_output=True, text=True)
    assert (version.returncode, version.stdout) == (0, f"carnot {carnot.__version__}\n")
    good = subprocess.run(
        [str(CONSOLE_SCRIPT), "solve", str(example_path("paper_cylinder_edge.toml")), "--json"],
        capture_output=True, text=True,
    )  # fmt: skip
    assert good.returncode == 0, good.stderr
    assert json.loads(good.stdout)["format"] == 1
    bad_path = write_scenario("format = 1\n[bodies.b]\nmass = -1.0\n")
    bad = subprocess.run([str(CONSOLE_SCRIPT), "solve", str(bad_path)], capture_output=True,
                         text=True)  # fmt: skip
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr == f"carnot: error: {bad_path}: bodies.b.mass: must be > 0, got -1.0\n"


def test_an_unreadable_file_is_refused(tmp_path, capsys) -> None:
    assert main(["solve", str(tmp_path)]) == 2  # a directory
    err = capsys.readouterr().err
    assert err.startswith(f"carnot: error: {tmp_path}: cannot read the file")
    assert len(err.splitlines()) == 1


def test_a_line_break_in_a_key_stays_on_one_line(write_scenario, capsys) -> None:
    path = write_scenario('format = 1\n[bodies."two\\nlines"]\nmass = 0.0\n')
    assert main(["solve", str(path)]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "must not contain control characters" in err


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

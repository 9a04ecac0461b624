"""Shared test helpers."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from carnot import records

# the compile notice (carnot.batch.compile_notice) is tested on its own; elsewhere a worker's
# first compile would add a line to the stderr that the command-line tests read
os.environ.setdefault("CARNOT_QUIET_COMPILE", "1")
# Record.from_fields checks the names and order of the fields it is given, not only their
# number (carnot.records: every producer's fields, checked in every test that reaches it; read
# at each call, so set here whenever the module was imported)
records.CHECK_FIELDS = True

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


@pytest.fixture
def write_scenario(tmp_path: Path):
    """Write scenario text to a file and return its path."""

    def write(text: str, name: str = "scenario.toml") -> Path:
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path

    return write


@pytest.fixture
def example_path():
    """The path of a file in examples/."""

    def path(name: str) -> Path:
        return EXAMPLES / name

    return path

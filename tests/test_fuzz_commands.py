"""Issue 19's guarantees for the commands that landed after it: ``carnot simulate`` on mutated
simulation scenarios and ``carnot solve`` on mutated ``[system]`` scenarios (the mutations of
tests/test_fuzz.py). Every case ends with exit 0 and finite output, or exit 2 and exactly one
line naming the file; no Python warning, no traceback, no hang."""

from __future__ import annotations

import json
import random
import tomllib
from collections import Counter
from pathlib import Path

import pytest
from test_fuzz import _finite, _no_constant, _time_limit, _TimeLimit, judge, mutate, run_cli

ROOT = Path(__file__).resolve().parent.parent
SIMULATIONS = sorted((ROOT / "examples" / "simulate").glob("*.toml"))
SYSTEMS = sorted((ROOT / "examples" / "systems").glob("*.toml"))
CASES = 60
#: A mutated simulation may run to its event limit; that takes seconds, not this long.
LIMIT = 60


def _judge_simulation(path: Path, code: int, out: str, err: str, caught: list[str]) -> str:
    assert not caught, f"Python warnings: {caught}"
    if code == 0:
        assert err == "" or "warning" in err, f"status 0 with stderr {err!r}"
        result = json.loads(out, parse_constant=_no_constant)
        assert _finite(result), "a non-finite number in the result"
        return "solved"
    assert code == 2, f"status {code}; stderr {err[-2000:]!r}"
    lines = err.splitlines()
    assert len(lines) == 1, f"{len(lines)} lines on stderr: {err[-2000:]!r}"
    assert lines[0].startswith(f"carnot: error: {path}"), lines[0]
    return "refused"


@pytest.mark.parametrize(("command", "sources", "seed"), [
    ("simulate", SIMULATIONS, 16), ("solve", SYSTEMS, 15),
], ids=["simulate", "systems"])  # fmt: skip
def test_fuzz_new_commands(command: str, sources: list[Path], seed: int, tmp_path: Path) -> None:
    assert sources, "no example to mutate"
    rng = random.Random(seed)
    datas = [tomllib.loads(p.read_text(encoding="utf-8")) for p in sources]
    for data in datas:  # the fuzz is about input handling: short runs (a mutation may remove it)
        if "simulation" in data:
            data["simulation"]["max_events"] = 500
    outcomes: Counter[str] = Counter()
    failures = []
    for case in range(CASES):
        index = rng.randrange(len(datas))
        kind, suffix, text = mutate(datas[index], rng)
        path = tmp_path / f"case{case}{suffix}"
        path.write_bytes(text.encode("latin-1") if kind == "garbage" else text.encode())
        path.with_name("sine_pulse.csv").write_bytes(
            (ROOT / "examples" / "simulate" / "sine_pulse.csv").read_bytes())  # fmt: skip
        what = f"case {case} ({sources[index].name}, {kind}): {text[-300:]!r}"
        try:
            with _time_limit(LIMIT):
                code, out, err, caught = run_cli([command, str(path), "--json"])
            if command == "simulate":
                outcomes[_judge_simulation(path, code, out, err, caught)] += 1
            else:
                outcomes[judge(path, code, out, err, caught)] += 1
        except _TimeLimit:
            failures.append(f"over {LIMIT} s: {what}")
        except AssertionError as failure:
            failures.append(f"{failure}\n  {what}")
        path.unlink()
    print(f"{command}: {CASES} cases: {dict(outcomes)}")
    assert not failures, "\n".join(failures)
    assert outcomes["solved"] > 0 and outcomes["refused"] > 0

"""Fuzzing the command line with mutations of every shipped example (issue 19).

Each case writes a mutated scenario file and runs ``carnot solve FILE --json`` in-process
(:func:`carnot.cli.main`, stdout and stderr captured, ``SystemExit`` caught), under a per-case
time limit. Mutations: a deleted key, a value of the wrong type, NaN / infinite / huge / tiny /
zero / negative numbers (and values just inside and outside the documented bounds of
:mod:`carnot.validate`), numbers scaled by up to 10^60 either way, bad normals, unknown body
names, unknown keys, duplicate keys, control characters in names, garbage bytes, a truncated
file, JSON written into a ``.toml`` file (and TOML into ``.json``), a
byte-order mark, deep nesting. Every case must end in one of two ways:

* status 0, nothing on stderr, and a result whose every number is finite; an energy gain
  (``dissipated < 0`` beyond round-off) must carry the ``energy_gain`` flag;
* status 2 and exactly one line on stderr, ``carnot: error: FILE: ...``, naming the file
  (and, for a value, its key path);

never a traceback, a Python warning, another status, or a hang. ``FUZZ_CASES`` cases run by
default (fixed seed); ``pytest -m fuzz_long`` runs ``FUZZ_LONG_CASES`` more with other seeds.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import math
import random
import signal
import time
import tomllib
import warnings
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from carnot.cli import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "examples").glob("*.toml"))
FUZZ_CASES = 400
FUZZ_LONG_CASES = 4000
#: Seconds one case may take (the slowest legitimate case, a 3D frictional impact with
#: Numba compiling on first use, takes about 2 s).
CASE_LIMIT = 20
#: A sweep case's limit: its first batch may compile a law's kernel on a cold Numba cache, as
#: in CI (the multi-contact kernel: about 100 s quiet, over 240 s once on a machine at load 4);
#: a hang still ends.
SWEEP_CASE_LIMIT = 360

NUMBERS = [
    math.nan, math.inf, -math.inf, 1e308, -1e308, 1e200, 1e-320, -1e-320, 5e-324, 0.0, -0.0,
    -1.0, 1e50, -1e50, 1.0000001e50, 1e-50, 0.99999e-50, 1e-300, 10**400, -(10**400), 10**30,
    2.5, 1e-12, 3, True,
]  # fmt: skip
WRONG_TYPES: list[Any] = ["x", "", True, [], {}, [1, 2], [[1, 2, 3]], {"x": 1}, "1.0", ["1", 0, 0]]
BAD_NORMALS = [
    [0, 0, 0], [1e308, 1e308, 0], [math.nan, 0, 1], [1e-320, 0, 0], [0, 0, math.inf], [1, 2],
    [-1e-300, 0, 1e-300], [0.0, -0.0, 0.0],
]  # fmt: skip
KINDS = (
    "delete", "wrong_type", "number", "normal", "unknown_name", "unknown_key", "duplicate_key",
    "garbage", "truncate", "swap_format", "bom", "deep", "control_name", "scale",
)  # fmt: skip


# ---------------------------------------------------------------------------------------------
# Writing TOML (the standard library only reads it)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string: the same escapes
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        pairs = (f"{json.dumps(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{" + ", ".join(pairs) + "}"
    raise TypeError(value)  # pragma: no cover


def to_toml(data: dict[str, Any]) -> str:
    """Top-level keys as ``key = value`` lines, tables and arrays of tables inline."""
    return "".join(f"{json.dumps(k)} = {_toml_value(v)}\n" for k, v in data.items())


def _json(data: Any) -> str:
    return json.dumps(data, allow_nan=True)


# ---------------------------------------------------------------------------------------------
# Mutations


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every key path in the document (tables and lists entered)."""
    items: Any = ()
    if isinstance(node, dict):
        items = node.items()
    elif isinstance(node, list):
        items = enumerate(node)
    for key, value in items:
        yield (*prefix, key)
        yield from _paths(value, (*prefix, key))


def _get(data: Any, path: tuple[Any, ...]) -> Any:
    for key in path:
        data = data[key]
    return data


def _set(data: Any, path: tuple[Any, ...], value: Any) -> None:
    _get(data, path[:-1])[path[-1]] = value


def mutate(data: dict[str, Any], rng: random.Random) -> tuple[str, str, str]:
    """A mutated file: (kind, suffix, text)."""
    kind = rng.choice(KINDS)
    data = copy.deepcopy(data)
    paths = list(_paths(data))
    leaves = [p for p in paths if not isinstance(_get(data, p), (dict, list))]
    numeric = [p for p in paths if isinstance(_get(data, p), (int, float))
               and not isinstance(_get(data, p), bool)]  # fmt: skip
    suffix = ".toml"
    if kind == "delete":
        path = rng.choice(paths)
        parent = _get(data, path[:-1])
        del parent[path[-1]]
    elif kind == "wrong_type":
        _set(data, rng.choice(paths), copy.deepcopy(rng.choice(WRONG_TYPES)))
    elif kind == "number":
        for _ in range(rng.choice((1, 1, 2))):
            _set(data, rng.choice(numeric or leaves), rng.choice(NUMBERS))
    elif kind == "normal":
        key = rng.choice(("normal", "axis", "point", "velocity", "angular_velocity"))
        spots = [p for p in paths if p[-1] == key] or numeric
        _set(data, rng.choice(spots), copy.deepcopy(rng.choice(BAD_NORMALS)))
    elif kind == "unknown_name":
        spots = [p for p in paths if p[-1] in ("a", "b", "body", "other")] or paths
        _set(data, rng.choice(spots), rng.choice(("nobody", "", 3, "ground ")))
    elif kind == "unknown_key":
        tables = [p for p in paths if isinstance(_get(data, p), dict)]
        target = _get(data, rng.choice(tables)) if tables and rng.random() < 0.8 else data
        target[rng.choice(("colour", "Mass", "massa", "restitutionn"))] = 1.0
    elif kind == "scale":  # extreme but often valid: the solver sees these
        for _ in range(rng.choice((1, 2, 3))):
            if numeric:
                path = rng.choice(numeric)
                _set(data, path, float(_get(data, path)) * 10 ** rng.uniform(-60, 60))
    elif kind == "control_name":
        names = list(data.get("bodies", {}))
        if names:
            old = rng.choice(names)
            new = old + rng.choice(("\n", "\t", "\x00", "\x1b[31m"))
            data["bodies"][new] = data["bodies"].pop(old)
    text = to_toml(data)
    if kind == "duplicate_key":
        if rng.random() < 0.5:
            lines = text.splitlines(keepends=True)
            text = "".join(lines + [rng.choice(lines)])
        else:
            suffix = ".json"
            body = _json(data)
            text = body[:-1] + ', "format": 1}'
    elif kind == "garbage":
        raw = bytearray(text.encode())
        for _ in range(rng.randint(1, 8)):
            raw.insert(rng.randrange(len(raw) + 1), rng.randrange(256))
        return kind, suffix, raw.decode("latin-1")  # written back as bytes below
    elif kind == "truncate":
        text = text[: rng.randrange(len(text))]
    elif kind == "swap_format":
        if rng.random() < 0.5:
            text = _json(data)  # JSON in a .toml file
        else:
            suffix = ".json"  # TOML in a .json file
    elif kind == "bom":
        text = "\ufeff" + text
    elif kind == "deep":
        depth = rng.choice((5, 31, 40, 1200, 5000))
        text = text + f'"title" = {"[" * depth}{"]" * depth}\n'
    return kind, suffix, text


# ---------------------------------------------------------------------------------------------
# Running one case and judging it


class _TimeLimit(Exception):
    pass


@contextlib.contextmanager
def _time_limit(seconds: float) -> Iterator[None]:
    def expired(signum: int, frame: Any) -> None:
        raise _TimeLimit

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def run_cli(args: list[str]) -> tuple[int, str, str, list[str]]:
    """``carnot ARGS`` in-process: (status, stdout, stderr, Python warnings raised)."""
    out, err = io.StringIO(), io.StringIO()
    with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):  # fmt: skip
        warnings.simplefilter("always")
        try:
            code = main(args)
        except SystemExit as stop:  # argparse's own exits
            code = stop.code if isinstance(stop.code, int) else 1
    return code, out.getvalue(), err.getvalue(), [str(w.message) for w in caught]


def _finite(node: Any) -> bool:
    if isinstance(node, float):
        return math.isfinite(node)
    if isinstance(node, dict):
        return all(_finite(v) for v in node.values())
    if isinstance(node, list):
        return all(_finite(v) for v in node)
    return True


def _no_constant(name: str) -> float:
    raise ValueError(f"non-finite number {name} in the JSON result")


def judge(path: Path, code: int, out: str, err: str, caught: list[str]) -> str:
    """``"solved"`` or ``"refused"``, or an AssertionError saying what broke."""
    assert not caught, f"Python warnings: {caught}"
    if code == 0:
        assert err == "", f"status 0 with stderr {err!r}"
        result = json.loads(out, parse_constant=_no_constant)
        assert _finite(result), "a non-finite number in the result"
        energy = result["energy"]
        gain = -energy["dissipated"]
        codes = {w["code"] if isinstance(w, dict) else str(w) for w in result["warnings"]}
        if gain > 1e-9 * max(energy["before"], energy["after"], 1e-300):
            assert "energy_gain" in codes, f"an energy gain of {gain} J without its flag"
        return "solved"
    assert code == 2, f"status {code}; stderr {err[-2000:]!r}"
    lines = err.splitlines()
    assert len(lines) == 1, f"{len(lines)} lines on stderr: {err[-2000:]!r}"
    assert lines[0].startswith(f"carnot: error: {path}"), lines[0]
    assert "Traceback" not in err
    return "refused"


def fuzz(seed: int, cases: int, tmp_path: Path) -> tuple[Counter[tuple[str, str]], list[str]]:
    """Run ``cases`` cases: the outcomes by (mutation, "solved"/"refused"), and a description
    of every case that broke the rules (the run goes on, to report them all)."""
    rng = random.Random(seed)
    sources = [tomllib.loads(p.read_text(encoding="utf-8")) for p in EXAMPLES]
    outcomes: Counter[tuple[str, str]] = Counter()
    failures: list[str] = []
    for case in range(cases):
        index = rng.randrange(len(sources))
        kind, suffix, text = mutate(sources[index], rng)
        path = tmp_path / f"case{case}{suffix}"
        path.write_bytes(text.encode("latin-1") if kind == "garbage" else text.encode())
        what = f"case {case} (seed {seed}, {EXAMPLES[index].name}, {kind}): {text[-400:]!r}"
        try:
            with _time_limit(CASE_LIMIT):
                code, out, err, caught = run_cli(["solve", str(path), "--json"])
            outcomes[(kind, judge(path, code, out, err, caught))] += 1
        except _TimeLimit:
            failures.append(f"over {CASE_LIMIT} s: {what}")
            outcomes[(kind, "broken")] += 1
        except AssertionError as failure:
            failures.append(f"{failure}\n  {what}")
            outcomes[(kind, "broken")] += 1
        path.unlink()
    return outcomes, failures


def _summary(outcomes: Counter[tuple[str, str]]) -> str:
    total = Counter(result for _, result in outcomes.elements())
    per_kind = ", ".join(
        f"{k}: {outcomes[(k, 'solved')]}/{outcomes[(k, 'refused')]}/{outcomes[(k, 'broken')]}"
        for k in KINDS
    )
    return (f"{sum(total.values())} cases: {dict(total)}; per mutation "
            f"solved/refused/broken: {per_kind}")  # fmt: skip


def test_fuzz_every_example(tmp_path: Path) -> None:
    outcomes, failures = fuzz(19, FUZZ_CASES, tmp_path)
    print(_summary(outcomes))
    assert not failures, "\n".join(failures)
    assert sum(outcomes.values()) == FUZZ_CASES
    solved = sum(v for (_, r), v in outcomes.items() if r == "solved")
    refused = sum(v for (_, r), v in outcomes.items() if r == "refused")
    # both outcomes occur, and every kind of mutation was tried
    assert solved > 0.1 * FUZZ_CASES and refused > 0.3 * FUZZ_CASES
    assert {k for k, _ in outcomes} == set(KINDS)


@pytest.mark.fuzz_long
@pytest.mark.parametrize("seed", range(1, 6))
def test_fuzz_every_example_long(seed: int, tmp_path: Path) -> None:
    outcomes, failures = fuzz(1000 + seed, FUZZ_LONG_CASES // 5, tmp_path)
    print(_summary(outcomes))
    assert not failures, "\n".join(failures)


# ---------------------------------------------------------------------------------------------
# carnot sweep: the same guarantees for its rows

RANGES = ["-1e200:-1:3", "0:1e60:4", "1e-320:1:3", "-1e51:1e51:3", "0:1:5", "-1:1:5",
          "1e-50:1e50:5", "2:2:1"]  # fmt: skip
DISTRIBUTIONS = ["normal(0, 1e60)", "loguniform(1e-60, 1e60)", "uniform(-1, 1)",
                 "normal(1, 0.1)", "lognormal(0, 300)"]  # fmt: skip
SWEEP_CASES = 40


def _sweep_keys(data: dict[str, Any]) -> list[str]:
    """The numeric key paths of a scenario, as ``carnot sweep`` names them."""
    keys = []
    tables = [("bodies", n, spec) for n, spec in data.get("bodies", {}).items()]
    tables += [("contacts", k, spec) for k, spec in enumerate(data.get("contacts", []))]
    for table, name, spec in tables:
        for key, value in spec.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                keys.append(f"{table}.{name}.{key}")
            elif isinstance(value, list) and value and all(
                isinstance(v, (int, float)) for v in value
            ):
                keys += [f"{table}.{name}.{key}.{i}" for i in range(len(value))]
            elif key == "inertia":
                keys += [f"{table}.{name}.inertia.{i}.{j}" for i in range(3) for j in range(i, 3)]
    return keys


def judge_sweep(path: Path, out: Path, code: int, stdout: str, err: str,
                caught: list[str]) -> str:  # fmt: skip
    import pyarrow.csv as pacsv

    assert not caught, f"Python warnings: {caught}"
    lines = err.splitlines()
    if code == 2:
        assert len(lines) == 1 and lines[0].startswith("carnot: error: "), err[-2000:]
        assert not out.exists()
        return "refused"
    assert code == 0, f"status {code}; stderr {err[-2000:]!r}"
    table = pacsv.read_csv(out)
    errors = [x or "" for x in table.column("error").to_pylist()]
    failed = sum(1 for x in errors if x)
    assert len(lines) == (1 if failed else 0), err
    if failed:
        assert lines[0].startswith(f"carnot: warning: {failed} of {table.num_rows} impacts")
        assert f"not computed: {failed}" in stdout
    for name in table.column_names:
        if name.endswith(".friction_required") or table.schema.field(name).type != "double":
            continue
        for value, why in zip(table.column(name).to_pylist(), errors, strict=True):
            assert (value is None or math.isnan(value)) if why else math.isfinite(value), name
    return "failed rows" if failed else "solved"


def test_fuzz_sweep(tmp_path: Path) -> None:
    rng = random.Random(5)
    sources = [(p, tomllib.loads(p.read_text(encoding="utf-8"))) for p in EXAMPLES]
    outcomes: Counter[str] = Counter()
    failures = []
    seconds: dict[str, float] = {}
    for case in range(SWEEP_CASES):
        example, data = rng.choice(sources)
        key = rng.choice(_sweep_keys(data))
        if rng.random() < 0.7:
            args = ["--vary", f"{key}={rng.choice(RANGES)}"]
        else:
            args = ["--random", f"{key}={rng.choice(DISTRIBUTIONS)}", "--samples", "7"]
        out = tmp_path / f"sweep{case}.csv"
        what = f"sweep case {case}: {example.name} {' '.join(args)}"
        try:
            began = time.perf_counter()
            with _time_limit(SWEEP_CASE_LIMIT):
                code, stdout, err, caught = run_cli(
                    ["sweep", str(example), *args, "--out", str(out), "--workers", "1"]
                )
            seconds[what] = time.perf_counter() - began
            outcomes[judge_sweep(example, out, code, stdout, err, caught)] += 1
        except _TimeLimit:
            failures.append(f"over {SWEEP_CASE_LIMIT} s: {what}")
        except AssertionError as failure:
            failures.append(f"{failure}\n  {what}")
    slowest = max(seconds, key=seconds.__getitem__)
    print(f"{SWEEP_CASES} sweep cases: {dict(outcomes)}; slowest {seconds[slowest]:.1f} s: "
          f"{slowest}")
    assert not failures, "\n".join(failures)
    assert outcomes["solved"] > 0 and outcomes["refused"] > 0


def test_the_mutations_are_read_back_as_written(tmp_path: Path) -> None:
    """The TOML writer of this module: every example survives the round trip unchanged (else
    the fuzz would test the writer, not carnot)."""
    for example in EXAMPLES:
        data = tomllib.loads(example.read_text(encoding="utf-8"))
        assert tomllib.loads(to_toml(data)) == data, example.name

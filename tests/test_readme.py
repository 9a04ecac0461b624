"""The README's commands and Python example, run as written (a README that lies is a bug).

The TOML block is saved as ``ball.toml`` in a scratch folder (as the README asks), with
``examples/`` beside it, and every ``carnot ...`` line of the README's ``sh`` blocks runs there
in a new process. The Python block runs in a new process and must print the ``text`` block
that follows it. ``make`` lines must name targets of the Makefile, ``pip install`` lines
extras of pyproject.toml.
"""

from __future__ import annotations

import http.client
import json
import os
import re
import shlex
import socket
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")
BIN = Path(sys.executable).parent
# `carnot prove` (its six SymPy proofs, about 20-40 s here) is already run whole by
# tests/test_symbolic.py through carnot.symbolic.proofs.prove(); here only its command line.
HEAVY = {("carnot", "prove"): ["--json", "--help"]}


def _blocks(language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", README, flags=re.S | re.M)


def _lines(block: str) -> list[list[str]]:
    """The commands of a shell block, comments dropped, continuation lines joined."""
    text = block.replace("\\\n", " ")
    return [shlex.split(line, comments=True) for line in text.splitlines() if line.strip()]


def _commands(program: str) -> list[list[str]]:
    return [argv for block in _blocks("sh") for argv in _lines(block) if argv[:1] == [program]]


@pytest.fixture(scope="module")
def scratch(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("readme")
    (toml,) = _blocks("toml")
    (folder / "ball.toml").write_text(toml, encoding="utf-8")
    (folder / "examples").symlink_to(ROOT / "examples")
    return folder


def _free(port: int) -> bool:
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


def _explore(argv: list[str], cwd: Path) -> None:
    """`carnot explore` serves until stopped: start it, read its page and an answer, stop it."""
    if "--port" not in argv and not _free(8765):  # someone's explore is running on this machine
        argv = [*argv, "--port", "0"]
    env = {**os.environ, "BROWSER": "true"}  # webbrowser runs `true`: no window in a test
    process = subprocess.Popen(
        [str(BIN / argv[0]), *argv[1:]], cwd=cwd, env=env, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        match = re.match(r"carnot explore: http://127\.0\.0\.1:(\d+)/ ", line)
        assert match, (line, process.stderr.read() if process.poll() is not None else "")
        connection = http.client.HTTPConnection("127.0.0.1", int(match.group(1)), timeout=60)
        connection.request("GET", "/")
        assert b"carnot explore" in connection.getresponse().read()
        body = json.dumps({"classic": "cradle"})
        connection.request("POST", "/api/solve", body=body)
        response = connection.getresponse()
        assert response.status == 200 and "result" in json.loads(response.read())
        connection.close()
    finally:
        process.terminate()
        process.wait(timeout=30)


@pytest.mark.parametrize("argv", _commands("carnot"), ids=shlex.join)
def test_carnot_commands_as_written(argv, scratch) -> None:
    if tuple(argv[:2]) in HEAVY:
        argv = [*argv, *HEAVY[tuple(argv[:2])][-1:]]
    if argv[1:2] == ["explore"]:
        _explore(argv, scratch)
        return
    run = subprocess.run([str(BIN / argv[0]), *argv[1:]], cwd=scratch, capture_output=True,
                         text=True, timeout=600)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip()
    if "--plot" in argv:
        assert (scratch / argv[argv.index("--plot") + 1]).stat().st_size > 10_000
    if "--out" in argv:
        assert (scratch / argv[argv.index("--out") + 1]).stat().st_size > 1_000


def test_the_json_result_says_what_the_readme_says(scratch) -> None:
    """'The ball leaves at v_z = +1.8 m/s ... E_d = 1.44 J twice'."""
    run = subprocess.run([str(BIN / "carnot"), "solve", "ball.toml", "--json"], cwd=scratch,
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    result = json.loads(run.stdout)
    assert result["bodies"]["ball"]["velocity"][2] == pytest.approx(1.8, rel=1e-12)
    assert result["energy"]["dissipated"] == pytest.approx(1.44, rel=1e-12)
    assert result["energy"]["dissipated_theorem"] == pytest.approx(1.44, rel=1e-12)


def test_python_example_prints_what_the_readme_shows(tmp_path) -> None:
    (code,) = _blocks("python")
    (shown,) = _blocks("text")
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stdout == shown


def test_make_targets_exist() -> None:
    targets = {argv[1] for argv in _commands("make")}
    assert {"demo", "test"} <= targets
    for target in targets:
        dry = subprocess.run(["make", "-n", "-C", str(ROOT), target], capture_output=True,
                             text=True)  # fmt: skip
        assert dry.returncode == 0, dry.stderr


def test_every_extra_named_exists() -> None:
    extras = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"])  # fmt: skip
    named = set(re.findall(r"^\| `(\w+)` \|", README, flags=re.M))
    for argv in _commands("pip"):
        for group in re.findall(r"\[([\w,]+)\]", " ".join(argv)):
            named |= set(group.split(","))
    assert named and named <= extras, named - extras
    assert extras <= named, f"extras the README does not describe: {extras - named}"
    assert "format" in README  # the file formats keep a section (or a link)

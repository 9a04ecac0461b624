"""Bad input: one clear message naming the field, the bound and the value; the CLI exits with
status 2 and prints that one line, no traceback."""

from __future__ import annotations

import numpy as np
import pytest

from carnot import (
    ConstraintConflictError,
    FixedBody,
    ImpactProblem,
    InputError,
    Pin,
    PointContact,
    RigidBody,
    solve_impact,
)
from carnot.cli import main
from carnot.io.scenario import load_scenario, parse_scenario
from carnot.model.contacts import Fasten

BASE = """
format = 1
[bodies.ball]
mass = {mass}
inertia = {inertia}
position = [0.0, 0.0, 0.1]
velocity = {velocity}
[bodies.floor]
fixed = true
[bodies.wall]
fixed = true
[[contacts]]
a = "{a}"
b = "{b}"
point = [0.0, 0.0, 0.0]
normal = {normal}
restitution = {e}
friction = {mu}
tangential = "stick"
{extra}
"""
GOOD = {
    "mass": "1.0",
    "inertia": "[[0.004, 0, 0], [0, 0.004, 0], [0, 0, 0.004]]",
    "velocity": "[1.0, 0.0, -2.0]",
    "a": "ball",
    "b": "floor",
    "normal": "[0.0, 0.0, 1.0]",
    "e": "0.5",
    "mu": "0.5",
    "extra": "",
}

CASES = {
    # name: (changes, substrings the message must contain)
    "non-positive mass": ({"mass": "0.0"}, ["bodies.ball.mass", "must be > 0", "got 0.0"]),
    "inertia not symmetric": (
        {"inertia": "[[0.004, 0.001, 0], [0, 0.004, 0], [0, 0, 0.004]]"},
        ["bodies.ball.inertia", "must be symmetric", "0.001"],
    ),
    "inertia not positive definite": (
        {"inertia": "[[0.004, 0, 0], [0, -0.004, 0], [0, 0, 0.004]]"},
        ["bodies.ball.inertia", "positive definite", "-0.004"],
    ),
    "inertia not realizable": (
        {"inertia": "[[1.0, 0, 0], [0, 1.0, 0], [0, 0, 3.0]]"},
        ["bodies.ball.inertia", "sum of the other two", "3.0"],
    ),
    "zero normal": ({"normal": "[0.0, 0.0, 0.0]"}, ["contacts[0].normal", "non-zero", "0.0"]),
    "non-finite normal": ({"normal": "[0.0, nan, 1.0]"}, ["contacts[0].normal", "finite", "nan"]),
    "restitution above 1": ({"e": "1.5"}, ["contacts[0].restitution", "[0, 1]", "1.5"]),
    "restitution below 0": ({"e": "-0.1"}, ["contacts[0].restitution", "[0, 1]", "-0.1"]),
    "negative friction": ({"mu": "-0.2"}, ["contacts[0].friction", ">= 0", "-0.2"]),
    "unknown body": ({"b": "flor"}, ["contacts[0].b", "unknown body", "'flor'", "floor"]),
    "infinite velocity": (
        {"velocity": "[1.0, inf, -2.0]"}, ["bodies.ball.velocity", "finite", "inf"]
    ),
    "NaN velocity": (
        {"velocity": "[1.0, nan, -2.0]"}, ["bodies.ball.velocity", "finite", "nan"]
    ),
    "string in velocity": (
        {"velocity": '[1.0, "0", -2.0]'}, ["bodies.ball.velocity", "3 numbers", "'0'"]
    ),
    "two fixed bodies": (
        {"a": "wall"}, ["contacts[0]", "two fixed bodies", "wall and floor"]
    ),
    "pin with relative velocity": (
        {"extra": '[[constraints]]\ntype = "pin"\nbody = "ball"\npoint = [0.0, 0.0, 0.1]'},
        ["constraints[0]", "pin needs zero relative velocity", "-2.0"],
    ),
    "contradictory constraints": (
        {"extra": '[[constraints]]\ntype = "fasten"\nbody = "ball"\npoint = [0.0, 0.0, 0.0]'},
        ["contacts[0] and constraints[0]", "contradict", "residual"],
    ),
    "unknown key": (
        {"extra": "colour = 'red'"}, ["contacts[0].colour", "unknown key", "allowed", "'colour'"]
    ),
}  # fmt: skip


def _scenario(changes: dict[str, str]) -> str:
    return BASE.format(**{**GOOD, **changes})


def test_the_base_scenario_is_good(write_scenario, capsys) -> None:
    assert main(["solve", str(write_scenario(_scenario({})))]) == 0


@pytest.mark.parametrize("name", sorted(CASES))
def test_cli_refuses_with_one_line(name: str, write_scenario, capsys) -> None:
    changes, expected = CASES[name]
    path = write_scenario(_scenario(changes))
    assert main(["solve", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"carnot: error: {path}: ")
    assert "Traceback" not in err
    for part in expected:
        assert part in lines[0], (part, lines[0])


@pytest.mark.parametrize(
    "text, expected",
    [
        ("format = 1\n[bodies.b\nmass = 1", ["malformed TOML", "line 2"]),
        ("format = 2\n", ["format", "must be 1", "got 2"]),
        ("title = 'no format'\n", ["scenario.format", "is required"]),
    ],
)
def test_cli_refuses_malformed_files(text, expected, write_scenario, capsys) -> None:
    path = write_scenario(text)
    assert main(["solve", str(path)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    for part in expected:
        assert part in err


def test_cli_refuses_malformed_json(write_scenario, capsys) -> None:
    path = write_scenario('{"format": 1, "bodies": {', "s.json")
    assert main(["solve", str(path)]) == 2
    assert "malformed JSON at line 1" in capsys.readouterr().err


def test_cli_refuses_a_missing_file(tmp_path, capsys) -> None:
    assert main(["solve", str(tmp_path / "nope.toml")]) == 2
    err = capsys.readouterr().err
    assert "nope.toml: cannot read the file" in err and "Traceback" not in err


# The same refusals through the Python API.


def _ball(**kw) -> RigidBody:
    args = {"name": "ball", "mass": 1.0, "inertia_com": np.eye(3) * 0.004,
            "velocity_com": [0.0, 0.0, -2.0], "position_com": [0, 0, 0.1]}  # fmt: skip
    return RigidBody(**{**args, **kw})


@pytest.mark.parametrize(
    "kwargs, field, bound",
    [
        ({"mass": -1.0}, "bodies.ball.mass", "must be > 0"),
        ({"inertia_com": [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]}, "bodies.ball.inertia", "symmetric"),
        ({"inertia_com": np.diag([1.0, 1.0, 0.0])}, "bodies.ball.inertia", "positive definite"),
        ({"inertia_com": np.diag([1.0, 1.0, 2.5])}, "bodies.ball.inertia", "other two"),
        ({"velocity_com": [0.0, float("nan"), 0.0]}, "bodies.ball.velocity", "finite"),
        ({"angular_velocity": [0.0, 0.0]}, "bodies.ball.angular_velocity", "3 numbers"),
    ],
)
def test_api_body_errors(kwargs, field, bound) -> None:
    with pytest.raises(InputError) as err:
        _ball(**kwargs)
    assert err.value.field == field
    assert bound in str(err.value) and ", got " in str(err.value)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"normal": [0, 0, 0]}, "contacts[0].normal"),
        ({"normal": [0, float("inf"), 1]}, "contacts[0].normal"),
        ({"restitution": 1.01}, "contacts[0].restitution"),
        ({"friction": -1.0}, "contacts[0].friction"),
        ({"law": "hertz"}, "contacts[0].law"),
        ({"b": "ball"}, "contacts[0].b"),
    ],
)
def test_api_contact_errors(kwargs, field) -> None:
    args = {"a": "ball", "b": "floor", "point": [0, 0, 0], "normal": [0, 0, 1]}
    with pytest.raises(InputError) as err:
        PointContact(**{**args, **kwargs})
    assert err.value.field == field


def test_api_problem_errors() -> None:
    floor, wall = FixedBody(name="floor"), FixedBody(name="wall")
    with pytest.raises(InputError, match="two fixed bodies"):
        ImpactProblem(bodies={"floor": floor, "wall": wall},
                      contacts=[PointContact(a="wall", b="floor", point=[0, 0, 0],
                                             normal=[0, 0, 1])])  # fmt: skip
    with pytest.raises(InputError, match="unknown body"):
        ImpactProblem(bodies={"ball": _ball()}, constraints=[Pin(body="bal", point=[0, 0, 0])])


def test_api_pin_and_conflict() -> None:
    bodies = {"ball": _ball(), "floor": FixedBody(name="floor")}
    with pytest.raises(InputError, match="pin needs zero relative velocity"):
        solve_impact(ImpactProblem(bodies=bodies, constraints=[Pin(body="ball", point=[0, 0, 0])]))
    contact = PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1], restitution=0.5)
    with pytest.raises(ConstraintConflictError, match="contradict"):
        solve_impact(ImpactProblem(bodies=bodies, contacts=[contact],
                                   constraints=[Fasten(body="ball", point=[0, 0, 0])]))  # fmt: skip


def test_api_file_errors(tmp_path) -> None:
    """The loader's own refusals, without the CLI: the same messages, as InputError."""
    with pytest.raises(InputError, match=r"nope\.toml: cannot read the file"):
        load_scenario(tmp_path / "nope.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("format = 1\n[bodies.b\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"broken\.toml: malformed TOML: .*line 2"):
        load_scenario(broken)
    with pytest.raises(InputError, match=r"^x\.toml: format: must be 1 .*, got 2$"):
        parse_scenario({"format": 2}, "x.toml")
    with pytest.raises(InputError, match=r"^x\.toml: bodies\.b\.mas: unknown key \(allowed: "):
        parse_scenario({"format": 1, "bodies": {"b": {"mas": 1.0}}}, "x.toml")


def test_api_scenario_errors_keep_their_class() -> None:
    """A core error raised while the loader builds the problem gets the file prefix and keeps
    its class (so that a caller can still tell a conflict from a bound)."""
    data = {
        "format": 1,
        "bodies": {"ball": {"mass": 1.0, "shape": "sphere", "radius": 0.1}},
        "contacts": [{"a": "ball", "b": "floor", "point": [0, 0, 0], "normal": [0, 0, 1],
                      "restitution": 0.5}],
    }  # fmt: skip
    with pytest.raises(InputError) as err:
        parse_scenario(data, "s.toml")
    assert type(err.value) is InputError
    assert err.value.field == "s.toml: contacts[0].b"
    assert str(err.value) == "s.toml: contacts[0].b: unknown body (known: ball), got 'floor'"

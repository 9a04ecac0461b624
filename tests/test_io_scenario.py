"""Scenario files (format 1): every key of DESIGN.md section 3, TOML and JSON alike."""

from __future__ import annotations

import json

import numpy as np
import pytest

from carnot import solve_impact
from carnot.errors import InputError
from carnot.io.scenario import load_scenario, parse_scenario
from carnot.model.bodies import FixedBody, RigidBody
from carnot.model.inertia import SHAPES, shape_inertia, solid_cylinder, solid_sphere

FULL = """
format = 1
title = "every key"

[bodies.cylinder]
mass = 2.0
inertia = [[0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01]]
position = [0.0, 0.0, 0.0]
velocity = [1.0, -2.0, 0.0]
angular_velocity = [0.0, 0.0, 3.0]

[bodies.ball]
mass = 0.5
shape = "sphere"
radius = 0.1
position = [0.0, 0.5, 0.0]

[bodies.edge]
fixed = true

[[contacts]]
a = "cylinder"
b = "edge"
point = [0.0, -0.1, 0.0]
normal = [0.0, 2.0, 0.0]
restitution = 0.5
law = "newton"
friction = 0.3
tangential = "stick"

[[contacts]]
a = "ball"
b = "edge"
point = [0.0, 0.4, 0.0]
normal = [0.0, 1.0, 0.0]
impulse = [0.0, 0.1, 0.0]
moment = [0.0, 0.0, 0.01]

[[constraints]]
type = "fasten"
body = "ball"
other = "cylinder"
point = [0.0, 0.45, 0.0]
"""


def test_every_key_is_read(write_scenario) -> None:
    problem = load_scenario(write_scenario(FULL))
    assert problem.title == "every key"
    cyl = problem.bodies["cylinder"]
    assert isinstance(cyl, RigidBody)
    assert cyl.mass == 2.0
    assert np.array_equal(cyl.velocity_com, [1.0, -2.0, 0.0])
    assert np.array_equal(cyl.angular_velocity, [0.0, 0.0, 3.0])
    ball = problem.bodies["ball"]
    assert isinstance(ball, RigidBody)
    assert np.allclose(ball.inertia_com, solid_sphere(0.5, 0.1))
    assert np.array_equal(ball.velocity_com, [0.0, 0.0, 0.0])  # default
    assert isinstance(problem.bodies["edge"], FixedBody)
    c0, c1 = problem.contacts
    assert np.allclose(c0.normal, [0, 1, 0])  # normalised
    assert (c0.restitution, c0.law, c0.friction, c0.tangential) == (0.5, "newton", 0.3, "stick")
    assert np.array_equal(c1.impulse, [0.0, 0.1, 0.0]) and c1.is_given
    assert np.array_equal(c1.moment, [0.0, 0.0, 0.01])
    (k,) = problem.constraints
    assert (k.kind, k.body, k.other) == ("fasten", "ball", "cylinder")
    assert [c.where for c in problem.contacts] == ["contacts[0]", "contacts[1]"]


def test_json_is_the_same_structure(write_scenario) -> None:
    import tomllib

    data = tomllib.loads(FULL)
    from_json = load_scenario(write_scenario(json.dumps(data), "s.json"))
    from_toml = load_scenario(write_scenario(FULL))
    a, b = solve_impact(from_json), solve_impact(from_toml)
    assert np.array_equal(a.row_impulses, b.row_impulses)


def test_shape_with_axis(write_scenario) -> None:
    problem = load_scenario(
        write_scenario("""
format = 1
[bodies.c]
mass = 2.0
shape = "solid_cylinder"
radius = 0.1
length = 0.4
axis = [1.0, 0.0, 0.0]
[bodies.g]
fixed = true
[[contacts]]
a = "c"
b = "g"
point = [0.0, 0.0, -0.1]
normal = [0.0, 0.0, 1.0]
restitution = 0.0
""")
    )
    assert np.allclose(problem.bodies["c"].inertia_com, solid_cylinder(2.0, 0.1, 0.4, [1, 0, 0]))


def test_parse_from_dict_names_the_source() -> None:
    with pytest.raises(ValueError, match=r"^here: bodies\.b\.mass: is required"):
        parse_scenario({"format": 1, "bodies": {"b": {"inertia": np.eye(3).tolist()}},
                        "constraints": []}, "here")  # fmt: skip


def _minimal(**changes) -> dict:
    """A good scenario as parsed data: a ball on a fixed floor; ``changes`` replace or add
    top-level keys."""
    data = {
        "format": 1,
        "bodies": {
            "ball": {"mass": 1.0, "inertia": [[0.004, 0, 0], [0, 0.004, 0], [0, 0, 0.004]],
                     "position": [0.0, 0.0, 0.1], "velocity": [0.0, 0.0, -2.0]},
            "floor": {"fixed": True},
        },
        "contacts": [{"a": "ball", "b": "floor", "point": [0.0, 0.0, 0.0],
                      "normal": [0.0, 0.0, 1.0], "restitution": 0.5}],
    }  # fmt: skip
    return {**data, **changes}


def test_defaults() -> None:
    data = _minimal()
    del data["bodies"]["ball"]["position"], data["bodies"]["ball"]["velocity"]
    problem = parse_scenario(data)
    ball = problem.bodies["ball"]
    assert isinstance(ball, RigidBody)
    for vector in (ball.position_com, ball.velocity_com, ball.angular_velocity):
        assert np.array_equal(vector, [0.0, 0.0, 0.0])
    (c,) = problem.contacts
    assert (c.law, c.friction, c.tangential, c.patch, c.impulse) == ("newton", 0.0, "slip",
                                                                     None, None)  # fmt: skip
    assert problem.title == "" and problem.constraints == ()


@pytest.mark.parametrize("law", ["newton", "poisson", "stronge"])
def test_every_law_is_read(law: str) -> None:
    data = _minimal()
    data["contacts"][0]["law"] = law
    assert parse_scenario(data).contacts[0].law == law


def test_patch_and_pin_are_read() -> None:
    data = _minimal()
    patch = [[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.1, 0.1, 0.0], [-0.1, 0.1, 0.0]]
    data["contacts"][0]["patch"] = patch
    data["constraints"] = [{"type": "pin", "body": "ball", "other": "floor", "point": [0, 0, 1]}]
    problem = parse_scenario(data)
    assert np.array_equal(problem.contacts[0].patch, patch)
    (pin,) = problem.constraints
    assert (pin.kind, pin.body, pin.other, pin.where) == ("pin", "ball", "floor", "constraints[0]")
    assert np.array_equal(pin.point, [0.0, 0.0, 1.0])


def _dimensions(required: tuple[str, ...], shape: str) -> dict:
    values = {"radius": 0.1, "length": 0.5, "size": [0.2, 0.3] if shape == "plate" else
              [0.2, 0.3, 0.4]}  # fmt: skip
    return {key: values[key] for key in required}


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_every_shape_gives_its_inertia(shape: str) -> None:
    _, required, _ = SHAPES[shape]
    dims = _dimensions(required, shape)
    data = _minimal()
    data["bodies"]["ball"] = {"mass": 2.0, "shape": shape, **dims}
    inertia = parse_scenario(data).bodies["ball"].inertia_com
    assert np.array_equal(inertia, shape_inertia(shape, 2.0, **dims))


def test_shape_with_orientation_and_inner_radius() -> None:
    quarter_turn_z = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    data = _minimal()
    data["bodies"]["ball"] = {"mass": 2.0, "shape": "box", "size": [0.2, 0.4, 0.6],
                              "orientation": quarter_turn_z}  # fmt: skip
    inertia = parse_scenario(data).bodies["ball"].inertia_com
    in_body_axes = shape_inertia("box", 2.0, size=[0.2, 0.4, 0.6])
    # The box's own x axis lies along world y: the moments about world x and y swap.
    assert np.allclose(np.diag(inertia), np.diag(in_body_axes)[[1, 0, 2]], rtol=1e-14)
    data["bodies"]["ball"] = {"mass": 2.0, "shape": "hollow_cylinder", "radius": 0.1,
                              "inner_radius": 0.05, "length": 0.3}  # fmt: skip
    inertia = parse_scenario(data).bodies["ball"].inertia_com
    # Axial moment of a thick tube: m (r1^2 + r2^2) / 2 (any table, e.g. Meriam & Kraige).
    assert inertia[2, 2] == pytest.approx(2.0 * (0.05**2 + 0.1**2) / 2, rel=1e-14)


def _set(path: str, value):
    """Data for ``_minimal()`` with the key at dotted ``path`` set (or removed if value is
    ``DELETE``)."""
    data = _minimal()
    *parents, last = path.split(".")
    node = data
    for key in parents:
        node = node[int(key)] if key.isdigit() else node[key]
    if value is DELETE:
        del node[last]
    else:
        node[last] = value
    return data


DELETE = object()
BALL_NO_INERTIA = {"mass": 1.0, "shape": "sphere", "radius": 0.1}

STRUCTURE_ERRORS = [
    # (path, value, [substrings of the message])
    ("colour", "red", ["s.toml: colour: unknown key", "allowed: format, title", "'colour'"]),
    ("format", DELETE, ["s.toml: scenario.format: is required"]),
    ("format", "1", ["format: must be 1", "got '1'"]),
    ("format", True, ["format: must be 1", "got True"]),
    ("title", 3, ["title: must be a string", "got 3"]),
    ("bodies", [], ["bodies: must be a table", "got []"]),
    ("bodies.ball", 3.0, ["bodies.ball: must be a table", "got 3.0"]),
    ("bodies.ball.colour", "red", ["bodies.ball.colour: unknown key", "allowed: mass, inertia"]),
    ("bodies.ball.mass", DELETE, ["bodies.ball.mass: is required"]),
    ("bodies.ball.mass", "1.0", ["bodies.ball.mass: must be a number", "got '1.0'"]),
    ("bodies.ball.mass", True, ["bodies.ball.mass: must be a number", "got True"]),
    ("bodies.ball.inertia", DELETE, ["bodies.ball.inertia: is required"]),
    ("bodies.ball.inertia", [[1, 0, 0], [0, 1, 0]], ["bodies.ball.inertia: must be a 3x3"]),
    ("bodies.ball.inertia", [["1", 0, 0], [0, 1, 0], [0, 0, 1]],
     ["bodies.ball.inertia: must be a 3x3 matrix of numbers", "'1'"]),
    ("bodies.ball.velocity", [0, "1", 0], ["bodies.ball.velocity: must be a list of 3 numbers"]),
    ("bodies.ball.velocity", [0, True, 0], ["bodies.ball.velocity: must be a list of 3", "True"]),
    ("bodies.ball.velocity", [[0], 1, 0], ["bodies.ball.velocity: must be a list of 3 numbers"]),
    ("bodies.ball.position", [0, 0], ["bodies.ball.position: must be a list of 3", "[0, 0]"]),
    ("bodies.ball.angular_velocity", {"z": 1}, ["bodies.ball.angular_velocity: must be a list"]),
    ("bodies.ball.radius", 0.1, ["bodies.ball.radius: is a shape dimension"]),
    ("bodies.ball.shape", "sphere", ["bodies.ball.inertia: give either inertia or shape"]),
    ("bodies.ball", {**BALL_NO_INERTIA, "shape": "blob"},
     ["bodies.ball.shape: unknown shape (known: sphere", "'blob'"]),
    ("bodies.ball", {**BALL_NO_INERTIA, "shape": ["sphere"]}, ["bodies.ball.shape: unknown"]),
    ("bodies.ball", {"mass": 1.0, "shape": "sphere"},
     ["bodies.ball.radius: is required for shape 'sphere'"]),
    ("bodies.ball", {**BALL_NO_INERTIA, "length": 1.0},
     ["bodies.ball.length: is not a dimension of shape 'sphere' (it takes: radius)"]),
    ("bodies.ball", {**BALL_NO_INERTIA, "radius": -0.1}, ["bodies.ball.radius: must be > 0"]),
    ("bodies.ball", {"mass": 1.0, "shape": "box", "size": [0.1, "0.2", 0.3]},
     ["bodies.ball.size[1]: must be a number", "'0.2'"]),
    ("bodies.ball", {"mass": 1.0, "shape": "rod", "radius": 0.01, "length": 1.0,
                     "axis": [0, 0, 0]}, ["bodies.ball.axis: must be a non-zero vector"]),
    ("bodies.floor.fixed", False, ["bodies.floor.fixed: must be true", "got False"]),
    ("bodies.floor.mass", 1.0, ["bodies.floor.mass: a fixed body takes no other keys"]),
    ("bodies.floor.colour", 1.0, ["bodies.floor.colour: unknown key (allowed: mass"]),
    ("contacts", {"a": "ball"}, ["contacts: must be an array of tables"]),
    ("contacts", [3], ["contacts[0]: must be a table"]),
    ("contacts.0.a", DELETE, ["contacts[0].a: is required"]),
    ("contacts.0.a", 3, ["contacts[0].a: must be a non-empty string", "got 3"]),
    ("contacts.0.b", "ball", ["contacts[0].b: must name a different body than a"]),
    ("contacts.0.point", DELETE, ["contacts[0].point: is required"]),
    ("contacts.0.normal", DELETE, ["contacts[0].normal: is required"]),
    ("contacts.0.restitution", DELETE, ["contacts[0].restitution: is required",
                                        "unless impulse is given"]),
    ("contacts.0.restitution", "0.5", ["contacts[0].restitution: must be a number"]),
    ("contacts.0.law", "hertz", ["contacts[0].law: must be one of newton, poisson, stronge"]),
    ("contacts.0.law", ["newton"], ["contacts[0].law: must be one of"]),
    ("contacts.0.tangential", "roll", ["contacts[0].tangential: must be 'slip' or 'stick'"]),
    ("contacts.0.friction", float("nan"), ["contacts[0].friction: must be finite", "nan"]),
    ("contacts.0.impulse", [0, 0, 1], ["contacts[0].restitution: does not go with a given"]),
    ("contacts.0.moment", [0, 0, 1], ["contacts[0].moment: needs an impulse beside it"]),
    ("contacts.0.patch", [], ["contacts[0].patch: must be a non-empty list of [x, y, z]"]),
    ("contacts.0.patch", [[0, 0, 0], [True, 0, 0]], ["contacts[0].patch[1]: must be a list"]),
    ("contacts.0.patch", [[0.1, 0, 0.1]], ["contacts[0].patch[0]: must lie in the contact"]),
    ("constraints", "pin", ["constraints: must be an array of tables"]),
    ("constraints", [{"type": "weld", "body": "ball", "point": [0, 0, 0]}],
     ["constraints[0].type: must be 'fasten' or 'pin'", "'weld'"]),
    ("constraints", [{"type": "pin", "body": "ball"}], ["constraints[0].point: is required"]),
    ("constraints", [{"type": "pin", "point": [0, 0, 0]}], ["constraints[0].body: is required"]),
    ("constraints", [{"type": "pin", "body": "ball", "point": [0, 0, 0], "at": 1}],
     ["constraints[0].at: unknown key (allowed: type, body, other, point)"]),
    ("constraints", [{"type": "pin", "body": "bal", "point": [0, 0, 0]}],
     ["constraints[0].body: unknown body", "'bal'"]),
    ("constraints", [{"type": "pin", "body": "floor", "point": [0, 0, 0]}],
     ["constraints[0].body: must be a movable body", "'floor'"]),
]  # fmt: skip


def _case_id(path: str, value) -> str:
    return f"{path} deleted" if value is DELETE else f"{path}={value!r}"[:60]


@pytest.mark.parametrize(
    "path, value, expected",
    STRUCTURE_ERRORS,
    ids=[_case_id(path, value) for path, value, _ in STRUCTURE_ERRORS],
)
def test_structure_errors_name_the_key(path: str, value, expected: list[str]) -> None:
    with pytest.raises(InputError) as err:
        parse_scenario(_set(path, value), "s.toml")
    message = str(err.value)
    assert message.startswith("s.toml: "), message
    for part in expected:
        assert part in message, (part, message)


def test_the_unchanged_minimal_scenario_is_good() -> None:
    """So that each structure error above is due to its own change."""
    problem = parse_scenario(_minimal(), "s.toml")
    assert solve_impact(problem).energy.dissipated > 0
    assert parse_scenario(_set("bodies.ball", BALL_NO_INERTIA)).bodies["ball"].mass == 1.0


def test_a_body_name_must_not_be_empty() -> None:
    data = _minimal()
    data["bodies"][""] = {"fixed": True}
    with pytest.raises(InputError, match=r"^s\.toml: bodies: a body's name must not be empty"):
        parse_scenario(data, "s.toml")

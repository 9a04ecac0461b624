"""Scenario files (format 1): every key of DESIGN.md section 3, TOML and JSON alike."""

from __future__ import annotations

import json

import numpy as np
import pytest

from carnot import solve_impact
from carnot.bodies import FixedBody, RigidBody
from carnot.inertia import solid_cylinder, solid_sphere
from carnot.io.scenario import load_scenario, parse_scenario

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

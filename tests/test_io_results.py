"""Result format 1: every key of DESIGN.md section 4 with its meaning, and the added keys."""

from __future__ import annotations

import json

import numpy as np
import pytest

from carnot import solve_impact
from carnot.io.results import result_to_dict, result_to_json
from carnot.io.scenario import load_scenario
from carnot.io.table import format_result


def test_ball_on_floor_against_newton(example_path) -> None:
    """Newton's restitution for a ball on a fixed floor (e.g. Stronge, Impact Mechanics, 2000,
    section 2.2): v''_n = -e v'_n, the tangential velocity unchanged, E_d = (1 - e^2) m v_n^2/2.
    """
    res = solve_impact(load_scenario(example_path("ball_on_floor.toml")))
    d = json.loads(result_to_json(res))
    m, e, vx, vz = 0.5, 0.6, 1.0, -3.0
    assert d["format"] == 1
    ball = d["bodies"]["ball"]
    assert ball["velocity"] == pytest.approx([vx, 0.0, -e * vz], rel=1e-12)
    assert ball["velocity_before"] == [vx, 0.0, vz]
    assert ball["angular_velocity"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)
    assert ball["angular_velocity_before"] == [0.0, 0.0, 0.0]
    assert d["bodies"]["floor"]["fixed"] is True
    (c,) = d["contacts"]
    assert (c["a"], c["b"], c["regime"]) == ("ball", "floor", "frictionless")
    assert c["impulse"] == pytest.approx([0.0, 0.0, -(1 + e) * m * vz], rel=1e-12)
    assert c["moment"] == [0.0, 0.0, 0.0]
    assert c["normal_impulse"] == pytest.approx(-(1 + e) * m * vz, rel=1e-12)
    assert c["tangential_impulse"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)
    e_d = (1 - e**2) * m * vz**2 / 2
    assert c["dissipated"] == pytest.approx(e_d, rel=1e-12)
    energy = d["energy"]
    assert energy["before"] == pytest.approx(m * (vx**2 + vz**2) / 2, rel=1e-15)
    assert energy["dissipated"] == pytest.approx(e_d, rel=1e-12)
    assert energy["dissipated_theorem"] == pytest.approx(e_d, rel=1e-12)
    assert energy["after"] == pytest.approx(energy["before"] - e_d, rel=1e-12)
    # Carnot: E_p = 1/2 m dv^2 with dv = (1 + e) |v_z|.
    assert energy["lost_velocities"] == pytest.approx(m * ((1 + e) * vz) ** 2 / 2, rel=1e-12)
    assert energy["carnot_defect"] == pytest.approx(energy["carnot_condition"], rel=1e-12)
    assert d["constraints"] == []
    assert d["warnings"] == []
    assert d["momentum"]["linear_residual"] < 1e-14


def test_constraint_keys_and_warnings_as_objects(example_path) -> None:
    d = result_to_dict(solve_impact(load_scenario(example_path("paper_pendulum_plane.toml"))))
    (k,) = d["constraints"]
    assert {"impulse", "moment", "type", "body", "point", "dissipated"} <= set(k)
    assert k["type"] == "pin" and k["other"] is None
    (w,) = d["warnings"]
    assert w["code"] == "statically_indeterminate" and "contacts[0]" in w["where"]
    assert d["contacts"][0]["centre_of_pressure"] is not None
    json.dumps(d, allow_nan=False)


def test_infinite_friction_requirement_is_null() -> None:
    from carnot import FixedBody, ImpactProblem, PointContact, RigidBody

    # A sticking contact that is not approaching: zero normal impulse, any tangential one
    # needs infinite friction; JSON has no infinity.
    body = RigidBody(name="b", mass=1.0, inertia_com=np.eye(3), velocity_com=[1.0, 0, 0])
    res = solve_impact(ImpactProblem(
        bodies={"b": body, "g": FixedBody(name="g")},
        contacts=[PointContact(a="b", b="g", point=[0, 0, -1.0], normal=[0, 0, 1],
                               restitution=0.5, tangential="stick")]))  # fmt: skip
    d = result_to_dict(res)
    assert d["contacts"][0]["friction_required"] is None
    assert "not_approaching" in [w["code"] for w in d["warnings"]]


def test_table_shows_both_routes(example_path) -> None:
    res = solve_impact(load_scenario(example_path("paper_cylinder_edge.toml")))
    text = format_result(res)
    assert "E_d = E' - E'' (direct)" in text and "E_d (theorem)" in text
    assert f"{res.energy.dissipated:.6g}" in text
    assert "cylinder" in text and "No warnings." in text

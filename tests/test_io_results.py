"""Result format 1: every key of DESIGN.md section 4 with its meaning, and the added keys."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.io.results import result_to_dict, result_to_json
from carnot.io.scenario import load_scenario
from carnot.io.table import format_result

# Ball on a floor: m = 0.5 kg, v' = (1, 0, -3) m/s, frictionless, Newton's e = 0.5.
MASS, E, VX, VZ = 0.5, 0.5, 1.0, -3.0
BALL_ON_FLOOR = f"""
format = 1
title = "ball on floor"
[bodies.ball]
mass = {MASS}
shape = "sphere"
radius = 0.1
position = [0.0, 0.0, 0.1]
velocity = [{VX}, 0.0, {VZ}]
[bodies.floor]
fixed = true
[[contacts]]
a = "ball"
b = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
restitution = {E}
"""

# DESIGN.md section 4: these keys, with these meanings, are the contract.
CONTRACT_TOP = {"format", "bodies", "contacts", "constraints", "energy", "warnings"}
CONTRACT_BODY = {"velocity", "angular_velocity", "velocity_before", "angular_velocity_before"}
CONTRACT_CONTACT = {"a", "b", "impulse", "moment", "normal_impulse", "tangential_impulse",
                    "regime", "dissipated"}  # fmt: skip
CONTRACT_CONSTRAINT = {"impulse", "moment"}
CONTRACT_ENERGY = {"before", "after", "dissipated", "dissipated_theorem", "lost_velocities"}

# The keys this version adds (documented in the README): adding is allowed, removing is not.
EXTRA_TOP = {"title", "momentum"}
EXTRA_BODY = {"fixed"}
EXTRA_CONTACT = {"where", "point", "normal", "dissipated_normal", "dissipated_tangential",
                 "dissipated_moment", "friction_required", "centre_of_pressure",
                 "relative_velocity_before", "relative_velocity_after",
                 "relative_angular_velocity_before", "relative_angular_velocity_after",
                 "law", "compression_impulse", "work", "history"}  # fmt: skip
EXTRA_CONSTRAINT = {"where", "type", "body", "other", "point", "dissipated",
                    "relative_velocity_before", "relative_velocity_after"}  # fmt: skip
EXTRA_ENERGY = {"carnot_defect", "carnot_condition", "dissipated_normal",
                "dissipated_tangential", "dissipated_moment"}  # fmt: skip
MOMENTUM = {"linear_residual", "angular_residual", "linear_change", "linear_external",
            "angular_change", "angular_external"}  # fmt: skip


def _ball_on_floor(write_scenario) -> dict:
    return json.loads(result_to_json(solve_impact(load_scenario(write_scenario(BALL_ON_FLOOR)))))


def test_ball_on_floor_against_newton(write_scenario) -> None:
    """Newton's restitution closed form for a ball on a fixed floor (e.g. Stronge, *Impact
    Mechanics*, 2000, section 2.2): v''_n = -e v'_n, the tangential velocity unchanged, the
    normal impulse m (1 + e) |v'_n|, and E_d = (1 - e^2) m v'_n^2 / 2."""
    d = _ball_on_floor(write_scenario)
    assert d["format"] == 1
    ball = d["bodies"]["ball"]
    assert ball["velocity"] == pytest.approx([VX, 0.0, -E * VZ], rel=1e-12)
    assert ball["velocity_before"] == [VX, 0.0, VZ]
    assert ball["angular_velocity"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)
    assert ball["angular_velocity_before"] == [0.0, 0.0, 0.0]
    assert d["bodies"]["floor"]["fixed"] is True and ball["fixed"] is False
    (c,) = d["contacts"]
    assert (c["a"], c["b"], c["regime"], c["where"]) == ("ball", "floor", "frictionless",
                                                         "contacts[0]")  # fmt: skip
    assert c["impulse"] == pytest.approx([0.0, 0.0, -(1 + E) * MASS * VZ], rel=1e-12)
    assert c["moment"] == [0.0, 0.0, 0.0]
    assert c["normal_impulse"] == pytest.approx(-(1 + E) * MASS * VZ, rel=1e-12)
    assert c["tangential_impulse"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)
    assert c["point"] == [0.0, 0.0, 0.0] and c["normal"] == [0.0, 0.0, 1.0]
    assert c["relative_velocity_before"] == [VX, 0.0, VZ]
    assert c["relative_velocity_after"] == pytest.approx([VX, 0.0, -E * VZ], rel=1e-12)
    e_d = (1 - E**2) * MASS * VZ**2 / 2  # Newton's closed form
    assert c["dissipated"] == pytest.approx(e_d, rel=1e-12)
    assert c["dissipated_normal"] == pytest.approx(e_d, rel=1e-12)
    assert c["dissipated_tangential"] == 0.0 and c["dissipated_moment"] == 0.0
    energy = d["energy"]
    assert energy["before"] == pytest.approx(MASS * (VX**2 + VZ**2) / 2, rel=1e-15)
    assert energy["dissipated"] == pytest.approx(e_d, rel=1e-12)
    assert energy["dissipated_theorem"] == pytest.approx(e_d, rel=1e-12)
    assert energy["dissipated"] == pytest.approx(energy["dissipated_theorem"], rel=1e-12)
    assert energy["after"] == pytest.approx(energy["before"] - e_d, rel=1e-12)
    # Carnot: E_p = 1/2 m dv^2 with dv = (1 + e) |v'_z|; E_d - E_p = -P . w''.
    assert energy["lost_velocities"] == pytest.approx(MASS * ((1 + E) * VZ) ** 2 / 2, rel=1e-12)
    p_dot_w_after = -(1 + E) * MASS * VZ * (-E * VZ)
    assert energy["carnot_condition"] == pytest.approx(-p_dot_w_after, rel=1e-12)
    assert energy["carnot_defect"] == pytest.approx(energy["carnot_condition"], rel=1e-12)
    assert d["constraints"] == []
    assert d["warnings"] == []
    assert d["momentum"]["linear_residual"] < 1e-14
    # The floor gave the ball the contact impulse: change of momentum = external impulse.
    assert d["momentum"]["linear_change"] == pytest.approx(c["impulse"], rel=1e-12)
    assert d["momentum"]["linear_external"] == pytest.approx(c["impulse"], rel=1e-12)


def test_keys_are_the_contract_plus_the_documented_extras(example_path) -> None:
    """Every key of DESIGN.md section 4, and nothing undocumented, at every level."""
    d = result_to_dict(solve_impact(load_scenario(example_path("paper_pendulum_plane.toml"))))
    assert set(d) == CONTRACT_TOP | EXTRA_TOP
    for body in d["bodies"].values():
        assert set(body) == CONTRACT_BODY | EXTRA_BODY
    assert d["contacts"] and d["constraints"] and d["warnings"]
    for contact in d["contacts"]:
        assert set(contact) == CONTRACT_CONTACT | EXTRA_CONTACT
    for constraint in d["constraints"]:
        assert set(constraint) == CONTRACT_CONSTRAINT | EXTRA_CONSTRAINT
    assert set(d["energy"]) == CONTRACT_ENERGY | EXTRA_ENERGY
    assert set(d["momentum"]) == MOMENTUM
    for warning in d["warnings"]:
        assert set(warning) == {"code", "where", "message"}
        assert all(isinstance(v, str) for v in warning.values())


def test_json_text_round_trips_to_the_dict(example_path) -> None:
    res = solve_impact(load_scenario(example_path("paper_cylinder_edge.toml")))
    assert json.loads(result_to_json(res)) == result_to_dict(res)
    assert result_to_json(res).startswith('{\n  "format": 1,')


def test_constraint_keys_and_warnings_as_objects(example_path) -> None:
    d = result_to_dict(solve_impact(load_scenario(example_path("paper_pendulum_plane.toml"))))
    (k,) = d["constraints"]
    assert k["type"] == "pin" and k["other"] is None and k["where"] == "constraints[0]"
    assert len(k["impulse"]) == 3 and k["moment"] == [0.0, 0.0, 0.0]
    (w,) = d["warnings"]
    assert w["code"] == "statically_indeterminate" and "contacts[0]" in w["where"]
    assert d["contacts"][0]["centre_of_pressure"] is not None
    json.dumps(d, allow_nan=False)


def test_impulses_follow_the_scenario_order(example_path) -> None:
    """``contacts`` and ``constraints`` list their entries in the scenario's order."""
    problem = load_scenario(example_path("paper_pendulum_plane.toml"))
    d = result_to_dict(solve_impact(problem))
    assert [c["where"] for c in d["contacts"]] == [c.where for c in problem.contacts]
    assert [k["where"] for k in d["constraints"]] == [k.where for k in problem.constraints]


def test_infinite_friction_requirement_is_null() -> None:
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
    json.dumps(d, allow_nan=False)


def test_non_finite_numbers_become_null(write_scenario) -> None:
    """Whatever overflowed, the JSON stays valid: a non-finite number or entry is ``null``."""
    res = solve_impact(load_scenario(write_scenario(BALL_ON_FLOOR)))
    ball = dataclasses.replace(res.bodies["ball"], velocity_after=np.array([1.0, np.inf, 0.0]))
    broken = dataclasses.replace(
        res,
        bodies={**res.bodies, "ball": ball},
        energy=dataclasses.replace(res.energy, after=float("nan")),
    )
    d = json.loads(result_to_json(broken))
    assert d["bodies"]["ball"]["velocity"] == [1.0, None, 0.0]
    assert d["energy"]["after"] is None


def test_table_shows_the_numbers(write_scenario) -> None:
    res = solve_impact(load_scenario(write_scenario(BALL_ON_FLOOR)))
    text = format_result(res)
    assert text.startswith("ball on floor\n=============")
    assert "E_d = E' - E'' (direct)" in text and "E_d (theorem)" in text
    e_d = (1 - E**2) * MASS * VZ**2 / 2
    assert f"{e_d:.6g}" in text  # 1.6875
    assert "[1, 0, -3]" in text and "[1, 0, 1.5]" in text  # v before and after
    assert f"{-(1 + E) * MASS * VZ:.6g}" in text  # normal impulse, 2.25
    assert f"{MASS * (VX**2 + VZ**2) / 2:.6g}" in text  # E', 2.5
    assert "frictionless" in text and "ball/floor" in text and "No warnings." in text
    bodies_section = text.split("Contacts and constraints")[0]
    assert "  ball " in bodies_section and "  floor " not in bodies_section  # fixed: no row


def test_table_lists_warnings_and_constraints(example_path) -> None:
    res = solve_impact(load_scenario(example_path("paper_pendulum_plane.toml")))
    text = format_result(res)
    assert "Warnings" in text and "[statically_indeterminate]" in text
    assert "constraints[0]" in text and "/world" in text
    assert "Momentum balance" in text

"""Systems in generalized coordinates (carnot.model.system, DESIGN.md section 7): validation,
rows that move nothing, pins from floating-point states, [system] scenario files and the CLI.

Closed forms: a point mass on a plane (any textbook: Newton's restitution and sticking remove
the normal and the tangential velocity), a pendulum struck at its centre of percussion
(no pivot reaction; Goldsmith, *Impact*, 1960, ch. 2).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from chains import Chain

from carnot import FixedBody, ImpactProblem, InputError, Pin, RigidBody, solve_impact
from carnot.cli import main
from carnot.io.results import result_to_dict
from carnot.io.scenario import load_problem, parse_scenario
from carnot.io.system_scenario import parse_system_scenario
from carnot.model.system import (
    System,
    SystemConstraint,
    SystemContact,
    SystemProblem,
    assemble_system,
)


def point_mass(velocity: list[float], **contact: object) -> SystemProblem:
    """A point mass of 2 kg in the plane (x, y) landing on the floor y = 0."""
    return SystemProblem(
        system=System(mass_matrix=np.eye(2) * 2.0, velocity=velocity, coordinates=("x", "y")),
        contacts=[SystemContact(jacobian=[[1, 0], [0, 1], [0, 0]], normal=[0, 1, 0], **contact)],  # type: ignore[arg-type]
    )


def test_point_mass_newton_and_stick_closed_forms() -> None:
    r = solve_impact(point_mass([0.5, -2.0], restitution=0.5))
    assert r.system is not None
    assert r.system.velocity_after.tolist() == [0.5, 1.0]  # y'' = -e y'
    assert r.energy.dissipated == pytest.approx(0.5 * 2 * (4 - 1), rel=1e-14)
    assert r.contacts[0].generalized_impulse.tolist() == [0.0, 6.0]  # J^T P = (0, m 3)
    stuck = solve_impact(point_mass([0.5, -2.0], restitution=0.0, tangential="stick"))
    assert np.allclose(stuck.system.velocity_after, 0.0, atol=1e-15)
    # planar: the out-of-plane tangent is dropped, not flagged as redundant
    assert stuck.warnings == ()


def test_rows_that_move_nothing_are_dropped_per_group() -> None:
    """A planar pin keeps two rows; a sticking contact one tangent; the rotated basis in a
    plane that is not a coordinate plane too."""
    tilt = np.array(
        [[1.0, 0, 0], [0, math.cos(0.3), -math.sin(0.3)], [0, math.sin(0.3), math.cos(0.3)]]
    )
    jac = tilt @ np.array([[1.0, 0], [0, 1.0], [0, 0]])  # the plane tilted about x
    normal = tilt @ np.array([0, 1.0, 0])
    problem = SystemProblem(
        system=System(mass_matrix=np.eye(2), velocity=[1.0, -1.0]),
        contacts=[SystemContact(jacobian=jac, normal=normal, tangential="stick")],
        constraints=[SystemConstraint(kind="fasten", jacobian=jac)],
    )
    space = assemble_system(problem)
    assert space.blocks[0].roles == ("normal", "tangent")
    assert space.blocks[1].roles == ("bilateral", "bilateral")
    r = solve_impact(problem)
    assert "statically_indeterminate" in r.flag_codes()  # the fasten and the contact: truly
    assert np.allclose(r.system.velocity_after, 0.0, atol=1e-15)


def test_pendulum_struck_at_its_centre_of_percussion() -> None:
    """A rod (m, L) pinned at its top end, in its angle: a given horizontal impulse at
    2L/3 below the pivot leaves no reaction at the pivot (Goldsmith 1960)."""
    m, length, impulse = 1.5, 1.2, 0.8
    chain = Chain(masses=[m], lengths=[length], angles=[-math.pi / 2], rates=[0.0], base="floating")
    system = System(mass_matrix=chain.mass_matrix(), velocity=chain.velocity)
    r = solve_impact(
        SystemProblem(
            system=system,
            contacts=[
                SystemContact(
                    jacobian=chain.jacobian(0, 2 * length / 3),
                    normal=[1, 0, 0],
                    impulse=[impulse, 0, 0],
                )
            ],
            constraints=[SystemConstraint(kind="pin", jacobian=chain.base_jacobian())],
        )
    )
    assert np.linalg.norm(r.constraints[0].impulse) < 1e-14
    # omega'' = P (2L/3) / (m L^2 / 3)
    assert r.system.velocity_after[2] == pytest.approx(
        impulse * 2 * length / 3 / (m * length**2 / 3), rel=1e-13
    )


@pytest.mark.parametrize(
    ("mass", "message"),
    [
        ([[1.0, 2.0], [2.0, 1.0]], "must be positive definite"),
        ([[1.0, 0.1], [0.0, 1.0]], "must be symmetric"),
        ([[1.0, 0.0]], "must be square"),
        ([[1.0, float("nan")], [float("nan"), 1.0]], "must have finite entries"),
        ([["a", 0], [0, 1]], "must be a k x n matrix of numbers"),
    ],
)
def test_mass_matrix_is_checked(mass: object, message: str) -> None:
    with pytest.raises(InputError, match=rf"system\.mass_matrix: {message}"):
        System(mass_matrix=mass, velocity=[0.0, 0.0])  # type: ignore[arg-type]


def test_shapes_are_checked_naming_the_field() -> None:
    with pytest.raises(InputError, match=r"system\.velocity: must be a list of 2 numbers"):
        System(mass_matrix=np.eye(2), velocity=[1.0])
    with pytest.raises(InputError, match=r"system\.coordinates: must name 2 coordinates"):
        System(mass_matrix=np.eye(2), velocity=[1.0, 0], coordinates=("x",))
    with pytest.raises(InputError, match=r"contacts\[0\]\.jacobian: must be 3 x n .*got '2 x 2'"):
        SystemContact(jacobian=np.eye(2), normal=[0, 1, 0])
    with pytest.raises(InputError, match=r"contacts\[0\]\.jacobian: must have 2 columns .*got 3"):
        SystemProblem(
            system=System(mass_matrix=np.eye(2), velocity=[0, 0]),
            contacts=[SystemContact(jacobian=np.zeros((3, 3)), normal=[0, 1, 0])],
        )
    with pytest.raises(
        InputError,
        match=r"contacts\[0\]\.angular_jacobian: is required with "
        "patch",
    ):
        SystemContact(
            jacobian=np.zeros((3, 2)),
            normal=[0, 1, 0],
            point=[0, 0, 0],
            patch=[[1, 0, 0], [-1, 0, 0]],
        )
    with pytest.raises(InputError, match=r"contacts\[0\]\.normal: no motion of the system"):
        solve_impact(
            SystemProblem(
                system=System(mass_matrix=np.eye(2), velocity=[1.0, 0]),
                contacts=[
                    SystemContact(
                        jacobian=[[1, 0], [0, 0], [0, 1]], normal=[0, 1, 0], tangential="stick"
                    )
                ],
            )
        )
    with pytest.raises(InputError, match=r"contacts\[0\]\.restitution: must be in \[0, 1\]"):
        SystemContact(jacobian=np.zeros((3, 1)), normal=[0, 1, 0], restitution=2)


def test_pin_from_a_floating_point_state_is_accepted() -> None:
    """Issue 15's defect: a double pendulum whose pivot velocity comes out of floating-point
    arithmetic (1e-16 m/s, not 0) was refused as "a pin on a moving point". The rest tolerance
    scales with the velocity scale of the bodies (free bodies) or of the point (a system)."""
    chain = Chain(
        masses=[1.0, 0.8],
        lengths=[1.0, 0.7],
        angles=[-1.1, -0.4],
        rates=[-1.3, 2.1],
        base="floating",
        base_rate=[0.0, 0.0],
    )
    # a state computed in floating point: the pivot rate is round-off of a rotation
    angle = 0.7
    rot = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    base_rate = rot.T @ (rot @ np.array([0.0, 0.0]) + np.array([1e-16, -2e-16]))
    chain.base_rate = base_rate.tolist()
    assert np.linalg.norm(chain.base_rate) > 0  # really not exactly zero
    tip = (1, 0.7, {"normal": [0, 1, 0], "restitution": 0.5})
    from test_system_twins import assert_agree, twins

    generalized, bodies = twins(chain, [tip], base_pin=True)
    assert_agree(chain, generalized, bodies)
    # the free-body pendulum whose pivot speed is round-off: accepted too
    body = RigidBody(
        name="rod",
        mass=1.0,
        inertia_com=np.diag([0.01, 0.1, 0.1]),
        position_com=[0, -0.5, 0],
        velocity_com=[1.0, 1e-16, 0],
        angular_velocity=[0, 0, 2.0 + 1e-15],
    )
    r = solve_impact(
        ImpactProblem(
            bodies={"rod": body, "g": FixedBody(name="g")},
            constraints=[Pin(body="rod", point=[0, 0, 0])],
        )
    )
    assert np.linalg.norm(r.constraints[0].impulse) < 1e-12


def test_a_moving_pin_is_refused() -> None:
    with pytest.raises(InputError, match=r"constraints\[0\]: a pin needs zero relative velocity"):
        solve_impact(
            SystemProblem(
                system=System(mass_matrix=np.eye(2), velocity=[1.0, 1e-3]),
                constraints=[SystemConstraint(kind="pin", jacobian=[[0, 1], [0, 0], [0, 0]])],
            )
        )


SCENARIO = """format = 1
title = "A point mass lands on a rough floor"

[system]
coordinates = ["x", "y"]
mass_matrix = [[2.0, 0.0], [0.0, 2.0]]
velocity = [0.5, -2.0]

[[contacts]]
name = "foot"
jacobian = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]
normal = [0.0, 1.0, 0.0]
point = [0.0, 0.0, 0.0]
restitution = 0.5
tangential = "stick"
"""


def test_system_scenario_file_and_cli(tmp_path, capsys) -> None:
    path = tmp_path / "mass.toml"
    path.write_text(SCENARIO)
    problem = load_problem(path)
    assert isinstance(problem, SystemProblem) and problem.contacts[0].name == "foot"
    assert main(["solve", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "bodies" not in data
    assert data["system"]["coordinates"] == ["x", "y"]
    assert data["system"]["velocity_before"] == [0.5, -2.0]
    assert data["system"]["velocity"] == pytest.approx([0.0, 1.0], abs=1e-15)
    contact = data["contacts"][0]
    assert contact["name"] == "foot" and contact["regime"] == "stick"
    assert contact["generalized_impulse"] == pytest.approx([-1.0, 6.0], abs=1e-14)
    assert data["energy"]["dissipated"] == pytest.approx(0.5 * 2 * (0.25 + 4 - 1), rel=1e-14)
    assert main(["solve", str(path)]) == 0
    table = capsys.readouterr().out
    assert "Generalized impulses J^T P" in table and "foot" in table


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            ("velocity = [0.5, -2.0]", "velocity = [0.5]"),
            "mass.toml: system.velocity: must be a list of 2 numbers",
        ),
        (
            ('name = "foot"', 'name = "foot"\ncolour = 1'),
            r"mass.toml: contacts\[0\].colour: unknown key",
        ),
        (
            ("jacobian = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]", "jacobian = [[1.0, 0.0]]"),
            r"mass.toml: contacts\[0\].jacobian: must be 3 x n",
        ),
        (
            ("mass_matrix = [[2.0, 0.0], [0.0, 2.0]]", "mass_matrix = [[2.0, 3.0], [3.0, 2.0]]"),
            "mass.toml: system.mass_matrix: must be positive definite",
        ),
        (("[system]", "[system]\nmass = 1"), "mass.toml: system.mass: unknown key"),
    ],
)
def test_system_scenario_errors_exit_2_with_one_line(tmp_path, capsys, edit, message) -> None:
    path = tmp_path / "mass.toml"
    path.write_text(SCENARIO.replace(*edit))
    assert main(["solve", str(path)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    import re

    assert re.search(message, err), err


def test_free_body_readers_say_what_a_system_needs() -> None:
    with pytest.raises(InputError, match="system: a system in generalized coordinates"):
        parse_scenario({"format": 1, "system": {}})
    with pytest.raises(InputError, match=r"s.json: system: must be a table"):
        parse_system_scenario({"format": 1, "system": 3}, "s.json")


def test_result_keys_of_a_system() -> None:
    d = result_to_dict(solve_impact(point_mass([0.0, -1.0], restitution=0.0)))
    assert list(d)[:3] == ["format", "title", "system"]
    assert "momentum" not in d and d["contacts"][0]["b"] is None
    assert d["system"]["momentum_residual"] == 0.0


def test_fasten_with_angular_rows_is_a_weld() -> None:
    """A free rod (1 kg, 1 m; coordinates x, y, phi of its centre) suddenly fastened at its
    end p: as a point fastening it turns about p keeping its angular momentum about p,
    ``phi'' = H_p / I_p`` (``I_p = m l^2 / 3``); with the angular rows too (a weld) it stops,
    ``P = -m v_c`` and ``M_P + (p - c) x P = -I_c omega`` (its angular momentum about c
    taken away)."""
    m, length, i_c = 1.0, 1.0, 1.0 / 12
    v_c, omega = np.array([0.3, -1.2, 0.0]), 0.8
    c, p = np.zeros(3), np.array([0.5, 0.0, 0.0])
    r = p - c
    jac = np.array([[1.0, 0.0, -r[1]], [0.0, 1.0, r[0]], [0.0, 0.0, 0.0]])  # v + omega x r
    rot = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    system = System(mass_matrix=np.diag([m, m, i_c]), velocity=[v_c[0], v_c[1], omega],
                    coordinates=("x", "y", "phi"))  # fmt: skip
    point = solve_impact(SystemProblem(system=system, constraints=[
        SystemConstraint(kind="fasten", jacobian=jac, point=p)]))  # fmt: skip
    h_p = i_c * omega + np.cross(c - p, m * v_c)[2]
    assert point.system.velocity_after[2] == pytest.approx(h_p / (m * length**2 / 3), rel=1e-13)
    weld = solve_impact(SystemProblem(system=system, constraints=[
        SystemConstraint(kind="fasten", jacobian=jac, angular_jacobian=rot, point=p)]))  # fmt: skip
    assert np.allclose(weld.system.velocity_after, 0.0, atol=1e-14)
    held = weld.constraints[0]
    assert np.allclose(held.impulse, -m * v_c, atol=1e-14)
    assert (held.moment + np.cross(r, held.impulse))[2] == pytest.approx(-i_c * omega, abs=1e-14)
    assert weld.energy.dissipated == pytest.approx(weld.energy.before, rel=1e-14)
    assert weld.energy.dissipated == pytest.approx(weld.energy.dissipated_theorem, rel=1e-13)
    # a pin's angular rows must be at rest before the impact, as its linear ones
    with pytest.raises(InputError, match=r"constraints\[0\].angular_jacobian: a pin needs zero "
                                         "relative angular velocity"):  # fmt: skip
        solve_impact(SystemProblem(system=System(mass_matrix=np.eye(2), velocity=[0.0, 0.5]),
                                   constraints=[SystemConstraint(kind="pin",
                                   jacobian=[[1, 0], [0, 0], [0, 0]],
                                   angular_jacobian=[[0, 0], [0, 0], [0, 1]])]))  # fmt: skip
    with pytest.raises(InputError, match=r"constraints\[0\].angular_jacobian: must be 3 x 2"):
        SystemConstraint(kind="pin", jacobian=[[1, 0], [0, 0], [0, 0]],
                         angular_jacobian=[[0, 1]])  # fmt: skip

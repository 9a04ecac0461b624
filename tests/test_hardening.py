"""Issue 19: every input solves with finite numbers or exits 2 with one line naming the field.

The reproducers of the issue (tests/data/reliability, copied from the report) and the limits
the loader now states: magnitudes (carnot.validate), file size, nesting depth, integers beyond
float64, byte-order marks, duplicate JSON keys, control characters in names; and the command
line's own errors (one line naming the sub-command).
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import carnot.io.scenario as scenario
from carnot import FixedBody, ImpactProblem, InputError, PointContact, RigidBody, solve_impact
from carnot.cli import main
from carnot.validate import MAX_MAGNITUDE, MIN_SCALE, unit_vector, vector3

DATA = Path(__file__).parent / "data" / "reliability"

#: reproducer -> substrings of the one line on stderr (None: it solves, exit 0)
REPROS = {
    "c0039.toml": ["constraints[1].point", "at most 1e+50", "1e+308"],
    "c0076.toml": ["bodies.rod.length", "at most 1e+50", "1e+200"],
    "c0173.toml": ["contacts[0].point", "at most 1e+50"],
    "c0225.toml": None,  # a normal [1e308, -0.6, 0]: a direction, normalised without overflow
    "c0235.toml": ["bodies.A.velocity", "at most 1e+50", "1e+200"],
    "c0475.toml": ["bodies.ball.mass", ">= 1e-50", "1e-320"],
    "c0507.toml": ["bodies.ball.mass", ">= 1e-50", "1e-320"],
    "c0638.toml": ["contacts[0].patch[0]", "contact plane"],  # normal [1e308, 1e308, 0]
    "c0688.toml": ["bodies.ball.inertia", ">= 1e-50 kg m^2"],
    "c0748.toml": ["bodies.cylinder.inertia", ">= 1e-50 kg m^2"],
    "c0967.toml": ["bodies", "control characters", "'bad\\nname'"],
    "c0979.json": ["bodies.ball.mass", "at most 1e+50", "an integer of about 401 digits"],
    "c1444.toml": ["contacts[0].impulse", "at most 1e+50", "1e+300"],
    "c1487.json": ["nested deeper than 32 levels"],
    "c1489.toml": ["nested deeper than 32 levels", "line 2"],
    "c1491.toml": ["malformed TOML", "4300 digits"],
}


def _run(args: list[str], capsys) -> tuple[int, str, str]:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a NumPy RuntimeWarning is a failure here
        try:
            code = main(args)
        except SystemExit as stop:
            code = int(stop.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


def _finite(node) -> bool:
    if isinstance(node, float):
        return math.isfinite(node)
    if isinstance(node, dict):
        return all(_finite(v) for v in node.values())
    if isinstance(node, list):
        return all(_finite(v) for v in node)
    return True


@pytest.mark.parametrize("name", sorted(REPROS))
def test_the_reproducers(name: str, capsys) -> None:
    path = DATA / name
    code, out, err = _run(["solve", str(path), "--json"], capsys)
    expected = REPROS[name]
    if expected is None:
        assert code == 0 and err == ""
        result = json.loads(out)
        assert _finite(result)
        e = result["energy"]
        assert abs(e["dissipated"] - e["dissipated_theorem"]) <= 1e-12 * e["before"]
        return
    assert code == 2
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"carnot: error: {path}: ")
    for part in expected:
        assert part in lines[0], part


BALL = """format = 1
[bodies.ball]
mass = {mass}
inertia = [[{j}, 0, 0], [0, {j}, 0], [0, 0, {j}]]
position = [0.0, 0.0, 0.1]
velocity = [0.0, 0.0, {v}]
[bodies.floor]
fixed = true
[[contacts]]
a = "ball"
b = "floor"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
restitution = 0.5
"""


@pytest.mark.parametrize("mass, v", [(1e50, -1e50), (MIN_SCALE, -1e-50), (1e-50, -1e50),
                                     (1e50, -1e-50), (1.0, -5e-324)])  # fmt: skip
def test_the_bounds_themselves_solve_as_the_closed_form(mass, v, write_scenario, capsys) -> None:
    """At the stated bounds the answer is still the textbook one: a ball dropped onto a floor
    with Newton's e rebounds at ``-e v`` and loses ``(1 - e^2) m v^2 / 2`` (Stronge,
    *Impact Mechanics*, 2000, section 2.1), by both routes of the ledger."""
    path = write_scenario(BALL.format(mass=mass, j=max(0.004 * mass, MIN_SCALE), v=v))
    code, out, err = _run(["solve", str(path), "--json"], capsys)
    assert code == 0 and err == ""
    result = json.loads(out)
    assert _finite(result)
    assert result["bodies"]["ball"]["velocity"][2] == pytest.approx(-0.5 * v, rel=1e-12)
    lost = 0.5 * (1 - 0.25) * mass * v * v
    for key in ("dissipated", "dissipated_theorem"):
        assert result["energy"][key] == pytest.approx(lost, rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("mass, v, part", [
    (1.0000001e50, -1.0, "bodies.ball.mass: must be at most 1e+50"),
    (0.99999e-50, -1.0, "bodies.ball.mass: must be >= 1e-50"),
    (1.0, -1.0000001e50, "bodies.ball.velocity: must be at most 1e+50"),
])  # fmt: skip
def test_just_past_the_bounds_is_refused(mass, v, part, write_scenario, capsys) -> None:
    path = write_scenario(BALL.format(mass=mass, j=0.004, v=v))
    code, _, err = _run(["solve", str(path)], capsys)
    assert code == 2 and len(err.splitlines()) == 1 and part in err


def test_an_impact_may_carry_the_state_past_the_input_bound() -> None:
    """Inputs at 1e50 may give velocities after of more than 1e50: a result, not an input,
    so it is not refused (it was, naming bodies.ball.angular_velocity)."""
    ball = RigidBody(name="ball", mass=1e50, inertia_com=np.eye(3) * 1e50,
                     position_com=[0, 0, 0.033], velocity_com=[1e50, 1e50, -1e50],
                     angular_velocity=[1e50, 1e50, 1e50])  # fmt: skip
    contact = PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
                           restitution=0.75, friction=0.3, tangential="stick")  # fmt: skip
    result = solve_impact(ImpactProblem(bodies={"ball": ball, "floor": FixedBody(name="floor")},
                                        contacts=[contact]))  # fmt: skip
    assert np.max(np.abs(result.bodies["ball"].angular_velocity_after)) > MAX_MAGNITUDE
    e = result.energy
    assert abs(e.dissipated - e.dissipated_theorem) <= 1e-12 * e.before


def test_a_shape_is_held_to_the_bounds_of_the_inertia_it_gives(write_scenario, capsys) -> None:
    text = BALL.replace("inertia = [[{j}, 0, 0], [0, {j}, 0], [0, 0, {j}]]",
                        'shape = "sphere"\nradius = 1e-10')  # fmt: skip
    path = write_scenario(text.format(mass=1e-40, j=0, v=-1.0))
    code, _, err = _run(["solve", str(path)], capsys)
    assert code == 2
    assert "bodies.ball.shape (sphere: its inertia): principal moments must each be >= 1e-50" in err


def test_directions_of_any_finite_length() -> None:
    assert unit_vector([1e308, 1e308, 0], "n").tolist() == pytest.approx([2**-0.5, 2**-0.5, 0])
    assert unit_vector([3e-320, 4e-320, 0], "n").tolist() == pytest.approx([0.6, 0.8, 0], rel=1e-3)
    assert unit_vector([0, 1, -1e308], "n").tolist() == [0.0, 0.0, -1.0]
    assert unit_vector([-0.8, -0.6, 0.0], "n").tolist() == [-0.8, -0.6, 0.0]  # as before
    with pytest.raises(InputError, match="an integer beyond float64"):
        vector3([10**400, 0, 0], "velocity")


def test_a_byte_order_mark_is_accepted(write_scenario, capsys, tmp_path) -> None:
    text = BALL.format(mass=1.0, j=0.004, v=-2.0)
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    code, out, _ = _run(["solve", str(path), "--json"], capsys)
    assert code == 0 and json.loads(out)["energy"]["dissipated"] == pytest.approx(1.5)
    as_json = tmp_path / "bom.json"
    as_json.write_bytes(b"\xef\xbb\xbf" + json.dumps(scenario.read_scenario_data(path)).encode())
    assert _run(["solve", str(as_json)], capsys)[0] == 0


def test_file_size_limit(tmp_path, monkeypatch, capsys) -> None:
    path = tmp_path / "big.toml"
    path.write_text("format = 1\n" + "# padding\n" * 20)
    monkeypatch.setattr(scenario, "MAX_FILE_BYTES", 100)
    code, _, err = _run(["solve", str(path)], capsys)
    assert code == 2 and "is larger than 100 bytes" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_nesting_depth_limit(suffix, tmp_path, capsys) -> None:
    for depth, refused in ((32, False), (33, True), (100_000, True)):
        inner = depth - 1 if suffix == ".json" else depth  # the JSON object is a level
        nest = "[" * inner + "]" * inner
        text = (f'{{"format": 1, "title": {nest}}}' if suffix == ".json"
                else f"format = 1\ntitle = {nest}\n")  # fmt: skip
        path = tmp_path / f"deep{depth}{suffix}"
        path.write_text(text)
        code, _, err = _run(["solve", str(path)], capsys)
        assert code == 2 and len(err.splitlines()) == 1
        assert ("nested deeper than 32 levels" in err) == refused, err
        if not refused:
            assert "title: must be a string" in err  # parsed, then refused for its meaning


def test_brackets_in_strings_and_comments_do_not_count(tmp_path) -> None:
    text = 'format = 1 # ' + "[" * 50 + "\ntitle = '" + "{" * 50 + "'\n"
    path = tmp_path / "strings.toml"
    path.write_text(text)
    assert scenario.read_scenario_data(path)["title"] == "{" * 50


def test_huge_integers_and_duplicate_keys(tmp_path, capsys) -> None:
    digits = "1" + "0" * 5000
    for name, text, part in [
        ("i.json", '{"format": 1, "title": ' + digits + "}", "malformed JSON: a number"),
        ("d.json", '{"format": 1, "bodies": {}, "format": 1}', "duplicate key 'format'"),
        ("d.toml", "format = 1\nformat = 1\n", "malformed TOML"),
    ]:
        path = tmp_path / name
        path.write_text(text)
        code, _, err = _run(["solve", str(path)], capsys)
        assert code == 2 and len(err.splitlines()) == 1 and part in err, err


@pytest.mark.parametrize("name", ["two\nlines", "tab\there", "nul\x00", "esc\x1b[31m"])
def test_control_characters_in_names_are_refused(name, write_scenario, capsys) -> None:
    text = BALL.format(mass=1.0, j=0.004, v=-2.0).replace("ball", json.dumps(name)[1:-1])
    text = text.replace(f"[bodies.{json.dumps(name)[1:-1]}]", f"[bodies.{json.dumps(name)}]")
    code, _, err = _run(["solve", str(write_scenario(text))], capsys)
    assert code == 2 and len(err.splitlines()) == 1
    assert "must not contain control characters" in err


@pytest.mark.parametrize("args, line", [
    (["paper", "--bogus"], "paper: unrecognized arguments: --bogus (see carnot paper --help)"),
    (["prove", "--bogus"], "prove: unrecognized arguments: --bogus (see carnot prove --help)"),
    (["derive"], "derive: the following arguments are required: file (see carnot derive --help)"),
    (["solve", "a.toml", "--contact", "x"], "solve: argument --contact: invalid int value: 'x'"),
    (["nonsense"], "argument COMMAND: invalid choice: 'nonsense'"),
])  # fmt: skip
def test_argparse_errors_are_one_line_naming_the_command(args, line, capsys) -> None:
    code, _, err = _run(args, capsys)
    assert code == 2 and len(err.splitlines()) == 1 and line in err


def test_contact_without_plot_is_refused(capsys) -> None:
    path = str(Path(__file__).parent.parent / "examples" / "ball_rough_court.toml")
    code, out, err = _run(["solve", path, "--contact", "5"], capsys)
    assert code == 2 and out == ""
    assert err.splitlines() == [
        "carnot: error: --contact: chooses the contact to draw: it goes with --plot, got 5"
    ]


def test_derive_names_the_file_for_a_coulomb_contact(capsys) -> None:
    path = str(Path(__file__).parent.parent / "examples" / "ball_rough_court.toml")
    code, _, err = _run(["derive", path], capsys)
    assert code == 2 and len(err.splitlines()) == 1
    assert err.startswith(f"carnot: error: {path}: contacts[0].friction: Coulomb friction")


# ---------------------------------------------------------------------------------------------
# The API: Hypothesis over magnitudes spanning the whole accepted range

decade = st.floats(min_value=-50, max_value=50)


@settings(max_examples=150, deadline=None)
@given(mass=decade, length=st.floats(-20, 20), speed=decade, spin=decade,
       e=st.floats(0, 1), mu=st.sampled_from([0.0, 0.3, 3.0]),
       law=st.sampled_from(["newton", "poisson", "stronge"]),
       direction=st.tuples(*[st.floats(-1, 1)] * 3).filter(
           lambda d: sum(x * x for x in d) > 0.01))  # fmt: skip
def test_any_accepted_magnitudes_give_finite_results_or_an_input_error(
    mass, length, speed, spin, e, mu, law, direction
) -> None:
    """A ball of any accepted mass and size, at any accepted speed and spin, on a floor:
    the result is finite and its ledger closes (theorem = direct difference, to round-off of
    the energies), or the solver refuses it with an InputError; never another exception, a
    NumPy warning, or a non-finite number."""
    m, r = 10.0**mass, 10.0**length
    inertia = max(0.4 * m * r * r, MIN_SCALE)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            problem = _ball_on_floor(m, r, inertia, direction, speed, spin, e, mu, law)
            result = solve_impact(problem)
        except InputError:
            return
    energy = result.energy
    numbers = [energy.before, energy.after, energy.dissipated, energy.dissipated_theorem,
               *result.row_impulses]  # fmt: skip
    assert all(math.isfinite(x) for x in numbers)
    scale = energy.before + energy.after
    assert abs(energy.dissipated - energy.dissipated_theorem) <= 1e-9 * scale


def _ball_on_floor(m, r, inertia, direction, speed, spin, e, mu, law) -> ImpactProblem:
    ball = RigidBody(name="ball", mass=m, inertia_com=np.eye(3) * inertia, position_com=[0, 0, r],
                     velocity_com=np.array(direction) * 10.0**speed - [0, 0, 10.0**speed],
                     angular_velocity=np.array(direction[::-1]) * 10.0**spin)  # fmt: skip
    contact = PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1], restitution=e,
                           law=law, friction=mu)  # fmt: skip
    return ImpactProblem(bodies={"ball": ball, "floor": FixedBody(name="floor")},
                         contacts=[contact])  # fmt: skip


def test_a_solver_refusal_names_the_file_and_the_contact(monkeypatch, capsys) -> None:
    """Defect 6's message named neither: a refusal from the frictional integration (a jam,
    or an integration that does not converge) now carries both."""
    import carnot.laws.coulomb
    from carnot.laws.friction import ImpactJamError

    def refuse(*args, **kwargs):
        raise ImpactJamError("the contact jams (test)")

    monkeypatch.setattr(carnot.laws.coulomb, "integrate_impact", refuse)
    path = str(Path(__file__).parent.parent / "examples" / "ball_rough_court.toml")
    code, _, err = _run(["solve", path], capsys)
    assert code == 2
    assert err.splitlines() == [f"carnot: error: {path}: contacts[0]: the contact jams (test)"]

"""Periodic orbits of MJCF models through held contacts (carnot.hybrid.cycle with
carnot.hybrid.section; ``carnot cycle model.xml``), against a published closed form and a
second route.

**The closed form.** McGeer's rimless wheel (*Passive dynamic walking*, IJRR 9, 1990; as in
Tedrake's *Underactuated Robotics*, "Simple models of walking"): a hub of mass ``m`` and
inertia ``I`` on ``N`` massless spokes of length ``l``, ``2 alpha = 2 pi / N`` apart, rolling
down a slope ``gamma`` under ``g``. Each plastic, sticking strike keeps the angular momentum
about the new foot, ``omega+ = c omega-``, ``c = (m l^2 cos 2 alpha + I) / (m l^2 + I)``;
each stance gains ``omega-^2 = omega+^2 + K``, ``K = 4 m g l sin(alpha) sin(gamma) / (m l^2
+ I)``; the rolling orbit's post-strike speed is ``omega* = c sqrt(K / (1 - c^2))``
(Tedrake's ``cot(2 alpha) sqrt(4 (g / l) sin alpha sin gamma)`` at ``I = 0``: tests/
test_hybrid.py checks the two forms and the named model against them) and its multiplier
``c^2``. Per period the hub moves ``2 l sin alpha`` along the floor, and the strike takes
the potential energy that step gives, ``m g sin(gamma) 2 l sin alpha``.

The MJCF wheel (examples/motion/rimless_wheel.xml) is that wheel in MuJoCo's coordinates:
slides x and z and a hinge pitch, the feet 1 nm spheres (their rolling a 1e-9 part of the
closed form), the slope as tilted gravity, friction 2 holding the stance foot, so that its
period holds one foot from just after a strike to the next. Every number of the closed form
is read here from the model itself (MuJoCo's gravity, the hub's mass and inertia, the feet's
places), none typed in.

**The second routes.** The named model ``rimless_wheel`` (carnot.hybrid.models: its own
chart, ``q = (theta)``, its strike in floating coordinates, the free flow's return map) at
the same numbers; the multipliers from central differences of the return map on the section
against those of the saltation matrices; the ledger against the potential energy lost.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from carnot.cli import main
from carnot.hybrid.cycle import (
    Cycle,
    find_cycle,
    finite_difference_multipliers,
    section_jacobian,
)
from carnot.hybrid.flow import Hold, contact_points
from carnot.hybrid.mjcf import mjcf_model
from carnot.hybrid.models import named_model
from carnot.hybrid.section import on_section, symmetry, tangent_basis
from carnot.hybrid.simulate import held_field, hold_saltation, simulate

ROOT = Path(__file__).resolve().parent.parent
WHEEL = ROOT / "examples" / "motion" / "rimless_wheel.xml"


def wheel_numbers() -> dict[str, float]:
    """The wheel's parameters as MuJoCo reads them: ``m``, ``I``, ``l``, ``r`` (the feet's
    radius), ``N``, ``g``, ``gamma``."""
    model = mujoco.MjModel.from_xml_path(str(WHEEL))
    hub = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "hub")
    feet = [g for g in range(model.ngeom)
            if (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or "").startswith("foot")]
    lengths = {round(float(np.linalg.norm(model.geom_pos[g])), 12) for g in feet}
    assert len(lengths) == 1  # the spokes are alike
    gravity = np.array(model.opt.gravity, dtype=float)
    return {"m": float(model.body_mass[hub]), "I": float(model.body_inertia[hub][1]),
            "l": lengths.pop(), "r": float(model.geom_size[feet[0]][0]), "N": float(len(feet)),
            "g": float(np.linalg.norm(gravity)),
            "gamma": math.atan2(float(gravity[0]), -float(gravity[2]))}  # fmt: skip


def mcgeer(p: dict[str, float]) -> tuple[float, float]:
    """``omega*`` (rad/s) and the multiplier ``c^2`` (module docstring)."""
    alpha = math.pi / p["N"]
    ml2 = p["m"] * p["l"] ** 2
    c = (ml2 * math.cos(2 * alpha) + p["I"]) / (ml2 + p["I"])
    k = 4 * p["m"] * p["g"] * p["l"] * math.sin(alpha) * math.sin(p["gamma"]) / (ml2 + p["I"])
    return c * math.sqrt(k / (1 - c * c)), c * c


@pytest.fixture(scope="module")
def wheel() -> Cycle:
    motion = mjcf_model(WHEEL, keyframe="post_strike")
    p = wheel_numbers()
    return find_cycle(motion.model, motion.state, motion.law, tolerance=1e-10,
                      shift={"pitch": 2 * math.pi / p["N"]}, cyclic=["x"])  # fmt: skip


def test_the_mjcf_rimless_wheel_rolls_at_mcgeers_fixed_point(wheel: Cycle) -> None:
    p = wheel_numbers()
    alpha = math.pi / p["N"]
    rate, multiplier = mcgeer(p)
    assert wheel.converged and wheel.stable and wheel.flags == ()
    x, z, pitch, vx, vz, w = wheel.state
    # just after the strike: the new foot ahead of the hub by alpha, rolling about it
    assert pitch == pytest.approx(-alpha, abs=1e-10)
    assert z == pytest.approx(p["l"] * math.cos(alpha) + p["r"], abs=1e-11)
    assert w == pytest.approx(rate, rel=1e-8)  # (measured: 8.5e-10, the feet's rolling)
    # the foot's contact point at rest (the hub z above it, l sin(-pitch) behind it)
    assert vx == pytest.approx(w * z, rel=1e-12)
    assert vz == pytest.approx(w * p["l"] * math.sin(-pitch), rel=1e-12)
    assert wheel.multipliers is not None and len(wheel.multipliers) == 1
    assert abs(wheel.multipliers[0].imag) == 0.0
    assert wheel.multipliers[0].real == pytest.approx(multiplier, rel=2e-6)  # (measured 2e-7)
    # a period is a step: the hub 2 l sin(alpha) on along the floor
    step = 2 * p["l"] * math.sin(alpha)
    assert wheel.advance["x"] == pytest.approx(step, rel=1e-8)


def test_the_mjcf_wheel_meets_the_named_model_a_second_route(wheel: Cycle) -> None:
    p = wheel_numbers()
    alpha = math.pi / p["N"]
    named = named_model("rimless_wheel", {"m": p["m"], "l": p["l"], "spokes": p["N"],
                                          "slope": p["gamma"], "I": p["I"], "g": p["g"]})
    c = find_cycle(named, np.array([p["gamma"] - alpha, 1.0]))
    assert c.converged
    assert c.state[1] == pytest.approx(wheel.state[5], rel=1e-8)
    assert c.period == pytest.approx(wheel.period, rel=1e-8)
    assert c.multipliers is not None and wheel.multipliers is not None
    assert abs(c.multipliers[0]) == pytest.approx(abs(wheel.multipliers[0]), rel=2e-6)
    assert c.energy["impacts"] == pytest.approx(wheel.energy["impacts"], rel=1e-8)


def test_the_strike_takes_what_the_slope_gives_per_period(wheel: Cycle) -> None:
    p = wheel_numbers()
    e = wheel.energy
    assert set(e) == {"impacts", "potential_drop"}  # no damper, no slide
    assert e["impacts"] == pytest.approx(e["potential_drop"], rel=1e-10)  # (measured 1e-12)
    # (and m g cos(gamma) times the hub's change of height over the period: the residual's)
    given = p["m"] * p["g"] * math.sin(p["gamma"]) * wheel.advance["x"]
    assert e["potential_drop"] == pytest.approx(given, rel=1e-10)  # (measured: 1.7e-11)
    assert wheel.strikes and len(wheel.strikes) == 1
    # the strike's own ledger: the kinetic energy lost, (1 - c^2) of it
    res = wheel.strikes[0].result.energy
    assert res.dissipated == pytest.approx(res.dissipated_theorem, rel=1e-9)


def test_the_multipliers_from_saltation_meet_finite_differences(wheel: Cycle) -> None:
    """``B^T D P B`` (the section's basis ``B``: 2 directions, x and the two feet's
    constraints left out) from the held flow's Phi and the saltation matrices, against
    central differences of the return map along ``B``; and the multipliers of each."""
    assert wheel.basis is not None and wheel.basis.shape == (6, 2)
    assert wheel.jacobian is not None and wheel.monodromy is not None
    salted = wheel.basis.T @ wheel.jacobian @ wheel.basis
    fd = section_jacobian(wheel)
    assert np.max(np.abs(salted - fd)) < 1e-5 * np.max(np.abs(fd))  # (measured: 1.1e-7)
    fd_mult = finite_difference_multipliers(wheel)
    assert wheel.multipliers is not None and len(fd_mult) == 1
    assert fd_mult[0].real == pytest.approx(wheel.multipliers[0].real, rel=2e-6)
    assert fd_mult[0].real == pytest.approx(mcgeer(wheel_numbers())[1], rel=1e-6)
    # the monodromy carries the flow into the flow: a shift in time along the orbit
    _, holds = on_section(wheel.model, wheel.state, wheel.law)
    f0 = held_field(wheel.model, holds, wheel.state, None)
    carried = wheel.monodromy @ f0
    np.testing.assert_allclose(carried, f0, rtol=0, atol=1e-6 * float(np.max(np.abs(f0))))


def test_a_release_where_the_force_falls_to_zero_has_saltation_the_identity() -> None:
    """The hopping leg's lift-off: the ground's force ``k (l0 - l) + m g`` falls to zero
    continuously, the held and the free fields agree there, and ``S = I``."""
    leg = named_model("hopping_leg")
    run = simulate(leg, np.array([1.0, 0.5, 0.0, 0.0]), 0.5, linearize=True)
    ends = [e for e in run.events if e.kind == "contact_end"]
    assert ends and run.jumps and max(run.jumps) < 1e-10  # (measured: 8e-14)
    salt, jump = hold_saltation(leg, (Hold(index=0),), (), "release", 0, ends[0].state, None)
    assert jump < 1e-10
    np.testing.assert_allclose(salt, np.eye(4), rtol=0, atol=1e-9)
    assert run.monodromy is not None and np.all(np.isfinite(run.monodromy))


def test_a_guess_far_from_any_orbit_is_flagged_with_its_residual() -> None:
    """Rolling at 0.2 rad/s the wheel rocks back: no orbit near, Newton says so."""
    motion = mjcf_model(WHEEL, keyframe="post_strike")
    x = motion.state.copy()
    x[3:] *= 0.2 / 1.1
    c = find_cycle(motion.model, x, motion.law, shift={"pitch": math.pi / 4}, cyclic=["x"],
                   tolerance=1e-10)  # fmt: skip
    assert not c.converged and "not_converged" in c.flags
    assert math.isfinite(c.residual) and c.residual > 1e-6


def test_a_contact_within_the_margin_of_a_body_of_several_geoms_is_listed() -> None:
    """MuJoCo's midphase ignores margins: the hold copy skips it, so that the wheel's foot
    1e-5 m above the floor is still listed (its gap, for the held flow's watch)."""
    motion = mjcf_model(WHEEL, keyframe="post_strike")
    y = on_section(motion.model, motion.state, motion.law)[0]
    y[1] += 1e-5
    points = contact_points(motion.model, motion.model.guards[0], y)
    assert len(points) == 1 and points[0].gap == pytest.approx(1e-5, abs=1e-12)


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_carnot_cycle_prints_the_wheel_s_orbit(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "cycle", str(WHEEL), "--keyframe", "post_strike",
                             "--shift", "pitch=pi/4", "--cyclic", "x", "--json", "--check")
    assert code == 0 and err == ""
    d = json.loads(out)
    rate, multiplier = mcgeer(wheel_numbers())
    assert d["converged"] and d["stable"] and d["warnings"] == []
    assert d["state"]["qdot"][2] == pytest.approx(rate, rel=1e-8)
    assert d["multipliers"][0][0] == pytest.approx(multiplier, rel=2e-6)
    assert d["multipliers_finite_difference"][0][0] == pytest.approx(multiplier, rel=1e-6)
    assert d["shift"] == {"pitch": pytest.approx(math.pi / 4, rel=1e-15)}
    assert set(d["advance"]) == {"x"}
    assert d["energy"]["impacts"] == pytest.approx(d["energy"]["potential_drop"], rel=1e-10)
    assert len(d["impacts"]) == 1
    assert "hint" not in d


def test_an_orbit_not_found_without_a_symmetry_says_how_to_declare_one(
        capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    """Without ``--shift`` the wheel's pitch advances by 2 pi / 8 a period, so no orbit is
    found: the answer is flagged, and a hint names the flags that declare the symmetry."""
    from carnot.hybrid.command import SYMMETRY_HINT, cycle_report

    code, out, err = run_cli(capsys, "cycle", str(WHEEL), "--keyframe", "post_strike", "--json")
    d = json.loads(out)
    assert code == 0 and not d["converged"] and d["hint"] == SYMMETRY_HINT
    assert "--shift" in SYMMETRY_HINT and "--cyclic" in SYMMETRY_HINT
    named = find_cycle(named_model("rimless_wheel", {"spokes": 8, "slope": 0.08}),
                       np.array([0.08 - math.pi / 8, 1.0]))  # (the text's line, on any orbit)
    text = cycle_report(named, "wheel", None, as_json=False, digits=9, hint=SYMMETRY_HINT)
    assert text.endswith("\n  hint: " + SYMMETRY_HINT)


@pytest.mark.parametrize(("extra", "said"), [
    (["--shift", "pitch"], "--shift: must be JOINT=AMOUNT"),
    (["--shift", "pitch=quarter"], "--shift pitch: must be a number or a multiple of pi"),
    (["--shift", "yaw=1"], "--shift 'yaw': is not a coordinate of rimless_wheel"),
    (["--cyclic", "x", "--shift", "x=1"], "--cyclic 'x': is shifted too"),
    (["--cyclic", "z", "--shift", "pitch=pi/4"], "--cyclic 'z': is not cyclic"),
    (["--plot", "orbit.png"], "--plot: is drawn for [model] scenarios"),
    (["--max-period", "-1"], "--max-period"),
])  # fmt: skip
def test_bad_cycle_flags_exit_2_with_one_line(extra: list[str], said: str,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "cycle", str(WHEEL), "--keyframe", "post_strike", *extra)
    assert code == 2 and out == "" and said in err and err.count("\n") == 1


def test_models_that_cannot_cycle_exit_2_naming_why(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    lone = tmp_path / "lone.xml"
    lone.write_text('<mujoco><worldbody><body><joint name="spin" type="hinge"/>'
                    '<geom size=".1" contype="0" conaffinity="0"/></body></worldbody></mujoco>')
    code, _, err = run_cli(capsys, "cycle", str(lone))
    assert code == 2 and "has nothing to strike" in err and err.count("\n") == 1
    code, _, err = run_cli(capsys, "cycle", str(ROOT / "tests" / "models" / "free_box_corner.xml"))
    assert code == 2 and "free joint" in err and "not supported yet" in err
    code, _, err = run_cli(capsys, "cycle", "examples/motion/rimless_wheel.toml", "--keyframe",
                           "k")  # fmt: skip
    assert code == 2 and "--keyframe: is for an MJCF model" in err
    code, _, err = run_cli(capsys, "cycle", "examples/simulate/ball_on_vibrating_table.toml",
                           "--cyclic", "x")  # fmt: skip
    assert code == 2 and "--cyclic: is for a model in motion" in err


def wheel_xml(spokes: int, slope: float, inertia: float, radius: float = 1e-9) -> str:
    """An MJCF rimless wheel like the example's (1 kg hub, 1 m spokes, friction 2, gravity
    9.81 tilted by ``slope``), with ``spokes`` feet of ``radius`` and the hub's ``inertia``;
    its keyframe ``guess`` a post-strike state rolling at 1 rad/s, to 1e-10."""
    feet = "\n".join(
        f'<geom name="foot{k}" type="sphere" size="{radius!r}" '
        f'pos="{-math.sin(2 * math.pi * k / spokes)!r} 0 {-math.cos(2 * math.pi * k / spokes)!r}"/>'
        for k in range(spokes))  # fmt: skip
    alpha = math.pi / spokes
    z = round(math.cos(alpha) + radius, 10) + 1e-10  # (a few digits, just clear of the floor)
    gravity = f"{9.81 * math.sin(slope)!r} 0 {-9.81 * math.cos(slope)!r}"
    return f'''<mujoco model="wheel{spokes}"><option gravity="{gravity}"/>
  <default><geom contype="1" conaffinity="1" condim="3" friction="2 0.005 0.0001"/></default>
  <worldbody><geom name="floor" type="plane" size="0 0 1"/>
    <body name="hub"><joint name="x" type="slide" axis="1 0 0"/>
      <joint name="z" type="slide" axis="0 0 1"/><joint name="pitch" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 0" mass="1" diaginertia="{inertia!r} {inertia!r} {inertia!r}"/>
      {feet}</body></worldbody>
  <keyframe><key name="guess" qpos="0 {z!r} {round(-alpha, 10)!r}"
    qvel="{round(z, 10)!r} {round(math.sin(alpha), 10)!r} 1.0"/></keyframe></mujoco>'''


def test_a_ten_spoke_wheel_on_a_steeper_slope_meets_both_routes(tmp_path: Path) -> None:
    """tests/test_hybrid.py's second wheel (10 spokes, slope 0.15 rad, I = 0.25 kg m^2),
    written as MJCF: McGeer's numbers and the named model's, the spokes' shift pi / 5."""
    spokes, slope, inertia = 10, 0.15, 0.25
    path = tmp_path / "wheel10.xml"
    path.write_text(wheel_xml(spokes, slope, inertia))
    motion = mjcf_model(path, keyframe="guess")
    c = find_cycle(motion.model, motion.state, motion.law, tolerance=1e-10,
                   shift={"pitch": 2 * math.pi / spokes}, cyclic=["x"])  # fmt: skip
    assert c.converged and c.stable and c.flags == ()
    alpha = math.pi / spokes
    rate, multiplier = mcgeer({"m": 1.0, "I": inertia, "l": 1.0, "N": spokes, "g": 9.81,
                               "gamma": slope})  # fmt: skip
    assert c.state[2] == pytest.approx(-alpha, abs=1e-10)
    assert c.state[5] == pytest.approx(rate, rel=1e-8)
    assert c.multipliers is not None and c.multipliers[0].real == pytest.approx(multiplier,
                                                                                rel=2e-6)
    named = named_model("rimless_wheel", {"spokes": spokes, "slope": slope, "I": inertia})
    n = find_cycle(named, np.array([slope - alpha, 1.0]))
    assert n.converged and n.period == pytest.approx(c.period, rel=1e-8)
    assert c.energy["impacts"] == pytest.approx(c.energy["potential_drop"], rel=1e-10)
    assert c.advance["x"] == pytest.approx(2 * math.sin(alpha), rel=1e-8)


def test_a_strike_into_a_hold_has_its_saltation_matrix_with_the_held_fields() -> None:
    """``carnot simulate --saltation`` on the wheel: the strike from one held foot to the
    next has its matrix (the held fields on each side, the held foot in ``D_x R``), which
    carries the field before into the field after, and whose every image lies on the new
    foot's held manifold (its gap and its velocity rows zero to first order: the plastic
    strike takes what would leave it)."""
    motion = mjcf_model(WHEEL, keyframe="post_strike")
    x0, holds = on_section(motion.model, motion.state, motion.law)
    run = simulate(motion.model, x0, 2.0, motion.law, saltation=True, strikes=1)
    (event,) = [e for e in run.events if e.kind == "impact"]
    assert event.saltation is not None and event.strike is not None
    after = tuple(e for e in run.events if e.kind == "contact_start")[-1].held
    assert holds and event.held == holds  # (the old foot, held before the strike)
    f_minus = held_field(motion.model, event.held, event.strike.x_before, None)
    f_plus = held_field(motion.model, after, event.state, None)
    np.testing.assert_allclose(event.saltation @ f_minus, f_plus, rtol=0, atol=1e-9)
    basis = tangent_basis(motion.model, event.state, after, motion.law, symmetry(motion.model))
    off = event.saltation - basis @ (basis.T @ event.saltation)
    assert basis.shape == (6, 3) and np.max(np.abs(off)) < 1e-5 * np.max(np.abs(event.saltation))

"""``carnot derive`` on scenarios with several contacts: one closed form per active set of the
simultaneous law, with the inequalities under which it holds, against the published closed
forms.

Sources: the three-ball cradle ``((1-2e)/3, (1+e)/3, (1+e)/3) v`` and its n-ball form
``v1'' = (1-(n-1)e)/n v``, the others ``(1+e)/n v`` (Glocker, *Set-Valued Force Laws*,
Springer 2001, ch. 7); Housner's rocking block landing on its other corner without slip,
``omega''/omega' = 1 - 3/2 sin^2 alpha``, the old corner lifting off (Housner, Bull. Seism. Soc.
Am. 53 (1963) 403-417); the same block on a frictionless floor, Newton's law at one point,
``(1 - 2 tan^2 alpha)/(1 + 4 tan^2 alpha)`` (Stronge, *Impact Mechanics*, CUP 2000, ch. 2); a ball
into a frictionless V-groove with walls at theta from the vertical: both walls act, and the
ball's velocity is reversed times e, exactly while ``|u| <= tan(theta) |v|`` (generalized
Newton law, Glocker 2001).
"""

from __future__ import annotations

import math

import pytest
import sympy as sp
from conftest import EXAMPLES

from carnot.cli import main
from carnot.errors import InputError
from carnot.io.scenario import load_scenario, parse_scenario, parse_text
from carnot.symbolic.active_sets import ActiveSet, derive_active_sets


def _only(sets: tuple[ActiveSet, ...], active: tuple[str, ...]) -> ActiveSet:
    return next(s for s in sets if s.active == active)


def _zero(expr: sp.Expr) -> bool:
    return bool(sp.simplify(expr) == 0)


@pytest.mark.parametrize("n", [3, 5])
def test_cradle_every_contact_active_is_the_published_form(n: int) -> None:
    name = "newtons_cradle.toml" if n == 3 else "newtons_cradle_5.toml"
    specs = [f"e_{k}=e" for k in range(n - 1)] + ["v_ball1_x=v"]
    symbols, several = derive_active_sets(load_scenario(EXAMPLES / name), specs)
    e, v = sp.Symbol("e", real=True), sp.Symbol("v", real=True)
    assert symbols == [e, v]
    assert len(several.sets) == 2 ** (n - 1)
    full = _only(several.sets, tuple(f"contacts[{k}]" for k in range(n - 1)))
    velocities = [full.expressions[f"bodies.ball{k}.velocity.0"] for k in range(1, n + 1)]
    expected = [(1 - (n - 1) * e) / n * v] + [(1 + e) / n * v] * (n - 1)
    assert all(_zero(got - want) for got, want in zip(velocities, expected, strict=True))
    # its conditions: every normal impulse, m (n - k)(1 + e) v / n >= 0
    for k in range(n - 1):
        p_n = full.conditions[f"contacts.{k}.normal_impulse"]
        assert _zero(p_n - sp.Rational(1, 10) * (n - 1 - k) * (1 + e) * v / n)
    assert full.holds
    # at the file's e = 1, v = 1 no other active set holds (the law's answer is unique)
    assert [s.holds for s in several.sets].count(True) == 1


def test_cradle_one_contact_active_fails_by_its_neighbour() -> None:
    """Only 1-2 active: balls 1 and 2 exchange as a pair, and ball 2 then runs into ball 3:
    ``w_n'' + e w_n' = -(1+e) v / 2 < 0`` at 2-3, so this set never holds for v > 0."""
    _, several = derive_active_sets(load_scenario(EXAMPLES / "newtons_cradle.toml"),
                                    ["e_0=e", "e_1=e", "v_ball1_x=v"])  # fmt: skip
    e, v = sp.Symbol("e", real=True), sp.Symbol("v", real=True)
    pair = _only(several.sets, ("contacts[0]",))
    assert _zero(pair.expressions["bodies.ball1.velocity.0"] - (1 - e) / 2 * v)
    assert _zero(pair.conditions["contacts.1: w_n'' + e w_n'"] + (1 + e) * v / 2)
    assert not pair.holds


def _stick_block_text() -> str:
    text = (EXAMPLES / "block_on_two_corners.toml").read_text()
    assert text.count("friction = 2.0") == 2
    return text.replace("friction = 2.0", 'tangential = "stick"\nfriction = 2.0')


def test_housner_block_in_closed_form() -> None:
    problem = parse_scenario(parse_text(_stick_block_text(), "block.toml"), "block.toml")
    _, several = derive_active_sets(problem)
    new = _only(several.sets, ("contacts[1]",))
    assert new.holds
    alpha_sin2 = sp.Rational(1, 17)  # tan alpha = b/h = 1/4: sin^2 = 1/17, exactly
    ratio = new.expressions["bodies.block.angular_velocity.2"] / sp.Rational(-4, 5)
    assert ratio == 1 - sp.Rational(3, 2) * alpha_sin2
    # the old corner separates: w_n'' + e w_n' > 0 there; the new corner pushes, within the cone
    assert new.conditions["contacts.0: w_n'' + e w_n'"] > 0
    assert new.conditions["contacts.1.normal_impulse"] > 0
    assert new.conditions["contacts.1: mu P_n - |P_t|"] > 0
    assert [s.active for s in several.sets if s.holds] == [("contacts[1]",)]


def test_frictionless_block_in_closed_form() -> None:
    _, several = derive_active_sets(
        load_scenario(EXAMPLES / "block_on_two_corners_frictionless.toml"))  # fmt: skip
    new = _only(several.sets, ("contacts[1]",))
    t2 = sp.Rational(1, 16)
    ratio = new.expressions["bodies.block.angular_velocity.2"] / sp.Rational(-4, 5)
    assert ratio == (1 - 2 * t2) / (1 + 4 * t2)
    assert new.holds and new.conditions["contacts.0: w_n'' + e w_n'"] > 0
    both = _only(several.sets, ("contacts[0]", "contacts[1]"))
    assert both.conditions["contacts.0.normal_impulse"] < 0 and not both.holds


def test_v_groove_conditions_are_the_wedge() -> None:
    """Velocity (u, v) with v < 0 (falling): both walls active exactly while
    |u| <= tan(theta) |v| = 3/4 |v|, and the ball leaves with -e (u, v)."""
    symbols, several = derive_active_sets(load_scenario(EXAMPLES / "ball_into_v_groove.toml"),
                                          ["v_ball_x=u", "v_ball_y=v"])  # fmt: skip
    u, v = symbols
    both = _only(several.sets, ("contacts[0]", "contacts[1]"))
    half = sp.Rational(1, 2)
    assert _zero(both.expressions["bodies.ball.velocity.0"] + half * u)
    assert _zero(both.expressions["bodies.ball.velocity.1"] + half * v)
    conditions = list(both.conditions.values())
    for slant in (-1.0, -0.76, -0.74, -0.3, 0.0, 0.5, 0.74, 0.76, 2.0):
        point = {u: sp.nsimplify(slant * 2), v: sp.Integer(-2)}
        holds = all(c.xreplace(point) >= 0 for c in conditions)
        assert holds == (abs(slant) <= 0.75), slant
    assert both.holds


def test_cli_derive_prints_each_active_set(capsys) -> None:  # type: ignore[no-untyped-def]
    path = EXAMPLES / "newtons_cradle.toml"
    assert main(["derive", str(path), "--symbols", "e_0=e,e_1=e"]) == 0
    out = capsys.readouterr().out
    assert "active set 1: contacts[0] (1-2), contacts[1] (2-3) [holds at the scenario's values]" \
        in out  # fmt: skip
    assert "if contacts.1: w_n'' + e w_n' = " in out
    assert out.count("active set ") == 4
    assert main(["derive", str(path), "--latex"]) == 0
    assert capsys.readouterr().out.count(r"\begin{align*}") == 4


def test_cli_derive_python_of_the_active_sets(capsys) -> None:  # type: ignore[no-untyped-def]
    path = EXAMPLES / "newtons_cradle.toml"
    assert main(["derive", str(path), "--symbols", "e_0=e,e_1=e", "--python"]) == 0
    namespace: dict = {}
    exec(capsys.readouterr().out, namespace)  # noqa: S102 - our own generated source
    out = namespace["active_set_1"](0.5)
    assert out["bodies.ball1.velocity.0"] == pytest.approx(0.0, abs=1e-15)
    assert out["if contacts.0.normal_impulse"] > 0
    assert namespace["ACTIVE_SETS"][namespace["active_set_2"]] == ("contacts[0]",)
    assert math.isclose(namespace["active_set_2"](0.5)["if contacts.1: w_n'' + e w_n'"], -0.75)


def test_derive_refuses_the_other_laws(capsys, write_scenario) -> None:  # type: ignore[no-untyped-def]
    text = (EXAMPLES / "newtons_cradle.toml").read_text()
    path = write_scenario(text.replace('multiple_impact = "simultaneous"',
                                       'multiple_impact = "sequential"'))  # fmt: skip
    assert main(["derive", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "multiple_impact: carnot derive gives the closed forms" in err
    with pytest.raises(InputError, match="multiple_impact"):
        derive_active_sets(parse_scenario(parse_text(text.replace(
            '"simultaneous"', '"dispersion"'), "c.toml"), "c.toml"))  # fmt: skip

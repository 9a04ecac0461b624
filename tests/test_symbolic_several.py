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

Coulomb friction, derived per regime (stick, slip either way, separate) in a planar motion:
each set that holds is checked against the planar impulse-momentum equations written out by
hand here (Stronge, *Impact Mechanics*, CUP 2000, ch. 2-3: ``m dv = P``, ``I dw = r x P``,
Newton's law at the contact, ``P_t = -+mu P_n`` while slipping), and against the numeric
simultaneous law (carnot.solve_impact), a second route with its own solver. The V-groove with
friction, walls at beta from the horizontal: by symmetry the ball leaves straight up at
``e |v|`` whatever ``mu``, with ``P_n = m (1+e) |v| / (2 (cos beta - mu sin beta))``.
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


def _block(mu: str = "2.0", e: str = "0.0") -> str:
    text = (EXAMPLES / "block_on_two_corners.toml").read_text()
    return text.replace("friction = 2.0", f"friction = {mu}").replace(
        "restitution = 0.0", f"restitution = {e}")  # fmt: skip


def _hand_block(sign: int, mu: sp.Symbol, e: sp.Symbol) -> dict[str, sp.Expr]:
    """The block of block_on_two_corners.toml landing on its right corner, slipping with the
    friction impulse ``P_t = -sign mu P_n`` (sign +1: slipping towards +x), the left corner
    lifting: the planar impulse-momentum equations by hand."""
    m, inertia = sp.Integer(3), sp.Rational(3, 12) * (sp.Rational(1, 4) + 4)  # m (a^2+b^2)/12
    vx0, vy0, w0 = sp.Rational(4, 5), sp.Rational(-1, 5), sp.Rational(-4, 5)
    rx, ry = sp.Rational(1, 4), sp.Integer(-1)  # corner (0.5, 0) from the centre (0.25, 1)
    vx, vy, w, p_n = sp.symbols("vx vy w p_n")
    p_t = -sign * mu * p_n
    normal_before = vy0 + w0 * rx  # the corner's normal velocity, v_y + omega r_x
    sol = sp.solve([m * (vx - vx0) - p_t, m * (vy - vy0) - p_n,
                    inertia * (w - w0) - (rx * p_n - ry * p_t),
                    vy + w * rx + e * normal_before], [vx, vy, w, p_n], dict=True)[0]  # fmt: skip
    slip = sol[vx] - sol[w] * ry  # the corner's velocity along x after
    return {"vx": sol[vx], "vy": sol[vy], "w": sol[w], "p_n": sol[p_n], "slip": sign * slip}


def _only_regime(
    sets: tuple[ActiveSet, ...], active: tuple[str, ...], regimes: tuple[str, ...]
) -> ActiveSet:
    return next(s for s in sets if s.active == active and s.regimes == regimes)


def test_housner_block_with_coulomb_friction_in_closed_form() -> None:
    """The file's block (Coulomb, mu = 2, not told to stick): the new corner sticks, the
    published ratio; below the friction it needs, the same corner slips, as by hand."""
    problem = parse_scenario(parse_text(_block(), "b.toml"), "b.toml")
    symbols, several = derive_active_sets(problem, ["mu_0=mu", "mu_1=mu", "e_0=e", "e_1=e"])
    mu, e = symbols
    assert several.axis is not None and list(several.axis) == [0, 0, 1]
    assert len(several.sets) == 16  # 4 regimes for each corner
    held = [s for s in several.sets if s.holds]
    assert [(s.active, s.regimes) for s in held] == [(("contacts[1]",), ("stick",))]
    ratio = held[0].expressions["bodies.block.angular_velocity.2"] / sp.Rational(-4, 5)
    assert _zero(ratio.subs(e, 0) - (1 - sp.Rational(3, 2) * sp.Rational(1, 17)))
    # slip+ slips along d = k x n = z x y = -x: its friction impulse points to +x (sign -1)
    for sign, regime in ((-1, "slip+"), (1, "slip-")):
        slip = _only_regime(several.sets, ("contacts[1]",), (regime,))
        hand = _hand_block(sign, mu, e)
        assert _zero(slip.expressions["bodies.block.velocity.0"] - hand["vx"])
        assert _zero(slip.expressions["bodies.block.velocity.1"] - hand["vy"])
        assert _zero(slip.expressions["bodies.block.angular_velocity.2"] - hand["w"])
        assert _zero(slip.conditions["contacts.1.normal_impulse"] - hand["p_n"])
        assert _zero(slip.conditions["contacts.1: d . w''"] - hand["slip"])
        assert _zero(slip.expressions["energy.dissipated"]
                     - slip.expressions["energy.dissipated_theorem"])  # fmt: skip
    # stick holds exactly where the slip does not: from mu_c, the friction the stick needs
    stick = held[0]
    mu_c = sp.solve(stick.conditions["contacts.1: mu P_n - |P_t|"].subs(e, 0), mu)[0]
    slip_minus = _only_regime(several.sets, ("contacts[1]",), ("slip-",))
    assert sp.solve(slip_minus.conditions["contacts.1: d . w''"].subs(e, 0), mu) == [mu_c]
    assert mu_c == stick.expressions["contacts.1.friction_required"].subs(e, 0)


@pytest.mark.parametrize(("mu", "e"), [("0.05", "0.0"), ("0.1", "0.5"), ("2.0", "0.0"),
                                       ("0.15", "1.0"), ("0.3", "0.5")])  # fmt: skip
def test_coulomb_sets_agree_with_the_numeric_law(mu: str, e: str) -> None:
    """Numeric against symbolic: the set that holds at the file's numbers is the numeric
    simultaneous law's answer (regimes and velocities, 1e-12)."""
    from carnot import solve_impact

    problem = parse_scenario(parse_text(_block(mu, e), "b.toml"), "b.toml")
    _, several = derive_active_sets(problem)
    held = [s for s in several.sets if s.holds]
    assert len(held) == 1
    numeric = solve_impact(problem)
    regimes = {c.where: c.regime for c in numeric.contacts}
    for where, regime in zip(held[0].active, held[0].regimes, strict=True):
        assert regimes[where] == regime.rstrip("+-")
    assert all(regimes[w] == "separate" for w in several.taking_part if w not in held[0].active)
    block = numeric.bodies["block"]
    got = [float(held[0].expressions[f"bodies.block.velocity.{i}"]) for i in range(3)]
    got += [float(held[0].expressions[f"bodies.block.angular_velocity.{i}"]) for i in range(3)]
    want = [*block.velocity_after, *block.angular_velocity_after]
    assert got == pytest.approx(want, abs=1e-12)


def test_v_groove_with_friction_is_symmetric_slip() -> None:
    text = (EXAMPLES / "ball_into_v_groove.toml").read_text()
    text = text.replace("restitution = 0.5", "restitution = 0.5\nfriction = 0.3")
    problem = parse_scenario(parse_text(text, "g.toml"), "g.toml")
    symbols, several = derive_active_sets(problem, ["mu_0=mu", "mu_1=mu", "e_0=e", "e_1=e",
                                                    "v_ball_y=v"])  # fmt: skip
    mu, e, v = symbols
    both = [s for s in several.sets if s.holds]
    assert [s.regimes for s in both] == [("slip+", "slip-")]  # each wall's slip, mirrored
    out = both[0].expressions
    assert _zero(out["bodies.ball.velocity.1"] + e * v)  # v < 0, falling: up at e |v|
    assert out["bodies.ball.velocity.0"] == 0 and out["bodies.ball.angular_velocity.2"] == 0
    cos_b, sin_b, m = sp.Rational(4, 5), sp.Rational(3, 5), sp.Rational(1, 5)
    for k in (0, 1):
        assert _zero(out[f"contacts.{k}.normal_impulse"]
                     - m * (1 + e) * (-v) / (2 * (cos_b - mu * sin_b)))  # fmt: skip


def test_coulomb_slip_in_3d_is_refused_naming_the_contact(capsys) -> None:  # type: ignore[no-untyped-def]
    path = EXAMPLES / "box_lands_flat.toml"
    with pytest.raises(InputError, match=r"contacts\[0\]\.friction: Coulomb slip is derived "
                                         "in a planar motion only"):  # fmt: skip
        derive_active_sets(load_scenario(path))
    # a symbol that could take the block out of its plane is refused too
    problem = parse_scenario(parse_text(_block(), "b.toml"), "b.toml")
    with pytest.raises(InputError, match="planar motion only"):
        derive_active_sets(problem, ["v_block_z"])
    assert main(["derive", str(path)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_cli_derive_names_each_coulomb_regime(capsys, write_scenario) -> None:  # type: ignore[no-untyped-def]
    path = write_scenario(_block("0.1"))
    assert main(["derive", str(path)]) == 0
    out = capsys.readouterr().out
    assert "slip+ slips along d = k x n" in out
    held = [line for line in out.splitlines() if "[holds at" in line]
    assert held == ["active set 15: contacts[1] (right) slip- [holds at the scenario's values]"]
    assert out.count("active set ") == 16
    assert main(["derive", str(path), "--python"]) == 0
    namespace: dict = {}
    exec(capsys.readouterr().out, namespace)  # noqa: S102 - our own generated source
    assert namespace["REGIMES"][namespace["active_set_15"]] == ("slip-",)


def test_slip_with_no_slip_after_is_the_stick_set(write_scenario) -> None:  # type: ignore[no-untyped-def]
    """A rod landing flat on two rough ledges, both sticking, the friction split between them
    not unique: a slip regime whose post-impact slip is zero is the same motion on the cone's
    edge, so its ``d . w'' > 0`` is strict and only the stick set holds, as in the numeric law
    (which requires a slipping contact to slip)."""
    from carnot import solve_impact

    text = (EXAMPLES / "rod_on_ledge.toml").read_text()
    text = text.replace("velocity = [0.0, 0.0, -2.0]",
                        "velocity = [0.5, 0.0, -2.0]\nangular_velocity = [0.0, 1.0, 0.0]")
    ledge = text[text.index("[[contacts]]"):].replace("restitution = 0.4",
                                                      "restitution = 0.4\nfriction = 0.3")
    text = text[:text.index("[[contacts]]")] + ledge + ledge.replace("0.3, 0.0, -0.01",
                                                                    "-0.4, 0.0, -0.01")
    problem = parse_scenario(parse_text(text, "rod.toml"), "rod.toml")
    _, several = derive_active_sets(problem)
    held = [s for s in several.sets if s.holds]
    assert [(s.active, s.regimes) for s in held] == [
        (("contacts[0]", "contacts[1]"), ("stick", "stick"))]
    edge = _only_regime(several.sets, ("contacts[0]", "contacts[1]"), ("stick", "slip+"))
    assert edge.conditions["contacts.1: d . w''"] == 0 and not edge.holds
    numeric = solve_impact(problem)
    assert [c.regime for c in numeric.contacts] == ["stick", "stick"]
    assert "statically_indeterminate" in numeric.flag_codes()

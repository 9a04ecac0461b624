"""The short path of one point contact (carnot.single: the batch formulas on Python floats)
against the general pipeline (carnot.solve.solve_pipeline: contact space, the equality law,
the outcome), field for field, on random two-body and body-on-obstacle impacts; and against
the closed form of a central impact of two spheres (Goldsmith, *Impact*, 1960, ch. 2:
``v_a'' = v_a' - (1 + e) m_b / (m_a + m_b) (v_a' - v_b')`` along the line of centres)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot import solve as solve_module
from carnot.single import short_path
from carnot.solve import solve_pipeline


def _inertia(rng: np.random.Generator) -> np.ndarray:
    """A realizable inertia tensor (principal moments obeying the triangle inequality),
    rotated at random."""
    while True:
        moments = rng.uniform(0.01, 0.1, size=3)
        if all(moments[i] <= moments[(i + 1) % 3] + moments[(i + 2) % 3] for i in range(3)):
            break
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q @ np.diag(moments) @ q.T


def _body(rng: np.random.Generator, name: str, z: float) -> RigidBody:
    return RigidBody(name=name, mass=float(rng.uniform(0.5, 3.0)), inertia_com=_inertia(rng),
                     position_com=rng.normal(scale=0.1, size=3) + [0, 0, z],
                     velocity_com=rng.normal(size=3),
                     angular_velocity=rng.normal(size=3))  # fmt: skip


def _problem(seed: int, *, fixed_b: bool, stick: bool, idle: bool = False) -> ImpactProblem:
    rng = np.random.default_rng(seed)
    bodies: dict[str, RigidBody | FixedBody] = {"a": _body(rng, "a", 0.2)}
    bodies["b"] = FixedBody(name="b") if fixed_b else _body(rng, "b", -0.2)
    if idle:
        bodies["c"] = _body(rng, "c", 1.0)
    contact = PointContact(a="a", b="b", point=rng.normal(scale=0.05, size=3),
                           normal=rng.normal(size=3), restitution=float(rng.uniform(0, 1)),
                           tangential="stick" if stick else "slip",
                           friction=float(rng.choice([0.0, 0.05, 5.0])) if stick else 0.0,
                           name="spot")  # fmt: skip
    return ImpactProblem(bodies=bodies, contacts=[contact], title=f"seed {seed}")


def _same(x: object, y: object, scale: float, where: str) -> None:
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        np.testing.assert_allclose(np.asarray(x, dtype=float), np.asarray(y, dtype=float),
                                   rtol=0, atol=1e-12 * scale, err_msg=where)  # fmt: skip
    elif isinstance(x, float) and isinstance(y, float):
        if np.isinf(x) or np.isinf(y):
            assert x == y, where
        else:
            assert x == pytest.approx(y, rel=0, abs=1e-12 * scale), where
    else:
        assert x == y, where


def _assert_same_fields(fast: object, slow: object) -> None:
    # the short path makes its results from their fields (carnot.result.from_fields): the
    # same attributes, in the same order, as the dataclasses' own __init__ makes
    assert list(vars(fast)) == list(vars(slow))
    for name in ("bodies", "contacts"):
        for x, y in zip(getattr(fast, name) if name == "contacts" else getattr(fast, name).values(),
                        getattr(slow, name) if name == "contacts" else getattr(slow, name).values(),
                        strict=True):  # fmt: skip
            assert list(vars(x)) == list(vars(y)), name
    assert list(vars(fast.energy)) == list(vars(slow.energy))  # type: ignore[attr-defined]


def _assert_same_result(fast: object, slow: object) -> None:
    _assert_same_fields(fast, slow)
    scale = max(1.0, float(np.max(np.abs(slow.row_impulses))), slow.energy.before)  # type: ignore[attr-defined]
    for name in ("title", "multiple_impact", "complementarity_residual", "stages",
                 "alternatives", "system", "constraints"):  # fmt: skip
        assert getattr(fast, name) == getattr(slow, name), name
    _same(fast.row_impulses, slow.row_impulses, scale, "row_impulses")  # type: ignore[attr-defined]
    assert list(fast.bodies) == list(slow.bodies)  # type: ignore[attr-defined]
    for key, motion in slow.bodies.items():  # type: ignore[attr-defined]
        for f in dataclasses.fields(motion):
            _same(getattr(fast.bodies[key], f.name), getattr(motion, f.name), scale,  # type: ignore[attr-defined]
                  f"bodies.{key}.{f.name}")  # fmt: skip
    (fc,), (sc,) = fast.contacts, slow.contacts  # type: ignore[attr-defined]
    for f in dataclasses.fields(sc):
        _same(getattr(fc, f.name), getattr(sc, f.name), scale, f"contacts[0].{f.name}")
    for obj in ("energy", "momentum"):
        for f in dataclasses.fields(getattr(slow, obj)):
            _same(getattr(getattr(fast, obj), f.name), getattr(getattr(slow, obj), f.name),
                  scale, f"{obj}.{f.name}")  # fmt: skip
    assert [(w.code, w.where) for w in fast.warnings] == [  # type: ignore[attr-defined]
        (w.code, w.where) for w in slow.warnings  # type: ignore[attr-defined]
    ]


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("fixed_b", [False, True])
@pytest.mark.parametrize("stick", [False, True])
def test_the_short_path_is_the_pipeline(seed: int, fixed_b: bool, stick: bool) -> None:
    problem = _problem(seed, fixed_b=fixed_b, stick=stick, idle=seed % 3 == 0)
    assert short_path(problem) == ("stick" if stick else "frictionless")
    _assert_same_result(solve_impact(problem), solve_pipeline(problem))


def test_the_flags_come_out_the_same() -> None:
    # every flag the short path can raise, in the general route's order
    codes = set()
    for seed in range(40):
        problem = _problem(seed, fixed_b=seed % 2 == 0, stick=True)
        fast = solve_impact(problem)
        _assert_same_result(fast, solve_pipeline(problem))
        codes.update(fast.flag_codes())
    assert {"not_approaching", "negative_normal_impulse", "friction_insufficient"} <= codes


def test_the_short_path_is_taken_and_only_when_it_applies(monkeypatch: pytest.MonkeyPatch
                                                          ) -> None:  # fmt: skip
    def refuse(problem: ImpactProblem) -> None:
        raise AssertionError("the general route was taken")

    monkeypatch.setattr(solve_module, "solve_pipeline", refuse)
    solve_impact(_problem(1, fixed_b=True, stick=False))
    rough = _problem(1, fixed_b=True, stick=False)
    rough = dataclasses.replace(rough, contacts=[dataclasses.replace(rough.contacts[0],
                                                                      friction=0.3)])  # fmt: skip
    assert short_path(rough) is None
    with pytest.raises(AssertionError, match="general route"):
        solve_impact(rough)


def test_a_sticking_contact_at_rest_falls_back_to_the_pipeline() -> None:
    # P_n = 0: the floats divide by zero where the pipeline reports friction_required = inf
    ball = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3) * 0.004)
    problem = ImpactProblem(
        bodies={"ball": ball, "floor": FixedBody(name="floor")},
        contacts=[PointContact(a="ball", b="floor", point=[0, 0, -0.1], normal=[0, 0, 1],
                               tangential="stick")],  # fmt: skip
    )
    result = solve_impact(problem)
    assert result.contacts[0].friction_required == float("inf")
    _assert_same_result(result, solve_pipeline(problem))


@pytest.mark.parametrize("e", [0.0, 0.4, 1.0])
def test_central_impact_of_two_spheres_against_the_closed_form(e: float) -> None:
    m_a, m_b, v_a, v_b = 2.0, 3.0, 1.5, -0.5
    sphere = {"a": (m_a, v_a, -0.1), "b": (m_b, v_b, 0.1)}
    bodies = {name: RigidBody(name=name, mass=m, inertia_com=np.eye(3) * 0.4 * m * 0.01,
                              position_com=[x, 0, 0], velocity_com=[v, 0, 0])
              for name, (m, v, x) in sphere.items()}  # fmt: skip
    contact = PointContact(a="a", b="b", point=[0, 0, 0], normal=[-1, 0, 0], restitution=e)
    result = solve_impact(ImpactProblem(bodies=bodies, contacts=[contact]))
    after_a = v_a - (1 + e) * m_b / (m_a + m_b) * (v_a - v_b)
    after_b = v_b + (1 + e) * m_a / (m_a + m_b) * (v_a - v_b)
    assert result.bodies["a"].velocity_after[0] == pytest.approx(after_a, rel=1e-14)
    assert result.bodies["b"].velocity_after[0] == pytest.approx(after_b, rel=1e-14)
    # Goldsmith's loss: (1 - e^2) m_a m_b / (2 (m_a + m_b)) (v_a - v_b)^2, by both routes
    loss = (1 - e * e) * m_a * m_b / (2 * (m_a + m_b)) * (v_a - v_b) ** 2
    assert result.energy.dissipated == pytest.approx(loss, abs=1e-14)
    assert result.energy.dissipated_theorem == pytest.approx(loss, abs=1e-14)


def test_the_momentum_check_is_made_when_read_and_kept() -> None:
    problem = _problem(5, fixed_b=False, stick=True)
    result = solve_impact(problem)
    assert "momentum" not in vars(result)
    first = result.momentum
    assert result.momentum is first
    assert first.linear_residual < 1e-14 and first.angular_residual < 1e-14
    with pytest.raises(AttributeError, match="no attribute 'velocity'"):
        _ = result.velocity  # type: ignore[attr-defined]


def test_a_body_with_new_motion_is_solved_with_it() -> None:
    # RigidBody.with_motion copies the body: its cached (v, omega) must not come along
    ball = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3) * 0.004,
                     velocity_com=[0, 0, -2.0])  # fmt: skip
    floor = FixedBody(name="floor")
    contact = PointContact(a="ball", b="floor", point=[0, 0, -0.1], normal=[0, 0, 1],
                           restitution=0.5)  # fmt: skip
    first = solve_impact(ImpactProblem(bodies={"ball": ball, "floor": floor}, contacts=[contact]))
    assert first.bodies["ball"].velocity_after.tolist() == [0.0, 0.0, 1.0]
    faster = ball.with_motion([0, 0, -4.0], [0, 0, 0])
    for solve in (solve_impact, solve_pipeline):
        again = solve(ImpactProblem(bodies={"ball": faster, "floor": floor}, contacts=[contact]))
        assert again.bodies["ball"].velocity_after.tolist() == [0.0, 0.0, 2.0]

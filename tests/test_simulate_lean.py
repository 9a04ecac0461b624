"""The lean event loop (carnot.simulate.lean) against the general loop it stands in for.

Two routes to the same events: the general loop (``lean.LEAN = False``: every impact a
``carnot.ImpactProblem`` solved by ``carnot.solve_impact``, the gaps and next impacts through
the feature dictionaries) and the lean loop (the solver's short-path arithmetic on the floats of
a body and contacts validated once, results built when first read). Every event's time, kind,
contacts, full impact result (impulses, velocities, ``E_d`` by the theorem and by the direct
difference, flags), the states after it and each Zeno series' energy, the ledger and the final
state must agree to 1e-12, on the ball and dice of ``benchmarks/bench_simulate.py``, a ball
that comes to rest by a Zeno series, a die on two planes and a sticking law. The physics of the
same scenes is tested against published results in ``tests/test_simulate.py`` (now through the
lean loop: a bouncing ball's impact times, rebound speeds and ``t_inf = t_1 (1 + e)/(1 - e)``,
Brogliato 2016) and ``tests/test_simulate_corners.py`` (a tumbling die's impacts against an
independent ``brentq`` search).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from carnot.errors import InputError
from carnot.io.results import result_to_dict
from carnot.simulate import lean, parse_simulation, run
from carnot.simulate.loop import SimulationResult

FLOOR = {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}}
WALL = {"fixed": True, "plane": {"point": [0.06, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0]}}


def _ball(e: float, events: int = 0, duration: float = 0.0, **law: Any) -> dict:
    t1 = math.sqrt(2 * 0.5 / 9.81)
    return {"format": 1,
            "simulation": {"duration": duration or t1 * (2 * events - 1) + 1e-3},
            "bodies": {"ball": {"mass": 0.1, "shape": "sphere", "radius": 0.05,
                                "position": [0.0, 0.55, 0.0], "velocity": [0.3, 0.0, 0.1],
                                "angular_velocity": [0.0, 0.0, 2.0]}, "floor": FLOOR},
            "pairs": [{"a": "ball", "b": "floor", "restitution": e, **law}]}  # fmt: skip


def _die(spin: list[float], duration: float, e: float = 1.0, wall: bool = False,
         **law: Any) -> dict:  # fmt: skip
    bodies: dict[str, Any] = {
        "die": {"mass": 0.02, "shape": "box", "size": [0.02, 0.02, 0.02],
                "position": [0.0, 0.3, 0.0], "velocity": [0.2 if wall else 0.0, 0.0, 0.0],
                "angular_velocity": spin}, "floor": FLOOR}  # fmt: skip
    if wall:
        bodies["wall"] = WALL
    return {"format": 1, "simulation": {"duration": duration, "max_events": 10**5},
            "bodies": bodies,
            "pairs": [{"a": "die", "b": "*", "restitution": e, **law}]}  # fmt: skip


def _both(scene: dict, monkeypatch: pytest.MonkeyPatch) -> tuple[SimulationResult,
                                                                  SimulationResult, int]:
    """The scene run by the general loop and by the lean one, and the lean loop's impacts."""
    sim = parse_simulation(scene)
    monkeypatch.setattr(lean, "LEAN", False)
    general = run(sim)
    monkeypatch.setattr(lean, "LEAN", True)
    solved = []
    original = lean.factored_floats  # (single_floats with the body's factors kept)

    def counted(*args: Any) -> Any:
        solved.append(args[0])
        return original(*args)

    monkeypatch.setattr(lean, "factored_floats", counted)
    return general, run(sim), len(solved)


def _close(a: Any, b: Any, where: str) -> None:
    """``a`` and ``b`` (numbers, or nested dicts and lists of them) equal to 1e-12."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        for k in a:
            _close(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{where}[{k}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert b == pytest.approx(a, rel=1e-12, abs=1e-12) or (math.isnan(a) and math.isnan(b)), \
            where  # fmt: skip
    else:
        assert a == b, where


def _state(s: Any) -> list[list[float]]:
    return [np.asarray(x).tolist() for x in (s.position, s.orientation, s.velocity,
                                             s.angular_velocity)]  # fmt: skip


def _same(general: SimulationResult, fast: SimulationResult) -> None:
    assert len(fast.events) == len(general.events)
    for k, (a, b) in enumerate(zip(general.events, fast.events, strict=True)):
        where = f"events[{k}]"
        _close(a.time, b.time, f"{where}.time")
        assert (a.kind, a.contacts) == (b.kind, b.contacts), where
        _close(a.energy, b.energy, f"{where}.energy")
        assert (a.impact is None) == (b.impact is None), where
        if a.impact is not None:
            assert b.impact is not None
            # the same attributes in the same order (the lean loop's result is assembled from
            # its fields: carnot.single.plane_result), then the same values
            ra, rb = a.impact.result, b.impact.result
            assert list(vars(ra)) == list(vars(rb)), where
            for x, y in ((ra.energy, rb.energy), *zip(ra.contacts, rb.contacts, strict=True),
                         *zip(ra.bodies.values(), rb.bodies.values(), strict=True)):
                assert list(vars(x)) == list(vars(y)), where
            _close(result_to_dict(a.impact.result), result_to_dict(b.impact.result), where)
            _close([_state(s) for s in a.impact.states], [_state(s) for s in b.impact.states],
                   f"{where}.states")  # fmt: skip
            assert [f.code for f in a.impact.flags] == [f.code for f in b.impact.flags]
            assert a.impact.features == b.impact.features
    for key in ("initial", "final", "impacts", "sliding", "ground_work", "residual"):
        _close(getattr(general.energy, key), getattr(fast.energy, key), f"energy.{key}")
    _close([_state(s) for s in general.final], [_state(s) for s in fast.final], "final")


@pytest.mark.parametrize(("name", "scene", "least"), [
    ("elastic ball", _ball(1.0, events=60), 60),
    ("ball sticking", _ball(0.9, events=40, tangential="stick", friction=0.5), 3),
    ("ball to rest by a Zeno series", _ball(0.8, duration=5.0), 3),
    ("die tumbling in 3D", _die([3.0, -2.0, 7.0], 12.0), 40),
    ("die edge on (two corners at once: the general route's)", _die([0.0, 0.0, 7.0], 6.0), 0),
    ("die between a floor and a wall", _die([3.0, -2.0, 7.0], 6.0, wall=True), 15),
    ("die losing energy", _die([3.0, -2.0, 7.0], 0.8, e=0.6), 3),
])  # fmt: skip
def test_lean_loop_gives_the_general_loops_events(name: str, scene: dict, least: int,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    general, fast, solved = _both(scene, monkeypatch)
    assert solved >= least, name  # the lean loop ran (and so did the general one's steps)
    assert sum(ev.kind == "impact" for ev in general.events) >= max(least, 3)
    _same(general, fast)


def test_lean_loop_stays_out_of_scenes_it_does_not_take() -> None:
    # Coulomb friction while slipping (the solver's integrated law), ground motion, two bodies
    coulomb = parse_simulation(_ball(0.8, events=5, friction=0.3))
    assert lean.lean_scene(coulomb) is None
    pulse = _ball(0.8, events=5)
    pulse["simulation"]["ground_pulse"] = {"shape": "sine", "amplitude": 1.0, "period": 0.5,
                                           "direction": [1.0, 0.0, 0.0]}  # fmt: skip
    assert lean.lean_scene(parse_simulation(pulse)) is None
    assert lean.lean_scene(parse_simulation(_ball(0.8, events=5))) is not None


def test_event_limit_is_the_general_loops_error(monkeypatch: pytest.MonkeyPatch) -> None:
    scene = _ball(1.0, events=30)
    scene["simulation"]["max_events"] = 10
    messages = []
    for flag in (False, True):
        monkeypatch.setattr(lean, "LEAN", flag)
        with pytest.raises(InputError) as err:
            run(parse_simulation(scene))
        messages.append(str(err.value))
    assert messages[0] == messages[1] and "simulation.max_events" in messages[0]


def test_lean_events_pickle_with_their_results() -> None:
    # an impact whose result is made when first read is pickled with it built (a worker
    # process sending events back)
    import pickle

    res = run(parse_simulation(_die([3.0, -2.0, 7.0], 2.0)))
    back = pickle.loads(pickle.dumps(res.events))
    assert len(back) == len(res.events) > 3
    for a, b in zip(res.events, back, strict=True):
        assert a.impact is not None and b.impact is not None
        assert result_to_dict(a.impact.result) == result_to_dict(b.impact.result)

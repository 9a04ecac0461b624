"""The closed-form corner root finder (carnot.simulate.corners) against an independent search:
each corner's gap sampled densely along the flight's own quaternion route (``Flight.points``,
not the finder's Rodrigues coefficients), the first sign change refined by SciPy's brentq.
Energy of an elastic, frictionless die is conserved (e = 1: Newton's rule keeps the normal
relative speed, so every impact's E_d is zero by the theorem and by the direct difference),
and a corner grazing the floor (a double root) is neither missed nor mishandled."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from carnot.simulate import events, parse_simulation, run
from carnot.simulate.events import features, geometry, next_contact, trigger_levels
from carnot.simulate.loop import scales
from carnot.simulate.motion import BodyState, Flight

G = 9.81
H = 0.01  # the die's half side (m)
FLOOR = {"fixed": True, "plane": {"point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0]}}


def _die(position, velocity, omega, duration=3.0, orientation=(1.0, 0.0, 0.0, 0.0)) -> dict:
    return {"format": 1, "simulation": {"duration": duration, "max_events": 10**5},
            "bodies": {"die": {"mass": 0.02, "shape": "box", "size": [2 * H] * 3,
                               "position": list(position), "velocity": list(velocity),
                               "angular_velocity": list(omega),
                               "orientation": list(orientation)},
                       "floor": copy.deepcopy(FLOOR)},
            "pairs": [{"a": "die", "b": "floor", "restitution": 1.0}]}  # fmt: skip


def _reference(flight: Flight, verts: np.ndarray, levels: np.ndarray, eps: float,
               horizon: float) -> float:  # fmt: skip
    """Dense sampling (1e-3 rad of rotation or 1e-5 s a step) of every corner's height on the
    floor y = 0, the first crossing (with the finder's arming rule for touching corners)
    refined by brentq."""
    w = float(np.linalg.norm(flight.state0.angular_velocity))
    step = min(1e-5, 1e-3 / w) if w > 0 else 1e-5
    s = np.append(np.arange(0.0, horizon, step), horizon)
    heights = flight.points(s, verts)[:, :, 1]  # (N, K)
    best = math.inf
    for k in range(len(verts)):
        g = heights[:, k]
        start, level = 0, float(levels[k])
        if level < 0:
            wide = np.flatnonzero(g > eps)
            open_at = int(wide[0]) if wide.size else len(g)
            deep = np.flatnonzero(g[:open_at] < level)
            if deep.size:
                j = int(deep[0])
            else:
                below = np.flatnonzero(g[open_at:] < 0.0)
                if not below.size:
                    continue
                j, level = open_at + int(below[0]), 0.0
        else:
            below = np.flatnonzero(g[start:] < level)
            if not below.size:
                continue
            j = int(below[0])
        root = brentq(lambda t, k=k, lev=level: flight.point_at(t, verts[k])[1] - lev,
                      s[j - 1], s[j], xtol=1e-15, rtol=8.9e-16)  # fmt: skip
        best = min(best, root)
    return best


def _finder(sim, flight: Flight, horizon: float, closed_form: bool = True) -> float:
    eps, _ = scales(sim)
    feats = features(sim.bodies, sim.planes)
    gaps = {f: geometry(f, sim.bodies, sim.planes, [flight.state0]).gap for f in feats}
    levels = trigger_levels(gaps, eps)
    saved = events.CLOSED_FORM_CORNERS
    events.CLOSED_FORM_CORNERS = closed_form
    try:
        root = next_contact([flight], sim.bodies, sim.planes, feats, horizon, levels, eps)
    finally:
        events.CLOSED_FORM_CORNERS = saved
    return math.inf if root is None else root


def _levels(sim, state: BodyState) -> np.ndarray:
    eps, _ = scales(sim)
    feats = features(sim.bodies, sim.planes)
    gaps = {f: geometry(f, sim.bodies, sim.planes, [state]).gap for f in feats}
    return np.array(list(trigger_levels(gaps, eps).values()))


def test_tumbling_die_impacts_equal_dense_sampling_and_brentq() -> None:
    """Every flight of an elastic die tumbling in 3D (one corner at a time) and of one spinning
    about a horizontal axis (two corners of an edge at once): the next impact by the closed
    form equals the dense search to 1e-12 s; the energy is conserved to round-off."""
    checked = 0
    for omega in ([3.0, -2.0, 7.0], [0.0, 0.0, 7.0]):
        sim = parse_simulation(_die([0.0, 0.3, 0.0], [0.4, 0.0, 0.0], omega, duration=3.0))
        res = run(sim)
        impacts = [ev for ev in res.events if ev.kind == "impact"]
        assert len(impacts) >= 8
        eps, _ = scales(sim)
        verts = sim.bodies[0].shape.vertices_body
        starts = [(0.0, sim.initial[0])] + [(ev.time, ev.impact.states[0]) for ev in impacts]
        for (t, state), nxt in zip(starts, impacts, strict=False):
            horizon = min(sim.duration - t, 1.0)
            flight = Flight(sim.bodies[0], t, state, sim.gravity, None, horizon)
            assert flight.kind == "constant"  # a cube: isotropic
            found = _finder(sim, flight, horizon)
            # the dense search up to a little past the finder's root: an earlier root missed
            # by the finder would be found before it, a spurious one not found at it
            window = min(horizon, found + 0.01)
            expected = _reference(flight, verts, _levels(sim, state), eps, window)
            assert found == pytest.approx(expected, abs=1e-12)
            assert t + found == pytest.approx(nxt.time, abs=1e-12)  # the simulation's event
            checked += 1
        # e = 1, frictionless: no joule lost, by the theorem and by the direct difference
        scale = res.energy.initial
        for ev in impacts:
            energy = ev.impact.result.energy
            assert abs(energy.dissipated) <= 1e-12 * scale
            assert abs(energy.dissipated_theorem) <= 1e-12 * scale
        assert res.energy.final == pytest.approx(res.energy.initial, rel=1e-12)
    assert checked >= 20


def _grazing(depth: float, spin: float = 50.0) -> tuple[dict, float, float]:
    """A die spinning about z whose corners (+-h, -h, +-h) reach their lowest point (-h sqrt 2
    below the centre) when the centre is at its apex, ``s_g = (pi/4) / spin`` s in, and there
    touch the floor ``depth`` m deep (0: a tangent touch, negative: a miss by that much).
    Returns the scene, ``s_g`` and the next corner's root after it (the one a quarter turn
    behind, which meets the floor while the centre falls)."""
    rho = H * math.sqrt(2)
    s_g = 0.25 * math.pi / spin
    vy = G * s_g
    y0 = rho - 0.5 * G * s_g * s_g - depth
    # the cube's axes along the world's: corner (-h, -h) is at height -h sqrt 2 sin(w s + pi/4)
    # above the centre, lowest at w s = pi/4; corner (-h, h) a quarter turn later
    scene = _die([0.0, y0, 0.0], [0.0, vy, 0.0], [0.0, 0.0, spin], duration=0.2)
    sim = parse_simulation(scene)
    flight = Flight(sim.bodies[0], 0.0, sim.initial[0], sim.gravity, None, 0.2)

    def lowest(t: float) -> float:
        return float(np.min(flight.points(np.array([t]), sim.bodies[0].shape.vertices_body)
                            [0, :, 1]))  # fmt: skip

    # the next corner's root: after the graze, while the centre falls (a bracket by scan)
    s = np.linspace(s_g + 1e-4, 0.2, 20001)
    heights = flight.points(s, sim.bodies[0].shape.vertices_body)[:, :, 1].min(axis=1)
    j = int(np.flatnonzero(heights < 0)[0])
    later = brentq(lowest, s[j - 1], s[j], xtol=1e-15, rtol=8.9e-16)
    return scene, s_g, later


def test_grazing_corner_is_found_where_sampling_misses_it() -> None:
    """A corner dipping 1e-12 m below the floor for ~0.3 us: the closed form finds its first
    root (brentq on the exact gap, bracketed by the dip's closed form) where samples 0.05 rad
    apart step over it (the route before: a missed impact)."""
    scene, s_g, later = _grazing(depth=1e-12)
    sim = parse_simulation(scene)
    flight = Flight(sim.bodies[0], 0.0, sim.initial[0], sim.gravity, None, 0.2)
    verts = sim.bodies[0].shape.vertices_body
    # the dip: g ~ g''(s_g) (s - s_g)^2 / 2 - depth, g'' = spin^2 rho - g
    half = math.sqrt(2 * 1e-12 / (50.0**2 * H * math.sqrt(2) - G))
    corner = int(np.argmin(flight.points(np.array([s_g]), verts)[0, :, 1]))
    expected = brentq(lambda t: flight.point_at(t, verts[corner])[1], s_g - 3 * half, s_g,
                      xtol=1e-15, rtol=8.9e-16)  # fmt: skip
    assert expected == pytest.approx(s_g - half, rel=1e-3)  # the closed form's width
    assert _finder(sim, flight, 0.2) == pytest.approx(expected, abs=1e-12)
    assert _finder(sim, flight, 0.2, closed_form=False) == pytest.approx(later, abs=1e-12)


@pytest.mark.parametrize("depth", [1e-12, 0.0, -1e-12])
def test_tangent_or_near_miss_is_not_mishandled(depth) -> None:
    """A tangent touch (depth 0: a double root, zero normal velocity) and a near miss 1e-12 m
    above the floor: the finder reports the touch at its minimum (within the double root's
    round-off width, ~1e-9 s) or, when the floor is not reached, the next corner's true root;
    the simulation passes the graze without an impact impulse and keeps every joule."""
    scene, s_g, later = _grazing(depth=depth)
    sim = parse_simulation(scene)
    flight = Flight(sim.bodies[0], 0.0, sim.initial[0], sim.gravity, None, 0.2)
    found = _finder(sim, flight, 0.2)
    if depth > 0:
        assert found < s_g  # the dip (previous test)
    elif depth < 0:
        assert found == pytest.approx(later, abs=1e-12)
    else:
        assert abs(found - s_g) <= 1e-8 or found == pytest.approx(later, abs=1e-12)
    res = run(sim)
    impacts = [ev for ev in res.events if ev.kind == "impact"]
    assert impacts and impacts[0].time == pytest.approx(later, abs=1e-12)
    assert all(abs(ev.impact.result.energy.dissipated) <= 1e-12 * res.energy.initial
               for ev in impacts)  # fmt: skip
    assert res.energy.final == pytest.approx(res.energy.initial, rel=1e-12)


def test_corner_gaps_and_speeds_at_once_equal_each_features_geometry() -> None:
    """The loop's batched gaps and normal velocities (one compiled call per body and plane)
    against each feature's :func:`geometry` (lever ``R s_k`` by the rotation matrix, the
    velocity ``v + omega x r`` at the contact point): a box and a ball over a tilted plane in
    random states."""
    from carnot.simulate.events import corner_groups, gaps_and_speeds
    from carnot.simulate.motion import quat_from_rotvec

    rng = np.random.default_rng(7)
    slope = 0.3
    scene = _die([0.0, 0.3, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    scene["bodies"]["ball"] = {"mass": 0.1, "shape": "sphere", "radius": 0.02,
                               "position": [0.5, 0.3, 0.0]}  # fmt: skip
    scene["bodies"]["floor"]["plane"]["normal"] = [math.sin(slope), math.cos(slope), 0.0]
    scene["pairs"][0]["b"] = "*"
    scene["pairs"].append({"a": "ball", "b": "*", "restitution": 0.5})
    sim = parse_simulation(scene)
    feats = features(sim.bodies, sim.planes)
    groups = corner_groups(feats, sim.bodies)
    for _ in range(20):
        states = [BodyState(position=rng.normal(size=3), orientation=quat_from_rotvec(
            rng.normal(size=3)), velocity=rng.normal(size=3),
            angular_velocity=rng.normal(size=3) * 5) for _ in sim.bodies]  # fmt: skip
        gaps, speeds = gaps_and_speeds(feats, sim.bodies, sim.planes, states, groups)
        for f in feats:
            g = geometry(f, sim.bodies, sim.planes, states)
            assert gaps[f] == pytest.approx(g.gap, abs=1e-15)
            assert speeds[f] == pytest.approx(g.normal_velocity, abs=1e-14)


@pytest.mark.parametrize("seed", range(8))
def test_random_flights_first_corner_impact_equals_dense_search(seed) -> None:
    """Random tumbling dice (spins up to about 300 rad/s about random axes), half of them starting
    with a corner on the floor and leaving it (as after an impact: the arming rule), half
    from random heights: the closed form's first impact equals the dense search's."""
    from carnot.simulate.motion import quat_from_rotvec

    rng = np.random.default_rng(seed)
    sim = parse_simulation(_die([0.0, 0.3, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]))
    eps, _ = scales(sim)
    verts = sim.bodies[0].shape.vertices_body
    for k in range(8):
        q = quat_from_rotvec(rng.normal(size=3) * 2)
        omega = rng.normal(size=3) * rng.uniform(1, 120)
        velocity = rng.normal(size=3) * 0.5
        levers = verts @ BodyState(position=np.zeros(3), orientation=q, velocity=velocity,
                                   angular_velocity=omega).rotation.T  # fmt: skip
        low = int(np.argmin(levers[:, 1]))
        height = -levers[low, 1] + (rng.uniform(0.01, 0.3) if k % 2 else 0.0)
        if k % 2 == 0:  # touching: make the corner leave the floor
            rise = velocity[1] + np.cross(omega, levers[low])[1]
            velocity[1] += abs(rise) + 0.1 - rise
        state = BodyState(position=np.array([0.0, height, 0.0]), orientation=q,
                          velocity=velocity, angular_velocity=omega)  # fmt: skip
        flight = Flight(sim.bodies[0], 0.0, state, sim.gravity, None, 1.0)
        found = _finder(sim, flight, 1.0)
        assert found < 1.0  # it falls: some corner lands within a second
        expected = _reference(flight, verts, _levels(sim, state), eps, min(1.0, found + 0.01))
        assert found == pytest.approx(expected, abs=1e-12)

"""Simulation scenarios (DESIGN.md section 8): TOML, or the same structure in JSON.

Keys (unknown keys are errors, every message names the file and the key path)::

    format = 1                      title = "..." (optional)
    [simulation]  duration (s, > 0, <= 1e6: required), gravity (m/s^2, default [0, -9.81, 0]),
                  ground_motion (CSV path, relative to the scenario file: ground.py) or
                  ground_pulse = {shape = "sine" | "cosine", amplitude (m/s^2), period (s),
                  direction (default [1, 0, 0])} (one cycle, ground.py's Pulse) or
                  ground_oscillation = {amplitude (m, >= 0), frequency (Hz, > 0), direction
                  (required), phase (rad, default 0)} (sustained, ground.py's Oscillation;
                  at most one of the three),
                  max_events (default 10000, at most 10^7), sample_step (s: --plot, --animate,
                  --trajectory; default duration / 500)
    [bodies.NAME] mass, shape = "sphere" (radius) | "box" (size: full edge lengths) |
                  "convex" (vertices: body axes, relative to the centre of mass; inertia
                  optional: kg m^2, body axes), position, velocity, angular_velocity,
                  orientation = [w, x, y, z] (body axes to world; normalised)
    [bodies.NAME] fixed = true, plane = {point = [...], normal = [...]}
    [[pairs]]     a, b (a name, or "*": any other), restitution, friction (default 0),
                  law (newton | poisson | stronge), tangential (slip | stick)
    [cycle]       strikes (the period in impacts, 1 to 64, default 1), tolerance (of
                  |P(x) - x|, default 1e-11): read by ``carnot cycle`` (simulate/cycle.py),
                  checked and otherwise ignored here

Each body must touch nothing at the start deeper than a billionth of its size, and every
pair of things that can meet (a body and a plane, two spheres) must have a pair law.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from carnot import validate
from carnot.errors import InputError
from carnot.io.scenario import read_scenario_data
from carnot.io.tables import known as _known
from carnot.io.tables import require as _require
from carnot.io.tables import table as _table
from carnot.io.tables import top_level as _top_level
from carnot.laws import LAW_NAMES
from carnot.simulate.events import Feature, features, geometry
from carnot.simulate.ground import Ground, Oscillation, Pulse, read_record
from carnot.simulate.impacts import PairLaw
from carnot.simulate.loop import MAX_EVENTS_LIMIT, Simulation
from carnot.simulate.motion import BodyState, SimBody
from carnot.simulate.shapes import (
    Convex,
    Plane,
    Sphere,
    box_vertices,
    hull_mass_properties,
    sphere_inertia,
)

TOP_KEYS = ("format", "title", "simulation", "bodies", "pairs", "cycle")
GROUND_KEYS = ("ground_motion", "ground_pulse", "ground_oscillation")
SIM_KEYS = ("duration", "gravity", *GROUND_KEYS, "max_events", "sample_step")
PULSE_KEYS = ("shape", "amplitude", "period", "direction")
OSCILLATION_KEYS = ("amplitude", "frequency", "direction", "phase")
#: Highest frequency of a ground oscillation (Hz): a period of at least a microsecond, the
#: shortest pulse.
MAX_FREQUENCY = 1e6
BODY_KEYS = ("mass", "shape", "radius", "size", "vertices", "inertia", "position", "velocity",
             "angular_velocity", "orientation")  # fmt: skip
SHAPE_DIMENSIONS = {"sphere": "radius", "box": "size", "convex": "vertices"}
PAIR_KEYS = ("a", "b", "restitution", "friction", "law", "tangential")
#: Longest simulated duration (s).
MAX_DURATION = 1e6
#: ``[cycle]`` keys (read by ``carnot cycle``; ``carnot simulate`` checks and ignores them),
#: the most strikes per period and the bounds of the tolerance of ``|P(x) - x|``.
CYCLE_KEYS = ("strikes", "tolerance")
MAX_STRIKES = 64
TOLERANCE_BOUNDS = (1e-15, 1e-3)
#: Most vertices of a convex body.
MAX_VERTICES = 256


def load_simulation(path: str | Path) -> Simulation:
    """Read a simulation scenario file.

    >>> load_simulation("no/such.toml")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: no/such.toml: cannot read the file (No such file or directory)
    """
    data = read_scenario_data(path)
    try:
        return parse_simulation(data, Path(path).parent)
    except InputError as err:
        raise type(err)(f"{path}: {err.field}", err.problem, err.value,
                        show_value=err.show_value) from None  # fmt: skip





def parse_simulation(data: Any, base: Path = Path(".")) -> Simulation:
    """Build a :class:`Simulation` from parsed scenario data (``base``: where relative paths
    start).

    >>> parse_simulation({"format": 1, "simulation": {"duration": -1.0}, "bodies": {}})
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: simulation.duration: must be > 0, got -1.0
    """
    top, title = _top_level(data, TOP_KEYS)
    cycle_settings(top)
    sim = _table(_require(top, "simulation", ""), "simulation")
    _known(sim, SIM_KEYS, "simulation")
    duration = validate.positive_number(_require(sim, "duration", "simulation"),
                                        "simulation.duration")  # fmt: skip
    if duration > MAX_DURATION:
        raise InputError("simulation.duration", f"must be <= {MAX_DURATION:g} s", duration)
    gravity = validate.vector3(sim.get("gravity", [0.0, -9.81, 0.0]), "simulation.gravity")
    max_events = sim.get("max_events", 10_000)
    if isinstance(max_events, bool) or not isinstance(max_events, int) or not (
            1 <= max_events <= MAX_EVENTS_LIMIT):  # fmt: skip
        raise InputError("simulation.max_events", f"must be an integer in [1, {MAX_EVENTS_LIMIT}]",
                         max_events)  # fmt: skip
    step = sim.get("sample_step")
    if step is not None:
        step = validate.positive_number(step, "simulation.sample_step")
        if duration / step > 1e6:
            raise InputError("simulation.sample_step", "gives more than 10^6 samples", step)
    given = [key for key in GROUND_KEYS if key in sim]
    if len(given) > 1:
        others = " and ".join(given[:1] + given[2:])
        raise InputError(f"simulation.{given[1]}", f"excludes {others} (the ground moves one "
                         "way: give one of ground_motion, ground_pulse, ground_oscillation)",
                         show_value=False)  # fmt: skip
    ground: Ground | None = None
    if "ground_motion" in sim:
        name = sim["ground_motion"]
        if not isinstance(name, str) or not name:
            raise InputError("simulation.ground_motion", "must be a CSV file name", name)
        ground = read_record(base / name, "simulation.ground_motion")
    if "ground_pulse" in sim:
        ground = ground_pulse(_table(sim["ground_pulse"], "simulation.ground_pulse"),
                              "simulation.ground_pulse")  # fmt: skip
    if "ground_oscillation" in sim:
        ground = ground_oscillation(_table(sim["ground_oscillation"],
                                           "simulation.ground_oscillation"),
                                    "simulation.ground_oscillation")  # fmt: skip
    bodies_table = _table(_require(top, "bodies", ""), "bodies")
    bodies: list[SimBody] = []
    initial: list[BodyState] = []
    planes: list[Plane] = []
    plane_names: list[str] = []
    for name, spec in bodies_table.items():
        spec = _table(spec, f"bodies.{name}")
        if spec.get("fixed") is not None:
            planes.append(_plane(name, spec))
            plane_names.append(name)
        else:
            body, state = _body(name, spec)
            bodies.append(body)
            initial.append(state)
    if not bodies:
        raise InputError("bodies", "needs at least one movable body", show_value=False)
    names = {b.name for b in bodies} | set(plane_names)
    law_of = _pairs(top.get("pairs", []), names)
    feats = features(bodies, planes)
    for f in feats:
        _law_for(law_of, f, bodies, plane_names)  # every possible meeting has a law
    _check_start(bodies, planes, plane_names, initial, feats)
    return Simulation(title=title, bodies=bodies, initial=initial, planes=planes,
                      plane_names=plane_names, gravity=gravity, ground=ground, duration=duration,
                      law_of=lambda f: _law_for(law_of, f, bodies, plane_names),
                      max_events=max_events, sample_step=step)  # fmt: skip


def cycle_settings(top: Mapping[str, Any]) -> tuple[int, float]:
    """The ``[cycle]`` table of a scenario: ``strikes`` (the period in impacts, default 1) and
    ``tolerance`` (of ``|P(x) - x|``, default 1e-11).

    >>> cycle_settings({"cycle": {"strikes": 2}})
    (2, 1e-11)
    >>> cycle_settings({"cycle": {"strikes": 0}})
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: cycle.strikes: must be an integer in [1, 64], got 0
    """
    cyc = _table(top.get("cycle", {}), "cycle")
    _known(cyc, CYCLE_KEYS, "cycle")
    strikes = cyc.get("strikes", 1)
    if isinstance(strikes, bool) or not isinstance(strikes, int) or not (
            1 <= strikes <= MAX_STRIKES):  # fmt: skip
        raise InputError("cycle.strikes", f"must be an integer in [1, {MAX_STRIKES}]", strikes)
    tolerance = float(validate.number_in(cyc.get("tolerance", 1e-11), "cycle.tolerance",
                                         *TOLERANCE_BOUNDS))  # fmt: skip
    return strikes, tolerance


def ground_pulse(spec: Mapping[str, Any], field: str = "ground_pulse") -> Pulse:
    """A one-cycle ground acceleration pulse (ground.py's :class:`Pulse`): ``shape``
    (``"sine"``: Zhang and Makris's type A, ``"cosine"``: type B), ``amplitude`` (m/s^2,
    signed), ``period`` (s) and the unit ``direction`` (default x).

    >>> g = ground_pulse({"shape": "sine", "amplitude": 2.0, "period": 0.4})
    >>> float(g.accel(0.1)[0]), float(g.accel(0.5)[0])
    (2.0, 0.0)
    """
    _known(spec, PULSE_KEYS, field)
    shape = _require(spec, "shape", field)
    if shape not in ("sine", "cosine"):
        raise InputError(f"{field}.shape", "must be 'sine' or 'cosine'", shape)
    amplitude = validate.finite_number(_require(spec, "amplitude", field), f"{field}.amplitude")
    period = validate.positive_number(_require(spec, "period", field), f"{field}.period")
    if not 1e-6 <= period <= MAX_DURATION:
        raise InputError(f"{field}.period", f"must be in [1e-06, {MAX_DURATION:g}] s", period)
    direction = validate.unit_vector(spec.get("direction", [1.0, 0.0, 0.0]),
                                     f"{field}.direction")  # fmt: skip
    return Pulse(shape=shape, amplitude=amplitude, period=period, direction=direction)


def ground_oscillation(spec: Mapping[str, Any], field: str = "ground_oscillation"
                       ) -> Oscillation:  # fmt: skip
    """A sustained ground oscillation (ground.py's :class:`Oscillation`): the fixed bodies'
    displacement ``A sin(2 pi f t + phase)`` along the unit ``direction`` (any non-zero
    length; normalised), with ``amplitude`` ``A`` (m, >= 0), ``frequency`` ``f`` (Hz, > 0, at
    most :data:`MAX_FREQUENCY`) and ``phase`` (rad, default 0); the peak acceleration
    ``A (2 pi f)^2`` at most 1e50 m/s^2 (carnot.validate's bound on magnitudes).

    >>> g = ground_oscillation({"amplitude": 0.01, "frequency": 5.0, "direction": [0, 2.0, 0]})
    >>> g.direction.tolist(), g.phase
    ([0.0, 1.0, 0.0], 0.0)
    >>> ground_oscillation({"amplitude": 0.01, "frequency": 0.0, "direction": [0, 1.0, 0]})
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: ground_oscillation.frequency: must be > 0, got 0.0
    """
    _known(spec, OSCILLATION_KEYS, field)
    amplitude = validate.non_negative_number(_require(spec, "amplitude", field),
                                             f"{field}.amplitude")  # fmt: skip
    frequency = validate.positive_number(_require(spec, "frequency", field), f"{field}.frequency")
    if frequency > MAX_FREQUENCY:
        raise InputError(f"{field}.frequency", f"must be <= {MAX_FREQUENCY:g} Hz", frequency)
    peak = amplitude * (2 * np.pi * frequency) ** 2
    if peak > validate.MAX_MAGNITUDE:
        raise InputError(f"{field}.amplitude", "gives a peak acceleration A (2 pi f)^2 above "
                         f"{validate.MAX_MAGNITUDE:g} m/s^2", amplitude)  # fmt: skip
    direction = validate.unit_vector(_require(spec, "direction", field), f"{field}.direction")
    phase = validate.finite_number(spec.get("phase", 0.0), f"{field}.phase")
    return Oscillation(amplitude=amplitude, frequency=frequency, direction=direction,
                       phase=phase)  # fmt: skip


def _plane(name: str, spec: Mapping[str, Any]) -> Plane:
    field = f"bodies.{name}"
    if spec["fixed"] is not True:
        raise InputError(f"{field}.fixed", "must be true (or absent)", spec["fixed"])
    _known(spec, ("fixed", "plane"), field)
    plane = _table(_require(spec, "plane", field), f"{field}.plane")
    _known(plane, ("point", "normal"), f"{field}.plane")
    return Plane(point=validate.vector3(_require(plane, "point", f"{field}.plane"),
                                        f"{field}.plane.point"),
                 normal=validate.unit_vector(_require(plane, "normal", f"{field}.plane"),
                                             f"{field}.plane.normal"))  # fmt: skip


def _body(name: str, spec: Mapping[str, Any]) -> tuple[SimBody, BodyState]:
    field = f"bodies.{name}"
    _known(spec, BODY_KEYS, field)
    mass = validate.positive_number(_require(spec, "mass", field), f"{field}.mass")
    shape_name = _require(spec, "shape", field)
    if shape_name not in SHAPE_DIMENSIONS:
        raise InputError(f"{field}.shape", f"must be one of {', '.join(SHAPE_DIMENSIONS)}",
                         shape_name)  # fmt: skip
    for other, key in SHAPE_DIMENSIONS.items():
        if other != shape_name and key in spec:
            raise InputError(f"{field}.{key}", f"is not a dimension of shape {shape_name!r}",
                             spec[key])  # fmt: skip
    dim = SHAPE_DIMENSIONS[shape_name]
    if dim not in spec:
        raise InputError(f"{field}.{dim}", f"is required for shape {shape_name!r}",
                         show_value=False)  # fmt: skip
    shape: Sphere | Convex
    if shape_name == "sphere":
        radius = validate.positive_number(spec["radius"], f"{field}.radius")
        shape = Sphere(radius=radius)
        inertia = sphere_inertia(mass, radius)
        if "inertia" in spec:
            raise InputError(f"{field}.inertia", "goes with shape = \"convex\" only",
                             spec["inertia"])  # fmt: skip
    else:
        if shape_name == "box":
            if "inertia" in spec:
                raise InputError(f"{field}.inertia", "goes with shape = \"convex\" only",
                                 spec["inertia"])  # fmt: skip
            vertices = box_vertices(spec["size"], f"{field}.size")
        else:
            raw = spec["vertices"]
            if not isinstance(raw, list) or not 3 <= len(raw) <= MAX_VERTICES:
                raise InputError(f"{field}.vertices",
                                 f"must be a list of 3 to {MAX_VERTICES} [x, y, z] points", raw)
            vertices = np.array([validate.vector3(v, f"{field}.vertices[{k}]")
                                 for k, v in enumerate(raw)])  # fmt: skip
        centroid, per_mass = hull_mass_properties(vertices, f"{field}.vertices")
        size = float(np.max(np.linalg.norm(vertices, axis=1)))
        if "inertia" in spec:
            inertia = validate.inertia_tensor(spec["inertia"], f"{field}.inertia")
        else:
            if float(np.linalg.norm(centroid)) > 1e-9 * size:
                raise InputError(
                    f"{field}.vertices",
                    "must be relative to the centre of mass: the uniform hull's centroid is "
                    f"at {np.round(centroid, 12).tolist()} (or give inertia for a body whose "
                    "mass is not uniform)", show_value=False)  # fmt: skip
            inertia = mass * per_mass
            try:
                inertia = validate.inertia_tensor(inertia, f"{field}.vertices")
            except InputError:
                raise InputError(
                    f"{field}.inertia",
                    "is required: a polygon's uniform inertia about its own normal axes is "
                    "not invertible (a lamina has no thickness); give the 3x3 inertia",
                    show_value=False) from None  # fmt: skip
        shape = Convex(vertices_body=vertices)
    orientation = _quaternion(spec.get("orientation"), field)
    state = BodyState(
        position=validate.vector3(spec.get("position", [0.0, 0, 0]), f"{field}.position"),
        orientation=orientation,
        velocity=validate.vector3(spec.get("velocity", [0.0, 0, 0]), f"{field}.velocity"),
        angular_velocity=validate.vector3(spec.get("angular_velocity", [0.0, 0, 0]),
                                          f"{field}.angular_velocity"))  # fmt: skip
    body = SimBody(name=name, mass=mass, inertia_body=np.asarray(inertia, float), shape=shape)
    v, w = body.planar_velocity(state.rotation, state.velocity, state.angular_velocity)
    if float(np.linalg.norm(v - state.velocity)) > 1e-12 * (1 + float(np.linalg.norm(v))):
        raise InputError(f"{field}.velocity", "a polygon moves in its plane: the velocity must "
                         "have no component along the polygon's normal", state.velocity.tolist())
    if float(np.linalg.norm(w - state.angular_velocity)) > 1e-12 * (1 + float(np.linalg.norm(w))):
        raise InputError(f"{field}.angular_velocity", "a polygon turns in its plane: the "
                         "angular velocity must be along the polygon's normal",
                         state.angular_velocity.tolist())  # fmt: skip
    return body, state


def _quaternion(value: Any, field: str) -> np.ndarray:
    if value is None:
        return np.array([1.0, 0.0, 0.0, 0.0])
    if not isinstance(value, list) or len(value) != 4:
        raise InputError(f"{field}.orientation", "must be a quaternion [w, x, y, z]", value)
    q = np.array([validate.finite_number(v, f"{field}.orientation[{k}]")
                  for k, v in enumerate(value)])  # fmt: skip
    length = float(np.linalg.norm(q))
    if length == 0:
        raise InputError(f"{field}.orientation", "must not be zero", value)
    return q / length


def _pairs(value: Any, names: set[str]) -> dict[tuple[str, str], PairLaw]:
    if not isinstance(value, list):
        raise InputError("pairs", "must be an array of tables ([[pairs]])", value)
    out: dict[tuple[str, str], PairLaw] = {}
    for k, spec in enumerate(value):
        field = f"pairs[{k}]"
        spec = _table(spec, field)
        _known(spec, PAIR_KEYS, field)
        a = _require(spec, "a", field)
        b = _require(spec, "b", field)
        if a not in names:
            raise InputError(f"{field}.a", f"unknown body (known: {', '.join(sorted(names))})", a)
        if b != "*" and b not in names:
            raise InputError(f"{field}.b",
                             f"unknown body (known: {', '.join(sorted(names))}, or \"*\")", b)
        if a == b:
            raise InputError(f"{field}.b", "must differ from a", b)
        law = spec.get("law", "newton")
        if law not in LAW_NAMES:
            raise InputError(f"{field}.law", f"must be one of {', '.join(LAW_NAMES)}", law)
        tangential = spec.get("tangential", "slip")
        if tangential not in ("slip", "stick"):
            raise InputError(f"{field}.tangential", "must be 'slip' or 'stick'", tangential)
        out[(a, b)] = PairLaw(
            restitution=validate.number_in(_require(spec, "restitution", field),
                                           f"{field}.restitution", 0, 1),
            friction=validate.non_negative_number(spec.get("friction", 0.0),
                                                  f"{field}.friction"),
            law=law, tangential=tangential)  # fmt: skip
    return out


def _law_for(table: dict[tuple[str, str], PairLaw], f: Feature, bodies: list[SimBody],
             plane_names: list[str]) -> PairLaw:  # fmt: skip
    a = bodies[f.body].name
    b = bodies[f.other].name if f.other >= 0 else plane_names[f.plane]
    for key in ((a, b), (b, a), (a, "*"), (b, "*")):
        if key in table:
            return table[key]
    raise InputError("pairs", f"no pair gives the law between {a!r} and {b!r} (add [[pairs]] "
                     f"a = {a!r}, b = {b!r}, or b = \"*\")", show_value=False)  # fmt: skip


def _check_start(bodies: list[SimBody], planes: list[Plane], plane_names: list[str],
                 states: list[BodyState], feats: list[Feature]) -> None:  # fmt: skip
    for f in feats:
        g = geometry(f, bodies, planes, states)
        if g.gap < -1e-9 * bodies[f.body].shape.size:
            other = bodies[f.other].name if f.other >= 0 else plane_names[f.plane]
            raise InputError(f"bodies.{bodies[f.body].name}.position",
                             f"starts inside {other!r} ({-g.gap:.6g} m deep)",
                             states[f.body].position.tolist())  # fmt: skip

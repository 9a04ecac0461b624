"""What one simulation amounts to, as numbers: the quantities a sweep of simulations records
per run (``carnot sweep`` on a ``[simulation]`` scenario; see docs/simulation.md).

Per run: ``events`` and ``impacts`` (counts), ``rest_time`` (s: the ``rest`` event, NaN when
the run does not come to rest), the ledger ``energy_initial``, ``energy_final``,
``energy_impacts``, ``energy_sliding``, ``ground_work``, ``energy_residual`` (J, loop.py),
``energy_impacts_theorem`` (J: the same impacts and series by the theorem, the second route
to ``energy_impacts``), ``impact_energy_ratio_min`` and ``_max`` (the smallest and largest
``T''/T'`` of the run's impacts, kinetic energy after over before; NaN without impacts: for
Housner's rocking block every impact keeps ``(1 - 3/2 sin^2 alpha)^2`` of it).
Per movable body ``NAME``:

- ``bodies.NAME.uplift``: one of the contacts it started on opened (a ``contact_end``
  event or an impact away from them): a block lifting a corner under a ground pulse;
- ``bodies.NAME.max_tilt`` (rad): the largest rotation from its initial orientation,
  ``2 acos |q_0 . q|``, over the sampled motion (every event, every integrator step and every
  ``sample_step``);
- ``bodies.NAME.overturned``: at the end of the run, the vertical through its centre of mass
  (along gravity) misses the region spanned by the vertices it started on: the static
  stability test of a body on its base (for Housner's rocking block, ``|theta| > alpha``).
  A body that starts on fewer than two vertices (a sphere, a body in flight) has no base:
  False;
- ``bodies.NAME.final_position_x|y|z`` (m).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from carnot.errors import InputError
from carnot.simulate.events import features, frame, geometry
from carnot.simulate.loop import Simulation, SimulationResult
from carnot.simulate.motion import quat_multiply
from carnot.simulate.shapes import Convex

#: Quantities of a run, and quantities of each movable body (column name ``bodies.NAME.Q``,
#: ``final_position`` as three columns), with their kinds (``float`` or ``bool``).
RUN_QUANTITIES = {"events": "float", "impacts": "float", "rest_time": "float",
                  "energy_initial": "float", "energy_final": "float",
                  "energy_impacts": "float", "energy_sliding": "float",
                  "ground_work": "float", "energy_residual": "float",
                  "energy_impacts_theorem": "float", "impact_energy_ratio_min": "float",
                  "impact_energy_ratio_max": "float"}  # fmt: skip
BODY_QUANTITIES = {"uplift": "bool", "max_tilt": "float", "overturned": "bool",
                   "final_position": "float"}  # fmt: skip
#: Quantities that may be NaN in a computed run.
MAY_BE_NAN = ("rest_time", "impact_energy_ratio_min", "impact_energy_ratio_max")


def check_record(names: Sequence[str]) -> tuple[str, ...]:
    """The quantities to record (all when ``names`` is empty), checked.

    >>> check_record(["impacts", "overturned"])
    ('impacts', 'overturned')
    >>> check_record(["angle"])
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --record: must name quantities of a simulation (events, impacts, rest_time, energy_initial, energy_final, energy_impacts, energy_sliding, ground_work, energy_residual, energy_impacts_theorem, impact_energy_ratio_min, impact_energy_ratio_max, uplift, max_tilt, overturned, final_position), got 'angle'
    """  # noqa: E501
    known = (*RUN_QUANTITIES, *BODY_QUANTITIES)
    out: list[str] = []
    for name in names:
        for part in (p.strip() for p in name.split(",")):
            if part not in known:
                raise InputError("--record", f"must name quantities of a simulation "
                                 f"({', '.join(known)})", part)  # fmt: skip
            if part not in out:
                out.append(part)
    return tuple(out) if out else known


def columns(sim: Simulation, record: Sequence[str]) -> list[tuple[str, str]]:
    """``(name, kind)`` of the recorded columns for the bodies of ``sim``."""
    out = [(q, RUN_QUANTITIES[q]) for q in RUN_QUANTITIES if q in record]
    for body in sim.bodies:
        for q, kind in BODY_QUANTITIES.items():
            if q not in record:
                continue
            if q == "final_position":
                out += [(f"bodies.{body.name}.final_position_{x}", kind) for x in "xyz"]
            else:
                out.append((f"bodies.{body.name}.{q}", kind))
    return out


def needs_samples(record: Sequence[str]) -> bool:
    """Whether the run must sample its motion (the tilt and the overturning)."""
    return "max_tilt" in record


def measure(result: SimulationResult, record: Sequence[str]) -> dict[str, float | bool]:
    """The recorded quantities of one run, by column name (module docstring)."""
    sim = result.simulation
    led = result.energy
    rest = [e.time for e in result.events if e.kind == "rest"]
    ratios = [e.impact.result.energy.after / e.impact.result.energy.before
              for e in result.events if e.kind == "impact" and e.impact is not None
              and e.impact.result.energy.before > 0]  # fmt: skip
    theorem = 0.0
    for e in result.events:
        if e.impact is not None:
            theorem += e.impact.result.energy.dissipated_theorem
        elif e.energy is not None:
            theorem += e.energy["dissipated_theorem"]
    run: dict[str, float] = {
        "events": float(len(result.events)),
        "impacts": float(sum(e.kind == "impact" for e in result.events)),
        "rest_time": rest[0] if rest else math.nan,
        "energy_initial": led.initial, "energy_final": led.final,
        "energy_impacts": led.impacts, "energy_sliding": led.sliding,
        "ground_work": led.ground_work, "energy_residual": led.residual,
        "energy_impacts_theorem": theorem,
        "impact_energy_ratio_min": min(ratios) if ratios else math.nan,
        "impact_energy_ratio_max": max(ratios) if ratios else math.nan,
    }  # fmt: skip
    out: dict[str, float | bool] = {q: v for q, v in run.items() if q in record}
    bases = initial_bases(sim)
    for i, body in enumerate(sim.bodies):
        pre = f"bodies.{body.name}."
        if "uplift" in record:
            out[pre + "uplift"] = _uplift(result, i, bases[i])
        if "max_tilt" in record:
            out[pre + "max_tilt"] = _max_tilt(result, i)
        if "overturned" in record:
            out[pre + "overturned"] = overturned(sim, i, bases[i], result.final[i])
        if "final_position" in record:
            for x, v in zip("xyz", result.final[i].position.tolist(), strict=True):
                out[pre + f"final_position_{x}"] = v
    return out


def initial_bases(sim: Simulation) -> list[list[tuple[int, int]]]:
    """Per body, the ``(plane, vertex)`` pairs it touches at the start (gap within a
    billionth of its size)."""
    out: list[list[tuple[int, int]]] = [[] for _ in sim.bodies]
    for f in features(sim.bodies, sim.planes):
        if f.other >= 0 or f.vertex < 0:
            continue
        if geometry(f, sim.bodies, sim.planes, sim.initial).gap <= \
                1e-9 * sim.bodies[f.body].shape.size:  # fmt: skip
            out[f.body].append((f.plane, f.vertex))
    return out


def overturned(sim: Simulation, i: int, base: list[tuple[int, int]], state: object) -> bool:
    """Whether the vertical through body ``i``'s centre of mass (along gravity), at ``state``,
    misses the region its base vertices span on their plane (module docstring).

    Projected on the plane along gravity, the base is a polygon (its 2D hull) or, for two
    vertices or collinear ones (a lamina on its two corners, a box on an edge), a segment:
    the centre of mass must lie within it (up to a billionth of the body's size)."""
    if len(base) < 2:
        return False
    shape = sim.bodies[i].shape
    assert isinstance(shape, Convex)
    plane = sim.planes[base[0][0]]
    n, t1, t2 = frame(plane.normal)
    g = sim.gravity
    g_n = float(g @ n)
    if g_n >= 0:  # gravity does not press the body on that plane: no base to stand on
        return False
    rot = state.rotation  # type: ignore[attr-defined]
    x = state.position  # type: ignore[attr-defined]

    def on_plane(p: np.ndarray) -> np.ndarray:  # along gravity, in the plane's axes
        q = p - float((p - plane.point) @ n) / g_n * g
        return np.array([float(q @ t1), float(q @ t2)])

    corners = np.array([on_plane(x + rot @ shape.vertices_body[k]) for _, k in base])
    centre = on_plane(x)
    tol = 1e-9 * shape.size
    offset = corners - corners.mean(axis=0)
    _, sing, vt = np.linalg.svd(offset)
    if sing.size < 2 or sing[1] <= 1e-9 * max(sing[0], 1e-300):  # a segment
        axis = vt[0]
        s = offset @ axis
        c = float((centre - corners.mean(axis=0)) @ axis)
        return bool(c < s.min() - tol or c > s.max() + tol)
    from scipy.spatial import ConvexHull

    hull = ConvexHull(corners)
    return bool(np.any(hull.equations[:, :2] @ centre + hull.equations[:, 2] > tol))


def _uplift(result: SimulationResult, i: int, base: list[tuple[int, int]]) -> bool:
    if not base:
        return False
    name = result.simulation.bodies[i].name
    for e in result.events:
        if e.kind == "contact_end" and any(a == name for a, _ in e.contacts):
            return True
    return False


def _max_tilt(result: SimulationResult, i: int) -> float:
    q0 = result.simulation.initial[i].orientation
    samples = result.samples
    states = [result.final[i]] if samples is None else [s[i] for s in samples.states]
    states.append(result.final[i])
    q = np.array([s.orientation for s in states])
    # the rotation q0^-1 q: 2 atan2(|vector part|, |scalar part|), accurate at small angles
    # (2 acos|q0 . q| loses half the digits there)
    rel = quat_multiply(np.broadcast_to(q0 * [1.0, -1.0, -1.0, -1.0], q.shape), q)
    return float((2 * np.arctan2(np.linalg.norm(rel[:, 1:], axis=1), np.abs(rel[:, 0]))).max())

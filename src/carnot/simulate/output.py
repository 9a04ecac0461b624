"""Reports of a simulation: the event table, the JSON of DESIGN.md section 8, the sampled
trajectory (Parquet), the energy budget over time and an animation.

JSON: ``{"format": 1, "title", "events": [...], "final": {body: {position, orientation,
velocity, angular_velocity}}, "energy": {initial, final, impacts, sliding, ground_work,
residual}}``; an impact event carries ``bodies``, ``contacts``, ``energy`` and ``warnings``
exactly as a section 4 result (:func:`carnot.io.results.result_to_dict`) plus the
simulation's own flags; an accumulation its series' energy (``dissipated`` directly,
``dissipated_theorem`` by the theorem summed over the series, ``ratio``, ``series_start``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.io.json_text import dumps
from carnot.io.json_text import finite_list as _vec
from carnot.io.json_text import finite_or_none as _num
from carnot.io.results import (
    bodies_to_dict,
    constraints_to_dict,
    contacts_to_dict,
    energy_to_dict,
    warnings_to_dict,
)
from carnot.simulate.loop import Event, SimulationResult
from carnot.simulate.motion import kinetic_energy, potential_energy

FORMAT = 1
ANIMATION_SUFFIXES = (".gif", ".mp4", ".html")
PLOT_SUFFIXES = (".png", ".svg", ".pdf")




def _event(e: Event) -> dict[str, Any]:
    out: dict[str, Any] = {"time": _num(e.time), "kind": e.kind,
                           "contacts": [{"a": a, "b": b} for a, b in e.contacts]}  # fmt: skip
    if e.impact is not None:
        # the keys of result_to_dict that an event carries, made alone (not the momentum
        # check, which an event does not carry and a result makes only when read)
        res = e.impact.result
        out["bodies"] = bodies_to_dict(res)
        out["contacts"] = contacts_to_dict(res)
        if res.constraints:  # a settling impact's fastened corners
            out["constraints"] = constraints_to_dict(res)
        out["energy"] = energy_to_dict(res)
        out["warnings"] = warnings_to_dict(res) + [
            {"code": f.code, "where": f.where, "message": f.message} for f in e.impact.flags]
    elif e.energy is not None:
        out["energy"] = {k: _num(float(v)) for k, v in e.energy.items()}
    return out


def to_dict(result: SimulationResult) -> dict[str, Any]:
    """The section 8 result as plain data.

    >>> from carnot.simulate import parse_simulation, run
    >>> sim = parse_simulation({"format": 1, "simulation": {"duration": 0.5},
    ...     "bodies": {"ball": {"mass": 1.0, "shape": "sphere", "radius": 0.1,
    ...                         "position": [0, 1.1, 0]},
    ...                "floor": {"fixed": True, "plane": {"point": [0, 0, 0],
    ...                                                    "normal": [0, 1, 0]}}},
    ...     "pairs": [{"a": "ball", "b": "floor", "restitution": 1.0}]})
    >>> d = to_dict(run(sim))
    >>> [e["kind"] for e in d["events"]], round(d["energy"]["impacts"], 12)
    (['impact'], 0.0)
    """
    sim = result.simulation
    e = result.energy
    return {
        "format": FORMAT,
        "title": sim.title,
        "events": [_event(ev) for ev in result.events],
        "final": {
            b.name: {"position": _vec(s.position), "orientation": _vec(s.orientation),
                     "velocity": _vec(s.velocity), "angular_velocity": _vec(s.angular_velocity)}
            for b, s in zip(sim.bodies, result.final, strict=True)
        },
        "energy": {"initial": _num(e.initial), "final": _num(e.final),
                   "impacts": _num(e.impacts), "sliding": _num(e.sliding),
                   "ground_work": _num(e.ground_work), "residual": _num(e.residual)},
    }  # fmt: skip


def to_json(result: SimulationResult) -> str:
    """:func:`to_dict` as indented JSON (``json.dumps(..., indent=2, allow_nan=False)``'s
    text: :func:`carnot.io.json_text.dumps`)."""
    return dumps(to_dict(result))


def format_table(result: SimulationResult) -> str:
    """A readable table: one line per event, then the ledger."""
    sim = result.simulation
    lines = [f"{sim.title or 'simulation'}: {len(result.events)} events in "
             f"{sim.duration:g} s", "",
             f"{'time (s)':>16}  {'kind':<14} {'contacts':<28} {'E_d (J)':>12} "
             f"{'theorem (J)':>12}"]  # fmt: skip
    for ev in result.events:
        names = ", ".join(f"{a}/{b}" for a, b in ev.contacts)
        e_d = th = ""
        if ev.impact is not None:
            led = ev.impact.result.energy
            e_d, th = f"{led.dissipated:12.6g}", f"{led.dissipated_theorem:12.6g}"
        elif ev.energy is not None:
            e_d = f"{ev.energy['dissipated']:12.6g}"
            th = f"{ev.energy['dissipated_theorem']:12.6g}"
        lines.append(f"{ev.time:16.12f}  {ev.kind:<14} {names:<28} {e_d:>12} {th:>12}")
    e = result.energy
    lines += ["", "energy (J, kinetic + potential, in the ground's frame):",
              f"  initial {e.initial:.12g} + ground work {e.ground_work:.12g} - impacts "
              f"{e.impacts:.12g} - sliding {e.sliding:.12g} = {e.initial + e.ground_work - e.impacts - e.sliding:.12g}",  # noqa: E501
              f"  final   {e.final:.12g}  (residual {e.residual:.3g})"]  # fmt: skip
    return "\n".join(lines)


def _need_samples(result: SimulationResult) -> Any:
    if result.samples is None:
        raise InputError("samples", "the simulation was run without record=True",
                         show_value=False)  # fmt: skip
    return result.samples


def write_trajectory(result: SimulationResult, path: str | Path) -> int:
    """Write the sampled motion to Parquet, one row per body and sample: ``time``, ``body``,
    position ``x, y, z``, quaternion ``qw, qx, qy, qz``, velocity ``vx, vy, vz``, angular
    velocity ``wx, wy, wz``, ``kinetic`` and ``potential`` (J). Needs pyarrow (the extra
    ``carnot[sweep]``). Returns the number of rows."""
    if not str(path).lower().endswith(".parquet"):
        raise InputError("--trajectory", "must end in .parquet", str(path))
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise InputError("--trajectory", "needs pyarrow: pip install 'carnot[sweep]'",
                         show_value=False) from None  # fmt: skip
    samples = _need_samples(result)
    sim = result.simulation
    columns: dict[str, list[Any]] = {k: [] for k in (
        "time", "body", "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy",
        "wz", "kinetic", "potential")}  # fmt: skip
    for t, states in zip(samples.times, samples.states, strict=True):
        for b, s in zip(sim.bodies, states, strict=True):
            columns["time"].append(t)
            columns["body"].append(b.name)
            for key, value in zip(("x", "y", "z"), s.position, strict=True):
                columns[key].append(float(value))
            for key, value in zip(("qw", "qx", "qy", "qz"), s.orientation, strict=True):
                columns[key].append(float(value))
            for key, value in zip(("vx", "vy", "vz"), s.velocity, strict=True):
                columns[key].append(float(value))
            for key, value in zip(("wx", "wy", "wz"), s.angular_velocity, strict=True):
                columns[key].append(float(value))
            columns["kinetic"].append(kinetic_energy(b, s))
            columns["potential"].append(potential_energy(b, s, sim.gravity))
    pq.write_table(pa.table(columns), str(path))
    return len(columns["time"])


def energy_budget(result: SimulationResult) -> dict[str, np.ndarray]:
    """Per sample: time (s), kinetic, potential, impacts, sliding, ground work (J) and the
    closure ``kinetic + potential + impacts + sliding - ground_work`` (constant = initial)."""
    samples = _need_samples(result)
    sim = result.simulation
    kin = np.array([sum(kinetic_energy(b, s) for b, s in zip(sim.bodies, st, strict=True))
                    for st in samples.states])  # fmt: skip
    pot = np.array([sum(potential_energy(b, s, sim.gravity)
                        for b, s in zip(sim.bodies, st, strict=True))
                    for st in samples.states])  # fmt: skip
    imp, sl, gw = (np.array(x) for x in (samples.impacts, samples.sliding, samples.ground_work))
    return {"time": np.array(samples.times), "kinetic": kin, "potential": pot, "impacts": imp,
            "sliding": sl, "ground_work": gw, "total": kin + pot + imp + sl - gw}  # fmt: skip


def check_suffix(path: str, option: str, allowed: tuple[str, ...]) -> None:
    """Refuse an output file of a kind we do not write (before the simulation runs)."""
    if not path.lower().endswith(allowed):
        raise InputError(option, f"must end in {', '.join(allowed)}", path)


def plot_energy(result: SimulationResult, path: str | Path) -> None:
    """The energy budget over time: kinetic, potential (relative to its start), lost in
    impacts, lost in sliding, work of the ground, and their closure (flat when every joule is
    accounted)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    check_suffix(str(path), "--plot", PLOT_SUFFIXES)
    d = energy_budget(result)
    pot = d["potential"] - d["potential"][0]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(d["time"], d["kinetic"], label="kinetic")
    ax.plot(d["time"], pot, label="potential (from its start)")
    ax.plot(d["time"], d["impacts"], label="lost in impacts", drawstyle="steps-post")
    ax.plot(d["time"], d["sliding"], label="lost in sliding")
    ax.plot(d["time"], d["ground_work"], label="work of the ground")
    ax.plot(d["time"], d["total"] - d["potential"][0], "k--",
            label="kinetic + potential + lost - ground work")  # fmt: skip
    ax.set_xlabel("time (s)")
    ax.set_ylabel("energy (J)")
    ax.set_title(result.simulation.title or "energy budget")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(str(path))
    plt.close(fig)


def animate(result: SimulationResult, path: str | Path, frames: int = 200) -> None:
    """Draw the motion in the world x-y plane (spheres as circles, convex bodies as the hull
    of their projected vertices, planes as lines) to a GIF (Pillow), an MP4 (needs ffmpeg) or
    an HTML page (``to_jshtml``: no ffmpeg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation
    from scipy.spatial import ConvexHull, QhullError

    from carnot.simulate.shapes import Sphere

    target = str(path)
    check_suffix(target, "--animate", ANIMATION_SUFFIXES)
    samples = _need_samples(result)
    sim = result.simulation
    times = np.array(samples.times)
    picks = np.unique(np.searchsorted(times, np.linspace(times[0], times[-1], frames)))
    picks = picks[picks < len(times)]
    xy = np.array([[s.position[:2] for s in samples.states[k]] for k in picks])
    size = max(b.shape.size for b in sim.bodies)
    lo, hi = xy.reshape(-1, 2).min(axis=0) - 1.5 * size, xy.reshape(-1, 2).max(axis=0) + 1.5 * size
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    span = np.linspace(-1, 1, 2) * 10 * float(np.max(hi - lo))
    for plane in sim.planes:
        n = plane.normal
        tangent = np.array([-n[1], n[0]]) if abs(n[2]) < 1 else np.array([1.0, 0.0])
        line = plane.point[:2] + span[:, None] * tangent / (np.linalg.norm(tangent) or 1.0)
        ax.plot(line[:, 0], line[:, 1], "k-", lw=1)
    patches: list[Any] = []
    for b in sim.bodies:
        patch: Any
        if isinstance(b.shape, Sphere):
            patch = plt.Circle((0, 0), b.shape.radius, fc="tab:blue", alpha=0.7)
        else:
            patch = plt.Polygon(np.zeros((3, 2)), closed=True, fc="tab:orange", alpha=0.7)
        ax.add_patch(patch)
        patches.append(patch)
    label = ax.set_title("")

    def draw(j: int) -> list[Any]:
        k = int(picks[j])
        for b, s, patch in zip(sim.bodies, samples.states[k], patches, strict=True):
            if isinstance(b.shape, Sphere):
                patch.center = (float(s.position[0]), float(s.position[1]))
            else:
                pts = (s.position + b.shape.vertices_body @ s.rotation.T)[:, :2]
                try:
                    pts = pts[ConvexHull(pts).vertices]
                except QhullError:
                    pass
                patch.set_xy(pts)
        label.set_text(f"t = {times[k]:.3f} s")
        return [*patches, label]

    anim = animation.FuncAnimation(fig, draw, frames=len(picks), interval=40, blit=False)
    try:
        if target.lower().endswith(".html"):
            Path(target).write_text(anim.to_jshtml(), encoding="utf-8")
        elif target.lower().endswith(".gif"):
            anim.save(target, writer=animation.PillowWriter(fps=25))
        else:
            if not animation.writers.is_available("ffmpeg"):
                raise InputError("--animate", "an .mp4 needs ffmpeg (use .gif or .html)", target)
            anim.save(target, writer=animation.FFMpegWriter(fps=25))
    finally:
        plt.close(fig)

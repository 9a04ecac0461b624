"""A mesh held on one vertex (carnot.hybrid.flow's held_drift, carnot.hybrid.mjcf's pair rows):
MuJoCo's plane-mesh collider lists the deepest vertex and a few of its neighbours, so that a
held vertex leaves the list where a neighbour becomes the deepest (Unitree G1's ankle mesh,
0.097 s into a drop). A held point that is another one from then on would move at that
point's speed, and the held force would do work ``F . J q'`` that no ledger books (G1: 4e-3
J). Such a run stops where it happens, flagged ``held_point_lost``, its ledger closed.

The model: a rod, an octagonal prism (radius 1 cm, 30 cm tall, 1 kg) leaning 0.03 rad about
x and 0.01 rad about y, its lowest vertex 0.7 mm above the floor; it falls on that vertex,
sticks there (plastic, MuJoCo's friction 1), rocks back about it and the next vertex of its
octagon comes down.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from carnot.hybrid.flow import held_drift
from carnot.hybrid.mjcf import mjcf_model
from carnot.hybrid.simulate import simulate


def _quat(axis: list[float], angle: float) -> np.ndarray:
    return np.array([math.cos(angle / 2), *(math.sin(angle / 2) * np.asarray(axis))])


def _product(p: np.ndarray, r: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = p
    w2, x2, y2, z2 = r
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])  # fmt: skip


def _rod(tmp_path: Path) -> Path:
    corners = [(0.01 * math.cos(2 * math.pi * (k + 0.5) / 8),
                0.01 * math.sin(2 * math.pi * (k + 0.5) / 8)) for k in range(8)]  # fmt: skip
    vertices = " ".join(f"{x:.6f} {y:.6f} {z}" for z in (0.0, 0.3) for x, y in corners)
    quat = _product(_quat([0.0, 1.0, 0.0], -0.01), _quat([1.0, 0.0, 0.0], -0.03))
    path = tmp_path / "rod.xml"
    path.write_text(f"""<mujoco>
  <asset><mesh name="rod" vertex="{vertices}"/></asset>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="rod" pos="0 0 0.001" quat="{' '.join(f'{c:.15g}' for c in quat)}">
      <freejoint/><geom name="rod" type="mesh" mesh="rod" mass="1"/>
    </body>
  </worldbody>
</mujoco>
""")
    return path


def test_a_held_vertex_that_mujoco_no_longer_lists_stops_the_run_its_ledger_closed(
        tmp_path: Path) -> None:  # fmt: skip
    """Held on one vertex from its strike at 0.0118 s, sticking; 0.158 s in, the next vertex
    becomes the deepest and MuJoCo lists it in the held one's place: the run stops there
    (before: the hold went on with the new vertex, coming down at its speed, and the
    ledger's residual was 3.0e-4 J of 1.48). Until then the held vertex stays at rest: its
    rows' speed within the integrator's tolerance at the stop's state, and the stop is the
    first state where it is not."""
    motion = mjcf_model(_rod(tmp_path))
    run = simulate(motion.model, motion.state, 0.5, motion.law)
    kinds = [(e.kind, e.flags) for e in run.events]
    assert kinds == [("impact", ()), ("contact_start", ("rod/floor", "sticking")),
                     ("stop", ("held_point_lost", "rod/floor"))]  # fmt: skip
    assert run.ended == "stop" and 0.15 < run.time < 0.17
    assert abs(run.energy["residual"]) < 1e-12 * run.energy["initial"]
    (hold,) = run.events[-1].held
    assert held_drift(motion.model, hold, run.final) >= 0.0  # the point there is another
    # the hold's state just after its start: its vertex at rest to round-off
    start = run.events[1].state
    assert held_drift(motion.model, hold, start) < 0.0

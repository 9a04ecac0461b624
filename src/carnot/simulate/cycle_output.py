"""What ``carnot cycle`` prints for a scenario of free bodies (DESIGN.md section 10; the
keys in docs/formats.md): the section 10 result, with ``state`` holding the bodies' states
on the section in place of ``q`` and ``qdot``.

``state``: ``time`` (s, the impact's time modulo the forcing period ``T``) and ``phase``
(rad, the ground's phase ``2 pi f time + phase`` modulo ``2 pi``) when the ground oscillates,
then ``bodies``: for each movable body ``position`` (m) and ``velocity`` (m/s) relative to the
fixed bodies, and ``orientation`` (``[w, x, y, z]``) and ``angular_velocity`` (rad/s) where
they are coordinates of the section (a body that turns; a sphere's orientation never is).
``section`` says what the multipliers are of: its ``coordinates``, the ``constraints`` (the
contacts struck at the section, whose gaps vanish on it: one coordinate fewer each) and the
``neutral`` directions left out with their multipliers (simulate/cycle.py).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from carnot.io.json_text import dumps
from carnot.io.json_text import finite_list as _vec
from carnot.io.json_text import finite_or_none as _num
from carnot.io.results import result_to_dict
from carnot.simulate.cycle import FreeCycle
from carnot.simulate.ground import Oscillation

FORMAT = 1

_FLAG_TEXT = {
    "grazing": "an impact of the period approaches at almost zero speed (the contact is met "
    "tangentially): the return map is not differentiable there and no multiplier is given",
    "not_converged": "Newton's method did not reach a periodic orbit (the residual, and the "
    "warnings that follow, say where it stopped)",
    "not_differentiable": "a state next to this one does not return as it does (its motion "
    "ends in a contact phase, chatter or no impact): the return map has no derivative here",
    "no_return": "the motion from the state does not come back to the section (no impact "
    "within the longest period, the bodies come to rest, or the simulator refused the run)",
}




def _complex(z: np.ndarray | None) -> list[list[float | None]] | None:
    if z is None:
        return None
    return [[_num(float(w.real)), _num(float(w.imag))] for w in z]


def state_to_dict(cycle: FreeCycle) -> dict[str, Any]:
    """The section's state as plain data (module docstring)."""
    out: dict[str, Any] = {}
    ground = cycle.simulation.ground
    if isinstance(ground, Oscillation) and cycle.forcing_period is not None:
        tau = math.fmod(cycle.point.time, cycle.forcing_period)
        tau = tau + cycle.forcing_period if tau < 0 else tau
        out["time"] = _num(tau)
        out["phase"] = _num(math.fmod(ground.angular_frequency * tau + ground.phase,
                                      2 * math.pi) % (2 * math.pi))  # fmt: skip
    bodies: dict[str, Any] = {}
    lay = cycle.layout
    for b, (name, s) in enumerate(zip(lay.names, cycle.point.states, strict=True)):
        entry: dict[str, Any] = {"position": _vec(s.position), "velocity": _vec(s.velocity)}
        if lay.orients[b]:
            entry["orientation"] = _vec(s.orientation)
        if lay.spins[b]:
            entry["angular_velocity"] = _vec(s.angular_velocity)
        bodies[name] = entry
    out["bodies"] = bodies
    return out


def free_cycle_to_dict(cycle: FreeCycle, title: str = "") -> dict[str, Any]:
    """A periodic orbit of free bodies as plain data (section 10; docs/formats.md)."""
    out: dict[str, Any] = {
        "format": FORMAT,
        "title": title,
        "period": _num(cycle.period),
        "forcing_period": _num(cycle.forcing_period),
        "forcing_periods": cycle.forcing_periods,
        "strikes": cycle.strikes,
        "state": state_to_dict(cycle),
        "multipliers": _complex(cycle.multipliers),
        "multipliers_route": cycle.route,
        "stable": cycle.stable,
        "residual": _num(cycle.residual),
        "converged": cycle.converged,
        "iterations": cycle.iterations,
        "section": {
            "coordinates": list(cycle.layout.coordinates),
            "constraints": [list(c) for c in cycle.constraints],
            "neutral": list(cycle.neutral_names),
            "neutral_multipliers": _complex(cycle.neutral),
        },
        "impacts": [result_to_dict(hit.result) for hit in cycle.impacts],
        "energy": {k: _num(v) for k, v in cycle.energy.items()},
        "warnings": [{"code": f, "message": _FLAG_TEXT.get(f, f)} for f in cycle.flags],
    }
    if cycle.guess_time is not None:
        out["warnings"].append({"code": "guess_flown", "message": (
            "the file's state is not just after an impact: the guess is the state after its "
            f"first impact, at t = {cycle.guess_time:.12g} s")})  # fmt: skip
    if cycle.check is not None:
        out["multipliers_finite_difference"] = _complex(cycle.check)
    return out


def free_cycle_to_json(cycle: FreeCycle, title: str = "") -> str:
    """:func:`free_cycle_to_dict` as indented JSON."""
    return dumps(free_cycle_to_dict(cycle, title))


def _shown(z: np.ndarray) -> str:
    return ", ".join(f"{w.real:.6f}{w.imag:+.6f}i" if abs(w.imag) > 0 else f"{w.real:.6f}"
                     for w in z)  # fmt: skip


def format_free_cycle(cycle: FreeCycle, title: str = "") -> str:
    """The orbit's period, state, multipliers and energy per period, as text."""
    head = "periodic orbit" if cycle.converged else "no periodic orbit found"
    lines = [f"{title or 'free bodies'}: {head} ({cycle.iterations} Newton steps, residual "
             f"{cycle.residual:.3g})"]  # fmt: skip
    if cycle.converged:
        forced = "" if cycle.forcing_period is None else (
            f", {cycle.forcing_periods} forcing period{'s' if cycle.forcing_periods > 1 else ''}"
            f" of {cycle.forcing_period:.12g} s")  # fmt: skip
        lines.append(f"  period {cycle.period:.12g} s ({cycle.strikes} impact"
                     f"{'s' if cycle.strikes > 1 else ''}{forced})")  # fmt: skip
        state = state_to_dict(cycle)
        if "time" in state:
            lines.append(f"  impact at t = {state['time']:.12g} s (mod T), ground phase "
                         f"{state['phase']:.12f} rad")  # fmt: skip
        for name, entry in state["bodies"].items():
            for key, value in entry.items():
                lines.append(f"  {name}.{key:<16} [" + ", ".join(f"{v: .12g}" for v in value)
                             + "]")  # fmt: skip
        if cycle.multipliers is not None:
            lines.append(f"  multipliers {_shown(cycle.multipliers)}  ("
                         f"{'stable' if cycle.stable else 'unstable'}; {cycle.route})")
            if cycle.neutral_names:
                lines.append(f"  left out (neutral, multiplier 1): "
                             f"{'; '.join(cycle.neutral_names)}")  # fmt: skip
        if cycle.check is not None:
            lines.append(f"  finite differences: {_shown(cycle.check)}")
        en = cycle.energy
        lines.append(f"  per period: impacts take {en['impacts']:.12g} J, sliding "
                     f"{en['sliding']:.12g} J, the ground gives {en['ground_work']:.12g} J "
                     f"(residual {en['residual']:.3g})")  # fmt: skip
    for f in cycle.flags:
        lines.append(f"  warning {f}: {_FLAG_TEXT.get(f, f)}")
    if cycle.guess_time is not None:
        lines.append(f"  note: the guess was flown to its first impact, t = "
                     f"{cycle.guess_time:.12g} s")  # fmt: skip
    return "\n".join(lines)

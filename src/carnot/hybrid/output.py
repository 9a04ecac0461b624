"""What ``carnot simulate`` and ``carnot cycle`` print for a model in motion: JSON (DESIGN.md
section 10) and readable tables.

A run's events are those of section 8: each impact carries ``contacts`` and ``energy``
exactly as a section 4 result (the strike solved in floating coordinates), with ``system``
(``q``, ``qdot`` in the model's chart just after the strike, and ``qdot_before``) in place of
``bodies``; ``final`` is ``{"system": {"q", "qdot"}}``. ``--saltation`` adds each impact's
``saltation`` matrix, in the state order ``(q, qdot)`` (with a free or ball joint, ``nq !=
n``: ``2 n x 2 n`` in the tangent chart ``(dq, dqdot)``, :func:`carnot.hybrid.model.
tangent_step`). A contact held in the flow has its
events (``contact_start``, ``contact_end``, ``stick``, ``slip``) with ``contacts`` (its
guard's name) and, where it can slide, ``regime`` (``sticking``, ``sliding``) and the slide's
``direction`` (``+t``, ``-t``). ``energy`` adds ``dampers`` and ``sliding``, the work the
dampers and the sliding contacts' friction took:
``initial - impacts - dampers - sliding = final`` to the integrator's tolerance.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from carnot.hybrid.cycle import Cycle
from carnot.hybrid.simulate import HybridEvent, HybridRun
from carnot.io.json_text import dumps
from carnot.io.json_text import finite_list as _vec
from carnot.io.json_text import finite_or_none as _num
from carnot.io.results import contacts_to_dict, energy_to_dict, result_to_dict, warnings_to_dict

FORMAT = 1




#: The events of a contact held in the flow (DESIGN.md section 8's kinds).
HELD_KINDS = ("contact_start", "contact_end", "stick", "slip")


def _system(nq: int, x: np.ndarray) -> dict[str, Any]:
    """``q`` (the ``nq`` positions: MuJoCo's ``qpos`` for an MJCF model, quaternions
    included) and ``qdot`` (the velocities: its ``qvel``)."""
    return {"q": _vec(x[:nq]), "qdot": _vec(x[nq:])}


def _event(e: HybridEvent, nq: int) -> dict[str, Any]:
    out: dict[str, Any] = {"time": _num(e.time), "kind": e.kind}
    if e.strike is not None:
        res = e.strike.result
        out["guard"] = e.strike.guard.name
        out["system"] = {**_system(nq, e.strike.x_after),
                         "qdot_before": _vec(e.strike.x_before[nq:]),
                         "q_before": _vec(e.strike.x_before[:nq])}  # fmt: skip
        out["contacts"] = contacts_to_dict(res)
        out["energy"] = energy_to_dict(res)
        out["warnings"] = warnings_to_dict(res) + [
            {"code": f, "where": e.strike.guard.name, "message": _FLAG_TEXT.get(f, f)}
            for f in e.flags]  # fmt: skip
        if e.saltation is not None:
            out["saltation"] = [_vec(row) for row in e.saltation]
    else:
        out["system"] = _system(nq, e.state)
        if e.kind in HELD_KINDS:  # a held contact's event: which, and how it is held now
            out["contacts"] = [e.flags[0]]
            if len(e.flags) > 1:
                out["regime"] = e.flags[1]
                if len(e.flags) > 2:
                    out["direction"] = e.flags[2]
        if e.kind == "stop":  # a stop with no strike of its own: what it says, by code
            code, *where = e.flags
            out["warnings"] = [{"code": code, "where": ", ".join(where),
                                "message": _FLAG_TEXT.get(code, code)}]  # fmt: skip
    out["anchor"] = _vec(e.anchor)
    return out


_FLAG_TEXT = {
    "stance_slips": "the struck point does not stick after the strike (too little friction, "
    "or a bounce): the walk stops here",
    "double_support": "the old stance point does not lift off: both feet hold (double "
    "support), which the model does not walk through",
    "grazing": "the guard is met tangentially: no saltation matrix exists here",
    "stance_lifts": "the ground's force on the stance foot would pull: the foot lifts off "
    "(a flight phase the model does not have), and the run stops here",
    "not_converged": "Newton's method did not reach a periodic orbit (the residual, and the "
    "warnings that follow, say where it stopped)",
    "no_return": "the flow from the state does not come back to the section (it falls or "
    "never strikes)",
    "held_contact": "a strike leaves its contact closed and at rest, held in the flow, on a "
    "model whose return map is the free flow's",
    "chatter": "a strike came within the chatter interval of the last on its guard (made "
    "plastic): the return map has no linearization there",
    "equilibrium": "Newton's method went to the state of rest, not to a periodic motion",
    "trivial_multiplier": "the monodromy has no eigenvalue within 1e-6 of 1 along the flow: "
    "its linearization is off, and the multipliers are doubtful",
    "contact_persists": "a contact between two bodies from MJCF stays closed, pressed by "
    "the flow, in a way carnot does not hold yet (no hold of its points, or of those that "
    "push, has pushing forces; or a point's regime cannot be decided: outside its cone "
    "while sticking, turning back when it slides): the run stops here",
    "held_singular": "the flow with contacts held cannot go on: its forces grow without "
    "bound (a sliding contact whose normal force's coefficient, with friction, falls to "
    "zero: Painleve's paradox) and the integrator's step falls below round-off; the run "
    "stops here",
    "held_point_lost": "a held contact point is no longer among the points MuJoCo's collider "
    "lists for its pair, another in its place (a mesh's vertex on a plane, which lists the "
    "deepest vertex and a few of its neighbours): the held force would do work on the new "
    "point's speed, which no ledger books; the run stops here",
}


def run_to_dict(run: HybridRun, title: str = "") -> dict[str, Any]:
    """A run as plain data (section 10)."""
    nq = run.model.nq
    return {
        "format": FORMAT,
        "title": title,
        "model": {"name": run.model.name, "parameters": dict(run.model.parameters),
                  "coordinates": list(run.model.coordinates), "notes": run.model.notes},
        "events": [_event(e, nq) for e in run.events],
        "final": {"system": _system(nq, run.final), "time": _num(run.time),
                  "anchor": _vec(run.anchor)},
        "ended": run.ended,
        "energy": {k: _num(v) for k, v in run.energy.items()},
    }  # fmt: skip


def cycle_to_dict(cycle: Cycle, title: str = "") -> dict[str, Any]:
    """A periodic orbit as plain data (section 10)."""
    n = cycle.model.n
    mult = None
    if cycle.multipliers is not None:
        mult = [[_num(float(z.real)), _num(float(z.imag))] for z in cycle.multipliers]
    return {
        "format": FORMAT,
        "title": title,
        "model": {"name": cycle.model.name, "parameters": dict(cycle.model.parameters),
                  "coordinates": list(cycle.model.coordinates)},
        "period": _num(cycle.period),
        "strikes": cycle.steps,
        "state": _system(n, cycle.state),
        "multipliers": mult,
        "stable": cycle.stable,
        "residual": _num(cycle.residual),
        "converged": cycle.converged,
        "iterations": cycle.iterations,
        "impacts": [result_to_dict(s.result) for s in cycle.strikes],
        "energy": {k: _num(v) for k, v in cycle.energy.items()},
        "warnings": [{"code": f, "message": _FLAG_TEXT.get(f, f)} for f in cycle.flags],
        **_symmetry(cycle),
    }  # fmt: skip


def _symmetry(cycle: Cycle) -> dict[str, Any]:
    """The symmetry the orbit returns up to, where one is declared: ``shift`` (each shifted
    coordinate's advance, rad or m) and ``advance`` (each cyclic coordinate's change over the
    period: a step's length)."""
    sym = cycle.symmetry
    if sym is None or not sym.given:
        return {}
    shift = {name: _num(float(v)) for name, v in zip(sym.names, sym.shift, strict=False) if v}
    return {"shift": shift, "advance": {k: _num(v) for k, v in cycle.advance.items()}}


def run_to_json(run: HybridRun, title: str = "") -> str:
    """:func:`run_to_dict` as indented JSON."""
    return dumps(run_to_dict(run, title))


def cycle_to_json(cycle: Cycle, title: str = "") -> str:
    """:func:`cycle_to_dict` as indented JSON."""
    return dumps(cycle_to_dict(cycle, title))


def format_run(run: HybridRun, title: str = "") -> str:
    """One line per event, then the ledger."""
    m = run.model
    lines = [f"{title or m.name}: {len(run.events)} events in {run.time:g} s ({run.ended})",
             f"  {m.name}, q = ({', '.join(m.coordinates)}); {m.notes}", "",
             f"{'time':>16}  {'kind':<13} {'guard':<16} {'E_d (J)':>12} {'theorem (J)':>12}"]
    for e in run.events:
        e_d = th = guard = ""
        if e.strike is not None:
            led = e.strike.result.energy
            e_d, th = f"{led.dissipated:12.6g}", f"{led.dissipated_theorem:12.6g}"
            guard = e.strike.guard.name
        flags = f"  [{', '.join(e.flags)}]" if e.flags else ""
        lines.append(f"{e.time:16.12f}  {e.kind:<13} {guard:<16} {e_d:>12} {th:>12}{flags}")
    en = run.energy
    taken = [("impacts", en["impacts"])] + [(k, en[k]) for k in ("dampers", "sliding")
                                             if en.get(k, 0.0)]  # fmt: skip
    lines += ["", "energy (J, kinetic + potential):",
              f"  initial {en['initial']:.12g} - "
              + " - ".join(f"{k} {v:.12g}" for k, v in taken)
              + f" = {en['initial'] - sum(v for _, v in taken):.12g}",
              f"  final   {en['final']:.12g}  (residual {en['residual']:.3g})"]  # fmt: skip
    return "\n".join(lines)


def format_cycle(cycle: Cycle, title: str = "") -> str:
    """The orbit's period, state, multipliers and energy per period."""
    m = cycle.model
    head = "periodic orbit" if cycle.converged else "no periodic orbit found"
    lines = [f"{title or m.name}: {head} ({cycle.iterations} Newton steps, residual "
             f"{cycle.residual:.3g})"]
    if cycle.converged:
        n = m.n
        lines.append(f"  period {cycle.period:.12g} ({cycle.steps} strike"
                     f"{'s' if cycle.steps > 1 else ''})")  # fmt: skip
        for k, name in enumerate(m.coordinates):
            lines.append(f"  {name:<10} {cycle.state[k]: .12f}   rate {cycle.state[n + k]: .12f}")
        if cycle.multipliers is not None:
            shown = ", ".join(f"{z.real:.6f}{z.imag:+.6f}i" if abs(z.imag) > 0 else
                              f"{z.real:.6f}" for z in cycle.multipliers)  # fmt: skip
            lines.append(f"  multipliers {shown}  ({'stable' if cycle.stable else 'unstable'})")
        for name, value in _symmetry(cycle).get("shift", {}).items():
            lines.append(f"  shift      {name} by {value:.12g} per period")
        for name, value in cycle.advance.items():
            lines.append(f"  advance    {name} by {value:.12g} per period (cyclic)")
        en = cycle.energy
        lines.append(f"  per period: impacts take {en['impacts']:.12g} J, the potential "
                     f"energy drops {en['potential_drop']:.12g} J")  # fmt: skip
    for f in cycle.flags:
        lines.append(f"  warning {f}: {_FLAG_TEXT.get(f, f)}")
    return "\n".join(lines)

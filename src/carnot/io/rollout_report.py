"""``carnot audit``'s outputs: the JSON document (format 1) and the readable table of a
rollout's impact episodes (:class:`carnot.rollout.AuditReport`).

JSON: ``{"format": 1, "episodes": [{"start", "end", "pair": [geom1, geom2], "energy_lost",
"effective_restitution", "rigid": {result format 1}, ...}], "steps": {...}}``;
``energy_lost`` is the drop of MuJoCo's own total energy (``mj_energy``) over the episode (the
whole system's), ``energy_split`` where it went (:data:`carnot.rollout.audit.SPLIT_KEYS`: this
pair's contact rows, the other contacts', limits, equalities, friction loss, damping,
actuators, the rest; J removed, summing to ``energy_lost``). ``rigid_flags``,
``rigid_unique`` and ``rigid_verdict`` carry the reference's law flags, its certificate's
verdict on uniqueness and why it has no outcome to compare, where it has none.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from typing import Any

import numpy as np

from carnot.io.results import result_to_dict
from carnot.io.table import grid
from carnot.rollout.audit import SPLIT_KEYS, AuditReport, Episode

FORMAT = 1


def _num(x: float | None) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


def _vec(x: Any) -> list[float | None] | None:
    return None if x is None else [_num(float(c)) for c in np.asarray(x, dtype=float)]


def _episode(e: Episode) -> dict[str, Any]:
    return {
        "start": e.start,
        "end": e.end,
        "pair": list(e.pair),
        "energy_lost": e.energy_lost,
        "effective_restitution": _num(e.effective_restitution),
        "tangential_restitution": _num(e.tangential_restitution),
        "complete": e.complete,
        "steps": e.steps,
        "energy_before": e.energy_before,
        "energy_after": e.energy_after,
        "contact_work": e.contact_work,
        "normal_velocity_before": e.normal_velocity_before,
        "normal_velocity_after": e.normal_velocity_after,
        "tangential_velocity_before": _vec(e.tangential_velocity_before),
        "tangential_velocity_after": _vec(e.tangential_velocity_after),
        "qpos_before": _vec(e.qpos_before),
        "qvel_before": _vec(e.qvel_before),
        "qvel_after": _vec(e.qvel_after),
        "point": _vec(e.point),
        "rigid": None if e.rigid is None else result_to_dict(e.rigid),
        "rigid_restitution": _num(e.rigid_restitution),
        "rigid_tangential_restitution": _num(e.rigid_tangential_restitution),
        "rigid_error": e.rigid_error or None,
        "first_step": e.first_step,
        "tangential_note": e.tangential_note or None,
        "energy_split": None if e.split is None else {k: _num(v) for k, v in e.split.items()},
        "rigid_flags": list(e.rigid_flags),
        "rigid_unique": e.rigid_unique,
        "rigid_dissipated_range": None if e.rigid_dissipated_range is None
        else list(e.rigid_dissipated_range),
        "rigid_verdict": e.rigid_verdict or None,
    }  # fmt: skip


def report_to_dict(report: AuditReport) -> dict[str, Any]:
    """The audit as plain data (module docstring); NaN becomes None.

    >>> from carnot.rollout import audit_model
    >>> data = report_to_dict(audit_model("examples/audit/ball_drop.xml", duration=0.01))
    >>> data["format"], data["episodes"], data["steps"]["count"], data["steps"]["exact"]
    (1, [], 10, True)
    """
    s = report.steps
    settings = report.settings
    return {
        "format": FORMAT,
        "title": report.title,
        "min_speed": report.min_speed,
        "rigid_law": None if settings is None else {
            "restitution": settings.restitution, "law": settings.law,
            "tangential": settings.tangential, "friction": settings.friction,
            "multiple_impact": settings.multiple_impact, "scope": settings.scope,
            "gap": settings.gap, "equality": settings.equality, "drift": settings.drift,
            "limits": settings.limits,
        },
        "warnings": list(report.warnings),
        "episodes": [_episode(e) for e in report.episodes],
        "steps": {
            "integrator": s.integrator,
            "exact": s.exact,
            "unsupported": s.reason or None,
            "timestep": s.timestep,
            "count": s.count,
            "max_abs_residual": _num(s.max_abs_residual),
            "time": _vec(s.time),
            "energy": _vec(s.energy),
            "kinetic": _vec(s.kinetic),
            "potential": _vec(s.potential),
            "work": {k: _vec(v) for k, v in s.work.items()},
            "mass_change": _vec(s.mass_change),
            "residual": _vec(s.residual),
            "by_constraint": {k: _num(v) for k, v in s.by_constraint.items()},
            "constraint_work": {k: _vec(v) for k, v in s.constraint_work.items()},
        },
    }  # fmt: skip


def report_to_json(report: AuditReport) -> str:
    """``report_to_dict`` as JSON text (no NaN or infinity)."""
    return json.dumps(report_to_dict(report), indent=1, allow_nan=False)


def _f(x: float | None, digits: int = 4) -> str:
    return "-" if x is None or not math.isfinite(x) else f"{x + 0.0:.{digits}g}"


def _flags(e: Episode) -> str:
    """The flags column: the reference's law flags and its certificate's verdict on
    uniqueness (``not unique``: the law allows other velocities, with the range of E_d over
    them; ``unverified``: not proved either way), ``-`` where there is nothing to say."""
    if e.rigid is None:
        return "-"
    counts = Counter(c for c in e.rigid_flags if c != "multiple_solutions")  # in order
    out = [c if n == 1 else f"{c} x{n}" for c, n in counts.items()]
    span = e.rigid_dissipated_range
    if e.rigid_unique is False or "multiple_solutions" in e.rigid_flags:
        if span is None:
            out.append("not unique")
        elif f"{span[0]:.4g}" == f"{span[1]:.4g}":  # other velocities, the same loss
            out.append(f"not unique (E_d {span[0]:.4g} J in each)")
        else:
            out.append(f"not unique (E_d {span[0]:.4g} to {span[1]:.4g} J)")
    elif e.rigid_unique is None:
        out.append("unverified")
    return ", ".join(out) or "-"


def _tangential(e: Episode, value: float | None) -> str:
    """``e_t``, or why there is none (``— (no slip before)``, ``— (frictionless)``)."""
    return _f(value) if value is not None else f"— ({e.tangential_note})"


def format_report(report: AuditReport) -> str:
    """A readable table: one row per episode (MuJoCo beside the rigid reference, and the
    reference's flags), where each episode's energy went, then the step ledger's totals.

    >>> from carnot.rollout import audit_model
    >>> report = audit_model("examples/audit/ball_drop.xml", keyframe="drop", duration=0.1)
    >>> print(format_report(report).splitlines()[4])
      (none: no contact approached faster than 0.01962 m/s)
    """
    s = report.steps
    lines = [f"Energy audit: {report.title}" if report.title else "Energy audit",
             f"  integrator {s.integrator}, h = {s.timestep:g} s, {s.count} steps, "
             f"MuJoCo's energy {s.energy[0]:.6g} J -> {s.energy[-1]:.6g} J", ""]  # fmt: skip
    if report.warnings:
        lines[-1:] = [*(f"  warning: {w}" for w in report.warnings), ""]
    settings = report.settings
    law = "" if settings is None else (
        f" (rigid: {settings.law} e = {settings.restitution:g}, {settings.tangential}, "
        f"{settings.multiple_impact})"
    )  # fmt: skip
    lines.append(f"Impact episodes{law}")
    rows = []
    for e in report.episodes:
        verdict = e.rigid_verdict
        if settings is None:
            rigid = ["-", "-", "-"]
        elif verdict:  # no outcome to compare: say so (why: below), not its numbers
            rigid = ["not computed" if e.rigid is None else "no rigid answer", "", ""]
        else:
            rigid = [_f(e.rigid_dissipated), _f(e.rigid_restitution),
                     _tangential(e, e.rigid_tangential_restitution)]  # fmt: skip
        rows.append([
            "/".join(e.pair), f"{e.start:.4f}", f"{e.end:.4f}" + ("" if e.complete else "+"),
            _f(e.normal_velocity_before), _f(e.energy_lost), _f(-e.contact_work),
            _f(e.effective_restitution), _tangential(e, e.tangential_restitution), *rigid,
            _flags(e) if settings is not None else "-",
        ])  # fmt: skip
    if rows:
        lines += grid(
            ["pair", "start s", "end s", "w_n' m/s", "E lost J", "-W_c J", "e", "e_t",
             "rigid E_d J", "rigid e", "rigid e_t", "flags"], rows,
        )  # fmt: skip
    else:
        lines.append(f"  (none: no contact approached faster than {report.min_speed:g} m/s)")
    errors = [f"  {'/'.join(e.pair)} at {e.start:.4f} s: {e.rigid_verdict}"
              for e in report.episodes if e.rigid_verdict]  # fmt: skip
    if errors:
        lines += ["", "No rigid outcome to compare:", *errors]
    split = [e for e in report.episodes if e.split is not None]
    if split:
        lines += ["", "Where each episode's energy went (J removed over its steps; E lost is "
                  "the whole system's)"]  # fmt: skip
        lines += grid(
            ["pair", "start s", "E lost", "this pair", "other contacts", "limits",
             "equalities", "friction loss", "damping", "actuators", "rest"],
            [["/".join(e.pair), f"{e.start:.4f}", _f(e.energy_lost),
              *(_f(e.split[k]) for k in SPLIT_KEYS)] for e in split if e.split is not None],
        )  # fmt: skip
        lines.append("  (rest: gravity against the potential's change, Coriolis against the "
                     "change of M, applied forces, round-off)")  # fmt: skip
    lines += ["", "Step ledger (J)"]
    if not s.exact:
        lines.append(f"  exact split unsupported: {s.reason}")
        return "\n".join(lines)
    totals = [[name, _f(float(np.sum(v)), 6)] for name, v in s.work.items()]
    totals += [[f"  of which {name.replace('_', ' ')}", _f(float(np.sum(v)), 6)]
               for name, v in s.constraint_work.items() if np.any(v != 0)]  # fmt: skip
    totals += [["mass_change (integrator)", _f(float(np.sum(s.mass_change)), 6)],
               ["potential change", _f(float(s.potential[-1] - s.potential[0]), 6)],
               ["max |residual| of a step", _f(s.max_abs_residual, 3)]]  # fmt: skip
    lines += grid(["term", "total"], totals)
    if s.by_constraint:
        lines += ["", "Work of each constraint (J)"]
        lines += grid(["constraint", "work"],
                       [[k, _f(v, 6)] for k, v in s.by_constraint.items()])  # fmt: skip
    return "\n".join(lines)

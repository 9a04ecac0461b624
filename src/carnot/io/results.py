"""Result files, format 1 (DESIGN.md section 4), with the keys this version adds.

The keys of DESIGN.md keep their meaning; the extra keys are documented in the README.
Infinities (a friction coefficient required where the normal impulse is 0) become ``null``:
JSON has no infinity (nor NaN); so does any entry of a vector that is not finite.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from carnot.conventions import contact_frame
from carnot.result import ImpactResult, ItemOutcome, MomentumCheck
from carnot.solvers.options import Certificate

FORMAT = 1


def _num(x: float | None) -> float | None:
    """A JSON number: ``None`` for a missing or non-finite value; ``-0.0`` written as ``0.0``."""
    if x is None or not math.isfinite(x):
        return None
    return float(x) + 0.0


def _vec(x: Any) -> list[float | None] | None:
    """A JSON list of numbers, each entry as ``_num`` (``tolist``: the entries as floats,
    which ``float(v)`` gives, in one call)."""
    if x is None:
        return None
    values = np.asarray(x, dtype=float)
    if values.ndim != 1:  # (iterated by rows, as before: an error for a matrix)
        return [_num(float(v)) for v in values]
    return [v + 0.0 if math.isfinite(v) else None for v in values.tolist()]


def _contact(o: ItemOutcome) -> dict[str, Any]:
    return {
        "a": o.a,
        "b": o.b,
        "impulse": _vec(o.impulse),
        "moment": _vec(o.moment),
        "normal_impulse": _num(o.normal_impulse),
        "tangential_impulse": _vec(o.tangential_impulse),
        "regime": o.regime,
        "dissipated": _num(o.dissipated),
        "where": o.where,
        "point": _vec(o.point),
        "normal": _vec(o.normal),
        "dissipated_normal": _num(o.dissipated_normal),
        "dissipated_tangential": _num(o.dissipated_tangential),
        "dissipated_moment": _num(o.dissipated_moment),
        "friction_required": _num(o.friction_required),
        "centre_of_pressure": _vec(o.centre_of_pressure),
        "relative_velocity_before": _vec(o.relative_velocity_before),
        "relative_velocity_after": _vec(o.relative_velocity_after),
        "relative_angular_velocity_before": _vec(o.relative_angular_velocity_before),
        "relative_angular_velocity_after": _vec(o.relative_angular_velocity_after),
        "law": o.law,
        **({"name": o.name} if o.name else {}),
        **({"active": o.active} if o.active is not None else {}),
        **_process(o),
        **_generalized(o),
    }


def _several(result: ImpactResult) -> dict[str, Any]:
    """The keys of several contacts at once (DESIGN.md section 6), only when a multiple-impact
    law applied: its name, the complementarity residual (m/s), the stages with their ledgers
    and the other outcomes (each a whole result)."""
    if result.multiple_impact is None:
        return {}
    return {
        "multiple_impact": result.multiple_impact,
        "complementarity_residual": _num(result.complementarity_residual),
        "stages": [
            {
                "index": st.index,
                "description": st.description,
                "contacts": list(st.contacts),
                "impulses": {k: _vec(v) for k, v in st.impulses.items()},
                "dissipated_by_contact": {k: _num(v) for k, v in st.dissipated_by_contact.items()},
                "dissipated": _num(st.dissipated),
            }
            for st in result.stages
        ],
        "alternatives": [result_to_dict(other) for other in result.alternatives],
        **({"solver": _certificate(result.solver, result.solver_groups)}
           if result.solver is not None else {}),
    }


def _certificate(cert: Certificate, groups: tuple[tuple[tuple[str, ...], Certificate], ...]
                 ) -> dict[str, Any]:  # fmt: skip
    """The simultaneous law's certificate (DESIGN.md section 9): the solver that answered and
    the one asked for, Siconos' relative residual evaluated apart, the iterations, whether the
    impulses and the velocities are unique (``null``: not verified), whether it converged;
    with several independent groups, each group's under ``groups``."""

    def one(c: Certificate) -> dict[str, Any]:
        out: dict[str, Any] = {
            "name": c.solver, "requested": c.requested, "residual": _num(c.residual),
            "iterations": c.iterations, "unique": c.unique,
            "velocities_unique": c.velocities_unique, "converged": c.converged,
            "dissipated_range": None if c.dissipated_range is None
            else [_num(c.dissipated_range[0]), _num(c.dissipated_range[1])]}  # fmt: skip
        if c.dissipated_bounds is not None:  # only where the range is bracketed, not known
            out["dissipated_bounds"] = [[_num(v) for v in end] for end in c.dissipated_bounds]
        return out

    out = one(cert)
    if len(groups) > 1:
        out["groups"] = [{"contacts": list(names), **one(c)} for names, c in groups]
    return out


def _generalized(o: ItemOutcome) -> dict[str, Any]:
    """A system's item (DESIGN.md section 7): its ``name`` and ``generalized_impulse``
    ``J^T P + J_ang^T M_P``; nothing for free bodies."""
    if o.generalized_impulse is None:
        return {}
    return {"name": o.name, "generalized_impulse": _vec(o.generalized_impulse)}


def _process(o: ItemOutcome) -> dict[str, Any]:
    """The impulse-space history of a contact with Coulomb friction (``null`` otherwise):
    ``compression_impulse`` (N s), ``work`` (J) and ``history``, its phases in order with
    their normal impulse at start and end and the slip direction in world components."""
    pr = o.process
    if pr is None or o.normal is None:
        return {"compression_impulse": None, "work": None, "history": None}
    _, t1, t2 = contact_frame(o.normal)

    def world(direction: np.ndarray | None) -> list[float | None] | None:
        return None if direction is None else _vec(direction[0] * t1 + direction[1] * t2)

    return {
        "compression_impulse": _num(pr.compression_impulse),
        "work": {
            "normal_compression": _num(pr.work_normal_compression),
            "normal_restitution": _num(pr.work_normal_restitution),
            "tangential_compression": _num(pr.work_tangential_compression),
            "tangential_restitution": _num(pr.work_tangential_restitution),
            "dissipated": _num(-(pr.work_normal + pr.work_tangential)),
        },
        "history": [
            {
                "regime": ph.regime,
                "began": ph.began,
                "normal_impulse_start": _num(ph.start),
                "normal_impulse_end": _num(ph.end),
                "slip_direction_start": world(ph.direction_start),
                "slip_direction_end": world(ph.direction_end),
                "slip_turn": _num(ph.turn),
            }
            for ph in pr.phases
        ],
    }


def _constraint(o: ItemOutcome) -> dict[str, Any]:
    return {
        "impulse": _vec(o.impulse),
        "moment": _vec(o.moment),
        "where": o.where,
        "type": o.kind,
        "body": o.a,
        "other": o.b,
        "point": _vec(o.point),
        "dissipated": _num(o.dissipated),
        "relative_velocity_before": _vec(o.relative_velocity_before),
        "relative_velocity_after": _vec(o.relative_velocity_after),
        **_generalized(o),
    }


def result_to_dict(result: ImpactResult) -> dict[str, Any]:
    """Result format 1 as plain data (lists, floats, strings, None).

    >>> from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
    >>> ball = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3), velocity_com=[0, 0, -1.0])
    >>> res = solve_impact(ImpactProblem(bodies={"ball": ball, "g": FixedBody(name="g")},
    ...     contacts=[PointContact(a="ball", b="g", point=[0, 0, 0], normal=[0, 0, 1])]))
    >>> d = result_to_dict(res)
    >>> d["format"], d["bodies"]["ball"]["velocity"], d["energy"]["dissipated"]
    (1, [0.0, 0.0, 0.0], 0.5)
    """
    m = result.momentum or _NO_MOMENTUM  # a system: no bodies' momentum (dropped below)
    out = {
        "format": FORMAT,
        "title": result.title,
        "bodies": bodies_to_dict(result),
        "contacts": contacts_to_dict(result),
        "constraints": constraints_to_dict(result),
        "energy": energy_to_dict(result),
        "momentum": {
            "linear_residual": _num(m.linear_residual),
            "angular_residual": _num(m.angular_residual),
            "linear_change": _vec(m.linear_change),
            "linear_external": _vec(m.linear_external),
            "angular_change": _vec(m.angular_change),
            "angular_external": _vec(m.angular_external),
        },
        "warnings": warnings_to_dict(result),
        **_several(result),
    }  # fmt: skip
    return out if result.system is None else _with_system(out, result)


def bodies_to_dict(result: ImpactResult) -> dict[str, Any]:
    """The ``bodies`` of :func:`result_to_dict` (each body's velocities after and before)."""
    return {
        name: {
            "velocity": _vec(b.velocity_after),
            "angular_velocity": _vec(b.angular_velocity_after),
            "velocity_before": _vec(b.velocity_before),
            "angular_velocity_before": _vec(b.angular_velocity_before),
            "fixed": b.fixed,
        }
        for name, b in result.bodies.items()
    }


def contacts_to_dict(result: ImpactResult) -> list[dict[str, Any]]:
    """The ``contacts`` of :func:`result_to_dict`."""
    return [_contact(o) for o in result.contacts]


def constraints_to_dict(result: ImpactResult) -> list[dict[str, Any]]:
    """The ``constraints`` of :func:`result_to_dict`."""
    return [_constraint(o) for o in result.constraints]


def energy_to_dict(result: ImpactResult) -> dict[str, float | None]:
    """The ``energy`` of :func:`result_to_dict` (the ledger, J)."""
    e = result.energy
    return {
        "before": _num(e.before),
        "after": _num(e.after),
        "dissipated": _num(e.dissipated),
        "dissipated_theorem": _num(e.dissipated_theorem),
        "lost_velocities": _num(e.lost_velocities),
        "carnot_defect": _num(e.carnot_defect),
        "carnot_condition": _num(e.carnot_condition),
        "dissipated_normal": _num(e.dissipated_normal),
        "dissipated_tangential": _num(e.dissipated_tangential),
        "dissipated_moment": _num(e.dissipated_moment),
    }


def warnings_to_dict(result: ImpactResult) -> list[dict[str, str]]:
    """The ``warnings`` of :func:`result_to_dict`."""
    return [{"code": w.code, "where": w.where, "message": w.message} for w in result.warnings]


def _with_system(out: dict[str, Any], result: ImpactResult) -> dict[str, Any]:
    """A system's result (DESIGN.md section 7): ``system`` (coordinates, ``q''`` as
    velocity, ``q'`` as velocity_before and the generalized momentum residual) instead of
    ``bodies`` and ``momentum``."""
    s = result.system
    assert s is not None
    system = {
        "coordinates": list(s.coordinates),
        "velocity": _vec(s.velocity_after),
        "velocity_before": _vec(s.velocity_before),
        "momentum_residual": _num(s.momentum_residual),
    }
    return {"format": out["format"], "title": out["title"], "system": system,
            **{k: v for k, v in out.items() if k not in ("format", "title", "bodies",
                                                         "momentum")}}  # fmt: skip


_NO_MOMENTUM = MomentumCheck(
    linear_change=np.zeros(3), linear_external=np.zeros(3), angular_change=np.zeros(3),
    angular_external=np.zeros(3), linear_residual=0.0, angular_residual=0.0,
)  # fmt: skip


def result_to_json(result: ImpactResult) -> str:
    """``result_to_dict`` as indented JSON text (no NaN or infinity)."""
    return json.dumps(result_to_dict(result), indent=2, allow_nan=False)

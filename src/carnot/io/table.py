"""A readable report of an impact: bodies, impulses, and the energy ledger with the theorem
beside the direct difference."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from carnot.conventions import contact_frame
from carnot.result import ImpactResult, ItemOutcome


def _v(x: Any) -> str:
    if x is None:
        return "-"
    return "[" + ", ".join(f"{float(c) + 0.0:.6g}" for c in np.asarray(x, dtype=float)) + "]"


def _n(x: float | None) -> str:
    if x is None:
        return "-"
    return f"{x + 0.0:.6g}"


def grid(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """The text table's lines: ``header``, a rule, then ``rows``, each column as wide as its
    widest entry, indented two spaces.

    >>> grid(["a", "bb"], [["1", "2"]])
    ['  a  bb', '  -  --', '  1  2']
    """
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h)
              for i, h in enumerate(header)]  # fmt: skip
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    lines = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    lines += [fmt.format(*r) for r in rows]
    return ["  " + line.rstrip() for line in lines]


def _history(o: ItemOutcome) -> list[str]:
    """The phases of a contact with Coulomb friction, and its works (empty otherwise)."""
    pr = o.process
    if pr is None or o.normal is None:
        return []
    _, t1, t2 = contact_frame(o.normal)

    def world(d: np.ndarray | None) -> str:
        return "-" if d is None else _v(d[0] * t1 + d[1] * t2)

    hyp = (o.law or "newton").capitalize()
    out = ["", f"Impact history at {o.where} ({hyp}'s hypothesis, Coulomb friction; normal "
               "impulse p in N s, slip direction in world axes)"]  # fmt: skip
    out += grid(
        ["phase", "began", "p from", "p to", "slip direction from", "to", "turn (deg)"],
        [[ph.regime, ph.began, _n(ph.start), _n(ph.end), world(ph.direction_start),
          world(ph.direction_end), f"{np.degrees(ph.turn):.3g}"] for ph in pr.phases],
    )  # fmt: skip
    out += grid(
        ["work (J)", "compression", "restitution", "total"],
        [["normal force", _n(pr.work_normal_compression), _n(pr.work_normal_restitution),
          _n(pr.work_normal)],
         ["friction", _n(pr.work_tangential_compression), _n(pr.work_tangential_restitution),
          _n(pr.work_tangential)]],
    )  # fmt: skip
    out.append(
        f"  maximum compression at p = {_n(pr.compression_impulse)} N s; "
        f"E_d = -(W_n + W_t) = {_n(-(pr.work_normal + pr.work_tangential))} J"
    )
    return out


def _system(result: ImpactResult) -> list[str]:
    """A system in generalized coordinates: each coordinate's rate before and after, and each
    item's generalized impulse ``J^T P`` (columns in the coordinates' order)."""
    s = result.system
    assert s is not None
    out = ["System (generalized velocities, in each coordinate's unit per second)"]
    rates = zip(s.coordinates, s.velocity_before, s.velocity_after, strict=True)
    out += grid(["coordinate", "before", "after"],
                 [[name, _n(float(a)), _n(float(b))] for name, a, b in rates])  # fmt: skip
    out += ["", "Generalized impulses J^T P (per item)"]
    out += grid(["item", "name", "J^T P"],
                 [[o.where, o.name or "-", _v(o.generalized_impulse)]
                  for o in (*result.contacts, *result.constraints)])  # fmt: skip
    return out


def _certificate_line(result: ImpactResult) -> str:
    """One line on the simultaneous law's answer: who answered, its residual, uniqueness."""
    c = result.solver
    assert c is not None

    def said(value: bool | None) -> str:
        return "not verified" if value is None else ("yes" if value else "no")

    how = f"{c.solver}" + (f" (chosen by {c.requested})" if c.requested != c.solver else "")
    done = "" if c.converged else ", NOT converged"
    span = c.dissipated_range
    over = "" if span is None or span[0] == span[1] else (
        f"; E_d over the answers from {span[0]:.6g} to {span[1]:.6g} J")  # fmt: skip
    return (f"Solver: {how}, {c.iterations} iteration{'s' if c.iterations != 1 else ''}, "
            f"fc3d residual {c.residual:.2g}{done}; impulses unique: {said(c.unique)}, "
            f"velocities unique: {said(c.velocities_unique)}{over}")


def format_result(result: ImpactResult) -> str:
    """The report ``carnot solve FILE`` prints.

    >>> from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
    >>> ball = RigidBody(name="ball", mass=1.0, inertia_com=np.eye(3), velocity_com=[0, 0, -1.0])
    >>> res = solve_impact(ImpactProblem(bodies={"ball": ball, "g": FixedBody(name="g")},
    ...     contacts=[PointContact(a="ball", b="g", point=[0, 0, 0], normal=[0, 0, 1])]))
    >>> "E_d (theorem)" in format_result(res)
    True
    """
    e = result.energy
    out: list[str] = []
    if result.title:
        out += [result.title, "=" * len(result.title), ""]
    if result.system is not None:
        out += _system(result)
    else:
        out.append("Bodies (velocity of the centre of mass, m/s; angular velocity, rad/s)")
        out += grid(
            ["body", "v before", "v after", "omega before", "omega after"],
            [[name, _v(b.velocity_before), _v(b.velocity_after), _v(b.angular_velocity_before),
              _v(b.angular_velocity_after)]
             for name, b in result.bodies.items() if not b.fixed],
        )  # fmt: skip
    out += ["", "Contacts and constraints (impulse on a, N s; moment, N m s; E_d share, J)"]
    rows = []
    for o in (*result.contacts, *result.constraints):
        pair = f"{o.a}/{o.b}" if o.b is not None else f"{o.a}/world"
        rows.append([
            o.where, o.regime, pair, _v(o.impulse), _v(o.moment), _n(o.normal_impulse),
            _n(o.friction_required) if o.friction_required is not None else "-",
            _n(o.dissipated),
        ])  # fmt: skip
    out += grid(["item", "regime", "a/b", "impulse P", "moment M_P", "P.n", "mu needed",
                  "E_d share"], rows)  # fmt: skip
    for o in result.contacts:
        out += _history(o)
    out += ["", "Energy ledger (J)"]
    difference = e.dissipated - e.dissipated_theorem
    out += grid(
        ["quantity", "value"],
        [
            ["E' (before)", _n(e.before)],
            ["E'' (after)", _n(e.after)],
            ["E_d = E' - E'' (direct)", _n(e.dissipated)],
            ["E_d (theorem)", _n(e.dissipated_theorem)],
            ["  direct - theorem", f"{difference + 0.0:.3g}"],
            ["  normal part", _n(e.dissipated_normal)],
            ["  tangential part", _n(e.dissipated_tangential)],
            ["  moment part", _n(e.dissipated_moment)],
            ["E_p (lost velocities)", _n(e.lost_velocities)],
            ["E_d - E_p (direct)", _n(e.carnot_defect)],
            ["-sum P.w'' + M_P.Omega''", _n(e.carnot_condition)],
        ],
    )
    if result.solver is not None:
        out += ["", _certificate_line(result)]
    m = result.momentum
    if m is not None:
        out += [
            "",
            f"Momentum balance: linear residual {m.linear_residual:.2g}, "
            f"angular residual {m.angular_residual:.2g} (relative)",
        ]
    elif result.system is not None:
        out += ["", "Generalized momentum balance M (q'' - q') = sum J^T P: residual "
                f"{result.system.momentum_residual:.2g} (relative)"]  # fmt: skip
    if result.warnings:
        out += ["", "Warnings"]
        out += [f"  [{w.code}] {w.where}: {w.message}" for w in result.warnings]
    else:
        out += ["", "No warnings."]
    return "\n".join(out)

"""The symbolic audit of the paper's printed formulas (``carnot paper --symbolic``).

Each example of section 3 is built again with the symbolic front end, with the paper's own
symbols for its parameters, and solved in closed form by :func:`derive_impact`. The quantities
the printed formulas claim (impulses, velocities after, energies) are read off the derived
result in the paper's axes and signs (those of :mod:`carnot.paper.examples`), substituted into
each transcription of :mod:`carnot.paper.formulas`, and the difference of the two sides is
reduced to 0, or not.

Section 3.3's three-dimensional body is taken with its principal axes along the world axes.
That loses nothing: every formula there is an equation between vectors and tensors, unchanged
in form by a rotation of the axes, and the position ``OC``, the velocities and the principal
moments stay general symbols.
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import sympy as sp

from carnot.paper import formulas as f
from carnot.paper.audit import Verdict, dimension_report
from carnot.paper.formulas import FORMULAS, PrintedFormula
from carnot.symbolic.model import (
    SymConstraint,
    SymContact,
    SymFixedBody,
    SymProblem,
    SymRigidBody,
)
from carnot.symbolic.solve import derive_impact

Quantities = dict[sp.Symbol, sp.Expr]


def _vec_subs(symbols: sp.Matrix, values: sp.Matrix) -> Quantities:
    return {s: x for s, x in zip(symbols, values, strict=True)}


def cylinder_edge() -> Quantities:
    """Section 3.1, derived: the cylinder of :func:`carnot.paper.examples.cylinder_edge_problem`."""
    m, r, v, a, w, e = f.m, f.r, f.v, f.alpha, f.omega1, f.e
    j_axis = m * r**2 / 2
    cylinder = SymRigidBody(
        name="cylinder", mass=m, inertia_com=sp.diag(m * r**2 / 3, m * r**2 / 3, j_axis),
        position_com=[0, r, 0], velocity_com=[v * sp.sin(a), -v * sp.cos(a), 0],
        angular_velocity=[0, 0, -w],
    )  # fmt: skip
    res = derive_impact(
        SymProblem(
            bodies={"cylinder": cylinder, "edge": SymFixedBody(name="edge")},
            contacts=[SymContact(a="cylinder", b="edge", point=[0, 0, 0], normal=[0, 1, 0],
                                 restitution=e, tangential="stick")],
        )
    )  # fmt: skip
    c = res.contacts[0]
    vel, ang = res.bodies["cylinder"]
    return {
        f.P_n: c.impulse[1], f.P_t: c.impulse[0],
        f.v2_On: vel[1], f.v2_Ot: vel[0], f.omega2: -ang[2],
        f.v1_An: c.relative_velocity_before[1], f.v1_At: c.relative_velocity_before[0],
        f.v2_An: c.relative_velocity_after[1], f.v2_At: c.relative_velocity_after[0],
        f.E_d: res.dissipated, f.E_d_theorem: res.dissipated_theorem,
    }  # fmt: skip


def _pendulum(given: tuple[sp.Expr, sp.Expr] | None) -> Any:
    m, l_, h, w, e = f.m, f.l_, f.h, f.omega1, f.e
    centre = sp.Matrix([0, -(l_ + h / 2), 0])
    j_rod = m * h**2 / 12
    pendulum = SymRigidBody(
        name="pendulum", mass=m,
        inertia_com=sp.diag(j_rod, sp.Symbol("J_axial", positive=True), j_rod),
        position_com=centre, velocity_com=sp.Matrix([0, 0, w]).cross(centre),
        angular_velocity=[0, 0, w],
    )  # fmt: skip
    if given is None:
        contact = SymContact(
            a="pendulum",
            b="plane",
            point=centre,
            normal=[-1, 0, 0],
            restitution=e,
            patch=[[0, -l_, 0], [0, -(l_ + h), 0]],
        )
    else:
        contact = SymContact(
            a="pendulum",
            b="plane",
            point=centre,
            normal=[-1, 0, 0],
            impulse=[-given[0], 0, 0],
            moment=[0, 0, -given[1]],
        )
    return derive_impact(
        SymProblem(
            bodies={"pendulum": pendulum, "plane": SymFixedBody(name="plane")},
            contacts=[contact],
            constraints=[SymConstraint(kind="pin", body="pendulum", point=[0, 0, 0])],
        )
    )


def pendulum_plane() -> Quantities:
    """Section 3.2, derived: by its law, and with the printed impulses given."""
    m, l_, h, w, e = f.m, f.l_, f.h, f.omega1, f.e
    res = _pendulum(None)
    vel, ang = res.bodies["pendulum"]
    v_before = sp.Matrix([0, 0, w]).cross(sp.Matrix([0, -(l_ + h / 2), 0]))
    p_c = sp.Rational(1, 2) * m * w * (1 + e) * (2 * l_ + h)
    m_pc = sp.Rational(1, 12) * m * w * (1 + e) * h**2
    given = _pendulum((p_c, m_pc))
    return {
        f.omega2: ang[2],
        f.v1_C: res.contacts[0].relative_velocity_before[0],
        f.v2_C: res.contacts[0].relative_velocity_after[0],
        f.P_C_needed: -m * (vel[0] - v_before[0]),
        f.M_PC_needed: -(m * h**2 / 12) * (ang[2] - w),
        **_vec_subs(f.P_O_given, given.constraints[0].impulse),
        f.omega2_given: given.bodies["pendulum"][1][2],
        f.E_d: res.dissipated,
        f.E_d_theorem: res.dissipated_theorem,
    }


def fasten_3d() -> Quantities:
    """Section 3.3 in 3D, derived; ``[J]_O`` written out from the principal moments."""
    m, oc, v_o, w1 = f.m, f.OC, f.v_O, f.omega1_vec
    j_c = sp.diag(*sp.symbols("J_C_1 J_C_2 J_C_3", positive=True))
    body = SymRigidBody(
        name="body",
        mass=m,
        inertia_com=j_c,
        position_com=oc,
        velocity_com=v_o + w1.cross(oc),
        angular_velocity=w1,
    )
    res = derive_impact(
        SymProblem(bodies={"body": body},
                   constraints=[SymConstraint(kind="fasten", body="body", point=[0, 0, 0])]),
        simplify=None,  # left unsimplified: is_zero reduces the differences directly
    )  # fmt: skip
    j_o = j_c + m * (oc.dot(oc) * sp.eye(3) - oc * oc.T)
    return {
        **_vec_subs(f.omega2_vec, res.bodies["body"][1]),
        **_vec_subs(f.P_vec, res.constraints[0].impulse),
        f.E_d: res.dissipated,
        f.E_d_theorem: res.dissipated_theorem,
        **{f.J_O_tensor[i, j]: j_o[i, j] for i in range(3) for j in range(i, 3)},
    }


def fasten_plate() -> Quantities:
    """Section 3.3 in the plane, derived (``v'_O`` along x, ``OC`` at ``alpha`` from it)."""
    m, l_, v, a, w = f.m, f.l_, f.v, f.alpha, f.omega1
    oc = sp.Matrix([l_ * sp.cos(a), l_ * sp.sin(a), 0])
    v_o = sp.Matrix([v, 0, 0])
    j_c = sp.diag(*sp.symbols("J_x J_y", positive=True), f.J_O - m * l_**2)
    body = SymRigidBody(
        name="plate",
        mass=m,
        inertia_com=j_c,
        position_com=oc,
        velocity_com=v_o + sp.Matrix([0, 0, w]).cross(oc),
        angular_velocity=[0, 0, w],
    )
    res = derive_impact(
        SymProblem(bodies={"plate": body},
                   constraints=[SymConstraint(kind="fasten", body="plate", point=[0, 0, 0])])
    )  # fmt: skip
    return {f.omega2: res.bodies["plate"][1][2], f.E_d: res.dissipated,
            f.E_d_theorem: res.dissipated_theorem}  # fmt: skip


DERIVATIONS: dict[str, Callable[[], Quantities]] = {
    "3.1": cylinder_edge,
    "3.2": pendulum_plane,
    "3.3-3d": fasten_3d,
    "3.3-planar": fasten_plate,
}


#: Expressions larger than this (SymPy operation count) are tested for zero exactly at random
#: rational points rather than reduced, which would take minutes.
LARGE = 1500
RANDOM_POINTS = 8


def _ops(expr: sp.Basic) -> int:
    if isinstance(expr, sp.MatrixBase):
        return sum(sp.count_ops(x) for x in expr)
    return int(sp.count_ops(expr))


def is_zero(expr: sp.Basic) -> tuple[bool, str]:
    """Whether ``expr`` (every entry of a matrix) is identically 0, and how that was decided.

    A rational function is first evaluated exactly at two random rational points: a non-zero
    value there proves it is not identically 0, at the cost of a substitution (reducing a sum
    of many fractions to one would take minutes). Small expressions are then reduced: one
    fraction whose expanded numerator vanishes, with ``sin^2 + cos^2 = 1`` applied where
    trigonometric terms remain. Large rational ones are evaluated exactly at more random
    rational points: a rational function that is not identically 0 vanishes at a random point
    with probability at most its degree over the size of the sample set (Schwartz-Zippel),
    here below 1e-4 at each of 8 points.

    >>> x = sp.Symbol("x")
    >>> is_zero((x**2 - 1) / (x - 1) - x - 1)
    (True, 'reduced to 0')
    >>> is_zero(1 / (x + 1) + 1 / (x + 2) - 2 / (x + 3))
    (False, 'non-zero at a rational point')
    """
    entries = list(expr) if isinstance(expr, sp.MatrixBase) else [sp.sympify(expr)]
    symbols = sorted(set().union(*(e.free_symbols for e in entries)), key=str)
    rng = random.Random(20261122)
    rational = all(e.is_rational_function(*symbols) for e in entries)
    if rational and _nonzero_at_random_points(entries, symbols, rng, 2):
        return False, "non-zero at a rational point"
    if _ops(expr) <= LARGE or not rational:
        for entry in entries:
            num, _ = sp.fraction(sp.together(entry))
            num = sp.expand(num)
            if num == 0:
                continue
            if num.has(sp.sin, sp.cos) and (
                sp.expand(sp.trigsimp(sp.expand_trig(num))) == 0 or sp.simplify(num) == 0
            ):
                continue
            return False, "reduced; a non-zero remainder"
        return True, "reduced to 0"
    if _nonzero_at_random_points(entries, symbols, rng, RANDOM_POINTS):
        return False, "non-zero at a rational point"
    return True, f"exactly 0 at {RANDOM_POINTS} random rational points"


def _nonzero_at_random_points(
    entries: list[sp.Basic], symbols: list[sp.Symbol], rng: random.Random, count: int
) -> bool:
    """Whether some entry is exactly non-zero at one of ``count`` random positive rational
    points (a point where a denominator vanishes proves nothing and is skipped)."""
    for _ in range(count):
        point = {s: sp.Rational(rng.randint(1, 10**6), rng.randint(1, 10**6)) for s in symbols}
        for e in entries:
            value = e.xreplace(point)
            if value.is_finite and value != 0:
                return True
    return False


def _compact(expr: sp.Basic) -> sp.Basic:
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(_compact)
    expr = sp.sympify(expr)
    out = sp.factor(sp.cancel(expr))
    if out.has(sp.sin, sp.cos):
        out = sp.trigsimp(out)
    return out


def _at(expr: Any, point: dict[sp.Symbol, sp.Rational]) -> Any:
    if isinstance(expr, sp.MatrixBase):
        return [float(sp.N(y.xreplace(point))) for y in expr]
    return float(sp.N(sp.sympify(expr).xreplace(point)))


def _counterexample(difference: sp.Basic, printed: sp.Basic, derived: sp.Basic) -> dict[str, Any]:
    """The two sides at a rational point where they differ."""
    symbols = sorted(
        (sp.sympify(printed) if not isinstance(printed, sp.MatrixBase) else printed).free_symbols
        | (derived.free_symbols if hasattr(derived, "free_symbols") else set()),
        key=str,
    )
    rng = random.Random(3)
    for _ in range(20):
        point = {s: sp.Rational(rng.randint(1, 9), rng.randint(1, 9)) for s in symbols}
        diff = difference.xreplace(point)
        values = list(diff) if isinstance(diff, sp.MatrixBase) else [diff]
        if any(abs(float(sp.N(x))) > 1e-12 for x in values):
            return {
                "parameters": {str(s): str(v) for s, v in point.items()},
                "printed": _at(printed, point),
                "derived": _at(derived, point),
            }
    return {}


@dataclass(frozen=True, kw_only=True)
class SymbolicCheck:
    """A formula's symbolic verdict and the time it took."""

    verdict: Verdict
    seconds: float


def _describe(expr: sp.Basic, equal_to: str | None) -> str:
    if _ops(expr) <= 300:
        return str(_compact(expr))
    size = f"a rational function of {_ops(expr)} operations"
    return f"{size}, equal to {equal_to}" if equal_to else size


def check_symbolic(formula: PrintedFormula, quantities: Quantities) -> Verdict:
    """Compare one printed formula with the derived closed form."""
    printed = formula.printed.subs(quantities)
    reference = formula.reference.subs(quantities)
    agrees, method = is_zero(printed - reference)
    if agrees and formula.theorem is not None:
        agrees, method = is_zero(printed - formula.theorem.subs(quantities))
    consistent, dims = dimension_report(formula)
    corrected = None
    counterexample = None
    extra: dict[str, Any] = {"method": method}
    equal_to = f"the printed form {formula.text}" if agrees else None
    if not agrees:
        counterexample = _counterexample(printed - reference, printed, reference)
        if formula.corrected is not None:
            corrected_ok, _ = is_zero(formula.corrected.subs(quantities) - reference)
            corrected = {
                "formula": formula.corrected_text,
                "verdict": "agrees" if corrected_ok else "disagrees",
            }
            if corrected_ok:
                equal_to = f"the corrected form {formula.corrected_text}"
                # The derived form equals the correction, so the printed form differs from it
                # by printed - corrected: compact, in the paper's own symbols.
                short = (formula.printed - formula.corrected).xreplace(f.ABBREVIATIONS)
                text = str(_compact(short))
                if any(k in text for k in ("k_x", "k_y", "k_z")):
                    text += f", where {f.ABBREVIATION_TEXT}"
                extra["difference"] = text
        if "difference" not in extra:
            extra["difference"] = _describe(printed - reference, None)
    return Verdict(
        id=formula.id,
        where=formula.where,
        printed=formula.text,
        verdict="agrees" if agrees else "disagrees",
        max_rel_diff=0.0 if agrees else float("nan"),
        max_rel_diff_solver=0.0 if agrees else float("nan"),
        max_rel_diff_theorem=None,
        cases=0,
        dimensions=dims,
        dimensions_consistent=consistent,
        counterexample=counterexample,
        corrected=corrected,
        note=formula.note,
        derived=_describe(reference, equal_to),
        extra=extra,
    )


def run_symbolic_audit(
    formulas: tuple[PrintedFormula, ...] = FORMULAS,
) -> tuple[list[Verdict], dict[str, float]]:
    """Derive every example and check every printed formula; also the seconds each took."""
    timings: dict[str, float] = {}
    derived: dict[str, Quantities] = {}
    for example, derive in DERIVATIONS.items():
        if any(fm.example == example for fm in formulas):
            start = time.perf_counter()
            derived[example] = derive()
            timings[f"derive {example}"] = time.perf_counter() - start
    verdicts = []
    for formula in formulas:
        start = time.perf_counter()
        verdicts.append(check_symbolic(formula, derived[formula.example]))
        timings[formula.id] = time.perf_counter() - start
    return verdicts, timings

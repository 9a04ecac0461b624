"""The numeric audit of the paper's printed formulas (``carnot paper``).

Every example of :mod:`carnot.paper.examples` is solved over its grid; every transcription of
:mod:`carnot.paper.formulas` is evaluated with each case's parameters and the quantities the
solver found, and compared with the solver's value of what it claims (for energies also with
the theorem's sum). A formula agrees when the largest relative difference over the grid is at
most :data:`AGREEMENT_TOLERANCE`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
import sympy as sp

from carnot.paper.examples import EXAMPLES, Measured
from carnot.paper.formulas import DIMENSIONS, FORMULAS, PrintedFormula
from carnot.symbolic.dimensions import check_equation

#: A printed formula "agrees" when it matches the solver to this relative difference.
AGREEMENT_TOLERANCE = 1e-9


@dataclass(frozen=True, kw_only=True)
class Verdict:
    """The outcome of checking one printed formula over its grid of cases."""

    id: str
    where: str
    printed: str
    verdict: str  # "agrees" or "disagrees"
    max_rel_diff: float
    max_rel_diff_solver: float
    max_rel_diff_theorem: float | None
    cases: int
    dimensions: str = ""
    dimensions_consistent: bool = True
    counterexample: dict[str, Any] | None = None
    corrected: dict[str, Any] | None = None
    note: str = ""
    derived: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)


@lru_cache(maxsize=512)  # (bounded: the audit's expressions are few, a caller's may not be)
def _compiled(expr: sp.Basic) -> tuple[tuple[sp.Symbol, ...], Callable[..., Any]]:
    symbols = tuple(sorted(expr.free_symbols, key=str))
    return symbols, sp.lambdify(symbols, expr, modules="numpy", dummify=True)


def evaluate(expr: sp.Basic, values: Measured) -> np.ndarray:
    """``expr`` at the given symbol values, as a flat float array."""
    symbols, fn = _compiled(sp.sympify(expr))
    out = fn(*(values[s] for s in symbols))
    return np.ravel(np.asarray(out, dtype=float))


def _rel_diff(value: np.ndarray, reference: np.ndarray, scale: float) -> float:
    diff = float(np.linalg.norm(value - reference))
    return diff / max(float(np.linalg.norm(reference)), abs(scale), 1e-300)


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        flat = [float(x) for x in value.ravel()]
        return flat[0] if len(flat) == 1 else flat
    if isinstance(value, (list, tuple)):
        return [_plain(x) for x in value]
    if isinstance(value, (float, np.floating)):
        return float(value)
    return value


def dimension_report(formula: PrintedFormula) -> tuple[bool, str]:
    """Whether the printed side has the dimensions of the quantity it claims."""
    return check_equation(formula.printed, formula.reference, DIMENSIONS)


def check_formula(
    formula: PrintedFormula, cases: Sequence[tuple[dict[str, Any], Measured]]
) -> Verdict:
    """Evaluate one printed formula over the solved cases of its example."""
    worst_solver, worst_theorem, worst_corrected = 0.0, 0.0, 0.0
    worst_case: tuple[dict[str, Any], np.ndarray, np.ndarray] | None = None
    for params, q in cases:
        scale = float(evaluate(formula.scale, q)[0]) if formula.scale is not None else 0.0
        printed = evaluate(formula.printed, q)
        reference = evaluate(formula.reference, q)
        d = _rel_diff(printed, reference, scale)
        if worst_case is None or d > worst_solver:
            worst_solver = max(worst_solver, d)
            worst_case = (params, printed, reference)
        if formula.theorem is not None:
            theorem = evaluate(formula.theorem, q)
            worst_theorem = max(worst_theorem, _rel_diff(printed, theorem, scale))
        if formula.corrected is not None:
            corrected = evaluate(formula.corrected, q)
            worst_corrected = max(worst_corrected, _rel_diff(corrected, reference, scale))
    worst = max(worst_solver, worst_theorem)
    agrees = worst <= AGREEMENT_TOLERANCE
    counterexample = None
    if not agrees and worst_case is not None:
        params, printed, reference = worst_case
        counterexample = {
            "parameters": {k: _plain(np.asarray(x)) for k, x in params.items()},
            "printed": _plain(printed),
            "solver": _plain(reference),
        }
    corrected_report = None
    if formula.corrected_text is not None:
        corrected_report = {
            "formula": formula.corrected_text,
            "verdict": "agrees" if worst_corrected <= AGREEMENT_TOLERANCE else "disagrees",
            "max_rel_diff": worst_corrected,
        }
    consistent, dims = dimension_report(formula)
    return Verdict(
        id=formula.id,
        where=formula.where,
        printed=formula.text,
        verdict="agrees" if agrees else "disagrees",
        max_rel_diff=worst,
        max_rel_diff_solver=worst_solver,
        max_rel_diff_theorem=worst_theorem if formula.theorem is not None else None,
        cases=len(cases),
        dimensions=dims,
        dimensions_consistent=consistent,
        counterexample=counterexample,
        corrected=corrected_report,
        note=formula.note,
    )


def solve_cases(example: str) -> list[tuple[dict[str, Any], Measured]]:
    """Every case of one example, solved and measured."""
    ex = EXAMPLES[example]
    return [(p, ex.measure(p)[0]) for p in ex.cases()]


def run_audit(formulas: Sequence[PrintedFormula] = FORMULAS) -> list[Verdict]:
    """Solve every example over its grid and check every printed formula.

    >>> verdicts = run_audit()
    >>> sorted(v.id for v in verdicts if v.verdict == "disagrees")
    ['3.1/eq-angular', '3.3/E_d', '3.3/P']
    """
    solved = {ex: solve_cases(ex) for ex in EXAMPLES if any(f.example == ex for f in formulas)}
    return [check_formula(f, solved[f.example]) for f in formulas]


def json_ready(value: Any) -> Any:
    """``value`` with every number that is not finite (NaN, an infinity) as ``None``, JSON's
    ``null``, and ``-0.0`` as ``0.0``: the rule of the result files (:mod:`carnot.io.results`),
    applied inside dicts, lists and tuples. JSON has no NaN nor infinity.

    >>> json_ready({"a": float("nan"), "b": [1.5, float("inf"), -0.0], "c": 2, "d": None})
    {'a': None, 'b': [1.5, None, 0.0], 'c': 2, 'd': None}
    """
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) + 0.0 if math.isfinite(value) else None
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def verdict_to_dict(verdict: Verdict) -> dict[str, Any]:
    """A verdict as plain JSON-ready data (``carnot paper --json``); numbers that are not
    finite (the grid's ``max_rel_diff`` of a symbolic disagreement, which has no grid) are
    ``None``, see :func:`json_ready`."""
    out: dict[str, Any] = {
        "id": verdict.id,
        "where": verdict.where,
        "printed": verdict.printed,
        "verdict": verdict.verdict,
        "max_rel_diff": verdict.max_rel_diff,
        "max_rel_diff_solver": verdict.max_rel_diff_solver,
        "max_rel_diff_theorem": verdict.max_rel_diff_theorem,
        "cases": verdict.cases,
        "dimensions": verdict.dimensions,
        "dimensions_consistent": verdict.dimensions_consistent,
        "counterexample": verdict.counterexample,
        "corrected": verdict.corrected,
        "note": verdict.note,
    }
    if verdict.derived is not None:
        out["derived"] = verdict.derived
    out.update(verdict.extra)
    return dict(json_ready(out))


def theorem_checks() -> list[dict[str, Any]]:
    """For every solved case of every example: the theorem against the direct difference.

    One row per example: the number of impacts and the largest
    ``|E_d(direct) - E_d(theorem)| / E'``.
    """
    from carnot.solve import solve_impact

    rows = []
    for ex in EXAMPLES.values():
        worst = 0.0
        count = 0
        for p in ex.cases():
            _, problem = ex.measure(p)
            e = solve_impact(problem).energy
            worst = max(worst, abs(e.dissipated - e.dissipated_theorem) / max(e.before, 1e-300))
            count += 1
        rows.append({"example": ex.id, "impacts": count, "max_rel_diff": worst})
    return rows

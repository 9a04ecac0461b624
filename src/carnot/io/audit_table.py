"""The paper audit as a plain-text table (``carnot paper``), or as JSON (``--json``)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from carnot.paper import Verdict, verdict_to_dict


def audit_to_json(verdicts: Sequence[Verdict]) -> str:
    """``carnot paper [--symbolic] --json``: one object per formula (:func:`verdict_to_dict`).

    Numbers that are not finite are written as ``null``, as in the result files; JSON has no
    NaN, and ``allow_nan=False`` makes a NaN that got through an error rather than bad JSON.

    >>> from carnot.paper import Verdict
    >>> print(audit_to_json([Verdict(id="3.9/x", where="s", printed="x = 1",
    ...     verdict="disagrees", max_rel_diff=float("nan"), max_rel_diff_solver=float("inf"),
    ...     max_rel_diff_theorem=None, cases=0)])) # doctest: +ELLIPSIS
    [
      {
        "id": "3.9/x",
        ...
        "max_rel_diff": null,
        "max_rel_diff_solver": null,
        "max_rel_diff_theorem": null,
        ...
    """
    return json.dumps([verdict_to_dict(v) for v in verdicts], indent=2, allow_nan=False)


def format_audit(
    verdicts: Sequence[Verdict],
    theorem_rows: Sequence[dict[str, Any]] = (),
    *,
    symbolic: bool = False,
) -> str:
    """One line per printed formula (id, verdict, largest relative difference, the formula as
    printed), then the notes on disagreements and the theorem-versus-direct check per example.

    >>> from carnot.paper import Verdict
    >>> print(format_audit([Verdict(id="3.9/x", where="s", printed="x = 1", verdict="agrees",
    ...     max_rel_diff=0.0, max_rel_diff_solver=0.0, max_rel_diff_theorem=None, cases=3,
    ...     dimensions="both sides 1")]))
    ... # doctest: +NORMALIZE_WHITESPACE
    The paper's printed formulas against carnot's solver (and the theorem, for energies)
    id      verdict   max rel diff  cases  units  printed formula
    3.9/x   agrees       0.0e+00       3  ok     x = 1
    <BLANKLINE>
    1 formulas: 1 agree, 0 disagree; 0 with inconsistent units.
    """
    width = max([len(v.id) for v in verdicts] + [2])
    if symbolic:
        return _format_symbolic(verdicts, width)
    lines = [
        "The paper's printed formulas against carnot's solver (and the theorem, for energies)",
        f"{'id':<{width}}  {'verdict':<9} {'max rel diff':>12} {'cases':>6}  units  "
        "printed formula",
    ]
    for v in verdicts:
        units = "ok" if v.dimensions_consistent else "WRONG"
        lines.append(
            f"{v.id:<{width}}  {v.verdict:<9} {v.max_rel_diff:>12.1e} {v.cases:>6}  "
            f"{units:<5}  {v.printed}"
        )
    disagreeing = [v for v in verdicts if v.verdict != "agrees"]
    lines.append("")
    wrong_units = sum(not v.dimensions_consistent for v in verdicts)
    lines.append(
        f"{len(verdicts)} formulas: {len(verdicts) - len(disagreeing)} agree, "
        f"{len(disagreeing)} disagree; {wrong_units} with inconsistent units."
    )
    for v in disagreeing:
        lines.append("")
        lines.append(f"{v.id} ({v.where}) disagrees: {v.printed}")
        if v.note:
            lines.append(f"  note: {v.note}")
        if not v.dimensions_consistent:
            lines.append(f"  units: {v.dimensions}")
        if v.derived is not None:
            lines.append(f"  derived: {v.derived}")
        if v.counterexample is not None:
            c = v.counterexample
            params = ", ".join(f"{k}={_short(x)}" for k, x in c["parameters"].items())
            lines.append(f"  counterexample: {params}")
            lines.append(
                f"    printed gives {_short(c['printed'])}; solver gives {_short(c['solver'])}"
            )
        if v.corrected is not None:
            lines.append(
                f"  corrected form {v.corrected['formula']}: {v.corrected['verdict']} "
                f"(max rel diff {v.corrected['max_rel_diff']:.1e})"
            )
    if theorem_rows:
        lines.append("")
        lines.append("The theorem against the direct difference E' - E'', every impact above:")
        for row in theorem_rows:
            lines.append(
                f"  {row['example']:<11} {row['impacts']:>4} impacts, "
                f"max |E_d - E_d(theorem)| / E' = {row['max_rel_diff']:.1e}"
            )
    return "\n".join(lines)


def _short(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(_short(v) for v in value) + "]"
    return str(value)


def _format_symbolic(verdicts: Sequence[Verdict], width: int) -> str:
    lines = [
        "The paper's printed formulas against closed forms derived with SymPy",
        f"{'id':<{width}}  {'verdict':<9}  units  derived",
    ]
    for v in verdicts:
        units = "ok" if v.dimensions_consistent else "WRONG"
        derived = v.derived or ""
        if len(derived) > 70:
            derived = derived[:67] + "..."
        lines.append(f"{v.id:<{width}}  {v.verdict:<9}  {units:<5}  {derived}")
    disagreeing = [v for v in verdicts if v.verdict != "agrees"]
    lines += [
        "",
        f"{len(verdicts)} formulas: {len(verdicts) - len(disagreeing)} agree, "
        f"{len(disagreeing)} disagree.",
    ]
    for v in disagreeing:
        lines += ["", f"{v.id} ({v.where}) disagrees: {v.printed}"]
        if v.note:
            lines.append(f"  note: {v.note}")
        lines.append(f"  derived: {v.derived}")
        if "difference" in v.extra:
            lines.append(f"  printed - derived: {v.extra['difference']}")
        if not v.dimensions_consistent:
            lines.append(f"  units: {v.dimensions}")
        if v.counterexample:
            c = v.counterexample
            params = ", ".join(f"{k}={x}" for k, x in c["parameters"].items())
            lines.append(f"  counterexample: {params}")
            lines.append(
                f"    printed gives {_short(c['printed'])}; derived gives {_short(c['derived'])}"
            )
        if v.corrected is not None:
            lines.append(f"  corrected form {v.corrected['formula']}: {v.corrected['verdict']}")
    return "\n".join(lines)

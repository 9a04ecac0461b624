"""``carnot derive``: the closed forms of a scenario, with chosen values as symbols, printed
as text, LaTeX, or the source of a NumPy function."""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp
from sympy.printing.numpy import NumPyPrinter

from carnot.problem import ImpactProblem
from carnot.symbolic.convert import parse_symbols, to_symbolic
from carnot.symbolic.solve import SymbolicResult, derive_impact


def derive_problem(
    problem: ImpactProblem,
    specs: Sequence[str] = (),
    shaped: set[str] | frozenset[str] = frozenset(),
) -> tuple[list[sp.Symbol], SymbolicResult]:
    """The symbols chosen by ``specs`` and the closed-form result (``shaped``: the bodies
    whose inertia came from a shape, see :func:`~carnot.symbolic.convert.to_symbolic`).

    >>> from carnot.io.scenario import load_scenario
    >>> symbols, res = derive_problem(load_scenario("examples/ball_on_floor.toml"), ["e"])
    >>> res.bodies["ball"][0].T, res.dissipated
    (Matrix([[1, 0, 3*e]]), -9*(e - 1)*(e + 1)/4)
    """
    chosen = parse_symbols(problem, specs)
    return list(chosen.values()), derive_impact(to_symbolic(problem, chosen, shaped))


def _nonzero(result: SymbolicResult) -> dict[str, sp.Expr]:
    return {k: v for k, v in result.expressions().items() if v != 0 or k.startswith("energy.")}


def as_text(symbols: Sequence[sp.Symbol], result: SymbolicResult, title: str = "") -> str:
    """One line per non-zero result, ``key = expression``."""
    head = [title] if title else []
    head.append("symbols: " + (", ".join(map(str, symbols)) or "(none: exact numbers)"))
    if result.redundant:
        head.append("note: redundant constraints; impulses are the minimum-norm split")
    return "\n".join(head + [f"{k} = {v}" for k, v in _nonzero(result).items()])


def as_latex(symbols: Sequence[sp.Symbol], result: SymbolicResult, title: str = "") -> str:
    """A LaTeX ``align*`` environment, one line per non-zero result."""
    lines = [f"% {title}" if title else "% carnot derive",
             "% symbols: " + ", ".join(sp.latex(s) for s in symbols), r"\begin{align*}"]
    items = list(_nonzero(result).items())
    for i, (k, v) in enumerate(items):
        end = r" \\" if i < len(items) - 1 else ""
        lines.append(rf"\text{{{k}}} &= {sp.latex(v)}{end}")
    lines.append(r"\end{align*}")
    return "\n".join(lines)


def as_python(symbols: Sequence[sp.Symbol], result: SymbolicResult, title: str = "") -> str:
    """The source of ``impact(*symbols)``, a NumPy function returning every non-zero result
    by key (it broadcasts over arrays of the symbols' values)."""
    printer = NumPyPrinter({"fully_qualified_modules": True})
    names = {s: _identifier(str(s)) for s in symbols}
    lines = [
        "import numpy",
        "",
        "",
        f"def impact({', '.join(names.values())}):",
        f'    """Closed forms derived by carnot{": " + title if title else ""}."""',
        "    return {",
    ]
    plain = {s: sp.Symbol(n) for s, n in names.items()}
    for key, expr in _nonzero(result).items():
        code = printer.doprint(sp.sympify(expr).xreplace(plain))
        lines.append(f"        {key!r}: {code},")
    lines.append("    }")
    return "\n".join(lines) + "\n"


def _identifier(name: str) -> str:
    out = "".join(c if c.isalnum() or c == "_" else "_" for c in name)
    return out if out and not out[0].isdigit() else f"s_{out}"

"""``carnot derive``: the closed forms of a scenario, with chosen values as symbols, printed
as text, LaTeX, or the source of a NumPy function."""

from __future__ import annotations

import keyword
from collections.abc import Sequence

import sympy as sp
from sympy.printing.numpy import NumPyPrinter

from carnot.model.problem import ImpactProblem
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


#: LaTeX's special characters in text mode, and what stands for each of them.
_LATEX_TEXT = {
    "\\": r"\textbackslash{}",
    "{": r"\{",
    "}": r"\}",
    "_": r"\_",
    "%": r"\%",
    "$": r"\$",
    "&": r"\&",
    "#": r"\#",
    "^": r"\textasciicircum{}",
    "~": r"\textasciitilde{}",
}


def latex_text(text: str) -> str:
    r"""``text`` for LaTeX's text mode (inside ``\text{}``): its special characters escaped,
    line breaks as spaces.

    >>> print(latex_text("contacts.0.normal_impulse"))
    contacts.0.normal\_impulse
    >>> print(latex_text("50% of {a} & $b#~^\\"))
    50\% of \{a\} \& \$b\#\textasciitilde{}\textasciicircum{}\textbackslash{}
    """
    return "".join(_LATEX_TEXT.get(c, c) for c in " ".join(text.splitlines()))


def as_latex(symbols: Sequence[sp.Symbol], result: SymbolicResult, title: str = "") -> str:
    r"""A LaTeX ``align*`` environment, one line per non-zero result; the keys are set in
    ``\text{}`` with LaTeX's special characters escaped (``normal\_impulse``). The title is a
    comment line (where nothing needs escaping), with its line breaks as spaces."""
    title = " ".join(title.splitlines())
    lines = [f"% {title}" if title else "% carnot derive",
             "% symbols: " + ", ".join(sp.latex(s) for s in symbols), r"\begin{align*}"]
    items = list(_nonzero(result).items())
    for i, (k, v) in enumerate(items):
        end = r" \\" if i < len(items) - 1 else ""
        lines.append(rf"\text{{{latex_text(k)}}} &= {sp.latex(v)}{end}")
    lines.append(r"\end{align*}")
    return "\n".join(lines)


def as_python(symbols: Sequence[sp.Symbol], result: SymbolicResult, title: str = "") -> str:
    """The source of ``impact(*symbols)``, a NumPy function returning every non-zero result
    by key. It broadcasts over arrays of the symbols' values: every entry has the broadcast
    shape of all the arguments, also one that depends on none or only some of them (a float
    for scalar arguments)."""
    printer = NumPyPrinter({"fully_qualified_modules": True})
    names = _identifiers(symbols)
    args = ", ".join(names.values())
    shapes = ", ".join(f"numpy.shape({n})" for n in names.values())
    title = " ".join(title.splitlines()).replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    lines = [
        "import numpy",
        "",
        "",
        f"def impact({args}):",
        f'    """Closed forms derived by carnot{": " + title if title else ""}."""',
        f"    _zero = numpy.zeros(numpy.broadcast_shapes({shapes}))",
        "    _out = {",
    ]
    plain = {s: sp.Symbol(n) for s, n in names.items()}
    for key, expr in _nonzero(result).items():
        code = printer.doprint(sp.sympify(expr).xreplace(plain))
        lines.append(f"        {key!r}: {code},")
    lines.append("    }")
    lines.append("    return {key: value + _zero for key, value in _out.items()}")
    return "\n".join(lines) + "\n"


#: Names the generated source uses itself: no argument may take them.
_RESERVED = frozenset({"numpy", "_zero", "_out"})


def _identifiers(symbols: Sequence[sp.Symbol]) -> dict[sp.Symbol, str]:
    """A distinct Python identifier for each symbol: its name, with every character that
    cannot be in one as ``_``, and ``_`` appended to a keyword, a reserved name or a repeat."""
    out: dict[sp.Symbol, str] = {}
    for s in symbols:
        name = "".join(c if c.isalnum() or c == "_" else "_" for c in str(s))
        name = name if name and not name[0].isdigit() else f"s_{name}"
        while (keyword.iskeyword(name) or name in _RESERVED or name in out.values()
               or not name.isidentifier()):  # fmt: skip
            name += "_"
        out[s] = name
    return out

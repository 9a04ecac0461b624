"""``carnot derive``: the closed forms of a scenario, with chosen values as symbols, printed
as text, LaTeX, or the source of a NumPy function."""

from __future__ import annotations

import keyword
from collections.abc import Sequence

import sympy as sp
from sympy.printing.numpy import NumPyPrinter

from carnot.model.problem import ImpactProblem
from carnot.symbolic.active_sets import ActiveSet, SeveralContacts
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
    return "import numpy\n\n\n" + _python_function(symbols, _nonzero(result), "impact", title)


def _python_function(
    symbols: Sequence[sp.Symbol], exprs: dict[str, sp.Expr], name: str, title: str
) -> str:
    """The source of ``name(*symbols)`` returning ``exprs`` by key (see :func:`as_python`)."""
    printer = NumPyPrinter({"fully_qualified_modules": True})
    names = _identifiers(symbols)
    args = ", ".join(names.values())
    shapes = ", ".join(f"numpy.shape({n})" for n in names.values())
    title = " ".join(title.splitlines()).replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    lines = [
        f"def {name}({args}):",
        f'    """Closed forms derived by carnot{": " + title if title else ""}."""',
        f"    _zero = numpy.zeros(numpy.broadcast_shapes({shapes}))",
        "    _out = {",
    ]
    plain = {s: sp.Symbol(n) for s, n in names.items()}
    for key, expr in exprs.items():
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


def _set_label(several: SeveralContacts, aset: ActiveSet) -> str:
    regimes = aset.regimes or ("closed",) * len(aset.active)
    named = [(f"{w} ({several.names[w]})" if several.names[w] != w else w)
             + ("" if r == "closed" else f" {r}")
             for w, r in zip(aset.active, regimes, strict=True)]  # fmt: skip
    return ", ".join(named) or "none"


def _several_head(several: SeveralContacts) -> list[str]:
    head = [
        "several contacts: the simultaneous law (generalized Newton), one closed form per "
        "active set; each holds where its conditions are >= 0",
        "taking part (approaching or closed at the scenario's values): "
        + (", ".join(several.taking_part) or "none"),
    ]
    if several.separating:
        head.append("separating before (no impulse): " + ", ".join(several.separating))
    if several.axis is not None:
        k = list(several.axis)
        head.append(f"Coulomb friction in the plane normal to k = {k}: slip+ slips along "
                    "d = k x n, slip- along -d (friction impulse -mu P_n d)")  # fmt: skip
    for regimes in several.singular:
        head.append("no unique closed form (G singular): " + ", ".join(regimes))
    return head


def several_as_text(
    symbols: Sequence[sp.Symbol], several: SeveralContacts, title: str = ""
) -> str:
    """Per active set: its contacts, whether it holds at the scenario's values, its conditions
    (``name = expression >= 0``) and its non-zero results (``key = expression``)."""
    lines = [title] if title else []
    lines.append("symbols: " + (", ".join(map(str, symbols)) or "(none: exact numbers)"))
    lines.extend(_several_head(several))
    for k, aset in enumerate(several.sets, start=1):
        verdict = "holds at the scenario's values" if aset.holds else "does not hold there"
        lines.append("")
        lines.append(f"active set {k}: {_set_label(several, aset)} [{verdict}]")
        for name, expr in aset.conditions.items():
            lines.append(f"  if {name} = {expr} {'>' if name in aset.strict else '>='} 0")
        if aset.result.redundant:
            lines.append("  note: redundant rows; impulses are the minimum-norm split")
        for key, expr in aset.expressions.items():
            if expr != 0 or key.startswith("energy."):
                lines.append(f"  {key} = {expr}")
    return "\n".join(lines)


def several_as_latex(
    symbols: Sequence[sp.Symbol], several: SeveralContacts, title: str = ""
) -> str:
    r"""One ``align*`` block per active set, its conditions first (``\geq 0``)."""
    title = " ".join(title.splitlines())
    lines = [f"% {title}" if title else "% carnot derive",
             "% symbols: " + ", ".join(sp.latex(s) for s in symbols)]  # fmt: skip
    lines.extend(f"% {line}" for line in _several_head(several))
    for k, aset in enumerate(several.sets, start=1):
        verdict = "holds at the scenario's values" if aset.holds else "does not hold there"
        lines.append(f"% active set {k}: {_set_label(several, aset)} ({verdict})")
        lines.append(r"\begin{align*}")
        rows = [rf"\text{{{latex_text(name)}}} &= {sp.latex(expr)} "
                + (">" if name in aset.strict else r"\geq") + " 0"
                for name, expr in aset.conditions.items()]  # fmt: skip
        rows += [rf"\text{{{latex_text(key)}}} &= {sp.latex(expr)}"
                 for key, expr in aset.expressions.items()
                 if expr != 0 or key.startswith("energy.")]  # fmt: skip
        lines.append(" \\\\\n".join(rows))
        lines.append(r"\end{align*}")
    return "\n".join(lines)


def several_as_python(
    symbols: Sequence[sp.Symbol], several: SeveralContacts, title: str = ""
) -> str:
    """The source of ``active_set_K(*symbols)`` for each set K (numbered as in the text form),
    each returning its results and, under ``"if ..."`` keys, its conditions (each must be
    ``>= 0`` for the set to hold; ``> 0``, a slip regime's ``d . w''``); ``ACTIVE_SETS``
    maps each function to its contacts, ``REGIMES`` to their regimes."""
    parts = ["import numpy", "", ""]
    table = []
    regimes = []
    for k, aset in enumerate(several.sets, start=1):
        exprs = {f"if {name}": expr for name, expr in aset.conditions.items()}
        exprs.update({key: expr for key, expr in aset.expressions.items()
                      if expr != 0 or key.startswith("energy.")})  # fmt: skip
        label = f"{title}, active set {k}" if title else f"active set {k}"
        parts.append(_python_function(symbols, exprs, f"active_set_{k}", label))
        parts.append("")
        table.append(f"    active_set_{k}: {aset.active!r},")
        regimes.append(f"    active_set_{k}: {aset.regimes!r},")
    parts.append("ACTIVE_SETS = {")
    parts.extend(table)
    parts.append("}")
    parts.append("# each active contact's regime: closed, or under Coulomb stick, slip+, slip-")
    parts.append("REGIMES = {")
    parts.extend(regimes)
    parts.append("}")
    return "\n".join(parts) + "\n"

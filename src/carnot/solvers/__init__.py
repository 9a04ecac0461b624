"""Solvers of the simultaneous law, behind one protocol, each answer with its certificate
(DESIGN.md section 9, issue 33).

The law is one contact problem (:mod:`carnot.solvers.problem`: Siconos' fc3d in De Saxce's
form, built once from ``G``, ``w'``, the contacts and the held rows). Its solvers, chosen by
name (``[solver] name``, ``carnot solve --solver``, ``solve_impact(..., solver=)``):

* ``enumerate``: every regime (:func:`carnot.laws.multiple.resolve_simultaneous`); exact, it
  verifies uniqueness where the regimes are few; its cost grows as 2^k to 4^k.
* ``iterative``: ADMM then a semismooth Newton polish (:mod:`carnot.solvers.iterative`); its
  cost grows polynomially, its answer meets the law to round-off where Newton identifies the
  regimes, and :mod:`carnot.solvers.certificate` says what is proved of uniqueness.
* ``auto`` (the default): enumerate where the enumeration verifies uniqueness or the batch
  kernels reach (:func:`carnot.solvers.dispatch._auto_choice`), iterate beyond, enumerating
  after all where the iterative solver stops short and the regimes are at most
  :data:`~carnot.laws.multiple.simultaneous.MAX_REGIMES`.

Whatever answered, :func:`resolve` then evaluates the answer apart from the solver (Siconos'
relative error from ``G`` and ``q``) and attaches a :class:`~carnot.laws.multiple.rows.
Certificate`. Every closed contact takes part (DESIGN.md section 6): one separating before the
impact, whose law the enumeration first leaves out, is taken in where the answer would drive
it into its obstacle, and the law solved again.
"""

from typing import Any

from carnot.solvers.options import SOLVER_NAMES, Certificate, SolverOptions

#: The names this package gives, and the module each lives in: the solvers (SciPy's sparse
#: linear algebra) load when one is first used, not with every impact.
_LAZY = {
    "resolve": "carnot.solvers.dispatch",
    "solve_fc3d": "carnot.solvers.dispatch",
    "Fc3dAnswer": "carnot.solvers.dispatch",
    "ContactProblem": "carnot.solvers.problem",
    "contact_problem": "carnot.solvers.problem",
    "fc3d_error": "carnot.solvers.problem",
    "fc3d_problem": "carnot.solvers.problem",
}

__all__ = ["SOLVER_NAMES", "Certificate", "SolverOptions", *_LAZY]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'carnot.solvers' has no attribute {name!r}")

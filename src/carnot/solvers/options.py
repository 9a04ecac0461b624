"""The solvers' options and their certificate: what a scenario chooses (``[solver]``) and
what every simultaneous answer carries (DESIGN.md section 9). Plain data, importing nothing
heavy, so that the model and the results can hold them without loading the solvers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from carnot.errors import InputError

#: The solvers by their scenario name.
SOLVER_NAMES = ("auto", "enumerate", "iterative")


@dataclass(frozen=True, kw_only=True)
class SolverOptions:
    """The ``[solver]`` table: ``name`` (:data:`SOLVER_NAMES`), ``tolerance`` (Siconos'
    relative error an iterative solver must reach, in (0, 1e-3]), ``max_iterations``
    (its iterations, 1 to 10^7) and ``trace_families`` (trace a family of answers along
    which 3D slip directions turn, for the range of E_d over it, the certificate's
    ``dissipated_range``, with every regime tried so that the range covers every answer:
    up to a second a problem, so off by default).

    >>> SolverOptions(name="fast")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: solver.name: must be one of auto, enumerate, iterative, got 'fast'
    """

    name: str = "auto"
    tolerance: float = 1e-12
    max_iterations: int = 10000
    trace_families: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.trace_families, bool):
            raise InputError("solver.trace_families", "must be true or false",
                             self.trace_families)  # fmt: skip
        if self.name not in SOLVER_NAMES:
            raise InputError("solver.name", f"must be one of {', '.join(SOLVER_NAMES)}",
                             self.name)  # fmt: skip
        tol = self.tolerance
        if isinstance(tol, bool) or not isinstance(tol, int | float) or not (
                math.isfinite(tol) and 0.0 < tol <= 1e-3):  # fmt: skip
            raise InputError("solver.tolerance", "must be a number in (0, 1e-3]", tol)
        its = self.max_iterations
        if isinstance(its, bool) or not isinstance(its, int) or not 1 <= its <= 10**7:
            raise InputError("solver.max_iterations", "must be an integer in [1, 10^7]", its)
        object.__setattr__(self, "tolerance", float(tol))


@dataclass(frozen=True, kw_only=True)
class Certificate:
    """What is known of a simultaneous answer (DESIGN.md section 9), apart from the solver.

    ``solver`` the solver that answered (``enumerate`` or ``iterative``), ``requested`` the
    one asked for (``auto`` chooses); ``residual`` Siconos' relative fc3d error of the
    answer, evaluated from ``G`` and ``q`` (:func:`carnot.solvers.problem.fc3d_error`);
    ``iterations`` those of the solver (1 for the enumeration); ``unique`` true when no
    other answer exists (proved), false when another is known, ``None`` when not verified;
    ``velocities_unique`` the same for the post-impact velocities; ``converged`` whether
    the solver reached its tolerance; ``dissipated_range`` the least and the most ``E_d``
    (J) over the law's answers where all are known (the one E_d of velocities proved unique;
    every regime of a verified enumeration, and over a family of answers with different
    velocities the whole family, where it has one dimension), ``None`` where not known (an
    unverified enumeration or iterative answer, a family of more dimensions whose least is
    not proved). ``dissipated_bounds``: where ``dissipated_range`` is not known but brackets
    are (every regime tried, a family of several dimensions with Coulomb cones), ``((a bound
    below the least, the least attained), (the most attained, a bound above the most))``: the
    least E_d over the answers lies in the first interval, the most in the second, and every
    answer's E_d between the outer ends; ``None`` otherwise.
    """

    solver: str
    requested: str
    residual: float
    iterations: int
    unique: bool | None
    velocities_unique: bool | None
    converged: bool = True
    dissipated_range: tuple[float, float] | None = None
    dissipated_bounds: tuple[tuple[float, float], tuple[float, float]] | None = None

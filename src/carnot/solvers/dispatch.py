"""The simultaneous law by the solver a scenario names, and the certificate of its answer
(DESIGN.md section 9; the solvers: :mod:`carnot.solvers`).

:func:`resolve` builds the contact problem once (:func:`carnot.solvers.problem.contact_problem`),
hands it to the enumeration or the iterative solver, and evaluates the answer apart from the
solver (Siconos' relative error from ``G`` and ``q``). Every closed contact takes part: one
separating before the impact, which the enumeration first leaves out, is taken in where the
answer would drive it into its obstacle, and the law is solved again. :func:`solve_fc3d`
takes Siconos' stored form (``W``, ``q``, ``mu``) to the same solvers.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from carnot.conventions import RELATIVE_TOLERANCE
from carnot.errors import InputError
from carnot.laws.multiple.rows import (
    ContactOutcome,
    ContactRows,
    HeldRows,
    MultipleImpactOutcome,
    check_problem,
    contact_residual,
    dissipated_by_row,
    held_residual,
    velocity_scale,
)
from carnot.laws.multiple.simultaneous import (
    BOUNDS_KEYS,
    MAX_REGIMES,
    VERIFY_SPATIAL_UP_TO,
    VERIFY_UP_TO,
    family_range,
    regime_count,
    resolve_simultaneous,
)
from carnot.solvers.certificate import verdict
from carnot.solvers.options import Certificate, SolverOptions
from carnot.solvers.problem import (
    ContactProblem,
    Delassus,
    contact_problem,
    fc3d_error,
    fc3d_problem,
)

#: Rows above which the iterative solver takes ``G`` as a sparse matrix (when mostly zeros).
SPARSE_FROM = 300
#: The most rows of an impact the batch kernels enumerate (:data:`carnot.batch.multi.MAX_ROWS`).
BATCH_ROWS = 12




def resolve(
    delassus: Delassus,
    w_before: np.ndarray,
    contacts: Sequence[ContactRows],
    held: HeldRows | None = None,
    options: SolverOptions | None = None,
) -> MultipleImpactOutcome:
    """The simultaneous law by the solver ``options`` name (module docstring), its answer
    with a :class:`~carnot.laws.multiple.rows.Certificate`.

    Three balls in a row, the first at 1 m/s into two touching ones, e = 0: all leave at
    1/3 m/s, found by either solver, unique.

    >>> g, w = np.array([[2.0, -1.0], [-1.0, 2.0]]), np.array([-1.0, 0.0])
    >>> c = [ContactRows(normal=0), ContactRows(normal=1)]
    >>> for name in ("enumerate", "iterative"):
    ...     out = resolve(g, w, c, options=SolverOptions(name=name))
    ...     print(np.round(out.impulses, 12).tolist(), out.certificate.solver,
    ...           out.certificate.unique, out.certificate.residual < 1e-15)
    [0.666666666667, 0.333333333333] enumerate True True
    [0.666666666667, 0.333333333333] iterative True True
    """
    options = options or SolverOptions()
    contacts = tuple(contacts)
    checked = not sp.issparse(delassus)  # (G and w' checked here: the law need not again)
    if not checked:
        g, w = delassus, np.asarray(w_before, dtype=float).reshape(-1)
    else:
        g, w = check_problem(delassus, w_before, contacts, held)
    scale = velocity_scale(w, held)
    tol = RELATIVE_TOLERANCE * scale
    closed = [False] * len(contacts)
    name = options.name
    fallback = False
    if name == "auto":
        name = _auto_choice(w, contacts, held)
        fallback = name == "iterative" and regime_count(w, contacts, held) <= MAX_REGIMES
    if name == "iterative" and isinstance(g, np.ndarray) and g.shape[0] > SPARSE_FROM:
        # many contacts couple few bodies each: G is mostly zeros, its LU sparse
        nonzero = np.count_nonzero(g)
        if nonzero < 0.1 * g.size:
            g = sp.csr_matrix(g)
    problem = contact_problem(g, w, contacts, held)
    if fallback:
        out = _iterative(problem, g, w, contacts, held, options, scale)
        if out.certificate is not None and out.certificate.converged:
            return out
        name = "enumerate"  # the iterative solver stopped short: the regimes, every one
    if name == "enumerate":
        if not isinstance(g, np.ndarray):
            g = g.toarray()
        while True:
            # a contact separating before takes part with e = 0 (restitution on approach)
            law_contacts = tuple(dataclasses.replace(c, restitution=0.0) if shut else c
                                 for c, shut in zip(contacts, closed, strict=True))  # fmt: skip
            if options.name == "auto" and regime_count(w, contacts, held, closed) > MAX_REGIMES:
                return _iterative(problem, g, w, contacts, held, options, scale)
            # (tracing families asks for every regime: a range of E_d over all the answers)
            out = resolve_simultaneous(g, w, law_contacts, held, closed=closed,
                                       verify=True if options.trace_families else None,
                                       checked=checked)  # fmt: skip
            driven_in = [k for k, c in enumerate(contacts) if not closed[k]
                         and w[c.normal] > tol and out.w_after[c.normal] < -tol]  # fmt: skip
            if not driven_in:
                break
            for k in driven_in:
                closed[k] = True
        if "no_solution" in out.flags and any(c.kind == "spatial" for c in contacts):
            # the slip angles' roots are sought from a few starts: not a proof
            other = _iterative(problem, g, w, contacts, held, options, scale)
            if other.certificate is not None and other.certificate.converged:
                return other
            out = dataclasses.replace(out, flags=tuple(
                "not_converged" if f == "no_solution" else f for f in out.flags))  # fmt: skip
        return _certified(out, problem, options.name, _traced(g, w, law_contacts, held, out)
                          if options.trace_families else None)  # fmt: skip
    return _iterative(problem, g, w, contacts, held, options, scale)


def _auto_choice(w: np.ndarray, contacts: tuple[ContactRows, ...], held: HeldRows | None
                 ) -> str:  # fmt: skip
    """``auto``'s solver: the enumeration where it verifies uniqueness (at most
    :data:`~carnot.laws.multiple.simultaneous.VERIFY_UP_TO` regimes and
    :data:`~carnot.laws.multiple.simultaneous.VERIFY_SPATIAL_UP_TO` 3D frictional contacts
    taking part) or where the batch kernels reach (at most :data:`BATCH_ROWS` rows: there
    the enumeration's order is the law's documented choice among several answers, the same
    in a batch and in ``solve_impact``); the iterative solver beyond, whose cost grows
    polynomially where the enumeration's first answer may come after thousands of regimes
    (a humanoid's foot on 6 or 7 contacts: 4 to 6 s), and which knows no more of uniqueness
    than an enumeration that does not verify. (:func:`resolve` enumerates after all where
    the iterative solver stops short and the regimes are at most
    :data:`~carnot.laws.multiple.simultaneous.MAX_REGIMES`.)

    >>> c = [ContactRows(normal=3 * k, tangents=(3 * k + 1, 3 * k + 2), friction=0.5)
    ...      for k in range(5)]
    >>> _auto_choice(-np.ones(12), tuple(c[:4]), None), _auto_choice(-np.ones(15), tuple(c), None)
    ('enumerate', 'iterative')
    """
    count = regime_count(w, contacts, held)
    if count > MAX_REGIMES:
        return "iterative"
    rows = w.shape[0]
    tol = RELATIVE_TOLERANCE * velocity_scale(w, held)
    spatial = sum(c.kind == "spatial" and bool(w[c.normal] <= tol) for c in contacts)
    verifies = count <= VERIFY_UP_TO and spatial <= VERIFY_SPATIAL_UP_TO
    return "enumerate" if verifies or rows <= BATCH_ROWS else "iterative"


def _traced(g: np.ndarray, w: np.ndarray, contacts: tuple[ContactRows, ...],
            held: HeldRows | None, out: MultipleImpactOutcome
            ) -> tuple[float, float] | None:  # fmt: skip
    """The range of E_d over the answers and their families (``trace_families``: where the
    enumeration's own range is not known, a family along which slip directions turn);
    None where one of them is not known."""
    if "dissipated_min" in out.extra or "multiple_solutions" not in out.flags:
        return None  # known already, or one answer whose velocities are unique
    spans = [family_range(g, w, contacts, held, o) for o in (out, *out.alternatives)]
    if any(s is None for s in spans):
        return None
    return (min(s[0] for s in spans if s is not None), max(s[1] for s in spans if s is not None))


def _certified(out: MultipleImpactOutcome, problem: ContactProblem, requested: str,
               traced: tuple[float, float] | None = None) -> MultipleImpactOutcome:  # fmt: skip
    """The enumeration's answer with its certificate: uniqueness as its flags say, where it
    verified (every regime tried); ``traced``: the range of E_d where the trace of its
    families gave it."""
    verified = bool(out.extra.get("uniqueness_verified", 1.0))
    flags = out.flags
    unique: bool | None
    v_unique: bool | None
    if "multiple_solutions" in flags:
        unique, v_unique = False, False
    elif "statically_indeterminate" in flags:
        unique, v_unique = False, (True if verified else None)
    elif "no_solution" in flags or "not_converged" in flags:
        unique, v_unique = None, None
    else:
        unique = v_unique = True if verified else None
    # the range only where every answer is known: every regime tried (an enumeration that
    # stopped at its first answer cannot say what the others would dissipate)
    span = ((out.extra["dissipated_min"], out.extra["dissipated_max"])
            if "dissipated_min" in out.extra else traced) if verified else None  # fmt: skip
    brackets = None
    if verified and span is None and BOUNDS_KEYS[0] in out.extra:
        lb, least, most, mb = (float(out.extra[k]) for k in BOUNDS_KEYS)
        brackets = ((lb, least), (most, mb))
    certificate = Certificate(
        solver="enumerate", requested=requested, residual=fc3d_error(problem, out.impulses),
        iterations=1, unique=unique, velocities_unique=v_unique,
        converged="not_converged" not in flags, dissipated_range=span,
        dissipated_bounds=brackets)  # fmt: skip
    return dataclasses.replace(out, certificate=certificate)


def _iterative(problem: ContactProblem, g: Delassus, w: np.ndarray,
               contacts: tuple[ContactRows, ...], held: HeldRows | None,
               options: SolverOptions, scale: float) -> MultipleImpactOutcome:  # fmt: skip
    """The iterative solver's answer as the law's outcome, with its certificate."""
    # (imported here: its compiled loops load Numba, which an enumerated answer does not need)
    from carnot.solvers.iterative import solve_iterative

    answer = solve_iterative(problem, tolerance=options.tolerance,
                             max_iterations=options.max_iterations)  # fmt: skip
    r = answer.impulses
    w_after = w + np.asarray(g @ r).reshape(-1)
    found = verdict(problem, r, answer.velocities, RELATIVE_TOLERANCE * scale)
    flags: list[str] = []
    if not answer.converged:
        flags.append("not_converged")
    if found.unique is False:
        flags.append("statically_indeterminate" if found.velocities_unique is not False
                     else "multiple_solutions")  # fmt: skip
    outcomes = []
    gd = _diagonal_view(g)
    for c, regime in zip(contacts, found.regimes, strict=True):
        p_n = float(r[c.normal])
        p_t = tuple(float(r[t]) for t in c.tangents)
        law_c = c if w[c.normal] <= 0.0 else dataclasses.replace(c, restitution=0.0)
        residual = contact_residual(law_c, gd, r, w, w_after)
        if c.stick and c.friction > 0.0 and math.hypot(*p_t) > c.friction * p_n * (
                1.0 + RELATIVE_TOLERANCE) and "friction_too_small_to_stick" not in flags:
            flags.append("friction_too_small_to_stick")
        outcomes.append(ContactOutcome(active=regime != "separate", regime=regime,  # type: ignore[arg-type]
                                       impulse_normal=p_n, impulse_tangent=p_t,
                                       residual=residual))  # fmt: skip
    residual = max([o.residual for o in outcomes] + [held_residual(held, w_after)])
    e_d = float(np.sum(dissipated_by_row(r, w, w_after)))
    certificate = Certificate(
        solver="iterative", requested=options.name, residual=answer.error,
        iterations=answer.iterations, unique=found.unique,
        velocities_unique=found.velocities_unique, converged=answer.converged,
        dissipated_range=(e_d, e_d) if found.velocities_unique is True else None)  # fmt: skip
    return MultipleImpactOutcome(
        law="simultaneous", impulses=r, w_before=w, w_after=w_after, contacts=tuple(outcomes),
        residual=residual, flags=tuple(flags),
        extra={"uniqueness_verified": float(found.unique is not None)},
        certificate=certificate)  # fmt: skip


class _Diagonal:
    """``G[n, n]`` lookups of a dense or sparse ``G`` (what :func:`contact_residual` reads)."""

    def __init__(self, g: Delassus):
        self._diag = np.asarray(g.diagonal() if sp.issparse(g) else np.diag(g))

    def __getitem__(self, key: tuple[int, int]) -> float:
        return float(self._diag[key[0]])


def _diagonal_view(g: Delassus) -> np.ndarray:
    return g if isinstance(g, np.ndarray) else _Diagonal(g)  # type: ignore[return-value]


@dataclass(frozen=True, kw_only=True, eq=False)
class Fc3dAnswer:
    """:func:`solve_fc3d`'s answer: impulses ``r``, velocities ``u = W r + q``, and the
    certificate (``residual`` Siconos' relative error)."""

    impulses: np.ndarray
    velocities: np.ndarray
    certificate: Certificate
    regimes: tuple[str, ...]


def solve_fc3d(
    delassus: Delassus,
    q: np.ndarray,
    mu: np.ndarray,
    *,
    solver: str = "auto",
    tolerance: float = 1e-12,
    max_iterations: int = 10000,
    dimension: int = 3,
) -> Fc3dAnswer:
    """Siconos' fc3d problem as it is stored (``W``, ``q``, ``mu``; each contact ``dimension``
    rows, normal first): find ``r`` in the cones with ``u_hat = W r + q + mu |u_t| e_n`` in
    the dual cones, orthogonal. The same solvers as the law's (a contact's ``q_n`` is its
    ``u_n`` with no restitution: ``e = 0``).

    >>> a = solve_fc3d(np.eye(3), np.array([-1.0, 0.5, 0.0]), np.array([0.2]))
    >>> np.round(a.impulses, 12).tolist(), a.regimes, a.certificate.residual < 1e-15
    ([1.0, -0.2, 0.0], ('slip',), True)
    """
    problem = fc3d_problem(delassus, q, mu, dimension)
    m = problem.size
    contacts = [ContactRows(normal=int(n), tangents=tuple(int(t) for t in ts if t < m),
                            friction=float(f))
                for n, ts, f in zip(problem.normal, problem.tangent, problem.mu,
                                    strict=True)]  # fmt: skip
    options = SolverOptions(name=solver, tolerance=tolerance, max_iterations=max_iterations)
    g = problem.delassus
    scale = float(abs(g).max()) if m else 0.0
    asymmetry = float(abs(g - g.T).max()) if m else 0.0
    if asymmetry > RELATIVE_TOLERANCE * scale:
        # W as some of Siconos' problems store it, not symmetric (by 1e-5 to 6e-4): the
        # problem as it is, which only the iterative solver takes (its ADMM by LU)
        if options.name == "enumerate":
            raise InputError("W", "must be symmetric for the enumeration (1e-9 relative)",
                             asymmetry)  # fmt: skip
        out = _iterative(problem, g, problem.q, tuple(contacts), None, options,
                         velocity_scale(problem.q, None))  # fmt: skip
    else:
        out = resolve(g, problem.q, contacts, options=options)
    assert out.certificate is not None
    return Fc3dAnswer(impulses=out.impulses, velocities=out.w_after,
                      certificate=out.certificate,
                      regimes=tuple(c.regime for c in out.contacts))  # fmt: skip

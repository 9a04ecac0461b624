"""The iterative solver of the simultaneous law: ADMM on De Saxce's form, then a semismooth
Newton polish on the natural map, to round-off (DESIGN.md section 9).

Why these two. The regime enumeration (:mod:`carnot.laws.multiple.simultaneous`) is exact
but costs 2^k to 4^k regimes for k contacts; the literature's solvers of the same problem
(Acary, Bremond and Huber 2018, the FCLIB comparison) reach any tolerance at polynomial
cost, but each alone has a weakness: first-order methods (Siconos' NSGS, Pinocchio's ADMM:
Carpentier, Le Lidec and Montaut 2024) are robust from any start but converge linearly, so
1e-12 costs thousands of sweeps on ill-conditioned stacks; Newton methods on a nonsmooth
reformulation (Alart and Curnier 1991; Siconos' ``fc3d_nonsmooth_Newton_NaturalMap``)
converge quadratically once the contacts' regimes are identified, to round-off, but may
stall far from the answer. So this solver does both:

1. **ADMM** (the alternating direction method of multipliers on ``min 1/2 r.G r + (q + s).r``
   over the cones, ``s`` De Saxce's shift ``mu |u_t|`` updated each iteration), vectorized
   over contacts: each iteration is one solve with ``G + R`` (factorized once: Cholesky, or
   SuperLU for a sparse ``G``), one projection per contact and a matrix product. ``R`` is
   diagonal, constant over each contact's rows (so the projection stays Euclidean), each
   contact's own ``G_nn`` times a scale. The scale that converges depends on the problem
   (1 for a pile of spheres, 0.1 or 0.003 for a tower of boxes with mu = 1; residual
   balancing, Boyd et al. 2011 section 3.4.1, lost convergence on both), so ADMM runs at a
   few scales side by side (:data:`ADMM_SCALES`), 100 iterations of each in turn, each
   state kept.
2. **Newton** on ``F(r) = r - proj_K(r - rho u_hat(r)) = 0`` with ``rho = 1 / G_nn`` per
   contact: the generalized Jacobian ``J = I - D + D diag(rho) (I + E) G``, ``D`` the
   projection's derivative (identity inside a cone, zero in its polar, the derivative of the
   projection on its surface between), ``E`` that of De Saxce's shift. Steps are damped by a
   backtracking line search on ``|F|``; a singular ``J`` (redundant contacts: a box's four
   coplanar corners) takes the minimum-norm step. Newton runs first, from zero; where it
   stalls, ADMM takes over, and after each of its rounds Newton tries again from ADMM's
   iterate (a try that does not divide the error by 100 in 10 steps gives up).
3. **The proximal point method** where ADMM stalls (its rounds with Newton's tries have not
   divided the error by :data:`PROXIMAL_PROGRESS` over the last :data:`PROXIMAL_WINDOW`
   iterations: :func:`stalled`): Siconos' ``PROX`` (``fc3d_proximal.c``) with a nonsmooth
   Newton inside (Acary, Bremond and Huber 2018). From a centre ``r_k``, the law with
   ``G + eps diag(G)`` and ``q - eps diag(G) r_k`` is solved by Newton, whose Jacobian is
   then regular, and its answer is the next centre; ``eps`` shrinks with the error. On a
   singular ``G`` with degenerate regimes (a humanoid crumpling: self-contacts and limits
   that hold its joints, contacts on their cone's edge at rest) ADMM stalls at 1e-5 and
   Newton's steps on ``G`` itself do not find the regimes, while this converges
   (tests/test_solvers_h1.py).
4. **The smoothed law, then its regime solved exactly**, where the proximal stage too
   stops short on a dense problem of at most :data:`SMOOTHED_UP_TO` rows
   (:func:`_smoothed_then_regime`). A box landing flat on four corners on a tilted floor
   with mu = 1.5, sticking impossible by a hair, slips at 1e-6 to 1e-4 of the impact's
   speed, in a family of answers; its internal impulses (in ``G``'s null space) are tied to
   the slips by ``1 / |u_t|`` alone, so ADMM creeps (6e-8 to 1.3e-6 after 10000 iterations) and
   Newton's basin on the natural map is of round-off's size. The law smoothed as for the
   enumeration's start (:mod:`carnot.laws.multiple.smoothing`: Fischer and Burmeister's
   function for Signorini, a viscous Coulomb law ``mu r_n u_t / sqrt(|u_t|^2 + eps^2)``)
   is followed from ``eps`` = the velocity scale to 1e-10 of it, and the regime it ends in
   is solved by Newton on equations whose slip direction is the impulse's
   (:func:`_regime_system`).

At a zero of ``F`` the regimes are those the answer shows (each contact separating, closed,
sticking or slipping) and Newton's last steps are the exact solve of that regime's
equations, so the answer meets the law to round-off. Its certificate
(:mod:`carnot.solvers.certificate`) is computed afterwards, apart from this module.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from carnot.solvers import kernels
from carnot.solvers.kernels import natural_map, onto_cones
from carnot.solvers.problem import ContactProblem, fc3d_error, relative_error, split

#: Residual (Siconos' relative error) at which ADMM hands over to Newton.
HANDOVER = 1e-6
#: Newton steps after which a try that has not divided the error by 100 gives up.
NEWTON_TRIAL = 10
#: ADMM iterations between two tries of Newton.
ADMM_ROUND = 100
#: The scales of ADMM's penalty ``R`` (times each contact's ``G_nn``), run in turn.
ADMM_SCALES = (1.0, 0.1, 0.003, 10.0, 3.0)


@dataclass(frozen=True, kw_only=True, eq=False)
class IterativeAnswer:
    """The impulses found, their velocities ``u = G r + q``, Siconos' relative error, the
    iterations spent (ADMM and Newton together) and whether ``tolerance`` was reached."""

    impulses: np.ndarray
    velocities: np.ndarray
    error: float
    iterations: int
    newton_steps: int
    converged: bool


def solve_iterative(
    problem: ContactProblem,
    *,
    tolerance: float = 1e-12,
    max_iterations: int = 10000,
    start: np.ndarray | None = None,
) -> IterativeAnswer:
    """ADMM then Newton (module docstring) until Siconos' relative error is at most
    ``tolerance``, within ``max_iterations`` (ADMM iterations and Newton steps together).

    Three balls in a row, e = 0 (``G = [[2, -1], [-1, 2]]`` for unit masses): the impulses
    ``(2/3, 1/3)`` N s, to round-off.

    >>> from carnot.solvers.problem import fc3d_problem
    >>> p = fc3d_problem(np.array([[2.0, 0, -1], [0, 2, 0], [-1, 0, 2]]), np.array([-1.0, 0, 0]),
    ...                  np.array([0.0]), dimension=3)
    >>> a = solve_iterative(p)
    >>> np.round(a.impulses, 12).tolist(), a.converged
    ([0.5, 0.0, 0.0], True)
    """
    m = problem.size
    r = np.zeros(m) if start is None else np.array(start, dtype=float)
    if m == 0:
        return IterativeAnswer(impulses=r, velocities=problem.q.copy(), error=0.0,
                               iterations=0, newton_steps=0, converged=True)  # fmt: skip
    diag = problem.diagonal()
    contact_scale = np.where(diag[problem.normal] > 0.0, diag[problem.normal], 1.0)
    rho = _per_row(problem, 1.0 / contact_scale, diag)
    # Newton first: from a good start (most landings, chains) it is done in a few steps
    best_r, best_err, spent = _newton(problem, r, rho, tolerance, min(50, max_iterations))
    newton_steps = spent
    if best_err > tolerance and spent < max_iterations and m <= REGULARIZED_UP_TO:
        # stalled: a singular G (more rows than the bodies' freedoms: a robot's feet, limits
        # and self-contacts) leaves the Jacobian singular wherever the regimes are not yet
        # right. Its steps taken with G + eps diag(G) instead (an inexact Newton on the same
        # F, each step well posed) find the regimes; the exact Newton then ends at round-off
        # (ADMM, where this too stops short, starts from the start as before)
        jac_problem = _regularized(problem, diag)
        near, err, used = _newton(problem, best_r, rho, HANDOVER,
                                  min(REGULARIZED_STEPS, max_iterations - spent), jac_problem,
                                  give_up=REGULARIZED_STEPS)  # fmt: skip
        spent += used
        newton_steps += used
        if err < best_err:
            near, err, more = _newton(problem, near, rho, tolerance,
                                      min(20, max_iterations - spent))  # fmt: skip
            spent += more
            newton_steps += more
            if err < best_err:
                best_r, best_err = near, err
    # ADMM at several penalty scales side by side, each state kept and run on in turn (the
    # scale that converges depends on the problem, and Newton's basin is reached from some
    # scales' iterates and not others'); after each round Newton tries from where it is:
    # once the regimes are identified Newton ends in a few steps, at round-off
    states: list[_Admm | None] = []
    bound = _impulse_bound(problem, diag)
    turn = 0
    proximal_left = PROXIMAL_BUDGET
    progress = [(spent, best_err)]  # (iterations spent, best error) after each ADMM round
    # (the smoothed stage and the regimes' exact solve: dense problems of a few contacts)
    smoothed_out = not (isinstance(problem.delassus, np.ndarray) and m <= SMOOTHED_UP_TO)
    smoothed = smoothed_out
    while best_err > tolerance and spent < max_iterations:
        if proximal_left > 0 and stalled(progress, PROXIMAL_WINDOW, PROXIMAL_PROGRESS):
            # ADMM's rounds with Newton's tries have not divided the error by
            # PROXIMAL_PROGRESS in the last PROXIMAL_WINDOW iterations: the proximal point
            # method with Newton inside (Siconos' PROX), from the best point so far; where it
            # stops short, ADMM goes on where it was, and it is tried again where ADMM stalls
            # again, from its best point then, while its own budget lasts
            near, err, used = _proximal(problem, best_r, rho, diag, tolerance,
                                        min(proximal_left, max_iterations - spent))  # fmt: skip
            spent += used
            newton_steps += used
            proximal_left -= used
            if err < best_err:
                best_r, best_err = near, err
            if best_err > tolerance and not smoothed and spent < max_iterations:
                # short there too (a box landing flat on a tilted floor: slips of 1e-6 of
                # the scale, where the law's internal impulses are tied to friction by
                # 1 / |u_t| alone): the smoothed law followed to the limit, and the regime
                # it ends in solved exactly (once)
                smoothed = True
                near, err, used = _smoothed_then_regime(problem, tolerance,
                                                        max_iterations - spent)  # fmt: skip
                spent += used
                newton_steps += used
                if err < best_err:
                    best_r, best_err = near, err
            progress = [(spent, best_err)]  # (a new window for ADMM)
            if best_err <= tolerance:
                # Newton's last steps on the law itself: to round-off
                near, err, used = _newton(problem, best_r, rho, tolerance,
                                          min(10, max_iterations - spent))  # fmt: skip
                spent += used
                newton_steps += used
                if err < best_err:
                    best_r, best_err = near, err
                break
            continue
        if states and all(s is None for s in states) and len(states) == len(ADMM_SCALES):
            break  # every scale diverges: left to the caller as not converged
        k = turn % len(ADMM_SCALES)
        if k == len(states):
            states.append(_Admm(problem, contact_scale, diag, r, ADMM_SCALES[k]))
        turn += 1
        admm = states[k]
        if admm is None:
            continue
        r, err, used = admm.run(min(ADMM_ROUND, max_iterations - spent), HANDOVER, bound)
        spent += used
        if not (np.isfinite(r).all() and float(np.abs(r).max()) <= bound):
            # a scale that diverges here (G singular: ADMM's step, at De Saxce's shift of
            # the moment, may be unbounded along G's null space; Go2's calf limit and
            # self-contact took it to 1e31 N s): dropped, not started again
            states[k] = None
            r = best_r
            continue
        if err < best_err:
            best_r, best_err = r, err
        if best_err <= tolerance or spent >= max_iterations:
            break
        r, err, used = _newton(problem, r, rho, tolerance, min(60, max_iterations - spent))
        spent += used
        newton_steps += used
        if err < best_err:
            best_r, best_err = r, err
        r = admm.z
        progress.append((spent, best_err))
    if (best_err > ROUND_OFF and not smoothed_out and spent < max_iterations
            and best_err <= HANDOVER):
        # an answer to the tolerance but not to round-off, where Newton's last steps on the
        # natural map gain nothing (its basin of round-off's size: slips of 1e-6 of the
        # scale), or one near it: its regime solved exactly
        near, err, used = _regime_polish(problem, best_r, best_err, ROUND_OFF,
                                         max_iterations - spent)  # fmt: skip
        spent += used
        newton_steps += used
        if err < best_err:
            best_r, best_err = near, err
    # on the cones exactly (Newton's iterates may lie outside by round-off: a normal impulse
    # of -1e-25 N s is a pull), kept where that does not lose the tolerance, or where it was
    # not reached
    projected = onto_cones(problem, best_r)
    err = fc3d_error(problem, projected)
    if err <= max(best_err, tolerance) or best_err > tolerance:
        # (short of the tolerance, impulses that pull would add a false flag to a true one)
        best_r, best_err = projected, err
    u = problem.velocities(best_r)
    # (Siconos' error is relative to |r|: impulses beyond any the problem can need meet it
    # while they cancel one another, so they are never an answer)
    bounded = bool(np.isfinite(best_r).all() and float(np.abs(best_r).max()) <= bound)
    return IterativeAnswer(impulses=best_r, velocities=u, error=best_err, iterations=spent,
                           newton_steps=newton_steps,
                           converged=best_err <= tolerance and bounded)  # fmt: skip


def _error(problem: ContactProblem, r: np.ndarray) -> float:
    """:func:`~carnot.solvers.problem.fc3d_error` by the compiled natural map (the same
    number), for the solver's own tests of progress; the answer's error is the NumPy
    route's."""
    f, u = natural_map(problem, r, np.ones(problem.size))
    return relative_error(problem, r, f, u)


#: How many times the largest impulse that stops one row alone an answer's impulses may be.
IMPULSE_BOUND = 1e6


def _impulse_bound(problem: ContactProblem, diag: np.ndarray) -> float:
    """The largest impulse (N s) an answer may carry: :data:`IMPULSE_BOUND` times the largest
    ``|q_i| / G_ii``, the impulse that would stop row ``i`` alone (a bound far above any
    answer's: a landing's impulses are a few times that at most; 1e-300 where nothing moves).
    """
    positive = diag > 0.0
    alone = np.abs(problem.q[positive]) / diag[positive] if positive.any() else np.zeros(1)
    return IMPULSE_BOUND * max(float(alone.max(initial=0.0)), 1e-300)


def _per_row(problem: ContactProblem, per_contact: np.ndarray, diag: np.ndarray) -> np.ndarray:
    """A per-contact value spread over each contact's rows; held rows get ``1 / G_hh``."""
    out = np.append(np.zeros(problem.size), 0.0)
    out[problem.tangent] = per_contact[:, None]
    out[problem.normal] = per_contact
    out = out[:-1]
    if problem.held.size:
        h = diag[problem.held]
        out[problem.held] = 1.0 / np.where(h > 0.0, h, 1.0)
    return out


class _Admm:
    """ADMM's state that outlives one run: ``R`` and the factorization of ``G + R``."""

    solve: Callable[[np.ndarray], np.ndarray]

    def __init__(self, problem: ContactProblem, contact_scale: np.ndarray, diag: np.ndarray,
                 start: np.ndarray, scale: float):  # fmt: skip
        self.problem = problem
        self.z = onto_cones(problem, start)
        self.y = np.zeros_like(self.z)  # scaled dual: -R y is De Saxce's velocity at the end
        base = _per_row(problem, 1.0 / contact_scale, diag)  # held rows: 1 / G_hh
        self.base = 1.0 / np.where(base > 0.0, base, 1.0)
        self.scale = scale
        g = problem.delassus
        self.symmetric = sp.issparse(g) or bool(np.array_equal(g, g.T))
        self._factor()

    def _factor(self) -> None:
        p = self.problem
        self.penalty = self.scale * self.base
        g = p.delassus
        if sp.issparse(g):
            a = (g + sp.diags(self.penalty)).tocsc()
            lu = spla.splu(a)
            self.solve = lu.solve
        elif self.symmetric:
            c, lower = sla.cho_factor(g + np.diag(self.penalty), check_finite=False)
            # (LAPACK's potrs, as cho_solve calls it, without its checks: a tenth of an
            # iteration)
            potrs = sla.get_lapack_funcs("potrs", (c,))
            self.solve = lambda b: potrs(c, b, lower=lower)[0]
        else:  # (a W stored unsymmetric: ADMM's step by LU, Newton on W as it is)
            lu = sla.lu_factor(g + np.diag(self.penalty), check_finite=False)
            self.solve = lambda b: sla.lu_solve(lu, b, check_finite=False)

    def run(self, iterations: int, target: float, bound: float = math.inf
            ) -> tuple[np.ndarray, float, int]:  # fmt: skip
        """Up to ``iterations`` more ADMM iterations; the last feasible iterate ``z``, its
        error, and the iterations used (stopping at ``target``, or where an impulse passes
        ``bound``: diverging)."""
        p = self.problem
        z, y = self.z, self.y
        used = 0
        finite = bool(np.isfinite(z).all())
        # (a scale at which ADMM diverges overflows: checked, and started again by the caller)
        with np.errstate(over="ignore", invalid="ignore"):
            err = _error(p, z)
            for used in range(1, iterations + 1):  # noqa: B007  (used after the loop)
                if not finite:
                    break  # diverged at this scale: the caller starts it again
                u = p.velocities(z)
                lam = self.solve(kernels.admm_rhs(u, p.q, z, y, self.penalty, p.normal,
                                                  p.tangent, p.mu))  # fmt: skip
                z, y, finite = kernels.admm_update(lam, y, p.normal, p.tangent, p.mu)
                if used % 10 == 0 or used == iterations:
                    err = _error(p, z)
                    if err <= target or not float(np.abs(z).max()) <= bound:
                        break
        self.z, self.y = z, y
        return z, err, used


#: The regularization of the Jacobian's ``G`` where Newton stalls (times ``diag(G)``).
REGULARIZATION = 1e-4
#: The most steps of Newton with that Jacobian.
REGULARIZED_STEPS = 60
#: The most rows for which that is tried (a robot's coupled landing: Go2 50, H1 42 rows;
#: measured: on H1's 36-row landing 1.05 s -> 22 ms, while on towers of 12 to 250 boxes,
#: 144 rows and more, ADMM's rounds find the regimes sooner and the try only adds steps).
REGULARIZED_UP_TO = 100


def _regularized(problem: ContactProblem, diag: np.ndarray) -> ContactProblem:
    """The problem with ``G + eps diag(G)`` (:data:`REGULARIZATION`), whose Jacobian
    :func:`_newton` may take."""
    g = problem.delassus
    shift = REGULARIZATION * np.where(diag > 0.0, diag, 1.0)
    g = (g + sp.diags(shift)).tocsr() if sp.issparse(g) else g + np.diag(shift)
    return dataclasses.replace(problem, delassus=g)


#: The proximal shift ``eps diag(G)`` of :func:`_proximal` is ``eps = sigma * error`` (the
#: relative error at the centre: Siconos' ``alpha = sigma error^nu``, ``nu = 1``; its default
#: ``sigma = 5`` stalled on one of H1's landings, 1 solves all nine).
PROXIMAL_SIGMA = 1.0
#: The most Newton steps on one proximal subproblem (one that succeeds takes 1 to 47 on H1's).
PROXIMAL_INNER = 50
#: The most Newton steps of the proximal stages in all (H1's landings: 100 to 1100).
PROXIMAL_BUDGET = 3000
#: The proximal stage is tried where ADMM's rounds with Newton's tries have not divided the
#: best error by :data:`PROXIMAL_PROGRESS` over the last :data:`PROXIMAL_WINDOW` iterations
#: (:func:`stalled`), and again after each window more that stops short. (After a count of
#: 300 ADMM iterations before 2026-12-03.) The window is a trade-off (docs/solvers.md,
#: Measured): a longer one spares a pile whose ADMM progresses slowly the stage's dearer steps
#: (at 500 the pile of 300 spheres never enters it, 6-16 % faster), but scenes whose ADMM
#: creeps from its first rounds reach it later, from a point where it takes longer (at 500
#: Siconos' Capsules 953 iterations for 505, the 100 poured spheres 1170 for 566, about 2x
#: the time); 200 gives all three the iterations of the count of 300 (470, 505, 566), so no
#: figure of the README is slower.
PROXIMAL_WINDOW = 200
PROXIMAL_PROGRESS = 10.0
#: The least and the largest ``eps``; the outer iterations without halving the error after
#: which a stage gives up.
PROXIMAL_SHIFTS = (1e-14, 1e2)
PROXIMAL_STALL = 40


def stalled(progress: list[tuple[int, float]], window: int, factor: float) -> bool:
    """Whether a solver's progress, ``(iterations spent, best error)`` recorded after each of
    its rounds (the first record where it began), shows the best error now above ``1 /
    factor`` of the best ``window`` iterations ago (the last record at or before then): too
    early to tell (less than ``window`` since the first record) is not stalled.

    >>> stalled([(0, 1.0), (300, 0.5), (600, 0.2)], 500, 10.0)
    True
    >>> stalled([(0, 1.0), (300, 0.5), (600, 0.05)], 500, 10.0)
    False
    >>> stalled([(0, 1.0), (300, 0.9)], 500, 10.0)
    False
    """
    now, best = progress[-1]
    before = [err for spent, err in progress if spent <= now - window]
    return bool(before) and best > before[-1] / factor


def _proximal(problem: ContactProblem, r0: np.ndarray, rho: np.ndarray, diag: np.ndarray,
              tolerance: float, steps: int) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """The proximal point method on the law (Rockafellar 1976; Siconos' ``fc3d_proximal``,
    ``PROX`` with a nonsmooth Newton inside, Acary, Bremond and Huber 2018): from the centre
    ``r_k``, the problem with ``G + eps D`` and ``q - eps D r_k`` (``D = diag(G)``) is solved
    by :func:`_newton` (its Jacobian regular: ``G + eps D`` is positive definite where ``G``
    is only semi-definite), and its answer is the next centre. A fixed point is an answer of
    the law itself. ``eps = sigma * error`` shrinks with the error (the method becomes
    superlinear near the answer), by at most ten times a centre (where it fell at once to
    the error, the next subproblem was as singular as ``G`` and Newton failed on it, every
    other centre, on H1's landing at t = 1.224 s); a subproblem that Newton does not solve to
    a tenth of the error takes ``eps`` ten times larger (better conditioned, a shorter step),
    from the same centre. Returns the best point, its error and the Newton steps taken (at
    most ``steps``)."""
    g = problem.delassus
    scale = np.where(diag > 0.0, diag, 1.0)
    r = r0
    err = _error(problem, r)
    best = (r, err)
    eps = PROXIMAL_SIGMA * err
    taken = 0
    since = 0  # outer iterations since the best error was last halved
    mark = err
    while err > tolerance and taken < steps and since < PROXIMAL_STALL:
        eps = min(max(eps, PROXIMAL_SHIFTS[0]), PROXIMAL_SHIFTS[1])
        shift = eps * scale
        shifted = (g + sp.diags(shift)).tocsr() if sp.issparse(g) else g + np.diag(shift)
        sub = dataclasses.replace(problem, delassus=shifted, q=problem.q - shift * r)
        inner = max(0.1 * err, 1e-16)
        trial, sub_err, used = _newton(sub, r, rho, inner, min(PROXIMAL_INNER, steps - taken),
                                       give_up=PROXIMAL_INNER)  # fmt: skip
        taken += used
        trial_err = _error(problem, trial) if np.isfinite(trial).all() else math.inf
        since += 1
        if sub_err <= inner and math.isfinite(trial_err):
            r, err = trial, trial_err
            eps = max(PROXIMAL_SIGMA * err, 0.1 * eps)
        elif eps >= PROXIMAL_SHIFTS[1]:
            break
        else:
            eps *= 10.0
        if err < best[1]:
            best = (r, err)
        if best[1] <= 0.5 * mark:
            mark, since = best[1], 0
    return best[0], best[1], taken


#: The smoothed law's continuation (:func:`_smoothed`) and the regime solve after it are
#: tried on problems of at most this many rows (dense: a box landing's 12 rows, a robot's
#: 15 to 50), where ADMM and the proximal stage stop short.
SMOOTHED_UP_TO = 100
#: The smoothing ``eps`` ends at this fraction of the velocity scale (as the enumeration's
#: start, :data:`carnot.laws.multiple.smoothing.EPS_END`).
SMOOTHED_END = 1e-10
#: Below this error an answer is at round-off; above it, where the regimes' exact solve
#: applies, it is tried on the answer found (:func:`_regime_polish`).
ROUND_OFF = 1e-14
#: The most Newton steps on one smoothed system, and on one regime's equations.
SMOOTHED_INNER = 20
#: A 3D contact whose impulse lies within these fractions of its cone's edge is taken to slip
#: (in turn: the regime solve is tried with each): the smoothing does not tell a slip of 1e-8
#: of the scale from sticking at the edge.
EDGE_MARGINS = (1e-6, 1e-3, 1e-1)


def _smoothed_system(problem: ContactProblem, r: np.ndarray, eps: float
                     ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The smoothed law at ``eps`` (m/s) and its Jacobian (dense): per contact, Signorini by
    Fischer and Burmeister's smoothed function ``a + b - sqrt(a^2 + b^2 + 2 eps^2)``
    (``a = G_nn r_n``, ``b = u_n``), Coulomb's law as the viscous-regularized
    ``G_nn (r_t + mu r_n u_t / sqrt(|u_t|^2 + eps^2))`` (a slip above ``eps`` takes the cone's
    edge against it; a sticking contact slips at about ``eps``), told to stick ``u_t``, no
    friction ``G_nn r_t``, held rows ``u_h`` (as :mod:`carnot.laws.multiple.smoothing`, on the
    solver's problem). At ``eps = 0`` its zeros are the law's answers; for ``eps > 0`` it is
    smooth, and the internal impulses that a singular ``G`` leaves to friction are tied to
    the slips by the gain ``mu r_n / eps``, where the law ties them by ``1 / |u_t|`` alone.

    >>> from carnot.solvers.problem import fc3d_problem
    >>> p = fc3d_problem(np.eye(3), np.array([-1.0, 0.0, 0.0]), np.array([0.5]))
    >>> f, _ = _smoothed_system(p, np.array([1.0, 0.0, 0.0]), 1e-8)
    >>> bool(np.abs(f).max() < 1e-15)
    True
    """
    g = problem.delassus
    m = problem.size
    u = problem.velocities(r)
    f = np.empty(m)
    jac = np.zeros((m, m))
    for k in range(problem.normal.shape[0]):
        n = int(problem.normal[k])
        ts = [int(t) for t in problem.tangent[k] if t < m]
        gnn = float(g[n, n]) if g[n, n] > 0.0 else 1.0
        a, b = gnn * float(r[n]), float(u[n])
        s = math.sqrt(a * a + b * b + 2.0 * eps * eps)
        f[n] = a + b - s
        jac[n] = (1.0 - b / s) * g[n]
        jac[n, n] += (1.0 - a / s) * gnn
        if not ts:
            continue
        mu = float(problem.mu[k])
        if math.isinf(mu):
            f[ts] = u[ts]
            jac[ts] = g[ts]
        elif mu == 0.0:
            f[ts] = gnn * r[ts]
            jac[ts, ts] = gnn
        else:
            u_t = u[ts]
            d2 = float(u_t @ u_t) + eps * eps
            root = math.sqrt(d2)
            unit = u_t / root
            f[ts] = gnn * (r[ts] + mu * float(r[n]) * unit)
            d_unit = (np.eye(len(ts)) * d2 - np.outer(u_t, u_t)) / (d2 * root)
            jac[ts] = (gnn * mu * float(r[n])) * (d_unit @ g[ts])
            jac[ts, ts] += gnn
            jac[ts, n] += gnn * mu * unit
    for h in problem.held:
        f[h] = u[h]
        jac[h] = g[h]
    return f, jac


def _smoothed_newton(problem: ContactProblem, r: np.ndarray, eps: float, target: float,
                     steps: int) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """Damped Newton on :func:`_smoothed_system` at ``eps`` from ``r`` (backtracking on
    ``|f|``): the point, its ``|f|`` (m/s) and the steps taken (until ``|f| <= target``)."""
    f, jac = _smoothed_system(problem, r, eps)
    norm = _length(f)
    taken = 0
    while norm > target and taken < steps:
        taken += 1
        d, _ = _step(jac, -f)
        if d is None:
            break
        trial, (f_t, jac_t), norm_t = _backtrack(
            lambda x: _smoothed_system(problem, x, eps), r, d, norm, 1e-6)
        if not norm_t < norm:
            break
        r, f, jac, norm = trial, f_t, jac_t, norm_t
    return r, norm, taken


def _smoothed(problem: ContactProblem, steps: int) -> tuple[np.ndarray, int]:
    """The smoothed law followed from ``eps`` = the velocity scale ``max |q|`` to
    :data:`SMOOTHED_END` of it (a homotopy: Chen and Mangasarian, *Math. Programming* 71,
    1995, the smoothing of Fischer and Burmeister; the enumeration's start,
    :func:`carnot.laws.multiple.smoothing.smoothed_impulses`, on the solver's problem), each
    ``eps``'s system solved by :func:`_smoothed_newton` from the last answer, ``eps`` falling
    by 10 and then up to 100 times a step (a step that fails is retried shorter). Returns the
    last point solved and the Newton steps taken (at most ``steps``)."""
    scale = float(np.abs(problem.q).max()) if problem.size else 0.0
    r = np.zeros(problem.size)
    if not scale > 0.0:
        return r, 0
    eps = scale
    solved = 1e-12 * scale
    r, norm, taken = _smoothed_newton(problem, r, eps, solved, min(steps, 4 * SMOOTHED_INNER))
    if norm > 1e-6 * scale:
        return r, taken
    factor = 10.0
    while eps > SMOOTHED_END * scale and taken < steps:
        trial_eps = max(eps / factor, SMOOTHED_END * scale)
        nxt, norm, used = _smoothed_newton(problem, r, trial_eps, solved,
                                           min(SMOOTHED_INNER, steps - taken))  # fmt: skip
        taken += used
        if norm > 1e-6 * scale or not np.isfinite(nxt).all():
            factor = math.sqrt(factor)
            if factor < 1.01:
                break  # stalled: the last point may still show the regime
            continue
        r, eps = nxt, trial_eps
        factor = min(factor * factor, 100.0)
    return r, taken


def regimes_at(problem: ContactProblem, r: np.ndarray, edge: float) -> tuple[str, ...]:
    """Each contact's regime as the impulses ``r`` show it: ``separate`` where it carries no
    normal impulse (1e-9 of the largest), ``frictionless`` where ``mu = 0``, ``stick`` where
    told to or where ``|r_t| < (1 - edge) mu r_n``, ``slip`` on the cone's edge (read from the
    impulse, not from a slip of round-off: a contact at rest on its cone's edge slips).

    >>> from carnot.solvers.problem import fc3d_problem
    >>> p = fc3d_problem(np.eye(6), np.zeros(6), np.array([0.5, 0.5]))
    >>> regimes_at(p, np.array([1.0, 0.5, 0.0, 1.0, 0.1, 0.0]), 1e-3)
    ('slip', 'stick')
    """
    r_n, r_t = split(problem, r)
    size = float(np.abs(r).max()) if r.size else 0.0
    along = np.sqrt(np.einsum("ij,ij->i", r_t, r_t))
    out = []
    for k in range(problem.normal.shape[0]):
        mu = float(problem.mu[k])
        if r_n[k] <= 1e-9 * size:
            out.append("separate")
        elif mu == 0.0:
            out.append("frictionless")
        elif math.isinf(mu) or along[k] < (1.0 - edge) * mu * r_n[k]:
            out.append("stick")
        else:
            out.append("slip")
    return tuple(out)


def _regime_system(problem: ContactProblem, r: np.ndarray, regimes: tuple[str, ...]
                   ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """One regime's equations at ``r`` and their Jacobian (dense), smooth where the contacts
    that slip carry a tangential impulse: ``separate`` ``r_c = 0``; ``frictionless``
    ``u_n = 0``, ``r_t = 0``; ``stick`` ``u_c = 0``; ``slip`` ``u_n = 0``, ``|r_t| = mu r_n``
    and, in 3D, ``t_perp . u_t = 0`` with ``t = r_t / |r_t|`` (the slip along the impulse's
    direction; that it opposes it, ``t . u_t <= 0``, is left to the law's residual); held rows
    ``u_h = 0``. The slip's direction is the impulse's, not ``u_t / |u_t|``: where the slip is
    1e-6 of the scale or less (a box landing flat on a tilted floor, sticking impossible by a
    hair) the latter's derivative ``1 / |u_t|`` leaves Newton a basin of round-off's size,
    while these equations have bounded derivatives (the form of the enumeration's slip-angle
    condition, :func:`carnot.laws.multiple.simultaneous._solve_regime`).

    >>> from carnot.solvers.problem import fc3d_problem
    >>> p = fc3d_problem(np.eye(3), np.array([-1.0, 0.5, 0.0]), np.array([0.2]))
    >>> f, _ = _regime_system(p, np.array([1.0, -0.2, 0.0]), ("slip",))  # u = (0, 0.3, 0)
    >>> float(np.abs(f).max())
    0.0
    >>> f, _ = _regime_system(p, np.array([1.0, 0.0, -0.2]), ("slip",))  # u_t = (0.5, -0.2)
    >>> f.round(12).tolist()  # (the slip across the impulse's direction)
    [0.0, 0.0, 0.5]
    """
    g = problem.delassus
    m = problem.size
    u = problem.velocities(r)
    f = np.zeros(m)
    jac = np.zeros((m, m))
    for h in problem.held:
        f[h] = u[h]
        jac[h] = g[h]
    for k, regime in enumerate(regimes):
        n = int(problem.normal[k])
        ts = [int(t) for t in problem.tangent[k] if t < m]
        if regime == "separate":
            for row in (n, *ts):
                f[row] = r[row]
                jac[row, row] = 1.0
            continue
        f[n] = u[n]
        jac[n] = g[n]
        if regime == "stick":
            for row in ts:
                f[row] = u[row]
                jac[row] = g[row]
        elif regime == "frictionless":
            for row in ts:
                f[row] = r[row]
                jac[row, row] = 1.0
        else:  # slip: on the cone's edge, and in 3D the slip along the impulse's direction
            mu = float(problem.mu[k])
            r_t = r[ts]
            size = _length(r_t)
            unit = r_t / size
            f[ts[0]] = size - mu * float(r[n])
            jac[ts[0], ts] = unit
            jac[ts[0], n] = -mu
            if len(ts) == 2:
                t1, t2 = ts
                c, s = float(unit[0]), float(unit[1])
                u1, u2 = float(u[t1]), float(u[t2])
                f[t2] = c * u2 - s * u1
                jac[t2] = c * g[t2] - s * g[t1]
                # d(c, s) = (I - t t^T) d r_t / |r_t|, so d f = (u2, -u1) (I - t t^T) / |r_t|
                jac[t2, t1] += (u2 * (1.0 - c * c) + u1 * c * s) / size
                jac[t2, t2] += (-u2 * c * s - u1 * (1.0 - s * s)) / size
    return f, jac


def _regime_solve(problem: ContactProblem, r0: np.ndarray, regimes: tuple[str, ...],
                  steps: int) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """Newton on :func:`_regime_system` from ``r0``, full steps, the minimum-norm one where
    the Jacobian is singular (a family of answers: a box's four corners), the best point by
    the law's own error kept: the point, its error and the steps taken. Full steps: the
    regime's Jacobian is nearly singular where the slips are small (its least singular
    values of the slips' size), so the first step may raise ``|f|`` on its way into the
    quadratic basin, where a line search on ``|f|`` would stop it."""
    r = r0
    best = (r0, _error(problem, r0))
    taken = 0
    for taken in range(1, steps + 1):  # noqa: B007
        f, jac = _regime_system(problem, r, regimes)
        d, _ = _step(jac, -f)
        if d is None:
            break
        r = r + d
        if not np.isfinite(r).all():
            break
        err = _error(problem, r)
        if err < best[1]:
            best = (r, err)
        if err < 1e-15 or _length(f) == 0.0:
            break
    return best[0], best[1], taken


def _smoothed_then_regime(problem: ContactProblem, tolerance: float, steps: int
                          ) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """:func:`_smoothed` from zero, then the regime its end shows solved exactly
    (:func:`_regime_polish`): the best point, its error and the Newton steps taken (at most
    ``steps``)."""
    r, taken = _smoothed(problem, steps)
    near, err, used = _regime_polish(problem, r, _error(problem, r), tolerance, steps - taken)
    return near, err, taken + used


def _regime_polish(problem: ContactProblem, r: np.ndarray, err: float, tolerance: float,
                   steps: int) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """The regime that ``r`` (of error ``err``) shows solved by :func:`_regime_solve`, the
    contacts near their cone's edge taken to slip at each of :data:`EDGE_MARGINS` in turn,
    until one meets ``tolerance``: the best point (``r`` where none is better), its error
    and the steps taken (at most ``steps``)."""
    best = (r, err)
    taken = 0
    tried: set[tuple[str, ...]] = set()
    for edge in EDGE_MARGINS:
        regimes = regimes_at(problem, r, edge)
        if regimes in tried or taken >= steps:
            continue
        tried.add(regimes)
        near, near_err, used = _regime_solve(problem, r, regimes,
                                             min(SMOOTHED_INNER, steps - taken))  # fmt: skip
        taken += used
        if near_err < best[1]:
            best = (near, near_err)
        if best[1] <= tolerance:
            break
    return best[0], best[1], taken


def _length(x: np.ndarray) -> float:
    """``|x|``, ``sqrt(x . x)`` (numpy.linalg.norm's formula)."""
    return math.sqrt(float(x.dot(x)))


def _backtrack(system: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], r: np.ndarray,
               d: np.ndarray, norm: float, floor: float
               ) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray], float]:  # fmt: skip
    """Armijo's backtracking along the step ``d`` from ``r`` on ``|f|``, ``f`` the first of
    ``system(x)``'s two arrays and ``norm`` its length at ``r``: the first ``alpha`` of 1,
    1/2, 1/4 ... with ``|f(r + alpha d)| <= (1 - 1e-4 alpha) norm``, or the first below
    ``floor``; returns the trial point, ``system`` there and its ``|f|``.

    >>> x, (f, _), n = _backtrack(lambda x: (x - 1.0, x), np.zeros(1), np.array([4.0]),
    ...                           1.0, 1e-6)
    >>> x.tolist(), n
    ([1.0], 0.0)
    """
    alpha = 1.0
    while True:
        trial = r + alpha * d
        values = system(trial)
        norm_t = _length(values[0])
        if norm_t <= (1.0 - 1e-4 * alpha) * norm or alpha < floor:
            return trial, values, norm_t
        alpha *= 0.5


def _newton(problem: ContactProblem, r0: np.ndarray, rho: np.ndarray, tolerance: float,
            steps: int, jac_problem: ContactProblem | None = None, give_up: int = NEWTON_TRIAL
            ) -> tuple[np.ndarray, float, int]:  # fmt: skip
    """Damped semismooth Newton on the natural map (module docstring) from ``r0``: the best
    point, its error and the steps taken (stopping at ``tolerance``, at a step that does not
    decrease ``|F|``, or after ``steps``; a try that has not divided the error by 100 in
    ``give_up`` steps gives up); the Jacobian that of ``jac_problem`` where given (the same
    cones, another ``G``: its steps converge linearly, so it is given all its steps)."""
    jac_of = problem if jac_problem is None else jac_problem
    r = r0.copy()
    f, u = natural_map(problem, r, rho)
    norm_f = _length(f)
    err = _error(problem, r)
    start_err = err
    best = (r, err)
    taken = 0
    polish = 0
    singular = False
    g = problem.delassus
    dense = isinstance(g, np.ndarray) and g.flags.c_contiguous and g.dtype == np.float64
    for taken in range(1, steps + 1):  # noqa: B007
        if err <= tolerance:
            # past the tolerance, a few more steps while they still gain: Newton's last steps
            # take the answer to round-off
            polish += 1
            if polish > 3 or err < 1e-15:
                taken -= 1
                break
        jac = _jacobian(jac_of, r, u, rho)
        # (a singular J stays singular while the regimes hold: redundant contacts)
        d, singular = _step(jac, -f, singular)
        if d is None:
            break
        if dense:
            alpha, trial, f_t, u_t, norm_t = kernels.line_search(
                r, d, g, problem.q, rho, problem.normal, problem.tangent, problem.mu, norm_f)
        else:
            trial, (f_t, u_t), norm_t = _backtrack(
                lambda x: natural_map(problem, x, rho), r, d, norm_f, 1e-10)
        if not norm_t < norm_f:
            # no decrease: at round-off, or stalled (left to ADMM)
            break
        r, f, u, norm_f = trial, f_t, u_t, norm_t
        err = _error(problem, r)
        if err < best[1]:
            best = (r, err)
        if taken == give_up and best[1] > 1e-2 * start_err:
            break  # not converging fast: the regimes are not identified yet (left to ADMM)
    return best[0], best[1], taken


def _jacobian(problem: ContactProblem, r: np.ndarray, u: np.ndarray, rho: np.ndarray
              ) -> np.ndarray | sp.csc_matrix:  # fmt: skip
    """``J = I - D + D diag(rho) (I + E) G`` at ``r`` (module docstring), dense or sparse as
    ``G`` is."""
    m = problem.size
    r_ext = np.append(r, 0.0)
    u_ext = np.append(u, 0.0)
    rho = np.asarray(rho, dtype=float)
    block, e_vals = kernels.jacobian_blocks(r_ext, u_ext, rho, problem.normal, problem.tangent,
                                            problem.mu)  # fmt: skip
    g = problem.delassus
    if not sp.issparse(g):
        return kernels.dense_jacobian(block, e_vals, rho, problem.normal, problem.tangent,
                               problem.held, g)  # fmt: skip
    rows = np.concatenate([problem.normal[:, None], problem.tangent], axis=1)  # (nc, 3)
    ii = np.repeat(rows, 3, axis=1).reshape(-1)
    jj = np.tile(rows, (1, 3)).reshape(-1)
    vals = block.reshape(-1)
    h = problem.held
    e_rows = np.repeat(problem.normal, 2)
    e_cols = problem.tangent.reshape(-1)
    e_flat = e_vals.reshape(-1)
    e_keep = (e_flat != 0.0) & (e_cols < m)
    keep = (ii < m) & (jj < m) & (vals != 0.0)
    d_sp = sp.csr_matrix((np.concatenate([vals[keep], np.ones(h.size)]),
                          (np.concatenate([ii[keep], h]), np.concatenate([jj[keep], h]))),
                         shape=(m, m))  # fmt: skip
    e_mat = sp.csr_matrix((e_flat[e_keep], (e_rows[e_keep], e_cols[e_keep])), shape=(m, m))
    eye = sp.identity(m, format="csr")
    k_mat = d_sp @ sp.diags(rho) @ (eye + e_mat)
    return (eye - d_sp + k_mat @ g).tocsc()


def _step(jac: np.ndarray | sp.csc_matrix, rhs: np.ndarray, singular: bool = False
          ) -> tuple[np.ndarray | None, bool]:  # fmt: skip
    """``J d = rhs`` and whether ``J`` was found singular: dense, by LU, or where ``J`` is
    singular (``singular``: the last step's was, so LU is not tried again) the minimum-norm
    least-squares step; sparse, by SuperLU of ``J`` shifted by 1e-10 of its scale.

    The minimum-norm step drops ``J``'s singular values below ``m eps`` of the largest
    (NumPy's ``lstsq`` cutoff) by a complete orthogonal factorization (LAPACK's ``gelsy``,
    QR with column pivoting). A cutoff of ``eps`` (SciPy's default) keeps round-off's own
    singular values: a box's four coplanar corners give ``J`` a null space whose computed
    singular values are 2e-16 to 4e-16 of the largest, about half of them above ``eps``, so
    the step then depended on round-off (by 10% to 90% on a tower of boxes, its residual
    no smaller); beyond ``m eps`` there is a clear gap (the least kept is 1e-7 to 1e-3 of
    the largest on the towers, the wall and Go2's landings), where ``gelsy`` and ``gelsd``
    (the SVD) agree to 1e-10 at half the cost."""
    if sp.issparse(jac):
        # shifted by 1e-10 of its scale, so that a singular J (redundant contacts: a stack
        # of boxes) factorizes at once: the step's part in J's range is then exact to
        # round-off and its null part small (one factorization a step, not a failed one first)
        shift = 1e-10 * max(float(abs(jac).max()), 1.0)
        try:
            d = spla.splu((jac + shift * sp.identity(jac.shape[0])).tocsc()).solve(rhs)
        except RuntimeError:
            return None, singular
        return (np.asarray(d) if np.isfinite(d).all() else None), singular
    if not singular and kernels.general_square(jac):
        d = _lu_step(jac, rhs)  # scipy.linalg.solve's own calls for a general J
        if d is not None and np.isfinite(d).all():
            return d, False
    elif not singular:
        with warnings.catch_warnings():
            warnings.simplefilter("error", sla.LinAlgWarning)
            try:
                d = sla.solve(jac, rhs, check_finite=False)
                if np.isfinite(d).all():
                    return np.asarray(d), False
            except (sla.LinAlgError, sla.LinAlgWarning):
                pass
    d = _min_norm_step(jac, rhs)
    ok = d is not None and np.isfinite(d).all() and math.isfinite(float(d @ d))
    return (np.asarray(d) if ok else None), True


_EPS = float(np.finfo(float).eps)
_GETRF, _GECON, _GETRS, _LANGE, _GELSY, _GELSY_LWORK = sla.get_lapack_funcs(
    ("getrf", "gecon", "getrs", "lange", "gelsy", "gelsy_lwork"), (np.zeros((1, 1)),)
)
#: dgelsy's workspace by size (its optimal ``lwork``, as scipy.linalg.lstsq queries it).
_GELSY_WORK: dict[int, int] = {}


def _lu_step(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray | None:
    """``J d = rhs`` as ``scipy.linalg.solve`` solves a general ``J`` (its structure detected:
    :func:`carnot.solvers.kernels.general_square`): LAPACK's ``getrf``, the reciprocal
    condition number in the 1-norm ``rcond = 1 / (|J|_1 |J^-1|_1)`` estimated by ``gecon``,
    ``getrs``; None where ``getrf`` finds ``J`` singular or ``rcond < eps`` (where
    ``scipy.linalg.solve`` raises ``LinAlgError`` or warns ``LinAlgWarning``). The same
    calls on the same matrix, so the same step to the last bit, without the wrapper's checks
    and broadcasting (some 30 us of a 40 to 60 us step on 18 to 50 rows).

    >>> _lu_step(np.array([[2.0, 1.0], [1.0, 3.0]]), np.array([3.0, 5.0])).round(12).tolist()
    [0.8, 1.4]
    >>> _lu_step(np.array([[1.0, 2.0], [2.0, 4.0]]), np.array([1.0, 1.0])) is None
    True
    """
    lu, piv, info = _GETRF(jac)
    if info != 0:
        return None
    anorm = float(_LANGE("1", jac))  # |J|_1: the largest column sum of |J|
    rcond, info = _GECON(lu, anorm, norm="1")
    if info < 0 or not rcond >= _EPS:
        return None
    d, info = _GETRS(lu, piv, rhs)
    return np.asarray(d) if info == 0 else None


def _min_norm_step(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray | None:
    """``scipy.linalg.lstsq(J, rhs, cond=m eps, lapack_driver="gelsy")[0]`` (:func:`_step`)
    by the same LAPACK call, its workspace queried once per size: the same numbers, without
    the wrapper (some 40 us a call). None where ``gelsy`` reports an illegal argument.

    >>> _min_norm_step(np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([2.0, 2.0])).round(12).tolist()
    [1.0, 1.0]
    """
    m = jac.shape[0]
    cond = m * _EPS
    if m not in _GELSY_WORK:
        work, info = _GELSY_LWORK(m, m, 1, cond)
        _GELSY_WORK[m] = int(work.real) if info == 0 else max(1, 4 * m + 1)
    _, d, _, _, info = _GELSY(jac, rhs, np.zeros(m, dtype=np.int32), cond, _GELSY_WORK[m],
                              False, False)  # fmt: skip
    return None if info < 0 else np.asarray(d)

"""The simultaneous multiple-impact law: Moreau/Glocker's generalized Newton in contact space.

Every contact that is approaching or closed before the impact (``w_n' <= 0`` to 1e-9 of the
velocity scale) takes part; a contact already separating receives nothing. With
``w'' = w' + G Lambda`` (``G`` the Delassus operator), each taking part obeys

* Signorini-Newton: ``0 <= P_n  ⟂  w_n'' + e w_n' >= 0`` with its own ``e`` (Glocker,
  *Set-Valued Force Laws*, Springer 2001, ch. 7; Moreau 1988), so a closed contact may
  separate with zero impulse;
* Coulomb at impact: stick (``w_t'' = 0`` and ``|P_t| <= mu P_n``) or slip
  (``P_t = -mu P_n w_t'' / |w_t''|``), with the exact circular cone in 3D;
* a contact *told to stick* has ``w_t'' = 0`` whenever it is loaded (no friction bound);

and held bilateral rows end at their target velocity.

**Why this solver.** The problems are small (a body or a few, up to a handful of contacts)
and the issue asks both for round-off complementarity *and* for a verdict on uniqueness. An
iterative solver (projected Gauss-Seidel, Siconos' ``fc3d`` Newton methods, an interior-point
SOCP such as Clarabel) reaches the tolerance it is given, not round-off, and finds one solution
when there may be several. So this module *enumerates the regimes* (each taking-part contact
separates, closes, sticks, or slips, the planar slip on either side): in each regime the law is
a square linear system ``A x = b`` on the free impulses, solved by NumPy's SVD (LAPACK), which
also gives its null space (impulses that are not unique) and its consistency. A regime is an
answer when its inequalities hold (``P_n >= 0``, the Coulomb cone, the slip direction, the
separating contacts' ``w_n'' + e w_n' >= 0``); when its impulses are not unique the
inequalities are sought over the whole family by a linear program (SciPy's HiGHS,
``scipy.optimize.linprog``; the circular cone inscribed by a 32-gon, a sufficient condition,
and where that finds none, the cone itself by cutting planes: :func:`_exact_cones`).
3D slip leaves one unknown angle per slipping contact: the slip direction must be parallel to
the post-impact slip, a small nonlinear system solved by Newton's method with Broyden's
updates (:func:`newton_broyden`, the batch kernel's iteration step for step) from the
predicted, the frictionless and the pre-impact slip directions. Every
regime that holds is kept: answers with different velocities are ``multiple_solutions`` (all
reported), answers with the same velocities but different impulses are
``statically_indeterminate``, no regime holding is ``no_solution``. This is the exhaustive
active-set enumeration that Siconos' ``lcp_enum`` does for LCPs, extended to Coulomb's cone.
Its cost grows as 2^k to 4^k in the number k of contacts taking part: the number of regimes is
bounded (:data:`MAX_REGIMES`), an explicit size limit.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import lapack

from carnot.conventions import RELATIVE_TOLERANCE
from carnot.errors import InputError
from carnot.laws.multiple import regimes
from carnot.laws.multiple.rows import (
    ContactOutcome,
    ContactRows,
    HeldRows,
    MultipleImpactOutcome,
    Regime,
    check_problem,
    contact_residual,
    dissipated_by_row,
    held_residual,
    velocity_scale,
)
from carnot.laws.multiple.smoothing import regime_of, smoothed_impulses

if TYPE_CHECKING:  # (SciPy's optimize is imported where a family of several dimensions is met)
    from carnot.laws.multiple.energy_range import EnergyRange

#: The most regimes one problem may enumerate (e.g. 4^6 planar frictional contacts).
MAX_REGIMES = 4096

#: Uniqueness is verified by default up to this many regimes and this many 3D frictional
#: contacts taking part (each 3D slip regime costs a nonlinear solve).
VERIFY_UP_TO = 64
VERIFY_SPATIAL_UP_TO = 2

#: A contact's kind by name, and its option codes by name (:mod:`~carnot.laws.multiple.
#: regimes`, the regimes' one statement, which the batch kernel compiles).
_KIND_CODES = {"frictionless": regimes.FRICTIONLESS_KIND, "planar": regimes.PLANAR,
               "spatial": regimes.SPATIAL, "told_to_stick": regimes.TOLD_TO_STICK}  # fmt: skip
_OPTION_CODES = {name: code for code, name in enumerate(regimes.OPTION_NAMES)}


def _options_of(kind: int) -> tuple[str, ...]:
    out = np.zeros(4, dtype=np.int64)
    return tuple(regimes.OPTION_NAMES[o] for o in out[: regimes.regime_options(kind, out)])


#: The regimes each kind of contact may be in, the most common first (so that the first
#: answer found is usually the one that holds): :func:`~carnot.laws.multiple.regimes.
#: regime_options`.
_OPTIONS: dict[str, tuple[str, ...]] = {name: _options_of(code)
                                        for name, code in _KIND_CODES.items()}  # fmt: skip

_POLYGON = 32  # sides of the polygon inscribed in the circular cone for the linear program
# A regime's inequalities may be violated by this much (relative to the velocity scale):
# round-off in the linear solve, several orders below any physical velocity.
_FEASIBILITY = 1e-9


_EPS = float(np.finfo(float).eps)


_LWORK: dict[tuple[int, int], tuple[int, int]] = {}  # dgelsd's workspace sizes by shape


def _norm(x: np.ndarray) -> float:
    """``float(numpy.linalg.norm(x))`` of a contiguous float vector: its own formula,
    ``sqrt(x . x)``, without its checks (a few microseconds a call, on 2-vectors).

    >>> _norm(np.array([3.0, 4.0]))
    5.0
    """
    return math.sqrt(float(x.dot(x)))


def _lstsq(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``numpy.linalg.lstsq(a, b, rcond=None)[0]``: the minimum-norm least squares solution,
    singular values below ``eps * max(m, n)`` of the largest cut, by the same LAPACK driver
    (``dgelsd``) called directly (NumPy's wrapper costs most of a small solve: about 20 of
    25 us at n = 4, and a 3D slip regime's angle search makes a dozen such solves). The same
    numbers to the last bit (checked on rank-deficient 12 x 6 systems).

    >>> _lstsq(np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([2.0, 2.0])).round(12).tolist()
    [1.0, 1.0]
    >>> a = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]); b = np.array([1.0, 2.0, 0.0])
    >>> bool(np.array_equal(_lstsq(a, b), np.linalg.lstsq(a, b, rcond=None)[0]))
    True
    """
    m, n = a.shape if a.ndim == 2 else (0, 0)
    if m == 0 or n == 0 or b.shape != (m,):
        return np.linalg.lstsq(a, b, rcond=None)[0]
    return _lstsq_of(m, n)(a, b)


def _lstsq_of(m: int, n: int) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """:func:`_lstsq` for ``m x n`` systems (``m, n >= 1``, ``b`` of ``m`` entries), its
    workspace looked up once: a slip regime's angle search solves some twenty systems of one
    shape, and the shape's checks and the workspace's lookup were a tenth of each
    evaluation. The same LAPACK call on the same arguments: the same numbers.

    >>> a = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]); b = np.array([1.0, 2.0, 0.0])
    >>> bool(np.array_equal(_lstsq_of(3, 2)(a, b), np.linalg.lstsq(a, b, rcond=None)[0]))
    True
    """
    if (m, n) not in _LWORK:
        work, iwork, info = lapack.dgelsd_lwork(m, n, 1, -1.0)
        _LWORK[m, n] = (int(work), int(iwork)) if info == 0 else (0, 0)
    lwork, liwork = _LWORK[m, n]
    cutoff = _EPS * max(m, n)
    dgelsd = lapack.dgelsd
    pad = np.zeros(n - m) if m < n else None

    def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        if lwork:
            # (dgelsd's right-hand side holds max(m, n) rows, the solution's n)
            x, _, _, info = dgelsd(a, b if pad is None else np.concatenate([b, pad]),
                                   lwork, liwork, cutoff)  # fmt: skip
            if info == 0:
                return x[:n]
        return np.linalg.lstsq(a, b[:m], rcond=None)[0]  # (no workspace, or no convergence)

    return solve


def _svd(a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``numpy.linalg.svd(a)`` (``u``, ``s``, ``vt``, full matrices) by the same LAPACK driver
    (``dgesdd``) called directly: the same numbers to the last bit, without NumPy's wrapper
    (a fifth of a 12 x 12 decomposition).

    >>> a = np.array([[2.0, 1.0], [1.0, 2.0]])
    >>> all(np.array_equal(x, y) and x.flags.c_contiguous for x, y in zip(_svd(a),
    ...                                                                np.linalg.svd(a)))
    True
    """
    if a.size:
        u, s, vt, info = lapack.dgesdd(a)
        if info == 0:
            # in NumPy's layout (C order; LAPACK's is Fortran's): the products taken with
            # them then sum in the same order, to the same bits
            return np.ascontiguousarray(u), s, np.ascontiguousarray(vt)
    return tuple(np.linalg.svd(a))  # type: ignore[return-value]  # (empty, or no convergence)


@dataclass(frozen=True, kw_only=True, eq=False)
class _Candidate:
    """One regime that holds: its pattern, row impulses and post-impact row velocities."""

    pattern: tuple[str, ...]
    impulses: np.ndarray
    w_after: np.ndarray
    not_unique: bool  # impulses not unique within this regime, velocities unique
    continuum: bool  # a family of different velocities within this regime
    # each contact's residual (contact_residual, taking part where the pattern is not "out")
    # and the held rows', as the regime's test computed them, for the outcome to report
    residuals: tuple[float, ...]
    # over a continuum: the least and the most E_d (J) of the family's members, where known
    # (:func:`dissipated_range`); None otherwise
    dissipated_range: tuple[float, float] | None = None
    # the same bracketed (:func:`dissipated_bounds`): (a bound below the least, the least
    # attained, the most attained, a bound above the most); equal pairs where exact
    dissipated_bounds: tuple[float, float, float, float] | None = None


def resolve_simultaneous(
    delassus: object,
    w_before: object,
    contacts: Sequence[ContactRows],
    held: HeldRows | None = None,
    *,
    verify: bool | None = None,
    closed: Sequence[bool] | None = None,
    checked: bool = False,
) -> MultipleImpactOutcome:
    """Solve the simultaneous law; row impulses ``Lambda`` (N s) with ``w'' = w' + G Lambda``.

    ``checked``: ``delassus`` and ``w_before`` are the float arrays that
    :func:`~carnot.laws.multiple.rows.check_problem` returned for these contacts' rows (the
    caller checked them: :func:`carnot.solvers.resolve`), used as they are (checked again,
    they come out the same numbers).

    ``closed`` (one per contact): contacts that take part even though they separate before
    the impact (``w_n' > 0``: they may carry an impulse where the others would drive them in;
    restitution acting on approach only, their ``e`` must then be 0, which the caller,
    :func:`carnot.solvers.resolve`, sees to). By default a contact takes part when it
    approaches or is at rest (``w_n' <= 0`` to 1e-9 of the velocity scale).

    ``delassus`` is ``G`` (m x m, 1/kg), ``w_before`` the pre-impact row velocities (m/s).
    Uniqueness (``verify``; by default verified when the problem is small: at most
    :data:`VERIFY_UP_TO` regimes and :data:`VERIFY_SPATIAL_UP_TO` contacts with 3D friction,
    whose slip regimes each need a nonlinear solve): without Coulomb friction the law is a monotone
    complementarity problem (``G`` positive semi-definite), whose solutions all share the same
    velocities (Cottle, Pang and Stone, *The Linear Complementarity Problem*, 1992, thm 3.1.7),
    so the first regime that holds is the answer, and its impulses are checked for uniqueness
    over every regime with the same velocities. With Coulomb friction there is no such theorem
    (several outcomes, or none, do occur): every regime is tried. Unverified, the regimes are
    tried most likely first (predicted from the impulses that closing every contact would
    need: every contact closed, the predicted regime with its 3D sticking contacts slipping,
    the predicted regime, then the others by the number of contacts whose regime differs from the
    first of these, fewest first; a contact predicted to separate is put back slipping before
    sticking where sticking everywhere would overload the cones) and the first that holds is
    returned, with
    ``extra["uniqueness_verified"] = 0``. A family of impulses (a regime whose impulses are not
    unique) is tested against the 3D cones exactly: by their inscribed 32-gons first (a
    sufficient test, one linear program), and where those hold no impulse, by the cones
    themselves (Kelley's cutting planes from the circumscribed 32-gons, :func:`_exact_cones`),
    so that the regimes' order alone decides which holds first.

    Three balls in a row, the first at 1 m/s into two touching ones, e = 0: all three leave
    together at 1/3 m/s (rows: approach velocities of the two contacts, ``G = [[2,-1],[-1,2]]``
    for unit masses).

    >>> out = resolve_simultaneous([[2.0, -1.0], [-1.0, 2.0]], [-1.0, 0.0],
    ...                            [ContactRows(normal=0), ContactRows(normal=1)])
    >>> np.round(out.impulses, 12).tolist(), out.flags
    ([0.666666666667, 0.333333333333], ())
    """
    contacts = tuple(contacts)
    if checked:
        g, w = np.asarray(delassus, dtype=float), np.asarray(w_before, dtype=float)
    else:
        g, w = check_problem(delassus, w_before, contacts, held)
    scale = velocity_scale(w, held)
    tol = RELATIVE_TOLERANCE * scale
    takes_part = tuple(bool(w[c.normal] <= tol) or (closed is not None and bool(closed[k]))
                       for k, c in enumerate(contacts))  # fmt: skip
    part = [i for i, t in enumerate(takes_part) if t]
    options = [_OPTIONS[contacts[i].kind] for i in part]
    count = math.prod(len(o) for o in options)
    if count > MAX_REGIMES:
        raise InputError(
            "contacts",
            f"at most {MAX_REGIMES} regimes can be enumerated by the simultaneous law "
            f"({len(part)} contacts taking part give {count})",
            len(part),
        )
    # (contacts told to stick are not monotone: loaded they hold any tangential impulse,
    # unloaded none, a set that is not convex; several sticking answers do occur, a humanoid's
    # two feet landing among them, so they are searched like frictional ones)
    monotone = all(contacts[i].kind == "frictionless" for i in part)
    if verify is None:
        spatial = sum(contacts[i].kind == "spatial" for i in part)
        verify = count <= VERIFY_UP_TO and spatial <= VERIFY_SPATIAL_UP_TO
    first_only = monotone or not verify
    ordered, predicted, overloaded = _predict(g, w, contacts, held, part, options, scale)
    # every contact closed (sticking where it can) first, the predicted regime next, the rest;
    # the predicted ones first when sticking needs more tangential impulse in all than the
    # friction can give in all (the closed regime would then fail, after a linear program)
    base = tuple(o[0] for o in options)
    guess = tuple(o[0] for o in ordered)
    # and the predicted regime with its 3D sticking contacts slipping, tried before it: where
    # some contact slips or separates, the others rarely all stick (a box landing on four
    # corners with one lifting: the other three slip, where the prediction had one or two
    # sticking), and a regime mixing 3D stick and slip is the dearest to try (its family of
    # impulses needs a linear program at every slip direction found)
    slid = tuple("slip" if option == "stick" and contacts[i].kind == "spatial" else option
                 for i, option in zip(part, guess, strict=True))
    first = [slid, guess, base] if overloaded else [base, slid, guess]
    # the rest nearest the predicted regime (slid) first: fewest contacts in another regime;
    # among equals, fewest of those that slid does not separate (itertools.product's order
    # among equals). A prediction is usually wrong in one or two contacts: a box landing with
    # one corner lifting is often predicted with two lifting (the closed regime's least-norm
    # impulses pull on a whole edge), so putting a predicted separation back comes first.
    # With more than VERIFY_UP_TO regimes the first that holds is the answer, so this order
    # is the law's documented choice where several hold (carnot.batch.multi_kernel: the same
    # order).
    #
    # A regime holds where some impulses of its family lie in the cones themselves: tested
    # exactly in this one pass (by the inscribed polygons first, then by cutting planes only
    # where those fail: a box landing flat and sticking with its corners' friction almost
    # used up). A pass by the polygons alone would pass over such a regime for a later one,
    # or try every regime and then all again (the batch kernel must then repeat that first
    # pass, slip roots and all): the order above, not the polygons' gap, decides.
    candidates: list[_Candidate] = []
    # contacts proved never to separate (the dissipation bound): their separating regimes
    # hold no answer, so skipping them leaves the answers found, in their order, as they were
    # (proved at the first regime that separates one: the first regimes often hold)
    held_shut: list[int] | None = None
    excluded: dict[tuple[int, ...], bool] = {}  # separated together: proved to hold no answer
    for choice in itertools.chain(dict.fromkeys(first),
                                  _nearest_first(ordered, slid, (base, guess, slid))):
        if "separate" in choice:
            if held_shut is None:
                shut = never_separate(g, w, contacts, held, part, scale)
                held_shut = [k for k, i in enumerate(part) if i in shut]
            if any(choice[k] == "separate" for k in held_shut):
                continue
            if "slip" in choice:
                # (a slip regime's root search costs 0.3 to 2 ms, this bound some 50 us: the
                # contacts it separates together, each set proved once)
                apart = tuple(i for i, o in zip(part, choice, strict=True) if o == "separate")
                if len(apart) > 1:
                    if apart not in excluded:
                        excluded[apart] = bool(shut_when_separated(g, w, contacts, held, part,
                                                                   apart, scale))  # fmt: skip
                    if excluded[apart]:
                        continue
        if "slip" in choice and regime_ruled_out(g, w, contacts, held, part, choice, scale):
            # (the regime's own equalities in the bound: some 100 us, where the slip
            # regime's root search costs 0.3 to 2 ms)
            continue
        pattern = ["out"] * len(contacts)  # "out": not taking part (separating before)
        for i, option in zip(part, choice, strict=True):
            pattern[i] = option
        candidates.extend(_solve_regime(g, w, contacts, held, tuple(pattern), scale,
                                        predicted, first_only))
        if candidates and first_only:
            break
    # No regime found where 3D slip takes part: the slip angles' roots may have been missed
    # (MINPACK from a few starts), though an answer exists. A start from the smoothed law
    # (carnot.laws.multiple.smoothing) names the regime and its slip directions, solved exactly.
    # Uniqueness is then unverified: the enumeration missed this answer, it may miss others.
    seeded = False
    if not candidates and any(contacts[i].kind == "spatial" for i in part):
        candidates = _seeded(g, w, contacts, held, takes_part, scale)
        seeded = bool(candidates)
    candidates = [_widest(g, w, contacts, held, c, scale) for c in candidates]
    verified = (verify or monotone) and not seeded
    return _outcome(g, w, contacts, held, takes_part, candidates, scale, verified)


#: The dissipation bound's margins: the ellipsoid widened by this much of its depth, and the
#: bound of ``u_n`` this far below zero (of the velocity scale) before a contact is proved
#: never to separate; the answers hold to ``_FEASIBILITY`` (1e-9), three orders tighter.
NEVER_SEPARATE_MARGIN = 1e-6


def never_separate(
    g: np.ndarray,
    w: np.ndarray,
    contacts: Sequence[ContactRows],
    held: HeldRows | None,
    part: Sequence[int],
    scale: float,
) -> frozenset[int]:
    """The contacts of ``part`` (indices into ``contacts``, those taking part) that separate
    in no answer of the law, proved by its dissipation: a sufficient condition, so a contact
    not listed may still never separate.

    At every answer each contact's impulse does no positive work on its velocity
    ``u = W r + q`` (``W = G`` on the taking-part contacts' rows and the held rows, ``q =
    w'`` there with ``e w_n'`` added on the normals and the targets taken off the held
    rows): ``r_k . u_k = 0`` closed, sticking, separated (``r_k = 0``) and held, and ``-mu
    r_n |u_t| <= 0`` slipping. So ``r^T (W r + q) <= 0``. With contact ``j`` separated
    (``r_j = 0``) the others' impulses ``x`` lie in the ellipsoid ``x^T H x + b^T x <= 0``
    (``H = W_VV``, ``b = q_V``, ``V`` the other rows): centre ``c = -H^-1 b / 2``, and
    ``(x - c)^T H (x - c) <= rho^2 = b^T H^-1 b / 4``. Over it, ``j``'s normal velocity
    ``u_nj = q_nj + a . x`` (``a = W_{n_j, V}``) is at most

        q_nj + a . c + rho sqrt(a^T H^-1 a)     (m/s)

    (Cauchy-Schwarz in the metric of ``H``). Where that, with ``rho^2`` widened by
    :data:`NEVER_SEPARATE_MARGIN` of itself, is below ``-NEVER_SEPARATE_MARGIN scale``, the
    separation's ``u_nj >= 0`` cannot hold: ``j`` never separates. ``H`` must be positive
    definite (its Cholesky pivots above 1e-12 of its largest diagonal entry); where it is
    not, ``j`` is not listed (the enumeration tries its separating regimes, as before).

    Two frictionless rows coupled by ``G = [[1, -1], [-1, 2]]``, row 0 approaching at 1 m/s
    and row 1 at rest: nothing can open row 0 (row 1's impulse only pushes it in), so it
    never separates; row 1 may (it does, with zero impulse, where row 0 takes the blow).

    >>> g, w = np.array([[1.0, -1.0], [-1.0, 2.0]]), np.array([-1.0, 0.0])
    >>> sorted(never_separate(g, w, [ContactRows(normal=0), ContactRows(normal=1)], None,
    ...                       [0, 1], 1.0))
    [0]
    """
    return frozenset(j for j in part
                     if shut_when_separated(g, w, contacts, held, part, (j,), scale))  # fmt: skip


def _law_q(w: np.ndarray, contacts: Sequence[ContactRows], part: Sequence[int],
           held: HeldRows | None) -> tuple[np.ndarray, list[int]]:  # fmt: skip
    """The velocities the law asks to vanish or stay >= 0, ``u = W r + q``: ``q = w'`` with
    each taking-part contact's ``e w_n'`` added to its normal row (De Saxce's form) and the
    held rows' targets taken off; and the held rows."""
    q = w.astype(float).copy()
    for i in part:
        c = contacts[i]
        q[c.normal] += c.restitution * w[c.normal]
    held_rows = list(held.rows) if held is not None else []
    if held is not None:
        q[held_rows] -= np.asarray(held.target, dtype=float)
    return q, held_rows


def shut_when_separated(
    g: np.ndarray,
    w: np.ndarray,
    contacts: Sequence[ContactRows],
    held: HeldRows | None,
    part: Sequence[int],
    separated: Sequence[int],
    scale: float,
) -> frozenset[int]:
    """The contacts of ``separated`` (some of ``part``) proved unable to separate where all
    of ``separated`` carry no impulse: :func:`never_separate`'s bound, with ``V`` the rows of
    the contacts of ``part`` outside ``separated`` and the held rows. Where it lists one, no
    answer separates all of ``separated`` at once (a regime separating them holds none).
    The smaller ``V``, the smaller the ellipsoid (a slice of the larger one), so a contact
    proved for ``(j,)`` is proved for every ``separated`` holding it.

    >>> g, w = np.array([[1.0, -1.0], [-1.0, 2.0]]), np.array([-1.0, 0.0])
    >>> c = [ContactRows(normal=0), ContactRows(normal=1)]
    >>> sorted(shut_when_separated(g, w, c, None, [0, 1], (0, 1), 1.0))
    [0]
    """
    q, held_rows = _law_q(w, contacts, part, held)
    others = sorted(r for i in part if i not in separated
                    for r in (contacts[i].normal, *contacts[i].tangents)) + held_rows  # fmt: skip
    margin = NEVER_SEPARATE_MARGIN * scale
    if not others:  # nothing can push them open: u_nj = q_nj
        return frozenset(j for j in separated if q[contacts[j].normal] < -margin)
    h = g[np.ix_(others, others)]
    try:
        factor = np.linalg.cholesky(h)
    except np.linalg.LinAlgError:
        return frozenset()  # not positive definite: no bound this way
    if float(np.diag(factor).min()) ** 2 <= 1e-12 * float(np.diag(h).max()):
        return frozenset()
    y = np.linalg.solve(factor, q[others])  # L^-1 b: b^T H^-1 b = y . y
    centre = -0.5 * np.linalg.solve(factor.T, y)
    rho = math.sqrt(0.25 * float(y @ y) * (1.0 + NEVER_SEPARATE_MARGIN))
    proved = []
    for j in separated:
        n_j = contacts[j].normal
        a = g[n_j, others]
        bound = float(q[n_j] + a @ centre) + rho * _norm(np.linalg.solve(factor, a))
        if bound < -margin:
            proved.append(j)
    return frozenset(proved)


def regime_ruled_out(
    g: np.ndarray,
    w: np.ndarray,
    contacts: Sequence[ContactRows],
    held: HeldRows | None,
    part: Sequence[int],
    choice: Sequence[str],
    scale: float,
) -> bool:
    """Whether the regime ``choice`` (one option per contact of ``part``, in its order) is
    proved to hold no answer of the law: :func:`never_separate`'s dissipation bound on the
    regime's own slice, a sufficient condition (False proves nothing).

    In the regime every contact of ``part`` that does not separate is shut, ``u_n = 0`` (its
    normal velocity, ``q`` as in :func:`never_separate`), a sticking one entirely, ``u = 0``,
    and held rows end at their targets: linear equalities ``W_EV x = -q_E`` on the impulses
    ``x`` of the rows ``V`` (those contacts' rows and the held rows; the separated ones carry
    none). They cut the ellipsoid ``x^T H x + b^T x <= 0`` (``H = W_VV``, ``b = q_V``) to an
    affine slice: with ``x = x_0 + N z`` (``x_0`` the least-norm solution, ``N`` a basis of
    ``W_EV``'s null space, SVD), ``Q = N^T H N``, ``l = N^T (2 H x_0 + b)``, ``c_0 = x_0^T H
    x_0 + b^T x_0``, the slice is ``(z - z_c)^T Q (z - z_c) <= rho^2`` with ``z_c = -Q^-1 l /
    2`` and ``rho^2 = l^T Q^-1 l / 4 - c_0`` (widened by :data:`NEVER_SEPARATE_MARGIN` of
    ``|c_0| + l^T Q^-1 l / 4``, the two terms it is the difference of). Over it a linear
    ``a . x`` is at most ``a . x_c + rho sqrt(a^T N Q^-1 N^T a)`` (``x_c = x_0 + N z_c``;
    Cauchy-Schwarz in ``Q``'s metric). The regime holds no answer where that bound proves

    * a separated contact's ``u_nj = q_nj + W_{n_j V} x`` below ``-NEVER_SEPARATE_MARGIN
      scale`` (its law needs ``u_nj >= 0``), or
    * a shut contact's ``G_nn P_n`` below it (its law needs ``P_n >= 0``; m/s, as the
      enumeration's own inequalities).

    ``Q`` must be positive definite (its Cholesky pivots above 1e-12 of its largest diagonal
    entry); where it is not, or the equalities are inconsistent (beyond 1e-9 of ``scale``),
    nothing is proved. The bound alone (:func:`shut_when_separated`) is the same without the
    equalities, so it proves less (and nothing about ``P_n``).

    Two frictionless rows, ``G = [[1, -1], [-1, 2]]``, row 0 approaching at 1 m/s, row 1 at
    rest: with row 1 shut, ``u_n1 = -P_0 + 2 P_1 - 0 = 0`` and row 0's ``u_n0 = P_0 - P_1 - 1``;
    separating row 0 leaves ``P_1`` alone, shut at ``P_1 = 0``, so ``u_n0 = -1``: no answer
    separates row 0. Both shut is the answer (``P = (2, 1)``), not ruled out.

    >>> g, w = np.array([[1.0, -1.0], [-1.0, 2.0]]), np.array([-1.0, 0.0])
    >>> c = [ContactRows(normal=0), ContactRows(normal=1)]
    >>> [regime_ruled_out(g, w, c, None, [0, 1], r, 1.0)
    ...  for r in (("separate", "closed"), ("closed", "closed"))]
    [True, False]
    """
    q, held_rows = _law_q(w, contacts, part, held)
    margin = NEVER_SEPARATE_MARGIN * scale
    shut = [i for i, o in zip(part, choice, strict=True) if o != "separate"]
    apart = [contacts[i].normal for i, o in zip(part, choice, strict=True) if o == "separate"]
    others = sorted(r for i in shut for r in (contacts[i].normal, *contacts[i].tangents))
    others += held_rows
    if not others:  # nothing acts: u = q
        return bool(np.any(q[apart] < -margin))
    place = {r: k for k, r in enumerate(others)}
    fixed = [contacts[i].normal for i in shut] + [
        t for i, o in zip(part, choice, strict=True) if o == "stick" for t in contacts[i].tangents
    ] + held_rows  # fmt: skip
    g_v = g[:, others]
    h, b = g_v[others], q[others]
    a_eq, rhs = g_v[fixed], -q[fixed]
    u, s, vt = _svd(a_eq)
    rank = int(np.sum(s > 1e-10 * s[0])) if s.size and s[0] > 0.0 else 0
    x0 = vt[:rank].T @ ((u[:, :rank].T @ rhs) / s[:rank])
    if np.abs(a_eq @ x0 - rhs).max() > _FEASIBILITY * scale:
        return False  # the equalities contradict each other: left to the regime's own solve
    null = vt[rank:].T
    hx0 = h @ x0
    c0 = float(x0 @ hx0 + b @ x0)
    if null.shape[1]:
        quad = null.T @ h @ null
        try:
            factor = np.linalg.cholesky(quad)
        except np.linalg.LinAlgError:
            return False
        if float(np.diag(factor).min()) ** 2 <= 1e-12 * float(np.diag(quad).max()):
            return False
        spread = np.linalg.solve(factor, null.T)  # L^-1 N^T: a^T N Q^-1 N^T a = |L^-1 N^T a|^2
        y = spread @ (2.0 * hx0 + b)  # L^-1 l: l^T Q^-1 l = y . y
        centre = x0 - 0.5 * (spread.T @ y)
        depth = 0.25 * float(y @ y)
    else:  # x fixed by the equalities: the slice is at most the point x_0
        spread, centre, depth = np.zeros((0, len(others))), x0, 0.0
    rho = math.sqrt(max(depth - c0, 0.0) + NEVER_SEPARATE_MARGIN * (abs(c0) + depth))
    if apart:  # u_nj's bound
        a = g_v[apart]
        spread_a = spread @ a.T
        bound = q[apart] + a @ centre + rho * np.sqrt(np.einsum("ij,ij->j", spread_a, spread_a))
        if bool(np.any(bound < -margin)):
            return True
    normals = [contacts[i].normal for i in shut]  # G_nn P_n's bound
    at = [place[n] for n in normals]
    gnn = g[normals, normals]
    reach = np.sqrt(np.einsum("ij,ij->j", spread[:, at], spread[:, at]))
    return bool(np.any(gnn * (centre[at] + rho * reach) < -margin))

def regime_count(
    w_before: np.ndarray, contacts: Sequence[ContactRows], held: HeldRows | None = None,
    closed: Sequence[bool] | None = None,
) -> int:
    """How many regimes :func:`resolve_simultaneous` would enumerate (``closed`` as there):
    the product over the contacts taking part of their regimes (2 frictionless or told to
    stick, 3 with 3D friction, 4 with planar friction).

    >>> regime_count(np.array([-1.0, 0.0, 1.0]), [ContactRows(normal=k) for k in range(3)])
    4
    """
    w = np.asarray(w_before, dtype=float)
    tol = RELATIVE_TOLERANCE * velocity_scale(w, held)
    return math.prod(len(_OPTIONS[c.kind]) for k, c in enumerate(contacts)
                     if w[c.normal] <= tol or (closed is not None and closed[k]))  # fmt: skip


def _seeded(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    takes_part: tuple[bool, ...],
    scale: float,
) -> list[_Candidate]:
    """The answer in the regime of the smoothed law's solution, from its slip directions
    (:mod:`carnot.laws.multiple.smoothing`), or in that regime with its contacts sticking at
    the cone's edge slipping; none where neither holds."""
    impulses = smoothed_impulses(g, w, contacts, held, takes_part, scale)
    if impulses is None:
        return []
    tried = set()
    for edge in (False, True):  # then its sticking contacts at the cone's edge slipping
        pattern, directions = regime_of(g, w, contacts, takes_part, impulses, scale, edge)
        if pattern in tried:
            continue
        tried.add(pattern)
        found = _solve_regime(g, w, contacts, held, pattern, scale, directions,
                              first_only=True, near=impulses)  # fmt: skip
        if found:
            return found
    return []


def _nearest_first(
    ordered: list[tuple[str, ...]], near: tuple[str, ...], skip: tuple[tuple[str, ...], ...]
) -> Iterator[tuple[str, ...]]:
    """Every regime of ``itertools.product(*ordered)`` but ``skip``, those differing from
    ``near`` in fewest contacts first; among equals, those differing in fewest contacts that
    ``near`` does not separate (so a contact ``near`` separates is put back first); then in
    the product's order (lazily: at the first regime asked for, one pass over the product,
    sorted stably by the two counts; the order of a pass per distance and count, which cost
    more from their second on, and every enumeration made at least two, the first yielding
    only ``near``, which is skipped).

    >>> [''.join(c) for c in _nearest_first([("a", "b"), ("a", "b")], ("a", "a"), ())]
    ['aa', 'ab', 'ba', 'bb']
    >>> [' '.join(c) for c in _nearest_first([("slip", "separate"), ("separate", "slip")],
    ...                                      ("slip", "separate"), ())]
    ['slip separate', 'slip slip', 'separate separate', 'separate slip']
    """

    def counts(choice: tuple[str, ...]) -> tuple[int, int]:
        changed = [b for a, b in zip(choice, near, strict=True) if a != b]
        return len(changed), sum(b != "separate" for b in changed)

    # (a generator: nothing is sorted where the first three regimes hold the answer)
    yield from sorted((c for c in itertools.product(*ordered) if c not in skip), key=counts)


def _predict(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    part: list[int],
    options: list[tuple[str, ...]],
    scale: float,
) -> tuple[list[tuple[str, ...]], dict[int, np.ndarray], bool]:
    """Order each contact's regimes most likely first, from the impulses (least squares) that
    closing every taking-part contact, sticking where it can, would need
    (:func:`carnot.laws.multiple.regimes.predicted_order`: a pull means it separates;
    outside the cone means it slips, opposite to that tangential impulse). Returns also the
    predicted 3D slip directions and whether the contacts are overloaded (their tangential
    impulses need more than their cones hold, in sum)."""
    closed = ["out"] * len(contacts)
    for i, opts in zip(part, options, strict=True):
        closed[i] = opts[0]
    b_matrix, rows, targets = _columns(len(w), contacts, held, tuple(closed), w, {})
    if not rows:
        return options, {}, False
    x = _lstsq(g[rows] @ b_matrix, targets - w[rows])
    impulses = b_matrix @ x
    # the order by regimes.predicted_order (the batch kernel's own), on the contacts' arrays
    k = len(contacts)
    nrow, trow, ntan, mu, _, kinds = _layout(contacts)
    taking = np.zeros(k, dtype=bool)
    taking[part] = True
    nopt = np.zeros(k, dtype=np.int64)
    codes = np.zeros((k, 4), dtype=np.int64)
    for i, names in zip(part, options, strict=True):
        nopt[i] = len(names)
        codes[i, : len(names)] = [_OPTION_CODES[name] for name in names]
    order = np.zeros((k, 4), dtype=np.int64)
    directions = np.zeros((k, 2))
    has_direction = np.zeros(k, dtype=bool)
    overloaded = regimes.predicted_order(g, nrow, trow, ntan, kinds, mu, taking, nopt, codes,
                                         order, directions, has_direction, impulses, scale)
    ordered = [tuple(regimes.OPTION_NAMES[o] for o in order[i, : nopt[i]]) for i in part]
    predicted = {i: directions[i].copy() for i in part if has_direction[i]}
    return ordered, predicted, bool(overloaded)


def _widest(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    cand: _Candidate,
    scale: float,
) -> _Candidate:
    """The same answer in its widest regime (:func:`carnot.laws.multiple.regimes.
    widest_pattern`: every separating contact whose law holds with equality, ``w_n'' + e
    w_n' = 0``, so it could carry an impulse, closed, sticking or slipping as its
    post-impact tangential velocity says). The impulses of the answer are not unique when
    they are not unique in that regime (a box landing flat on four corners found with three
    of them loaded)."""
    k = len(contacts)
    nrow, trow, ntan, _, e, kinds = _layout(contacts)
    codes = _codes(cand.pattern)
    wide_codes = np.zeros(k, dtype=np.int64)
    dirs = np.zeros((k, 2))
    if not regimes.widest_pattern(nrow, trow, ntan, kinds, e, w, cand.w_after, codes,
                                  RELATIVE_TOLERANCE * scale, wide_codes, dirs):  # fmt: skip
        return cand
    wide = [regimes.OPTION_NAMES[o] for o in wide_codes]
    directions = {i: dirs[i].copy() for i in range(k) if wide_codes[i] == regimes.SLIP_OPT}
    wider = _linear_regime(g, w, contacts, held, tuple(wide), directions, scale)
    if wider is None or not (wider.not_unique or wider.continuum):
        return cand
    if wider.continuum or np.abs(wider.w_after - cand.w_after).max() > 1e-8 * scale:
        value = _dissipated(cand, w)
        span = _joined(wider.dissipated_range, value) if wider.continuum else (
            _joined((_dissipated(wider, w),) * 2, value))  # fmt: skip
        bounds = _joined_bounds(wider.dissipated_bounds, value) if wider.continuum else (
            _joined_bounds((_dissipated(wider, w),) * 4, value))  # fmt: skip
        return _Candidate(pattern=cand.pattern, impulses=cand.impulses, w_after=cand.w_after,
                          not_unique=cand.not_unique, continuum=True,
                          residuals=cand.residuals, dissipated_range=span,
                          dissipated_bounds=bounds)  # fmt: skip
    # the same velocities: report the widest regime and its least-norm impulses (a box
    # landing flat gets the same impulse at its four corners, not one corner left at zero)
    return wider


def _outcome(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    takes_part: tuple[bool, ...],
    candidates: list[_Candidate],
    scale: float,
    verified: bool,
) -> MultipleImpactOutcome:
    """Group the regimes that hold by their velocities and build the reported outcome."""
    if not candidates:
        zero = np.zeros_like(w)
        pattern = tuple("out" for _ in contacts)
        return _build(g, w, contacts, held, takes_part, pattern, zero, ("no_solution",), verified)
    # grouped by their velocities, each group's verdict: regimes.answer_groups and
    # group_verdict (the batch kernel's own)
    cand_imp = np.array([c.impulses for c in candidates])
    cand_wa = np.array([c.w_after for c in candidates])
    not_unique = np.array([c.not_unique for c in candidates])
    continuum = np.array([c.continuum for c in candidates])
    count, tol = len(candidates), 1e-8 * scale
    firsts = regimes.answer_groups(cand_wa, count, tol)
    outcomes = []
    for f in (j for j in range(count) if (firsts >> j) & 1):
        indeterminate, multiple = regimes.group_verdict(cand_imp, cand_wa, not_unique,
                                                        continuum, count, f, firsts, tol, 1e-8)
        flags = [name for name, set_ in (("statically_indeterminate", indeterminate),
                                         ("multiple_solutions", multiple)) if set_]  # fmt: skip
        first = candidates[f]
        outcomes.append(
            _build(g, w, contacts, held, takes_part, first.pattern, first.impulses, tuple(flags),
                   verified, first)
        )
    span = _span(candidates, w)
    if span is not None:  # (the least and the most E_d over every answer: DESIGN.md section 9)
        outcomes[0] = dataclasses.replace(outcomes[0], extra={
            **outcomes[0].extra, "dissipated_min": span[0], "dissipated_max": span[1]})
    else:
        bounds = _bounds(candidates, w)
        if bounds is not None:  # bracketed only: a family of cones in several dimensions
            outcomes[0] = dataclasses.replace(outcomes[0], extra={
                **outcomes[0].extra, **dict(zip(BOUNDS_KEYS, bounds, strict=True))})
    primary = outcomes[0]
    if len(outcomes) == 1:
        return primary
    return MultipleImpactOutcome(
        law=primary.law,
        impulses=primary.impulses,
        w_before=primary.w_before,
        w_after=primary.w_after,
        contacts=primary.contacts,
        residual=primary.residual,
        flags=primary.flags,
        alternatives=tuple(outcomes[1:]),
        extra=primary.extra,
    )


def _build(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    takes_part: tuple[bool, ...],
    pattern: tuple[str, ...],
    impulses: np.ndarray,
    flags: tuple[str, ...],
    verified: bool = True,
    cand: _Candidate | None = None,
) -> MultipleImpactOutcome:
    """The outcome of one answer: per-contact regimes, impulses and residuals. ``cand``: the
    regime's answer that ``impulses`` are, whose velocities and residuals (computed by its
    test, :func:`_linear_regime`, with the same formulas) are reported as they are."""
    w_after = w + g @ impulses if cand is None else cand.w_after
    # its residuals where the contacts taking part are those of its pattern (always, for the
    # patterns the enumeration makes: "out" is exactly the contacts not taking part)
    known = cand is not None and all(
        (option != "out") == part for option, part in zip(pattern, takes_part, strict=True)
    )
    residuals = cand.residuals if known and cand is not None else (
        *[contact_residual(c, g, impulses, w, w_after, takes_part=part)
          for c, part in zip(contacts, takes_part, strict=True)],
        held_residual(held, w_after))  # fmt: skip
    results: list[ContactOutcome] = []
    extra_flags = list(flags)
    tol = RELATIVE_TOLERANCE * velocity_scale(w, held)
    for c, option, part in zip(contacts, pattern, takes_part, strict=True):
        regime: Regime
        if option in ("separate", "out"):
            regime = "separate"
        elif option == "closed":
            regime = "frictionless"
        elif option == "stick":
            regime = "stick"
        else:
            regime = "slip"
        p_n = float(impulses[c.normal])
        p_t = tuple(float(impulses[t]) for t in c.tangents)
        if (
            not part
            and w_after[c.normal] < -tol
            and "separating_contact_approaches" not in extra_flags
        ):
            extra_flags.append("separating_contact_approaches")
        if (
            c.stick
            and c.friction > 0.0
            and math.hypot(*p_t) > c.friction * p_n * (1.0 + RELATIVE_TOLERANCE)
            and "friction_too_small_to_stick" not in extra_flags
        ):
            extra_flags.append("friction_too_small_to_stick")
        results.append(
            ContactOutcome(
                active=regime != "separate",
                regime=regime,
                impulse_normal=p_n,
                impulse_tangent=p_t,
                residual=residuals[len(results)],
            )
        )
    residual = max(residuals)
    return MultipleImpactOutcome(
        law="simultaneous",
        impulses=impulses,
        w_before=w,
        w_after=w_after,
        contacts=tuple(results),
        residual=residual,
        flags=tuple(extra_flags),
        extra={"uniqueness_verified": float(verified)},
    )


#: The layouts of the contact tuples met lately, by identity (:func:`_layout`).
_LAYOUTS: dict[int, tuple[tuple[ContactRows, ...], tuple[np.ndarray, ...]]] = {}


def _layout(contacts: tuple[ContactRows, ...]) -> tuple[np.ndarray, ...]:
    """The contacts' rows as the regimes' arrays (:mod:`~carnot.laws.multiple.regimes`):
    ``(nrow, trow, ntan, mu, e, kinds)``, read-only (absent tangent rows -1). Kept by the
    tuple's identity (one problem hands the same tuple to every regime it tries; hashing
    its contacts cost more than the arrays), the tuple held beside them so that its
    identity stays its own."""
    hit = _LAYOUTS.get(id(contacts))
    if hit is not None and hit[0] is contacts:
        return hit[1]
    nrow = np.array([c.normal for c in contacts], dtype=np.int64)
    trow = np.full((len(contacts), 2), -1, dtype=np.int64)
    for i, c in enumerate(contacts):
        trow[i, : len(c.tangents)] = c.tangents
    ntan = np.array([len(c.tangents) for c in contacts], dtype=np.int64)
    mu = np.array([c.friction for c in contacts], dtype=float)
    e = np.array([c.restitution for c in contacts], dtype=float)
    kinds = np.array([_KIND_CODES[c.kind] for c in contacts], dtype=np.int64)
    arrays = (nrow, trow, ntan, mu, e, kinds)
    for a in arrays:
        a.setflags(write=False)
    if len(_LAYOUTS) >= 64:
        _LAYOUTS.clear()
    _LAYOUTS[id(contacts)] = (contacts, arrays)
    return arrays


def _view(a: np.ndarray) -> memoryview:
    """A memoryview of ``a``'s entries, for the regimes' loops run as Python: they index
    it as Python floats at about half the cost of a NumPy array's scalar indexing (the
    6-contact planar enumeration 33 -> 31 ms); ``a`` itself where NumPy has no buffer to
    give (strides a buffer cannot hold)."""
    try:
        return a.data
    except (ValueError, BufferError):
        return a  # type: ignore[return-value]


def _codes(pattern: tuple[str, ...]) -> np.ndarray:
    """A regime's options by name as the regimes' codes (:data:`~carnot.laws.multiple.
    regimes.OPTION_NAMES`)."""
    return np.array([_OPTION_CODES[o] for o in pattern], dtype=np.int64)


def _direction_rows(k: int, slip_directions: dict[int, np.ndarray]) -> np.ndarray:
    """The 3D slip directions by contact as the regimes' ``(k, 2)`` array (zero where
    none)."""
    dirs = np.zeros((k, 2))
    for i, d in slip_directions.items():
        dirs[i] = d
    return dirs


def _columns(
    m: int,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    pattern: tuple[str, ...],
    w: np.ndarray,
    slip_directions: dict[int, np.ndarray],
) -> tuple[np.ndarray, list[int], np.ndarray]:
    """The regime's unknowns: ``Lambda = B x``; the rows whose post-impact velocity it fixes,
    and their targets ``w''_R`` (m/s): the held rows' columns first, then the contacts',
    by :func:`carnot.laws.multiple.regimes.regime_columns` (the batch kernel's own)."""
    nrow, trow, ntan, mu, e, _ = _layout(contacts)
    h = len(held.rows) if held is not None else 0
    # B in Fortran order: its columns contiguous (the layout the linear algebra met before)
    b = np.zeros((m, h + m), order="F")
    rows = np.zeros(h + m, dtype=np.int64)
    targets = np.zeros(h + m)
    if held is not None:
        for j, (r, target) in enumerate(zip(held.rows, held.target, strict=True)):
            b[r, j] = 1.0
            rows[j] = r
            targets[j] = target
    q, _ = regimes.regime_columns(m, nrow, trow, ntan, mu, e, _codes(pattern), w,
                                  _direction_rows(len(contacts), slip_directions),
                                  _view(b[:, h:]), _view(rows[h:]),
                                  _view(targets[h:]))  # fmt: skip
    q += h
    return b[:, :q], rows[:q].tolist(), targets[:q].copy()


def _solve_regime(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    pattern: tuple[str, ...],
    scale: float,
    predicted: dict[int, np.ndarray] | None = None,
    first_only: bool = False,
    near: np.ndarray | None = None,
) -> list[_Candidate]:
    """The answers of one regime (none, or one; 3D slip may give several). ``predicted``:
    slip directions to try first; ``first_only``: stop at the first answer.

    ``near``: row impulses near an answer (the smoothed law's, with ``predicted`` its slip
    directions). Where the regime's impulses form a family at those directions (a box flat on
    four corners: its normal impulses are not unique, and with friction neither are its
    velocities), the family's member is pinned near them (``N^T x = N^T x_near``, ``N`` the
    family's directions there) rather than taken least-norm, which may hold no answer."""
    slipping = [i for i, o in enumerate(pattern) if o == "slip"]
    if not slipping:
        cand = _linear_regime(g, w, contacts, held, pattern, {}, scale, near=near)
        return [] if cand is None else [cand]
    # The regime's matrices once; only the slip columns' tangent entries depend on the angles.
    zero = {i: np.zeros(2) for i in slipping}
    b_base, rows, targets = _columns(len(w), contacts, held, pattern, w, zero)
    rhs = targets - w[rows]
    columns = [int(np.flatnonzero(b_base[contacts[i].normal])[0]) for i in slipping]
    t1s = [contacts[i].tangents[0] for i in slipping]
    t2s = [contacts[i].tangents[1] for i in slipping]
    mus = np.array([contacts[i].friction for i in slipping])
    # A = G_R B and the slipping rows' w'' = w' + G_T B x are linear in each slip column's
    # (cos, sin): their fixed parts and the parts along each slip column's tangents once
    a_base = g[rows] @ b_base
    a_1, a_2 = g[rows][:, t1s], g[rows][:, t2s]  # (q, slipping)
    tangent_rows = t1s + t2s
    w_base = g[tangent_rows] @ b_base  # (2 slipping, q)
    w_1, w_2 = g[tangent_rows][:, t1s], g[tangent_rows][:, t2s]
    w_t = w[tangent_rows]
    ns = len(slipping)
    pin = _pin(g, w, contacts, held, pattern, rows, predicted, near)
    neg_mus = -mus
    # where the slip columns are the first columns in order (every contact slipping), the
    # update is a sum, not a fancy-indexed one (several microseconds of each evaluation)
    every = columns == list(range(a_base.shape[1]))
    # (as an index array, made once: a list is converted at every fancy index, a quarter of
    # an evaluation's cost on 4 x 4 systems; the same elements, the same numbers)
    at_columns = np.array(columns, dtype=np.intp)

    def system(cos: np.ndarray, sin: np.ndarray) -> np.ndarray:
        # A = G_R B at the slip columns' tangents cos, sin: -mu (cos, sin) of the angles
        if every:
            return a_base + (a_1 * cos + a_2 * sin)
        a = a_base.copy()
        a[:, at_columns] += a_1 * cos + a_2 * sin
        return a

    solve = _lstsq_of(*a_base.shape) if a_base.size else _lstsq  # (one shape: the regime's)

    def impulses_of(angles: np.ndarray, cos: np.ndarray, sin: np.ndarray) -> np.ndarray:
        a = system(cos, sin)
        if pin is None:
            return solve(a, rhs)
        return np.linalg.lstsq(np.vstack([a, pin[0]]), np.concatenate([rhs, pin[1]]),
                               rcond=None)[0]  # fmt: skip

    def parallel(angles: np.ndarray) -> np.ndarray:
        # MINPACK calls this some 15 times per start: each NumPy call on these tiny arrays
        # costs about as much as its arithmetic, so each is made once (the same operations,
        # in the same order, as the plain formula: the same numbers to the last bit)
        c, s = np.cos(angles), np.sin(angles)
        cos, sin = neg_mus * c, neg_mus * s
        x = impulses_of(angles, cos, sin)
        w_after = w_t + w_base.dot(x) + (w_1 * cos + w_2 * sin).dot(x if every else x[at_columns])
        return w_after[:ns] * s - w_after[ns:] * c

    def jacobian(angles: np.ndarray) -> list[list[float]]:
        # the conditions' Jacobian exactly (the batch kernel's _jacobian_exact): angle j moves
        # slip column c alone, dA_j = d_j e_c^T; the least-squares solution x = A^+ rhs of a
        # consistent system moves by dx_j = -A^+ d_j x_c + (I - A^+ A) e_c (d_j . A^+T x)
        # (Golub and Pereyra 1973), the velocities by G (B dx_j + dB_j x)
        c, s = np.cos(angles), np.sin(angles)
        cos, sin = neg_mus * c, neg_mus * s
        a = system(cos, sin)
        a_pinv = np.linalg.pinv(a, rcond=_EPS * max(a.shape))
        x = a_pinv @ rhs
        free = np.eye(a.shape[1]) - a_pinv @ a
        z = a_pinv.T @ x
        w_x = w_base.copy()
        w_x[:, at_columns] += w_1 * cos + w_2 * sin
        w_after = w_t + w_x @ x
        dcos, dsin = mus * s, -mus * c  # (d/da of -mu cos a, -mu sin a)
        jac = np.empty((ns, ns))
        for j, col_j in enumerate(columns):
            d_j = a_1[:, j] * dcos[j] + a_2[:, j] * dsin[j]
            dx = -a_pinv @ d_j * x[col_j] + free[:, col_j] * float(d_j @ z)
            dw = w_x @ dx + (w_1[:, j] * dcos[j] + w_2[:, j] * dsin[j]) * x[col_j]
            jac[:, j] = dw[:ns] * s - dw[ns:] * c
            jac[j, j] += w_after[j] * c[j] + w_after[ns + j] * s[j]
        return jac.tolist()

    # the exact Jacobian where no contact sticks (every 3D slip regime but those mixing
    # stick and slip, the batch kernel's choice): in a mixed regime a start that fails
    # wanders, and its path, so the roots found, can part between this iteration and the
    # kernel's on round-off (with the exact Jacobian there too, one tilted box landing of
    # 500 went from agreeing to not, and another the other way); there, as before, by
    # forward differences. The family pinned near the smoothed law's impulses: the same.
    exact = jacobian if pin is None and "stick" not in pattern else None
    found: list[_Candidate] = []
    roots: list[np.ndarray] = []
    for directions in _slip_guesses(g, w, contacts, held, pattern, slipping, predicted):
        angles0 = np.array([math.atan2(d[1], d[0]) for d in directions])
        sol_x, sol_fun = newton_broyden(parallel, angles0, scale, exact)
        if not np.all(np.isfinite(sol_x)) or np.abs(sol_fun).max() > 1e-9 * scale:
            continue
        if any(_same_angles(sol_x, r) for r in roots):
            continue  # a root already checked: the same regime answer again
        roots.append(sol_x)
        d = _directions(slipping, sol_x)
        cand = _linear_regime(g, w, contacts, held, pattern, d, scale,
                              particular=None if pin is None else impulses_of(
                                  sol_x, neg_mus * np.cos(sol_x), neg_mus * np.sin(sol_x)))
        if cand is not None and not any(
            np.abs(cand.w_after - f.w_after).max() <= 1e-8 * scale for f in found
        ):
            found.append(cand)
            if first_only:
                break
    return found


def _pin(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    pattern: tuple[str, ...],
    rows: list[int],
    predicted: dict[int, np.ndarray] | None,
    near: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray] | None:
    """``(N^T, N^T x_near)``: the directions ``N`` of a regime's family of free impulses at
    the slip directions ``predicted`` and the coordinates along them of ``near`` (row
    impulses, fitted to the regime's columns); None without ``near`` or a family."""
    if near is None:
        return None
    slipping = [i for i, o in enumerate(pattern) if o == "slip"]
    directions = {i: predicted[i] for i in slipping} if predicted else {}
    b_matrix, _, _ = _columns(len(w), contacts, held, pattern, w, directions)
    a = g[rows] @ b_matrix
    _, s, vt = _svd(a)
    rank = int(np.sum(s > 1e-10 * s[0])) if s.size and s[0] > 0.0 else 0
    if rank == a.shape[1]:
        return None
    null_t = vt[rank:]
    return null_t, null_t @ np.linalg.lstsq(b_matrix, near, rcond=None)[0]


#: The most steps of :func:`newton_broyden` (carnot.batch.multi_kernel: the same).
ROOT_STEPS = 60
#: Its finite-difference step (rad).
ROOT_DIFFERENCE = 1e-7


def _step(jac: list[list[float]], rhs: list[float]) -> list[float]:
    """``jac^-1 rhs`` by Gaussian elimination with partial pivoting, or where a pivot falls
    below 1e-7 of the largest entry, the minimum-norm solution with the singular values below
    1e-10 of the largest cut: the batch kernel's ``_lu_solve`` and ``_svd_solve``, the same
    operations in the same order (plain floats: at n <= 4 a LAPACK call costs more in its
    wrapper than this in arithmetic).

    >>> _step([[2.0, 1.0], [1.0, 3.0]], [3.0, 5.0])
    [0.8, 1.4]
    >>> [round(v, 12) for v in _step([[1.0, 1.0], [1.0, 1.0]], [2.0, 2.0])]
    [1.0, 1.0]
    """
    n = len(rhs)
    lu = [row[:] for row in jac]
    x = rhs[:]
    amax = 0.0
    for row in jac:
        for v in row:
            amax = max(amax, abs(v))
    tiny = 1e-7 * amax
    singular = not amax > 0.0
    for k in range(n if not singular else 0):
        p = k
        best = abs(lu[k][k])
        for i in range(k + 1, n):
            v = abs(lu[i][k])
            if v > best:
                p, best = i, v
        if not best > tiny:
            singular = True
            break
        if p != k:
            lu[k], lu[p] = lu[p], lu[k]
            x[k], x[p] = x[p], x[k]
        row_k = lu[k]
        pivot = row_k[k]
        for i in range(k + 1, n):
            row_i = lu[i]
            f = row_i[k] / pivot
            if f != 0.0:
                for j in range(k + 1, n):
                    row_i[j] -= f * row_k[j]
                x[i] -= f * x[k]
    if not singular:
        for i in range(n - 1, -1, -1):
            row = lu[i]
            v = x[i]
            for j in range(i + 1, n):
                v -= row[j] * x[j]
            x[i] = v / row[i]
        return x
    u, sv, vt = np.linalg.svd(np.array(jac, dtype=float))
    rank = int(np.sum(sv > 1e-10 * sv[0])) if sv.size and sv[0] > 0.0 else 0
    out = np.zeros(n)
    for k in range(rank):
        out += vt[k] * (float(u[:, k] @ np.array(rhs)) / sv[k])
    return out.tolist()


def newton_broyden(fun: Callable[[np.ndarray], np.ndarray], x0: np.ndarray, scale: float,
                   jacobian: Callable[[np.ndarray], list[list[float]]] | None = None,
                   ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """A root of ``fun`` (the 3D slip conditions, m/s) from ``x0`` (the slip angles, rad):
    ``(x, fun(x))``. Newton's method with the Jacobian ``jacobian(x)`` (or, without it, by
    forward differences, step :data:`ROOT_DIFFERENCE`) at the start and by Broyden's update
    along each step after, taken anew when a step fails; a step that does not reduce ``max |fun|``
    is halved (up to 30 times; twice once ``max |fun|`` is below 1e-12 of ``scale``, where
    round-off rules). It stops at ``max |fun| <= 1e-15 scale``, at a step below 1e-14 rad,
    or after :data:`ROOT_STEPS` steps.

    The compiled batch kernel (:func:`carnot.batch.multi_kernel._newton_angles`) runs the
    same iteration, step by step, with the same exact Jacobian (its ``_jacobian_exact``; by
    differences where the system is singular but for its structure), so both reach the same
    root from the same start (MINPACK's ``hybr``, used here before, and the kernel's Newton
    iteration reached different roots, or one none, on ill-conditioned slip systems: a box
    landing on three slipping corners). The iteration's arithmetic is on plain floats, the
    kernel's operations in its order. The slip regimes' own ``jacobian`` (since 2026-11-27,
    where no contact sticks; by forward differences before, and still in a regime mixing
    stick and slip) spares the differences' evaluation per angle.

    >>> f = lambda x: np.array([x[0] ** 2 - 2.0, x[1] - x[0]])
    >>> x, fx = newton_broyden(f, np.array([1.0, 0.0]), 1.0)
    >>> round(float(x[0]), 12), round(float(x[1]), 12), bool(np.abs(fx).max() < 1e-15)
    (1.414213562373, 1.414213562373, True)
    >>> j = lambda x: [[2.0 * x[0], 0.0], [-1.0, 1.0]]
    >>> x, fx = newton_broyden(f, np.array([1.0, 0.0]), 1.0, j)
    >>> round(float(x[0]), 12), bool(np.abs(fx).max() < 1e-15)
    (1.414213562373, True)
    """
    angles = [float(v) for v in x0]
    n = len(angles)
    f_array = fun(np.array(angles))
    f = f_array.tolist()
    jac = [[0.0] * n for _ in range(n)]
    h = ROOT_DIFFERENCE

    def differences() -> None:
        if jacobian is not None:
            jac[:] = jacobian(np.array(angles))
            return
        for j in range(n):
            trial = angles[:]
            trial[j] += h
            f2 = fun(np.array(trial)).tolist()
            for i in range(n):
                jac[i][j] = (f2[i] - f[i]) / h

    fresh = False  # whether jac is the finite-difference Jacobian at the angles
    for it in range(ROOT_STEPS):
        size = 0.0
        for v in f:
            size = max(size, abs(v))
        if size <= 1e-15 * scale or not math.isfinite(size):
            break
        if it == 0:
            differences()
            fresh = True
        size_new = math.inf
        lam = 1.0
        while True:
            step = _step(jac, [-v for v in f])
            lam = 1.0
            for _ in range(30 if size > 1e-12 * scale else 2):
                trial = [a + lam * d for a, d in zip(angles, step, strict=True)]
                f_array_new = fun(np.array(trial))
                f2 = f_array_new.tolist()
                size_new = 0.0
                for v in f2:
                    size_new = max(size_new, abs(v))
                if size_new < size:
                    break
                lam *= 0.5
            if size_new < size or fresh:
                break
            differences()
            fresh = True
        if not size_new < size:
            break
        # Broyden's update along the step taken
        ss = 0.0
        for d in step:
            ss += (lam * d) ** 2
        if ss > 0.0:
            for i in range(n):
                resid = f2[i] - f[i]
                row = jac[i]
                for j in range(n):
                    resid -= row[j] * lam * step[j]
                for j in range(n):
                    row[j] += resid * lam * step[j] / ss
        fresh = False
        angles, f, f_array = trial, f2, f_array_new
        if max(abs(lam * d) for d in step) <= 1e-14:
            break
    return np.array(angles), f_array


#: Two slip-angle roots closer than this (rad, each angle modulo 2 pi) are the same root.
SAME_ROOT = 1e-10


def _same_angles(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether slip angles ``a`` and ``b`` (rad) are the same root: each within
    :data:`SAME_ROOT` modulo ``2 pi`` (the kernel's test, carnot.batch.multi_kernel).

    >>> _same_angles(np.array([0.5, -math.pi]), np.array([0.5, math.pi]))
    True
    """
    for x, y in zip(a.tolist(), b.tolist(), strict=True):
        d = x - y
        d -= 2.0 * math.pi * math.floor(d / (2.0 * math.pi) + 0.5)
        if not abs(d) <= SAME_ROOT:
            return False
    return True


def _directions(slipping: list[int], angles: np.ndarray) -> dict[int, np.ndarray]:
    """Unit slip directions (in the contact's t1, t2 axes) from their angles (rad)."""
    return {
        i: np.array([math.cos(a), math.sin(a)]) for i, a in zip(slipping, angles, strict=True)
    }


def _slip_guesses(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    pattern: tuple[str, ...],
    slipping: list[int],
    predicted: dict[int, np.ndarray] | None = None,
) -> Iterator[list[np.ndarray]]:
    """Starting slip directions: the predicted ones (opposite to the tangential impulse that
    sticking would need), the post-impact slip of the same regime without friction on the
    slipping contacts, and the pre-impact slip (lazily: the first often serves)."""
    if predicted and all(i in predicted for i in slipping):
        yield [predicted[i] for i in slipping]
    frictionless = tuple("closed" if o == "slip" else o for o in pattern)
    w_free = _velocities(g, w, contacts, held, frictionless, {})
    for source in (w_free, w):
        dirs = []
        for i in slipping:
            w_t = source[list(contacts[i].tangents)]
            norm = math.hypot(float(w_t[0]), float(w_t[1]))
            dirs.append(w_t / norm if norm > 0.0 else np.array([1.0, 0.0]))
        yield dirs


def _velocities(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    pattern: tuple[str, ...],
    slip_directions: dict[int, np.ndarray],
) -> np.ndarray:
    """Post-impact row velocities of a regime (least squares when its system is singular)."""
    b_matrix, rows, targets = _columns(len(w), contacts, held, pattern, w, slip_directions)
    if not rows:
        return w.copy()
    x = _lstsq(g[rows] @ b_matrix, targets - w[rows])
    return w + g @ (b_matrix @ x)


def _linear_regime(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    pattern: tuple[str, ...],
    slip_directions: dict[int, np.ndarray],
    scale: float,
    particular: np.ndarray | None = None,
    near: np.ndarray | None = None,
) -> _Candidate | None:
    """Solve one regime with fixed slip directions; None when it does not hold. A family of
    impulses meets the 3D cones exactly: by their inscribed polygons (one linear program),
    or where those find none, by the cones themselves (:func:`_exact_cones`).
    ``particular``: a solution of the regime's equations to start its family from, in place
    of the least-norm one; ``near``: row impulses whose member of the family starts it."""
    m = len(w)
    b_matrix, rows, targets = _columns(m, contacts, held, pattern, w, slip_directions)
    q = len(rows)
    tol = _FEASIBILITY * scale
    if q:
        a = g[rows] @ b_matrix
        rhs = targets - w[rows]
        u, s, vt = _svd(a)
        # rank to 1e-10 relative: contact rows dependent to round-off are redundant
        rank = int(np.sum(s > 1e-10 * s[0])) if s[0] > 0.0 else 0
        x0 = vt[:rank].T @ ((u[:, :rank].T @ rhs) / s[:rank])
        if near is not None and rank < a.shape[1]:
            fit = np.linalg.lstsq(b_matrix, near, rcond=None)[0]
            x0 = x0 + vt[rank:].T @ (vt[rank:] @ (fit - x0))
        if particular is not None:
            x0 = particular
        if np.abs(a @ x0 - rhs).max() > tol:
            return None  # inconsistent: the regime's equalities contradict each other
        null = vt[rank:].T
    else:
        x0 = np.zeros(0)
        null = np.zeros((0, 0))
    gb = g @ b_matrix
    lin_a, lin_c, cones = _inequalities(g, w, contacts, pattern, b_matrix, gb, slip_directions)
    margin0 = _margin(lin_a, lin_c, cones, b_matrix, x0, g)
    not_unique = continuum = False
    span: tuple[float, float] | None = None
    x = x0
    if null.shape[1]:
        continuum = bool(np.abs(gb @ null).max() > 1e-9 * max(1.0, float(np.abs(gb).max())))
        if margin0 <= tol and cones:
            x, margin0 = _capacity_weighted(contacts, pattern, lin_a, lin_c, cones, b_matrix,
                                            x0, null, g)
        if margin0 > tol:
            not_unique = not continuum
        else:
            best = _most_feasible(lin_a, lin_c, cones, b_matrix, x0, null, g, scale)
            if cones and (best is None or best[1] < -tol):
                best = _exact_cones(lin_a, lin_c, cones, b_matrix, x0, null, g, scale, tol)
            if best is None:
                return None
            x, margin = best
            if margin < -tol:
                return None
            not_unique = margin > tol and not continuum
    elif margin0 < -tol:
        return None
    impulses = b_matrix @ x
    w_after = w + g @ impulses
    # a slipping contact must slip: with w_t'' = 0 it is the stick regime, on the cone
    if any(o.startswith("slip") for o in pattern) and not regimes.slips_as_assumed(
            _layout(contacts)[1], _codes(pattern),
            _direction_rows(len(contacts), slip_directions), w_after, tol):
        return None
    # the last word: the law itself (its natural-map residual) must hold at round-off
    residuals = (*[contact_residual(c, g, impulses, w, w_after, takes_part=option != "out")
                   for c, option in zip(contacts, pattern, strict=True)],
                 held_residual(held, w_after))  # fmt: skip
    if max(residuals) > tol:
        return None
    bounds: tuple[float, float, float, float] | None = None
    if continuum:
        slips = [(c.tangents, slip_directions[i])
                 for i, (c, option) in enumerate(zip(contacts, pattern, strict=True))
                 if option == "slip"]  # fmt: skip
        if null.shape[1] == 1:
            span = dissipated_range(g, w, b_matrix, x, null, lin_a, lin_c, cones, slips)
            bounds = None if span is None else (span[0], span[0], span[1], span[1])
        else:
            found = dissipated_bounds(g, w, b_matrix, x, null, lin_a, lin_c, cones, slips)
            if found is not None:
                span = (found.least, found.most) if found.exact else None
                bounds = (found.least_bound, found.least, found.most, found.most_bound)
    return _Candidate(
        pattern=pattern,
        impulses=impulses,
        w_after=w_after,
        not_unique=not_unique,
        continuum=continuum,
        residuals=residuals,
        dissipated_range=span,
        dissipated_bounds=bounds,
    )


def _dissipated(cand: _Candidate, w: np.ndarray) -> float:
    """A candidate's ``E_d = -1/2 Lambda . (w' + w'')`` (J), ``w = w'``."""
    return float(np.sum(dissipated_by_row(cand.impulses, w, cand.w_after)))


def _joined(span: tuple[float, float] | None, value: float) -> tuple[float, float] | None:
    """``span`` widened to hold ``value``; None (not known) stays None."""
    return None if span is None else (min(span[0], value), max(span[1], value))


#: The outcome's ``extra`` keys of a bracketed range of E_d (J): a bound below the least,
#: the least attained, the most attained, a bound above the most (:func:`dissipated_bounds`)
BOUNDS_KEYS = ("dissipated_least_bound", "dissipated_least", "dissipated_most",
               "dissipated_most_bound")  # fmt: skip


def _joined_bounds(bounds: tuple[float, ...] | None,
                   value: float) -> tuple[float, float, float, float] | None:  # fmt: skip
    """``bounds`` (:data:`BOUNDS_KEYS`) widened to hold an answer's ``value``."""
    if bounds is None:
        return None
    return (min(bounds[0], value), min(bounds[1], value), max(bounds[2], value),
            max(bounds[3], value))  # fmt: skip


def _bounds(candidates: list[_Candidate],
            w: np.ndarray) -> tuple[float, float, float, float] | None:  # fmt: skip
    """:func:`_span` bracketed (:data:`BOUNDS_KEYS`): over each candidate and each
    continuum's family; None where a continuum's is not known."""
    out = (math.inf, math.inf, -math.inf, -math.inf)
    for cand in candidates:
        value = _dissipated(cand, w)
        found = cand.dissipated_bounds if cand.continuum else (value,) * 4
        if found is None:
            return None
        out = (min(out[0], found[0], value), min(out[1], found[1], value),
               max(out[2], found[2], value), max(out[3], found[3], value))  # fmt: skip
    return out


def _span(candidates: list[_Candidate], w: np.ndarray) -> tuple[float, float] | None:
    """The least and the most E_d (J) over the answers the regimes found: each candidate's,
    and over a continuum its family's; None where a continuum's range is not known."""
    lo, hi = math.inf, -math.inf
    for cand in candidates:
        value = _dissipated(cand, w)
        span = cand.dissipated_range if cand.continuum else (value, value)
        if span is None:
            return None
        lo, hi = min(lo, span[0], value), max(hi, span[1], value)
    return lo, hi


def dissipated_range(
    g: np.ndarray,
    w: np.ndarray,
    b_matrix: np.ndarray,
    x: np.ndarray,
    null: np.ndarray,
    lin_a: np.ndarray,
    lin_c: np.ndarray,
    cones: list[tuple[int, tuple[int, ...], float]],
    slips: Sequence[tuple[tuple[int, ...], np.ndarray]] = (),
) -> tuple[float, float] | None:
    """The least and the most ``E_d`` (J) over a regime's family of answers
    ``Lambda(z) = B (x + N z)`` that meet its inequalities (``lin_a x + lin_c >= 0`` and the
    Coulomb ``cones``, as :func:`_inequalities` gives them), ``x`` a member; None where the
    range is unbounded or, for a family of more dimensions, not proved exact
    (:func:`dissipated_bounds`: Coulomb cones leave the least between a bound and a value
    attained).
    ``slips``: each 3D slipping contact's tangent rows and slip direction ``d``, fixed in the
    regime: a member must slip along ``d`` (``d_perp . w_t'' = 0``). Where the family turns
    a slip, its answers are not this regime's line but a curve along which the directions
    turn with the impulses (a box sliding on four corners): not computed here (None).

    ``E_d(Lambda) = -Lambda . w' - 1/2 Lambda . G Lambda`` (the theorem summed over the rows,
    ``w'' = w' + G Lambda``). Along a family of one dimension ``Lambda = L0 + L1 t``:
    ``E_d(t) = E_d(0) + e1 t + e2 t^2``, ``e1 = -L1 . (w' + G L0)``, ``e2 = -1/2 L1 . G L1``;
    the members form an interval of ``t`` (each linear inequality bounds one side; each cone
    ``mu p_n(t) >= |p_t(t)|``, a quadratic in ``t`` with ``p_n(t) >= 0``, is convex: an
    interval too), over which ``E_d`` is extreme at an end or at the vertex ``-e1 / (2 e2)``.
    A family of more dimensions: :func:`dissipated_bounds`, its range where that is exact
    (no cones: every vertex of the polytope enumerated, the most certified by its KKT bound).

    >>> g = np.array([[2.0, 1.0], [1.0, 2.0]])  # two rows, P_n >= 0 each, P_1 + P_2 = 1 fixed
    >>> dissipated_range(g, np.array([-1.0, -1.0]), np.eye(2), np.array([0.5, 0.5]),
    ...                  np.array([[1.0], [-1.0]]) / math.sqrt(2), np.eye(2) * 2.0,
    ...                  np.zeros(2), [])  # E_d(t) = 1/4 - t^2 / 2 over |t| <= sqrt(2) / 2
    (0.0, 0.25)
    """
    if null.shape[1] != 1:
        found = dissipated_bounds(g, w, b_matrix, x, null, lin_a, lin_c, cones, slips)
        return None if found is None or not found.exact else (found.least, found.most)
    n = null[:, 0]
    lam0, lam1 = b_matrix @ x, b_matrix @ n
    g1 = g @ lam1
    e2 = -0.5 * float(lam1 @ g1)
    e1 = -float(lam1 @ (w + g @ lam0))
    e0 = -float(lam0 @ w) - 0.5 * float(lam0 @ (g @ lam0))
    lo, hi = -math.inf, math.inf
    for tangents, d in slips:  # the slip's direction along the line: fixed, or a curve
        rate = g1[list(tangents)]
        turn = float(d[0] * rate[1] - d[1] * rate[0])
        if abs(turn) > 1e-9 * max(float(np.abs(g1).max()), 1e-300):
            return None
    if len(lin_c):
        slack, rate = lin_a @ x + lin_c, lin_a @ n
        for s_i, r_i in zip(slack.tolist(), rate.tolist(), strict=True):
            if r_i > 0.0:
                lo = max(lo, -max(s_i, 0.0) / r_i)
            elif r_i < 0.0:
                hi = min(hi, max(s_i, 0.0) / -r_i)
    for nrow, tangents, mu in cones:
        lo, hi = _cone_interval(lam0, lam1, nrow, tangents, mu, lo, hi)
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
        return None
    ends = [lo, hi] + ([-e1 / (2.0 * e2)] if e2 < 0.0 and lo < -e1 / (2.0 * e2) < hi else [])
    values = [e0 + e1 * t + e2 * t * t for t in ends]
    return min(values), max(values)


def dissipated_bounds(
    g: np.ndarray,
    w: np.ndarray,
    b_matrix: np.ndarray,
    x: np.ndarray,
    null: np.ndarray,
    lin_a: np.ndarray,
    lin_c: np.ndarray,
    cones: list[tuple[int, tuple[int, ...], float]],
    slips: Sequence[tuple[tuple[int, ...], np.ndarray]] = (),
) -> EnergyRange | None:
    """The least and the most ``E_d`` (J) over a regime's family of answers of any dimension
    ``d`` (``Lambda(z) = B (x + N z)``, ``z`` in R^d, arguments as :func:`dissipated_range`):
    ``E_d(z) = e0 + e1 . z + z . E2 z`` with ``L1 = B N``, ``e1 = -L1^T (w' + G L0)`` and
    ``E2 = -1/2 L1^T G L1`` (negative semi-definite: concave) over the convex set of the
    members, by :func:`carnot.laws.multiple.energy_range.energy_range`: the attained least
    and most and their certified bounds (exact where there are no cones). None where a 3D
    slip direction turns along the family (its answers are a curve, not this regime's flat),
    or the family is unbounded or empty.

    >>> g = np.array([[2.0, 1.0], [1.0, 2.0]])  # the 1-D example of dissipated_range
    >>> r = dissipated_bounds(g, np.array([-1.0, -1.0]), np.eye(2), np.array([0.5, 0.5]),
    ...                       np.array([[1.0], [-1.0]]) / math.sqrt(2), np.eye(2) * 2.0,
    ...                       np.zeros(2), [])
    >>> (round(r.least, 12), round(r.most, 12), r.exact)
    (0.0, 0.25, True)
    """
    lam0, lam1 = b_matrix @ x, b_matrix @ null
    g1 = g @ lam1
    for tangents, d in slips:  # the slip's direction over the family: fixed, or it turns
        rate = g1[list(tangents)]
        turn = d[0] * rate[1] - d[1] * rate[0]
        if np.abs(turn).max() > 1e-9 * max(float(np.abs(g1).max()), 1e-300):
            return None
    e2 = -0.5 * lam1.T @ g1
    e1 = -lam1.T @ (w + g @ lam0)
    e0 = -float(lam0 @ w) - 0.5 * float(lam0 @ (g @ lam0))
    if len(lin_c):
        a, c = lin_a @ null, lin_a @ x + lin_c
    else:
        a, c = np.zeros((0, null.shape[1])), np.zeros(0)
    cones_z = [(float(lam0[n]), lam1[n], lam0[list(t)], lam1[list(t)], mu) for n, t, mu in cones]
    from carnot.laws.multiple.energy_range import energy_range  # (SciPy's optimize: here only)

    return energy_range(e0, e1, e2, a, c, cones_z)


def family_range(
    g: np.ndarray,
    w: np.ndarray,
    contacts: Sequence[ContactRows],
    held: HeldRows | None,
    outcome: MultipleImpactOutcome,
) -> tuple[float, float] | None:
    """The least and the most E_d (J) over the family of answers that ``outcome`` (one
    answer of :func:`resolve_simultaneous` on ``g``, ``w``, ``contacts``) belongs to, where
    its regime (the contacts' regimes, the slips' directions as its velocities give them) has
    a family of one dimension: the line's range (:func:`dissipated_range`) or, where 3D slip
    directions turn along it, the traced curve's (:func:`_traced_range`); its own E_d where
    the regime has no family; None where the family has more dimensions or the trace fails.
    """
    contacts = tuple(contacts)
    scale = velocity_scale(w, held)
    pattern: list[str] = []
    directions: dict[int, np.ndarray] = {}
    for i, (c, o) in enumerate(zip(contacts, outcome.contacts, strict=True)):
        if o.regime == "separate":
            pattern.append("separate")
        elif o.regime == "frictionless" or c.kind == "frictionless":
            pattern.append("closed")
        elif o.regime == "stick":
            pattern.append("stick")
        elif c.kind == "planar":
            pattern.append("slip+" if outcome.w_after[c.tangents[0]] > 0.0 else "slip-")
        else:
            w_t = outcome.w_after[list(c.tangents)]
            pattern.append("slip")
            directions[i] = w_t / _norm(w_t)
    b_matrix, rows, _ = _columns(len(w), contacts, held, tuple(pattern), w, directions)
    e_d = outcome.dissipated
    if not rows:
        return e_d, e_d
    x = _lstsq(b_matrix, outcome.impulses)
    _, s, vt = _svd(g[rows] @ b_matrix)
    rank = int(np.sum(s > 1e-10 * s[0])) if s[0] > 0.0 else 0
    null = vt[rank:].T
    if not null.shape[1]:
        return e_d, e_d
    gb = g @ b_matrix
    if np.abs(gb @ null).max() <= 1e-9 * max(1.0, float(np.abs(gb).max())):
        return e_d, e_d  # impulses only: the velocities, and E_d, are the same
    lin_a, lin_c, cones = _inequalities(g, w, contacts, tuple(pattern), b_matrix, gb, directions)
    slips = [(contacts[i].tangents, d) for i, d in directions.items()]
    span = dissipated_range(g, w, b_matrix, x, null, lin_a, lin_c, cones, slips)
    if span is None and slips and null.shape[1] == 1:
        span = _traced_range(g, w, contacts, held, tuple(pattern), directions, x, null[:, 0],
                             scale)  # fmt: skip
    return None if span is None else (min(span[0], e_d), max(span[1], e_d))


#: Tracing a family of 3D slip answers (:func:`_traced_range`): the step along it (of the
#: largest impulse), the steps at most each way, the bisections of an end, and the Newton
#: iterations (and tolerance, of the velocity scale) that turn the slips to meet it.
TRACE_STEP, TRACE_STEPS, TRACE_BISECTIONS, TRACE_NEWTON, TRACE_TOL = 0.05, 400, 30, 40, 1e-13


def _traced_range(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    held: HeldRows | None,
    pattern: tuple[str, ...],
    slip_directions: dict[int, np.ndarray],
    x0: np.ndarray,
    null: np.ndarray,
    scale: float,
) -> tuple[float, float] | None:
    """The least and the most ``E_d`` (J) over a family of answers along which 3D slip
    directions turn (a box sliding on four corners: the split of the normal impulses is free,
    and each split sets a different yaw, so different slip directions), traced as a curve;
    None where the trace fails.

    The regime's unknowns ``x`` (:func:`_columns`, one column per normal impulse and held
    row) meet its rows' equations for the slip angles ``theta``; the family direction ``n``
    of ``x`` at the start fixes a coordinate ``s = n . x``. For each ``s``: ``x(s, theta)``
    the least-squares solution of the rows with ``n . x = s``, and ``theta`` by Newton
    (central differences) on ``d_i(theta_i) x w_t,i'' = 0``, each slip along its direction.
    From ``s0 = n . x0`` the trace steps both ways (``TRACE_STEP`` of the largest
    impulse) while the members meet the regime's inequalities and the law itself
    (:func:`contact_residual` within the law's tolerance, as every answer must), bisects
    each end, and reports the extremes of ``E_d = -1/2 Lambda . (w' + w'')`` over the members
    it met, an interior one refined by golden sections: to about 1e-9 relative.
    """
    slipping = [i for i, option in enumerate(pattern) if option == "slip"]
    tol = RELATIVE_TOLERANCE * scale

    def member(s: float, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        dirs = dict(slip_directions)
        for k, i in enumerate(slipping):
            dirs[i] = np.array([math.cos(angles[k]), math.sin(angles[k])])
        b, rows, targets = _columns(len(w), contacts, held, pattern, w, dirs)
        a = np.vstack([g[rows] @ b, null[None, :]])
        x = _lstsq(a, np.append(targets - w[rows], s))
        lam = b @ x
        w_after = w + g @ lam
        turn = np.array([dirs[i][0] * w_after[contacts[i].tangents[1]]
                         - dirs[i][1] * w_after[contacts[i].tangents[0]]
                         for i in slipping])  # fmt: skip
        return x, lam, turn

    def jacobian(s: float, angles: np.ndarray) -> np.ndarray:
        jac = np.empty((len(slipping), len(slipping)))
        for k in range(len(slipping)):
            h = np.zeros(len(slipping))
            h[k] = 1e-7
            jac[:, k] = (member(s, angles + h)[2] - member(s, angles - h)[2]) / 2e-7
        return jac

    chord: list[np.ndarray] = []  # the last Jacobian, kept while it converges (a chord method)

    def solve(s: float, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        angles = angles.copy()
        size = math.inf
        for _ in range(TRACE_NEWTON):
            _, lam, turn = member(s, angles)
            now = float(np.abs(turn).max())
            if now <= TRACE_TOL * scale:
                return angles, lam
            if not chord or now > 0.5 * size:  # slow or none: a fresh Jacobian
                chord[:] = [jacobian(s, angles)]
            size = now
            angles -= _lstsq(chord[0], turn)
        return None

    def holds(s: float, angles: np.ndarray) -> tuple[np.ndarray, float] | None:
        found = solve(s, angles)
        if found is None:
            return None
        angles, lam = found
        w_after = w + g @ lam
        dirs = {i: np.array([math.cos(angles[k]), math.sin(angles[k])])
                for k, i in enumerate(slipping)}  # fmt: skip
        b, rows, targets = _columns(len(w), contacts, held, pattern, w, {**slip_directions, **dirs})
        x = _lstsq(b, lam)
        lin_a, lin_c, cones = _inequalities(g, w, contacts, pattern, b, g @ b, dirs)
        if np.abs(g[rows] @ lam + w[rows] - targets).max() > tol:
            return None
        if _margin(lin_a, lin_c, cones, b, x, g) < -tol:
            return None
        if any(float(dirs[i] @ w_after[list(contacts[i].tangents)]) <= tol for i in slipping):
            return None  # a slip that stops is the stick regime's
        if max(contact_residual(c, g, lam, w, w_after, takes_part=option != "out")
               for c, option in zip(contacts, pattern, strict=True)) > tol:  # fmt: skip
            return None
        return angles, float(np.sum(dissipated_by_row(lam, w, w_after)))

    start = np.array([math.atan2(slip_directions[i][1], slip_directions[i][0]) for i in slipping])
    s0 = float(null @ x0)
    first = holds(s0, start)
    if first is None:
        return None
    step = TRACE_STEP * max(float(np.abs(x0).max()), 1e-300)
    seen: list[tuple[float, float]] = [(s0, first[1])]  # (s, E_d) of the members met
    for sign in (1.0, -1.0):
        s_ok, angles = s0, first[0]
        for _ in range(TRACE_STEPS):
            trial = holds(s_ok + sign * step, angles)
            if trial is None:
                lo, hi = s_ok, s_ok + sign * step  # the end between the last member and this
                for _ in range(TRACE_BISECTIONS):
                    mid = 0.5 * (lo + hi)
                    got = holds(mid, angles)
                    if got is None:
                        hi = mid
                    else:
                        lo, angles = mid, got[0]
                        seen.append((mid, got[1]))
                break
            s_ok, angles = s_ok + sign * step, trial[0]
            seen.append((s_ok, trial[1]))
        else:
            return None  # no end within TRACE_STEPS: not bounded here
    seen.sort()
    values = [e for _, e in seen]
    k = int(np.argmax(values))
    if 0 < k < len(seen) - 1:  # an interior maximum (E_d along the curve): golden sections
        values.append(_golden_max(lambda s: holds(s, first[0]), seen[k - 1][0], seen[k + 1][0],
                                  values[k]))  # fmt: skip
    return min(values), max(values)


def _golden_max(f: Callable[[float], tuple[np.ndarray, float] | None], a: float, b: float,
                best: float) -> float:  # fmt: skip
    """The largest value of ``f(s)[1]`` on ``[a, b]`` by golden sections (40: the interval to
    4e-9 of itself, E_d to round-off near its maximum), at least ``best``; a member ``f``
    cannot solve is passed over."""
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(40):
        c, d = b - ratio * (b - a), a + ratio * (b - a)
        fc, fd = f(c), f(d)
        vc = -math.inf if fc is None else fc[1]
        vd = -math.inf if fd is None else fd[1]
        best = max(best, vc, vd)
        if vc >= vd:
            b = d
        else:
            a = c
    return best


def _cone_interval(lam0: np.ndarray, lam1: np.ndarray, nrow: int, tangents: tuple[int, ...],
                   mu: float, lo: float, hi: float) -> tuple[float, float]:  # fmt: skip
    """``[lo, hi]`` cut to the ``t`` where ``mu p_n(t) >= |p_t(t)|`` (``p = L0 + L1 t``):
    ``p_n(t) >= 0`` and ``q(t) = mu^2 p_n^2 - |p_t|^2 >= 0``, the second a quadratic whose
    set on the half-line of the first is one interval (the cone is convex); ``t = 0`` is a
    member (within round-off) and stays in."""
    pn0, pn1 = float(lam0[nrow]), float(lam1[nrow])
    pt0, pt1 = lam0[list(tangents)], lam1[list(tangents)]
    if pn1 > 0.0:
        lo = max(lo, min(-pn0 / pn1, 0.0))
    elif pn1 < 0.0:
        hi = min(hi, max(-pn0 / pn1, 0.0))
    a = mu * mu * pn1 * pn1 - float(pt1 @ pt1)
    b = 2.0 * (mu * mu * pn0 * pn1 - float(pt0 @ pt1))
    c = mu * mu * pn0 * pn0 - float(pt0 @ pt0)
    disc = b * b - 4.0 * a * c
    if a == 0.0:  # linear: b t + c >= 0
        if b > 0.0:
            lo = max(lo, min(-c / b, 0.0))
        elif b < 0.0:
            hi = min(hi, max(-c / b, 0.0))
        return lo, hi
    if disc < 0.0:  # no root: q keeps the sign of a (a > 0: every t; a < 0: only t = 0)
        return (lo, hi) if a > 0.0 else (max(lo, 0.0), min(hi, 0.0))
    root = math.sqrt(disc)
    # the roots without cancellation
    qq = -0.5 * (b + math.copysign(root, b))
    t1, t2 = sorted((qq / a, c / qq) if qq != 0.0 else (0.0, 0.0))
    if a < 0.0:  # q >= 0 between the roots
        return max(lo, min(t1, 0.0)), min(hi, max(t2, 0.0))
    # a > 0: q >= 0 outside the roots (with p_n >= 0, one nappe: the side of t = 0)
    if t2 <= 0.0:
        return max(lo, t2), hi
    if t1 >= 0.0:
        return lo, min(hi, t1)
    # t = 0 between the roots by round-off: the side of the nearer root
    return (lo, min(hi, 0.0)) if -t1 < t2 else (max(lo, 0.0), hi)


def _inequalities(
    g: np.ndarray,
    w: np.ndarray,
    contacts: tuple[ContactRows, ...],
    pattern: tuple[str, ...],
    b_matrix: np.ndarray,
    gb: np.ndarray,
    slip_directions: dict[int, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, list[tuple[int, tuple[int, ...], float]]]:
    """The regime's inequalities ``lin_a x + lin_c >= 0`` (all in m/s: impulses times the
    contact's ``G_nn``) and its Coulomb cones ``(normal row, tangent rows, mu)``:
    :func:`carnot.laws.multiple.regimes.regime_inequalities` (the batch kernel's own), on
    the unknowns of :func:`_columns` (the held rows' columns, which no inequality reads,
    included)."""
    q = b_matrix.shape[1]
    k = len(contacts)
    nrow, trow, _, mu, e, kinds = _layout(contacts)
    lin_a = np.zeros((3 * k, q))
    lin_c = np.zeros(3 * k)
    cone_rows = np.zeros((k, 3))
    nlin, ncones = regimes.regime_inequalities(
        g, w, nrow, trow, kinds, e, mu, _codes(pattern), _direction_rows(k, slip_directions),
        _view(b_matrix), q, _view(gb), _view(lin_a), _view(lin_c), cone_rows)
    cones = [(int(n), contacts[int(c)].tangents, float(f)) for n, c, f in cone_rows[:ncones]]
    return lin_a[:nlin], lin_c[:nlin], cones


def _margin(
    lin_a: np.ndarray,
    lin_c: np.ndarray,
    cones: list[tuple[int, tuple[int, ...], float]],
    b_matrix: np.ndarray,
    x: np.ndarray,
    g: np.ndarray,
) -> float:
    """The smallest slack of the inequalities at ``x`` (m/s); +inf when there are none."""
    slack = list(lin_a @ x + lin_c) if len(lin_c) else []
    impulses = b_matrix @ x
    for n, tangents, mu in cones:
        norm_t = math.hypot(*(float(impulses[t]) for t in tangents))  # floats: no NumPy call
        slack.append(float(g[n, n]) * (mu * float(impulses[n]) - norm_t))
    return min(slack) if slack else math.inf


def _capacity_weighted(
    contacts: tuple[ContactRows, ...],
    pattern: tuple[str, ...],
    lin_a: np.ndarray,
    lin_c: np.ndarray,
    cones: list[tuple[int, tuple[int, ...], float]],
    b_matrix: np.ndarray,
    x0: np.ndarray,
    null: np.ndarray,
    g: np.ndarray,
) -> tuple[np.ndarray, float]:
    """A cheap try before the linear program: over the family ``x0 + N z``, the least
    weighted norm of the impulses, each contact's tangential impulse weighted by the inverse
    of its friction capacity ``mu P_n`` (from ``x0``), so that the tangential impulse goes
    where the normal impulse can hold it (a spinning box sticking on four corners)."""
    p0 = b_matrix @ x0
    p_max = float(np.abs(p0).max()) if p0.size else 0.0
    if not p_max > 0.0:  # no impulse anywhere (all at rest): nothing to spread
        return x0, _margin(lin_a, lin_c, cones, b_matrix, x0, g)
    # weights relative to the largest impulse (the minimiser does not depend on their scale;
    # relative ones cannot overflow)
    weights = np.ones(len(p0))
    for c, option in zip(contacts, pattern, strict=True):
        if option == "stick" and c.friction > 0.0:
            capacity = max(c.friction * float(p0[c.normal]), 1e-3 * p_max)
            weights[list(c.tangents)] = p_max / capacity
    wb = weights[:, None] * b_matrix
    z = -_lstsq(wb @ null, wb @ x0)
    x = x0 + null @ z
    return x, _margin(lin_a, lin_c, cones, b_matrix, x, g)


#: The most cutting-plane rounds of :func:`_exact_cones` (each a linear program).
EXACT_CONE_ROUNDS = 60


def _exact_cones(
    lin_a: np.ndarray,
    lin_c: np.ndarray,
    cones: list[tuple[int, tuple[int, ...], float]],
    b_matrix: np.ndarray,
    x0: np.ndarray,
    null: np.ndarray,
    g: np.ndarray,
    scale: float,
    tol: float,
) -> tuple[np.ndarray, float] | None:
    """Over the family ``x = x0 + N z``, impulses meeting the inequalities and the circular
    cones exactly (slack >= ``-tol``), or None when there are none: Kelley's cutting planes
    (Kelley 1960). Each cone starts as its *circumscribed* polygon (``mu P_n >= d . P_t`` for
    :data:`_POLYGON` directions ``d``: a necessary condition), the linear program maximizes
    the smallest slack ``t``, and a cone violated at the answer gets the tangent plane along
    its tangential impulse. The program's ``t`` bounds the cones' best slack from above, so a
    negative ``t`` proves there is none; an answer in the cones is exact.

    A sticking contact whose friction must be used to 99.9 %: ``P = (P_n, P_t) = (1, 0.999)``,
    ``mu = 1``, the only impulse of the family. The inscribed 32-gon (0.5 % inside the
    cone) refuses it; the cone holds it:

    >>> b = np.eye(3); x0 = np.array([1.0, 0.999, 0.0]); null = np.zeros((3, 0))
    >>> cones = [(0, (1, 2), 1.0)]; g = np.eye(3)
    >>> x, slack = _exact_cones(np.zeros((0, 3)), np.zeros(0), cones, b, x0, null, g, 1.0, 1e-12)
    >>> round(slack, 12)
    0.001
    """
    angles = 2.0 * np.pi * (np.arange(_POLYGON) + 0.5) / _POLYGON
    cuts: list[list[np.ndarray]] = [
        [np.array([math.cos(a), math.sin(a)]) for a in angles] for _ in cones
    ]
    for _ in range(EXACT_CONE_ROUNDS):
        rows_a = [lin_a] if len(lin_c) else []
        rows_c = [lin_c] if len(lin_c) else []
        for (n, (t1, t2), mu), directions in zip(cones, cuts, strict=True):
            d = np.array(directions)
            rows_a.append(float(g[n, n]) * (mu * b_matrix[n][None, :] - d[:, :1] * b_matrix[t1]
                                            - d[:, 1:] * b_matrix[t2]))  # fmt: skip
            rows_c.append(np.zeros(len(d)))
        best = _max_min_slack(np.vstack(rows_a), np.concatenate(rows_c), x0, null, scale)
        if best is None or best[1] < -tol:
            return None  # even the outer polygons hold no impulse: the cones hold none
        x = best[0]
        margin = _margin(lin_a, lin_c, cones, b_matrix, x, g)
        if margin >= -tol:
            return x, margin
        impulses = b_matrix @ x
        for (n, (t1, t2), mu), directions in zip(cones, cuts, strict=True):
            p_t = np.array([impulses[t1], impulses[t2]])
            norm_t = _norm(p_t)
            if norm_t > 0.0 and float(g[n, n]) * (mu * float(impulses[n]) - norm_t) < -tol:
                directions.append(p_t / norm_t)  # the tangent plane where it is violated
    return None


def _most_feasible(
    lin_a: np.ndarray,
    lin_c: np.ndarray,
    cones: list[tuple[int, tuple[int, ...], float]],
    b_matrix: np.ndarray,
    x0: np.ndarray,
    null: np.ndarray,
    g: np.ndarray,
    scale: float,
) -> tuple[np.ndarray, float] | None:
    """Over the regime's family ``x = x0 + N z``, maximize the smallest slack ``t`` (capped
    at the velocity scale so the program is bounded) by a linear program: HiGHS through
    ``scipy.optimize.linprog``; each cone replaced by its inscribed polygon."""
    rows_a = [lin_a] if len(lin_c) else []
    rows_c = [lin_c] if len(lin_c) else []
    angles = 2.0 * np.pi * (np.arange(_POLYGON) + 0.5) / _POLYGON
    for n, tangents, mu in cones:
        gnn = float(g[n, n])
        t1, t2 = tangents
        facets = (
            mu * math.cos(math.pi / _POLYGON) * b_matrix[n][None, :]
            - np.cos(angles)[:, None] * b_matrix[t1][None, :]
            - np.sin(angles)[:, None] * b_matrix[t2][None, :]
        )
        rows_a.append(gnn * facets)
        rows_c.append(np.zeros(_POLYGON))
    best = _max_min_slack(np.vstack(rows_a), np.concatenate(rows_c), x0, null, scale)
    if best is None:
        return None
    return best[0], _margin(lin_a, lin_c, cones, b_matrix, best[0], g)


def _max_min_slack(
    a_all: np.ndarray, c_all: np.ndarray, x0: np.ndarray, null: np.ndarray, scale: float
) -> tuple[np.ndarray, float] | None:
    """Over ``x = x0 + N z``, the ``x`` that maximizes the smallest slack ``t`` of
    ``a_all x + c_all >= t`` (``t`` capped at ``scale`` so that the program is bounded), and
    that ``t``; None if HiGHS (``scipy.optimize.linprog``) finds no optimum."""
    # imported here: scipy.optimize costs 0.2 s at start-up, and only a regime whose
    # impulses are not unique and whose first guess breaks an inequality needs the program
    from scipy.optimize import linprog

    k = null.shape[1]
    # variables (z, t): maximize t subject to a_all (x0 + N z) + c_all >= t
    a_ub = np.hstack([-(a_all @ null), np.ones((len(c_all), 1))])
    cost = np.zeros(k + 1)
    cost[-1] = -1.0
    res = linprog(cost, A_ub=a_ub, b_ub=a_all @ x0 + c_all,
                  bounds=[(None, None)] * k + [(None, scale)], method="highs")  # fmt: skip
    if res.status != 0:
        return None
    return x0 + null @ res.x[:k], float(res.x[-1])

"""The simultaneous multiple-impact law compiled for batches (Numba): one impact per call.

The same law, the same regime enumeration and the same choices as
:func:`carnot.laws.multiple.resolve_simultaneous` (read its docstring first), written for
Numba on the rows of one impact, so that :mod:`carnot.batch.multi` can run it over arrays of
impacts in parallel. Contact space: ``G`` (m x m, 1/kg), ``w'`` (m/s); contact ``c`` owns its
normal row and 0, 1 or 2 tangent rows. Its kind per impact: frictionless (no tangent rows or
``mu = 0``), planar (one tangent row), spatial (two: the exact circular cone).

The rules this kernel shares with the law are not written here but compiled from where they
are stated: the regimes, each regime's unknowns, rows, targets and inequalities, the slip
check, the prediction that orders the search, an answer's widest regime and the verdict on
the answers found (:mod:`carnot.laws.multiple.regimes`), Coulomb's cone and the law's residual
(:mod:`carnot.laws.cone`), the contact frame (:mod:`carnot.conventions`), a body's inertia
check and kinetic energy (:mod:`carnot.batch.rigid`); every function here is compiled under a
name stamped with those modules' source digest (:data:`_RULES`). What is written here is the
enumeration's machinery, for Numba.

What differs from the reference, and why it gives the same answers:

* a regime without slip columns (closed, stick, separate) has the symmetric positive
  semi-definite system ``G_RR x = b``: solved by Cholesky with diagonal pivoting, which gives
  the rank (pivots below 1e-10 of the largest diagonal entry, where the reference counts
  singular values below 1e-10 of the largest), a null-space basis ``[-L1^-T L2^T; I]`` and the
  minimum-norm solution (the basic solution with its null-space part projected out): the
  reference's SVD answer, to round-off, for a consistent system (an inconsistent regime is
  rejected by both); slip regimes (non-symmetric) use NumPy's SVD as the reference does;
* for one free body against a fixed obstacle (a batch of :func:`run`), the regime that
  closes or sticks every taking-part contact is solved in the body's 6 velocities:
  ``G = J M^-1 J^T`` with ``J`` of full column rank gives the minimum-norm impulse
  ``J (J^T J)^-1 M (J^T J)^-1 J^T rhs`` and the capacity-weighted one
  ``D^-2 J (J^T D^-2 J)^-1 J^T x`` (:func:`_body_min_norm`, :func:`_body_weighted`), the
  same impulses to round-off as the rows' route (tested against it and against NumPy's
  pseudo-inverse); the rows' null space is computed only where neither meets the
  inequalities (then the linear program needs it);
* the 3D slip angles (the slip direction parallel to the post-impact slip) are found by the
  reference's own iteration, step for step (:func:`carnot.laws.multiple.simultaneous.
  newton_broyden`: Newton's method, a finite-difference Jacobian at the start, then
  Broyden's update) from the same starting directions; a root reached from two starting
  directions is checked once, in both. With MINPACK's ``hybr`` in the reference instead
  (as it once was): where the slip conditions' system is ill-conditioned (a box landing
  with three corners slipping), Newton creeps and so does ``hybr``, and they parted ways,
  one reaching a root the other missed (each a genuine solution: the problem has several;
  ``benchmarks/tilt_differences.py``); such impacts (an iteration over 30 steps) were
  left to the reference, at 0.1-0.3 s each;
* where the reference solves a linear program (a rank-deficient regime whose minimum-norm and
  capacity-weighted impulses miss an inequality: SciPy's HiGHS), the kernel solves the same
  program: exactly over a one-dimensional family (:func:`_most_feasible_1d`), by a dense
  simplex on its dual otherwise (:func:`_most_feasible_nd`); where the inscribed polygons
  hold no impulse of the family, the cones themselves by the reference's cutting planes on
  that simplex (:func:`_exact_cones`). The optimum is the same; where
  the maximizer is not unique the impulses may differ within the regime's family (then the
  velocities do not, or the impact is flagged as the reference flags it). Only if that
  simplex reaches its pivot limit does the kernel return :data:`NEEDS_REFERENCE`, and the
  caller solves the impact with the reference law itself. So every row is either the
  reference's answer or the reference's own computation.

Speed without a different answer (benchmarks/same_answers.py checks it bit for bit against a
revision): the closed regime, the first tried, is the prediction's system and is not solved
again; the one-dimensional linear program skips the candidates that cannot win
(:func:`_envelope_floor`); an impact's arrays and the slip-angle iteration's are workspaces
allocated once per task of the parallel loop (:func:`workspace`, :func:`newton_workspace`,
:func:`regime_workspace`):
allocation and its reference counting were about a third of a landing's time. A slip-angle
evaluation (:func:`_parallel`, a dozen per slip regime and start) skips the zero products of
``B`` (a slip column has three non-zero rows, a row of ``B`` one column: the sums add the
same terms in the same order, so the same bits), takes each angle's cosine and sine once,
sets in a finite difference only the column that changed, and no longer tries Gaussian
elimination on a system that it found singular by its structure (a pivot below 1e-12 of the
largest entry: a flat box's four coplanar corners, whose normal velocities have rank 3,
where the QR always decides); the null-space projection of :func:`_sym_solve` sums over the
basis's rows above its identity block only (the same bits). Numba counts every array handed
to a compiled function in and out (an atomic operation each way, ~40 cycles an array and a
call): every function of one impact is a leaf compiled without that counting
(:data:`_leaf`), from :func:`solve_front` and :func:`solve_into` down. None allocates: each
takes its arrays from workspaces allocated once per task, the solvers' from two scratch
arenas (:func:`arena_size`), and the SVD is LAPACK's ``dgesdd`` called on arena arrays as
NumPy calls it (:func:`_svd_into`, the same bits). Until the leaves reached the regime
solvers (:func:`solve_regime`, :func:`linear_regime`, :func:`_newton_angles` and the
linear programs), the counting of their arrays was about a fifth of a sliding landing
(``bench_kernel_ab.py``: 1.26x on the sliding landings, 1.08x on the sticking ones).

The regime solvers are called by their address, so that LLVM optimizes them once. Numba
compiles each function as a library of its own, links into it the already optimized code of
every function it calls and has LLVM optimize and emit the whole module again; a parallel
loop adds three such libraries above its entry point (its gufunc, the gufunc's wrapper, the
scheduler's entry). A function deep in the call tree is so optimized and emitted once per
level above it: after all their callees were compiled, :func:`run` took 68 s more and
:func:`solve_rows` 99 s. Three C callbacks (``numba.cfunc``, built by :func:`impact_solvers`
on first use and cached on disk as the kernels are) cut the tree where the most code lay
below the most levels:

* :func:`solve_in_workspaces` (:func:`solve_front`, then :func:`solve_into`), which both
  entry points take as an argument (a first-class function, ``numba.types.FunctionType``)
  and call by its address: its module is not linked into theirs, so they compile their own
  loops and the small functions of the frictionless front and of the bodies only;
* :func:`solve_regime` (a regime's slip angles, roots and checks), which
  :func:`solve_into` calls by its address, handed down from the entry points;
* :func:`regime_holds` (a regime's check: its inequalities, its family's linear programs
  and cones), called by its address from the linear and root regimes, :func:`_widest` and
  :func:`solve_into`: it lay below five levels in both callbacks.

With the first alone, the whole kernel's cold compile took 110-115 s of CPU; with all three,
75 s (``benchmarks/bench_cold_compile.py``; docs/performance.md). As the three link none of each
other's code, a first call that finds them missing from the cache has child processes
compile the two costliest side by side while it compiles the entry point and the third
(:func:`impact_solvers`, :mod:`carnot.batch.compile_apart`). The price is per call of an
entry point: Numba types the callback arguments and looks their addresses up, about 0.2 ms on
a quiet machine (a batch of 10^4 landings takes ~0.1 s); a call by address inside compiled
code costs an indirect call, as a call of a library that LLVM did not inline did before.

Regime codes (per contact, of :data:`REGIME_NAMES` in :mod:`carnot.batch.multi`):
``SEPARATE`` (not taking part, or separating with no impulse), ``FRICTIONLESS`` (closed),
``STICK``, ``SLIP``.
"""

from __future__ import annotations

import functools
import math
import threading
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numba.np.linalg import _LAPACK

from carnot import conventions
from carnot.batch import rigid
from carnot.batch.ops import compiled_rules, source_digest, specialize, stamped
from carnot.conventions import contact_frame_into
from carnot.laws import cone
from carnot.laws.multiple import regimes
from carnot.laws.multiple.regimes import (
    CLOSED,
    FRICTIONLESS_KIND,
    OUT,
    PLANAR,
    SEPARATE_OPT,
    SLIP_OPT,
    SPATIAL,
    STICK_OPT,
)

#: Limits of one impact: contacts and contact rows (4 frictional 3D contacts = 12 rows).
MAX_CONTACTS = 8
MAX_ROWS = 12
#: The most regimes one impact may enumerate (the reference's MAX_REGIMES).
MAX_REGIMES = 4096
#: Uniqueness is verified (every regime tried) up to this many regimes and 3D contacts.
VERIFY_UP_TO = 64
VERIFY_SPATIAL_UP_TO = 2

RELATIVE_TOLERANCE = 1e-9  # carnot.conventions.RELATIVE_TOLERANCE (checked in the tests)
SAME_ROOT = 1e-10  # carnot.laws.multiple.simultaneous.SAME_ROOT (rad)
#: The slip-angle iteration's most steps and finite-difference step (rad): the reference's
#: ROOT_STEPS and ROOT_DIFFERENCE (carnot.laws.multiple.simultaneous; checked in the tests).
ROOT_STEPS = 60
ROOT_DIFFERENCE = 1e-7
FEASIBILITY = 1e-9
RANK = 1e-10
# results of the slip-angle iteration
NO_ROOT, ROOT = 0, 1

# contact kinds and a contact's options in a regime: carnot.laws.multiple.regimes' (imported)
# regime codes reported per contact
SEPARATE, FRICTIONLESS, STICK, SLIP = 0, 1, 2, 3
# status of one impact
SOLVED, NEEDS_REFERENCE, NO_SOLUTION, TOO_MANY_REGIMES = 0, 1, 2, 3
# flag bits
STATICALLY_INDETERMINATE, MULTIPLE_SOLUTIONS, NO_SOLUTION_FLAG = 1, 2, 4
SEPARATING_CONTACT_APPROACHES, UNVERIFIED = 8, 16

#: The rules of physics this kernel compiles from the modules that state them (the contact
#: frame, Coulomb's cone and the law's residual, the regimes' equations, a body's inertia
#: check and energy): every
#: function here is compiled under a name that carries their source's digest
#: (:func:`carnot.batch.ops.stamped`: Numba's cache stamps an entry with this file alone,
#: and a changed rule must not load as the old one).
_RULES = source_digest([conventions, cone, rigid, regimes])


def _stamp(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` renamed with :data:`_RULES` (:func:`carnot.batch.ops.stamped`)."""
    return stamped(fn, _RULES)


_JIT = numba.njit(cache=True, nogil=True, error_model="numpy")


def _jit(fn: Callable[..., Any]) -> Any:
    """A compiled function that may allocate (Numba's reference counting on)."""
    return _JIT(_stamp(fn))


#: A leaf: a function that allocates no array and calls only leaves, compiled without
#: Numba's reference counting (its ``_nrt=False`` target option; numba is pinned). Every
#: array handed to a compiled function is otherwise counted in and out, an atomic operation
#: each way: measured here, a call handing over 20 arrays took ~800 cycles, ~5 as a leaf,
#: and a slip-angle evaluation (:func:`_parallel`, 27 arrays) 2800 -> 1100 cycles. A leaf's
#: arrays are borrowed from its caller, which outlives the call; a leaf cannot allocate
#: (its arrays come from workspaces and arenas), and an array it returns must go to a leaf
#: only (a counting caller, or Python, would release what was never counted).
_LEAF = numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=False)  # type: ignore[call-overload]


def _leaf(fn: Callable[..., Any]) -> Any:
    """A leaf (above)."""
    return _LEAF(_stamp(fn))


#: A leaf whose body Numba copies into each caller (``inline="always"``). A call hands every
#: array over as its fields, seven to nine words each, on the stack, and LLVM does not
#: inline these functions on its own (each is compiled as a module of its own): a
#: slip-angle evaluation's call (:func:`_parallel`, 27 arrays) passed 181 words (read in
#: the compiled module). Copied, a sliding landing takes about 5 % fewer cycles
#: (``benchmarks/cycles_kernel_ab.py``). Only for :func:`_parallel` (six call sites): each
#: copy is typed and compiled again: with its pieces copied as well, each entry point of the
#: kernel took 17 s more compilation; LLVM's ``alwaysinline`` (Numba's ``forceinline``) on
#: it and :func:`_slip_conditions` took 57 s more (210 s against 153 s for ``run``;
#: docs/performance.md).
_INLINE_LEAF = numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=False,
                          inline="always")  # type: ignore[call-overload]  # fmt: skip


def _inline_leaf(fn: Callable[..., Any]) -> Any:
    """An inlined leaf (above)."""
    return _INLINE_LEAF(_stamp(fn))


@numba.njit(cache=True, nogil=True, error_model="numpy", _nrt=False, fastmath={"afn"})  # type: ignore[call-overload]
@_stamp
def _cos_sin(angle):  # type: ignore[no-untyped-def]
    """``(cos(angle), sin(angle))`` in one call of the C library's ``sincos``: LLVM joins a
    sine and a cosine of one argument only where they may be approximated (the ``afn``
    flag; without it, as glibc's ``sin``/``cos`` set ``errno``, it keeps the two calls).
    glibc's ``sincos`` runs the same code as its ``sin`` and ``cos``: the same bits (checked
    on 8e6 arguments, |a| up to 1e3, 1e300, inf and nan), at about 2/3 of the cost. A
    leaf (:data:`_leaf`).

    >>> _cos_sin(0.5) == (math.cos(0.5), math.sin(0.5))
    True
    """
    return math.cos(angle), math.sin(angle)


# A loop counter handed to another compiled function starts as ``np.int64(0)``, not ``0``:
# while Numba infers the loop's types, a plain ``0`` is first seen as the literal
# ``Literal[int](0)``, and the callee is compiled for it as well as for ``int64`` (twice the
# compile time of the regime solvers, paid by every clean checkout's tests). The same for a
# flag (``np.bool_(False)``, not ``False``: ``Literal[bool](False)`` is another type than
# ``bool``) and for an array: a read-only one (the batch's inputs, frozen in
# carnot.batch.multi) is another type than a writable one, so the body route hands the
# solvers a writable copy of the inertia, as the contact-space route's (issue 35: each
# solver compiled once for both routes, checked by benchmarks/bench_cold_compile.py).


#: The regimes a contact may be in, a regime's unknowns, rows and targets, and its
#: inequalities: the law's own statement (:mod:`carnot.laws.multiple.regimes`), compiled as
#: leaves.
_REGIMES = compiled_rules(regimes, ("regime_options", "regime_columns", "regime_inequalities",
                                    "predicted_order", "widest_pattern", "slips_as_assumed",
                                    "_apart", "answer_groups", "group_first", "group_verdict"),
                          _LEAF, _RULES)  # fmt: skip
_options = _REGIMES["regime_options"]
_columns = _REGIMES["regime_columns"]
_inequalities = _REGIMES["regime_inequalities"]
_predicted_order = _REGIMES["predicted_order"]
_widest_pattern = _REGIMES["widest_pattern"]
_slips_as_assumed = _REGIMES["slips_as_assumed"]
_answer_groups = _REGIMES["answer_groups"]
_group_verdict = _REGIMES["group_verdict"]


@_leaf
def _spd_solve(a, rhs, n, y, fa, top):  # type: ignore[no-untyped-def]
    """``y = a[:n, :n]^-1 rhs`` for a small symmetric positive definite ``a`` (Cholesky; its
    factor in the scratch arena ``fa`` from ``top``: see :func:`arena_size`)."""
    low = fa[top : top + n * n].reshape((n, n))
    for i in range(n):
        for j in range(n):
            low[i, j] = 0.0
    for j in range(n):
        s = a[j, j]
        for p in range(j):
            s -= low[j, p] * low[j, p]
        low[j, j] = math.sqrt(s) if s > 0.0 else 2.2250738585072014e-308
        for i in range(j + 1, n):
            s = a[i, j]
            for p in range(j):
                s -= low[i, p] * low[j, p]
            low[i, j] = s / low[j, j]
    for i in range(n):
        y[i] = rhs[i]
    _cholesky_solve(low, y)


@_leaf
def _normal_arrays(fa, top, nn):  # type: ignore[no-untyped-def]
    """A small normal-equations system's arrays carved from the arena ``fa`` at ``top``:
    its matrix (nn x nn), right-hand side and solution (nn each), and the arena's next free
    place. Views of the arena: for leaves only (see :func:`_svd_into`)."""
    mat = fa[top : top + nn * nn].reshape((nn, nn))
    t = top + nn * nn
    return mat, fa[t : t + nn], fa[t + nn : t + 2 * nn], t + 2 * nn


@_leaf
def _sym_solve(a, rhs, q, x, null, fa, ia, top):  # type: ignore[no-untyped-def]
    """Minimum-norm solution ``x`` of the symmetric positive semi-definite ``a[:q, :q] x =
    rhs`` (Cholesky with diagonal pivoting; rank below 1e-10 of the largest pivot cut) and a
    basis of its null space (unit columns of ``null``); returns the null space's dimension.
    Its arrays in the scratch arenas ``fa``/``ia`` from ``top`` (:func:`arena_size`)."""
    t = top
    work = fa[t : t + q * q].reshape((q, q))
    t += q * q
    for i in range(q):
        for j in range(q):
            work[i, j] = a[i, j]
    perm = ia[t : t + q]
    t += q
    for i in range(q):
        perm[i] = i
    dmax = 0.0
    for i in range(q):
        dmax = max(dmax, work[i, i])
    r = 0
    for k in range(q):
        p = k
        for j in range(k + 1, q):
            if work[j, j] > work[p, p]:
                p = j
        if not work[p, p] > RANK * dmax:
            break
        if p != k:  # symmetric swap of rows and columns k and p
            for j in range(q):
                work[k, j], work[p, j] = work[p, j], work[k, j]
            for j in range(q):
                work[j, k], work[j, p] = work[j, p], work[j, k]
            perm[k], perm[p] = perm[p], perm[k]
        piv = math.sqrt(work[k, k])
        work[k, k] = piv
        for i in range(k + 1, q):
            work[i, k] /= piv
        for j in range(k + 1, q):
            for i in range(j, q):
                work[i, j] -= work[i, k] * work[j, k]
                work[j, i] = work[i, j]
        r += 1
    # basic solution: L1 L1^T y = rhs_perm[:r], the rest zero
    y = fa[t : t + q]
    t += q
    for i in range(q):
        y[i] = 0.0
    for i in range(r):
        y[i] = rhs[perm[i]]
    _cholesky_solve(work, y[:r])
    nn = q - r
    if nn == 0:
        for i in range(q):
            x[perm[i]] = y[i]
        return 0
    # null basis in permuted order: [-L1^-T L2^T; I]
    nb = fa[t : t + q * nn].reshape((q, nn))
    t += q * nn
    for i in range(q):
        for c in range(nn):
            nb[i, c] = 0.0
    for c in range(nn):
        nb[r + c, c] = 1.0
        # solve L1^T z = -L2[c, :]  (L2 rows are work[r + c, :r])
        for i in range(r - 1, -1, -1):
            s = -work[r + c, i]
            for j in range(i + 1, r):
                s -= work[j, i] * nb[j, c]
            nb[i, c] = s / work[i, i]
    # project the basic solution's null-space part out: y - N (N^T N)^-1 N^T y. N's rows
    # r.. are the identity and y's are zero: the sums over them add 1.0 (a diagonal entry)
    # or zeros, so they run over rows :r only (the same bits), and N^T N is symmetric
    ntn, nty, z, t = _normal_arrays(fa, t, nn)
    for c1 in range(nn):
        s = 0.0
        for i in range(r):
            s += nb[i, c1] * y[i]
        nty[c1] = s
        for c2 in range(c1, nn):
            s = 0.0
            for i in range(r):
                s += nb[i, c1] * nb[i, c2]
            if c2 == c1:
                s += 1.0
            ntn[c1, c2] = s
            ntn[c2, c1] = s
    _spd_solve(ntn, nty, nn, z, fa, t)
    for i in range(r):
        s = y[i]
        for c in range(nn):
            s -= nb[i, c] * z[c]
        x[perm[i]] = s
    for c in range(nn):
        x[perm[r + c]] = 0.0 - z[c]
    for c in range(nn):
        size = 0.0
        for i in range(r):
            size += nb[i, c] * nb[i, c]
        size += 1.0
        size = math.sqrt(size)
        for i in range(r):
            null[perm[i], c] = nb[i, c] / size
        for c2 in range(nn):
            null[perm[r + c2], c] = 0.0
        null[perm[r + c], c] = 1.0 / size
    return nn


#: LAPACK's divide-and-conquer SVD as NumPy's ``np.linalg.svd`` calls it in compiled code
#: (Numba's helper ``numba_ez_gesdd``, which takes its own workspace): called here on arrays
#: of the scratch arena, so that a leaf (:data:`_leaf`) can take an SVD.
_GESDD = _LAPACK().numba_ez_gesdd(numba.types.float64)


@_leaf
def _svd_into(a, q, fa, top):  # type: ignore[no-untyped-def]
    """``u, s, vt`` of ``a[:q, :q] = u diag(s) vt`` (singular values descending): the same
    call of LAPACK's ``dgesdd`` (``jobz = 'A'``) on the same column-major copy as NumPy's
    ``np.linalg.svd`` makes, so the same bits; ``u`` and ``vt`` are views of the arena ``fa``
    (``3 q^2 + q`` from ``top``), valid until the arena is written there again. Raises
    NumPy's ``LinAlgError`` on a non-finite entry, as ``np.linalg.svd`` does. It returns
    views of an arena that it does not own: called by compiled leaves only, never from
    Python (nor from a counting caller, which would release what it never held). Its
    caller :func:`_svd_solve`:

    >>> a = np.array([[3.0, 0.0], [4.0, 5.0]])
    >>> x, null = np.empty(2), np.empty((2, 2))
    >>> _svd_solve(a, np.array([3.0, 9.0]), 2, x, null, np.empty(arena_size(1, 2)), 0)
    0
    >>> bool(np.allclose(x, [1.0, 1.0], rtol=0, atol=1e-15))
    True
    """
    acpy = fa[top : top + q * q]
    for j in range(q):
        for i in range(q):
            v = a[i, j]
            if not math.isfinite(v):
                raise np.linalg.LinAlgError("Array must not contain infs or NaNs.")
            acpy[j * q + i] = v  # (column-major, as LAPACK reads it)
    t = top + q * q
    s = fa[t : t + q]
    ubuf = fa[t + q : t + q + q * q]
    vtbuf = fa[t + q + q * q : t + q + 2 * q * q]
    info = _GESDD(_KIND_DOUBLE, _JOBZ_ALL, q, q, acpy.ctypes, q, s.ctypes, ubuf.ctypes, q,
                  vtbuf.ctypes, q)  # fmt: skip
    if info != 0:
        raise ValueError("Internal algorithm failed to converge.")
    return ubuf.reshape((q, q)).T, s, vtbuf.reshape((q, q)).T


_KIND_DOUBLE = ord("d")
_JOBZ_ALL = ord("A")


@_leaf
def _svd_solve(a, rhs, q, x, null, fa, top):  # type: ignore[no-untyped-def]
    """The reference's solve of a general ``a[:q, :q] x = rhs``: SVD, rank to 1e-10 of the
    largest singular value, minimum norm; the null space's orthonormal basis into ``null``.
    The SVD is :func:`_svd_into`'s (NumPy's, to the bit), in the arena ``fa`` from ``top``."""
    u, s, vt = _svd_into(a, q, fa, top)
    rank = 0
    if s[0] > 0.0:
        for i in range(q):
            if s[i] > RANK * s[0]:
                rank += 1
    for i in range(q):
        x[i] = 0.0
    for k in range(rank):
        c = 0.0
        for i in range(q):
            c += u[i, k] * rhs[i]
        c /= s[k]
        for i in range(q):
            x[i] += vt[k, i] * c
    nn = q - rank
    for c in range(nn):
        for i in range(q):
            null[i, c] = vt[rank + c, i]
    return nn


@_leaf
def _qr_solve(a, rhs, q, x, null, fa, ia, top):  # type: ignore[no-untyped-def]
    """:func:`_qr_solve_into` with its workspaces in the arenas ``fa``/``ia`` from ``top``."""
    return _qr_solve_into(a, rhs, q, x, null, fa[top : top + 2 * q * q].reshape((2 * q, q)),
                          fa[top + 2 * q * q : top + 2 * q * q + 3 * q].reshape((3, q)),
                          ia[top : top + q])  # fmt: skip


@_leaf
def _qr_solve_into(a, rhs, q, x, null, mats, vecs, perm):  # type: ignore[no-untyped-def]
    """The reference's minimum-norm (least-squares) solve of ``a[:q, :q] x = rhs``, without
    LAPACK's allocations: Householder QR with column pivoting (Golub and Van Loan, *Matrix
    Computations*, 4th ed., algorithm 5.4.1) reveals the rank, the basic solution has its
    null-space part ``[-R11^-1 R12; I]`` projected out, and that basis, orthonormalized,
    goes into ``null``. Returns the null space's dimension, or -1 when a diagonal entry of
    ``R`` lies between 1e-13 and 1e-6 of the largest: there QR's rank could differ from the
    SVD's (cut at 1e-10 of the largest singular value), and the caller asks the SVD.
    Workspaces (none allocated here: the slip angles' Newton iteration solves a dozen such
    systems per regime): ``mats`` (>= 2q x q), ``vecs`` (>= 3 x q), ``perm`` (>= q, int)."""
    r = mats[:q, :q]
    nb = mats[q : 2 * q, :q]
    qtb = vecs[0]
    v = vecs[1]
    y = vecs[2]
    for i in range(q):
        perm[i] = i
        qtb[i] = rhs[i]
        for j in range(q):
            r[i, j] = a[i, j]
    rank = q
    d0 = 0.0
    for k in range(q):
        p = k
        best = -1.0
        for j in range(k, q):
            s = 0.0
            for i in range(k, q):
                s += r[i, j] * r[i, j]
            if s > best:
                best = s
                p = j
        if p != k:
            for i in range(q):
                r[i, k], r[i, p] = r[i, p], r[i, k]
            perm[k], perm[p] = perm[p], perm[k]
        alpha = math.sqrt(best)
        if k == 0:
            d0 = alpha
            if not d0 > 0.0:
                rank = 0
                break
        ratio = alpha / d0
        if ratio <= 1e-13:
            rank = k
            break
        if ratio <= 1e-6:
            return -1
        if r[k, k] > 0.0:
            alpha = -alpha
        # the reflector I - 2 v v^T / v.v taking r[k:, k] to alpha e_k
        vv = 0.0
        for i in range(k, q):
            v[i] = r[i, k]
        v[k] -= alpha
        for i in range(k, q):
            vv += v[i] * v[i]
        if vv > 0.0:
            for j in range(k, q):
                s = 0.0
                for i in range(k, q):
                    s += v[i] * r[i, j]
                f = 2.0 * s / vv
                for i in range(k, q):
                    r[i, j] -= f * v[i]
            s = 0.0
            for i in range(k, q):
                s += v[i] * qtb[i]
            f = 2.0 * s / vv
            for i in range(k, q):
                qtb[i] -= f * v[i]
    # basic solution: R11 y = (Q^T b)[:rank], the rest zero
    for i in range(q):
        y[i] = 0.0
    for i in range(rank - 1, -1, -1):
        s = qtb[i]
        for j in range(i + 1, rank):
            s -= r[i, j] * y[j]
        y[i] = s / r[i, i]
    nn = q - rank
    if nn == 0:
        for i in range(q):
            x[perm[i]] = y[i]
        return 0
    for i in range(q):
        for c in range(nn):
            nb[i, c] = 0.0
    for c in range(nn):
        nb[rank + c, c] = 1.0
        for i in range(rank - 1, -1, -1):  # R11 z = -R12[:, c]
            s = -r[i, rank + c]
            for j in range(i + 1, rank):
                s -= r[i, j] * nb[j, c]
            nb[i, c] = s / r[i, i]
    # orthonormal basis (modified Gram-Schmidt: nb has full column rank), then project
    for c in range(nn):
        for c2 in range(c):
            s = 0.0
            for i in range(q):
                s += nb[i, c2] * nb[i, c]
            for i in range(q):
                nb[i, c] -= s * nb[i, c2]
        s = 0.0
        for i in range(q):
            s += nb[i, c] * nb[i, c]
        s = math.sqrt(s)
        for i in range(q):
            nb[i, c] /= s
    for c in range(nn):
        s = 0.0
        for i in range(q):
            s += nb[i, c] * y[i]
        for i in range(q):
            y[i] -= s * nb[i, c]
    for i in range(q):
        x[perm[i]] = y[i]
        for c in range(nn):
            null[perm[i], c] = nb[i, c]
    return nn


@_leaf
def _solve(g, rows, b, m, q, symmetric, rhs, x, null, a, fa, ia, top):  # type: ignore[no-untyped-def]
    """``(G_R B) x = rhs`` in minimum norm, ``G_R B`` into ``a`` (q x q); returns the null
    space's dimension. Scratch in the arenas ``fa``/``ia`` from ``top``."""
    for i in range(q):
        for j in range(q):
            if symmetric:  # B selects the rows (unit columns): G_R B is G_RR, to the bit
                a[i, j] = g[rows[i], rows[j]]
                continue
            s = 0.0
            for r in range(m):
                s += g[rows[i], r] * b[r, j]
            a[i, j] = s
    if symmetric:
        # (G_R B is G_RR here; symmetrized, as the reference's check_problem does)
        for i in range(q):
            for j in range(i + 1, q):
                v = 0.5 * (a[i, j] + a[j, i])
                a[i, j] = v
                a[j, i] = v
        return _sym_solve(a, rhs, q, x, null, fa, ia, top)
    nn = _qr_solve(a, rhs, q, x, null, fa, ia, top)
    if nn < 0:
        nn = _svd_solve(a, rhs, q, x, null, fa, top)
    return nn


#: :func:`_body_min_norm`'s test of ``J_R^T J_R``'s pivots, each relative to its own diagonal
#: entry (scale-free: a pivot is the squared distance of a column from the previous ones'
#: span, per its squared length): below it the general solve decides the rank.
BODY_PIVOT = 1e-8


@_leaf
def _body_min_norm(jac, mass, inertia, rows, q, rhs, x, tol, y, a, du, z):  # type: ignore[no-untyped-def]
    """The minimum-norm ``x`` of ``G_RR x = rhs`` for one free body against a fixed obstacle,
    in its 6 velocities instead of the ``q`` contact rows (issue 14's batch): with
    ``G = J M^-1 J^T`` (``J`` the body's Jacobian rows ``R``, ``M = diag(m I, J_C)``) of full
    column rank, ``G^+ = J (J^T J)^-1 M (J^T J)^-1 J^T``, so

        du = (J^T J)^-1 J^T rhs,   x = J (J^T J)^-1 M du

    (``du``, rad/s and m/s: the body's change of velocity; ``x``, N s). Two 6 x 6 solves with
    one Cholesky factor, where the rows' own system is 12 x 12 of rank 6 (pivoted Cholesky,
    a null-space basis and its projection: :func:`_sym_solve`). Returns False, ``x``
    untouched, unless ``J^T J``'s pivots pass :data:`BODY_PIVOT` and the rows are reached,
    ``|J du - rhs| <= tol / 2`` (m/s): the general route then decides (the rank and the
    consistency at their own thresholds). ``y`` (6) receives ``M du = J^T x`` (N s), the
    generalized impulse every member of the family shares (:func:`_body_weighted`); ``a``
    (6 x 6), ``du``, ``z`` (6): workspaces.

    >>> jac = np.zeros((9, 6))
    >>> for c, (px, py) in enumerate(((1.0, 0.0), (0.0, 1.0), (-1.0, -1.0))):
    ...     jac[3 * c, 2], jac[3 * c, 3], jac[3 * c, 4] = 1.0, py, -px      # normal z
    ...     jac[3 * c + 1, 0], jac[3 * c + 1, 5] = 1.0, -py                 # tangent x
    ...     jac[3 * c + 2, 1], jac[3 * c + 2, 5] = 1.0, px                  # tangent y
    >>> rows, rhs, x = np.arange(9), jac @ np.array([0, 0, 2.0, 0, 0, 0]), np.zeros(9)
    >>> ws = np.empty(6), np.empty((6, 6)), np.empty(6), np.empty(6)
    >>> _body_min_norm(jac, 3.0, np.eye(3), rows, 9, rhs, x, 1e-9, *ws)
    True
    >>> [round(float(v), 12) for v in x[0::3]]  # 2 m/s up, 3 kg: 2 N s at each corner
    [2.0, 2.0, 2.0]
    """
    if not _normal_factor(jac, rows, q, du, np.bool_(False), a):  # (du: unused weights)
        return False
    for i in range(6):
        s = 0.0
        for r in range(q):
            s += jac[rows[r], i] * rhs[r]
        du[i] = s
    _cholesky_solve(a, du)
    for r in range(q):
        s = -rhs[r]
        for i in range(6):
            s += jac[rows[r], i] * du[i]
        if not abs(s) <= 0.5 * tol:
            return False
    for i in range(3):
        z[i] = mass * du[i]
        z[3 + i] = inertia[i, 0] * du[3] + inertia[i, 1] * du[4] + inertia[i, 2] * du[5]
    for i in range(6):
        y[i] = z[i]
    _cholesky_solve(a, z)
    for r in range(q):
        s = 0.0
        for i in range(6):
            s += jac[rows[r], i] * z[i]
        x[r] = s
    return True


@_leaf
def _body_weighted(jac, pattern, nrow, trow, ntan, mu, rows, q, x, y, weights, a, lam):  # type: ignore[no-untyped-def]
    """The reference's ``_capacity_weighted`` (:func:`_capacity_weighted`) in the body's
    velocities: of the impulses ``x`` with ``J^T x = y`` (the family of :func:`_body_min_norm`,
    ``x`` its minimum-norm member, replaced), the least weighted norm ``|D x|``, a sticking
    contact's tangent rows weighted by ``1 / (mu P_n)``, the rest by ``1 / max |x|``:

        x = D^-2 J (J^T D^-2 J)^-1 y

    (the unique minimizer of a strictly convex quadratic on the family, so the rows' route's
    answer to round-off). Returns False, ``x`` untouched, when ``J^T D^-2 J`` fails
    :data:`BODY_PIVOT`. ``weights`` (m), ``a`` (6 x 6), ``lam`` (6): workspaces.

    >>> jac = np.zeros((9, 6))
    >>> for c, (px, py) in enumerate(((1.0, 0.0), (0.0, 1.0), (-1.0, -1.0))):
    ...     jac[3 * c, 2], jac[3 * c, 3], jac[3 * c, 4] = 1.0, py, -px
    ...     jac[3 * c + 1, 0], jac[3 * c + 1, 5] = 1.0, -py
    ...     jac[3 * c + 2, 1], jac[3 * c + 2, 5] = 1.0, px
    >>> x, y = np.zeros(9), np.array([0.0, 0, 6.0, 0, 0, 0])
    >>> x[0::3] = 2.0
    >>> _body_weighted(jac, np.full(3, STICK_OPT), np.arange(0, 9, 3),
    ...                np.arange(9).reshape(3, 3)[:, 1:], np.full(3, 2), np.full(3, 0.5),
    ...                np.arange(9), 9, x, y, np.empty(9), np.empty((6, 6)), np.empty(6))
    True
    >>> [round(float(v), 12) for v in x[0::3]]  # already the least: 2 N s at each corner
    [2.0, 2.0, 2.0]
    """
    pmax = 0.0
    for j in range(q):
        pmax = max(pmax, abs(x[j]))
    pmax = max(pmax, 2.2250738585072014e-308)
    m = jac.shape[0]
    for r in range(m):  # (per row, as the reference's)
        weights[r] = 1.0 / pmax
    for c in range(nrow.shape[0]):
        if pattern[c] == STICK_OPT and mu[c] > 0.0:
            pn = 0.0
            for j in range(q):
                if rows[j] == nrow[c]:
                    pn = x[j]
            cap = max(mu[c] * pn, 1e-3 * pmax)
            for j in range(ntan[c]):
                weights[trow[c, j]] = 1.0 / cap
    if not _normal_factor(jac, rows, q, weights, np.bool_(True), a):
        return False
    for i in range(6):
        lam[i] = y[i]
    _cholesky_solve(a, lam)
    for r in range(q):
        d = 1.0 / weights[rows[r]]
        s = 0.0
        for i in range(6):
            s += jac[rows[r], i] * lam[i]
        x[r] = s * (d * d)
    return True


@_leaf
def _normal_factor(jac, rows, q, weights, weighted, a):  # type: ignore[no-untyped-def]
    """The Cholesky factor (lower, into ``a``, 6 x 6) of ``J^T D^-2 J`` over the rows
    ``rows[:q]`` of ``jac``, ``D = diag(weights)`` per row where ``weighted`` (else ``I``);
    returns False where a pivot fails :data:`BODY_PIVOT` (``J`` short of full column rank,
    to that precision)."""
    for i in range(6):
        for j in range(i + 1):
            s = 0.0
            for r in range(q):
                d = 1.0 / weights[rows[r]] if weighted else 1.0
                s += jac[rows[r], i] * jac[rows[r], j] * (d * d)
            a[i, j] = s
    for j in range(6):  # Cholesky, lower, in place
        s = a[j, j]
        for p in range(j):
            s -= a[j, p] * a[j, p]
        if not s > BODY_PIVOT * a[j, j]:
            return False
        piv = math.sqrt(s)
        a[j, j] = piv
        for i in range(j + 1, 6):
            s = a[i, j]
            for p in range(j):
                s -= a[i, p] * a[j, p]
            a[i, j] = s / piv
    return True


@_leaf
def _cholesky_solve(low, v):  # type: ignore[no-untyped-def]
    """``v <- (L L^T)^-1 v`` in place, ``L`` the lower triangle of ``low`` (n x n)."""
    n = v.shape[0]
    for i in range(n):
        s = v[i]
        for p in range(i):
            s -= low[i, p] * v[p]
        v[i] = s / low[i, i]
    for i in range(n - 1, -1, -1):
        s = v[i]
        for p in range(i + 1, n):
            s -= low[p, i] * v[p]
        v[i] = s / low[i, i]


#: One contact's residual: :func:`carnot.laws.cone.contact_law_residual` itself, compiled as a
#: leaf (the rule's one statement, which ``solve_impact``'s law runs as Python).
law_residual = compiled_rules(cone, ("project_onto_cone", "contact_law_residual"), _LEAF,
                              _RULES)["contact_law_residual"]  # fmt: skip


@_leaf
def contact_residual(c, g, nrow, trow, ntan, kind, e, mu, imp, w, wa, part):  # type: ignore[no-untyped-def]
    """The natural-map residual of contact ``c`` (m/s): :func:`carnot.laws.multiple.rows.
    contact_residual` for a contact that is not told to stick, from the rows of ``imp``,
    ``w`` and ``wa``."""
    n = nrow[c]
    rho = 1.0 / max(g[n, n], 2.2250738585072014e-308)
    nt = ntan[c]
    t1 = trow[c, 0]
    t2 = trow[c, 1]
    return law_residual(part, kind == FRICTIONLESS_KIND, mu[c], rho, imp[n],
                        imp[t1] if nt >= 1 else 0.0, imp[t2] if nt >= 2 else 0.0,
                        wa[n] + e[c] * w[n], wa[t1] if nt >= 1 else 0.0,
                        wa[t2] if nt >= 2 else 0.0)  # fmt: skip


@_leaf
def _margin(lin_a, lin_c, nlin, cones, ncones, b, x, q, g, trow):  # type: ignore[no-untyped-def]
    """The smallest slack of the regime's inequalities at ``x`` (m/s); +inf when none."""
    slack = np.inf
    for i in range(nlin):
        s = lin_c[i]
        for j in range(q):
            s += lin_a[i, j] * x[j]
        slack = min(slack, s)
    for k in range(ncones):
        n, c, mu = cones[k, 0], cones[k, 1], cones[k, 2]
        pn = 0.0
        p1 = 0.0
        p2 = 0.0
        t1, t2 = trow[int(c), 0], trow[int(c), 1]
        for j in range(q):
            pn += b[int(n), j] * x[j]
            p1 += b[t1, j] * x[j]
            p2 += b[t2, j] * x[j]
        slack = min(slack, g[int(n), int(n)] * (mu * pn - math.sqrt(p1 * p1 + p2 * p2)))
    return slack


@_leaf
def _zero(x_all, null_all, q):  # type: ignore[no-untyped-def]
    """A regime's unknowns ``x_all[:q]`` and null-space basis ``null_all[:q * q]`` (q x q)
    set to zero before its solve."""
    for i in range(q):
        x_all[i] = 0.0
    for i in range(q * q):
        null_all[i] = 0.0


@_leaf
def linear_regime(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, scale, imp, wa, lws, fa,  # type: ignore[no-untyped-def]
                  ia, top, holds):  # fmt: skip
    """One regime with fixed slip directions (the reference's ``_linear_regime``): writes the
    impulses and velocities after into ``imp`` and ``wa``; returns ``(status, not_unique,
    continuum)`` with status 1 when it holds, 0 when not, 2 when only a linear program over
    its rank-deficient family could tell (:data:`NEEDS_REFERENCE` for the impact). Scratch
    in the arenas ``fa``/``ia`` from ``top`` (:func:`arena_size`). ``holds``:
    :func:`regime_holds`' C callback."""
    m = w.shape[0]
    gb, lin_a, lin_c, cones, b, rows, targets, x_all, null_all, rhs_all, a_all = lws
    q, symmetric = _columns(m, nrow, trow, ntan, mu, e, pattern, w, dirs, b, rows, targets)
    _zero(x_all, null_all, q)
    x = x_all[:q]
    null = null_all[: q * q].reshape((q, q))
    nn = 0
    rhs = rhs_all[:q]
    a = a_all[: q * q].reshape((q, q))
    if q > 0:
        for i in range(q):
            rhs[i] = targets[i] - w[rows[i]]
        nn = _solve(g, rows, b, m, q, symmetric, rhs, x, null, a, fa, ia, top)
    return _held(holds(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, scale, imp, wa, b,
                       rows, q, symmetric, rhs, a, x, null, nn, (gb, lin_a, lin_c, cones), fa,
                       ia, top))  # fmt: skip


@_leaf
def _root_regime(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, scale, imp, wa, lws, nws,  # type: ignore[no-untyped-def]
                 held, fa, ia, top, holds):  # fmt: skip
    """:func:`linear_regime` at a root of the slip angles (``dirs`` their cosines and sines),
    on the slip system as :func:`_newton_angles` solved it there (its workspaces ``nws``;
    ``held``: how, as it returns) rather than solved again: the same ``B``, rows and
    right-hand side (:func:`_slip_system` builds them with :func:`_columns`; the slip
    columns' entries ``-mu cos``, ``-mu sin`` are the bits of ``-mu dirs``), and ``x`` the
    system's minimum-norm solution, the QR's to round-off. Where the elimination solved
    it, ``A`` is regular (every pivot above :data:`LU_PIVOT` of its largest entry): no null
    space. Where the independent rows did, the null space is the complement of their
    orthonormalized rows (:func:`_complement`), of dimension ``q - nsel``: the rank the
    reference's least squares finds (the other rows depend on those by their structure).
    The same returns as :func:`linear_regime`; the check itself is :func:`regime_holds`
    (``holds``, its C callback)."""
    gb, lin_a, lin_c, cones, _b, _rows, _targets, x_all, null_all, _rhs, _a = lws
    b, rows, rhs, a, x_n, mats, setup = nws[0], nws[1], nws[2], nws[4], nws[6], nws[15], nws[23]
    q = setup[0]
    nsel = setup[1]
    _zero(x_all, null_all, q)
    x = x_all[:q]
    null = null_all[: q * q].reshape((q, q))
    for j in range(q):
        x[j] = x_n[j]
    nn = 0
    if held == MIN_NORM_PATH:
        nn = _complement(mats, nsel, q, null, nws[16][1])
    # A's q x q block copied to the arena, C-contiguous as linear_regime's (a slice of it
    # is another Numba type than the callback's; regime_holds reads A for the residual only)
    a_q = fa[top : top + q * q].reshape((q, q))
    for i in range(q):
        for j in range(q):
            a_q[i, j] = a[i, j]
    return _held(holds(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, scale, imp, wa, b,
                       rows, q, np.bool_(False), rhs[:q], a_q, x, null, nn,
                       (gb, lin_a, lin_c, cones), fa, ia, top + q * q))  # fmt: skip


@_leaf
def _complement(u, nsel, q, null, y):  # type: ignore[no-untyped-def]
    """An orthonormal basis of the complement of the ``nsel`` orthonormal rows ``u[:nsel, :q]``
    in ``R^q``, into the first ``q - nsel`` columns of ``null``; returns ``q - nsel``. Each
    vector is the unit vector ``e_j`` that keeps the most of its length once made orthogonal
    to the rows and the vectors before it (at least ``1 / sqrt(q)`` of it, far from
    round-off), by :func:`_orthonormalize` as a row of ``u`` after them: ``u``'s rows
    ``nsel`` to ``q - 1`` are overwritten. ``y`` (>= q): workspace.

    >>> u, null = np.array([[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [0.0, 0.0, 0.0]]), np.zeros((3, 3))
    >>> _complement(u, 2, 3, null, np.zeros(3))
    1
    >>> [round(float(t), 12) for t in null[:, 0]]
    [0.0, 0.8, -0.6]
    """
    for i in range(q):
        y[i] = 0.0  # (carried through the steps, and not wanted)
    for c in range(q - nsel):
        row = nsel + c
        best = -1.0
        pick = 0
        for j in range(q):  # (the length e_j keeps: 1 - |its projection|^2)
            kept = 1.0
            for i in range(row):
                kept -= u[i, j] * u[i, j]
            if kept > best:
                best = kept
                pick = j
        for j in range(q):
            u[row, j] = 0.0
        u[row, pick] = 1.0
        _orthonormalize(u, y, row, q, 0.0)
        for j in range(q):
            null[j, c] = u[row, j]
    return q - nsel


@_leaf
def _holds_code(status, not_unique, continuum):  # type: ignore[no-untyped-def]
    """``(status, not_unique, continuum)`` of a regime's check in one integer (a C callback
    returns one number): ``status + 4 not_unique + 8 continuum``; :func:`_held` decodes it.

    >>> _held(_holds_code(1, True, False))
    (1, True, False)
    """
    return status + (4 if not_unique else 0) + (8 if continuum else 0)


@_leaf
def _held(code):  # type: ignore[no-untyped-def]
    """:func:`_holds_code`'s ``(status, not_unique, continuum)`` again."""
    return code & 3, (code & 4) != 0, (code & 8) != 0


def regime_holds(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, scale, imp, wa, b, rows,  # type: ignore[no-untyped-def]
                 q, symmetric, rhs, a, x, null, nn, hws, fa, ia, top):  # fmt: skip
    """:func:`linear_regime` once its system ``a x = rhs`` is solved (``x`` minimum norm,
    ``nn`` columns of ``null`` its null space; ``b``, ``rows``, ``q``, ``symmetric`` of
    :func:`_columns`): the same returns, coded in one integer (:func:`_holds_code`: a C
    callback, :func:`impact_solvers`, called by its address from the regime solvers and
    :func:`solve_into`, so that LLVM optimizes it and its linear programs once). Split so
    that the regime the prediction solved (every taking-part contact closed or sticking) is
    not solved again: ``x`` may be replaced (a point of the family that meets the
    inequalities). ``hws``: workspaces
    (``gb``, ``lin_a``, ``lin_c``, ``cones`` of :func:`regime_workspace`); the inequalities and
    the check of the velocities after are the leaves :func:`_inequalities` and
    :func:`_outcome_holds`, shared with :func:`_holds_fast`. Scratch: the arenas ``fa``/``ia``
    from ``top``."""
    m = w.shape[0]
    tol = FEASIBILITY * scale
    if q > 0:
        worst = 0.0
        for i in range(q):
            s = -rhs[i]
            for j in range(q):
                s += a[i, j] * x[j]
            worst = max(worst, abs(s))
        if worst > tol:
            return 0
    # gb = G B
    gb, lin_a, lin_c, cones = hws  # (workspaces: (m, q), (3 k, q), 3 k, (k, 3) used)
    gbmax = 0.0
    for j in range(q):
        if symmetric:  # (B selects the rows: G B is G's columns R, to the bit)
            for i in range(m):
                s = g[i, rows[j]]
                gb[i, j] = s
                gbmax = max(gbmax, abs(s))
            continue
        # over the column's non-zero rows (three at most: a contact's normal and tangents),
        # in the dense loop's order: an added +-0 changes no bit, so these are its bits
        r0 = r1 = r2 = -1
        more = False
        for r in range(m):
            if b[r, j] != 0.0:
                if r0 < 0:
                    r0 = r
                elif r1 < 0:
                    r1 = r
                elif r2 < 0:
                    r2 = r
                else:
                    more = True
        for i in range(m):
            s = 0.0
            if more:
                for r in range(m):
                    s += g[i, r] * b[r, j]
            else:
                if r0 >= 0:
                    s += g[i, r0] * b[r0, j]
                if r1 >= 0:
                    s += g[i, r1] * b[r1, j]
                if r2 >= 0:
                    s += g[i, r2] * b[r2, j]
            gb[i, j] = s
            gbmax = max(gbmax, abs(s))
    # the inequalities (the reference's _inequalities)
    nlin, ncones = _inequalities(g, w, nrow, trow, kind, e, mu, pattern, dirs, b, q, gb, lin_a,
                                 lin_c, cones)  # fmt: skip
    margin0 = _margin(lin_a, lin_c, nlin, cones, ncones, b, x, q, g, trow)
    not_unique = False
    continuum = False
    if nn > 0:
        worst = 0.0
        for i in range(m):
            for c2 in range(nn):
                s = 0.0
                for j in range(q):
                    s += gb[i, j] * null[j, c2]
                worst = max(worst, abs(s))
        continuum = worst > 1e-9 * max(1.0, gbmax)
        if margin0 <= tol and ncones > 0:
            margin0 = _capacity_weighted(pattern, kind, nrow, trow, ntan, mu, b, x, null, q,
                                         nn, m, fa, top)  # fmt: skip
            margin0 = _margin(lin_a, lin_c, nlin, cones, ncones, b, x, q, g, trow)
        if margin0 > tol:
            not_unique = not continuum
        else:
            if nn == 1:
                margin = _most_feasible_1d(lin_a, lin_c, nlin, cones, ncones, b, x, null, q,
                                           g, trow, scale, fa, top)  # fmt: skip
            else:
                ok, margin = _most_feasible_nd(lin_a, lin_c, nlin, cones, ncones, b, x, null,
                                               q, nn, g, trow, scale, fa, ia, top)  # fmt: skip
                if not ok:
                    return 2  # the reference's linear program decides
            if margin < -tol and ncones > 0:
                # none by the inscribed polygons: the cones themselves (the reference's
                # _exact_cones; x is a member of the family, wherever the program left it)
                status, margin = _exact_cones(lin_a, lin_c, nlin, cones, ncones, b, x, null,
                                              q, nn, g, trow, scale, tol, fa, ia,
                                              top)  # fmt: skip
                if status == 2:
                    return 2
            if margin < -tol:
                return 0
            not_unique = margin > tol and not continuum
    elif margin0 < -tol:
        return 0
    if not _outcome_holds(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, b, x, q, imp,
                          wa, tol):  # fmt: skip
        return 0
    return _holds_code(np.int64(1), not_unique, continuum)


@_leaf
def _outcome_holds(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, b, x, q, imp, wa, tol):  # type: ignore[no-untyped-def]
    """The impulses ``imp = B x`` and velocities after ``wa = w' + G imp`` of a regime whose
    inequalities hold at ``x``, into ``imp`` and ``wa``; returns whether each slipping
    contact slips its way and every contact's residual is within ``tol`` (m/s)."""
    m = w.shape[0]
    k = nrow.shape[0]
    for i in range(m):
        s = 0.0
        for j in range(q):
            s += b[i, j] * x[j]
        imp[i] = s
    for i in range(m):
        s = w[i]
        for r in range(m):
            s += g[i, r] * imp[r]
        wa[i] = s
    if not _slips_as_assumed(trow, pattern, dirs, wa, tol):
        return False
    residual = 0.0
    for c in range(k):
        residual = max(residual, contact_residual(c, g, nrow, trow, ntan, kind[c], e, mu, imp,
                                                  w, wa, pattern[c] != OUT))  # fmt: skip
    return residual <= tol


@_leaf
def _holds_fast(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, scale, imp, wa, b, q, x,  # type: ignore[no-untyped-def]
                gb, lin_a, lin_c, cones):  # fmt: skip
    """:func:`regime_holds` where ``x`` is :func:`_body_min_norm`'s (or
    :func:`_body_weighted`'s), for a regime of closed and sticking contacts: the rows are
    already checked as reached, the velocities after are unique (``G_RR n = 0`` implies
    ``G n = 0`` for a positive semi-definite ``G``: no continuum) and the impulses are not
    (the body has 6 velocities, the regime more rows). Returns 1 when it holds (then
    statically indeterminate), 0 when not, 3 when ``x`` misses an inequality: the family is
    needed, and the caller asks :func:`regime_holds`. A leaf (:data:`_leaf`)."""
    tol = FEASIBILITY * scale
    nlin, ncones = _inequalities(g, w, nrow, trow, kind, e, mu, pattern, dirs, b, q, gb, lin_a,
                                 lin_c, cones)  # fmt: skip
    if not _margin(lin_a, lin_c, nlin, cones, ncones, b, x, q, g, trow) > tol:
        return 3
    if not _outcome_holds(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs, b, x, q, imp, wa,
                          tol):  # fmt: skip
        return 0
    return 1


#: :func:`_stick_impossible`'s safety factor on its bound of what the tolerance admits (the
#: bound is 2; the factor leaves a decision near the edge to the linear program).
IMPOSSIBLE_MARGIN = 20.0


@_leaf
def _stick_impossible(body_jac, y, nrow, part, base, kind, mu, g, tol):  # type: ignore[no-untyped-def]
    """Whether no impulse of the prediction's family (every taking-part contact closed or
    sticking, one free body against a fixed obstacle) can meet the friction cones, proved
    without the family's linear program: every member ``x`` gives the body the same
    generalized impulse ``y = J^T x`` (N s, :func:`_body_min_norm`), whose linear part
    ``Y = sum_c P_c`` is the sum of the contacts' impulses. A direction ``d`` in the dual
    of every contact's cone (``d . n_c >= mu_c |d - (d . n_c) n_c|``, ``n_c`` its unit
    normal, ``mu_c = 0`` frictionless) has ``d . P_c >= 0`` on each cone, so
    ``d . Y >= 0`` for any member inside the cones (Farkas' lemma, as a certificate);
    within the regime's tolerance (each slack ``>= -tol`` m/s, so ``p_n`` and
    ``mu p_n - |p_t|`` ``>= -eps_c = -tol / G_nn``), ``d . Y >= -2 |d| sum_c eps_c``. The
    direction tried: ``d = mu_max n - t``, ``n`` the contacts' mean normal, ``t`` the unit
    tangential part of ``Y`` (for a common normal, the best: ``d . Y = mu_max Y_n - |Y_t|``,
    the landing's tangential impulse beyond what the cones can give in sum). True where
    ``d . Y < -IMPOSSIBLE_MARGIN |d| sum_c eps_c``: the regime does not hold, as the linear
    program and the exact cones would find (:func:`regime_holds`) at several times their
    cost. False (undecided) otherwise. A leaf (:data:`_leaf`).

    >>> jac = np.zeros((9, 6))
    >>> for c in range(3):
    ...     jac[3 * c, 2], jac[3 * c + 1, 0], jac[3 * c + 2, 1] = 1.0, 1.0, 1.0
    >>> nrow, part = np.array([0, 3, 6]), np.ones(3, dtype=np.bool_)
    >>> base, kind = np.full(3, STICK_OPT, np.int8), np.full(3, SPATIAL, np.int8)
    >>> g = np.eye(9)  # (only the diagonal is read)
    >>> y = np.array([-3.0, 0.0, 2.0, 0.0, 0.0, 0.0])  # 3 N s sideways, 2 N s up
    >>> bool(_stick_impossible(jac, y, nrow, part, base, kind, np.full(3, 0.5), g, 1e-9))
    True
    >>> bool(_stick_impossible(jac, y, nrow, part, base, kind, np.full(3, 1.5), g, 1e-9))
    False
    """
    k = nrow.shape[0]
    n0 = n1 = n2 = 0.0
    mu_max = 0.0
    for c in range(k):
        if not part[c]:
            continue
        if base[c] != STICK_OPT and base[c] != CLOSED:
            return False
        r = nrow[c]
        n0 += body_jac[r, 0]
        n1 += body_jac[r, 1]
        n2 += body_jac[r, 2]
        if base[c] == STICK_OPT:
            mu_max = max(mu_max, mu[c])
    norm = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if not norm > 0.0:
        return False
    n0, n1, n2 = n0 / norm, n1 / norm, n2 / norm
    yn = y[0] * n0 + y[1] * n1 + y[2] * n2
    t0, t1, t2 = y[0] - yn * n0, y[1] - yn * n1, y[2] - yn * n2
    yt = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
    if not yt > 0.0:
        return False
    d0 = mu_max * n0 - t0 / yt
    d1 = mu_max * n1 - t1 / yt
    d2 = mu_max * n2 - t2 / yt
    dd = d0 * d0 + d1 * d1 + d2 * d2
    eps = 0.0
    for c in range(k):
        if not part[c]:
            continue
        r = nrow[c]
        a0, a1, a2 = body_jac[r, 0], body_jac[r, 1], body_jac[r, 2]
        an = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if not an > 0.0 or not g[r, r] > 0.0:
            return False
        dn = (d0 * a0 + d1 * a1 + d2 * a2) / an
        dt = math.sqrt(max(dd - dn * dn, 0.0))
        mu_c = mu[c] if base[c] == STICK_OPT else 0.0
        if not dn >= mu_c * dt:
            return False
        eps += tol / g[r, r]
    return d0 * y[0] + d1 * y[1] + d2 * y[2] < -IMPOSSIBLE_MARGIN * math.sqrt(dd) * eps


@_leaf
def _capacity_weighted(pattern, kind, nrow, trow, ntan, mu, b, x, null, q, nn, m, fa, top):  # type: ignore[no-untyped-def]
    """The reference's ``_capacity_weighted``: over ``x + N z``, the least weighted norm of
    the impulses, a sticking contact's tangential rows weighted by ``1 / (mu P_n)``; ``x``
    is replaced (normal equations of the small weighted least-squares problem). Scratch in
    the arena ``fa`` from ``top``."""
    t = top
    p0 = fa[t : t + m]
    t += m
    pmax = 0.0
    for i in range(m):
        s = 0.0
        for j in range(q):
            s += b[i, j] * x[j]
        p0[i] = s
        pmax = max(pmax, abs(s))
    pmax = max(pmax, 2.2250738585072014e-308)
    weights = fa[t : t + m]
    t += m
    for i in range(m):
        weights[i] = 1.0 / pmax
    for c in range(nrow.shape[0]):
        if pattern[c] == STICK_OPT and mu[c] > 0.0:
            cap = max(mu[c] * p0[nrow[c]], 1e-3 * pmax)
            for j in range(ntan[c]):
                weights[trow[c, j]] = 1.0 / cap
    wbn = fa[t : t + m * nn].reshape((m, nn))
    t += m * nn
    wbx = fa[t : t + m]
    t += m
    for i in range(m):
        for c in range(nn):
            s = 0.0
            for j in range(q):
                s += b[i, j] * null[j, c]
            wbn[i, c] = weights[i] * s
        wbx[i] = weights[i] * p0[i]
    # the normal equations of min |wbn z + wbx| (wbn has full column rank: B N does)
    ata, atb, z, t = _normal_arrays(fa, t, nn)
    for c1 in range(nn):
        s = 0.0
        for i in range(m):
            s -= wbn[i, c1] * wbx[i]
        atb[c1] = s
        for c2 in range(nn):
            s = 0.0
            for i in range(m):
                s += wbn[i, c1] * wbn[i, c2]
            ata[c1, c2] = s
    _spd_solve(ata, atb, nn, z, fa, t)
    for j in range(q):
        s = x[j]
        for c in range(nn):
            s += null[j, c] * z[c]
        x[j] = s
    return 0.0


_POLYGON = 32  # sides of the polygon inscribed in the cone (the reference's linear program)
_FACET_COS = np.cos(2.0 * np.pi * (np.arange(_POLYGON) + 0.5) / _POLYGON)
_FACET_SIN = np.sin(2.0 * np.pi * (np.arange(_POLYGON) + 0.5) / _POLYGON)
_HALF = math.cos(math.pi / _POLYGON)


@_leaf
def _most_feasible_1d(lin_a, lin_c, nlin, cones, ncones, b, x, null, q, g, trow, scale, fa,  # type: ignore[no-untyped-def]
                      top):  # fmt: skip
    """The reference's linear program (``_most_feasible``: over ``x + N z`` maximize the
    smallest slack, capped at the velocity scale, each cone by its inscribed 32-gon) for a
    one-dimensional family, solved exactly: the smallest slack is a concave piecewise-linear
    function of ``z``, so its maximum is at the crossing of a rising and a falling line (or
    where a line meets the cap). ``x`` is replaced by the maximizer; returns the exact
    margin there (cones exact, as the reference re-checks it). Scratch in the arena ``fa``
    from ``top``."""
    size = nlin + _POLYGON * ncones + 1
    alpha = fa[top : top + size]
    beta = fa[top + size : top + 2 * size]
    n_lines = 0
    for i in range(nlin):
        sa = 0.0
        sb = lin_c[i]
        for j in range(q):
            sa += lin_a[i, j] * null[j, 0]
            sb += lin_a[i, j] * x[j]
        alpha[n_lines] = sa
        beta[n_lines] = sb
        n_lines += 1
    half = math.cos(math.pi / _POLYGON)
    for k in range(ncones):
        n, c, mu = int(cones[k, 0]), int(cones[k, 1]), cones[k, 2]
        t1, t2 = trow[c, 0], trow[c, 1]
        gnn = g[n, n]
        for f in range(_POLYGON):
            angle = 2.0 * math.pi * (f + 0.5) / _POLYGON
            ca, sa_ = math.cos(angle), math.sin(angle)
            sa = 0.0
            sb = 0.0
            for j in range(q):
                row = gnn * (mu * half * b[n, j] - ca * b[t1, j] - sa_ * b[t2, j])
                sa += row * null[j, 0]
                sb += row * x[j]
            alpha[n_lines] = sa
            beta[n_lines] = sb
            n_lines += 1
    alpha[n_lines] = 0.0  # the cap: t <= scale
    beta[n_lines] = scale
    n_lines += 1
    # The answer is the first candidate below (in its order) whose smallest slack is the
    # largest; a candidate whose slack is at most a value that some point reaches cannot be
    # it. So the search starts from such a value, found by bisection on the concave envelope
    # (its slope the slope of the lowest line) and lowered by 1e-9 of the velocity scale (and
    # of itself), far above round-off: the same candidate wins, without computing the many
    # that cannot.
    reached = _envelope_floor(alpha, beta, n_lines)
    floor = reached - 1e-9 * (scale + abs(reached))
    best_z = _best_candidate(alpha, beta, n_lines, floor)
    if not math.isfinite(best_z):  # (none above the floor: cannot happen; the full search)
        best_z = _best_candidate(alpha, beta, n_lines, -np.inf)
    for j in range(q):
        x[j] += null[j, 0] * best_z
    return _margin(lin_a, lin_c, nlin, cones, ncones, b, x, q, g, trow)


@_leaf
def _envelope(alpha, beta, n_lines, z):  # type: ignore[no-untyped-def]
    """The lowest of the lines ``alpha z + beta`` at ``z`` and its slope (the first lowest)."""
    t = np.inf
    slope = 0.0
    for r in range(n_lines):
        v = alpha[r] * z + beta[r]
        if v < t:
            t = v
            slope = alpha[r]
    return t, slope


@_leaf
def _envelope_floor(alpha, beta, n_lines):  # type: ignore[no-untyped-def]
    """A value the lowest line reaches at some ``z`` (the larger the better: near the
    maximum of the concave envelope, by doubling steps to bracket its peak, then bisection).

    >>> _envelope_floor(np.array([1.0, -1.0, 0.0]), np.array([0.0, 2.0, 5.0]), 3)
    1.0
    """
    best, slope = _envelope(alpha, beta, n_lines, 0.0)
    if slope == 0.0 or not math.isfinite(best):
        return best
    direction = 1.0 if slope > 0.0 else -1.0
    inner = 0.0
    outer = direction
    for _ in range(1100):  # (the cap's line is flat: the slope turns within 2^1100)
        t, slope = _envelope(alpha, beta, n_lines, outer)
        best = max(best, t)
        if not slope * direction > 0.0:
            break
        inner = outer
        outer *= 2.0
    for _ in range(100):
        mid = 0.5 * (inner + outer)
        if mid == inner or mid == outer:
            break
        t, slope = _envelope(alpha, beta, n_lines, mid)
        best = max(best, t)
        if slope * direction > 0.0:
            inner = mid
        elif slope == 0.0:
            break
        else:
            outer = mid
    return best


@_leaf
def _best_candidate(alpha, beta, n_lines, floor):  # type: ignore[no-untyped-def]
    """The reference's maximizer over the candidates of :func:`_most_feasible_1d`: the first
    whose smallest slack is the largest, among those above ``floor``; NaN when none is."""
    best_t = floor
    best_z = np.nan
    # candidates: z = 0, crossings of a rising line with a falling one or with the cap
    for i in range(n_lines):
        for j in range(i, n_lines):
            if i == j:
                if i != 0:
                    continue
                z = 0.0
            elif alpha[i] * alpha[j] < 0.0 or (alpha[i] == 0.0) != (alpha[j] == 0.0):
                z = (beta[j] - beta[i]) / (alpha[i] - alpha[j])
            else:
                continue
            if alpha[i] * z + beta[i] <= best_t:
                continue  # (line i is among those minimized below: t cannot be taken)
            # t only falls along r: once it is at most the best so far, this candidate
            # cannot be taken (the test below is strict), so stop (the same answer as the
            # full minimum, in a fraction of the O(n^3) work)
            t = np.inf
            for r in range(n_lines):
                t = min(t, alpha[r] * z + beta[r])
                if t <= best_t:
                    break
            if t > best_t:
                best_t = t
                best_z = z
    return best_z


#: Pivots of the compiled linear program (:func:`_most_feasible_nd`) before it gives up (the
#: impact then goes to the reference; never reached in the tests and benchmarks).
_LP_PIVOTS = 500
#: A regime whose linear program's dual bound falls below this fraction of the velocity
#: scale fails (:func:`_most_feasible_nd`): the exact margin cannot recover that much.
_HOPELESS = 0.1


@_leaf
def _on_family(lin_a, lin_c, nlin, cones, ncones, b, trow, x, null, q, nn, lin_alpha, lin_beta,  # type: ignore[no-untyped-def]
               at, along):  # fmt: skip
    """The regime's inequalities along its family ``x + N z``: each linear one as ``lin_alpha
    z + lin_beta`` (``(nlin, nn)``, ``(nlin,)``), and each cone's three impulse rows (normal,
    tangents) at ``x`` (``at``, ``(ncones, 3)``) and along ``N`` (``along``, ``(ncones, 3,
    nn)``): a facet of a cone is linear in those three."""
    for i in range(nlin):
        sb = lin_c[i]
        for j in range(q):
            sb += lin_a[i, j] * x[j]
        lin_beta[i] = sb
        for c in range(nn):
            sa = 0.0
            for j in range(q):
                sa += lin_a[i, j] * null[j, c]
            lin_alpha[i, c] = sa
    for k in range(ncones):
        n, cc = int(cones[k, 0]), int(cones[k, 1])
        for a in range(3):
            r = n if a == 0 else trow[cc, a - 1]
            sb = 0.0
            for j in range(q):
                sb += b[r, j] * x[j]
            at[k, a] = sb
            for c in range(nn):
                sa = 0.0
                for j in range(q):
                    sa += b[r, j] * null[j, c]
                along[k, a, c] = sa


@_leaf
def _family_arrays(fa, top, lines, ncones, nn):  # type: ignore[no-untyped-def]
    """The arrays of :func:`_on_family` carved from the arena ``fa`` at ``top``: ``alpha``
    (lines x nn), ``beta`` (lines), ``along`` (ncones x 3 x nn), ``at`` (ncones x 3), and
    the arena's next free place. Views of the arena: for leaves only (see
    :func:`_svd_into`)."""
    t = top
    alpha = fa[t : t + lines * nn].reshape((lines, nn))
    t += lines * nn
    beta = fa[t : t + lines]
    t += lines
    along = fa[t : t + ncones * 3 * nn].reshape((ncones, 3, nn))
    t += ncones * 3 * nn
    at = fa[t : t + ncones * 3].reshape((ncones, 3))
    t += ncones * 3
    return alpha, beta, along, at, t


@_leaf
def _most_feasible_nd(lin_a, lin_c, nlin, cones, ncones, b, x, null, q, nn, g, trow, scale, fa,  # type: ignore[no-untyped-def]
                      ia, top):  # fmt: skip
    """The reference's linear program (``_most_feasible``) for a family ``x + N z`` of any
    dimension ``nn``: maximize ``t`` subject to ``alpha_i . z + beta_i >= t`` (each linear
    inequality, each cone by the facets of its inscribed 32-gon) and ``t <= scale``.

    Solved by the primal simplex method on its dual, ``min beta . y`` subject to
    ``sum_i y_i alpha_i = 0``, ``sum_i y_i = 1``, ``y >= 0`` (Chvatal, *Linear Programming*,
    1983, ch. 2-3: dense tableau, Dantzig's entering rule, Bland's rule after 50 degenerate
    pivots so that it cannot cycle). The dual is feasible at ``y`` = the cap's row alone,
    with artificial variables (zero) on the ``nn`` equality rows, which are pivoted out first
    (a row that cannot be: the inequalities do not depend on that direction, it stays at 0).
    The primal optimum is the simplex multipliers ``pi = c_B B^-1``: ``z = -pi[:nn]``,
    ``t = pi[nn]``. The problem is small (``nn <= 12`` unknowns, at most ``3 k + 32 k + 1``
    inequalities), so a dense tableau serves where SciPy's HiGHS (the reference) cannot be
    called: inside a compiled loop. ``x`` is replaced by the maximizer; returns ``(ok,
    margin)``, the exact margin there (cones exact, as the reference re-checks it); ``ok``
    False when the pivot limit was reached. Scratch in the arenas ``fa``/``ia`` from
    ``top``."""
    size = nlin + _POLYGON * ncones + 1
    alpha, beta, along, at, t = _family_arrays(fa, top, size, ncones, nn)
    _on_family(lin_a, lin_c, nlin, cones, ncones, b, trow, x, null, q, nn, alpha, beta, at,
               along)  # fmt: skip
    line = nlin
    for k in range(ncones):
        n, mu = int(cones[k, 0]), cones[k, 2]
        gnn = g[n, n]
        for f in range(_POLYGON):
            f0, f1, f2 = gnn * mu * _HALF, -gnn * _FACET_COS[f], -gnn * _FACET_SIN[f]
            beta[line] = f0 * at[k, 0] + f1 * at[k, 1] + f2 * at[k, 2]
            for c in range(nn):
                alpha[line, c] = (f0 * along[k, 0, c] + f1 * along[k, 1, c]
                                  + f2 * along[k, 2, c])  # fmt: skip
            line += 1
    cap = line  # the cap: t <= scale
    for c in range(nn):
        alpha[cap, c] = 0.0
    beta[cap] = scale
    z = fa[t : t + nn]
    t += nn
    status, most = _max_min_slack(alpha, beta, size, nn, scale, z, fa, ia, t)
    if status == LP_LIMIT:
        return False, -np.inf
    if status == LP_HOPELESS:
        return True, most
    for j in range(q):
        s = x[j]
        for c in range(nn):
            s += null[j, c] * z[c]
        x[j] = s
    return True, _margin(lin_a, lin_c, nlin, cones, ncones, b, x, q, g, trow)


#: The most cutting-plane rounds of :func:`_exact_cones` (each a linear program; the
#: reference's ``EXACT_CONE_ROUNDS``).
EXACT_CONE_ROUNDS = 60


@_leaf
def _exact_cones(lin_a, lin_c, nlin, cones, ncones, b, x, null, q, nn, g, trow, scale, tol, fa,  # type: ignore[no-untyped-def]
                 ia, top):  # fmt: skip
    """The reference's ``_exact_cones``: over the family ``x + N z``, impulses meeting the
    inequalities and the circular cones exactly (slack >= ``-tol``), by Kelley's cutting
    planes (Kelley 1960). Each cone starts as its *circumscribed* 32-gon (``mu P_n >= d .
    P_t`` for 32 directions ``d``: a necessary condition), the linear program
    (:func:`_max_min_slack`) maximizes the smallest slack ``t``, and a cone violated at the
    answer gets the tangent plane along its tangential impulse there. The program's ``t``
    bounds the cones' best slack from above, so ``t < -tol`` proves there is none. Returns
    ``(status, margin)``: status 1 with ``x`` replaced by impulses in the cones (``margin``
    their exact smallest slack), 0 when there are none, 2 when the linear program reached its
    pivot limit (the reference decides). Scratch in the arenas ``fa``/``ia`` from ``top``."""
    most = _POLYGON + EXACT_CONE_ROUNDS
    o = top
    dirs = fa[o : o + ncones * most * 2].reshape((ncones, most, 2))
    o += ncones * most * 2
    ndirs = ia[o : o + ncones]
    o += ncones
    for k in range(ncones):
        for f in range(_POLYGON):
            dirs[k, f, 0] = _FACET_COS[f]
            dirs[k, f, 1] = _FACET_SIN[f]
        ndirs[k] = _POLYGON
    # the linear inequalities, and each cone's three impulse rows, at x and along N
    lin_alpha, lin_beta, along, at, o = _family_arrays(fa, o, nlin, ncones, nn)
    _on_family(lin_a, lin_c, nlin, cones, ncones, b, trow, x, null, q, nn, lin_alpha, lin_beta,
               at, along)  # fmt: skip
    lines = nlin + ncones * most + 1
    alpha = fa[o : o + lines * nn].reshape((lines, nn))
    o += lines * nn
    beta = fa[o : o + lines]
    o += lines
    z = fa[o : o + nn]
    o += nn
    trial = fa[o : o + q]
    o += q
    for _round in range(EXACT_CONE_ROUNDS):
        line = 0
        for i in range(nlin):
            beta[line] = lin_beta[i]
            for c in range(nn):
                alpha[line, c] = lin_alpha[i, c]
            line += 1
        for k in range(ncones):
            gnn = g[int(cones[k, 0]), int(cones[k, 0])]
            mu = cones[k, 2]
            for f in range(ndirs[k]):
                f0, f1, f2 = gnn * mu, -gnn * dirs[k, f, 0], -gnn * dirs[k, f, 1]
                beta[line] = f0 * at[k, 0] + f1 * at[k, 1] + f2 * at[k, 2]
                for c in range(nn):
                    alpha[line, c] = f0 * along[k, 0, c] + f1 * along[k, 1, c] + f2 * along[k, 2, c]
                line += 1
        for c in range(nn):  # the cap: t <= scale
            alpha[line, c] = 0.0
        beta[line] = scale
        line += 1
        status, t = _max_min_slack(alpha, beta, line, nn, scale, z, fa, ia, o)
        if status == LP_LIMIT:
            return 2, -np.inf
        if status == LP_HOPELESS or t < -tol:
            return 0, t  # even the outer polygons hold no impulse: the cones hold none
        for j in range(q):
            v = x[j]
            for c in range(nn):
                v += null[j, c] * z[c]
            trial[j] = v
        margin = _margin(lin_a, lin_c, nlin, cones, ncones, b, trial, q, g, trow)
        if margin >= -tol:
            for j in range(q):
                x[j] = trial[j]
            return 1, margin
        added = False
        for k in range(ncones):
            n, cc, mu = int(cones[k, 0]), int(cones[k, 1]), cones[k, 2]
            pn = 0.0
            p1 = 0.0
            p2 = 0.0
            t1, t2 = trow[cc, 0], trow[cc, 1]
            for j in range(q):
                pn += b[n, j] * trial[j]
                p1 += b[t1, j] * trial[j]
                p2 += b[t2, j] * trial[j]
            norm_t = math.sqrt(p1 * p1 + p2 * p2)
            if norm_t > 0.0 and g[n, n] * (mu * pn - norm_t) < -tol and ndirs[k] < most:
                dirs[k, ndirs[k], 0] = p1 / norm_t  # the tangent plane where it is violated
                dirs[k, ndirs[k], 1] = p2 / norm_t
                ndirs[k] += 1
                added = True
        if not added:  # pragma: no cover - a violated cone always gets its cut
            return 0, margin
    return 0, -np.inf


#: Outcomes of :func:`_max_min_slack`.
LP_OPTIMUM, LP_LIMIT, LP_HOPELESS = 0, 1, 2


@_leaf
def _max_min_slack(alpha, beta, size, nn, scale, z, fa, ia, top):  # type: ignore[no-untyped-def]
    """Maximize ``t`` subject to ``alpha_i . z + beta_i >= t`` (rows ``i < size``; the
    last is the cap ``t <= scale``) by the simplex method on the dual (see
    :func:`_most_feasible_nd`): returns ``(status, t)``, the maximizer into ``z``.
    ``status``: :data:`LP_OPTIMUM`; :data:`LP_LIMIT` (the pivot limit: ``t`` is -inf);
    :data:`LP_HOPELESS` (the dual bound ``t`` fell below :data:`_HOPELESS` of the velocity
    scale: the optimum is lower still; ``z`` is not set). Its tableau in the arenas
    ``fa``/``ia`` from ``top``."""
    rows = nn + 1
    cap = size - 1
    amax = 0.0
    for i in range(size):
        for c in range(nn):
            amax = max(amax, abs(alpha[i, c]))
    eps = 1e-12 * max(amax, 1.0)
    # tableau: columns 0..size-1 the y's, then the nn artificials; inv = B^-1 alongside
    cols = size + nn
    t = top
    tab = fa[t : t + rows * cols].reshape((rows, cols))
    t += rows * cols
    rhs = fa[t : t + rows]
    t += rows
    inv = fa[t : t + rows * rows].reshape((rows, rows))
    t += rows * rows
    cost = fa[t : t + cols]
    t += cols
    pi = fa[t : t + rows]
    t += rows
    for r in range(rows):
        rhs[r] = 0.0
        for j in range(cols):
            tab[r, j] = 0.0
        for j in range(rows):
            inv[r, j] = 0.0
    for j in range(cols):
        cost[j] = 0.0
    for i in range(size):
        for c in range(nn):
            tab[c, i] = alpha[i, c]
        tab[nn, i] = 1.0
        cost[i] = beta[i]
    for c in range(nn):
        tab[c, size + c] = 1.0
    rhs[nn] = 1.0
    for r in range(rows):
        inv[r, r] = 1.0
    basis = ia[t : t + rows]
    t += rows
    for c in range(nn):
        basis[c] = size + c
    basis[nn] = cap
    in_basis = ia[t : t + cols]  # (0 or 1)
    t += cols
    for j in range(cols):
        in_basis[j] = 0
    for r in range(rows):
        in_basis[basis[r]] = 1
    pivots = 0

    # pivot the artificials out where a y column has a non-zero entry in their row
    for r in range(nn):
        best = np.int64(-1)
        size_best = eps
        for j in range(size):
            if abs(tab[r, j]) > size_best and not in_basis[j]:
                size_best = abs(tab[r, j])
                best = j
        if best >= 0:
            in_basis[basis[r]] = 0
            in_basis[best] = 1
            _pivot(tab, rhs, inv, basis, r, best)
    degenerate = 0
    while True:
        pivots += 1
        if pivots > _LP_PIVOTS:
            return LP_LIMIT, -np.inf
        # pi = c_B B^-1 and the reduced costs of the y columns (artificials never enter)
        for r in range(rows):
            pi[r] = 0.0
        for r in range(rows):
            cb = cost[basis[r]] if basis[r] < size else 0.0
            for s in range(rows):
                pi[s] += cb * inv[r, s]
        enter = np.int64(-1)
        most = 0.0
        bland = degenerate > 50
        for j in range(size):
            if in_basis[j]:
                continue  # (its reduced cost is zero: round-off must not re-enter it)
            red = cost[j]
            for c in range(nn):
                red -= pi[c] * alpha[j, c]
            red -= pi[nn]
            if red < -1e-13 * max(abs(cost[j]), scale):
                if bland:
                    enter = j
                    break
                if red < most:
                    most = red
                    enter = j
        if enter < 0:
            break
        # the dual objective bounds the primal optimum from above and only falls: far below
        # zero, no point of the family can meet the inequalities (the 32-gon's gap to the
        # exact cone is below 0.5 % of mu G_nn P_n), so the regime fails whatever the
        # maximizer; stop here
        bound = 0.0
        for r in range(rows):
            if basis[r] < size:
                bound += cost[basis[r]] * rhs[r]
        if bound < -_HOPELESS * scale:
            return LP_HOPELESS, bound
        leave = np.int64(-1)
        ratio = np.inf
        for r in range(rows):
            if tab[r, enter] > eps:
                v = rhs[r] / tab[r, enter]
                if v < ratio or (v == ratio and basis[r] < basis[leave]):
                    ratio = v
                    leave = r
        if leave < 0:  # pragma: no cover - the primal is feasible, so the dual is bounded
            return LP_LIMIT, -np.inf
        degenerate = degenerate + 1 if ratio <= 0.0 else 0
        in_basis[basis[leave]] = 0
        in_basis[enter] = 1
        _pivot(tab, rhs, inv, basis, leave, enter)
    for c in range(nn):
        z[c] = -pi[c]
    return LP_OPTIMUM, pi[nn]


@_leaf
def _pivot(tab, rhs, inv, basis, r, j):  # type: ignore[no-untyped-def]
    """One simplex pivot of the tableau (and ``B^-1`` beside it) on row ``r``, column ``j``."""
    rows, cols = tab.shape
    p = tab[r, j]
    for cc in range(cols):
        tab[r, cc] /= p
    for s in range(rows):
        inv[r, s] /= p
    rhs[r] /= p
    for rr in range(rows):
        if rr == r:
            continue
        f = tab[rr, j]
        if f == 0.0:
            continue
        for cc in range(cols):
            tab[rr, cc] -= f * tab[r, cc]
        for s in range(rows):
            inv[rr, s] -= f * inv[r, s]
        rhs[rr] -= f * rhs[r]
        if rhs[rr] < 0.0 and rhs[rr] > -1e-15:
            rhs[rr] = 0.0
    basis[r] = j


@_leaf
def _slip_system(g, w, nrow, trow, ntan, mu, e, pattern, slipping, ns, b, rows, rhs, grows,  # type: ignore[no-untyped-def]
                 a, col, rowcol, dirs, targets):  # fmt: skip
    """The slip regime's system once for all its slip angles (the reference's ``parallel``
    builds it once as well): ``B`` with the slip columns' tangent entries zero, the rows it
    fixes, ``rhs = w''_R - w'_R``, ``G_R`` (``grows``), ``A = G_R B`` (its columns that do not
    slip: the slip columns are set with the angles by :func:`_parallel`), each slipping
    contact's column ``col[s]`` and each contact row's column ``rowcol[r]`` (-1: none).

    A row of ``B`` has at most one non-zero entry (a contact's normal and tangent rows
    belong to its own columns), a column at most three (a slip column: its contact's normal
    and tangent rows, in this order): products with ``B`` skip its zeros and add the rest in
    the order of the dense loops (an added ``+-0`` changes no bit), so they are the dense
    products, to the bit. Returns the number ``q`` of columns. ``dirs`` (k x 2, set to zero
    here) and ``targets`` (m): workspaces. A leaf (:data:`_leaf`)."""
    m = w.shape[0]
    for c in range(nrow.shape[0]):
        dirs[c, 0] = 0.0
        dirs[c, 1] = 0.0
    q, _ = _columns(m, nrow, trow, ntan, mu, e, pattern, w, dirs, b, rows, targets)
    for r in range(m):
        rowcol[r] = -1
    for j in range(q):
        for r in range(m):
            if b[r, j] != 0.0:
                rowcol[r] = j
    for s in range(ns):
        n = nrow[slipping[s]]
        for j in range(q):
            if rows[j] == n:
                col[s] = j
        c = slipping[s]
        rowcol[trow[c, 0]] = col[s]
        rowcol[trow[c, 1]] = col[s]
    for i in range(q):
        rhs[i] = targets[i] - w[rows[i]]
        for r in range(m):
            grows[i, r] = g[rows[i], r]
    for j in range(q):
        slip = False
        for s in range(ns):
            slip = slip or col[s] == j
        if slip:  # (set with the angles, by every first evaluation: _parallel's lo = 0)
            continue
        for i in range(q):
            v = 0.0
            for r in range(m):
                if rowcol[r] == j:
                    v += grows[i, r] * b[r, j]
            a[i, j] = v
    return q


#: :func:`_row_basis`'s test: a row of ``G_R`` whose distance from the span of the rows kept
#: before it is at most this fraction of its own length depends on them by the structure (a
#: flat box's four coplanar corners: their normal rows span three velocities, to round-off,
#: some 1e-17); its right-hand side must then follow from theirs to :data:`CONSISTENT` of the
#: largest. And :func:`_min_norm_rows`' test of a kept row at given slip angles (the QR's
#: own threshold for asking the SVD, :func:`_qr_solve_into`).
ROW_DEPENDENT = 1e-13
CONSISTENT = 1e-13
ROW_PIVOT = 1e-6


@_leaf
def _row_basis(grows, rhs, q, m, sel, u, ur):  # type: ignore[no-untyped-def]
    """The rows of a slip system ``A x = rhs`` (``A = G_R B``, :func:`_slip_system`) that are
    independent at every slip angle: those of ``G_R`` (``grows[:q, :m]``) independent of the
    rows before them, by Gram-Schmidt (twice, for orthogonality to round-off) to
    :data:`ROW_DEPENDENT`. A row of ``G_R`` that is a combination of others makes the same
    row of ``A = G_R B`` that combination, whatever ``B``'s slip columns: ``A`` has rank
    ``nsel < q`` at every angle, and the reference's least-squares answer (``lstsq``, its
    singular values beyond the rank cut) is the minimum-norm solution of the kept rows
    (:func:`_min_norm_rows`), where ``rhs`` is consistent: its dependent entries the same
    combination of the kept ones to :data:`CONSISTENT` (checked here once, as the rows are
    the same at every angle). Writes the kept rows' indices into ``sel``; returns their
    number ``nsel``, or ``q`` (no reduction) where every row is independent or ``rhs`` is not
    consistent. ``u`` (>= q x m), ``ur`` (>= q): workspaces.

    >>> grows = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.0, 1.0, 2.0]])
    >>> sel, u, ur = np.zeros(3, dtype=np.int64), np.empty((3, 3)), np.empty(3)
    >>> _row_basis(grows, np.array([1.0, 2.0, 3.0]), 3, 3, sel, u, ur), sel[:2].tolist()
    (2, [0, 1])
    >>> _row_basis(grows, np.array([1.0, 2.0, 4.0]), 3, 3, sel, u, ur)  # (not consistent)
    3
    """
    nsel = np.int64(0)  # (not a literal 0: _orthonormalize compiles once)
    rmax = 0.0
    for i in range(q):
        rmax = max(rmax, abs(rhs[i]))
    for i in range(q):
        for r in range(m):
            u[nsel, r] = grows[i, r]
        ur[nsel] = rhs[i]
        if _orthonormalize(u, ur, nsel, m, ROW_DEPENDENT):
            sel[nsel] = i
            nsel += 1
        elif not abs(ur[nsel]) <= CONSISTENT * rmax:
            return q
    return nsel


@_leaf
def _orthonormalize(u, y, i, n, pivot):  # type: ignore[no-untyped-def]
    """Row ``i`` of ``u`` (its first ``n`` entries) made orthogonal to the orthonormal rows
    before it by Gram-Schmidt, twice (orthogonal to round-off), ``y[i]`` carried through the
    same steps; then, where its length is more than ``pivot`` times its length before,
    scaled to unit length (and ``y[i]`` with it). Returns whether it was.

    >>> u, y = np.array([[1.0, 0.0], [1.0, 1.0]]), np.array([2.0, 3.0])
    >>> _orthonormalize(u, y, 1, 2, 1e-6), u[1].tolist(), float(y[1])
    (True, [0.0, 1.0], 1.0)
    """
    n0 = 0.0
    for j in range(n):
        n0 += u[i, j] * u[i, j]
    for _pass in range(2):
        for p in range(i):
            c = 0.0
            for j in range(n):
                c += u[p, j] * u[i, j]
            for j in range(n):
                u[i, j] -= c * u[p, j]
            y[i] -= c * y[p]
    nrm = 0.0
    for j in range(n):
        nrm += u[i, j] * u[i, j]
    nrm = math.sqrt(nrm)
    if not nrm > pivot * math.sqrt(n0):
        return False
    for j in range(n):
        u[i, j] /= nrm
    y[i] /= nrm
    return True


@_leaf
def _min_norm_rows(a, rhs, q, sel, nsel, x, u, y):  # type: ignore[no-untyped-def]
    """The minimum-norm ``x`` of ``A_S x = rhs_S``, ``A_S`` the rows ``sel[:nsel]`` of
    ``a[:q, :q]``: the rows orthonormalized by Gram-Schmidt (twice), ``A_S = L U`` with ``L``
    lower triangular and ``U``'s rows orthonormal, so that ``x = U^T L^-1 rhs_S`` (the
    right-hand side carried through the same steps is ``L^-1 rhs_S``). Where the other rows
    depend on these (:func:`_row_basis`), it is the reference's least-squares answer to
    round-off, at a fraction of the pivoted QR's cost (:func:`_qr_solve_into`). Returns
    False, ``x`` not set, where a row's distance from the rows before falls to
    :data:`ROW_PIVOT` of its length (the QR then decides the rank). ``u`` (>= nsel x q),
    ``y`` (>= nsel): workspaces.

    >>> a = np.array([[1.0, 1.0], [2.0, 2.0]]); x = np.zeros(2)
    >>> _min_norm_rows(a, np.array([2.0, 4.0]), 2, np.array([0]), 1, x, np.empty((2, 2)),
    ...                np.empty(2)), [round(float(v), 12) for v in x]
    (True, [1.0, 1.0])
    """
    for i in range(nsel):
        row = sel[i]
        for j in range(q):
            u[i, j] = a[row, j]
        y[i] = rhs[row]
        if not _orthonormalize(u, y, i, q, ROW_PIVOT):
            return False
    for j in range(q):
        s = 0.0
        for i in range(nsel):
            s += y[i] * u[i, j]
        x[j] = s
    return True


@_leaf
def _lu_solve(a, rhs, q, x, lu):  # type: ignore[no-untyped-def]
    """``a[:q, :q] x = rhs`` by Gaussian elimination with partial pivoting (into ``x``, ``lu``
    the workspace); returns False when a pivot falls below 1e-7 of the largest entry (then
    the caller takes the SVD's minimum-norm answer, as the reference's ``lstsq`` would)."""
    return _lu_try(a, rhs, q, x, lu) > LU_PIVOT


#: :func:`_lu_solve`'s pivot test (relative to the largest entry), and the pivot below which
#: a slip system is taken as singular by its structure (a flat box's four coplanar corners:
#: normal velocities of rank 3) for the rest of its slip-angle iteration, its elimination
#: not tried again (:func:`_parallel`).
LU_PIVOT = 1e-7
LU_STRUCTURAL = 1e-12
#: :func:`_parallel`'s ``pivot`` where :func:`_min_norm_rows` solved the system (above both
#: tests: the elimination stays skipped, as it was to reach that path).
MIN_NORM_PATH = 2.0


@_leaf
def _lu_try(a, rhs, q, x, lu):  # type: ignore[no-untyped-def]
    """:func:`_lu_solve`, returning 1.0 when it solved ``a x = rhs`` and else the pivot that
    failed the test, relative to the largest entry (0.0 for a zero matrix)."""
    amax = 0.0
    for i in range(q):
        x[i] = rhs[i]
        for j in range(q):
            lu[i, j] = a[i, j]
            amax = max(amax, abs(a[i, j]))
    if not amax > 0.0:
        return 0.0
    for k in range(q):
        p = k
        for i in range(k + 1, q):
            if abs(lu[i, k]) > abs(lu[p, k]):
                p = i
        if not abs(lu[p, k]) > LU_PIVOT * amax:
            return abs(lu[p, k]) / amax
        if p != k:
            for j in range(q):
                lu[k, j], lu[p, j] = lu[p, j], lu[k, j]
            x[k], x[p] = x[p], x[k]
        for i in range(k + 1, q):
            f = lu[i, k] / lu[k, k]
            if f != 0.0:
                for j in range(k + 1, q):
                    lu[i, j] -= f * lu[k, j]
                x[i] -= f * x[k]
    for i in range(q - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, q):
            s -= lu[i, j] * x[j]
        x[i] = s / lu[i, i]
    return 1.0


@_inline_leaf
def _parallel(g, w, nrow, trow, mu, slipping, ns, angles, lo, hi, q, b, rhs, grows, a, col, x,  # type: ignore[no-untyped-def]
              lu, imp, out, mats, vecs, perm, rowcol, cs, skip_lu, sel, nsel):  # fmt: skip
    """The 3D slip conditions ``w_t1'' sin(a) - w_t2'' cos(a)`` of the slipping contacts for
    slip angles ``angles`` (the reference's ``parallel``), on :func:`_slip_system`'s arrays:
    only the slip columns change with the angles, and only those of the slipping contacts
    ``lo <= s < hi`` are set here (the others are already their angles': a finite
    difference changes one). A column's product ``G_R B`` runs over its three non-zero rows
    ``n < t1 < t2`` (the dense loop's order: the same bits); the cosine and sine go into
    ``cs[s]``. The system is solved without allocation: by Gaussian elimination when ``A``
    is well-conditioned (its answer is the reference's least-squares one to round-off) and
    not ``skip_lu``, else by the QR in the workspaces ``mats``, ``vecs``, ``perm`` (the
    SVD's minimum-norm answer where the QR cannot tell the rank). Where the system's rows
    are dependent by their structure (``nsel < q``: :func:`_row_basis`), its minimum-norm
    solution from the ``nsel`` independent rows ``sel`` (:func:`_min_norm_rows`), the QR
    only where those rows are ill-conditioned at these angles. Returns ``(pivot, svd)``:
    :func:`_lu_try`'s pivot (1.0 when the elimination solved it, 0.0 when skipped;
    :data:`MIN_NORM_PATH` when the independent rows did), and whether the QR could not tell
    the rank. ``nsel = -1`` (the first evaluation of an iteration): where the elimination
    finds the system singular by its structure (a pivot below :data:`LU_STRUCTURAL`), it
    returns that pivot at once, ``out`` not set, for the caller to look for the independent
    rows before any QR:
    then ``out`` is not set, and the caller takes the SVD's answer and
    :func:`_slip_conditions` (the caller holds the SVD's scratch arena: :func:`_svd_solve`)."""
    for s in range(lo, hi):
        c = slipping[s]
        j = col[s]
        t1, t2 = trow[c, 0], trow[c, 1]
        co, si = _cos_sin(angles[s])
        cs[s, 0] = co
        cs[s, 1] = si
        b1 = -mu[c] * co
        b2 = -mu[c] * si
        b[t1, j] = b1
        b[t2, j] = b2
        n = nrow[c]  # (b[n, j] = 1)
        for i in range(q):
            v = 0.0
            v += grows[i, n] * b[n, j]
            v += grows[i, t1] * b1
            v += grows[i, t2] * b2
            a[i, j] = v
    pivot = 0.0
    stop = nsel < 0  # (the first evaluation: see the docstring)
    if stop:
        nsel = q
    if nsel < q:
        if _min_norm_rows(a, rhs, q, sel, nsel, x, mats, vecs[0]):
            pivot = MIN_NORM_PATH  # (above LU_PIVOT: no QR)
    elif not skip_lu:
        pivot = _lu_try(a, rhs, q, x, lu)
        if stop and pivot < LU_STRUCTURAL:
            return pivot, False
    if not pivot > LU_PIVOT and _qr_solve_into(a, rhs, q, x, lu, mats, vecs, perm) < 0:
        return pivot, True
    # (one call site: _parallel is copied into its six callers, and this call with it)
    _slip_conditions(g, w, trow, slipping, ns, b, x, imp, out, rowcol, cs)
    return pivot, False


@_leaf
def _slip_conditions(g, w, trow, slipping, ns, b, x, imp, out, rowcol, cs):  # type: ignore[no-untyped-def]
    """:func:`_parallel`'s conditions ``out`` once its system is solved (``x``): the
    impulses ``imp = B x`` and each slipping contact's ``w_t1'' sin(a) - w_t2'' cos(a)``."""
    m = w.shape[0]
    for i in range(m):  # B x: a row of B has one non-zero entry at most (column rowcol[i])
        j = rowcol[i]
        v = 0.0
        if j >= 0:
            v += b[i, j] * x[j]
        imp[i] = v
    for s in range(ns):
        c = slipping[s]
        t1, t2 = trow[c, 0], trow[c, 1]
        wa1 = w[t1]
        wa2 = w[t2]
        for r in range(m):
            if rowcol[r] >= 0:  # (imp[r] is 0 otherwise: adds no bit)
                wa1 += g[t1, r] * imp[r]
                wa2 += g[t2, r] * imp[r]
        out[s] = wa1 * cs[s, 1] - wa2 * cs[s, 0]


@_leaf
def _jacobian_exact(g, w, trow, mu, slipping, ns, q, b, grows, a, col, x, imp, jac, mats,  # type: ignore[no-untyped-def]
                    rowcol, cs, sel, nsel, path, fa, top):  # fmt: skip
    """The slip conditions' Jacobian, exactly, at the angles of the last evaluation
    (:func:`_parallel`, whose system ``A x = rhs``, columns ``cs`` and impulses ``imp`` it
    reads), into ``jac``; returns False (``jac`` not set) where the system is singular (a
    pivot of the elimination below :data:`LU_STRUCTURAL` of the largest entry) but for its
    structure (``path``: how the evaluation solved it, :data:`MIN_NORM_PATH` for the
    independent rows, else its elimination's pivot).

    An angle ``a_j`` moves slip column ``c = col[j]`` of ``B`` alone: its tangent entries
    ``-mu (cos a_j, sin a_j)``, so ``dA_j = d_j e_c^T`` with ``d_j = mu G_R (sin a_j e_t1 -
    cos a_j e_t2)``. Then ``dx_j = -A^-1 d_j x_c`` where ``A`` is regular (elimination, the
    right-hand sides all at once, also where the QR solved an ill-conditioned system: the
    reference's least squares is ``A^-1`` there as well). For the independent rows ``A_S =
    L U`` of a system singular by its structure (:func:`_min_norm_rows`: ``U``'s rows
    orthonormal, ``L = A_S U^T``), the derivative of its minimum-norm solution ``x = A_S^+
    rhs_S``: ``dx_j = -U^T L^-1 d_j x_c + (d_j . z) (e_c - U^T U e_c)``, ``z = L^-T U x``
    (Golub and Pereyra, SIAM J. Numer. Anal. 10, 1973: the derivative of a pseudo-inverse,
    here of a consistent system of full row rank). The velocities' derivative is ``G (B
    dx_j + dB_j x)``, and condition ``f_s = w_t1'' sin a_s - w_t2'' cos a_s`` has
    ``df_s/da_j = dw_t1 sin a_s - dw_t2 cos a_s + [s = j] (w_t1'' cos a_s + w_t2'' sin
    a_s)``. It costs about one and a half evaluations, where the finite differences take
    one per angle; tested against central differences
    (``tests/test_batch_multi.py``). Scratch: the arena ``fa`` from ``top``."""
    m = w.shape[0]
    dx = fa[top : top + q * ns].reshape((q, ns))
    t = top + q * ns
    d = fa[t : t + q * ns].reshape((q, ns))  # (d_j, in column j)
    t += q * ns
    for j in range(ns):
        c = slipping[j]
        t1, t2 = trow[c, 0], trow[c, 1]
        b1 = mu[c] * cs[j, 1]  # (d/da of -mu cos a, -mu sin a)
        b2 = -mu[c] * cs[j, 0]
        for i in range(q):
            d[i, j] = grows[i, t1] * b1 + grows[i, t2] * b2
    if path != MIN_NORM_PATH:
        lu = fa[t : t + q * q].reshape((q, q))
        amax = 0.0
        for i in range(q):
            for j in range(q):
                lu[i, j] = a[i, j]
                amax = max(amax, abs(a[i, j]))
            for j in range(ns):
                dx[i, j] = -d[i, j] * x[col[j]]
        for k in range(q):
            p = k
            for i in range(k + 1, q):
                if abs(lu[i, k]) > abs(lu[p, k]):
                    p = i
            if not abs(lu[p, k]) > LU_STRUCTURAL * amax:
                return False  # (singular: the finite differences)
            if p != k:
                for j in range(q):
                    lu[k, j], lu[p, j] = lu[p, j], lu[k, j]
                for j in range(ns):
                    dx[k, j], dx[p, j] = dx[p, j], dx[k, j]
            for i in range(k + 1, q):
                f = lu[i, k] / lu[k, k]
                if f != 0.0:
                    for j in range(k + 1, q):
                        lu[i, j] -= f * lu[k, j]
                    for j in range(ns):
                        dx[i, j] -= f * dx[k, j]
        for j in range(ns):
            for i in range(q - 1, -1, -1):
                v = dx[i, j]
                for h in range(i + 1, q):
                    v -= lu[i, h] * dx[h, j]
                dx[i, j] = v / lu[i, i]
    else:
        u = mats
        low = fa[t : t + nsel * nsel].reshape((nsel, nsel))
        t += nsel * nsel
        z = fa[t : t + nsel]
        v = fa[t + nsel : t + 2 * nsel]
        for i in range(nsel):
            for k in range(i + 1):
                s = 0.0
                for h in range(q):
                    s += a[sel[i], h] * u[k, h]
                low[i, k] = s
            if not abs(low[i, i]) > 0.0:
                return False
        for i in range(nsel):  # U x
            s = 0.0
            for h in range(q):
                s += u[i, h] * x[h]
            z[i] = s
        for i in range(nsel - 1, -1, -1):  # z = L^-T (U x)
            s = z[i]
            for k in range(i + 1, nsel):
                s -= low[k, i] * z[k]
            z[i] = s / low[i, i]
        for j in range(ns):
            cj = col[j]
            sigma = 0.0
            for i in range(nsel):
                sigma += d[sel[i], j] * z[i]
            for i in range(nsel):  # v = L^-1 d_S x_c
                s = d[sel[i], j] * x[cj]
                for k in range(i):
                    s -= low[i, k] * v[k]
                v[i] = s / low[i, i]
            for h in range(q):
                s = sigma if h == cj else 0.0
                for i in range(nsel):
                    s -= u[i, h] * (v[i] + sigma * u[i, cj])
                dx[h, j] = s
    # G_T B (the slipping contacts' tangent rows; B's non-zero entries: one per row at most,
    # in column rowcol[r]), so that each derivative of the velocities is a sum over the q
    # columns and the two tangent entries that the angle moves
    gtb = fa[t : t + 2 * ns * q].reshape((2 * ns, q))
    for s_ in range(ns):
        cc = slipping[s_]
        for h in range(2):
            tangent = trow[cc, h]
            for i in range(q):
                gtb[2 * s_ + h, i] = 0.0
            for r in range(m):
                jc = rowcol[r]
                if jc >= 0:
                    gtb[2 * s_ + h, jc] += g[tangent, r] * b[r, jc]
    for j in range(ns):
        c = slipping[j]
        t1, t2 = trow[c, 0], trow[c, 1]
        xc = x[col[j]]
        e1 = mu[c] * cs[j, 1] * xc  # (dB_j x: its two tangent entries)
        e2 = -mu[c] * cs[j, 0] * xc
        for s_ in range(ns):
            cc = slipping[s_]
            u1, u2 = trow[cc, 0], trow[cc, 1]
            dw1 = g[u1, t1] * e1 + g[u1, t2] * e2
            dw2 = g[u2, t1] * e1 + g[u2, t2] * e2
            for h in range(q):
                dw1 += gtb[2 * s_, h] * dx[h, j]
                dw2 += gtb[2 * s_ + 1, h] * dx[h, j]
            jac[s_, j] = dw1 * cs[s_, 1] - dw2 * cs[s_, 0]
    for s_ in range(ns):
        cc = slipping[s_]
        wa1 = w[trow[cc, 0]]
        wa2 = w[trow[cc, 1]]
        for h in range(q):
            wa1 += gtb[2 * s_, h] * x[h]
            wa2 += gtb[2 * s_ + 1, h] * x[h]
        jac[s_, s_] += wa1 * cs[s_, 0] + wa2 * cs[s_, 1]
    return True


@_leaf
def _jacobian_fd(g, w, nrow, trow, mu, slipping, ns, angles, q, b, rhs, grows, a, col, x, lu,  # type: ignore[no-untyped-def]
                 imp, f, f2, trial, jac, mats, vecs, perm, rowcol, cs, at_angles,
                 skip_lu, sel, nsel, j, fa, top):  # fmt: skip
    """The slip conditions' Jacobian at ``angles`` by forward differences (step 1e-7 rad)
    into ``jac``, ``f`` the conditions there (``f2``, ``trial``: workspaces), from column
    ``j`` on, where the leaf :func:`_differences` stopped: its difference in angle ``j`` has
    a system only the SVD can solve, finished here (its scratch in the arena ``fa`` from
    ``top``) before :func:`_differences` goes on. ``at_angles``: whether the columns are
    ``angles``' (the last evaluation's); a difference in angle ``j`` sets column ``j`` alone
    (and puts ``j - 1`` back), the same columns, to the bit, as setting all. Leaves the last
    difference's columns. Returns ``skip_lu`` or whether an elimination failed on a structurally
    singular system (:data:`LU_STRUCTURAL`)."""
    while j < ns:
        _svd_solve(a, rhs, q, x, lu, fa, top)
        _slip_conditions(g, w, trow, slipping, ns, b, x, imp, f2, rowcol, cs)
        for i in range(ns):
            jac[i, j] = (f2[i] - f[i]) / ROOT_DIFFERENCE
        skip_lu, j = _differences(g, w, nrow, trow, mu, slipping, ns, angles, q, b, rhs, grows,
                                  a, col, x, lu, imp, f, f2, trial, jac, mats, vecs, perm,
                                  rowcol, cs, at_angles, skip_lu, j + 1, sel,
                                  nsel)  # fmt: skip
    return skip_lu


@_leaf
def _differences(g, w, nrow, trow, mu, slipping, ns, angles, q, b, rhs, grows, a, col, x, lu,  # type: ignore[no-untyped-def]
                 imp, f, f2, trial, jac, mats, vecs, perm, rowcol, cs, at_angles, skip_lu,
                 start, sel, nsel):  # fmt: skip
    """:func:`_jacobian_fd`'s columns from ``start`` on; returns ``(skip_lu, j)``: ``j`` the
    column whose system the QR could not decide (its solve and column left to the caller,
    which goes on from ``j + 1``), or ``ns`` when all are done."""
    for i in range(ns):
        trial[i] = angles[i]
    for j in range(start, ns):
        h = ROOT_DIFFERENCE
        if j > 0:
            trial[j - 1] = angles[j - 1]
        trial[j] += h
        lo, hi = max(j - 1, 0), j + 1
        if j == 0 and not at_angles:
            hi = ns
        pivot, svd = _parallel(g, w, nrow, trow, mu, slipping, ns, trial, lo, hi, q, b, rhs,
                               grows, a, col, x, lu, imp, f2, mats, vecs, perm, rowcol, cs,
                               skip_lu, sel, nsel)  # fmt: skip
        skip_lu = skip_lu or pivot < LU_STRUCTURAL
        if svd:
            return skip_lu, j
        for i in range(ns):
            jac[i, j] = (f2[i] - f[i]) / h
    return skip_lu, ns


@_jit
def newton_workspace(k, m):  # type: ignore[no-untyped-def]
    """The workspaces of :func:`_newton_angles` for ``k`` contacts and ``m`` rows, at their
    largest (a regime uses their leading parts): allocated once per task of a parallel loop,
    not per slip regime and starting direction."""
    return (np.empty((m, m)), np.empty(m, dtype=np.int64), np.empty(m), np.empty((m, m)),
            np.empty((m, m)), np.empty(k, dtype=np.int64), np.empty(m), np.empty((m, m)),
            np.empty(m), np.empty(k), np.empty(k), np.empty((k, k)), np.empty(k), np.empty(k),
            np.empty((k, k)), np.empty((2 * m, m)), np.empty((3, m)),
            np.empty(m, dtype=np.int64), np.empty(m, dtype=np.int64),
            np.empty((k, 2)), np.empty(m, dtype=np.int64), np.empty((k, 2)),
            np.empty(m), np.empty(3, dtype=np.int64))  # fmt: skip


@_leaf
def _newton_angles(g, w, nrow, trow, ntan, mu, e, pattern, dirs, slipping, ns, angles, scale,  # type: ignore[no-untyped-def]
                   nws, fa, top, ready):  # fmt: skip
    """Slip angles where every slipping contact slips along its slip direction: Newton's
    method, the Jacobian exactly at the start (:func:`_jacobian_exact`, where no contact
    sticks and the system is regular or singular by its structure; else by finite
    differences) and by Broyden's update after each step (taken anew when a step fails);
    returns whether the conditions hold to 1e-9 of the velocity scale
    (the reference's acceptance): :data:`ROOT` or :data:`NO_ROOT`, and how the system was
    solved at the angles it ends on (1.0: the elimination; :data:`MIN_NORM_PATH`: the
    independent rows; 0.0: otherwise, or not at those angles), for :func:`_root_regime`,
    which checks the root on that solution rather than solving again. The reference's
    :func:`carnot.laws.multiple.simultaneous.newton_broyden` (its constants:
    :data:`ROOT_STEPS`, :data:`ROOT_DIFFERENCE`) with its exact ``jacobian`` (the same
    choice of where): the same iteration, to round-off in the Jacobian. The residual is
    driven to 1e-15 of the velocity scale; below 1e-12 a step that does not reduce it ends
    the iteration after two halvings (round-off: more would only spend evaluations). The
    SVD's scratch: the arena ``fa`` from ``top``. ``ready``: the regime's slip system is in
    the workspaces ``nws`` from a previous start (the same regime: built once, its
    independent rows and whether its elimination is skipped kept in ``nws``'s last array)."""
    (b, rows, rhs, grows, a, col, x, lu, imp, f, f2, jac, trial, step, null, mats, vecs, perm,
     rowcol, cs, sel, zero_dirs, targets, setup) = nws  # fmt: skip
    # the exact Jacobian where no contact sticks (the reference's choice: in a regime mixing
    # stick and slip, a start that fails wanders, and its path differs between two
    # iterations whose Jacobians differ by round-off), else by finite differences
    exact = True
    for c in range(nrow.shape[0]):
        if pattern[c] == STICK_OPT:
            exact = False
    if ready:
        q, nsel, skip_lu = setup[0], setup[1], setup[2] != 0
        pivot, svd = _parallel(g, w, nrow, trow, mu, slipping, ns, angles, 0, ns, q, b, rhs,
                               grows, a, col, x, lu, imp, f, mats, vecs, perm, rowcol, cs,
                               skip_lu, sel, nsel)  # fmt: skip
        skip_lu = skip_lu or pivot < LU_STRUCTURAL
    else:
        for s in range(ns):
            col[s] = 0
        q = _slip_system(g, w, nrow, trow, ntan, mu, e, pattern, slipping, ns, b, rows, rhs,
                         grows, a, col, rowcol, zero_dirs, targets)  # fmt: skip
        nsel = q
        pivot, svd = _parallel(g, w, nrow, trow, mu, slipping, ns, angles, 0, ns, q, b, rhs,
                               grows, a, col, x, lu, imp, f, mats, vecs, perm, rowcol, cs, False,
                               sel, -1)  # fmt: skip
        # a system singular by its structure stays so at every angle: no elimination tried
        # again, and where its rows depend on each other by their structure, the rest solved
        # from the independent ones (looked for only here: a regular system does not pay for
        # the search), this first evaluation among them (its columns are set: lo = hi)
        skip_lu = pivot < LU_STRUCTURAL
        if skip_lu:
            nsel = _row_basis(grows, rhs, q, w.shape[0], sel, mats, vecs[0])
            pivot, svd = _parallel(g, w, nrow, trow, mu, slipping, ns, angles, ns, ns, q, b,
                                   rhs, grows, a, col, x, lu, imp, f, mats, vecs, perm, rowcol,
                                   cs, True, sel, nsel)  # fmt: skip
        setup[0] = q
        setup[1] = nsel
        setup[2] = 1 if skip_lu else 0
    if svd:
        _svd_solve(a, rhs, q, x, lu, fa, top)
        _slip_conditions(g, w, trow, slipping, ns, b, x, imp, f, rowcol, cs)
    path = 0.0 if svd else pivot  # (how the last evaluation at the angles was solved)
    trial_path = path
    at_angles = True  # whether the columns are the present angles' (the last evaluation's)
    fresh = False  # whether jac is the finite-difference Jacobian at the present angles
    steps = 0
    for it in range(ROOT_STEPS):
        size = 0.0
        for i in range(ns):
            size = max(size, abs(f[i]))
        if size <= 1e-15 * scale or not math.isfinite(size):
            break
        # damped: a step that does not reduce the residual is halved (at most 30 times);
        # when it fails with Broyden's Jacobian, the finite-difference one is taken anew
        # (and at the start)
        size_new = np.inf
        lam = 1.0
        differences = it == 0
        while True:
            if differences:
                # the Jacobian exactly, from the system solved at the angles (evaluated there
                # again after a failed step, or where the independent rows found at the start
                # now solve it); by finite differences where the QR solved it
                if exact and (not at_angles
                              or (path != 1.0 and path != MIN_NORM_PATH and nsel < q)):
                    pivot, svd = _parallel(g, w, nrow, trow, mu, slipping, ns, angles, 0, ns, q,
                                           b, rhs, grows, a, col, x, lu, imp, f2, mats, vecs,
                                           perm, rowcol, cs, skip_lu, sel, nsel)  # fmt: skip
                    if svd:
                        _svd_solve(a, rhs, q, x, lu, fa, top)
                        _slip_conditions(g, w, trow, slipping, ns, b, x, imp, f2, rowcol, cs)
                    skip_lu = skip_lu or pivot < LU_STRUCTURAL
                    path = 0.0 if svd else pivot
                    at_angles = np.bool_(True)
                if not exact or not _jacobian_exact(g, w, trow, mu, slipping, ns, q, b, grows,
                                                    a, col, x, imp, jac, mats, rowcol, cs,
                                                    sel, nsel, path, fa, top):  # fmt: skip
                    skip_lu, j = _differences(g, w, nrow, trow, mu, slipping, ns, angles, q, b,
                                              rhs, grows, a, col, x, lu, imp, f, f2, trial,
                                              jac, mats, vecs, perm, rowcol, cs, at_angles,
                                              skip_lu, np.int64(0), sel, nsel)  # fmt: skip
                    if j < ns:  # (a difference that only the SVD solves)
                        skip_lu = _jacobian_fd(g, w, nrow, trow, mu, slipping, ns, angles, q,
                                               b, rhs, grows, a, col, x, lu, imp, f, f2, trial,
                                               jac, mats, vecs, perm, rowcol, cs, at_angles,
                                               skip_lu, sel, nsel, j, fa, top)  # fmt: skip
                    at_angles = False  # (the last difference's columns)
                fresh = True
            for i in range(ns):
                f2[i] = -f[i]
            if not _lu_solve(jac, f2, ns, step, null):
                _svd_solve(jac, f2, ns, step, fa[top : top + ns * ns].reshape((ns, ns)), fa,
                           top + ns * ns)  # fmt: skip
            lam = 1.0
            halvings = 30 if size > 1e-12 * scale else 2
            for _k in range(halvings):
                for i in range(ns):
                    trial[i] = angles[i] + lam * step[i]
                pivot, svd = _parallel(g, w, nrow, trow, mu, slipping, ns, trial, 0, ns, q, b,
                                       rhs, grows, a, col, x, lu, imp, f2, mats, vecs, perm,
                                       rowcol, cs, skip_lu, sel, nsel)  # fmt: skip
                if svd:
                    _svd_solve(a, rhs, q, x, lu, fa, top)
                    _slip_conditions(g, w, trow, slipping, ns, b, x, imp, f2, rowcol, cs)
                skip_lu = skip_lu or pivot < LU_STRUCTURAL
                trial_path = 0.0 if svd else pivot
                at_angles = False
                size_new = 0.0
                for i in range(ns):
                    size_new = max(size_new, abs(f2[i]))
                if size_new < size:
                    break
                lam *= 0.5
            if size_new < size or fresh:
                break
            differences = True
        if not size_new < size:
            break
        # Broyden's update of the Jacobian along the step taken (as MINPACK's hybr, the
        # reference's root finder, updates its own): one evaluation per iteration where
        # finite differences took one per angle more
        ss = 0.0
        for i in range(ns):
            ss += (lam * step[i]) ** 2
        if ss > 0.0:
            for i in range(ns):
                resid = f2[i] - f[i]
                for j in range(ns):
                    resid -= jac[i, j] * lam * step[j]
                for j in range(ns):
                    jac[i, j] += resid * lam * step[j] / ss
        fresh = False
        steps += 1
        for i in range(ns):
            angles[i] = trial[i]
            f[i] = f2[i]
        at_angles = True  # (the step's evaluation was the last)
        path = trial_path
        small = 0.0
        for i in range(ns):
            small = max(small, abs(lam * step[i]))
        if small <= 1e-14:
            break
    worst = 0.0  # (f holds the conditions at the angles: set with them, or at the start)
    for i in range(ns):
        worst = max(worst, abs(f[i]))
    # the system as solved at the angles, for the root's check (:func:`_root_regime`):
    # where the elimination or the independent rows solved it (x is then its minimum-norm
    # solution there, the QR's to round-off)
    held = path if at_angles and (path == 1.0 or path == MIN_NORM_PATH) else 0.0
    return ROOT if worst <= 1e-9 * scale else NO_ROOT, held


@_leaf
def _velocities(g, w, nrow, trow, ntan, mu, e, pattern, dirs, out, lws, fa, ia, top):  # type: ignore[no-untyped-def]
    """Row velocities after a regime, in least squares (the reference's ``_velocities``);
    in :func:`linear_regime`'s workspaces (never used by both at once)."""
    m = w.shape[0]
    _, _, _, _, b, rows, targets, x_all, null_all, rhs_all, a_all = lws
    q, symmetric = _columns(m, nrow, trow, ntan, mu, e, pattern, w, dirs, b, rows, targets)
    for i in range(m):
        out[i] = w[i]
    if q == 0:
        return
    rhs = rhs_all[:q]
    for i in range(q):
        rhs[i] = targets[i] - w[rows[i]]
    _zero(x_all, null_all, q)
    x = x_all[:q]
    _solve(g, rows, b, m, q, symmetric, rhs, x, null_all[: q * q].reshape((q, q)),
           a_all[: q * q].reshape((q, q)), fa, ia, top)  # fmt: skip
    for i in range(m):
        s = 0.0
        for j in range(q):
            s += b[i, j] * x[j]
        for r in range(m):
            out[r] += g[r, i] * s


@_leaf
def _record(cand_imp, cand_wa, cand_info, ncand, imp, wa, not_unique, continuum, pattern):  # type: ignore[no-untyped-def]
    """A regime that holds, candidate ``ncand`` (its impulses, velocities after, whether its
    impulses are not unique, whether its velocities are not, its pattern); returns
    ``ncand + 1``."""
    for i in range(imp.shape[0]):
        cand_imp[ncand, i] = imp[i]
        cand_wa[ncand, i] = wa[i]
    cand_info[ncand, 0] = not_unique
    cand_info[ncand, 1] = continuum
    for c in range(pattern.shape[0]):
        cand_info[ncand, 2 + c] = pattern[c]
    return ncand + 1


def solve_regime(g, w, nrow, trow, ntan, kind, e, mu, pattern, scale, predicted, has_pred,  # type: ignore[no-untyped-def]
                 first_only, cand_imp, cand_wa, cand_info, ncand, max_cand, nws, rws, top,
                 holds):  # fmt: skip
    """The answers of one regime appended to the candidates (the reference's
    ``_solve_regime``); returns the candidates' new count, or :data:`REGIME_NEEDS_REFERENCE`.
    Scratch: the arenas of ``rws`` from ``top``. Compiled by :func:`impact_solvers` as a C
    callback, which :func:`solve_into` calls by its address (the module's docstring); a
    leaf's body."""
    m = w.shape[0]
    k = nrow.shape[0]
    lws = rws[:11]
    fa = rws[28]
    ia = rws[29]
    slipping = rws[11]
    ns = np.int64(0)
    for c in range(k):
        if pattern[c] == SLIP_OPT:
            slipping[ns] = c
            ns += 1
    dirs = rws[12]
    for c in range(k):
        dirs[c, 0] = 0.0
        dirs[c, 1] = 0.0
    imp = rws[13]
    wa = rws[14]
    if ns == 0:
        status, nu, cont = linear_regime(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs,
                                         scale, imp, wa, lws, fa, ia, top, holds)  # fmt: skip
        if status == 2:
            return REGIME_NEEDS_REFERENCE
        if status == 1 and ncand < max_cand:
            ncand = _record(cand_imp, cand_wa, cand_info, ncand, imp, wa, nu, cont, pattern)
        return ncand
    # starting directions: predicted, frictionless in the slipping contacts, pre-impact slip
    # (lazily, as the reference's generator: the frictionless one needs a solve, and the
    # first start usually serves)
    all_pred = True
    for s in range(ns):
        if not has_pred[slipping[s]]:
            all_pred = False
    angles = rws[15][:ns]
    roots = rws[16]  # (3, ns used)
    nroots = 0
    first = ncand
    w_free = rws[17]
    built = np.int64(0)  # (np.int64: not a literal, so the callee compiles once)
    for gi in range(3):
        if gi == 0:
            if not all_pred:
                continue
            for s in range(ns):
                c = slipping[s]
                angles[s] = math.atan2(predicted[c, 1], predicted[c, 0])
        else:
            if gi == 1:
                free = rws[18]
                for c in range(k):
                    free[c] = pattern[c]
                for s in range(ns):
                    free[slipping[s]] = CLOSED
                _velocities(g, w, nrow, trow, ntan, mu, e, free, dirs, w_free, lws, fa, ia, top)
            for s in range(ns):
                c = slipping[s]
                t1, t2 = trow[c, 0], trow[c, 1]
                a1 = w_free[t1] if gi == 1 else w[t1]
                a2 = w_free[t2] if gi == 1 else w[t2]
                norm = math.sqrt(a1 * a1 + a2 * a2)
                if norm > 0.0:
                    angles[s] = math.atan2(a2 / norm, a1 / norm)
                else:
                    angles[s] = math.atan2(0.0, 1.0)
        found, held = _newton_angles(g, w, nrow, trow, ntan, mu, e, pattern, dirs, slipping,
                                     ns, angles, scale, nws, fa, top, built)  # fmt: skip
        built = np.int64(1)  # (the regime's slip system, for its next start)
        if found == NO_ROOT:
            continue
        # a root already checked gives the same answer again (the reference's _same_angles)
        seen = False
        for r in range(nroots):
            same = True
            for s in range(ns):
                d = angles[s] - roots[r, s]
                d -= 2.0 * math.pi * math.floor(d / (2.0 * math.pi) + 0.5)
                if not abs(d) <= SAME_ROOT:
                    same = False
            if same:
                seen = True
        if seen:
            continue
        for s in range(ns):
            roots[nroots, s] = angles[s]
        nroots += 1
        for s in range(ns):
            c = slipping[s]
            dirs[c, 0], dirs[c, 1] = _cos_sin(angles[s])
        if held > 0.0:
            status, nu, cont = _root_regime(g, w, nrow, trow, ntan, kind, e, mu, pattern, dirs,
                                            scale, imp, wa, lws, nws, held, fa, ia, top,
                                            holds)  # fmt: skip
        else:
            status, nu, cont = linear_regime(g, w, nrow, trow, ntan, kind, e, mu, pattern,
                                             dirs, scale, imp, wa, lws, fa, ia, top,
                                             holds)  # fmt: skip
        if status == 2:
            return REGIME_NEEDS_REFERENCE
        if status != 1:
            continue
        dup = False
        for j in range(first, ncand):
            worst = 0.0
            for i in range(m):
                worst = max(worst, abs(wa[i] - cand_wa[j, i]))
            if worst <= 1e-8 * scale:
                dup = True
        if dup or ncand >= max_cand:
            continue
        ncand = _record(cand_imp, cand_wa, cand_info, ncand, imp, wa, nu, cont, pattern)
        if first_only:
            break
    return ncand


#: What :func:`solve_regime` returns where only the reference can decide.
REGIME_NEEDS_REFERENCE = -1


@_leaf
def _widest(g, w, nrow, trow, ntan, kind, e, mu, scale, cand_imp, cand_wa, cand_info, j, rws,  # type: ignore[no-untyped-def]
            top, holds):  # fmt: skip
    """The reference's ``_widest`` on candidate ``j`` (in place; the widest regime by
    :func:`carnot.laws.multiple.regimes.widest_pattern`, the law's own); returns
    needs_reference. Scratch: the arenas of ``rws`` from ``top``."""
    m = w.shape[0]
    k = nrow.shape[0]
    pattern = rws[19]
    wide = rws[20]
    dirs = rws[21]
    for c in range(k):
        pattern[c] = cand_info[j, 2 + c]
    if not _widest_pattern(nrow, trow, ntan, kind, e, w, cand_wa[j], pattern,
                           RELATIVE_TOLERANCE * scale, wide, dirs):  # fmt: skip
        return False
    imp = rws[22]
    wa = rws[23]
    status, nu, cont = linear_regime(g, w, nrow, trow, ntan, kind, e, mu, wide, dirs, scale,
                                     imp, wa, rws[:11], rws[28], rws[29], top,
                                     holds)  # fmt: skip
    if status == 2:
        return True
    if status == 0 or not (nu or cont):
        return False
    worst = 0.0
    for i in range(m):
        worst = max(worst, abs(wa[i] - cand_wa[j, i]))
    if cont or worst > 1e-8 * scale:
        cand_info[j, 1] = True
        return False
    for i in range(m):
        cand_imp[j, i] = imp[i]
        cand_wa[j, i] = wa[i]
    cand_info[j, 0] = nu
    cand_info[j, 1] = cont
    for c in range(k):
        cand_info[j, 2 + c] = wide[c]
    return False


#: Candidates one impact keeps (regimes that hold).
MAX_CANDIDATES = 16


@_jit
def arena_size(k, m):  # type: ignore[no-untyped-def]
    """Length of the scratch arenas (one of floats, one of integers) that the regime
    solvers carve their arrays from, for ``k`` contacts and ``m`` rows: each solver takes
    its arrays from ``top`` on and hands what lies beyond them to the solvers it calls (a
    stack), so the arena holds the deepest chain at its largest, which is the cutting
    planes' linear program (:func:`_exact_cones` and its :func:`_max_min_slack`); bounded
    here by every solver's arrays added together, with the base regime's ``m x m`` system
    that :func:`solve_into` keeps at the arena's start.

    >>> arena_size(4, 12) > 4 * 12 * 12
    True
    """
    most = _POLYGON + EXACT_CONE_ROUNDS
    lines = 3 * k + k * most + 1  # (the cutting planes' inequalities, at their most)
    cones = k * most * 2 + k + 2 * (3 * k * m + 3 * k) + lines * (m + 1) + 2 * m
    tableau = (m + 1) * (lines + m) + 4 * (m + 1) + (m + 1) * (m + 1) + 2 * (lines + m)
    solves = 8 * m * m + 8 * m  # (_solve, _sym_solve, _svd_into, _capacity_weighted, ...)
    return 2 * m * m + cones + tableau + solves  # (a root's system copied: _root_regime)


@_jit
def regime_workspace(k, m):  # type: ignore[no-untyped-def]
    """The workspaces of one regime's check (:func:`regime_holds`, :func:`linear_regime`),
    of :func:`solve_regime` and :func:`_widest`, for ``k`` contacts and ``m`` rows: one array
    per quantity, at its largest, allocated once per task (the checks run once or more per
    impact: their arrays were most of an impact's allocations). The last two are the scratch
    arenas of :func:`arena_size`: every array the solvers need, so that none allocates and
    all are leaves (:data:`_leaf`)."""
    size = arena_size(k, m)
    return (np.empty((m, m)), np.empty((3 * k, m)), np.empty(3 * k), np.empty((k, 3)),
            np.empty((m, m)), np.empty(m, dtype=np.int64), np.empty(m), np.empty(m),
            np.empty(m * m), np.empty(m), np.empty(m * m),
            np.empty(k, dtype=np.int64), np.empty((k, 2)), np.empty(m), np.empty(m),
            np.empty(k), np.empty((3, k)), np.empty(m), np.empty(k, dtype=np.int64),
            np.empty(k, dtype=np.int64), np.empty(k, dtype=np.int64), np.empty((k, 2)),
            np.empty(m), np.empty(m), np.empty((6, 6)), np.empty(6), np.empty(6),
            np.empty(m), np.empty(size), np.empty(size, dtype=np.int64))  # fmt: skip


@_jit
def workspace(k, m):  # type: ignore[no-untyped-def]
    """The workspaces of :func:`solve_into` for ``k`` contacts and ``m`` rows, one array per
    quantity (allocated once per task of a parallel loop, not per impact: an array made or
    sliced in the loop costs its reference counting, about a tenth of a landing's time when
    :func:`solve_into` carved them from three arrays per impact)."""
    ints = np.empty(18 * k + m + MAX_CANDIDATES * (2 + k), dtype=np.int64)
    floats = np.empty(4 * k + 2 * m * m + (5 + 2 * MAX_CANDIDATES) * m)
    bools = np.empty(2 * k, dtype=np.bool_)
    kind = ints[0:k]
    nopt = ints[k : 2 * k]
    opts = ints[2 * k : 6 * k].reshape((k, 4))
    base = ints[6 * k : 7 * k]
    ordered = ints[7 * k : 11 * k].reshape((k, 4))
    guess = ints[11 * k : 12 * k]
    slid = ints[12 * k : 13 * k]
    digit = ints[13 * k : 14 * k]
    pattern = ints[14 * k : 15 * k]
    firsts = ints[15 * k : 18 * k].reshape((3, k))
    rows = ints[18 * k : 18 * k + m]
    cand_info = ints[18 * k + m :].reshape((MAX_CANDIDATES, 2 + k))
    part = bools[0:k]
    has_pred = bools[k : 2 * k]
    predicted = floats[0 : 2 * k].reshape((k, 2))
    dirs0 = floats[2 * k : 4 * k].reshape((k, 2))
    o = 4 * k
    b = floats[o : o + m * m].reshape((m, m))
    o += m * m
    targets = floats[o : o + m]
    p = floats[o + m : o + 2 * m]
    imp_base = floats[o + 2 * m : o + 3 * m]
    wa_base = floats[o + 3 * m : o + 4 * m]
    x_all = floats[o + 4 * m : o + 5 * m]
    o += 5 * m
    null_all = floats[o : o + m * m]
    o += m * m
    cand_imp = floats[o : o + MAX_CANDIDATES * m].reshape((MAX_CANDIDATES, m))
    o += MAX_CANDIDATES * m
    cand_wa = floats[o : o + MAX_CANDIDATES * m].reshape((MAX_CANDIDATES, m))
    return (kind, nopt, opts, base, ordered, guess, slid, digit, pattern, firsts, rows,
            cand_info, part, has_pred, predicted, dirs0, b, targets, p, imp_base, wa_base,
            x_all, null_all, cand_imp, cand_wa, np.empty(m), np.empty(6))  # fmt: skip


@_leaf
def _prepare(g, w, nrow, trow, ntan, e, mu, ws, body_jac, body_mass, body_inertia, body, bws):  # type: ignore[no-untyped-def]
    """The start of :func:`solve_into` (the reference's ``_predict``, first half): each
    contact's kind, whether it takes part and its regimes, and the system of the regime
    that closes (sticks) every taking-part contact, ``G_RR x = rhs`` in ``ws``, solved where
    the body's velocities allow (:func:`_body_min_norm`). Returns ``(scale, count, verify,
    monotone, q, symmetric, fast)``: the velocity scale (m/s), the number of regimes,
    whether they are all to be tried, whether every contact is frictionless, the system's
    size and kind, and whether ``x`` is solved (else the caller solves it: :func:`_solve`).
    ``count > MAX_REGIMES``: nothing else is set. A leaf (:data:`_leaf`)."""
    m = w.shape[0]
    k = nrow.shape[0]
    (kind, nopt, opts, base, ordered, guess, slid, digit, pattern, firsts, rows, cand_info,
     part, has_pred, predicted, dirs0, b, targets, p, imp_base, wa_base, x_all, null_all,
     cand_imp, cand_wa, rhs_all, body_y) = ws  # fmt: skip
    scale = 0.0
    for i in range(m):
        scale = max(scale, abs(w[i]))
    if not (scale > 0.0 and math.isfinite(scale)):
        scale = 1.0
    tol = RELATIVE_TOLERANCE * scale
    for c in range(k):
        nopt[c] = 0
        for j in range(4):
            opts[c, j] = 0
    count = 1
    monotone = True
    spatial = 0
    for c in range(k):
        if ntan[c] == 0 or mu[c] == 0.0:
            kind[c] = FRICTIONLESS_KIND
        elif ntan[c] == 1:
            kind[c] = PLANAR
        else:
            kind[c] = SPATIAL
        part[c] = w[nrow[c]] <= tol
        if part[c]:
            nopt[c] = _options(kind[c], opts[c])
            count *= nopt[c]
            if kind[c] != FRICTIONLESS_KIND:
                monotone = False
            if kind[c] == SPATIAL:
                spatial += 1
    if count > MAX_REGIMES:
        return scale, count, False, monotone, 0, True, False
    verify = count <= VERIFY_UP_TO and spatial <= VERIFY_SPATIAL_UP_TO
    # _predict: the impulses that closing (sticking) every taking-part contact would need
    for c in range(k):
        base[c] = opts[c, 0] if part[c] else OUT
        for j in range(4):
            ordered[c, j] = opts[c, j]
        predicted[c, 0] = 0.0
        predicted[c, 1] = 0.0
        dirs0[c, 0] = 0.0
        dirs0[c, 1] = 0.0
        has_pred[c] = False
    q, symmetric = _columns(m, nrow, trow, ntan, mu, e, base, w, dirs0, b, rows, targets)
    # (kept: the base regime is this system, solved once)
    rhs = rhs_all[:q]
    x = x_all[:q]
    null = null_all[: q * q].reshape((q, q))
    for i in range(q):
        x[i] = 0.0
        for j in range(q):
            null[i, j] = 0.0
    fast = False
    if q > 0:
        for i in range(q):
            rhs[i] = targets[i] - w[rows[i]]
        if body and symmetric and q > 6:
            fast = _body_min_norm(body_jac, body_mass, body_inertia, rows, q, rhs, x,
                                  FEASIBILITY * scale, body_y, bws[0], bws[1], bws[2])  # fmt: skip
    return scale, count, verify, monotone, q, symmetric, fast


@_leaf
def _predict(g, nrow, trow, ntan, kind, mu, part, nopt, opts, ordered, predicted, has_pred, b,  # type: ignore[no-untyped-def]
             x, q, p, scale):  # fmt: skip
    """The rest of the reference's ``_predict``: the impulses ``p = B x`` that closing
    (sticking) every taking-part contact would need, then each contact's regimes in order
    by :func:`carnot.laws.multiple.regimes.predicted_order` (the law's own); returns
    whether the contacts are overloaded. A leaf (:data:`_leaf`)."""
    m = p.shape[0]
    for i in range(m):
        p[i] = 0.0
    for i in range(m):
        for j in range(q):
            p[i] += b[i, j] * x[j]
    return _predicted_order(g, nrow, trow, ntan, kind, mu, part, nopt, opts, ordered,
                            predicted, has_pred, p, scale)  # fmt: skip


@_leaf
def _report(g, w, nrow, trow, ntan, kind, e, mu, part, ncand, cand_imp, cand_wa, cand_info,  # type: ignore[no-untyped-def]
            verify, monotone, scale, imp_out, wa_out, regime_out, active_out):  # fmt: skip
    """The end of :func:`solve_into`: the first candidate's impulses, velocities and regimes
    into the outputs, the flags (statically indeterminate, multiple solutions, none,
    unverified, a separating contact that approaches) and the residual; returns ``(status,
    flags, residual)``. A leaf (:data:`_leaf`)."""
    m = w.shape[0]
    k = nrow.shape[0]
    tol = RELATIVE_TOLERANCE * scale
    flags = 0
    if not (verify or monotone):
        flags |= UNVERIFIED
    status = SOLVED
    if ncand == 0:
        flags |= NO_SOLUTION_FLAG
        status = NO_SOLUTION
        for i in range(m):
            imp_out[i] = 0.0
            wa_out[i] = w[i]
        for c in range(k):
            regime_out[c] = SEPARATE
            active_out[c] = False
    else:
        # the verdict on the first answer's group (the same velocities): the law's own
        firsts = _answer_groups(cand_wa, ncand, 1e-8 * scale)
        indeterminate, multiple = _group_verdict(cand_imp, cand_wa, cand_info[:, 0],
                                                 cand_info[:, 1], ncand, np.int64(0), firsts,
                                                 1e-8 * scale, 1e-8)  # fmt: skip
        if indeterminate:
            flags |= STATICALLY_INDETERMINATE
        if multiple:
            flags |= MULTIPLE_SOLUTIONS
        for i in range(m):
            imp_out[i] = cand_imp[0, i]
            wa_out[i] = cand_wa[0, i]
        for c in range(k):
            opt = cand_info[0, 2 + c]
            if opt == SEPARATE_OPT or opt == OUT:
                regime_out[c] = SEPARATE
            elif opt == CLOSED:
                regime_out[c] = FRICTIONLESS
            elif opt == STICK_OPT:
                regime_out[c] = STICK
            else:
                regime_out[c] = SLIP
            active_out[c] = regime_out[c] != SEPARATE
    residual = 0.0
    for c in range(k):
        if not part[c] and wa_out[nrow[c]] < -tol:
            flags |= SEPARATING_CONTACT_APPROACHES
        residual = max(residual, contact_residual(c, g, nrow, trow, ntan, kind[c], e, mu,
                                                  imp_out, w, wa_out, part[c]))  # fmt: skip
    return status, flags, residual


#: :func:`solve_front`'s status where it does not decide (the impact goes to
#: :func:`solve_into`), and what it found of the prediction's regime: not tried, does not
#: hold, or needs its family of impulses (the rows' system and its linear program).
UNDECIDED = -1
BASE_UNTRIED, BASE_FAILS, BASE_FAMILY = 0, 1, 2
#: :func:`solve_into`'s ``front`` where no front ran: start afresh.
AFRESH = (1.0, 0, False, False, 0, False, BASE_UNTRIED)


@_leaf
def solve_front(g, w, nrow, trow, ntan, e, mu, imp_out, wa_out, regime_out, active_out, ws,  # type: ignore[no-untyped-def]
                hws, body_jac, body_mass, body_inertia, body, bws):  # fmt: skip
    """The landing that sticks as predicted, decided without :func:`solve_into`: where the
    prediction's system is solved in the body's velocities (:func:`_prepare`), only the
    first regime is wanted (every regime is not verified), the contacts are not overloaded,
    so that the prediction's regime is the first tried, and it holds with the minimum-norm
    or capacity-weighted impulse (:func:`_holds_fast`). The same steps as
    :func:`solve_into`'s, in leaves (:data:`_leaf`: no reference counting); returns
    :func:`solve_into`'s ``(status, flags, residual)``, or :data:`UNDECIDED`, followed by
    what it found for :func:`solve_into` to go on from: ``(scale, count, verify, monotone,
    q, overloaded, base)``, ``q > 0`` where the prediction is in the workspaces (``q`` its
    system's size, solved in the body's velocities), ``base`` one of :data:`BASE_UNTRIED`,
    :data:`BASE_FAILS`, :data:`BASE_FAMILY`."""
    (kind, nopt, opts, base, ordered, guess, slid, digit, pattern, firsts, rows, cand_info,
     part, has_pred, predicted, dirs0, b, targets, p, imp_base, wa_base, x_all, null_all,
     cand_imp, cand_wa, rhs_all, body_y) = ws  # fmt: skip
    gb, lin_a, lin_c, cones = hws
    k = nrow.shape[0]
    prepared = _prepare(g, w, nrow, trow, ntan, e, mu, ws, body_jac, body_mass, body_inertia,
                        body, bws)  # fmt: skip
    scale, count, verify, monotone, q, symmetric, fast = prepared
    if count > MAX_REGIMES or not fast:
        return UNDECIDED, 0, 0.0, scale, count, verify, monotone, 0, False, BASE_UNTRIED
    x = x_all[:q]
    overloaded = _predict(g, nrow, trow, ntan, kind, mu, part, nopt, opts, ordered, predicted,
                          has_pred, b, x, q, p, scale)  # fmt: skip
    if overloaded or not (monotone or not verify):  # (the prediction's regime is not the
        # first tried, or every regime is: solve_into goes on from the prediction)
        return UNDECIDED, 0, 0.0, scale, count, verify, monotone, q, overloaded, BASE_UNTRIED
    status = _holds_fast(g, w, nrow, trow, ntan, kind, e, mu, base, dirs0, scale, imp_base,
                         wa_base, b, q, x, gb, lin_a, lin_c, cones)  # fmt: skip
    cone = False  # (the reference weights by capacity only where a cone sticks)
    for c in range(k):
        cone = cone or (base[c] == STICK_OPT and kind[c] == SPATIAL)
    if status == 3 and cone and _body_weighted(body_jac, base, nrow, trow, ntan, mu, rows, q,
                                               x, body_y, bws[3], bws[0], bws[1]):  # fmt: skip
        status = _holds_fast(g, w, nrow, trow, ntan, kind, e, mu, base, dirs0, scale, imp_base,
                             wa_base, b, q, x, gb, lin_a, lin_c, cones)  # fmt: skip
    if status != 1:
        base = BASE_FAILS if status == 0 else BASE_FAMILY
        return UNDECIDED, 0, 0.0, scale, count, verify, monotone, q, overloaded, base
    # (statically indeterminate: 6 velocities, more rows; no continuum)
    _record(cand_imp, cand_wa, cand_info, np.int64(0), imp_base, wa_base, np.bool_(True),
            np.bool_(False), base)  # fmt: skip
    # (no contact of the prediction's regime separates: _widest has nothing to widen)
    status, flags, residual = _report(g, w, nrow, trow, ntan, kind, e, mu, part, np.int64(1),
                                      cand_imp,
                                      cand_wa, cand_info, verify, monotone, scale, imp_out,
                                      wa_out, regime_out, active_out)  # fmt: skip
    return status, flags, residual, scale, count, verify, monotone, q, overloaded, BASE_UNTRIED


@_leaf
def solve_into(g, w, nrow, trow, ntan, e, mu, imp_out, wa_out, regime_out, active_out, ws,  # type: ignore[no-untyped-def]
               nws, rws, body_jac, body_mass, body_inertia, body, front, regime,
               holds):  # fmt: skip
    """One impact by the simultaneous law: impulses and row velocities after into
    ``imp_out``/``wa_out``, per contact its regime code and whether it is active; returns
    ``(status, flags, residual)`` (status :data:`SOLVED`, :data:`NEEDS_REFERENCE`,
    :data:`NO_SOLUTION` or :data:`TOO_MANY_REGIMES`; flags the bits of the module). In the
    workspaces of :func:`workspace`, :func:`newton_workspace` and :func:`regime_workspace`
    (a batch allocates them once per task: allocation and its reference counting cost about
    as much as the arithmetic of a landing otherwise).

    ``body``: ``G = J M^-1 J^T`` of one free body against a fixed obstacle, ``J`` its
    Jacobian ``body_jac`` (m x 6), ``M`` of ``body_mass`` (kg) and ``body_inertia`` (world,
    kg m^2): the prediction's system (every taking-part contact closed or sticking) is then
    solved in the body's 6 velocities (:func:`_body_min_norm`) where that is well
    conditioned, its rows' null space only where the minimum-norm impulse misses an
    inequality. The same answer, to round-off. ``front``: :func:`solve_front`'s state after
    an :data:`UNDECIDED` (its last seven values; ``q = 0`` there: start afresh). ``regime`` and
    ``holds``: :func:`solve_regime` and :func:`regime_holds` as C callbacks
    (:func:`impact_solvers`), called by their address."""
    m = w.shape[0]
    k = nrow.shape[0]
    (kind, nopt, opts, base, ordered, guess, slid, digit, pattern, firsts, rows, cand_info,
     part, has_pred, predicted, dirs0, b, targets, p, imp_base, wa_base, x_all, null_all,
     cand_imp, cand_wa, rhs_all, body_y) = ws  # fmt: skip
    hws = rws[:4]
    scale, count, verify, monotone, q, overloaded, base_state = front
    fast = q > 0  # (the front went as far as the prediction, in the body's velocities)
    symmetric = True
    if not fast:
        scale, count, verify, monotone, q, symmetric, fast = _prepare(
            g, w, nrow, trow, ntan, e, mu, ws, body_jac, body_mass, body_inertia, body,
            (rws[24], rws[25], rws[26], rws[27]))  # fmt: skip
        base_state = BASE_UNTRIED
    if count > MAX_REGIMES:
        return TOO_MANY_REGIMES, 0, 0.0
    tol = RELATIVE_TOLERANCE * scale
    first_only = monotone or not verify
    rhs = rhs_all[:q]
    x = x_all[:q]
    null = null_all[: q * q].reshape((q, q))
    nn_base = 0
    fa = rws[28]
    ia = rws[29]
    a_base = fa[: q * q].reshape((q, q))  # (the base's system, kept: read where _solve set it)
    top = m * m  # (the arenas beyond it: the scratch of every solver called here)
    if q > 0 and fast:
        nn_base = q - 6
    if q > 0 and front[4] == 0:  # (not predicted by the front)
        if not fast:
            nn_base = _solve(g, rows, b, m, q, symmetric, rhs, x, null, a_base, fa, ia, top)
        overloaded = _predict(g, nrow, trow, ntan, kind, mu, part, nopt, opts, ordered,
                              predicted, has_pred, b, x, q, p, scale)  # fmt: skip
    for c in range(k):
        guess[c] = ordered[c, 0] if part[c] else OUT
    max_cand = MAX_CANDIDATES
    ncand = np.int64(0)
    # the regimes in the reference's order: base, slid (the guess with its 3D sticking
    # contacts slipping) and guess first, then the rest
    for c in range(k):
        slid[c] = guess[c]
    for c in range(k):
        if slid[c] == STICK_OPT and kind[c] == SPATIAL:
            slid[c] = SLIP_OPT
    for c in range(k):
        if overloaded:
            firsts[0, c], firsts[1, c], firsts[2, c] = slid[c], guess[c], base[c]
        else:
            firsts[0, c], firsts[1, c], firsts[2, c] = base[c], slid[c], guess[c]
    for f in range(3):
        repeated = False  # (the reference's dict.fromkeys: each regime once)
        for f2 in range(f):
            equal = True
            for c in range(k):
                if firsts[f, c] != firsts[f2, c]:
                    equal = False
            if equal:
                repeated = True
        if repeated:
            continue
        is_base = q > 0
        for c in range(k):
            if firsts[f, c] != base[c]:
                is_base = False
        if is_base:  # the prediction's system: its solution checked, not solved again
            gb, lin_a, lin_c, cones = hws
            if base_state == BASE_FAILS:  # (the front found it does not hold)
                status, nu, cont = 0, False, False
            elif base_state == BASE_FAMILY:  # (the front found its family is needed)
                status, nu, cont = 3, False, False
            elif fast:  # x is the body's minimum-norm impulse (the rows' system not solved)
                status = _holds_fast(g, w, nrow, trow, ntan, kind, e, mu, base, dirs0, scale,
                                     imp_base, wa_base, b, q, x, gb, lin_a, lin_c,
                                     cones)  # fmt: skip
                nu, cont = True, False
            else:
                status, nu, cont = _held(holds(g, w, nrow, trow, ntan, kind, e, mu, base,
                                                 dirs0, scale, imp_base, wa_base, b, rows, q,
                                                 symmetric, rhs, a_base, x, null, nn_base,
                                                 hws, fa, ia, top))  # fmt: skip
            cone = False  # (the reference weights by capacity only where a cone sticks)
            for c in range(k):
                cone = cone or (base[c] == STICK_OPT and kind[c] == SPATIAL)
            if status == 3 and base_state == BASE_UNTRIED and cone and _body_weighted(
                    body_jac, base, nrow, trow, ntan, mu, rows, q, x, body_y, rws[27],
                    rws[24], rws[25]):  # fmt: skip
                # the minimum norm misses an inequality: the reference's capacity weighting
                status = _holds_fast(g, w, nrow, trow, ntan, kind, e, mu, base, dirs0, scale,
                                     imp_base, wa_base, b, q, x, gb, lin_a, lin_c,
                                     cones)  # fmt: skip
            if status == 3 and fast and _stick_impossible(
                    body_jac, body_y, nrow, part, base, kind, mu, g,
                    FEASIBILITY * scale):  # fmt: skip
                status = 0  # (no member of the family meets the cones: no program needed)
            if status == 3:  # neither: the family is needed (its linear program)
                nn_base = _solve(g, rows, b, m, q, symmetric, rhs, x, null, a_base, fa, ia, top)
                status, nu, cont = _held(holds(g, w, nrow, trow, ntan, kind, e, mu, base,
                                                 dirs0, scale, imp_base, wa_base, b, rows, q,
                                                 symmetric, rhs, a_base, x, null, nn_base,
                                                 hws, fa, ia, top))  # fmt: skip
            needs = status == 2
            if status == 1 and ncand < max_cand:
                ncand = _record(cand_imp, cand_wa, cand_info, ncand, imp_base, wa_base, nu,
                                cont, base)  # fmt: skip
        else:
            found = regime(g, w, nrow, trow, ntan, kind, e, mu, firsts[f], scale, predicted,
                           has_pred, first_only, cand_imp, cand_wa, cand_info, ncand,
                           max_cand, nws, rws, top, holds)  # fmt: skip
            needs = found == REGIME_NEEDS_REFERENCE
            ncand = ncand if needs else found
        if needs:
            return NEEDS_REFERENCE, 0, 0.0
        if ncand > 0 and first_only:
            break
    # the rest nearest slid first (the reference's _nearest_first): by the number of
    # contacts in another regime than in slid, fewest first; among equals, by the number of
    # those that slid did not separate, fewest first; and in itertools.product's order among
    # equals (the last contact varies fastest)
    npart = 0
    for c in range(k):
        if part[c]:
            npart += 1
    distance = 1
    while distance <= npart and not (ncand > 0 and first_only):
        for other in range(distance + 1):
            if ncand > 0 and first_only:
                break
            for c in range(k):
                digit[c] = 0
            for _ in range(count):
                away = 0
                moved = 0
                as_base = True
                as_guess = True
                for c in range(k):
                    pattern[c] = ordered[c, digit[c]] if part[c] else OUT
                    if pattern[c] != slid[c]:
                        away += 1
                        if slid[c] != SEPARATE_OPT:
                            moved += 1
                    if pattern[c] != base[c]:
                        as_base = False
                    if pattern[c] != guess[c]:
                        as_guess = False
                skip = away != distance or moved != other or as_base or as_guess
                if not skip:
                    found = regime(g, w, nrow, trow, ntan, kind, e, mu, pattern, scale,
                                   predicted, has_pred, first_only, cand_imp, cand_wa,
                                   cand_info, ncand, max_cand, nws, rws, top,
                                   holds)  # fmt: skip
                    if found == REGIME_NEEDS_REFERENCE:
                        return NEEDS_REFERENCE, 0, 0.0
                    ncand = found
                    if ncand > 0 and first_only:
                        break
                # the next pattern (itertools.product: the last contact varies fastest)
                c = k - 1
                while c >= 0:
                    if part[c]:
                        digit[c] += 1
                        if digit[c] < nopt[c]:
                            break
                        digit[c] = 0
                    c -= 1
        distance += 1
    for j in range(ncand):
        widen = False  # (_widest's test: a separating contact whose velocity is its target)
        for c in range(k):
            if cand_info[j, 2 + c] == SEPARATE_OPT:
                widen = widen or abs(cand_wa[j, nrow[c]] + e[c] * w[nrow[c]]) <= tol
        if widen and _widest(g, w, nrow, trow, ntan, kind, e, mu, scale, cand_imp, cand_wa,
                             cand_info, j, rws, top, holds):  # fmt: skip
            return NEEDS_REFERENCE, 0, 0.0
    return _report(g, w, nrow, trow, ntan, kind, e, mu, part, ncand, cand_imp, cand_wa,
                   cand_info, verify, monotone, scale, imp_out, wa_out, regime_out,
                   active_out)  # fmt: skip


def solve_in_workspaces(g, w, nrow, trow, ntan, e, mu, imp_out, wa_out, regime_out, active_out, ws,  # type: ignore[no-untyped-def]
                        nws, rws, body_jac, body_mass, body_inertia, body, front, flags_out,
                        residual_out, regime, holds):  # fmt: skip
    """One impact in the workspaces: :func:`solve_front`, then :func:`solve_into` where it
    did not decide (``front``: the body route), or :func:`solve_into` alone; returns the
    status and writes the flags and the residual into ``flags_out[0]``, ``residual_out[0]``.
    Compiled by :func:`impact_solvers` as a C callback, which the parallel entry points call
    by its address (the module's docstring: its solvers are then optimized once); a leaf's
    body (no allocation, no reference counting)."""
    if front:
        s, f, r, sc, cnt, ver, mono, q, over, bst = solve_front(
            g, w, nrow, trow, ntan, e, mu, imp_out, wa_out, regime_out, active_out, ws, rws[:4],
            body_jac, body_mass, body_inertia, body, (rws[24], rws[25], rws[26], rws[27]))
        if s == UNDECIDED:
            s, f, r = solve_into(g, w, nrow, trow, ntan, e, mu, imp_out, wa_out, regime_out,
                                 active_out, ws, nws, rws, body_jac, body_mass, body_inertia,
                                 body, (sc, cnt, ver, mono, q, over, bst), regime,
                                 holds)  # fmt: skip
    else:
        s, f, r = solve_into(g, w, nrow, trow, ntan, e, mu, imp_out, wa_out, regime_out,
                             active_out, ws, nws, rws, body_jac, body_mass, body_inertia, body,
                             AFRESH, regime, holds)  # fmt: skip
    flags_out[0] = f
    residual_out[0] = r
    return s


def _returned(workspace_of):  # type: ignore[no-untyped-def]
    """The type Numba gives what ``workspace_of(k, m)`` returns: ``numba.typeof`` of what its
    Python function returns for 4 contacts and 12 rows (every array of it then larger than
    one entry, so that its flags say its layout as Numba's inference of the compiled
    function does: checked against the compiled function's own return type by
    tests/test_compile_apart.py). Typing a call costs 0.2 ms where compiling the three
    workspaces cost 2 s of a cold start, on one core before the child processes could start
    (the entry points compile them anyway, meanwhile)."""
    return numba.typeof(workspace_of.py_func(4, 12))


#: The C callbacks of :func:`impact_solvers`, in its order, and their cold compile on a quiet
#: core (seconds, 2026-12-04; what :mod:`carnot.batch.compile_apart` plans by).
SOLVERS = ("solve_in_workspaces", "solve_regime", "regime_holds")
SOLVER_COSTS = (18.5, 18.4, 8.1)


@functools.cache
def _solver_signatures() -> tuple[Any, Any, Any]:
    """The C signatures of :data:`SOLVERS`: the argument types their callers hand them (the
    batch's ``e`` and ``mu`` read-only, every work array writable and C-contiguous, as the
    workspaces hold them; the regime solver and the check as first-class functions)."""
    t = numba.types
    rows = t.float64[::1]
    square = t.float64[:, ::1]
    ints = t.int64[::1]
    frozen = t.Array(t.float64, 1, "C", readonly=True)
    ws, nws, rws = _returned(workspace), _returned(newton_workspace), _returned(regime_workspace)
    holds_signature = t.int64(square, rows, ints, t.int64[:, ::1], ints, ws[0], frozen, frozen,
                              ws[8], rws[12], t.float64, rws[13], rws[14], rws[4], rws[5],
                              t.int64, t.boolean, rows, square, rows, square, t.int64,
                              t.Tuple(rws.types[:4]), rws[28], rws[29], t.int64)  # fmt: skip
    holds_type = t.FunctionType(holds_signature)
    regime_signature = t.int64(square, rows, ints, t.int64[:, ::1], ints, ws[0], frozen, frozen,
                               ws[8], t.float64, ws[14], ws[13], t.boolean, ws[23], ws[24],
                               ws[11], t.int64, t.int64, nws, rws, t.int64,
                               holds_type)  # fmt: skip
    signature = t.int64(square, rows, ints, t.int64[:, ::1], ints, frozen, frozen, rows, rows,
                        t.int8[::1], t.boolean[::1], ws, nws, rws, square, t.float64, square,
                        t.boolean, t.boolean, ints, rows, t.FunctionType(regime_signature),
                        holds_type)  # fmt: skip
    return signature, regime_signature, holds_signature


@functools.cache
def _callback(name: str) -> Callable[..., Any]:
    """The Python function of the callback ``name`` of :data:`SOLVERS`, under its stamped name
    (:func:`_stamp`; one copy per process, so that the cache's lookup and the compile see
    the same function)."""
    return _stamp(globals()[name])


def _compile_c(name: str) -> Any:
    """The callback ``name`` of :data:`SOLVERS` as a C function (``numba.cfunc``, cached on
    disk; a leaf's options: no reference counting), loaded from the cache or compiled."""
    signature = _solver_signatures()[SOLVERS.index(name)]
    return numba.cfunc(signature, cache=True, nogil=True, error_model="numpy",
                       _nrt=False)(_callback(name))  # type: ignore[call-arg]  # fmt: skip


def build_solvers(names: list[str]) -> None:
    """Compile the callbacks ``names`` (of :data:`SOLVERS`) into Numba's cache: what a child
    process of :func:`impact_solvers` runs."""
    for name in names:
        _compile_c(name)


def solver_types() -> tuple[Any, Any, Any]:
    """The Numba types of :func:`impact_solvers`' three callbacks as arguments
    (``numba.types.FunctionType`` of their signatures): what an entry point's last three
    arguments are typed as, so that it can be compiled before the callbacks exist."""
    return tuple(numba.types.FunctionType(s) for s in _solver_signatures())  # type: ignore[return-value]


_SOLVERS_BUILT: list[tuple[Any, Any, Any]] = []
_SOLVERS_LOCK = threading.Lock()


def impact_solvers(meanwhile: Callable[[], object] | None = None) -> tuple[Any, Any, Any]:
    """:func:`solve_in_workspaces`, :func:`solve_regime` and :func:`regime_holds` compiled as
    C callbacks (``numba.cfunc``, cached on disk as the kernels are): the last three
    arguments of :func:`run` and :func:`solve_rows`, which hand the other two to the first,
    and it the last to the second. Built on first use, not at import: the frictionless front
    (:func:`run_normal`, :func:`solve_rows_normal`) does not need them.

    Where the cache lacks several, the costliest are compiled by child processes side by
    side, one per core, while this process runs ``meanwhile`` (an entry point's own compile,
    typed by :func:`solver_types`), then compiles the others
    (:mod:`carnot.batch.compile_apart`: alone, the three take their sum of time on one
    core). ``meanwhile`` runs on the first call only; the callbacks are built once per
    process."""
    with _SOLVERS_LOCK:
        if not _SOLVERS_BUILT:
            _SOLVERS_BUILT.append(_build_solvers(meanwhile))
        elif meanwhile is not None:
            meanwhile()
        return _SOLVERS_BUILT[0]


def _build_solvers(meanwhile: Callable[[], object] | None) -> tuple[Any, Any, Any]:
    """:func:`impact_solvers`' build: the plan, the children, this process's share."""
    from carnot.batch import compile_apart

    signatures = _solver_signatures()
    # The lookup loads the machine code it finds, and _compile_c loads it again (~0.03 s a
    # callback): the costliest is asked first, and where it is cached (a warm start: the
    # three are written by one build) the others are not asked but loaded; a cache
    # holding it alone then has the others compiled here, one after the other.
    missing = [not compile_apart.cached(_callback(SOLVERS[0]), signatures[0])]
    if missing[0]:
        missing += [not compile_apart.cached(_callback(name), signature)
                    for name, signature in zip(SOLVERS[1:], signatures[1:], strict=True)]
    else:
        missing += [False] * (len(SOLVERS) - 1)
    apart = compile_apart.plan(SOLVER_COSTS, missing, compile_apart.cores())
    children = compile_apart.start_children(__name__, [SOLVERS[i] for i in apart])
    try:
        if meanwhile is not None:
            meanwhile()
        here = {name: _compile_c(name) for i, name in enumerate(SOLVERS)
                if missing[i] and i not in apart}  # fmt: skip
    finally:
        compile_apart.wait_for(children)
    solver, regime, holds = (here.get(name) or _compile_c(name) for name in SOLVERS)
    return solver, regime, holds


@numba.njit(cache=True, nogil=True, error_model="numpy", parallel=True)
@_stamp
def solve_rows(g, w, nrow, trow, ntan, e, mu, imp, wa, regime, active, status, flags,  # type: ignore[no-untyped-def]
               residual, solver, regime_solver, holds):  # fmt: skip
    """:func:`solve_in_workspaces` for every impact ``i`` of ``g (N, m, m)``, ``w (N, m)``,
    ``e`` and ``mu (N, k)``, in parallel, into the ``(N, ...)`` outputs. ``solver``:
    ``regime_solver`` and ``holds``: :func:`impact_solvers`' C callbacks (called by their
    address). Frictionless rows come here after :func:`solve_rows_normal`, those that
    :func:`frictionless_fast` could not decide only (as in :func:`run`)."""
    count = g.shape[0]
    k = nrow.shape[0]
    m = w.shape[1]
    for task in numba.prange((count + 63) // 64):
        ws = workspace(k, m)
        nws = newton_workspace(k, m)
        rws = regime_workspace(k, m)
        no_jac = np.empty((0, 6))
        no_inertia = np.empty((3, 3))
        flags_out = np.empty(1, dtype=np.int64)
        residual_out = np.empty(1)
        for i in range(task * 64, min(count, (task + 1) * 64)):
            status[i] = solver(g[i], w[i], nrow, trow, ntan, e[i], mu[i], imp[i], wa[i],
                               regime[i], active[i], ws, nws, rws, no_jac, 1.0, no_inertia,
                               np.bool_(False), np.bool_(False), flags_out, residual_out,
                               regime_solver, holds)  # fmt: skip
            flags[i] = flags_out[0]
            residual[i] = residual_out[0]


# ------------------------------------------------------------------ free bodies
# One or two free rigid bodies in several point contacts: contact space for one impact
# (Numba), and the velocities and ledger after it.
#
# For body ``a`` (and ``b``, or a fixed obstacle) and contacts ``c`` at points ``p_c`` with
# normals ``n_c`` (from ``b`` into ``a``; frame ``(n, t1, t2)`` of
# :func:`carnot.conventions.contact_frame`), each contact row ``d`` (``n``, and ``t1``, ``t2``
# when the layout gives the contact tangent rows) is the functional ``d . (v_a + omega_a x r_a
# - v_b - omega_b x r_b)`` with ``r = p - x``: the Jacobian row ``W_a = [d, r_a x d]`` on ``a``'s
# velocities and ``-[d, r_b x d]`` on ``b``'s. Then (DESIGN.md section 1)
#
#     G = W_a M_a^-1 W_a^T + W_b M_b^-1 W_b^T,   w' = W u',   u'' = u' + M^-1 W^T Lambda,
#
# with ``M^-1 = diag(I / m, J_C^-1)``, and the ledger ``E' - E''`` (Koenig, paper eq. 5) beside
# the theorem ``-1/2 Lambda . (w' + w'')`` (paper eqs. 11 and 16), per contact.


#: The one-contact batch formulas compiled (:func:`carnot.batch.ops.specialize`): the inertia
#: check and the kinetic energy are theirs, written once in :mod:`carnot.batch.rigid`.
_factor = specialize("numba", "frictionless").factor
_kinetic_energy = specialize("numba", "frictionless").kinetic_energy


@_leaf
def inverse_inertia(j, inv):  # type: ignore[no-untyped-def]
    """``J_C^-1`` (3 x 3, into ``inv``) and whether ``J_C`` is a valid inertia tensor:
    symmetric, positive definite and realizable (``tr(J)/2 I - J`` positive semi-definite),
    decided by :func:`carnot.batch.rigid.factor` itself; the inverse is the adjugate over
    the determinant."""
    _, valid = _factor((j[0, 0], j[0, 1], j[0, 2], j[1, 0], j[1, 1], j[1, 2], j[2, 0],
                              j[2, 1], j[2, 2]))  # fmt: skip
    j01, j02, j12 = j[0, 1], j[0, 2], j[1, 2]
    det = (j[0, 0] * (j[1, 1] * j[2, 2] - j12 * j12) - j01 * (j01 * j[2, 2] - j12 * j02)
           + j02 * (j01 * j12 - j[1, 1] * j02))  # fmt: skip
    if not (valid and det > 0 and math.isfinite(det)):
        for r in range(3):
            for c in range(3):
                inv[r, c] = np.nan
        return False
    # the adjugate over the determinant (symmetric 3 x 3)
    inv[0, 0] = (j[1, 1] * j[2, 2] - j12 * j12) / det
    inv[0, 1] = inv[1, 0] = (j02 * j12 - j01 * j[2, 2]) / det
    inv[0, 2] = inv[2, 0] = (j01 * j12 - j02 * j[1, 1]) / det
    inv[1, 1] = (j[0, 0] * j[2, 2] - j02 * j02) / det
    inv[1, 2] = inv[2, 1] = (j01 * j02 - j[0, 0] * j12) / det
    inv[2, 2] = (j[0, 0] * j[1, 1] - j01 * j01) / det
    return True


#: ``(n, t1, t2)`` as the rows of ``out`` (3 x 3): :func:`carnot.conventions.contact_frame_into`
#: itself, compiled as a leaf (the one statement of the frame, which ``solve_impact`` runs as
#: Python: the same bits).
frame = _leaf(contact_frame_into)


@_leaf
def _jacobian(x, points, axes, tangential, sign, jac):  # type: ignore[no-untyped-def]
    """The rows ``sign [d, r x d]`` (m x 6, into ``jac``) of every contact row on one body at
    ``x`` (``axes[c]``: contact ``c``'s frame)."""
    r = 0
    for c in range(points.shape[0]):
        rx = points[c, 0] - x[0]
        ry = points[c, 1] - x[1]
        rz = points[c, 2] - x[2]
        for a in range(1 + 2 * tangential[c]):
            d0, d1, d2 = axes[c, a, 0], axes[c, a, 1], axes[c, a, 2]
            jac[r, 0], jac[r, 1], jac[r, 2] = sign * d0, sign * d1, sign * d2
            jac[r, 3] = sign * (ry * d2 - rz * d1)
            jac[r, 4] = sign * (rz * d0 - rx * d2)
            jac[r, 5] = sign * (rx * d1 - ry * d0)
            r += 1


@_leaf
def _add_delassus(g, jac, inv_mass, inv_j, m):  # type: ignore[no-untyped-def]
    """``g += W M^-1 W^T`` for one body."""
    for i in range(m):
        for k in range(i, m):
            s = inv_mass * (jac[i, 0] * jac[k, 0] + jac[i, 1] * jac[k, 1] + jac[i, 2] * jac[k, 2])
            for p in range(3):
                for q in range(3):
                    s += jac[i, 3 + p] * inv_j[p, q] * jac[k, 3 + q]
            g[i, k] += s
            if k != i:
                g[k, i] += s


@_leaf
def assemble_into(mass_a, j_a, x_a, v_a, om_a, mass_b, j_b, x_b, v_b, om_b, movable_b,  # type: ignore[no-untyped-def]
                  points, normals, tangential, m, g, w, jac_a, jac_b, axes, inv_a,
                  inv_b):  # fmt: skip
    """``G``, ``w'``, both bodies' Jacobians, the contact frames and ``J^-1`` of one impact
    into the given arrays; returns whether the inertia of ``a`` and of ``b`` are valid."""
    ok_a = inverse_inertia(j_a, inv_a)
    ok_b = inverse_inertia(j_b, inv_b)
    for c in range(points.shape[0]):
        frame(normals[c], axes[c])
    _jacobian(x_a, points, axes, tangential, 1.0, jac_a)
    _jacobian(x_b, points, axes, tangential, -1.0, jac_b)
    for i in range(m):
        for k in range(m):
            g[i, k] = 0.0
    _add_delassus(g, jac_a, 1.0 / mass_a, inv_a, m)
    if movable_b:
        _add_delassus(g, jac_b, 1.0 / mass_b, inv_b, m)
    for i in range(m):
        s = 0.0
        for p in range(3):
            s += jac_a[i, p] * v_a[p] + jac_a[i, 3 + p] * om_a[p]
            if movable_b:
                s += jac_b[i, p] * v_b[p] + jac_b[i, 3 + p] * om_b[p]
        w[i] = s
    return ok_a, ok_b


@_jit
def assemble(mass_a, j_a, x_a, v_a, om_a, mass_b, j_b, x_b, v_b, om_b, movable_b, points,  # type: ignore[no-untyped-def]
             normals, tangential, m):  # fmt: skip
    """:func:`assemble_into` into new arrays: ``(G, w', W_a, W_b, axes, J_a^-1, J_b^-1,
    ok_a, ok_b)``."""
    g = np.empty((m, m))
    w = np.empty(m)
    jac_a = np.empty((m, 6))
    jac_b = np.empty((m, 6))
    axes = np.empty((points.shape[0], 3, 3))
    inv_a = np.empty((3, 3))
    inv_b = np.empty((3, 3))
    ok_a, ok_b = assemble_into(mass_a, j_a, x_a, v_a, om_a, mass_b, j_b, x_b, v_b, om_b,
                               movable_b, points, normals, tangential, m, g, w, jac_a, jac_b,
                               axes, inv_a, inv_b)  # fmt: skip
    return g, w, jac_a, jac_b, axes, inv_a, inv_b, ok_a, ok_b


@_leaf
def _energy(mass, j, v0, v1, v2, o0, o1, o2):  # type: ignore[no-untyped-def]
    """Koenig's kinetic energy (J): :func:`carnot.batch.rigid.kinetic_energy` itself."""
    return _kinetic_energy(mass, (j[0, 0], j[0, 1], j[0, 2], j[1, 0], j[1, 1], j[1, 2],
                                        j[2, 0], j[2, 1], j[2, 2]),
                                 (v0, v1, v2), (o0, o1, o2))  # fmt: skip


@_leaf
def finish(mass_a, j_a, v_a, om_a, mass_b, j_b, v_b, om_b, movable_b, axes, tangential,  # type: ignore[no-untyped-def]
           jac_a, jac_b, inv_a, inv_b, imp, w, wa, floats):  # fmt: skip
    """The velocities after, the ledger and each contact's impulse into ``floats`` (the
    columns :func:`carnot.batch.multi._multi_result` reads)."""
    k = axes.shape[0]
    m = imp.shape[0]
    # u'' = u' + M^-1 W^T Lambda, per body: W^T Lambda into floats[0:6] and [6:12] first
    for p in range(12):
        floats[p] = 0.0
    for i in range(m):
        for p in range(6):
            floats[p] += jac_a[i, p] * imp[i]
            floats[6 + p] += jac_b[i, p] * imp[i]
    fa0, fa1, fa2 = floats[3], floats[4], floats[5]
    fb0, fb1, fb2 = floats[9], floats[10], floats[11]
    for p in range(3):
        floats[p] = v_a[p] + floats[p] / mass_a
        floats[3 + p] = om_a[p] + inv_a[p, 0] * fa0 + inv_a[p, 1] * fa1 + inv_a[p, 2] * fa2
        if movable_b:
            floats[6 + p] = v_b[p] + floats[6 + p] / mass_b
            floats[9 + p] = om_b[p] + inv_b[p, 0] * fb0 + inv_b[p, 1] * fb1 + inv_b[p, 2] * fb2
        else:
            floats[6 + p] = v_b[p]
            floats[9 + p] = om_b[p]
    before = _energy(mass_a, j_a, v_a[0], v_a[1], v_a[2], om_a[0], om_a[1], om_a[2])
    after = _energy(mass_a, j_a, floats[0], floats[1], floats[2], floats[3], floats[4],
                    floats[5])  # fmt: skip
    # Carnot's E_p (paper eq. 13): the kinetic energy of the velocities lost
    lost = _energy(mass_a, j_a, floats[0] - v_a[0], floats[1] - v_a[1], floats[2] - v_a[2],
                   floats[3] - om_a[0], floats[4] - om_a[1], floats[5] - om_a[2])  # fmt: skip
    if movable_b:
        before += _energy(mass_b, j_b, v_b[0], v_b[1], v_b[2], om_b[0], om_b[1], om_b[2])
        after += _energy(mass_b, j_b, floats[6], floats[7], floats[8], floats[9], floats[10],
                         floats[11])  # fmt: skip
        lost += _energy(mass_b, j_b, floats[6] - v_b[0], floats[7] - v_b[1],
                        floats[8] - v_b[2], floats[9] - om_b[0], floats[10] - om_b[1],
                        floats[11] - om_b[2])  # fmt: skip
    floats[12] = before
    floats[13] = after
    floats[14] = before - after
    floats[16] = lost
    theorem = 0.0
    r = 0
    base = 17
    for c in range(k):
        share = 0.0
        px, py, pz = 0.0, 0.0, 0.0
        for a in range(1 + 2 * tangential[c]):
            share += -0.5 * imp[r] * (w[r] + wa[r])
            px += imp[r] * axes[c, a, 0]
            py += imp[r] * axes[c, a, 1]
            pz += imp[r] * axes[c, a, 2]
            if a == 0:
                floats[base + 3 * k + c] = imp[r]  # normal impulse
            r += 1
        floats[base + 3 * c] = px
        floats[base + 3 * c + 1] = py
        floats[base + 3 * c + 2] = pz
        floats[base + 4 * k + c] = share
        theorem += share
    floats[15] = theorem


@_leaf
def frictionless_fast(g, w, nrow, trow, ntan, e, mu, imp, wa, regime, active, work, rhs, sel):  # type: ignore[no-untyped-def]
    """The simultaneous law for normal rows only (``m = k``, no friction), when every
    taking-part subset that is tried has a clearly non-singular ``G_SS`` (pivots above 1e-8
    of its largest diagonal entry): then the impulses are unique (Cottle, Pang and Stone,
    thm 3.1.6: a positive definite LCP) and any enumeration finds the reference's answer. The
    active sets are tried all closed first, then the one the all-closed impulses predict
    (a pull: separates), then every other; each by Cholesky, without allocation. Returns
    ``(done, status, flags, residual)``; ``done`` False leaves the impact to
    :func:`solve_in_workspaces`."""
    m = w.shape[0]
    k = nrow.shape[0]
    scale = 0.0
    for i in range(m):
        scale = max(scale, abs(w[i]))
    if not (scale > 0.0 and math.isfinite(scale)):
        scale = 1.0
    tol = RELATIVE_TOLERANCE * scale
    npart = 0
    for c in range(k):
        if w[c] <= tol:
            npart += 1
    total = 1 << npart
    guess = -1
    for trial in range(total + 2):
        # the subset: bit j of ``code`` set = the j-th taking-part contact separates
        if trial == 0:
            code = 0
        elif trial == 1:
            if guess <= 0:
                continue
            code = guess
        else:
            code = trial - 2
            if code == 0 or code == guess:
                continue
        q = 0
        j = 0
        for c in range(k):
            sel[c] = 0
            if w[c] <= tol:
                if not (code >> j) & 1:
                    sel[c] = 1
                    rhs[q] = -(1.0 + e[c]) * w[c]
                    q += 1
                j += 1
        # Cholesky of G_SS (rows of the closed contacts, in order)
        dmax = 0.0
        a = 0
        for c in range(k):
            if sel[c]:
                b = 0
                for c2 in range(k):
                    if sel[c2]:
                        work[a, b] = g[c, c2]
                        b += 1
                dmax = max(dmax, g[c, c])
                a += 1
        for jj in range(q):
            s = work[jj, jj]
            for p in range(jj):
                s -= work[jj, p] * work[jj, p]
            if not s > 1e-8 * dmax:
                return False, 0, 0, 0.0
            d = math.sqrt(s)
            work[jj, jj] = d
            for i in range(jj + 1, q):
                s2 = work[i, jj]
                for p in range(jj):
                    s2 -= work[i, p] * work[jj, p]
                work[i, jj] = s2 / d
        _cholesky_solve(work, rhs[:q])
        a = 0
        for c in range(k):
            if sel[c]:
                imp[c] = rhs[a]
                a += 1
            else:
                imp[c] = 0.0
        feasible = True
        pred = 0
        j = 0
        for c in range(k):
            s = w[c]
            for r in range(k):
                s += g[c, r] * imp[r]
            wa[c] = s
            if w[c] <= tol:
                if sel[c]:
                    if g[c, c] * imp[c] < -tol:
                        feasible = False
                        if imp[c] < -RELATIVE_TOLERANCE * scale / max(g[c, c], 1e-300):
                            pred |= 1 << j
                elif s + e[c] * w[c] < -tol:
                    feasible = False
                j += 1
        if trial == 0:
            guess = pred
        if feasible:
            flags = 0
            residual = 0.0
            kinds = np.int64(FRICTIONLESS_KIND)
            for c in range(k):
                part = w[c] <= tol
                regime[c] = FRICTIONLESS if sel[c] else SEPARATE
                active[c] = sel[c] == 1
                if not part and wa[c] < -tol:
                    flags |= SEPARATING_CONTACT_APPROACHES
                residual = max(residual, contact_residual(c, g, nrow, trow, ntan, kinds, e, mu,
                                                          imp, w, wa, part))  # fmt: skip
            if residual > tol:
                return False, 0, 0, 0.0
            return True, SOLVED, flags, residual
    return False, 0, 0, 0.0


#: Impacts per task of the parallel loop (each task allocates its workspace once).
TASK = 64


@numba.njit(cache=True, nogil=True, error_model="numpy", parallel=True)
@_stamp
def run(mass_a, j_a, x_a, v_a, om_a, mass_b, j_b, x_b, v_b, om_b, movable_b, points, normals,  # type: ignore[no-untyped-def]
        e, mu, nrow, trow, ntan, tangential, floats, regime, active, status, flags,
        residual, bad, solver, regime_solver, holds):  # fmt: skip
    """Every impact ``i`` of the ``(N, ...)`` inputs: assemble, solve (the simultaneous law:
    :func:`solve_front` and :func:`solve_into`, in ``solver``, which calls ``regime_solver``
    and ``holds``: :func:`impact_solvers`' C callbacks, called by their address), finish; in
    parallel, :data:`TASK` impacts per task. ``bad[i]``: 1 or 2 when the inertia of ``a`` or
    ``b`` is invalid. A frictionless batch comes here after :func:`run_normal`, with the
    impacts that :func:`frictionless_fast` could not decide only: it is not tried again
    (compiled into this entry point it cost 1.9 s of its 8.7 s cold compile)."""
    count = mass_a.shape[0]
    k = nrow.shape[0]
    m = k + 2 * int(np.sum(tangential))
    for task in numba.prange((count + TASK - 1) // TASK):
        g = np.empty((m, m))
        w = np.empty(m)
        jac_a = np.empty((m, 6))
        jac_b = np.empty((m, 6))
        axes = np.empty((k, 3, 3))
        inv_a = np.empty((3, 3))
        inv_b = np.empty((3, 3))
        imp = np.empty(m)
        wa = np.empty(m)
        ws = workspace(k, m)
        nws = newton_workspace(k, m)
        rws = regime_workspace(k, m)
        inertia_a = np.empty((3, 3))  # (writable: the solvers' type in both routes)
        flags_out = np.empty(1, dtype=np.int64)
        residual_out = np.empty(1)
        for i in range(task * TASK, min(count, (task + 1) * TASK)):
            ok_a, ok_b = assemble_into(mass_a[i], j_a[i], x_a[i], v_a[i], om_a[i], mass_b[i],
                                       j_b[i], x_b[i], v_b[i], om_b[i], movable_b, points[i],
                                       normals[i], tangential, m, g, w, jac_a, jac_b, axes,
                                       inv_a, inv_b)  # fmt: skip
            if not ok_a or not (ok_b or not movable_b):
                bad[i] = 1 if not ok_a else 2
                status[i] = 4
                continue
            # (the landing that sticks as predicted: solve_front alone)
            inertia_a[:, :] = j_a[i]
            s = solver(g, w, nrow, trow, ntan, e[i], mu[i], imp, wa, regime[i], active[i], ws,
                       nws, rws, jac_a, mass_a[i], inertia_a, not movable_b, np.bool_(True),
                       flags_out, residual_out, regime_solver, holds)  # fmt: skip
            status[i] = s
            flags[i] = flags_out[0]
            residual[i] = residual_out[0]
            if s == SOLVED or s == NO_SOLUTION:
                finish(mass_a[i], j_a[i], v_a[i], om_a[i], mass_b[i], j_b[i], v_b[i], om_b[i],
                       movable_b, axes, tangential, jac_a, jac_b, inv_a, inv_b, imp, w, wa,
                       floats[i])  # fmt: skip


@numba.njit(cache=True, nogil=True, error_model="numpy", parallel=True)
@_stamp
def run_normal(mass_a, j_a, x_a, v_a, om_a, mass_b, j_b, x_b, v_b, om_b,  # type: ignore[no-untyped-def]
               movable_b, points, normals, e, mu, nrow, trow, ntan, tangential, floats,
               regime, active, status, flags, residual, bad):  # fmt: skip
    """:func:`run` for normal rows only (no contact with friction): each impact that
    :func:`frictionless_fast` decides, and ``status[i] =`` :data:`UNDECIDED` for the others,
    which :func:`run` then does. A frictionless batch compiles this small kernel (seconds),
    and the regime solvers of :func:`solve_into` (a minute) only if some impact is not
    decided here (a ``G`` of the taking-part contacts near singular), and runs as fast as
    :func:`run` did on these impacts (``benchmarks/bench_batch_multi.py``)."""
    count = mass_a.shape[0]
    k = nrow.shape[0]
    m = k
    for task in numba.prange((count + TASK - 1) // TASK):
        g = np.empty((m, m))
        w = np.empty(m)
        jac_a = np.empty((m, 6))
        jac_b = np.empty((m, 6))
        axes = np.empty((k, 3, 3))
        inv_a = np.empty((3, 3))
        inv_b = np.empty((3, 3))
        imp = np.empty(m)
        wa = np.empty(m)
        work = np.empty((m, m))
        rhs = np.empty(m)
        sel = np.empty(k, dtype=np.int64)
        for i in range(task * TASK, min(count, (task + 1) * TASK)):
            ok_a, ok_b = assemble_into(mass_a[i], j_a[i], x_a[i], v_a[i], om_a[i], mass_b[i],
                                       j_b[i], x_b[i], v_b[i], om_b[i], movable_b, points[i],
                                       normals[i], tangential, m, g, w, jac_a, jac_b, axes,
                                       inv_a, inv_b)  # fmt: skip
            if not ok_a or not (ok_b or not movable_b):
                bad[i] = 1 if not ok_a else 2
                status[i] = 4
                continue
            done, s, f, r = frictionless_fast(g, w, nrow, trow, ntan, e[i], mu[i], imp, wa,
                                              regime[i], active[i], work, rhs, sel)  # fmt: skip
            if not done:
                status[i] = UNDECIDED
                continue
            status[i] = s
            flags[i] = f
            residual[i] = r
            finish(mass_a[i], j_a[i], v_a[i], om_a[i], mass_b[i], j_b[i], v_b[i], om_b[i],
                   movable_b, axes, tangential, jac_a, jac_b, inv_a, inv_b, imp, w, wa,
                   floats[i])  # fmt: skip


@numba.njit(cache=True, nogil=True, error_model="numpy", parallel=True)
@_stamp
def solve_rows_normal(g, w, nrow, trow, ntan, e, mu, imp, wa, regime, active, status,  # type: ignore[no-untyped-def]
                      flags, residual):  # fmt: skip
    """:func:`solve_rows` for normal rows only (``m = k``): each impact that
    :func:`frictionless_fast` decides, and ``status[i] =`` :data:`UNDECIDED` for the others,
    which :func:`solve_rows` then does (as :func:`run_normal` for bodies: a frictionless
    batch of contact spaces, a cradle say, compiles the regime solvers only if needed)."""
    count = g.shape[0]
    k = nrow.shape[0]
    m = w.shape[1]
    for task in numba.prange((count + 63) // 64):
        work = np.empty((m, m))
        rhs = np.empty(m)
        sel = np.empty(k, dtype=np.int64)
        for i in range(task * 64, min(count, (task + 1) * 64)):
            done, s, f, r = frictionless_fast(g[i], w[i], nrow, trow, ntan, e[i], mu[i],
                                              imp[i], wa[i], regime[i], active[i], work, rhs,
                                              sel)  # fmt: skip
            status[i] = s if done else UNDECIDED
            flags[i] = f
            residual[i] = r

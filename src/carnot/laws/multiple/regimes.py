"""The simultaneous law's regimes, written once: which regimes a contact may be in, and the
linear system a regime sets (its unknowns and the velocities it fixes).

In a regime each contact taking part is closed, stuck, slipping or separated
(:mod:`carnot.laws.multiple.simultaneous`, whose docstring states the law). Its free impulses
``x`` give the row impulses ``Lambda = B x``: a closed or stuck contact's normal column
``e_n``, a stuck one's tangent columns ``e_t``, a slipping one's single column
``e_n - mu s`` (``s`` the unit slip direction: ``+-e_t`` in a plane, ``(cos a, sin a)`` over
the two tangent rows in 3D). The rows ``R`` whose velocity after the regime fixes are the
closed and stuck rows and the slipping normals, with the targets ``w_n'' = -e w_n'`` (Newton)
and ``w_t'' = 0``; the regime's system is ``(G B)_R x = w''_R - w'_R``.

Why written as plain Python loops on a contact's layout arrays (``nrow``, the normal row of
each contact; ``trow``, its tangent rows; ``ntan``, how many; ``mu``, ``e``; the regime as
one option code a contact): the law enumerates regimes in Python for :func:`carnot.
solve_impact` and the multi-contact batch kernel (:mod:`carnot.batch.multi_kernel`) enumerates
them compiled, and both run these functions, the law as written and the kernel compiled by
Numba (:func:`carnot.batch.ops.compiled_rules`). So the regimes and their equations have one
statement, and the two routes build the same ``B``, rows and targets to the bit
(tests/test_regimes.py).

>>> import numpy as np
>>> b, rows, targets = np.zeros((3, 3)), np.zeros(3, dtype=np.int64), np.zeros(3)
>>> regime_columns(3, np.array([0]), np.array([[1, 2]]), np.array([2]), np.array([0.5]),
...                np.array([0.2]), np.array([SLIP_OPT]), np.array([-1.0, 0.3, 0.4]),
...                np.array([[0.6, 0.8]]), b, rows, targets)
(1, False)
>>> b[:, 0].tolist(), rows[:1].tolist(), targets[:1].tolist()
([1.0, -0.3, -0.4], [0], [0.2])
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from carnot.conventions import RELATIVE_TOLERANCE

#: A contact's kind: its tangent rows' law (``FRICTIONLESS_KIND``: none, or ``mu = 0``;
#: ``PLANAR``: Coulomb on one tangent row; ``SPATIAL``: Coulomb's circular cone on two;
#: ``TOLD_TO_STICK``: stuck whenever loaded, no friction bound).
FRICTIONLESS_KIND, PLANAR, SPATIAL, TOLD_TO_STICK = 0, 1, 2, 3
#: A contact's option in a regime: not taking part, separating, closed (frictionless), stuck,
#: slipping towards ``-t`` (``SLIP_PLUS``: impulse ``e_n - mu e_t``) or ``+t`` in a plane, and
#: slipping in 3D along its slip direction.
OUT, SEPARATE_OPT, CLOSED, STICK_OPT, SLIP_PLUS, SLIP_MINUS, SLIP_OPT = 0, 1, 2, 3, 4, 5, 6
#: The options' names in the law's results and regimes (:mod:`carnot.laws.multiple.rows`).
OPTION_NAMES = ("out", "separate", "closed", "stick", "slip+", "slip-", "slip")


def regime_options(kind: int, out: Any) -> int:
    """The options a contact of ``kind`` may take in a regime, the most common first (the
    order the enumeration tries them), into ``out``; returns their number.

    >>> import numpy as np
    >>> out = np.zeros(4, dtype=np.int64)
    >>> [OPTION_NAMES[o] for o in out[:regime_options(PLANAR, out)]]
    ['stick', 'slip+', 'slip-', 'separate']
    """
    if kind == FRICTIONLESS_KIND:
        out[0], out[1] = CLOSED, SEPARATE_OPT
        return 2
    if kind == PLANAR:
        out[0], out[1], out[2], out[3] = STICK_OPT, SLIP_PLUS, SLIP_MINUS, SEPARATE_OPT
        return 4
    if kind == TOLD_TO_STICK:
        out[0], out[1] = STICK_OPT, SEPARATE_OPT
        return 2
    out[0], out[1], out[2] = STICK_OPT, SLIP_OPT, SEPARATE_OPT
    return 3


def regime_columns(m, nrow, trow, ntan, mu, e, pattern, w, dirs, b, rows, targets):  # type: ignore[no-untyped-def]
    """The regime ``pattern`` (an option code per contact)'s unknowns ``Lambda = B x``, as
    the first columns of ``b`` (m rows; only the columns written are set), the rows whose
    velocity after it fixes into ``rows`` and their targets (m/s) into ``targets``;
    ``dirs[c]`` is contact ``c``'s unit slip direction over its two tangent rows (3D slip).
    Returns ``(q, symmetric)``: the number of columns and whether ``B`` is a selection of
    rows (no slip column: then ``G_RR`` is the regime's system, symmetric)."""
    q = 0
    symmetric = True
    for c in range(nrow.shape[0]):
        opt = pattern[c]
        if opt == OUT or opt == SEPARATE_OPT:
            continue
        for r in range(m):
            b[r, q] = 0.0
        n = nrow[c]
        b[n, q] = 1.0
        if opt == SLIP_PLUS:
            b[trow[c, 0], q] = -mu[c]
            symmetric = False
        elif opt == SLIP_MINUS:
            b[trow[c, 0], q] = mu[c]
            symmetric = False
        elif opt == SLIP_OPT:
            b[trow[c, 0], q] = -mu[c] * dirs[c, 0]
            b[trow[c, 1], q] = -mu[c] * dirs[c, 1]
            symmetric = False
        rows[q] = n
        targets[q] = -e[c] * w[n]
        q += 1
        if opt == STICK_OPT:
            for j in range(ntan[c]):
                t = trow[c, j]
                for r in range(m):
                    b[r, q] = 0.0
                b[t, q] = 1.0
                rows[q] = t
                targets[q] = 0.0
                q += 1
    return q, symmetric


def regime_inequalities(g, w, nrow, trow, kind, e, mu, pattern, dirs, b, q, gb, lin_a, lin_c,  # type: ignore[no-untyped-def]
                        cones):  # fmt: skip
    """A regime's inequalities on its unknowns ``x`` (``Lambda = B x`` of
    :func:`regime_columns`, ``gb = G B``): the linear ones ``lin_a x + lin_c >= 0`` (m/s:
    impulses times the contact's ``G_nn``) into the first rows of ``lin_a`` and ``lin_c``
    (``3 k`` rows at most), and each sticking 3D contact's cone into ``cones`` (a row each:
    its normal row, the contact, ``mu``); returns their numbers ``(nlin, ncones)``.

    Per contact: separating, Glocker's ``w_n'' + e w_n' >= 0``; loaded, ``P_n >= 0``; stuck
    in a plane, ``|P_t| <= mu P_n`` as two lines (in 3D the circular cone, kept apart: it is
    not linear); slipping, the post-impact slip along the slip direction it was given
    (``s . w_t'' >= 0``: friction opposes the slip it causes)."""
    k = nrow.shape[0]
    for i in range(3 * k):  # (lin_a's and cones' rows are written before they are read)
        lin_c[i] = 0.0
    nlin = np.int64(0)  # (typed so, not a literal: the compiled callers take one type)
    ncones = np.int64(0)
    for c in range(k):
        opt = pattern[c]
        n = nrow[c]
        gnn = g[n, n]
        if opt == OUT:
            continue
        if opt == SEPARATE_OPT:
            for j in range(q):
                lin_a[nlin, j] = gb[n, j]
            lin_c[nlin] = w[n] + e[c] * w[n]
            nlin += 1
            continue
        for j in range(q):
            lin_a[nlin, j] = gnn * b[n, j]
        nlin += 1
        if opt == STICK_OPT and kind[c] == PLANAR:
            t = trow[c, 0]
            for j in range(q):
                lin_a[nlin, j] = gnn * (mu[c] * b[n, j] - b[t, j])
                lin_a[nlin + 1, j] = gnn * (mu[c] * b[n, j] + b[t, j])
            nlin += 2
        elif opt == STICK_OPT and kind[c] == SPATIAL:
            cones[ncones, 0] = n
            cones[ncones, 1] = c
            cones[ncones, 2] = mu[c]
            ncones += 1
        elif opt == SLIP_PLUS or opt == SLIP_MINUS:
            sign = 1.0 if opt == SLIP_PLUS else -1.0
            t = trow[c, 0]
            for j in range(q):
                lin_a[nlin, j] = sign * gb[t, j]
            lin_c[nlin] = sign * w[t]
            nlin += 1
        elif opt == SLIP_OPT:
            t1, t2 = trow[c, 0], trow[c, 1]
            for j in range(q):
                lin_a[nlin, j] = dirs[c, 0] * gb[t1, j] + dirs[c, 1] * gb[t2, j]
            lin_c[nlin] = dirs[c, 0] * w[t1] + dirs[c, 1] * w[t2]
            nlin += 1
    return nlin, ncones


def predicted_order(g, nrow, trow, ntan, kind, mu, part, nopt, opts, ordered, predicted,  # type: ignore[no-untyped-def]
                    has_pred, p, scale):  # fmt: skip
    """Each taking-part contact's options (``opts[c, :nopt[c]]``, :func:`regime_options`'
    order) ordered most likely first into ``ordered[c]``, from the impulses ``p`` (N s, per
    row) that closing every taking-part contact, sticking where it can, would need: a pull
    (``p_n < -1e-9 v / G_nn``, ``v = scale`` the velocity scale, m/s) means it separates;
    outside its cone (``|p_t| > mu p_n``) means it slips, opposite to that tangential
    impulse (in 3D that direction into ``predicted[c]``, ``has_pred[c]`` set). Returns
    whether the contacts are overloaded (their tangential impulses need more than their
    cones hold, in sum, ``sum |p_t| > sum mu max(p_n, 0)``); then a contact predicted to
    separate has its slip options before sticking (the order in which it is put back: a
    box sliding flat onto four corners, predicted with two lifting where one does, has the
    other tried slipping, as its neighbours slip, before a mixed regime whose slip roots
    all fail)."""
    k = nrow.shape[0]
    need = 0.0
    capacity = 0.0
    for c in range(k):
        if not part[c]:
            continue
        n = nrow[c]
        pn = p[n]
        p1 = p[trow[c, 0]] if ntan[c] >= 1 else 0.0
        p2 = p[trow[c, 1]] if ntan[c] >= 2 else 0.0
        pt = math.sqrt(p1 * p1 + p2 * p2)
        first = opts[c, 0]
        if pn < -RELATIVE_TOLERANCE * scale / max(g[n, n], 1e-300):
            first = SEPARATE_OPT
        elif (kind[c] == PLANAR or kind[c] == SPATIAL) and pt > mu[c] * pn:
            if kind[c] == PLANAR:
                first = SLIP_PLUS if p1 < 0.0 else SLIP_MINUS
            else:
                first = SLIP_OPT
                predicted[c, 0] = -p1 / pt
                predicted[c, 1] = -p2 / pt
                has_pred[c] = True
        ordered[c, 0] = first
        j = 1
        for o in range(nopt[c]):
            if opts[c, o] != first:
                ordered[c, j] = opts[c, o]
                j += 1
        if kind[c] == PLANAR or kind[c] == SPATIAL:
            need += pt
            capacity += mu[c] * max(pn, 0.0)
    overloaded = need > capacity
    if overloaded:
        # a contact predicted to separate is put back slipping before sticking (the
        # reference's order: its slip options moved before the stick option, in their order)
        for c in range(k):
            if part[c] and ordered[c, 0] == SEPARATE_OPT and ordered[c, 1] == STICK_OPT:
                for j in range(1, nopt[c] - 1):
                    ordered[c, j] = ordered[c, j + 1]
                ordered[c, nopt[c] - 1] = STICK_OPT
    return overloaded


def widest_pattern(nrow, trow, ntan, kind, e, w, w_after, pattern, tol, wide, dirs):  # type: ignore[no-untyped-def]
    """The widest regime of an answer (``pattern``, its velocities after ``w_after``, m/s):
    every separating contact whose law holds with equality (``|w_n'' + e w_n'| <= tol``, so
    it could carry an impulse) closed, stuck or slipping as its post-impact tangential
    velocity says (``|w_t''| > tol``: slipping, along it), into ``wide``; each slipping
    contact's unit slip direction (``w_t'' / |w_t''|``) into ``dirs`` (zero elsewhere).
    Returns whether any contact was widened. (The answer's impulses are not unique when they
    are not unique in that regime: a box landing flat on four corners found with three of
    them loaded.)

    >>> import numpy as np
    >>> wide, dirs = np.zeros(1, dtype=np.int64), np.zeros((1, 2))
    >>> widest_pattern(np.array([0]), np.array([[1, 2]]), np.array([2]), np.array([SPATIAL]),
    ...                np.array([0.0]), np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, 2.0]),
    ...                np.array([SEPARATE_OPT]), 1e-9, wide, dirs)
    True
    >>> OPTION_NAMES[wide[0]], dirs[0].tolist()
    ('slip', [0.0, 1.0])
    """
    changed = False
    for c in range(nrow.shape[0]):
        dirs[c, 0] = 0.0
        dirs[c, 1] = 0.0
        wide[c] = pattern[c]
        nt = ntan[c]
        a1 = w_after[trow[c, 0]] if nt >= 1 else 0.0
        a2 = w_after[trow[c, 1]] if nt >= 2 else 0.0
        norm = math.sqrt(a1 * a1 + a2 * a2)
        if pattern[c] == SLIP_OPT:
            dirs[c, 0] = a1 / norm
            dirs[c, 1] = a2 / norm
        vn = w_after[nrow[c]] + e[c] * w[nrow[c]]
        if pattern[c] != SEPARATE_OPT or abs(vn) > tol:
            continue
        changed = True
        if kind[c] == FRICTIONLESS_KIND:
            wide[c] = CLOSED
        elif kind[c] == TOLD_TO_STICK or not norm > tol:
            wide[c] = STICK_OPT
        elif kind[c] == PLANAR:
            wide[c] = SLIP_PLUS if a1 > 0.0 else SLIP_MINUS
        else:
            wide[c] = SLIP_OPT
            dirs[c, 0] = a1 / norm
            dirs[c, 1] = a2 / norm
    return changed


def slips_as_assumed(trow, pattern, dirs, w_after, tol):  # type: ignore[no-untyped-def]
    """Whether every slipping contact of the regime ``pattern`` slips after it the way the
    regime assumed (``+-w_t'' > tol`` in a plane, ``s . w_t'' > tol`` in 3D along its slip
    direction ``dirs[c]``; m/s): with ``w_t'' = 0`` the answer is the stick regime's, on
    the cone's surface, and not this one's.

    >>> import numpy as np
    >>> slips_as_assumed(np.array([[1, -1]]), np.array([SLIP_MINUS]), np.zeros((1, 2)),
    ...                  np.array([0.0, -0.5]), 1e-9)
    True
    """
    for c in range(pattern.shape[0]):
        opt = pattern[c]
        if opt == SLIP_PLUS or opt == SLIP_MINUS:
            sign = 1.0 if opt == SLIP_PLUS else -1.0
            if sign * w_after[trow[c, 0]] <= tol:
                return False
        elif opt == SLIP_OPT:
            if dirs[c, 0] * w_after[trow[c, 0]] + dirs[c, 1] * w_after[trow[c, 1]] <= tol:
                return False
    return True


def answer_groups(cand_wa, ncand, tol):  # type: ignore[no-untyped-def]
    """The answers (regimes that hold) grouped by their velocities after, ``cand_wa[j]``
    (m/s): each answer joins the first group whose first answer's velocities are within
    ``tol`` of its own (largest difference of a row), else it starts a group. Returns the
    groups' first answers as a bit mask (bit ``j``: answer ``j`` starts a group; answers in
    the order found).

    >>> import numpy as np
    >>> answer_groups(np.array([[0.0, 1.0], [0.0, 1.0 + 1e-12], [0.5, 1.0]]), 3, 1e-9)
    5
    """
    firsts = 0
    for j in range(ncand):
        alone = True
        for f in range(j):
            if (firsts >> f) & 1 and _apart(cand_wa, j, f) <= tol:
                alone = False
                break
        if alone:
            firsts |= 1 << j
    return firsts


def group_first(cand_wa, j, firsts, tol):  # type: ignore[no-untyped-def]
    """The first answer of answer ``j``'s group (``firsts``: :func:`answer_groups`)."""
    for f in range(j + 1):
        if (firsts >> f) & 1 and _apart(cand_wa, j, f) <= tol:
            return f
    return j


def group_verdict(cand_imp, cand_wa, not_unique, continuum, ncand, first, firsts, tol,  # type: ignore[no-untyped-def]
                  impulse_tol):  # fmt: skip
    """The verdict on the group of answers that answer ``first`` starts (``firsts``:
    :func:`answer_groups`; velocities within ``tol``, m/s): ``(statically_indeterminate,
    multiple_solutions)``. Statically indeterminate: one of them has impulses that are not
    unique in its regime (``not_unique``), or two of them differ in their impulses by more
    than ``impulse_tol`` times the group's largest impulse (N s; 1 where all are zero): the
    same velocities, other impulses. Multiple solutions: another group exists (other
    velocities), or one of the group is a continuum of answers (``continuum``)."""
    scale = 0.0
    for j in range(ncand):
        if group_first(cand_wa, j, firsts, tol) == first:
            for i in range(cand_imp.shape[1]):
                scale = max(scale, abs(cand_imp[j, i]))
    if scale == 0.0:
        scale = 1.0
    indeterminate = False
    multiple = firsts != (1 << first)
    for j in range(ncand):
        if group_first(cand_wa, j, firsts, tol) != first:
            continue
        if continuum[j]:
            multiple = True
        if not_unique[j] or _apart(cand_imp, j, first) > impulse_tol * scale:
            indeterminate = True
    return indeterminate, multiple


def _apart(rows, i, j):  # type: ignore[no-untyped-def]
    """The largest difference of rows ``i`` and ``j`` of ``rows``."""
    worst = 0.0
    for r in range(rows.shape[1]):
        worst = max(worst, abs(rows[i, r] - rows[j, r]))
    return worst

"""Coulomb friction with slip in the batch kernels: Newton, Poisson and Stronge restitution.

Written once for :mod:`carnot.batch.ops` (one impact in scalars for Numba, or a whole batch
with masks), with the signature of :mod:`carnot.batch.laws`,

    law(k, w, e, mu) -> (p_n, p_1, p_2, regime, p_c, W_nc, W_nr, W_tc, W_tr, law_flags)

in the contact frame ``(n, t1, t2)``: ``k`` the six entries of the contact's inverse mass
``K`` (1/kg), ``w = (w_n, w_1, w_2)`` the relative velocity before (m/s), ``e`` in [0, 1],
``mu >= 0``. It is the single-impact engine :mod:`carnot.laws.friction` (Darboux-Keller:
the normal impulse ``p`` is the clock, ``w(P) = w' + K P``) rule for rule:

* slip along ``s = w_t / |w_t|`` (``dP_t = -mu s dp``, Stronge 2000 eq. 5.7); slip slower
  than ``NEAR_STOP |w'|`` counts as none;
* a slip direction is *invariant* when ``dw_t/dp = K_tn - mu K_tt s`` is parallel to ``s``
  (always so in a planar problem): the phase is linear in ``p`` and its events (the stop
  ``w_t = 0``, maximum compression ``w_n = 0``, the end of the impact) are roots of linear and
  quadratic equations, solved exactly;
* at a stop, the contact sticks (``dP_t/dp = -K_tt^-1 K_tn``) when that ratio is inside the
  friction cone, else slip resumes at once along the invariant direction ``K_tn - mu K_tt s =
  lambda s``, ``lambda > 0`` (a reversal when ``s`` is opposite to the old direction; a
  redirection otherwise), which never stops again;
* a slip direction that turns (3D) is integrated by :func:`_turning_slip`: the DOP853 of
  :mod:`carnot.laws.slip3d` (at ``RTOL = 1e-10``, not 1e-12), but on the polar form of the
  slip (``|w_t|``, held to a relative tolerance, and the unit direction on the clock ``d
  tau = dp / |w_t|``, smooth where the slip stops), its events located on the step map; the
  last ``NEAR_STOP |w'|`` of a stop, and the rest of a phase whose direction has settled on
  an attracting invariant direction, finished in closed form. It is written as passes of
  straight-line code (:func:`slip_start`, :func:`slip_pass`, :func:`slip_end`: one DOP853
  step per row and pass), which the compiled kernel runs on many impacts side by side,
  vectorized (SIMD lanes: :mod:`carnot.batch.compiled`);
* the impact ends by the hypothesis (Stronge 2000 ch. 2 and 5): Newton ``w_n = -e w'_n``,
  Poisson ``p = (1 + e) p_c``, Stronge ``W_nr = -e^2 W_nc`` (normal work in restitution).

Like the engine, everything is computed in units of ``|w'|`` and ``|w'| / K_nn`` (every
quantity of order 1: the tolerances are relative), then scaled back. Rows with ``mu = 0``
get the frictionless law (regime ``FRICTIONLESS``), rows not approaching no impulse at all
(regime ``NONE``), as :func:`carnot.solve_impact` gives them.

The regime codes (:data:`carnot.batch.laws.REGIME_NAMES`: ``SLIP``, ``SLIP_STICK``,
``SLIP_REVERSAL``, ``SLIP_REDIRECTED``, ``STICK``, ``NONE``) name the phases as
``FrictionalImpulse.regime`` does; the warning bits of ``law_flags`` are below.

A uniform sphere (``K = diag(1, 3.5, 3.5)`` per kg) landing at 1 m/s while sliding at 1 m/s,
mu = 0.1, e = 0.5: gross slip, ``P_t = -mu P_n`` (Brach 1991, ch. 4):

>>> out = coulomb_poisson((1.0, 0.0, 0.0, 3.5, 0.0, 3.5), (-1.0, 1.0, 0.0), 0.5, 0.1)
>>> [round(float(x), 12) for x in out[:3]], REGIME_NAMES[int(out[3])]
([1.5, -0.15, 0.0], 'slip')
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from carnot.batch.laws import (
    FRICTIONLESS,
    NONE,
    REGIME_NAMES,  # noqa: F401 - the doctests name the regimes
    SLIP,
    SLIP_REDIRECTED,
    SLIP_REVERSAL,
    SLIP_STICK,
    STICK,
    frictionless,
)
from carnot.batch.ops import formula, select, sqrt

#: ``law_flags`` bits. ``NORMAL_WORK_GAIN``: the normal impulse did net positive work
#: (``W_n > 1e-9 |W_nc|``: restitution gave back more than compression took, Newton's or
#: Poisson's hypothesis after slip stopped or reversed; the single solver's
#: ``normal_energy_gain``). ``HYPOTHESIS_ENERGY_GAIN``: the contact's works add up to an energy
#: gain (``W_n + W_t > 1e-12 (|W_nc| + |W_t|)``: Kane and Levinson's paradox; never under
#: Stronge's hypothesis). ``JAM``: the normal impulse grows without bound (Painleve's paradox:
#: no rigid-body solution; the impulse is NaN). ``STEP_LIMIT``: the 3D integration did not
#: finish within its step budget (or its step fell below round-off; the impulse is NaN).
NORMAL_WORK_GAIN, HYPOTHESIS_ENERGY_GAIN, JAM, STEP_LIMIT = 1, 2, 4, 8

#: The hypotheses, as the constant argument of :func:`coulomb`, and the laws that fix them.
NEWTON, POISSON, STRONGE = 0, 1, 2
HYPOTHESES = {"coulomb_newton": NEWTON, "coulomb_poisson": POISSON, "coulomb_stronge": STRONGE}

#: As carnot.laws.friction: slip slower than this fraction of |w'| counts as none (and a 3D
#: slip that slows to it is finished in closed form); the relative slack of the cone test.
NEAR_STOP = 1e-9
CONE_SLACK = 1e-12
#: Relative tolerance of the 3D integration: 1e-10, two digits looser than the single-impact
#: engine's (carnot.laws.friction.RTOL = 1e-12) for ~30% fewer steps. On the benchmark's 3D
#: cases the impulses stay within 2e-10 of the engine's (relative; median 2e-12), regimes and
#: flags the same; tests/test_batch_coulomb.py holds every impact to RTOL cond(K).
RTOL = 1e-10
INF = math.inf
NAN = math.nan


@formula
def _velocity(k: Any, w0: Any, p: Any, q1: Any, q2: Any) -> Any:
    """``w' + K P`` for ``P = (p, q1, q2)``."""
    return (w0[0] + k[0] * p + k[1] * q1 + k[2] * q2,
            w0[1] + k[1] * p + k[3] * q1 + k[4] * q2,
            w0[2] + k[2] * p + k[4] * q1 + k[5] * q2)  # fmt: skip


@formula
def _positive(x: Any) -> Any:
    """``x`` where it is > 0, else 1: a safe denominator (the other branch is discarded)."""
    return select(x > 0, x, 1.0)


@formula
def _termination_step(hyp: Any, e: Any, w0n: Any, p: Any, p_c: Any, work_r: Any,
                      work_c: Any, w_n: Any, slope_n: Any) -> Any:  # fmt: skip
    """The normal impulse still to go in a linear phase until the hypothesis ends the impact
    (``inf``: never within this phase); ``slope_n = dw_n/dp``."""
    if hyp == POISSON:  # p = (1 + e) p_c
        left = (1.0 + e) * p_c - p
        return select(left > 0, left, 0.0)
    if hyp == NEWTON:  # w_n = -e w'_n
        gap = -e * w0n - w_n
        return select(gap <= 0, 0.0, select(slope_n > 0, gap / _positive(slope_n), INF))
    # Stronge: a/2 dp^2 + w_n dp + (W_r + e^2 W_c) = 0, its smallest root >= 0
    c = work_r + e * e * work_c
    a = 0.5 * slope_n
    disc = w_n * w_n - 4.0 * a * c
    root = sqrt(select(disc > 0, disc, 0.0))
    stable = -2.0 * c / _positive(w_n + root)  # (-w_n + root) / (2 a) without cancellation
    at_top = (root - w_n) / _positive(2.0 * a)  # at maximum compression (w_n ~ 0)
    return select(c >= 0, 0.0, select(disc < 0, INF, select(
        w_n > 0, stable, select(a > 0, at_top, INF))))  # fmt: skip


@formula
def _segment(k: Any, w0: Any, e: Any, hyp: Any, rate1: Any, rate2: Any, d1: Any, d2: Any,
             has_dir: Any, state: Any, active: Any) -> Any:  # fmt: skip
    """One stretch of a linear phase (``dP_t/dp = rate`` constant) to its first event: the
    stop (when ``has_dir``: slip along ``d``), maximum compression, or the end; ties in the
    engine's order (compression, end, stop). Rows not ``active`` or done keep their state.
    Returns ``(state, stopped, jammed)``. The works are exact (quadratics in ``dp``)."""
    p, q1, q2, wn, wt, wr, comp, pc, wc, wtc, done = state
    go = active & (done < 0.5)
    w = _velocity(k, w0, p, q1, q2)
    s0 = k[0] + k[1] * rate1 + k[2] * rate2  # dw/dp
    s1 = k[1] + k[3] * rate1 + k[4] * rate2
    s2 = k[2] + k[4] * rate1 + k[5] * rate2
    approach = s1 * d1 + s2 * d2
    can_stop = has_dir & (approach < 0)
    dp_stop = select(can_stop, (w[1] * d1 + w[2] * d2) / select(can_stop, -approach, 1.0), INF)
    dp_comp = select((comp < 0.5) & (s0 > 0), -w[0] / _positive(s0), INF)
    dp_end = select(comp > 0.5, _termination_step(hyp, e, w0[0], p, pc, wr, wc, w[0], s0),
                    INF)  # fmt: skip
    first_comp = (dp_comp <= dp_end) & (dp_comp <= dp_stop)
    first_end = select(first_comp, False, dp_end <= dp_stop)
    first_stop = _not(first_comp | first_end)
    dp = select(first_comp, dp_comp, select(first_end, dp_end, dp_stop))
    jammed = go & (dp == INF)
    dp = select(dp > 0, dp, 0.0)
    dp = select(go & (dp < INF), dp, 0.0)
    work_n = w[0] * dp + 0.5 * s0 * dp * dp
    wn2 = wn + work_n
    wr2 = select(comp > 0.5, wr + work_n, wr)
    wt2 = (wt + (w[1] * rate1 + w[2] * rate2) * dp
           + 0.5 * (s1 * rate1 + s2 * rate2) * dp * dp)  # fmt: skip
    p2 = p + dp
    q12 = q1 + rate1 * dp
    q22 = q2 + rate2 * dp
    ok = go & _not(jammed)
    mark = ok & first_comp
    comp2 = select(mark, 1.0, comp)
    done2 = select(ok & (first_end | (first_comp & (e == 0))), 1.0, done)
    new = (select(ok, p2, p), select(ok, q12, q1), select(ok, q22, q2), select(ok, wn2, wn),
           select(ok, wt2, wt), select(ok, wr2, wr), comp2, select(mark, p2, pc),
           select(mark, wn2, wc), select(mark, wt2, wtc), done2)  # fmt: skip
    return new, ok & first_stop, jammed


@formula
def _linear_phase(k: Any, w0: Any, e: Any, hyp: Any, rate1: Any, rate2: Any, d1: Any,
                  d2: Any, has_dir: Any, state: Any, active: Any) -> Any:  # fmt: skip
    """A phase with the constant ``dP_t/dp = rate`` (carnot.laws.friction._linear_phase): at
    most two stretches, as only maximum compression lets it go on. ``(state, stopped,
    jammed)``."""
    state, stop_a, jam_a = _segment(k, w0, e, hyp, rate1, rate2, d1, d2, has_dir, state,
                                    active)  # fmt: skip
    more = active & _not(stop_a | jam_a) & (state[10] < 0.5)  # neither stopped nor done
    if any_true(more):
        state, stop_b, jam_b = _segment(k, w0, e, hyp, rate1, rate2, d1, d2, has_dir, state,
                                        more)  # fmt: skip
        return state, stop_a | stop_b, jam_a | jam_b
    return state, stop_a, jam_a


@formula
def _resumed_direction(k: Any, mu: Any) -> Any:
    """The slip direction after a stop that cannot stick: ``s = (mu K_tt + lambda I)^-1 K_tn``
    with ``|s| = 1``, ``lambda > 0``. Newton's method on ``1/|s(lambda)| - 1`` (increasing
    and concave, as in Moré and Sorensen's trust-region iteration, and exactly linear in a
    planar problem) from ``lambda = 0``, where ``|s| > 1`` (no stick), climbs to the root
    from the left."""
    a11, a12, a22 = mu * k[3], mu * k[4], mu * k[5]
    b1, b2 = k[1], k[2]
    lam = 0.0 * mu
    for _ in range(RESUME_ITERATIONS):
        c11, c22 = a11 + lam, a22 + lam
        inv_det = 1.0 / (c11 * c22 - a12 * a12)
        s1 = (c22 * b1 - a12 * b2) * inv_det
        s2 = (c11 * b2 - a12 * b1) * inv_det
        t1 = (c22 * s1 - a12 * s2) * inv_det
        t2 = (c11 * s2 - a12 * s1) * inv_det
        size = _positive(sqrt(s1 * s1 + s2 * s2))  # 0 only where K_tn = 0: it sticks
        residual = 1.0 / size - 1.0
        if not any_true(abs(residual) > 4.0 * EPS):  # a Python bool in both builds
            break  # converged (a planar problem: after one step, the equation being linear)
        # d(1/|s|)/dlambda = s . A^-1 s / |s|^3
        slope = _positive((s1 * t1 + s2 * t2) / (size * size * size))
        lam = lam - residual / slope
        lam = select(lam > 0, lam, 0.0)  # a row that sticks would walk left: keep it at 0
    c11, c22 = a11 + lam, a22 + lam
    s1 = c22 * b1 - a12 * b2  # the determinant is > 0: the direction needs no division
    s2 = c11 * b2 - a12 * b1
    size = _positive(sqrt(s1 * s1 + s2 * s2))
    return s1 / size, s2 / size


#: Newton steps of :func:`_resumed_direction` (quadratic convergence from the left: 8 reach
#: round-off on the cases of tests/test_batch_coulomb.py).
RESUME_ITERATIONS = 8


@formula
def coulomb(k: Any, w: Any, e: Any, mu: Any, hyp: Any) -> Any:
    """Coulomb friction under the hypothesis ``hyp`` (``NEWTON``, ``POISSON``, ``STRONGE``: a
    constant), with the law signature of :mod:`carnot.batch.laws` (see the module
    docstring): :func:`coulomb_head`, the 3D slip whose direction turns
    (:func:`_turning_slip`) where there is one, then :func:`coulomb_tail`. (The compiled
    kernel runs the three parts itself, the middle one for many impacts side by side: see
    :func:`slip_start`.)"""
    head = coulomb_head(k, w, e, mu, hyp)
    ks, ws, _, _, state, _, _, turning, d1, d2 = head
    turned = (state, turning & False, turning & False, turning & False, d1, d2)
    if any_true(turning):
        turned = _turning_slip(ks, ws, e, hyp, mu, d1, d2, state, turning)
    return coulomb_tail(k, w, e, mu, hyp, head, turned)


@formula
def _approach(ws: Any, mu: Any) -> Any:
    """From the scaled ``w'``: ``(rough, approaching, rho, sliding)``, ``rho = |w'_t|``
    (recomputed by :func:`coulomb_tail` rather than kept: the compiled kernel stores the
    head of every impact between its passes)."""
    rough = mu > 0
    approaching = rough & (ws[0] < 0)
    rho = sqrt(ws[1] * ws[1] + ws[2] * ws[2])
    speed_s = sqrt(ws[0] * ws[0] + ws[1] * ws[1] + ws[2] * ws[2])
    return rough, approaching, rho, (approaching & (rho > NEAR_STOP * speed_s))


@formula
def coulomb_head(k: Any, w: Any, e: Any, mu: Any, hyp: Any) -> Any:
    """The part of :func:`coulomb` before a 3D slip whose direction turns: the scaled ``K``
    and ``w'`` (units ``|w'|`` and ``|w'| / K_nn``), the first slip phase when its direction
    is invariant (exact). Returns ``(ks, ws, unit_i, unit_v, state, stopped, jam, turning,
    d1, d2)``, ``turning`` the rows whose slip direction turns from ``d``."""
    speed = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    unit_i = select((speed > 0) & (k[0] > 0), speed / _positive(k[0]), 1.0)  # |w'| / K_nn
    unit_v = select(speed > 0, speed, 1.0)  # |w'|
    f = unit_i / unit_v
    ks = (k[0] * f, k[1] * f, k[2] * f, k[3] * f, k[4] * f, k[5] * f)
    ws = (w[0] / unit_v, w[1] / unit_v, w[2] / unit_v)
    rough, approaching, rho, sliding = _approach(ws, mu)
    d1 = ws[1] / _positive(rho)
    d2 = ws[2] / _positive(rho)
    zero = 0.0 * speed
    state = (zero, zero, zero, zero, zero, zero, zero, NAN + zero, NAN + zero, NAN + zero,
             select(approaching, zero, 1.0))  # fmt: skip
    # the first slip phase, along the initial direction: exact when it is invariant
    r1 = ks[1] - mu * (ks[3] * d1 + ks[4] * d2)
    r2 = ks[2] - mu * (ks[4] * d1 + ks[5] * d2)
    size_tn = sqrt(ks[1] * ks[1] + ks[2] * ks[2])
    invariant = abs(r1 * d2 - r2 * d1) <= 1e-13 * (size_tn + mu * ks[0])
    # Each stage below runs only where some row needs it (any_true: in the compiled build
    # the row's own flag, so a row pays only for its own stages; in the array build any row)
    never = approaching & False
    stopped, jam = never, never
    if any_true(sliding & invariant):
        state, stopped, jam = _linear_phase(ks, ws, e, hyp, -mu * d1, -mu * d2, d1, d2, True,
                                            state, sliding & invariant)  # fmt: skip
    turning = sliding & _not(invariant)
    return ks, ws, unit_i, unit_v, state, stopped, jam, turning, d1, d2


@formula
def coulomb_tail(k: Any, w: Any, e: Any, mu: Any, hyp: Any, head: Any, turned: Any) -> Any:
    """The part of :func:`coulomb` after a 3D slip whose direction turns: ``head`` from
    :func:`coulomb_head`, ``turned`` the 3D slip's ``(state, stopped, jammed, failed, dir1,
    dir2)`` (:func:`_turning_slip`; read on the rows that turn). At rest in the tangent
    plane: stick, or slip at once along the invariant direction; the regime, the works and
    the flags, scaled back."""
    ks, ws, unit_i, unit_v, state, stopped, jam, turning, d1, d2 = head
    state_3d, stop_3d, jam_3d, fail_3d, dir1, dir2 = turned
    state = _pick11(turning, state_3d, state)
    zero = 0.0 * unit_i
    rough, approaching, _, sliding = _approach(ws, mu)
    old1 = select(turning, dir1, d1)
    old2 = select(turning, dir2, d2)
    stopped = stopped | (turning & stop_3d)
    jam = jam | (turning & jam_3d)
    fail_3d = turning & fail_3d
    # at rest in the tangent plane (from the start, or after a stop): stick, or slip at once
    # along the invariant direction (which never stops again)
    size_tt = ks[3] * ks[5] - ks[4] * ks[4]
    ratio1 = -(ks[5] * ks[1] - ks[4] * ks[2]) / size_tt
    ratio2 = -(ks[3] * ks[2] - ks[4] * ks[1]) / size_tt
    sticks = sqrt(ratio1 * ratio1 + ratio2 * ratio2) <= mu * (1.0 + CONE_SLACK)
    at_rest = approaching & select(sliding, stopped, True)
    new1, new2 = old1, old2  # (read only where the contact slides off again)
    if any_true(at_rest & _not(sticks)):
        new1, new2 = _resumed_direction(ks, select(rough, mu, 1.0))
    if any_true(at_rest):
        state, _, jam_b = _linear_phase(
            ks, ws, e, hyp, select(sticks, ratio1, -mu * new1),
            select(sticks, ratio2, -mu * new2), new1, new2, _not(sticks), state,
            at_rest)  # fmt: skip
        jam = jam | jam_b
    p, q1, q2, wn, wt, wr, comp, pc, wc, wtc, done = state
    reversed_ = new1 * old1 + new2 * old2 < -1.0 + 1e-9
    regime = select(approaching, select(
        sliding,
        select(stopped, select(sticks, SLIP_STICK, select(reversed_, SLIP_REVERSAL + zero,
                                                          SLIP_REDIRECTED)), SLIP),
        select(sticks, STICK + zero, SLIP)), NONE)  # fmt: skip
    # not compressed (not approaching): no impulse, works 0 (carnot.laws.friction._finish)
    pc = select(comp > 0.5, pc, 0.0)
    wc = select(comp > 0.5, wc, 0.0)
    wtc = select(comp > 0.5, wtc, 0.0)
    bad = jam | fail_3d
    work = unit_v * unit_i
    p_n = select(bad, NAN, p * unit_i)
    p_1 = select(bad, NAN, q1 * unit_i)
    p_2 = select(bad, NAN, q2 * unit_i)
    normal_gain = wn > 1e-9 * (abs(wc) + 1e-300)
    law_gain = wn + wt > 1e-12 * (abs(wc) + abs(wt) + 1e-300)
    flags = (select(normal_gain, NORMAL_WORK_GAIN + zero, 0.0)
             + select(law_gain, HYPOTHESIS_ENERGY_GAIN + zero, 0.0)
             + select(jam, JAM + zero, 0.0) + select(fail_3d, STEP_LIMIT + zero, 0.0))  # fmt: skip
    free = frictionless(k, w, e, mu)
    return (select(rough, p_n, free[0]), select(rough, p_1, free[1]),
            select(rough, p_2, free[2]), select(rough, regime, FRICTIONLESS),
            select(rough, pc * unit_i, free[4]), select(rough, wc * work, free[5]),
            select(rough, (wn - wc) * work, free[6]), select(rough, wtc * work, free[7]),
            select(rough, (wt - wtc) * work, free[8]), select(rough, flags, 0))  # fmt: skip


@formula
def coulomb_newton(k: Any, w: Any, e: Any, mu: Any) -> Any:
    """Coulomb friction, Newton's kinematic restitution (``w_n'' = -e w_n'``)."""
    return coulomb(k, w, e, mu, NEWTON)


@formula
def coulomb_poisson(k: Any, w: Any, e: Any, mu: Any) -> Any:
    """Coulomb friction, Poisson's kinetic restitution (``p = (1 + e) p_c``)."""
    return coulomb(k, w, e, mu, POISSON)


@formula
def coulomb_stronge(k: Any, w: Any, e: Any, mu: Any) -> Any:
    """Coulomb friction, Stronge's energetic restitution (``W_nr = -e^2 W_nc``)."""
    return coulomb(k, w, e, mu, STRONGE)


# ------------------------------------------------------------ slip whose direction turns (3D)
#
# The loop of the 3D integration runs until no row is left: ``any_true`` is the one value it
# tests, a Python bool in both builds (Numba: the row's own flag; arrays: any row still
# running), so the compiled build pays nothing for rows that never turn, and the array build
# stops when its last row is done. Every pass is a masked update of every row.


def any_true(mask: Any) -> bool:
    """Whether any entry of ``mask`` is true (array build; Numba's build: the overload below,
    the identity on one impact's flag). A lazy array (Dask) would have to compute the whole
    batch at every pass of the loop: refused, with the backends that can do it."""
    if isinstance(mask, bool | np.bool_):
        return bool(mask)
    import array_api_compat

    # JAX counts as "lazy" (it may be traced), but its arrays outside jax.jit are concrete
    if array_api_compat.is_dask_array(mask):
        from carnot.errors import InputError

        raise InputError(
            "backend",
            "Coulomb friction with slip needs an eager array namespace (its 3D slip phases "
            "are integrated with adaptive steps): use backend='numba' or NumPy, JAX, "
            "array_api_strict arrays (Dask input, with backend='auto', is solved chunk by "
            "chunk by the compiled kernel)",
            type(mask).__name__,
        )
    return bool(array_api_compat.array_namespace(mask).any(mask))


try:
    from numba.extending import overload
except ImportError:  # pragma: no cover - numba is in the lock file
    pass
else:

    @overload(any_true)
    def _any_true_one_impact(mask: Any) -> Any:
        def impl(mask: Any) -> Any:
            return mask

        return impl


#: DOP853's step-size control (Hairer et al. II.4, II.10; as carnot.laws.slip3d).
#: (The error exponent, -1/8, is taken as three square roots: see :func:`slip_pass`.)
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
#: A slip phase that has not ended by ``dp = JAM_SPAN |w'| / K_nn`` never ends (jam).
JAM_SPAN = 1e6
#: Passes (step attempts and event-location iterations) one row may take: more is
#: ``STEP_LIMIT`` (the cases of the tests take at most a few hundred).
ATTEMPT_LIMIT = 20_000
#: Newton iterations of the event location (on the interpolant, then on the step map).
LOCATE_LIMIT = 60
#: The event location's last Newton correction, when at most this fraction of the step (and
#: the root already at round-off: see :func:`slip_pass`), is made by Euler's method (error ~
#: (POLISH h)^2 |y''| / 2: 1e-14 of the step's change).
POLISH = 1e-7
EPS = 2.220446049250313e-16


@formula
def _not(x: Any) -> Any:
    """``not x`` for a mask (one of ``select``'s values an array: array_api_strict wants one)."""
    return select(x, x & False, True)


@formula
def _larger(a: Any, b: Any) -> Any:
    return select(a > b, a, b)


@formula
def _smaller(a: Any, b: Any) -> Any:
    return select(a < b, a, b)


@formula
def _slip_rhs(y: Any, c: Any, wn0: Any) -> Any:
    """``f(y)`` for ``y = (r, s_1, s_2, dp, dP_1, dP_2, dW_n, dW_t)`` on the clock ``tau``,
    ``d tau = dp / |w_t|``, with ``w_t = r u``, ``r = |w_t|``, ``u = s / |s|`` (Stronge 2000
    eq. 5.7 in 3D, ``dw_t/dp = g = K_tn - mu K_tt u``, in polar form):

        dr/dtau = F r,  ds/dtau = g - F u  (F = u . g),  dp/dtau = r,
        dP_t/dtau = -mu u r,  dW_n/dtau = w_n r,  dW_t/dtau = -mu r^2

    ``c = (k_nn, k_n1, k_n2, k_11, k_12, k_22, mu)``, ``wn0`` the normal velocity at ``dp =
    0``. ``u = s (3 - |s|^2) / 2`` is ``s / |s|`` to second order in ``|s|^2 - 1`` (Newton's
    step for ``1 / |s|`` from 1: no square root, no division), and ``s . ds/dtau = (s . g)
    O((|s|^2 - 1)^2)``: ``|s|`` drifts only by the integration's error, ``|s|^2 - 1 ~ 1e-11``
    (the unnormalized ``g - (s . g) s`` would make ``|s|`` unstable where the slip
    decelerates, ``F < 0``: seen). ``r`` decays like ``exp(F tau)`` towards a stop: smooth,
    and its error is held relative (:func:`_slip_constants`). Polynomial: no ``exp`` or
    ``pow``, which would not vectorize (the compiled build runs 8 impacts per instruction)."""
    return _slip_field(y[0], y[1], y[2], wn0 + c[0] * y[3] + c[1] * y[4] + c[2] * y[5], c)


@formula
def _slip_field(r: Any, s1: Any, s2: Any, w_n: Any, c: Any) -> Any:
    """:func:`_slip_rhs` at ``|w_t| = r``, ``s = (s1, s2)`` and the normal velocity ``w_n``
    (what the field depends on: the impulses and works are quadratures)."""
    norm = 1.5 - 0.5 * (s1 * s1 + s2 * s2)
    u1 = s1 * norm
    u2 = s2 * norm
    mu = c[6]
    g1 = c[1] - mu * (c[3] * u1 + c[4] * u2)
    g2 = c[2] - mu * (c[4] * u1 + c[5] * u2)
    rate = u1 * g1 + u2 * g2
    return (rate * r, g1 - rate * u1, g2 - rate * u2, r, -mu * u1 * r, -mu * u2 * r,
            w_n * r, -mu * r * r)  # fmt: skip


@formula
def _event(y: Any, f: Any, c: Any, wn0: Any, near: Any, comp: Any, target: Any,
           hyp: Any) -> Any:  # fmt: skip
    """The first of the phase's events as one function that rises through 0 when either
    fires: ``G = max(g_near, g_end)`` (the near-stop ``near - |w_t|``, the end: maximum
    compression, or the hypothesis' end ``target``), its slope ``dG/dtau`` and which it is
    (``1`` near-stop, ``2`` end)."""
    g_near = near - y[0]
    s_near = -f[0]
    w_n = wn0 + c[0] * y[3] + c[1] * y[4] + c[2] * y[5]
    s_wn = c[0] * f[3] + c[1] * f[4] + c[2] * f[5]
    if hyp == POISSON:  # p = (1 + e) p_c
        g_t, s_t = y[3] - target, f[3]
    elif hyp == NEWTON:  # w_n = -e w'_n
        g_t, s_t = w_n - target, s_wn
    else:  # Stronge: the normal work since the leg began reaches W_r + e^2 W_c = 0
        g_t, s_t = y[6] - target, f[6]
    g_end = select(comp > 0.5, g_t, w_n)
    s_end = select(comp > 0.5, s_t, s_wn)
    is_end = g_end >= g_near
    return (select(is_end, g_end, g_near), select(is_end, s_end, s_near),
            select(is_end, 2.0 + 0.0 * near, 1.0))  # fmt: skip


@formula
def _settled(y: Any, f: Any, c: Any) -> Any:
    """Whether the slip direction has settled on an attracting invariant direction: with
    ``dtheta/dtau = G`` (``ds/dtau = G u_perp``, ``u_perp = (-u_2, u_1)``), ``dG/dtheta =
    -(F + mu u_perp . K_tt u_perp)``; where that is ``-kappa < 0`` the direction converges
    to the invariant one, and what it has left to turn is ``|G| / kappa``. Settled: at most
    ``RTOL`` rad; from there the phase is linear in ``p`` (the invariant slip of
    :func:`_linear_phase`, exact), and the integration would only creep at DOP853's
    stability limit (``kappa h ~ 6``) while ``|w_t|`` changes slowly (the stiff approach to a
    stop along an invariant direction: seen, 600 steps)."""
    inv = 1.0 / _positive(sqrt(y[1] * y[1] + y[2] * y[2]))
    u1 = y[1] * inv
    u2 = y[2] * inv
    kappa = (f[0] / _positive(y[0])
             + c[6] * (c[3] * u2 * u2 - 2.0 * c[4] * u1 * u2 + c[5] * u1 * u1))  # fmt: skip
    turn = sqrt(f[1] * f[1] + f[2] * f[2])
    return (kappa > 0) & (turn <= RTOL * kappa)


@formula
def _pick(mask: Any, a: Any, b: Any) -> Any:
    """``a`` where ``mask``, else ``b``, for the 8-tuples of the 3D integration."""
    return (select(mask, a[0], b[0]), select(mask, a[1], b[1]), select(mask, a[2], b[2]),
            select(mask, a[3], b[3]), select(mask, a[4], b[4]), select(mask, a[5], b[5]),
            select(mask, a[6], b[6]), select(mask, a[7], b[7]))  # fmt: skip


@formula
def _pick11(mask: Any, a: Any, b: Any) -> Any:
    """``a`` where ``mask``, else ``b``, for the 11-tuple ``state`` of an impact."""
    return _pick(mask, a[:8], b[:8]) + (select(mask, a[8], b[8]), select(mask, a[9], b[9]),
                                        select(mask, a[10], b[10]))  # fmt: skip


@formula
def _hermite(x: Any, h: Any, inv_h: Any, g0: Any, s0: Any, g1: Any, s1: Any) -> Any:
    """The cubic Hermite interpolant of ``G`` over a step of size ``h`` (``inv_h = 1 / h``;
    values ``g0``, ``g1`` and slopes ``s0``, ``s1`` at its ends) at the fraction ``x``, and
    its slope: ``(2x^3 - 3x^2 + 1) g0 + (x^3 - 2x^2 + x) h s0 + (3x^2 - 2x^3) g1 + (x^3 -
    x^2) h s1``."""
    value = (((2.0 * x - 3.0) * x * x + 1.0) * g0 + ((x - 2.0) * x + 1.0) * x * h * s0
             + (3.0 - 2.0 * x) * x * x * g1 + (x - 1.0) * x * x * h * s1)  # fmt: skip
    slope = (6.0 * (x - 1.0) * x * (g0 - g1) * inv_h
             + ((3.0 * x - 4.0) * x + 1.0) * s0 + (3.0 * x - 2.0) * x * s1)  # fmt: skip
    return value, slope


@formula
def _newton_bracketed(theta: Any, g: Any, slope: Any, lo: Any, hi: Any, tau: Any) -> Any:
    """One Newton step for a root of ``G`` (value ``g``, slope at ``theta``), safeguarded by
    the bracket ``[lo, hi]`` (``G(lo) < 0 <= G(hi)``), which it narrows: ``(next, lo, hi,
    newton, converged)``; the next point is bisection where Newton's leaves the bracket."""
    up = g >= 0
    hi = select(up, theta, hi)
    lo = select(up, lo, theta)
    newton = select(slope != 0, -g / select(slope != 0, slope, 1.0), INF)
    guess = theta + newton
    converged = ((g == 0) | (hi - lo <= 4.0 * EPS * (tau + hi))
                 | (abs(newton) <= 4.0 * EPS * (tau + theta)))  # fmt: skip
    return (select((lo < guess) & (guess < hi), guess, 0.5 * (lo + hi)), lo, hi, newton,
            converged)  # fmt: skip


@formula
def _hermite_root(h: Any, g0: Any, s0: Any, g1: Any, s1: Any, tau: Any) -> Any:
    """Where the event location starts, inside a step of size ``h`` over which ``G`` rose
    from ``g0 < 0`` to ``g1 >= 0``: the root of the cubic Hermite interpolant of ``G`` (its
    values and slopes at both ends: no field evaluation), by ``HERMITE_STEPS`` bracketed
    Newton steps from the secant's root. A fixed count, as the compiled build runs many
    impacts side by side in SIMD lanes, where a loop of its own length per lane would not
    vectorize; the start need only be close (the location is finished on the step map)."""
    lo = 0.0 * h
    hi = h
    theta = select(g1 > g0, h * (-g0) / select(g1 > g0, g1 - g0, 1.0), h)
    searching = g1 >= g0
    inv_h = 1.0 / _positive(h)
    for _ in range(HERMITE_STEPS):
        theta = _smaller(_larger(theta, lo), hi)
        g, slope = _hermite(theta * inv_h, h, inv_h, g0, s0, g1, s1)
        guess, lo, hi, _, converged = _newton_bracketed(theta, g, slope, lo, hi, tau)
        theta = select(searching, guess, theta)
        searching = searching & _not(converged)
    return _smaller(_larger(theta, lo), hi)


#: Bracketed Newton steps on the event's Hermite interpolant (:func:`_hermite_root`), from
#: the secant's root. Every pass pays for them (in SIMD lanes), the location's passes only
#: fall: per impact of the benchmark's 3D cases, 20.8 passes with none, 19.1 with 1, 18.5
#: with 2, 18.3 with 3 or 4.
HERMITE_STEPS = 2


@formula
def _slip_constants(consts: Any) -> Any:
    """What a 3D slip's every pass uses, from ``consts = (k, w0, e, mu, v_scale,
    imp_scale)`` (:func:`slip_start`): ``(c, near, span, tau_scale, atol)``, ``c`` the
    field's coefficients (:func:`_slip_rhs`), ``atol`` the absolute tolerances: ``|w_t|``
    relative (down to ``1e-3`` of the near-stop), the unit direction, the impulses and the
    works, each on its natural scale."""
    k, _, _, mu, v_scale, imp_scale = consts
    c = (k[0], k[1], k[2], k[3], k[4], k[5], mu)
    a_imp = RTOL * imp_scale
    a_work = RTOL * v_scale * imp_scale
    atol = (RTOL * 1e-3 * NEAR_STOP * v_scale, RTOL + 0.0 * mu, RTOL + 0.0 * mu, a_imp, a_imp,
            a_imp, a_work, a_work)  # fmt: skip
    return c, NEAR_STOP * v_scale, JAM_SPAN * imp_scale, imp_scale / v_scale, atol


@formula
def slip_start(k: Any, w0: Any, e: Any, hyp: Any, mu: Any, d1: Any, d2: Any, state: Any,
               active: Any) -> Any:  # fmt: skip
    """The start of a 3D slip whose direction turns (:func:`_turning_slip`), from ``state``
    along ``d`` on the ``active`` rows: ``(consts, carry)``, what :func:`slip_pass` reads
    and what it updates (DOP853's first step: Hairer et al. II.4, as SciPy's
    ``select_initial_step``, order 8).

    ``carry = (y, f0, (h, tau, tries, target, wn0), state, (running, rejected, locating,
    near_hit, settled, jammed, failed), (lo, hi, theta, count))``: the integrator's state and
    field, its step, clock, passes, the current leg's end and normal velocity at its start,
    the impact's totals, the flags, and the event location's bracket, point and passes."""
    w = _velocity(k, w0, state[0], state[1], state[2])
    v_scale = _positive(sqrt(w0[0] * w0[0] + w0[1] * w0[1] + w0[2] * w0[2]))
    imp_scale = v_scale / k[0]
    consts = (k, w0, e, mu, v_scale, imp_scale)
    c, _, _, tau_scale, atol = _slip_constants(consts)
    zero = 0.0 * d1
    r0 = _positive(sqrt(w[1] * w[1] + w[2] * w[2]))
    wn0 = w[0] + zero
    y = (r0 + zero, d1 + zero, d2 + zero, zero, zero, zero, zero, zero)
    f0 = _slip_rhs(y, c, wn0)
    n0 = zero
    n1 = zero
    for j in range(8):
        scale = atol[j] + RTOL * abs(y[j])
        n0 = n0 + (y[j] / scale) * (y[j] / scale)
        n1 = n1 + (f0[j] / scale) * (f0[j] / scale)
    n0 = sqrt(n0 / 8.0)
    n1 = sqrt(n1 / 8.0)
    h0 = select((n0 < 1e-5) | (n1 < 1e-5), 1e-6 * tau_scale, 0.01 * n0 / _positive(n1))
    y_try = (y[0] + h0 * f0[0], y[1] + h0 * f0[1], y[2] + h0 * f0[2], y[3] + h0 * f0[3],
             y[4] + h0 * f0[4], y[5] + h0 * f0[5], y[6] + h0 * f0[6],
             y[7] + h0 * f0[7])  # fmt: skip
    f_try = _slip_rhs(y_try, c, wn0)
    n2 = zero
    for j in range(8):
        scale = atol[j] + RTOL * abs(y[j])
        n2 = n2 + ((f_try[j] - f0[j]) / scale) * ((f_try[j] - f0[j]) / scale)
    n2 = sqrt(n2 / 8.0) / h0
    h1 = select((n1 <= 1e-15) & (n2 <= 1e-15), _larger(1e-6 * tau_scale, h0 * 1e-3),
                sqrt(sqrt(sqrt(0.01 / _positive(_larger(n1, n2))))))  # fmt: skip
    h = _smaller(100.0 * h0, h1)
    never = active & False
    flags = (active & (state[10] < 0.5), never, never, never, never, never, never)
    return consts, (y, f0, (h, zero, zero, zero, wn0), state, flags, (zero, zero, zero, zero))


@formula
def slip_pass(consts: Any, carry: Any, hyp: Any) -> Any:
    """One pass of a 3D slip (:func:`_turning_slip`): ``carry`` (:func:`slip_start`) after
    one DOP853 step on every running row. A row is either stepping (a trial step of size
    ``h``: refused, accepted, or, where an event fires inside it, the start of the event's
    location) or locating (a trial step to ``theta``, the current estimate of the event:
    the root of ``G`` on the step map, ``G(step(y, theta)) = 0``, so that the state there is
    a genuine DOP853 step, as carnot.laws.slip3d). The location is Newton's method (the
    slope from ``f`` at the trial step's end) safeguarded by the bracket ``[lo, hi]``,
    started from the root of the cubic Hermite interpolant of ``G`` (:func:`_hermite_root`):
    then two trial steps and an Euler correction usually finish, where regula falsi took
    four or five. (DOP853's 7th-order continuous extension gives a closer start, but its 15
    field evaluations cost more than the trial step they spare: measured.)

    Straight-line code, one step per row and pass whatever the row is doing: the compiled
    build runs it on many impacts side by side (vectorized), the array build on every row.
    A step that ends (an accepted plain step, or an event located) moves the clock; at an
    event the leg's increments go into the impact's totals and the next leg begins (after
    maximum compression: to the end the hypothesis sets), or the row stops running (the
    impact's end, the near-stop, the direction settled, a jam, the step budget spent)."""
    k, w0, e, mu, _, _ = consts
    c, near, span, tau_scale, atol = _slip_constants(consts)
    y, f0, step, state, flags, hunt = carry
    h, tau, tries, target, wn0 = step
    p, q1, q2, wn, wt, wr, comp, pc, wc, wtc, done = state
    running, rejected, locating, near_hit, settled, jammed, failed = flags
    lo, hi, theta, count = hunt
    zero = 0.0 * h
    tries = select(running, tries + 1.0, tries)
    stepping = running & _not(locating)
    hunting = running & locating
    jam_now = stepping & (y[3] >= span)
    fail_now = (running & (tries > ATTEMPT_LIMIT)) | (stepping & _not(jam_now) & (
        h <= 10.0 * EPS * _larger(tau, tau_scale)))  # fmt: skip
    theta = _smaller(_larger(theta, lo), hi)
    h_try = select(hunting, theta, select(stepping, h, zero))
    y_new, f_new, err = _dop853(y, f0, h_try, c, wn0, atol)
    g, slope, which = _event(y_new, f_new, c, wn0, near, comp, target, hyp)
    g0, s0, _ = _event(y, f0, c, wn0, near, comp, target, hyp)
    # stepping: the trial step refused, accepted plain, or fired (the location starts)
    live = stepping & _not(jam_now | fail_now)
    accepted = live & (err <= 1.0)
    refused = live & _not(err <= 1.0)
    fired = accepted & (g >= 0)
    plain = accepted & (g < 0)
    start = _hermite_root(h_try, g0, s0, g, slope, tau)
    # locating: a Newton step on the step map; a last correction this small is made by
    # Euler's method, sparing a trial step: when the state's error, newton^2 y''/2, is
    # below the tolerance (|newton| <= POLISH h), and the root's, newton^2 G''/(2 G'), is
    # round-off (what the next Newton step would have left; G'' from the slopes at both
    # ends of the trial step: a slope that is small beside the step's, near a double root
    # of G, keeps the iteration going)
    live_hunt = hunting & _not(fail_now)
    following, lo_next, hi_next, newton, converged = _newton_bracketed(
        h_try, g, slope, lo, hi, tau)  # fmt: skip
    curvature = abs(slope - s0) / _positive(h_try)
    euler = live_hunt & _not(converged) & (abs(newton) <= POLISH * h) & (
        curvature * newton * newton <= 8.0 * EPS * (tau + h_try) * abs(slope))  # fmt: skip
    count = select(live_hunt, count + 1.0, count)
    located = live_hunt & (converged | euler | (count >= LOCATE_LIMIT))
    polish = select(euler, newton, 0.0)  # (newton is inf where the slope is 0)
    y_eu = (y_new[0] + polish * f_new[0], y_new[1] + polish * f_new[1],
            y_new[2] + polish * f_new[2], y_new[3] + polish * f_new[3],
            y_new[4] + polish * f_new[4], y_new[5] + polish * f_new[5],
            y_new[6] + polish * f_new[6], y_new[7] + polish * f_new[7])  # fmt: skip
    # (the field there is not needed: a located event ends the leg, and the next leg's
    # field is evaluated below)
    y_new = _pick(euler, y_eu, y_new)
    h_end = h_try + polish
    lo = select(fired, zero, select(live_hunt, lo_next, lo))
    hi = select(fired, h_try, select(live_hunt, hi_next, hi))
    theta = select(fired, start, select(live_hunt, following, theta))
    count = select(fired, zero, count)
    locating = select(fired, True, select(located | fail_now, False, locating))
    # a step that ends: the clock moves
    moved = plain | located
    tau = select(moved, tau + h_end, tau)
    y = _pick(moved, y_new, y)
    f0 = _pick(moved, f_new, f0)
    is_end = located & (which == 2)
    is_near = located & _not(is_end)
    settle = plain & _settled(y, f0, c)
    growth = SAFETY / _positive(sqrt(sqrt(sqrt(_positive(err)))))  # err^(-1/8)
    factor = select(err == 0, MAX_FACTOR, _smaller(MAX_FACTOR, growth))
    shrink = select(err < INF, _larger(MIN_FACTOR, growth), MIN_FACTOR)
    h = select(plain, h_try * select(rejected, _smaller(factor, 1.0), factor),
               select(refused, h_try * shrink, h))  # fmt: skip
    rejected = select(refused, True, select(plain, False, rejected))
    # a leg ends (an end, the near-stop, or the direction settled): its increments go into
    # the impact's totals
    fold = is_end | is_near | settle
    p = select(fold, p + y[3], p)
    q1 = select(fold, q1 + y[4], q1)
    q2 = select(fold, q2 + y[5], q2)
    wn = select(fold, wn + y[6], wn)
    wt = select(fold, wt + y[7], wt)
    wr = select(fold & (comp > 0.5), wr + y[6], wr)
    mark = is_end & (comp < 0.5)
    finish = is_end & (comp > 0.5)
    comp = select(mark, 1.0, comp)
    pc = select(mark, p, pc)
    wc = select(mark, wn, wc)
    wtc = select(mark, wt, wtc)
    done = select(finish | (mark & (e == 0)), 1.0, done)
    y = (y[0], y[1], y[2], select(fold, zero, y[3]), select(fold, zero, y[4]),
         select(fold, zero, y[5]), select(fold, zero, y[6]), select(fold, zero, y[7]))
    # the next leg (after maximum compression): to the end the hypothesis sets
    leg = mark & (e > 0)
    w_now = _velocity(k, w0, p, q1, q2)
    if hyp == POISSON:
        target = select(leg, (1.0 + e) * pc - p, target)
    elif hyp == NEWTON:
        target = select(leg, -e * w0[0], target)
    else:
        target = select(leg, -(wr + e * e * wc), target)
    wn0 = select(leg, w_now[0], wn0)
    f0 = _pick(leg, _slip_rhs(y, c, wn0), f0)
    running = running & _not(jam_now | fail_now | is_near | settle | finish
                             | (mark & (e == 0)))  # fmt: skip
    flags = (running, rejected, locating, near_hit | is_near, settled | settle,
             jammed | jam_now, failed | fail_now)  # fmt: skip
    return (y, f0, (h, tau, tries, target, wn0), (p, q1, q2, wn, wt, wr, comp, pc, wc, wtc,
                                                  done), flags, (lo, hi, theta, count))  # fmt: skip


@formula
def slip_end(consts: Any, carry: Any, hyp: Any) -> Any:
    """The end of a 3D slip (:func:`_turning_slip`), once no row runs: the last ``NEAR_STOP
    |w'|`` of a stop, in closed form along the slip's direction when it is still
    decelerating, else the slip counts as stopped (carnot.laws.friction); a settled
    direction: the rest of the phase, in closed form along it. Returns ``(state, stopped,
    jammed, failed, dir1, dir2)``."""
    k, w0, e, mu, _, _ = consts
    y, _, _, state, flags, _ = carry
    _, _, _, near_hit, settled, jammed, failed = flags
    size = _positive(sqrt(y[1] * y[1] + y[2] * y[2]))
    here1 = y[1] / size
    here2 = y[2] / size
    approach = ((k[1] - mu * (k[3] * here1 + k[4] * here2)) * here1
                + (k[2] - mu * (k[4] * here1 + k[5] * here2)) * here2)  # fmt: skip
    finishing = (near_hit & (approach < 0)) | settled
    state, stop_lin, jam_lin = _linear_phase(k, w0, e, hyp, -mu * here1, -mu * here2, here1,
                                             here2, True, state, finishing)  # fmt: skip
    stopped = (near_hit & _not(finishing)) | stop_lin
    return state, stopped, jammed | jam_lin, failed, here1, here2


@formula
def _turning_slip(k: Any, w0: Any, e: Any, hyp: Any, mu: Any, d1: Any, d2: Any, state: Any,
                  active: Any) -> Any:  # fmt: skip
    """Slip whose direction turns, from ``state`` along ``d`` on the ``active`` rows, to its
    stop or the end of the impact (carnot.laws.friction._integrated_slip): DOP853 with
    adaptive steps on the polar form of :func:`_slip_rhs`, the first event inside an
    accepted step located on the step map, the phase's two legs (to maximum compression,
    then to the hypothesis' end), and the last ``NEAR_STOP |w'|`` of a stop, or the rest of
    a phase whose direction has settled (:func:`_settled`), finished in closed form along
    the slip's direction: :func:`slip_start`, :func:`slip_pass` until no row runs,
    :func:`slip_end`. Returns ``(state, stopped, jammed, failed, dir1, dir2)``, ``dir`` the
    slip direction at the end.

    Why the polar form on the clock ``tau = int dp / |w_t|`` (and not ``w_t`` on the clock
    ``p``, as carnot.laws.slip3d): near a stop the slip direction turns like ``1/|w_t|`` in
    ``p``, and ``w_t`` decays to 0 like ``(p* - p)^(1 + beta)`` (``beta`` not an integer), so
    a step of a high-order method can only be a fraction of the distance to the stop: ~120
    accepted and ~60 refused steps to go from ``|w'|`` to ``NEAR_STOP |w'|``. In ``tau`` the
    direction converges exponentially to the invariant direction of approach and ``|w_t|``
    decays exponentially: smooth, and the steps grow as the direction settles. Away from
    stops the two clocks are alike (``|w_t| ~ |w'|``)."""
    consts, carry = slip_start(k, w0, e, hyp, mu, d1, d2, state, active)
    while any_true(carry[4][0]):
        carry = slip_pass(consts, carry, hyp)
    return slip_end(consts, carry, hyp)


# DOP853 (Hairer, Norsett and Wanner II.10; SciPy's coefficients, as carnot.laws.slip3d)
# (the nodes _C* are kept with the tableau: the polar field is autonomous, no stage needs them)
_C1 = 0.05260015195876773
_A1_0 = 0.05260015195876773
_C2 = 0.0789002279381516
_A2_0 = 0.0197250569845379
_A2_1 = 0.0591751709536137
_C3 = 0.1183503419072274
_A3_0 = 0.02958758547680685
_A3_2 = 0.08876275643042054
_C4 = 0.2816496580927726
_A4_0 = 0.2413651341592667
_A4_2 = -0.8845494793282861
_A4_3 = 0.924834003261792
_C5 = 0.3333333333333333
_A5_0 = 0.037037037037037035
_A5_3 = 0.17082860872947386
_A5_4 = 0.12546768756682242
_C6 = 0.25
_A6_0 = 0.037109375
_A6_3 = 0.17025221101954405
_A6_4 = 0.06021653898045596
_A6_5 = -0.017578125
_C7 = 0.3076923076923077
_A7_0 = 0.03709200011850479
_A7_3 = 0.17038392571223998
_A7_4 = 0.10726203044637328
_A7_5 = -0.015319437748624402
_A7_6 = 0.008273789163814023
_C8 = 0.6512820512820513
_A8_0 = 0.6241109587160757
_A8_3 = -3.3608926294469414
_A8_4 = -0.868219346841726
_A8_5 = 27.59209969944671
_A8_6 = 20.154067550477894
_A8_7 = -43.48988418106996
_C9 = 0.6
_A9_0 = 0.47766253643826434
_A9_3 = -2.4881146199716677
_A9_4 = -0.590290826836843
_A9_5 = 21.230051448181193
_A9_6 = 15.279233632882423
_A9_7 = -33.28821096898486
_A9_8 = -0.020331201708508627
_C10 = 0.8571428571428571
_A10_0 = -0.9371424300859873
_A10_3 = 5.186372428844064
_A10_4 = 1.0914373489967295
_A10_5 = -8.149787010746927
_A10_6 = -18.52006565999696
_A10_7 = 22.739487099350505
_A10_8 = 2.4936055526796523
_A10_9 = -3.0467644718982196
_C11 = 1.0
_A11_0 = 2.273310147516538
_A11_3 = -10.53449546673725
_A11_4 = -2.0008720582248625
_A11_5 = -17.9589318631188
_A11_6 = 27.94888452941996
_A11_7 = -2.8589982771350235
_A11_8 = -8.87285693353063
_A11_9 = 12.360567175794303
_A11_10 = 0.6433927460157636
_B0 = 0.054293734116568765
_B5 = 4.450312892752409
_B6 = 1.8915178993145003
_B7 = -5.801203960010585
_B8 = 0.3111643669578199
_B9 = -0.1521609496625161
_B10 = 0.20136540080403034
_B11 = 0.04471061572777259
_E5_0 = 0.01312004499419488
_E5_5 = -1.2251564463762044
_E5_6 = -0.4957589496572502
_E5_7 = 1.6643771824549864
_E5_8 = -0.35032884874997366
_E5_9 = 0.3341791187130175
_E5_10 = 0.08192320648511571
_E5_11 = -0.022355307863886294
_E3_0 = -0.18980075407240762
_E3_5 = 4.450312892752409
_E3_6 = 1.8915178993145003
_E3_7 = -5.801203960010585
_E3_8 = -0.4226823213237919
_E3_9 = -0.1521609496625161
_E3_10 = 0.20136540080403034
_E3_11 = 0.02265179219836082
#: E3 - B: nonzero in three stages only (SciPy's E3 is B - BHH), so that the 3rd-order error
#: estimate reuses the step's weighted sum.
_D3_0, _D3_8, _D3_11 = _E3_0 - _B0, _E3_8 - _B8, _E3_11 - _B11
assert all(_E3 == _B for _E3, _B in ((_E3_5, _B5), (_E3_6, _B6), (_E3_7, _B7), (_E3_9, _B9),
                                     (_E3_10, _B10)))  # fmt: skip


@formula
def _dop853(y: Any, f0: Any, h: Any, c: Any, wn0: Any, atol: Any) -> Any:
    """One DOP853 step of size ``h`` from ``y`` (the field is autonomous: the clock is not an
    argument), ``f0 = f(y)``, the coefficients of carnot.laws.slip3d written out, zeros left
    out (generated): ``(y_new, f(y_new), err)``, ``err`` the error norm of SciPy's
    ``DOP853._estimate_error_norm`` (accept when <= 1)."""
    k0 = f0
    # the normal velocity w_n = wn0 + c_0 y_3 + c_1 y_4 + c_2 y_5 carried through the
    # stages as one quantity (its rate c . k[3:6]), not as the impulses it is made of
    wn = wn0 + c[0] * y[3] + c[1] * y[4] + c[2] * y[5]
    v0 = c[0] * k0[3] + c[1] * k0[4] + c[2] * k0[5]
    k1 = _slip_field(
        y[0] + h * (_A1_0 * k0[0]),
        y[1] + h * (_A1_0 * k0[1]),
        y[2] + h * (_A1_0 * k0[2]),
        wn + h * (_A1_0 * v0),
        c)  # fmt: skip
    v1 = c[0] * k1[3] + c[1] * k1[4] + c[2] * k1[5]
    k2 = _slip_field(
        y[0] + h * (_A2_0 * k0[0] + _A2_1 * k1[0]),
        y[1] + h * (_A2_0 * k0[1] + _A2_1 * k1[1]),
        y[2] + h * (_A2_0 * k0[2] + _A2_1 * k1[2]),
        wn + h * (_A2_0 * v0 + _A2_1 * v1),
        c)  # fmt: skip
    v2 = c[0] * k2[3] + c[1] * k2[4] + c[2] * k2[5]
    k3 = _slip_field(
        y[0] + h * (_A3_0 * k0[0] + _A3_2 * k2[0]),
        y[1] + h * (_A3_0 * k0[1] + _A3_2 * k2[1]),
        y[2] + h * (_A3_0 * k0[2] + _A3_2 * k2[2]),
        wn + h * (_A3_0 * v0 + _A3_2 * v2),
        c)  # fmt: skip
    v3 = c[0] * k3[3] + c[1] * k3[4] + c[2] * k3[5]
    k4 = _slip_field(
        y[0] + h * (_A4_0 * k0[0] + _A4_2 * k2[0] + _A4_3 * k3[0]),
        y[1] + h * (_A4_0 * k0[1] + _A4_2 * k2[1] + _A4_3 * k3[1]),
        y[2] + h * (_A4_0 * k0[2] + _A4_2 * k2[2] + _A4_3 * k3[2]),
        wn + h * (_A4_0 * v0 + _A4_2 * v2 + _A4_3 * v3),
        c)  # fmt: skip
    v4 = c[0] * k4[3] + c[1] * k4[4] + c[2] * k4[5]
    k5 = _slip_field(
        y[0] + h * (_A5_0 * k0[0] + _A5_3 * k3[0] + _A5_4 * k4[0]),
        y[1] + h * (_A5_0 * k0[1] + _A5_3 * k3[1] + _A5_4 * k4[1]),
        y[2] + h * (_A5_0 * k0[2] + _A5_3 * k3[2] + _A5_4 * k4[2]),
        wn + h * (_A5_0 * v0 + _A5_3 * v3 + _A5_4 * v4),
        c)  # fmt: skip
    v5 = c[0] * k5[3] + c[1] * k5[4] + c[2] * k5[5]
    k6 = _slip_field(
        y[0] + h * (_A6_0 * k0[0] + _A6_3 * k3[0] + _A6_4 * k4[0] + _A6_5 * k5[0]),
        y[1] + h * (_A6_0 * k0[1] + _A6_3 * k3[1] + _A6_4 * k4[1] + _A6_5 * k5[1]),
        y[2] + h * (_A6_0 * k0[2] + _A6_3 * k3[2] + _A6_4 * k4[2] + _A6_5 * k5[2]),
        wn + h * (_A6_0 * v0 + _A6_3 * v3 + _A6_4 * v4 + _A6_5 * v5),
        c)  # fmt: skip
    v6 = c[0] * k6[3] + c[1] * k6[4] + c[2] * k6[5]
    k7 = _slip_field(
        y[0] + h * (_A7_0 * k0[0] + _A7_3 * k3[0] + _A7_4 * k4[0] + _A7_5 * k5[0] + _A7_6 * k6[0]),
        y[1] + h * (_A7_0 * k0[1] + _A7_3 * k3[1] + _A7_4 * k4[1] + _A7_5 * k5[1] + _A7_6 * k6[1]),
        y[2] + h * (_A7_0 * k0[2] + _A7_3 * k3[2] + _A7_4 * k4[2] + _A7_5 * k5[2] + _A7_6 * k6[2]),
        wn + h * (_A7_0 * v0 + _A7_3 * v3 + _A7_4 * v4 + _A7_5 * v5 + _A7_6 * v6),
        c)  # fmt: skip
    v7 = c[0] * k7[3] + c[1] * k7[4] + c[2] * k7[5]
    k8 = _slip_field(
        y[0] + h * (_A8_0 * k0[0] + _A8_3 * k3[0] + _A8_4 * k4[0] + _A8_5 * k5[0] + _A8_6 * k6[0] +
            _A8_7 * k7[0]),
        y[1] + h * (_A8_0 * k0[1] + _A8_3 * k3[1] + _A8_4 * k4[1] + _A8_5 * k5[1] + _A8_6 * k6[1] +
            _A8_7 * k7[1]),
        y[2] + h * (_A8_0 * k0[2] + _A8_3 * k3[2] + _A8_4 * k4[2] + _A8_5 * k5[2] + _A8_6 * k6[2] +
            _A8_7 * k7[2]),
        wn + h * (_A8_0 * v0 + _A8_3 * v3 + _A8_4 * v4 + _A8_5 * v5 + _A8_6 * v6 + _A8_7 * v7),
        c)  # fmt: skip
    v8 = c[0] * k8[3] + c[1] * k8[4] + c[2] * k8[5]
    k9 = _slip_field(
        y[0] + h * (_A9_0 * k0[0] + _A9_3 * k3[0] + _A9_4 * k4[0] + _A9_5 * k5[0] + _A9_6 * k6[0] +
            _A9_7 * k7[0] + _A9_8 * k8[0]),
        y[1] + h * (_A9_0 * k0[1] + _A9_3 * k3[1] + _A9_4 * k4[1] + _A9_5 * k5[1] + _A9_6 * k6[1] +
            _A9_7 * k7[1] + _A9_8 * k8[1]),
        y[2] + h * (_A9_0 * k0[2] + _A9_3 * k3[2] + _A9_4 * k4[2] + _A9_5 * k5[2] + _A9_6 * k6[2] +
            _A9_7 * k7[2] + _A9_8 * k8[2]),
        wn + h * (_A9_0 * v0 + _A9_3 * v3 + _A9_4 * v4 + _A9_5 * v5 + _A9_6 * v6 + _A9_7 * v7 +
            _A9_8 * v8),
        c)  # fmt: skip
    v9 = c[0] * k9[3] + c[1] * k9[4] + c[2] * k9[5]
    k10 = _slip_field(
        y[0] + h * (_A10_0 * k0[0] + _A10_3 * k3[0] + _A10_4 * k4[0] + _A10_5 * k5[0] +
            _A10_6 * k6[0] + _A10_7 * k7[0] + _A10_8 * k8[0] + _A10_9 * k9[0]),
        y[1] + h * (_A10_0 * k0[1] + _A10_3 * k3[1] + _A10_4 * k4[1] + _A10_5 * k5[1] +
            _A10_6 * k6[1] + _A10_7 * k7[1] + _A10_8 * k8[1] + _A10_9 * k9[1]),
        y[2] + h * (_A10_0 * k0[2] + _A10_3 * k3[2] + _A10_4 * k4[2] + _A10_5 * k5[2] +
            _A10_6 * k6[2] + _A10_7 * k7[2] + _A10_8 * k8[2] + _A10_9 * k9[2]),
        wn + h * (_A10_0 * v0 + _A10_3 * v3 + _A10_4 * v4 + _A10_5 * v5 + _A10_6 * v6 +
            _A10_7 * v7 + _A10_8 * v8 + _A10_9 * v9),
        c)  # fmt: skip
    v10 = c[0] * k10[3] + c[1] * k10[4] + c[2] * k10[5]
    k11 = _slip_field(
        y[0] + h * (_A11_0 * k0[0] + _A11_3 * k3[0] + _A11_4 * k4[0] + _A11_5 * k5[0] +
            _A11_6 * k6[0] + _A11_7 * k7[0] + _A11_8 * k8[0] + _A11_9 * k9[0] + _A11_10 * k10[0]),
        y[1] + h * (_A11_0 * k0[1] + _A11_3 * k3[1] + _A11_4 * k4[1] + _A11_5 * k5[1] +
            _A11_6 * k6[1] + _A11_7 * k7[1] + _A11_8 * k8[1] + _A11_9 * k9[1] + _A11_10 * k10[1]),
        y[2] + h * (_A11_0 * k0[2] + _A11_3 * k3[2] + _A11_4 * k4[2] + _A11_5 * k5[2] +
            _A11_6 * k6[2] + _A11_7 * k7[2] + _A11_8 * k8[2] + _A11_9 * k9[2] + _A11_10 * k10[2]),
        wn + h * (_A11_0 * v0 + _A11_3 * v3 + _A11_4 * v4 + _A11_5 * v5 + _A11_6 * v6 +
            _A11_7 * v7 + _A11_8 * v8 + _A11_9 * v9 + _A11_10 * v10),
        c)  # fmt: skip
    # the weighted sum of the stages, per component: y_new = y + h sb (and the 3rd-order
    # error estimate below is sb plus three terms: E3 = B - BHH)
    sb = (
        _B0 * k0[0] + _B5 * k5[0] + _B6 * k6[0] + _B7 * k7[0] + _B8 * k8[0] + _B9 * k9[0] +
            _B10 * k10[0] + _B11 * k11[0],
        _B0 * k0[1] + _B5 * k5[1] + _B6 * k6[1] + _B7 * k7[1] + _B8 * k8[1] + _B9 * k9[1] +
            _B10 * k10[1] + _B11 * k11[1],
        _B0 * k0[2] + _B5 * k5[2] + _B6 * k6[2] + _B7 * k7[2] + _B8 * k8[2] + _B9 * k9[2] +
            _B10 * k10[2] + _B11 * k11[2],
        _B0 * k0[3] + _B5 * k5[3] + _B6 * k6[3] + _B7 * k7[3] + _B8 * k8[3] + _B9 * k9[3] +
            _B10 * k10[3] + _B11 * k11[3],
        _B0 * k0[4] + _B5 * k5[4] + _B6 * k6[4] + _B7 * k7[4] + _B8 * k8[4] + _B9 * k9[4] +
            _B10 * k10[4] + _B11 * k11[4],
        _B0 * k0[5] + _B5 * k5[5] + _B6 * k6[5] + _B7 * k7[5] + _B8 * k8[5] + _B9 * k9[5] +
            _B10 * k10[5] + _B11 * k11[5],
        _B0 * k0[6] + _B5 * k5[6] + _B6 * k6[6] + _B7 * k7[6] + _B8 * k8[6] + _B9 * k9[6] +
            _B10 * k10[6] + _B11 * k11[6],
        _B0 * k0[7] + _B5 * k5[7] + _B6 * k6[7] + _B7 * k7[7] + _B8 * k8[7] + _B9 * k9[7] +
            _B10 * k10[7] + _B11 * k11[7],
    )  # fmt: skip
    y_new = (y[0] + h * sb[0], y[1] + h * sb[1], y[2] + h * sb[2], y[3] + h * sb[3],
             y[4] + h * sb[4], y[5] + h * sb[5], y[6] + h * sb[6], y[7] + h * sb[7])
    f_new = _slip_rhs(y_new, c, wn0)
    err5 = 0.0 * h
    err3 = 0.0 * h
    for j in range(8):  # DOP853's two error estimates, scaled per component
        # one division per component (the compiled build's vector divisions are slow)
        inv_scale = 1.0 / (atol[j] + RTOL * _larger(abs(y[j]), abs(y_new[j])))
        e5 = (_E5_0 * k0[j] + _E5_5 * k5[j] + _E5_6 * k6[j] + _E5_7 * k7[j] + _E5_8 * k8[j] +
            _E5_9 * k9[j] + _E5_10 * k10[j] + _E5_11 * k11[j]) * inv_scale  # fmt: skip
        e3 = (sb[j] + _D3_0 * k0[j] + _D3_8 * k8[j] + _D3_11 * k11[j]) * inv_scale
        err5 = err5 + e5 * e5
        err3 = err3 + e3 * e3
    both = err5 + 0.01 * err3
    err = select(both > 0, abs(h) * err5 / sqrt(_positive(both) * 8.0), 0.0)
    return y_new, f_new, err

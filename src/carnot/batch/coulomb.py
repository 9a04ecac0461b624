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
* a slip direction that turns (3D) is integrated by the DOP853 of :func:`_slip_3d` (the method
  and tolerances of :mod:`carnot.laws.slip3d`), its events located on the step map, the last
  ``NEAR_STOP |w'|`` of a stop finished in closed form;
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

#: The hypotheses, as the constant argument of :func:`coulomb`.
NEWTON, POISSON, STRONGE = 0, 1, 2

#: As carnot.laws.friction: slip slower than this fraction of |w'| counts as none (and a 3D
#: slip that slows to it is finished in closed form); the relative slack of the cone test.
NEAR_STOP = 1e-9
CONE_SLACK = 1e-12
#: Relative tolerance of the 3D integration (carnot.laws.friction.RTOL).
RTOL = 1e-12
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
    first_stop = select(first_comp | first_end, False, True)
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
    ok = go & select(jammed, False, True)
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
    state, stop_b, jam_b = _segment(k, w0, e, hyp, rate1, rate2, d1, d2, has_dir, state,
                                    active & select(stop_a | jam_a, False, True))  # fmt: skip
    return state, stop_a | stop_b, jam_a | jam_b


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
        # d(1/|s|)/dlambda = s . A^-1 s / |s|^3
        slope = _positive((s1 * t1 + s2 * t2) / (size * size * size))
        lam = lam - (1.0 / size - 1.0) / slope
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
    docstring)."""
    speed = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    unit_i = select((speed > 0) & (k[0] > 0), speed / _positive(k[0]), 1.0)  # |w'| / K_nn
    unit_v = select(speed > 0, speed, 1.0)  # |w'|
    f = unit_i / unit_v
    ks = (k[0] * f, k[1] * f, k[2] * f, k[3] * f, k[4] * f, k[5] * f)
    ws = (w[0] / unit_v, w[1] / unit_v, w[2] / unit_v)
    speed_s = sqrt(ws[0] * ws[0] + ws[1] * ws[1] + ws[2] * ws[2])
    rough = mu > 0
    approaching = rough & (ws[0] < 0)
    rho = sqrt(ws[1] * ws[1] + ws[2] * ws[2])
    sliding = approaching & (rho > NEAR_STOP * speed_s)
    d1 = ws[1] / _positive(rho)
    d2 = ws[2] / _positive(rho)
    zero = 0.0 * speed
    state = (zero, zero, zero, zero, zero, zero, zero, NAN + zero, NAN + zero, NAN + zero,
             select(approaching, 0.0, 1.0))  # fmt: skip
    # the first slip phase, along the initial direction: exact when it is invariant
    r1 = ks[1] - mu * (ks[3] * d1 + ks[4] * d2)
    r2 = ks[2] - mu * (ks[4] * d1 + ks[5] * d2)
    size_tn = sqrt(ks[1] * ks[1] + ks[2] * ks[2])
    invariant = abs(r1 * d2 - r2 * d1) <= 1e-13 * (size_tn + mu * ks[0])
    state, stopped, jam = _linear_phase(ks, ws, e, hyp, -mu * d1, -mu * d2, d1, d2, True,
                                        state, sliding & invariant)  # fmt: skip
    old1, old2 = d1, d2
    turning = sliding & select(invariant, False, True)
    state, stop_3d, jam_3d, fail_3d, old1, old2 = _turning_slip(
        ks, ws, e, hyp, mu, d1, d2, state, turning, old1, old2)
    stopped = stopped | stop_3d
    jam = jam | jam_3d
    # at rest in the tangent plane (from the start, or after a stop): stick, or slip at once
    # along the invariant direction (which never stops again)
    size_tt = ks[3] * ks[5] - ks[4] * ks[4]
    ratio1 = -(ks[5] * ks[1] - ks[4] * ks[2]) / size_tt
    ratio2 = -(ks[3] * ks[2] - ks[4] * ks[1]) / size_tt
    sticks = sqrt(ratio1 * ratio1 + ratio2 * ratio2) <= mu * (1.0 + CONE_SLACK)
    new1, new2 = _resumed_direction(ks, select(rough, mu, 1.0))
    at_rest = approaching & select(sliding, stopped, True)
    state, _, jam_b = _linear_phase(
        ks, ws, e, hyp, select(sticks, ratio1, -mu * new1), select(sticks, ratio2, -mu * new2),
        new1, new2, select(sticks, False, True), state, at_rest)  # fmt: skip
    jam = jam | jam_b
    p, q1, q2, wn, wt, wr, comp, pc, wc, wtc, done = state
    reversed_ = new1 * old1 + new2 * old2 < -1.0 + 1e-9
    regime = select(approaching, select(
        sliding,
        select(stopped, select(sticks, SLIP_STICK, select(reversed_, SLIP_REVERSAL,
                                                          SLIP_REDIRECTED)), SLIP),
        select(sticks, STICK, SLIP)), NONE)  # fmt: skip
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
    flags = (select(normal_gain, NORMAL_WORK_GAIN, 0) + select(law_gain, HYPOTHESIS_ENERGY_GAIN, 0)
             + select(jam, JAM, 0) + select(fail_3d, STEP_LIMIT, 0))  # fmt: skip
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


@formula
def _turning_slip(k: Any, w0: Any, e: Any, hyp: Any, mu: Any, d1: Any, d2: Any, state: Any,
                  active: Any, old1: Any, old2: Any) -> Any:  # fmt: skip
    """Placeholder until the 3D integration: rows whose slip turns fail (``STEP_LIMIT``)."""
    zero = 0.0 * d1
    return state, active & False, active & False, active | (zero > 0), old1, old2


_ = np  # numpy is used by the 3D integration

"""A compiled integrator of 3D Coulomb slip whose direction turns, for one impact in scalars.

The slip phase of ``carnot.laws.friction`` in the contact frame ``(n, t1, t2)``: with
``P = (p, P_1, P_2)`` the impulse received so far and ``w = w' + K P`` the relative velocity
(``K`` symmetric positive definite, 1/kg), Coulomb's law ``dP_t = -mu s dp``,
``s = w_t / |w_t|``, gives, with the normal impulse ``p`` as the clock (Stronge, *Impact
Mechanics*, 2000, eq. 5.7 in 3D):

    dw_t/dp = K_tn - mu K_tt s,        dP_t/dp = -mu s,
    dW_n/dp = w_n = w_n0 + k_nn dp + k_n1 dP_1 + k_n2 dP_2,        dW_t/dp = -mu |w_t|

integrated by Dormand and Prince's explicit Runge-Kutta 8(5,3) (DOP853: Hairer, Norsett and
Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer 1993, II.10; the
coefficients and the error estimate as in SciPy's ``solve_ivp(method="DOP853")``), with
adaptive steps and events located on the step map itself: an event inside an accepted step is
the root ``theta`` of ``g(step(y0, theta))``, found by safeguarded Newton iteration (the slope
from the last stage, which is ``f`` at the end of the step), so the state at an event is a
genuine DOP853 step, as accurate as any other.

``w_t`` is a state of its own (not ``w' + K P`` recomputed): near a stop that sum cancels to
round-off of the size of ``|w'|``, while integrated its error stays relative to ``|w_t|``. The
field is continued through ``w_t = 0`` along the direction of approach: ``s = sign(w_t .
s_seg) w_t / |w_t|`` with ``s_seg`` a reference slip direction (renewed after each turn by
``SEGMENT_TURN``), so that a stop is a sign change of the smooth ``w_t . s_seg`` and not the
kink of ``|w_t|``.

API contract (:func:`slip_phase`): plain floats and one scratch array in, a tuple of scalars
out; no Python objects inside, so that a batch kernel can call it per impact in a
``numba.prange`` loop (``nogil``). Everything is relative to the start of the phase: the
increments ``dp``, ``dP_t``, ``dW_n``, ``dW_t`` start at 0 (the caller adds its totals; kept
apart because a target such as Stronge's remaining work is small beside the totals). Units are
any consistent set (the module's tolerances scale with ``v_scale`` and ``k_nn``).

Inputs: ``k_nn, k_n1, k_n2, k_11, k_12, k_22`` the unique entries of ``K``; ``mu > 0``;
``w_n, w_1, w_2`` the relative velocity at the start; ``s_1, s_2`` the unit slip direction at
the start (``w_t / |w_t|``, or the direction slip leaves in when ``w_t`` is round-off);
``end_kind`` and ``end_target`` the condition that ends the phase besides the slip stopping:

* ``END_COMPRESSION`` (0): ``w_n`` rises to 0 (``end_target`` unused);
* ``END_VELOCITY`` (1): ``w_n`` rises to ``end_target`` (Newton: ``-e w'_n``);
* ``END_IMPULSE`` (2): ``dp`` reaches ``end_target`` (Poisson: ``(1 + e) p_c - p``);
* ``END_WORK`` (3): ``dW_n`` rises to ``end_target`` (Stronge: ``-(W_r + e^2 W_c)``);

``near`` the slip speed at which the phase ends with ``NEAR_STOP`` (the caller finishes the
stop in closed form: near a stop the direction field turns like ``1/|w_t|``); ``v_scale`` the
speed scale of the impact (``|w'|``): the absolute tolerances are ``rtol`` times ``1e-3 near``
for ``w_t``, ``v_scale / k_nn`` for ``P_t`` and ``v_scale^2 / k_nn`` for the works, and slip
slower than ``1e-6 v_scale`` no longer updates the direction of approach; ``rtol`` the
relative tolerance; ``max_step`` the largest step in ``p`` (``inf``: none; smaller for plots);
``path`` a float array ``(rows, 6)`` that receives ``(dp, w_n, w_1, w_2, dW_n, dW_t)`` after
every accepted step and at the event (rows beyond its length are counted, not written: pass
``(0, 6)`` for none); ``settle`` whether to end with ``SETTLED`` once the slip direction has
settled on an attracting invariant direction (off: integrate on to the event, as reference
runs and the kernel's tests do).

Output: ``(code, dp, w_n, w_1, w_2, dP_1, dP_2, dW_n, dW_t, seg_1, seg_2, dir_1, dir_2, turn,
steps, evaluations, rows)``: the event's code, the state there, ``seg`` the reference
direction of the stop's sign change at the end, ``dir`` the direction of approach
(the last one with slip faster than ``1e-6 v_scale``), ``turn`` the angle it swept (rad, summed
step by step), the accepted steps, the right-hand-side evaluations and the rows of ``path``
needed. Codes: ``NEAR_STOP`` (``|w_t|`` fell to ``near``; also when a step jumped through
``w_t = 0``, seen as a sign change of ``w_t . seg``: the near-stop is then located before it;
a sign change with faster slip is a turn through 90 degrees inside a step, and the integration
goes on), ``END`` (the end condition), ``JAM`` (``dp`` grew to ``1e6 v_scale / k_nn``
without an event: Painleve's paradox), ``SETTLED`` (with ``settle`` only: the slip
direction has settled, to ``rtol`` rad, on an attracting invariant direction: the rest of the
phase is linear in ``p`` and the caller finishes it in closed form; see :func:`_settled`),
``FAILED`` (``MAX_STEPS`` steps, or a step below round-off of ``dp``). The phase ends at once
(``dp = 0``) when the end condition already holds or ``|w_t| <= near`` at the start.

Without Numba (it is the optional extra ``fast``) the same code runs as plain Python: the same
answers, about as fast as SciPy's ``solve_ivp`` was (a few ms per impact).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

try:
    import numba
except ImportError:  # pragma: no cover - the optional extra "fast" is absent
    numba = None  # type: ignore[assignment]

#: Compiled once per machine (cached beside this file); without Numba, the function as written.
_jit: Callable[[Any], Any] = (
    numba.njit(cache=True, nogil=True, error_model="numpy") if numba else lambda f: f
)


STOP, NEAR_STOP, END, JAM, FAILED, SETTLED = 1, 2, 3, 4, 5, 6
#: The least first step (of the impulse scale ``|w'| / K_nn``) of a phase.
INITIAL_STEP = 1e-9
END_COMPRESSION, END_VELOCITY, END_IMPULSE, END_WORK = 0, 1, 2, 3
MAX_STEPS = 100_000
#: A phase that has not ended by ``dp = JAM_SPAN v_scale / k_nn`` never ends (jam).
JAM_SPAN = 1e6

# DOP853: the nodes, the Runge-Kutta matrix (row i: stage i, lower triangle), the weights of
# the 8th-order solution, and the 5th- and 3rd-order error estimators (Hairer et al. II.10;
# SciPy's scipy/integrate/_ivp/dop853_coefficients.py, BSD licence, rounded to double).
_C = np.array([
    0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274, 0.2816496580927726,
    0.3333333333333333, 0.25, 0.3076923076923077, 0.6512820512820513, 0.6, 0.8571428571428571,
    1.0,
])  # fmt: skip
_A = np.zeros((12, 12))
_A[1, :1] = [0.05260015195876773]
_A[2, :2] = [0.0197250569845379, 0.0591751709536137]
_A[3, :3] = [0.02958758547680685, 0.0, 0.08876275643042054]
_A[4, :4] = [0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792]
_A[5, :5] = [0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242]
_A[6, :6] = [0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125]
_A[7, :7] = [0.03709200011850479, 0.0, 0.0, 0.17038392571223998, 0.10726203044637328,
             -0.015319437748624402, 0.008273789163814023]  # fmt: skip
_A[8, :8] = [0.6241109587160757, 0.0, 0.0, -3.3608926294469414, -0.868219346841726,
             27.59209969944671, 20.154067550477894, -43.48988418106996]  # fmt: skip
_A[9, :9] = [0.47766253643826434, 0.0, 0.0, -2.4881146199716677, -0.590290826836843,
             21.230051448181193, 15.279233632882423, -33.28821096898486,
             -0.020331201708508627]  # fmt: skip
_A[10, :10] = [-0.9371424300859873, 0.0, 0.0, 5.186372428844064, 1.0914373489967295,
               -8.149787010746927, -18.52006565999696, 22.739487099350505,
               2.4936055526796523, -3.0467644718982196]  # fmt: skip
_A[11, :11] = [2.273310147516538, 0.0, 0.0, -10.53449546673725, -2.0008720582248625,
               -17.9589318631188, 27.94888452941996, -2.8589982771350235, -8.87285693353063,
               12.360567175794303, 0.6433927460157636]  # fmt: skip
_B = np.array([
    0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
    -5.801203960010585, 0.3111643669578199, -0.1521609496625161, 0.20136540080403034,
    0.04471061572777259,
])  # fmt: skip
_E3 = np.array([
    -0.18980075407240762, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
    -5.801203960010585, -0.4226823213237919, -0.1521609496625161, 0.20136540080403034,
    0.02265179219836082,
])  # fmt: skip
_E5 = np.array([
    0.01312004499419488, 0.0, 0.0, 0.0, 0.0, -1.2251564463762044, -0.4957589496572502,
    1.6643771824549864, -0.35032884874997366, 0.3341791187130175, 0.08192320648511571,
    -0.022355307863886294,
])  # fmt: skip
#: The reference direction ``seg`` of the stop's sign change is renewed when the slip has
#: turned by this much (rad) from it: far from 90 degrees, so the field stays smooth.
SEGMENT_TURN = math.pi / 3
_COS_SEGMENT_TURN = math.cos(SEGMENT_TURN)
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_ERROR_EXPONENT = -1.0 / 8.0  # DOP853's step-size control (Hairer et al. II.4, II.10)

@_jit
def _rhs(dp: float, y: np.ndarray, c: np.ndarray, seg_1: float, seg_2: float,
         out: np.ndarray) -> None:  # fmt: skip
    """``out = f(dp, y)`` for ``y = (w_1, w_2, dP_1, dP_2, dW_n, dW_t)``; ``c = (k_nn, k_n1,
    k_n2, k_11, k_12, k_22, mu, w_n at the start)``; ``seg`` the reference direction."""
    w_1, w_2 = y[0], y[1]
    rho = math.hypot(w_1, w_2)
    if rho == 0.0:
        s_1, s_2 = seg_1, seg_2
    else:  # continued through w_t = 0 along the direction of approach (module docstring)
        sign = 1.0 if w_1 * seg_1 + w_2 * seg_2 >= 0.0 else -1.0
        s_1, s_2 = sign * w_1 / rho, sign * w_2 / rho
    mu = c[6]
    out[0] = c[1] - mu * (c[3] * s_1 + c[4] * s_2)
    out[1] = c[2] - mu * (c[4] * s_1 + c[5] * s_2)
    out[2] = -mu * s_1
    out[3] = -mu * s_2
    out[4] = c[7] + c[0] * dp + c[1] * y[2] + c[2] * y[3]
    out[5] = -mu * (w_1 * s_1 + w_2 * s_2)


@_jit
def _step(dp: float, y: np.ndarray, f0: np.ndarray, h: float, c: np.ndarray, seg_1: float,
          seg_2: float, stages: np.ndarray, y_new: np.ndarray, scratch: np.ndarray,
          atol: np.ndarray, rtol: float) -> float:  # fmt: skip
    """One DOP853 step of size ``h`` from ``(dp, y)`` with ``f0 = f(dp, y)``: ``y_new``, the
    stages (row 12: ``f`` at the end, for the next step and for event slopes), and the
    returned error norm (accept when <= 1; SciPy's ``DOP853._estimate_error_norm``)."""
    stages[0, :] = f0
    for i in range(1, 12):
        for j in range(6):
            acc = 0.0
            for m in range(i):
                acc += _A[i, m] * stages[m, j]
            scratch[j] = y[j] + h * acc
        _rhs(dp + _C[i] * h, scratch, c, seg_1, seg_2, stages[i])
    for j in range(6):
        acc = 0.0
        for m in range(12):
            acc += _B[m] * stages[m, j]
        y_new[j] = y[j] + h * acc
    _rhs(dp + h, y_new, c, seg_1, seg_2, stages[12])
    err5, err3 = 0.0, 0.0
    for j in range(6):
        e5, e3 = 0.0, 0.0
        for m in range(12):
            e5 += _E5[m] * stages[m, j]
            e3 += _E3[m] * stages[m, j]
        scale = atol[j] + rtol * max(abs(y[j]), abs(y_new[j]))
        err5 += (e5 / scale) ** 2
        err3 += (e3 / scale) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / math.sqrt((err5 + 0.01 * err3) * 6.0)


@_jit
def _event(code: int, dp: float, y: np.ndarray, f: np.ndarray, c: np.ndarray, seg_1: float,
           seg_2: float, near: float, end_kind: int,
           end_target: float) -> tuple[float, float]:  # fmt: skip
    """``(g, dg/dp)`` of one event, signed so that it fires when ``g`` rises to >= 0."""
    if code == STOP:  # w_t . seg falls through 0
        return -(y[0] * seg_1 + y[1] * seg_2), -(f[0] * seg_1 + f[1] * seg_2)
    if code == NEAR_STOP:  # |w_t| falls to near
        rho = math.hypot(y[0], y[1])
        slope = -(y[0] * f[0] + y[1] * f[1]) / rho if rho > 0.0 else 0.0
        return near - rho, slope
    if end_kind == END_IMPULSE:
        return dp - end_target, 1.0
    if end_kind == END_WORK:
        return y[4] - end_target, f[4]
    w_n = c[7] + c[0] * dp + c[1] * y[2] + c[2] * y[3]
    slope = c[0] + c[1] * f[2] + c[2] * f[3]  # dw_n/dp
    if end_kind == END_VELOCITY:
        return w_n - end_target, slope
    return w_n, slope  # END_COMPRESSION


@_jit
def _settled(w_1: float, w_2: float, c: np.ndarray, seg_1: float, seg_2: float,
             rtol: float) -> bool:  # fmt: skip
    """Whether the slip direction ``s`` has settled on an attracting invariant direction.

    On the clock ``d tau = dp / |w_t|`` the direction angle obeys ``dtheta/dtau = G(theta) =
    s_perp . (K_tn - mu K_tt s)`` (``s_perp = (-s_2, s_1)``): an autonomous equation of its
    own, whose zeros are the invariant directions. ``dG/dtheta = -kappa`` with ``kappa = s .
    K_tn - mu s . K_tt s + mu s_perp . K_tt s_perp``; where ``kappa > 0`` the direction
    converges to the zero, and what it has left to turn is ``|G| / kappa`` rad. Settled: at
    most ``rtol`` rad, with ``kappa`` clear of round-off (``> 1e-6 (|K_tn| + mu tr K_tt)``).
    Without this the integration creeps on: in ``p`` the direction relaxes
    at the rate ``kappa / |w_t|`` while ``|w_t|`` may change a thousand times more slowly
    (a soft tangential direction, ``K_tt`` nearly singular), and DOP853's steps are held to
    its stability limit (``kappa h / |w_t| ~ 6``): 10^5 steps were seen before the stop (the
    same test as :func:`carnot.batch.coulomb._settled`)."""
    rho = math.hypot(w_1, w_2)
    if rho == 0.0:
        return False
    sign = 1.0 if w_1 * seg_1 + w_2 * seg_2 >= 0.0 else -1.0
    s_1, s_2 = sign * w_1 / rho, sign * w_2 / rho
    mu = c[6]
    rate_1 = c[1] - mu * (c[3] * s_1 + c[4] * s_2)
    rate_2 = c[2] - mu * (c[4] * s_1 + c[5] * s_2)
    turn = -s_2 * rate_1 + s_1 * rate_2
    kappa = (s_1 * rate_1 + s_2 * rate_2
             + mu * (c[3] * s_2 * s_2 - 2.0 * c[4] * s_1 * s_2 + c[5] * s_1 * s_1))  # fmt: skip
    # kappa of the size of round-off: a neutral direction field (K_tt a multiple of the
    # identity and K_tn = 0: every direction invariant), not an attracting direction
    scale = math.hypot(c[1], c[2]) + mu * (c[3] + c[5])
    return kappa > 1e-6 * scale and abs(turn) <= rtol * kappa


@_jit
def _locate(code: int, dp: float, y: np.ndarray, f0: np.ndarray, h: float, g_end: float,
            c: np.ndarray, seg_1: float, seg_2: float, near: float, end_kind: int,
            end_target: float, stages: np.ndarray, y_root: np.ndarray, scratch: np.ndarray,
            atol: np.ndarray, rtol: float) -> tuple[float, int]:  # fmt: skip
    """The step ``theta`` in ``(0, h]`` at which event ``code`` fires inside the accepted
    step from ``(dp, y)``: ``g(step(theta)) = 0`` by Newton's method on the step map,
    safeguarded by the bracket ``[lo, hi]`` (falls back to bisection). Leaves the state at
    ``theta`` in ``y_root`` and ``f`` there in ``stages[12]``; returns ``(theta, evals)``."""
    g_start = _event(code, dp, y, f0, c, seg_1, seg_2, near, end_kind, end_target)[0]
    lo, hi, g_lo, g_hi = 0.0, h, g_start, g_end
    theta = h * (-g_lo) / (g_hi - g_lo) if g_hi > g_lo else h  # regula falsi to start
    evals = 0
    at = theta  # the step that y_root holds: returned with it, whatever ends the iteration
    for _ in range(60):
        theta = min(max(theta, lo), hi)
        _step(dp, y, f0, theta, c, seg_1, seg_2, stages, y_root, scratch, atol, rtol)
        evals += 12
        at = theta
        g, slope = _event(code, dp + theta, y_root, stages[12], c, seg_1, seg_2, near,
                          end_kind, end_target)  # fmt: skip
        if g >= 0.0:
            hi, g_hi = theta, g
        else:
            lo, g_lo = theta, g
        if g == 0.0 or hi - lo <= 4.0 * 2.220446049250313e-16 * (dp + hi):
            break
        step = -g / slope if slope != 0.0 else math.inf
        guess = theta + step
        if not lo < guess < hi:
            guess = 0.5 * (lo + hi)
        if abs(step) <= 4.0 * 2.220446049250313e-16 * (dp + theta):
            break  # converged: theta is the root to round-off of dp
        theta = guess
    return at, evals


@_jit
def slip_phase(
    k_nn: float, k_n1: float, k_n2: float, k_11: float, k_12: float, k_22: float, mu: float,
    w_n: float, w_1: float, w_2: float, s_1: float, s_2: float, end_kind: int,
    end_target: float, near: float, v_scale: float, rtol: float, max_step: float,
    path: np.ndarray, settle: bool = False,
) -> tuple[int, float, float, float, float, float, float, float, float, float, float, float,
           float, float, int, int, int]:  # fmt: skip
    """Integrate one 3D slip phase to its first event (contract: the module docstring).

    The relative velocity in the contact frame (m/s) evolves by ``dw/dp = K (e_n - mu s)``,
    ``s = w_t / |w_t|`` (``K``: 1/kg, ``p``: N s); the works ``dW_n = w_n dp`` and ``dW_t =
    -mu |w_t| dp`` (J). A sphere (``K = diag(1, 3.5, 3.5)``: the slip keeps its direction)
    landing at 1 m/s while sliding at 1 m/s, mu = 0.1: compression ends at ``dp = 1`` with
    ``w_1 = 1 - 0.1 * 3.5 * 1 = 0.65`` and ``W_n = -1/2``, ``W_t = -(1 + 0.65) / 2 * 0.1``:

    >>> out = slip_phase(1.0, 0.0, 0.0, 3.5, 0.0, 3.5, 0.1, -1.0, 1.0, 0.0, 1.0, 0.0,
    ...                  END_COMPRESSION, 0.0, 1e-9, 1.0, 1e-12, np.inf, np.empty((0, 6)))
    >>> out[0] == END, [round(v, 12) for v in (out[1], out[3], out[7], out[8])]
    (True, [1.0, 0.65, -0.5, -0.0825])
    """
    c = np.array([k_nn, k_n1, k_n2, k_11, k_12, k_22, mu, w_n])
    impulse_scale = v_scale / k_nn
    atol = np.empty(6)
    atol[0] = atol[1] = rtol * 1e-3 * near
    atol[2] = atol[3] = rtol * impulse_scale
    atol[4] = atol[5] = rtol * v_scale * impulse_scale
    span = JAM_SPAN * impulse_scale
    fast = 1e-6 * v_scale  # slower slip: its direction no longer counts as the approach's
    y = np.zeros(6)
    y[0], y[1] = w_1, w_2
    y_new, y_root, scratch = np.empty(6), np.empty(6), np.empty(6)
    f0 = np.empty(6)
    stages = np.empty((13, 6))
    stages_root = np.empty((13, 6))
    seg_1, seg_2 = s_1, s_2
    dir_1, dir_2 = s_1, s_2
    turn = 0.0
    dp = 0.0
    steps, evals, rows = 0, 1, 0
    _rhs(dp, y, c, seg_1, seg_2, f0)
    code = 0
    # Already there: the end condition holds, or the slip is as slow as a stop.
    if _event(END, dp, y, f0, c, seg_1, seg_2, near, end_kind, end_target)[0] >= 0.0:
        code = END
    elif math.hypot(w_1, w_2) <= near:
        code = NEAR_STOP
    # The initial step: Hairer et al. II.4, as SciPy's select_initial_step (order 8).
    d0, d1 = 0.0, 0.0
    for j in range(6):
        scale = atol[j] + rtol * abs(y[j])
        d0 += (y[j] / scale) ** 2
        d1 += (f0[j] / scale) ** 2
    d0, d1 = math.sqrt(d0 / 6.0), math.sqrt(d1 / 6.0)
    h0 = 1e-6 * impulse_scale if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, max_step)
    for j in range(6):
        y_new[j] = y[j] + h0 * f0[j]
    _rhs(dp + h0, y_new, c, seg_1, seg_2, scratch)
    evals += 1
    d2 = 0.0
    for j in range(6):
        scale = atol[j] + rtol * abs(y[j])
        d2 += ((scratch[j] - f0[j]) / scale) ** 2
    d2 = math.sqrt(d2 / 6.0) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6 * impulse_scale, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    # (Hairer's estimate weighs each component by its tolerance: the slip's components
    # carry 1e-3 of the near-stop speed, so a component at 0 with a steep rate, a slip in
    # one tangent turning into the other, made it 1e-16 of the impulse scale, under the
    # round-off floor below before a step was taken; the step control, not the estimate,
    # then sizes the steps: from INITIAL_STEP at least)
    h = min(max(100.0 * h0, INITIAL_STEP * impulse_scale), h1, max_step)
    rejected = False
    while code == 0:
        if steps >= MAX_STEPS:
            code = FAILED
            break
        if dp >= span:
            code = JAM
            break
        h = min(h, max_step, span - dp)
        rho = math.hypot(y[0], y[1])
        closing = -(y[0] * f0[0] + y[1] * f0[1]) / rho  # -d|w_t|/dp
        if closing > 0.0:
            # Aim a step that would reach the stop at the near-stop speed, between it and the
            # stop (to first order): no stage of a step lands on the singular w_t ~ 0, where
            # the continued field amplifies the off-path round-off (seen: a step ending a
            # hair from the stop, turned by 90 degrees, that the error estimate passed).
            h = min(h, (rho - 0.5 * near) / closing)
        if h <= 10.0 * 2.220446049250313e-16 * max(dp, impulse_scale):
            code = FAILED
            break
        err = _step(dp, y, f0, h, c, seg_1, seg_2, stages, y_new, scratch, atol, rtol)
        evals += 12
        if not err <= 1.0:  # rejected (a NaN too): smaller, by the 8th-order error law
            h *= max(_MIN_FACTOR, _SAFETY * err**_ERROR_EXPONENT) if err < math.inf else 0.2
            rejected = True
            continue
        # Events inside the accepted step: the first one, each located on the step map.
        first, theta = 0, math.inf
        for event in (STOP, NEAR_STOP, END):
            g_end = _event(event, dp + h, y_new, stages[12], c, seg_1, seg_2, near, end_kind,
                           end_target)[0]  # fmt: skip
            if g_end < 0.0:
                continue
            at, used = _locate(event, dp, y, f0, h, g_end, c, seg_1, seg_2, near, end_kind,
                               end_target, stages_root, y_root, scratch, atol, rtol)  # fmt: skip
            evals += used
            rho_at = math.hypot(y_root[0], y_root[1])
            if event == STOP and rho_at <= near:  # |w_t| fell through near before: find that
                event = NEAR_STOP
                at, used = _locate(NEAR_STOP, dp, y, f0, at, near - rho_at, c, seg_1, seg_2,
                                   near, end_kind, end_target, stages_root, y_root, scratch,
                                   atol, rtol)  # fmt: skip
                evals += used
            if at < theta:
                first, theta = event, at
                y_new[:] = y_root
                stages[12, :] = stages_root[12]
        dp += h if first == 0 else theta
        y[:] = y_new
        steps += 1
        rho = math.hypot(y[0], y[1])
        if rho > fast:  # the direction of approach, and the angle swept
            d_1, d_2 = y[0] / rho, y[1] / rho
            turn += math.atan2(abs(dir_1 * d_2 - dir_2 * d_1), dir_1 * d_1 + dir_2 * d_2)
            dir_1, dir_2 = d_1, d_2
        if rows < path.shape[0]:
            w_now = w_n + k_nn * dp + k_n1 * y[2] + k_n2 * y[3]
            path[rows, 0], path[rows, 1], path[rows, 2] = dp, w_now, y[0]
            path[rows, 3], path[rows, 4], path[rows, 5] = y[1], y[4], y[5]
        rows += 1
        if first != 0 and not (first == STOP and rho > near):
            code = first
            break
        if settle and first == 0 and _settled(y[0], y[1], c, seg_1, seg_2, rtol):
            code = SETTLED
            break
        if rho > 0.0 and y[0] * seg_1 + y[1] * seg_2 < _COS_SEGMENT_TURN * rho:
            # A new reference direction once the slip has turned by SEGMENT_TURN (the field
            # is unchanged). Not at every step: slip that swings through w_t ~ 0 over several
            # steps (a stop where round-off leaves the path a hair off the origin) must show
            # as a sign change of w_t . seg against a fixed reference.
            seg_1, seg_2 = y[0] / rho, y[1] / rho
        if first == STOP:  # w_t turned through 90 degrees inside the step: not a stop
            _rhs(dp, y, c, seg_1, seg_2, f0)  # on the old reference's edge: evaluate anew
            evals += 1
            rejected = False
            continue  # and keep h
        f0[:] = stages[12]  # first same as last: f at the end of the step
        factor = _MAX_FACTOR if err == 0.0 else min(_MAX_FACTOR, _SAFETY * err**_ERROR_EXPONENT)
        h *= min(factor, 1.0) if rejected else factor
        rejected = False
    w_end = w_n + k_nn * dp + k_n1 * y[2] + k_n2 * y[3]
    return (code, dp, w_end, y[0], y[1], y[2], y[3], y[4], y[5], seg_1, seg_2, dir_1, dir_2,
            turn, steps, evals, rows)  # fmt: skip

"""Coulomb friction with slip: the impact integrated in impulse space (Darboux-Keller).

Everything here is in contact space, in the contact frame ``(n, t1, t2)`` of
``conventions.contact_frame``. During the impact the relative velocity at the contact is an
affine function of the impulse ``P = (p, P_t)`` that body ``a`` has received so far,

    w(P) = w' + K P,        K = the contact block of W M^-1 W^T  (1/kg, symmetric positive
                             definite; persistent constraints folded in by solve.py)

The normal impulse ``p`` grows monotonically through the impact and serves as its clock.

* **Slip** (``|w_t| > 0``): Coulomb's law ``dP_t = -mu s dp`` with ``s = w_t / |w_t|``, so
  ``dw/dp = K (e_n - mu s)``. In 3D the slip direction ``s`` rotates as ``w_t`` evolves; it is
  constant when ``dw_t/dp`` is parallel to ``s`` (an *invariant* direction: always so in a
  planar problem).
* **Stop**: when ``w_t`` reaches 0 the contact sticks if the impulse ratio that keeps it at
  rest, ``dP_t/dp = -K_tt^-1 K_tn``, lies inside the friction cone (``|.| <= mu``); else slip
  resumes at once along the invariant direction ``s`` with ``K_tn - mu K_tt s = lambda s``,
  ``lambda > 0`` (a *reversal* when ``s`` is opposite to the old direction: always so in a
  planar problem; a *direction change* otherwise).
* **Stick**: ``w_t = 0`` and ``dP_t/dp = -K_tt^-1 K_tn``; with a constant ``K`` a contact that
  sticks stays stuck.

Compression ends at ``w_n = 0`` (normal impulse ``p_c``, normal work ``W_c < 0``); the impact
ends by the restitution hypothesis of the contact (Stronge, *Impact Mechanics*, CUP 2000,
ch. 2 and 5):

* ``newton`` (kinematic): ``w_n = -e w'_n``;
* ``poisson`` (kinetic): ``p = (1 + e) p_c``;
* ``stronge`` (energetic): the normal work in restitution is ``-e^2 W_c``, i.e.
  ``W_n = (1 - e^2) W_c``.

Every phase with a constant slip direction (or stick) is linear in ``p`` and is solved exactly
(its events are roots of linear or quadratic equations): this is the exact piecewise-linear
solution of planar problems. A 3D slip phase whose direction rotates is integrated by
:mod:`carnot.laws.slip3d`, a DOP853 integrator compiled with Numba (plain Python without it),
its events located on the step map; the slip-direction field is continued through ``w_t = 0``
along the direction of approach (``s = sign(w_t . s_seg) w_t / |w_t|``, ``s_seg`` a reference
direction renewed after each turn by 60 degrees), so that the stop is a sign change of the
smooth function ``w_t . s_seg`` and not the kink of ``|w_t|``; the last ``NEAR_STOP |w'|``
of a stop, and the rest of a phase whose direction has settled on an attracting invariant
direction (where the explicit integrator would creep at its stability limit: a slender body,
mu of 2 to 10), are finished in closed form, as in :mod:`carnot.batch.coulomb`. Numba is
imported only when such a phase is integrated.
The works ``W_n = int w_n dp`` and ``W_t = int w_t . dP_t`` are integrated alongside:
``E_d = -(W_n + W_t)``, an independent route to the energy ledger.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from carnot.errors import CarnotError

Hypothesis = Literal["newton", "poisson", "stronge"]
Method = Literal["auto", "exact", "integrate"]

#: Relative tolerance of the 3D integrator (DOP853, laws/slip3d.py), and of its tests.
RTOL = 1e-12
#: Relative slack of the friction cone test at a stop (round-off in K_tt^-1 K_tn).
CONE_SLACK = 1e-12
#: Rows of the integrator's path buffer (steps of one integrated slip phase); more: a rerun.
_PATH_ROWS = 256
#: Slip slower than this fraction of |w'| is finished along its current direction, in closed
#: form: near a stop the 3D slip direction field is singular (it turns like 1/|w_t|), and an
#: adaptive integrator would creep towards the stop in ever smaller steps.
NEAR_STOP = 1e-9


class ImpactJamError(CarnotError):
    """The normal impulse grows without bound: the contact jams (Painleve's paradox).

    The rigid-body impact model has no solution then; a compliant contact model is needed.
    """


@dataclass(frozen=True, kw_only=True, eq=False)
class Phase:
    """One phase of the impact: ``regime`` ``"slip"`` or ``"stick"``, from normal impulse
    ``start`` to ``end`` (N s). ``began`` says how it started: ``"impact"`` (the first
    phase), ``"stop"`` (a stick phase after slip stopped), ``"reversal"`` or
    ``"direction_change"``. Slip directions are unit tangent vectors in contact-frame
    components ``(t1, t2)``; ``turn`` is the angle (rad) the slip direction swept during the
    phase."""

    regime: Literal["slip", "stick"]
    began: str
    start: float
    end: float
    direction_start: np.ndarray | None = None
    direction_end: np.ndarray | None = None
    turn: float = 0.0


@dataclass(frozen=True, kw_only=True, eq=False)
class FrictionalImpulse:
    """The outcome of one frictional impact in contact space.

    ``impulse`` is ``(p, P_t1, P_t2)`` (N s) in the contact frame; ``compression_impulse`` the
    normal impulse ``p_c`` at maximum compression; works in J: ``work_normal_compression``
    (``W_c <= 0``), ``work_normal_restitution``, ``work_tangential_compression``,
    ``work_tangential_restitution`` (both ``<= 0``: friction only dissipates). ``samples``:
    rows ``(p, w_n, w_t1, w_t2, W_n, W_t)`` along the impact, for plots.
    """

    impulse: np.ndarray
    hypothesis: str
    method: str
    compression_impulse: float
    work_normal_compression: float
    work_normal_restitution: float
    work_tangential_compression: float
    work_tangential_restitution: float
    phases: tuple[Phase, ...]
    samples: np.ndarray
    k: np.ndarray
    w_before: np.ndarray
    friction: float
    restitution: float

    def resampled(self, points_per_phase: int = 64) -> FrictionalImpulse:
        """The same impact integrated again with ``points_per_phase`` samples in every phase
        (for smooth plots; the default run keeps only the events and integrator steps)."""
        return integrate_impact(
            self.k, self.w_before, friction=self.friction, restitution=self.restitution,
            hypothesis=self.hypothesis, method=self.method,  # type: ignore[arg-type]
            dense=points_per_phase,
        )  # fmt: skip

    @property
    def regime(self) -> str:
        """The phases in order, joined by ``-``: ``slip``, ``stick``, ``reversal`` (slip that
        began by reversing), ``redirected`` (slip that began in a new, not opposite,
        direction); ``none`` when the bodies were not approaching.

        >>> K = np.eye(3)
        >>> integrate_impact(K, np.array([-1.0, 0.1, 0]), friction=1.0, restitution=0.0,
        ...                  hypothesis="newton").regime
        'slip-stick'
        """
        labels = {"reversal": "reversal", "direction_change": "redirected"}
        names = [labels.get(ph.began, ph.regime) for ph in self.phases]
        return "-".join(names) if names else "none"

    @property
    def work_normal(self) -> float:
        """``W_n = int w_n dp`` (J): the work of the normal impulse on the relative motion."""
        return self.work_normal_compression + self.work_normal_restitution

    @property
    def work_tangential(self) -> float:
        """``W_t = int w_t . dP_t`` (J), ``<= 0``."""
        return self.work_tangential_compression + self.work_tangential_restitution


@dataclass(kw_only=True)
class _State:
    """The running state of one impact (mutable inside this module only)."""

    p: float
    p_t: np.ndarray
    work_n: float
    work_t: float
    work_r: float = 0.0  # normal work since maximum compression (J), kept apart: precision
    compressed: bool = False
    p_c: float = math.nan
    work_c: float = math.nan
    work_t_c: float = math.nan
    done: bool = False


class _Impact:
    """The impact's fixed data and event rules: ``K``, ``w'``, ``mu``, ``e``, hypothesis."""

    def __init__(
        self, k: np.ndarray, w0: np.ndarray, mu: float, e: float, hyp: str, dense: int = 0
    ):
        self.dense = dense
        self.k = k
        self.w0 = w0
        self.mu = mu
        self.e = e
        self.hyp = hyp
        self.k_tt = k[1:, 1:]
        self.k_tn = k[1:, 0]
        self.k_nt = k[0, 1:]
        self.k_nn = float(k[0, 0])
        self.speed = float(np.linalg.norm(w0))
        self.impulse_scale = self.speed / self.k_nn
        self.samples: list[np.ndarray] = []

    def velocity(self, s: _State) -> np.ndarray:
        return self.w0 + self.k @ np.concatenate([[s.p], s.p_t])

    def record(self, s: _State) -> None:
        w = self.velocity(s)
        self.samples.append(np.array([s.p, w[0], w[1], w[2], s.work_n, s.work_t]))

    def newton_target(self) -> float:
        return -self.e * float(self.w0[0])

    def terminated_at_compression(self) -> bool:
        return self.e == 0.0

    def mark_compression(self, s: _State) -> None:
        s.compressed = True
        s.p_c = s.p
        s.work_c = s.work_n
        s.work_t_c = s.work_t
        if self.terminated_at_compression():
            s.done = True


def integrate_impact(
    k: np.ndarray,
    w_before: np.ndarray,
    *,
    friction: float,
    restitution: float,
    hypothesis: str,
    method: Method = "auto",
    rtol: float = RTOL,
    dense: int = 0,
) -> FrictionalImpulse:
    """Integrate one frictional impact in impulse space (see the module docstring).

    ``k``: the contact-frame effective inverse mass (3x3, 1/kg); ``w_before``: the relative
    velocity ``(w_n, w_t1, w_t2)`` before (m/s, ``w_n < 0`` approaching); ``friction``: mu;
    ``restitution``: e in [0, 1]; ``hypothesis``: ``newton``, ``poisson`` or ``stronge``;
    ``method``: ``exact`` (every phase linear: the problem must be planar or its slip
    direction invariant), ``integrate`` (every first slip phase through the ODE integrator, for
    checks), ``auto`` (exact where the slip direction is invariant); ``dense``: samples per
    phase to record for plots (0: the events and integrator steps only).

    A sphere (m = 1 kg, radius 1 m, I = 2/5) landing at 1 m/s while sliding at 1 m/s on a
    plane with mu = 0.1, e = 0.5: gross slip, ``P_t = -mu P_n = -0.15`` N s (Brach,
    *Mechanical Impact Dynamics*, 1991, ch. 4):

    >>> K = np.diag([1.0, 1 + 1 / 0.4, 1 + 1 / 0.4])
    >>> out = integrate_impact(K, np.array([-1.0, 1.0, 0.0]), friction=0.1, restitution=0.5,
    ...                        hypothesis="poisson")
    >>> out.impulse.round(12).tolist(), out.regime
    ([1.5, -0.15, 0.0], 'slip')
    """
    k = np.asarray(k, dtype=float)
    w0 = np.asarray(w_before, dtype=float)
    # In units of |w'| and of the impulse |w'| / K_nn every quantity is of order 1: the
    # integrator's absolute tolerances and the thresholds are relative to these scales.
    speed = float(np.linalg.norm(w0))
    impulse = speed / float(k[0, 0]) if speed > 0 and k[0, 0] > 0 else 1.0
    speed = speed if speed > 0 else 1.0
    out = _integrate(k * (impulse / speed), w0 / speed, float(friction), float(restitution),
                     hypothesis, method, rtol, dense)  # fmt: skip
    work = speed * impulse
    return dataclasses.replace(
        out,
        impulse=out.impulse * impulse,
        compression_impulse=out.compression_impulse * impulse,
        work_normal_compression=out.work_normal_compression * work,
        work_normal_restitution=out.work_normal_restitution * work,
        work_tangential_compression=out.work_tangential_compression * work,
        work_tangential_restitution=out.work_tangential_restitution * work,
        phases=tuple(dataclasses.replace(ph, start=ph.start * impulse, end=ph.end * impulse)
                     for ph in out.phases),
        samples=out.samples * np.array([impulse, speed, speed, speed, work, work]),
        k=k,
        w_before=w0,
    )  # fmt: skip


def _integrate(
    k: np.ndarray, w0: np.ndarray, friction: float, restitution: float, hypothesis: str,
    method: Method, rtol: float, dense: int,
) -> FrictionalImpulse:  # fmt: skip
    """:func:`integrate_impact` in units where ``|w'| = 1`` and ``K_nn = 1``."""
    imp = _Impact(k, w0, friction, restitution, hypothesis, dense)
    state = _State(p=0.0, p_t=np.zeros(2), work_n=0.0, work_t=0.0)
    phases: list[Phase] = []
    imp.record(state)
    if not w0[0] < 0.0:
        return _finish(imp, state, phases, method)
    w_t = w0[1:]
    slip_speed = float(np.linalg.norm(w_t))
    began = "impact"
    direction: np.ndarray | None = None
    # Slip slower than the near-stop speed counts as none, as when slip stops: its direction
    # would be round-off (and the integrator would creep through that noise in tiny steps).
    if slip_speed > NEAR_STOP * imp.speed:
        direction = w_t / slip_speed
    if imp.mu == 0.0:  # frictionless: one linear phase, whatever the tangential motion
        _linear_phase(imp, state, np.zeros(2), None)
        phases.append(Phase(regime="slip", began=began, start=0.0, end=state.p,
                            direction_start=direction, direction_end=direction))  # fmt: skip
    for _ in range(8):  # at most: slip, stop, stick or redirected slip; each at most once
        if state.done:
            break
        from_rest = direction is None
        if direction is None:  # at rest in the tangent plane: stick, or slip at once
            ratio = _sticking_ratio(imp)
            if float(np.linalg.norm(ratio)) <= imp.mu * (1 + CONE_SLACK):
                start = state.p
                _linear_phase(imp, state, ratio, None)
                # slip that stopped just as the impact ended (a tie, e.g. K = I, w' = (-1,
                # 1, 0), mu = 1, e = 0 under Newton) had no stick phase: the exact route's
                # first event is then the end, and the integrated route must say the same
                if state.p - start > RTOL * state.p:
                    phases.append(Phase(regime="stick", began=began, start=start, end=state.p))
                continue
            new = _resumed_direction(imp)
            old = phases[-1].direction_end if phases else None
            if old is not None:
                began = "reversal" if float(new @ old) < -1 + 1e-9 else "direction_change"
            direction = new
        start = state.p
        invariant = _is_invariant(imp, direction)
        if method == "exact" and not invariant:
            raise CarnotError(
                "method='exact' needs a constant slip direction (a planar problem); the slip "
                f"direction {direction.tolist()} turns: use method='auto' or 'integrate'"
            )
        # slip that starts from rest grows along an invariant ray: exact, whatever the method
        if invariant and (method != "integrate" or from_rest):
            stopped = _linear_phase(imp, state, -imp.mu * direction, direction)
            end_dir, turn = direction, 0.0
        else:
            stopped, end_dir, turn = _integrated_slip(imp, state, direction, rtol)
        phases.append(
            Phase(regime="slip", began=began, start=start, end=state.p,
                  direction_start=direction, direction_end=end_dir, turn=turn)
        )  # fmt: skip
        if stopped:  # the next pass decides: stick, or slip again in a new direction
            began = "stop"
            direction = None
    else:  # pragma: no cover - the phase sequence above is finite
        raise CarnotError("the frictional impact did not end within 8 phases")
    return _finish(imp, state, phases, method)


def _finish(
    imp: _Impact, state: _State, phases: list[Phase], method: str
) -> FrictionalImpulse:
    if not state.compressed:  # not approaching: no impulse at all
        state.p_c, state.work_c, state.work_t_c = 0.0, 0.0, 0.0
    return FrictionalImpulse(
        impulse=np.concatenate([[state.p], state.p_t]),
        hypothesis=imp.hyp,
        method=method,
        compression_impulse=state.p_c,
        work_normal_compression=state.work_c,
        work_normal_restitution=state.work_n - state.work_c,
        work_tangential_compression=state.work_t_c,
        work_tangential_restitution=state.work_t - state.work_t_c,
        phases=tuple(phases),
        samples=np.array(imp.samples),
        k=imp.k,
        w_before=imp.w0,
        friction=imp.mu,
        restitution=imp.e,
    )


def _sticking_ratio(imp: _Impact) -> np.ndarray:
    """``dP_t/dp = -K_tt^-1 K_tn``: the tangential impulse rate that keeps ``w_t = 0``."""
    return -np.linalg.solve(imp.k_tt, imp.k_tn)


def _resumed_direction(imp: _Impact) -> np.ndarray:
    """The slip direction ``s`` after a stop that cannot stick: ``K_tn - mu K_tt s = lambda s``
    with ``lambda > 0`` and ``|s| = 1``. With ``K_tt = Q diag(k) Q^T`` and ``c = Q^T K_tn``,
    ``|s(lambda)|^2 = sum c_i^2 / (mu k_i + lambda)^2`` falls from above 1 (no stick) at
    ``lambda = 0`` to at most 1 at ``lambda = |c|``: one root, found by Brent's method."""
    from scipy.optimize import brentq  # here: importing SciPy's solvers costs 0.3 s

    kval, kvec = np.linalg.eigh(imp.k_tt)
    c = kvec.T @ imp.k_tn
    top = float(np.linalg.norm(c))

    def excess(lam: float) -> float:
        return float(np.sum(c**2 / (imp.mu * kval + lam) ** 2)) - 1.0

    lam = top if excess(top) >= 0 else brentq(excess, 0.0, top, xtol=1e-15 * top, rtol=1e-15)
    s = kvec @ (c / (imp.mu * kval + lam))
    return s / np.linalg.norm(s)


def _invariant_near(imp: _Impact, direction: np.ndarray) -> np.ndarray:
    """The invariant slip direction next to ``direction`` (unit, within about 1e-12 rad of
    it: see :func:`carnot.laws.slip3d._settled`), by Newton's method on the angle: ``theta <-
    theta + G / kappa`` with ``G = s_perp . (K_tn - mu K_tt s)`` and ``kappa = -dG/dtheta``.
    On it, slip keeps its direction exactly, so the linear phase that follows has no drift
    across it.

    >>> imp = _Impact(np.diag([1.0, 1.0, 2.0]), np.array([-1.0, 1.0, 0.0]), 0.5, 0.0, "newton")
    >>> s = _invariant_near(imp, np.array([1.0, 1e-11]))
    >>> abs(float(s[1])) < 1e-20, float(s[0])
    (True, 1.0)
    """
    s = direction / float(np.linalg.norm(direction))
    for _ in range(4):
        perp = np.array([-s[1], s[0]])
        rate = imp.k_tn - imp.mu * imp.k_tt @ s
        turn = float(perp @ rate)
        kappa = float(s @ rate) + imp.mu * float(perp @ imp.k_tt @ perp)
        if not kappa > 0.0 or turn == 0.0:
            break
        angle = turn / kappa
        if abs(angle) > 1e-9:  # not next to an attracting invariant direction: leave it
            break
        s = np.cos(angle) * s + np.sin(angle) * perp
        s = s / float(np.linalg.norm(s))
    return s


def _is_invariant(imp: _Impact, direction: np.ndarray) -> bool:
    """Whether slip along ``direction`` keeps its direction: ``dw_t/dp`` parallel to it."""
    along = imp.k_tt @ direction
    rate = imp.k_tn - imp.mu * along
    cross = float(rate[0] * direction[1] - rate[1] * direction[0])
    # relative to the rate's own terms: a tiny inertia's K_tt (r^2/J) may dwarf K_nn
    size = float(np.linalg.norm(imp.k_tn)) + imp.mu * (imp.k_nn + float(np.linalg.norm(along)))
    return abs(cross) <= 1e-13 * size


def _linear_phase(
    imp: _Impact, state: _State, rate_t: np.ndarray, direction: np.ndarray | None
) -> bool:
    """Advance ``state`` through a phase with the constant ``dP_t/dp = rate_t`` to its first
    event (exactly: roots of linear and quadratic equations). Returns whether it ended with
    the slip stopping (``w_t = 0``)."""
    slope = imp.k[:, 0] + imp.k[:, 1:] @ rate_t  # dw/dp
    while not state.done:
        w = imp.velocity(state)
        candidates: list[tuple[float, str]] = []
        if direction is not None:
            approach = float(slope[1:] @ direction)
            if approach < 0:
                candidates.append((-float(w[1:] @ direction) / approach, "stop"))
        if not state.compressed:
            if slope[0] > 0:
                candidates.append((-float(w[0]) / float(slope[0]), "compression"))
        else:
            dp = _termination_step(imp, state, w, float(slope[0]))
            if dp is not None:
                candidates.append((dp, "end"))
        if not candidates:
            raise ImpactJamError(
                "the contact jams: with dw_n/dp = "
                f"{float(slope[0]):.6g} 1/kg at p = {state.p:.6g} N s the impact never ends "
                "(nor does the slip stop); the rigid-body impact has no solution (Painleve)"
            )
        dp, event = min(candidates)
        dp = max(dp, 0.0)
        w_t = w[1:]
        for tau in np.linspace(0.0, dp, imp.dense + 2)[1:-1] if imp.dense else ():
            imp.samples.append(np.array([
                state.p + tau, *(w + slope * tau),
                state.work_n + float(w[0]) * tau + 0.5 * float(slope[0]) * tau * tau,
                state.work_t + float(w_t @ rate_t) * tau
                + 0.5 * float(slope[1:] @ rate_t) * tau * tau,
            ]))  # fmt: skip
        _advance(imp, state, dp, rate_t)
        if event == "stop":
            return True
        if event == "compression":
            imp.mark_compression(state)
        else:
            state.done = True
    return False


def _advance(imp: _Impact, state: _State, dp: float, rate_t: np.ndarray) -> None:
    """Move ``state`` by ``dp`` of normal impulse with the constant ``dP_t/dp = rate_t``;
    the works exactly (quadratics in ``dp``)."""
    w = imp.velocity(state)
    slope = imp.k[:, 0] + imp.k[:, 1:] @ rate_t
    work_n = float(w[0]) * dp + 0.5 * float(slope[0]) * dp * dp
    state.work_n += work_n
    if state.compressed:
        state.work_r += work_n
    state.work_t += float(w[1:] @ rate_t) * dp + 0.5 * float(slope[1:] @ rate_t) * dp * dp
    state.p += dp
    state.p_t = state.p_t + rate_t * dp
    imp.record(state)


def _termination_step(imp: _Impact, state: _State, w: np.ndarray, slope_n: float) -> float | None:
    """The normal impulse still to go, in a linear phase, until the hypothesis ends the
    impact; ``None`` when it never does within this phase."""
    w_n = float(w[0])
    if imp.hyp == "poisson":
        return max((1.0 + imp.e) * state.p_c - state.p, 0.0)
    if imp.hyp == "newton":
        gap = imp.newton_target() - w_n
        if gap <= 0:
            return 0.0
        return gap / slope_n if slope_n > 0 else None
    # stronge: a/2 dp^2 + w_n dp + (W_r + e^2 W_c) = 0, smallest root >= 0
    c = state.work_r + imp.e**2 * state.work_c
    if c >= 0:
        return 0.0
    a = 0.5 * slope_n
    disc = w_n * w_n - 4.0 * a * c
    if disc < 0:
        return None
    root = math.sqrt(disc)
    if w_n > 0:
        return -2.0 * c / (w_n + root)  # the stable form of (-w_n + root) / (2 a)
    if a > 0:  # at maximum compression (w_n = 0 up to round-off): no cancellation here
        return (root - w_n) / (2.0 * a)
    return None


def _end_condition(imp: _Impact, state: _State, w: np.ndarray) -> tuple[int, float]:
    """What ends the slip phase besides a stop, for :func:`carnot.laws.slip3d.slip_phase`:
    maximum compression, or the hypothesis' end of the impact as a target relative to now."""
    from carnot.laws import slip3d

    if not state.compressed:
        return slip3d.END_COMPRESSION, 0.0
    if imp.hyp == "poisson":  # p = (1 + e) p_c
        return slip3d.END_IMPULSE, (1.0 + imp.e) * state.p_c - state.p
    if imp.hyp == "newton":  # w_n = -e w'_n
        return slip3d.END_VELOCITY, imp.newton_target()
    # stronge: W_r + e^2 W_c = 0, i.e. the normal work still to go (small numbers: precision)
    return slip3d.END_WORK, -(state.work_r + imp.e**2 * state.work_c)


def _integrated_slip(
    imp: _Impact, state: _State, direction: np.ndarray, rtol: float
) -> tuple[bool, np.ndarray, float]:
    """Integrate a slip phase whose direction may turn (the compiled DOP853 of
    :mod:`carnot.laws.slip3d`), from ``state`` to its first stop or the end of the impact.
    Returns (stopped, the direction of approach at the end, the angle swept)."""
    from carnot.laws import slip3d  # here: importing Numba costs 0.3 s at start-up

    mu = imp.mu
    near = NEAR_STOP * imp.speed
    k = imp.k
    turn = 0.0
    last_dir = direction.copy()
    seg = direction.copy()
    for _ in range(4):  # at most: compression, then the end (a stop returns at once)
        w = imp.velocity(state)
        kind, target = _end_condition(imp, state, w)
        args = (float(k[0, 0]), float(k[0, 1]), float(k[0, 2]), float(k[1, 1]),
                float(k[1, 2]), float(k[2, 2]), mu, float(w[0]), float(w[1]), float(w[2]),
                float(seg[0]), float(seg[1]), kind, target, near, imp.speed, rtol)  # fmt: skip
        max_step = math.inf
        if imp.dense:  # for plots: a first pass for the length, then >= dense + 1 steps
            length = slip3d.slip_phase(*args, math.inf, np.empty((0, 6)), True)[1]
            max_step = length / (imp.dense + 1) if length > 0 else math.inf
        path = np.empty((_PATH_ROWS, 6))
        out = slip3d.slip_phase(*args, max_step, path, True)
        if out[16] > len(path):  # more steps than the buffer held: again, with room for all
            path = np.empty((out[16], 6))
            out = slip3d.slip_phase(*args, max_step, path, True)
        code, dp, _, w_1, w_2, dp_1, dp_2, dw_n, dw_t, seg_1, seg_2, dir_1, dir_2 = out[:13]
        if code == slip3d.JAM:
            raise ImpactJamError(
                "the contact jams: the normal impulse grew past "
                f"{state.p + dp:.6g} N s without the impact ending; the rigid-body impact "
                "has no solution (Painleve)"
            )
        if code == slip3d.FAILED:  # pragma: no cover - a step below round-off, or 1e5 steps
            raise CarnotError(
                "the 3D slip integration did not converge (after "
                f"{out[14]} steps, at normal impulse {state.p + dp:.6g} in units of |w'|/K_nn; "
                f"K = {np.round(k, 12).tolist()}, w' = {np.round(imp.w0, 12).tolist()}, "
                f"mu = {mu:g}): please report this impact"
            )
        rows = path[: out[16]]  # the steps (or a finer grid), for plots
        imp.samples.extend(rows + np.array([state.p, 0, 0, 0, state.work_n, state.work_t]))
        state.p += dp
        state.p_t = state.p_t + np.array([dp_1, dp_2])
        state.work_n += dw_n
        state.work_t += dw_t
        if state.compressed:
            state.work_r += dw_n
        turn += out[13]
        last_dir = np.array([dir_1, dir_2])
        seg = np.array([seg_1, seg_2])
        w_t = np.array([w_1, w_2])
        rho = math.hypot(w_1, w_2)
        if code == slip3d.SETTLED:  # the rest is slip along an invariant direction: exact
            here = _invariant_near(imp, w_t / rho)
            stopped = _linear_phase(imp, state, -mu * here, here)
            return stopped, here, turn
        if code == slip3d.NEAR_STOP:
            # The last stretch, |w_t| <= NEAR_STOP |w'|, in closed form along its direction
            # when that direction is still decelerating; else the slip counts as stopped and
            # the next pass decides (stick, or slip in a new direction).
            here = w_t / rho if rho > 0 else seg
            approach = float((imp.k_tn - mu * imp.k_tt @ here) @ here)
            if approach < 0:
                stopped = _linear_phase(imp, state, -mu * here, here)
                return stopped, last_dir, turn
            return True, last_dir, turn
        if not state.compressed:
            imp.mark_compression(state)
        else:
            state.done = True
        if state.done:
            return False, last_dir, turn
        if rho > 0:
            seg = w_t / rho
    raise CarnotError("the 3D slip integration did not converge")  # pragma: no cover

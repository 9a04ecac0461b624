"""The energy-dispersion multiple-impact law of Liu, Zhao and Brogliato.

C. Liu, Z. Zhao, B. Brogliato, *Frictionless multiple impacts in multibody systems. I.
Theoretical framework*, Proc. R. Soc. A 464 (2008) 3193-3211 (the "LZB" law). Each contact
``i`` stores a potential energy ``E_i`` through a compliant element ``F_i = k_i delta_i^p_i``
(``k_i`` the relative ``stiffness``, ``p_i`` the ``exponent``: 1 linear, 1.5 Hertz), so
``E_i = k_i delta_i^(p_i+1) / (p_i+1)`` and ``F_i = k_i^(1/(p_i+1)) ((p_i+1) E_i)^(p_i/(p_i+1))``.
In impulse space the contacts share the impulse in the ratio of their forces (LZB's
distributing law, ``dP_i / dP_r = F_i / F_r``) and the velocities follow
``dw = G dP``; the energies obey ``dE_i = -w_i dP_i`` while compressing (``w_i < 0``) and
``dE_i = -w_i dP_i / e_i^2`` while expanding (``w_i > 0``): the energetic restitution of
Stronge that LZB adopt, so that a contact gives back ``e_i^2`` of the energy it stored (one
contact alone leaves with ``w'' = -e w'``). With e = 1 this is exactly the compliant
dynamics ``F = k delta^p`` in contact space.

**Why a time-like variable.** LZB integrate in the impulse of the "primary" contact (the one
storing the most energy). That variable is a monotone re-parametrisation of the one used here,
``d tau = dP_r / F_r``: any of the impulses, all contacts' impulses and energies are the same
functions of each other. In ``tau`` the equations are regular where LZB's are not (at the start
every ``E_i = 0``, so ``F_i / F_r`` is ``0 / 0``; a contact closed at rest and pushed later
starts from ``E_i = 0`` where ``dE_i / dP_r = 0`` has the spurious solution ``E_i = 0``). The
state is the impulses ``P_i`` and the *apparent indentations* ``delta_i`` that give ``E_i`` (an
equivalent of ``E_i``, regular at 0): ``dP_i/dtau = F_i``, ``d delta_i/dtau = -w_i``
(compressing) or ``-w_i / e_i^2`` (expanding). Once a contact has given back its energy
(``delta_i = 0`` while expanding) it is open, and ``delta_i`` goes on as the signed gap, ``d
delta_i/dtau = -w_i`` with no force while it is negative: the contact closes again only when the
gap has closed, as in the compliant dynamics (LZB's energy variables cannot hold a gap: they
reactivate an open contact as soon as it approaches, which is the same answer when no contact
closes again after it opened, as in a cradle of equal balls, and differs otherwise: 1.4e-4 of
the impact speed on a three-ball cradle at e = 0.2; ``reactivation="approach"`` gives LZB's
rule, tested against their algorithm). SciPy's ``solve_ivp`` (DOP853, rtol 1e-12) integrates
each phase; events end a phase when a contact turns from compression to expansion (``w_i =
0``), from expansion back to compression, opens (``delta_i = 0``) or closes again. Each phase
is a :class:`~carnot.laws.multiple.rows.Stage`. With e = 0 the expansion is instantaneous: the
stored energy is lost when the contact's compression ends.

**Ties and redundant contacts.** A box landing flat on four corners has four contacts and three
normal freedoms (``G`` of rank 3): the law needs no rule for that, the compliant elements share
the load. But its corners end their compression at the same instant (by symmetry, or to 1e-16
with a tiny tilt), and solve_ivp reports only the event it placed first: every contact whose
own event falls at the phase's end to round-off switches with it (``_simultaneous_switches``).
**Energy.** ``K + sum E_i + lost`` is constant under the law; the phases' impulses are scaled
by the factor (1 to 1e-12) that makes the kinetic energy fall by exactly the law's loss, so an
elastic impact does not gain the integration's 1e-12 (``_energy_consistent_scale``).

Held rows (pins, fasten, targets) stay at their targets throughout: the contacts see the
Schur complement ``G_cc - G_ch G_hh^+ G_hc`` and the held rows receive ``-G_hh^+ G_hc P_c``.
The law is frictionless: friction or a contact told to stick is an InputError.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from carnot.conventions import RELATIVE_TOLERANCE
from carnot.errors import InputError
from carnot.laws.multiple.rows import (
    ContactOutcome,
    ContactRows,
    HeldRows,
    MultipleImpactOutcome,
    Stage,
    check_problem,
    frictionless_only,
    held_residual,
    velocity_scale,
)

#: The most phases one impact may have (an explicit bound on the integration).
MAX_PHASES = 10_000

#: When an open contact takes part again: ``gap`` once the bodies are back where it opened
#: (the compliant dynamics; the default), ``approach`` as soon as it approaches (LZB 2008, and
#: Siconos's ``OSNSMultipleImpact``). The two differ only when a contact closes again.
REACTIVATIONS = ("gap", "approach")

_LOAD, _EXPAND = 0, 1


def resolve_dispersion(
    delassus: object,
    w_before: object,
    contacts: Sequence[ContactRows],
    held: HeldRows | None = None,
    *,
    rtol: float = 1e-12,
    max_phases: int = MAX_PHASES,
    reactivation: str = "gap",
) -> MultipleImpactOutcome:
    """The LZB energy-dispersion law; row impulses ``Lambda`` (N s), phases in ``stages``.

    ``delassus`` is ``G`` (m x m, 1/kg), ``w_before`` the row velocities (m/s); each
    contact's ``stiffness``, ``exponent`` and ``restitution`` are read. ``reactivation``: when
    an open contact acts again, ``"gap"`` (once its gap has closed: the compliant dynamics) or
    ``"approach"`` (as soon as it approaches: LZB's rule); see :data:`REACTIVATIONS`.

    One contact alone gives Newton's answer ``w'' = -e w'`` (Stronge's energetic restitution
    of a frictionless central impact):

    >>> out = resolve_dispersion([[2.0]], [-1.0], [ContactRows(normal=0, restitution=0.5)])
    >>> round(float(out.w_after[0]), 9)
    0.5
    """
    contacts = tuple(contacts)
    frictionless_only(contacts, "dispersion")
    if not (isinstance(rtol, float) and 1e-14 <= rtol <= 1e-3):
        raise InputError("rtol", "must be a float in [1e-14, 1e-3]", rtol)
    if reactivation not in REACTIVATIONS:
        raise InputError("reactivation", f"must be one of {', '.join(REACTIVATIONS)}",
                         reactivation)
    g, w0 = check_problem(delassus, w_before, contacts, held)
    scale = velocity_scale(w0, held)
    tol = RELATIVE_TOLERANCE * scale
    stages: list[Stage] = []
    w = w0.copy()
    h_rows = list(held.rows) if held is not None else []
    c_rows = [c.normal for c in contacts]
    g_hh_pinv = np.linalg.pinv(g[np.ix_(h_rows, h_rows)]) if h_rows else np.zeros((0, 0))
    if held is not None and held_residual(held, w) > tol:
        # held rows brought to their targets first (a given target is an impulse of its own)
        x = g_hh_pinv @ (np.array(held.target) - w[h_rows])
        impulses = np.zeros_like(w)
        impulses[h_rows] = x
        stages.append(Stage(index=0, contacts=(), impulses=impulses, w_before=w,
                            w_after=w + g @ impulses, description="held rows"))
        w = stages[-1].w_after
    # Row impulses per unit of contact impulse: e_c on the contact rows, -G_hh^+ G_hc on held.
    lift = np.zeros((len(w), len(contacts)))
    lift[c_rows, np.arange(len(contacts))] = 1.0
    if h_rows:
        lift[h_rows, :] = -g_hh_pinv @ g[np.ix_(h_rows, c_rows)]
    s = (g @ lift)[c_rows]  # d w_c / d P_c: the condensed Delassus operator
    k = np.array([c.stiffness for c in contacts])
    p = np.array([c.exponent for c in contacts])
    e2 = np.array([c.restitution**2 for c in contacts])
    flags: list[str] = []
    if len(contacts) and np.any(w[c_rows] < -tol):
        phases, ok, lost = _integrate(s, w[c_rows], k, p, e2, rtol, tol, max_phases,
                                      reactivation == "approach")
        if not ok:
            flags.append("stage_limit")
        scale_p = _energy_consistent_scale(lift @ sum(dp for _, dp in phases), w, g, lost)
        for members, dp in phases:
            if not members:
                continue  # every contact open (gaps closing or opening): no impulse
            impulses = lift @ (scale_p * dp)
            stages.append(Stage(index=len(stages), contacts=members, impulses=impulses,
                                w_before=w, w_after=w + g @ impulses,
                                description="phase"))
            w = stages[-1].w_after
    total = np.sum([st.impulses for st in stages], axis=0) if stages else np.zeros_like(w0)
    w_after = w0 + g @ total
    results = []
    for c in contacts:
        p_n = float(total[c.normal])
        active = p_n > 0.0
        results.append(ContactOutcome(
            active=active,
            regime="frictionless" if active else "separate",
            impulse_normal=p_n,
            impulse_tangent=tuple(0.0 for _ in c.tangents),
            residual=max(0.0, -float(w_after[c.normal]))
            + max(0.0, -p_n) * float(g[c.normal, c.normal]),
        ))
    return MultipleImpactOutcome(
        law="dispersion",
        impulses=total,
        w_before=w0,
        w_after=w_after,
        contacts=tuple(results),
        residual=max([r.residual for r in results] + [held_residual(held, w_after)]),
        flags=tuple(flags),
        stages=tuple(stages),
    )


#: The largest correction of the impulses' scale taken as the integration's error (it is of
#: the order of ``rtol``); a larger one is left alone, and a gain shows as ``energy_gain``.
ENERGY_SCALE_LIMIT = 1e-9


def _energy_consistent_scale(total: np.ndarray, w: np.ndarray, g: np.ndarray,
                             lost: float) -> float:
    """The factor ``lam`` on the phases' row impulses ``total`` that makes the kinetic energy
    fall by exactly ``lost`` (J), the law's own loss: ``lam a + lam^2 b / 2 = -lost`` with
    ``a = total . w``, ``b = total . G total`` (the larger root; with ``lost = 0``,
    ``lam = -2 a / b``).

    Why: under the law ``K + sum E_i + lost`` is constant, so an elastic impact (every e = 1)
    conserves K exactly; the integration's error (1e-13 to 1e-12 of the impulses, largest where
    a Hertz contact opens, ``F ~ delta^1.5``) showed as a gain of 1e-12 of K, flagged
    ``energy_gain``. The factor is 1 to that error; one further from 1 than
    :data:`ENERGY_SCALE_LIMIT` is not an integration error and is not applied (1.0 returned).

    One contact, ``G = 2``, ``w = -1``: the elastic impulse is 1 N s. An integrated 1 + 1e-12
    is brought back to 1; 1.01 is no integration error and is left:

    >>> g = np.array([[2.0]]); w = np.array([-1.0])
    >>> lam = _energy_consistent_scale(np.array([1.0 + 1e-12]), w, g, 0.0)
    >>> round(lam * (1.0 + 1e-12), 15)
    1.0
    >>> _energy_consistent_scale(np.array([1.01]), w, g, 0.0)
    1.0
    """
    a = float(total @ w)
    b = float(total @ g @ total)
    if not (b > 0.0 and a < 0.0 and lost >= 0.0):
        return 1.0
    lam = (-a + np.sqrt(max(a * a - 2.0 * b * lost, 0.0))) / b
    return float(lam) if abs(lam - 1.0) <= ENERGY_SCALE_LIMIT else 1.0


def _stored(k: np.ndarray, p: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The energy held by apparent indentations ``d``: ``k d^(p+1) / (p+1)`` (J), 0 for a gap."""
    return k * np.maximum(d, 0.0) ** (p + 1.0) / (p + 1.0)


def _integrate(
    s: np.ndarray,
    w_c: np.ndarray,
    k: np.ndarray,
    p: np.ndarray,
    e2: np.ndarray,
    rtol: float,
    tol: float,
    max_phases: int,
    approach: bool = False,
) -> tuple[list[tuple[tuple[int, ...], np.ndarray]], bool, float]:
    """Integrate the phases; each phase's contacts under load and its contact impulses, and
    the energy the law dissipated (J): ``1 - e^2`` of what an expanding contact releases, and
    what a contact holds when it is emptied at once (e = 0, or round-off at its opening)."""
    n = len(w_c)
    mode = np.full(n, _LOAD)
    delta = np.zeros(n)
    impulse = np.zeros(n)
    v_max = float(np.max(-w_c))
    g_diag = np.maximum(np.diag(s), np.finfo(float).tiny)
    # time scale of one contact hitting at v_max: (1 / (k g v^(p-1)))^(1/(p+1))
    t_scale = float(np.max((1.0 / (k * g_diag * v_max ** (p - 1.0))) ** (1.0 / (p + 1.0))))
    p_scale = v_max / float(np.min(g_diag))
    atol = np.concatenate([np.full(n, 1e-15 * p_scale), np.full(n, 1e-15 * v_max * t_scale)])
    lost = 0.0
    phases: list[tuple[tuple[int, ...], np.ndarray]] = []
    eps_delta = 1e-13 * v_max * t_scale
    # round-off in a row velocity at an event (brentq places the root to 4 ulp of the phase's
    # time, and w is a sum over the rows)
    eps_w = 1e-12 * v_max
    # The impact is over when no contact approaches and what is left compressed is below
    # 1e-9 of the deformation scale (its energy below 1e-18 of the kinetic energy): a chain
    # that ends as a cluster rattles on in ever smaller phases (an inelastic collapse).
    delta_done = 1e-9 * v_max * t_scale
    stalled = 0

    def force(d: np.ndarray) -> np.ndarray:
        return k * np.maximum(d, 0.0) ** p

    while len(phases) < max_phases:
        w_now = w_c + s @ impulse
        rate = np.where(mode == _EXPAND, 1.0 / np.maximum(e2, np.finfo(float).tiny), 1.0)

        def rhs(_t: float, y: np.ndarray, mode: np.ndarray = mode,
                rate: np.ndarray = rate) -> np.ndarray:
            w_y = w_c + s @ y[:n]
            d_delta = np.where(mode == _EXPAND, -w_y * rate, -w_y)
            if approach:  # an open contact holds no gap: it is pressed once it approaches
                d_delta = np.where((mode == _LOAD) & (y[n:] <= 0.0), np.maximum(d_delta, 0.0),
                                   d_delta)  # fmt: skip
            return np.concatenate([force(y[n:]), d_delta])

        events = []
        for i in range(n):
            if mode[i] == _LOAD:
                if delta[i] > 0.0 or (delta[i] == 0.0 and w_now[i] < -eps_w):
                    # loaded: compression ends when the contact stops approaching (emptied at
                    # e = 0 with w = -1e-16 past its event, a contact is not loaded again: its
                    # event fired at once, and phases of zero length ended in stage_limit)
                    events.append(_event(lambda _t, y, i=i: (w_c + s @ y[:n])[i], +1, i, "w"))
                else:
                    # open, a gap delta < 0: a new phase once it closes (then it is loaded);
                    # the event waits for delta = eps so a contact closed at rest (delta = 0)
                    # does not end a phase of zero length
                    events.append(_event(lambda _t, y, i=i: y[n + i] - eps_delta, +1, i,
                                         "close"))
            else:
                events.append(_event(lambda _t, y, i=i: y[n + i], -1, i, "open"))
                events.append(_event(lambda _t, y, i=i: (w_c + s @ y[:n])[i], -1, i, "w"))
        # the span: long enough for the slowest open gap to close at its present rate (with
        # no contact loaded nothing changes the rates, and a gap closing at 1e-5 of v_max
        # outlasts a span fixed in t_scale)
        span = 1e4 * t_scale
        for i in range(n):
            if mode[i] == _LOAD and delta[i] < 0.0 and w_now[i] < 0.0:
                span = max(span, 2.0 * (eps_delta - delta[i]) / -w_now[i])
        # imported here: SciPy's integrators cost 0.25 s at start-up, and of the solve
        # only this law uses them
        from scipy.integrate import solve_ivp

        sol = solve_ivp(rhs, (0.0, span), np.concatenate([impulse, delta]),
                        method="DOP853", rtol=rtol, atol=atol, events=events)
        y_end = sol.y[:, -1]
        # an expanding contact gives back e^2 of what it releases and loses the rest (d K =
        # w dP = -F d delta / rate = -e^2 dE), in closed form from its energy at both ends
        released = _stored(k, p, delta) - _stored(k, p, y_end[n:])
        lost += float(np.sum(np.where(mode == _EXPAND, (1.0 - e2) * released, 0.0)))
        dp = y_end[:n] - impulse
        # under load: pressed at the start, or pressed during the phase (a gap closing up to
        # the event at eps_delta takes an impulse of 1e-13 of the scale: dropped, the total
        # was not the integrated one and the energy's factor missed it)
        loaded = tuple(int(i) for i in range(n) if mode[i] == _EXPAND or delta[i] > 0.0
                       or (delta[i] == 0.0 and w_now[i] < -eps_w) or dp[i] != 0.0)
        phases.append((loaded, dp))
        impulse = y_end[:n].copy()
        delta = y_end[n:].copy()
        if sol.status != 1:
            return phases, False, lost  # ran to the end of the time span: not converged
        held_before = float(np.sum(_stored(k, p, delta)))
        fired = [ev for ev, t in zip(events, sol.t_events, strict=True) if len(t)]
        switched = set()
        for ev in fired:
            i = ev.contact
            if ev.kind == "close":
                continue
            switched.add(i)
            if ev.kind == "open":
                mode[i], delta[i] = _LOAD, 0.0
            elif mode[i] == _LOAD:
                _end_compression(i, mode, delta, e2)
            else:
                mode[i] = _LOAD  # compressed again before it opened
        w_now = w_c + s @ impulse
        _simultaneous_switches(switched, mode, delta, e2, w_now, s @ force(delta),
                               eps_w, eps_delta)
        lost += held_before - float(np.sum(_stored(k, p, delta)))  # emptied at once
        if np.all(delta <= delta_done) and np.all(w_now >= -tol):
            return phases, True, lost + float(np.sum(_stored(k, p, delta)))
        # a phase of zero length (an event firing at once, w = 0 to round-off) three times in a
        # row: the integration makes no progress
        stalled = stalled + 1 if sol.t[-1] == 0.0 else 0
        if stalled >= 3:
            return phases, False, lost
    return phases, False, lost


def _end_compression(i: int, mode: np.ndarray, delta: np.ndarray, e2: np.ndarray) -> None:
    """Contact ``i`` stops approaching: it expands, or with e = 0 loses its stored energy."""
    if e2[i] == 0.0:
        delta[i] = 0.0  # e = 0: the stored energy is lost, the contact opens
    else:
        mode[i] = _EXPAND


def _simultaneous_switches(
    switched: set[int],
    mode: np.ndarray,
    delta: np.ndarray,
    e2: np.ndarray,
    w: np.ndarray,
    dw: np.ndarray,
    eps_w: float,
    eps_delta: float,
) -> None:
    """Switch the contacts whose own event falls at the phase's end to round-off.

    Why: solve_ivp ends a phase at the first terminal event and reports only the events whose
    roots it placed before that one. Two contacts reaching the end of compression at the same
    instant (a box landing flat on four corners with equal stiffness: a tie by symmetry, or
    to 1e-16 with a tiny tilt) fire one event; the other contact, its velocity 1e-16 past zero,
    was left loading and gave back its energy elastically (a box at e = 0 left at 0.35 m/s) or
    started a phase of zero length (flagged ``stage_limit``). A contact is switched here when
    its state is that of its event to within ``eps_w`` (m/s) or ``eps_delta`` and its velocity
    moves on the event's side (``dw`` = d w / d tau, so a contact just compressed again, its
    ``w`` 1e-17 below zero and falling, stays loaded).
    """
    for i in range(len(mode)):
        if i in switched:
            continue
        if mode[i] == _LOAD:
            if delta[i] > 0.0 and (w[i] > 0.0 or (w[i] >= -eps_w and dw[i] > 0.0)):
                _end_compression(i, mode, delta, e2)
        elif delta[i] <= eps_delta and w[i] >= 0.0:
            mode[i], delta[i] = _LOAD, 0.0  # the energy given back: open
        elif w[i] < 0.0 and (w[i] < -eps_w or dw[i] < 0.0):
            mode[i] = _LOAD  # compressed again before it opened


class _Event:
    """A solve_ivp event that ends the phase, with the contact and kind it belongs to."""

    terminal = True

    def __init__(self, fun: object, direction: float, contact: int, kind: str) -> None:
        self.fun = fun
        self.direction = direction
        self.contact = contact
        self.kind = kind

    def __call__(self, t: float, y: np.ndarray) -> float:
        return float(self.fun(t, y))  # type: ignore[operator]


def _event(fun: object, direction: float, contact: int, kind: str) -> _Event:
    return _Event(fun, direction, contact, kind)

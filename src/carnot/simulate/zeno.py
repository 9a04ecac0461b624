"""Zeno: infinitely many impacts in finite time, summed instead of stepped through.

A body bouncing on a plane with its velocity changed only along the normal (a sphere, or a
body that does not turn, with no slip at the contact or no friction), under constant gravity
with ``g_n = n . g < 0`` and no ground motion, rebounds with the same coefficient ``e`` each
time: the normal rebound speeds ``u_k`` form a geometric series, and so do the flight times
``tau_k = 2 u_k / |g_n|``. Once three impacts in a row show it (the same feature, the same
ratio to 1e-9, only flight between them), the series is summed (for a ball dropped from rest
this is ``t_inf = t_1 (1 + e)/(1 - e)``):

    t_inf = t_k + 2 u_k / (|g_n| (1 - e))

At ``t_inf`` the body is in contact with zero normal velocity; the tangential motion has gone
on as in free flight (the impacts do not touch it). The energy of the rest of the series is
accounted two ways: directly, the mechanical energy after impact ``k`` minus that at
``t_inf``; and by the theorem summed over the series,
``sum_j 1/2 m_n (1 - e^2) (e^j u_k)^2 = 1/2 m_n u_k^2`` with ``m_n = P_n / (w_n'' - w_n')`` the
effective mass of the last impact.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from carnot.simulate.events import Feature
from carnot.simulate.motion import BodyState, quat_about, quat_multiply

#: Relative agreement of successive restitution ratios that identifies the geometric series.
RATIO_TOLERANCE = 1e-9
#: The same for a rocking block: its pivot phases are integrated (the pivot drifts by the
#: integrator's tolerance, and the ratio with it, by about 1e-9 per impact).
ROCK_RATIO_TOLERANCE = 1e-7


@dataclass(frozen=True, kw_only=True)
class BounceRecord:
    """An impact as the Zeno test reads it: time (s), the single feature, normal relative
    speed before (< 0) and after (m/s), whether the velocity changed only along the normal,
    the normal impulse (N s), and whether only free flight preceded it since the last one."""

    time: float
    feature: Feature
    normal_before: float
    normal_after: float
    normal_only: bool
    normal_impulse: float
    flight_before: bool


@dataclass(frozen=True, kw_only=True, eq=False)
class Accumulation:
    """The summed series: accumulation time ``t_inf`` (s), state there, the ratio ``e``, the
    energy of the series by the theorem (J) and the start time of the series (s)."""

    time: float
    state: BodyState
    ratio: float
    dissipated_theorem: float
    start: float


#: What :func:`bounce` reads of an impact: ``(dv, dw, normal, w_before, w_after, P_n)``.
BounceMotion = tuple[Sequence[float], Sequence[float], Sequence[float], Sequence[float],
                     Sequence[float], float]


def _dot(a: Sequence[float], b: Sequence[float]) -> float:
    """``a . b`` of two 3-vectors of floats (written out: it runs at every impact)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def bounce(records: list[BounceRecord], *, time: float, feature: Feature, sphere: bool,
           size: float, spin: Sequence[float], state: Callable[[], BodyState],
           motion: Callable[[], BounceMotion], flight: bool,
           gravity: np.ndarray, ground: bool) -> Accumulation | None:  # fmt: skip
    """Record an impact of one feature on a plane in ``records`` (the last three kept) and
    :func:`detect` the accumulation after it. ``spin``: the body's angular velocity after it
    (rad/s); ``state()``: its state after it; ``motion()``: the velocity change ``dv`` (m/s),
    the angular velocity change ``dw`` (rad/s), the contact's unit normal, the relative
    velocity there before and after (m/s) and the normal impulse (N s). ``size`` (m): the
    body's length scale. A spinning polyhedron's impact is no bounce of a series (its
    velocity does not change along the normal only): the records are forgotten, and
    ``motion`` and ``state`` are not called."""
    if not sphere and _dot(spin, spin) != 0.0:
        # forgetting the records is the same as keeping this one, which would bar a series
        # until three more came after it
        records.clear()
        return None
    dv, dw, n, w_before, w_after, impulse = motion()
    along = _dot(n, dv)
    scale = math.sqrt(_dot(dv, dv)) + 1e-300
    across = math.sqrt((dv[0] - along * n[0]) ** 2 + (dv[1] - along * n[1]) ** 2
                       + (dv[2] - along * n[2]) ** 2)  # fmt: skip
    normal_only = (across <= 1e-12 * scale and math.sqrt(_dot(dw, dw)) <= 1e-12 * scale / size
                   and (sphere or _dot(spin, spin) == 0.0))  # fmt: skip
    records.append(BounceRecord(
        time=time, feature=feature, normal_before=_dot(n, w_before),
        normal_after=_dot(n, w_after), normal_only=normal_only,
        normal_impulse=float(impulse or 0.0), flight_before=flight))  # fmt: skip
    del records[:-3]
    last = records[-1]
    if not (last.normal_before < 0 and 0 < last.normal_after / -last.normal_before < 1):
        return None  # (what detect answers then, at once: no rebound ratio e in (0, 1))
    return detect(records, state(), np.asarray(n, dtype=float), gravity, ground)


def detect(records: list[BounceRecord], state: BodyState, normal: np.ndarray,
           gravity: np.ndarray, ground: bool) -> Accumulation | None:  # fmt: skip
    """The accumulation after the last impact of ``records`` (``state``: just after it), or
    None when the last three impacts are not a geometric series (module docstring)."""
    if ground or len(records) < 3:
        return None
    last = records[-3:]
    g_n = float(normal @ gravity)
    if g_n >= 0 or any(r.feature != last[-1].feature or not r.normal_only for r in last):
        return None
    if not all(r.flight_before for r in last[1:]):
        return None
    ratios = [r.normal_after / -r.normal_before for r in last if r.normal_before < 0]
    if len(ratios) < 3 or not 0 < ratios[-1] < 1:
        return None
    if max(ratios) - min(ratios) > RATIO_TOLERANCE * ratios[-1]:
        return None
    e = ratios[-1]
    u = last[-1].normal_after
    remaining = 2 * u / (-g_n * (1 - e))
    v = state.velocity
    v_t = v - (normal @ v) * normal
    g_t = gravity - g_n * normal
    position = state.position + v_t * remaining + 0.5 * g_t * remaining**2
    w = state.angular_velocity
    speed = float(np.linalg.norm(w))
    q = state.orientation
    if speed > 0:
        q = quat_multiply(quat_about(w / speed, np.array(speed * remaining)), q)
    end = BodyState(position=position, orientation=q / np.linalg.norm(q),
                    velocity=v_t + g_t * remaining, angular_velocity=w.copy())  # fmt: skip
    last_jump = last[-1].normal_after - last[-1].normal_before
    m_n = last[-1].normal_impulse / last_jump
    return Accumulation(time=last[-1].time + remaining, state=end, ratio=e,
                        dissipated_theorem=0.5 * m_n * u * u, start=last[-1].time)  # fmt: skip


# --- a rocking block coming to rest ----------------------------------------------------------
# G. W. Housner, Bull. Seismol. Soc. Am. 53 (1963) 403-417: a block rocking on two corners
# keeps the ratio r of its angular velocity at each impact (1 - 3/2 sin^2 alpha for a
# rectangle); between impacts it pivots on one corner, rising by conservation of energy and
# coming back to the crossing with the same speed. The impacts accumulate: the angular
# velocities after them are omega r^j, and the time to rest is the sum of the half cycles.


@dataclass(frozen=True, kw_only=True)
class RockRecord:
    """An impact as the rocking test reads it: time (s), its single feature (a corner), the
    ratio ``omega''/omega'`` of the angular velocity about the lamina's normal, and whether
    only pivoting on one sticking corner preceded it since the last impact."""

    time: float
    feature: Feature
    ratio: float
    pivoting: bool


def half_cycle(omega: float, p2: float, alpha: float) -> float:
    """The time (s) a block pivoting on a corner takes from the crossing (both corners down)
    with angular velocity ``omega`` (rad/s) up to its turning angle ``theta_m`` and back:
    ``2 int_0^theta_m dtheta / theta'``, ``theta'^2 = 2 p^2 (cos(alpha - theta_m) -
    cos(alpha - theta))`` (energy; ``p^2 = m g R / I_O``, ``alpha`` the angle of the centre of
    mass from the vertical over the corner, ``cos(alpha - theta_m) = cos alpha +
    omega^2 / (2 p^2)``). With ``s = theta_m - theta`` the integrand is ``s^-1/2`` times a
    smooth function, integrated by QUADPACK's algebraic weight (``scipy.integrate.quad``,
    ``weight="alg"``). Small ``omega``: ``2 omega / (p^2 sin alpha)`` (a constant
    deceleration). Infinite when the block would pass over the corner.

    >>> p2, alpha = 3 * 9.81 / (4 * 0.5099), 0.1974
    >>> small = half_cycle(1e-4, p2, alpha)
    >>> round(float(small / (2e-4 / (p2 * np.sin(alpha)))), 6)
    1.0
    """
    from scipy.integrate import quad
    from scipy.optimize import brentq

    rise = omega * omega / (2 * p2)  # cos(alpha - theta_m) - cos alpha
    if np.cos(alpha) + rise >= 1.0:
        return float("inf")
    # theta_m from 2 sin(alpha - theta_m/2) sin(theta_m/2) = rise: no cancellation however
    # small the rise (alpha - arccos(cos alpha + rise) loses every digit below 1e-16)
    top = float(brentq(lambda x: 2 * np.sin(alpha - x / 2) * np.sin(x / 2) - rise, 0.0, alpha,
                       xtol=1e-300, rtol=8.9e-16))  # fmt: skip
    if top == 0.0:
        return 0.0

    def smooth(s: float) -> float:
        # sin(s/2)/s = sinc(s / 2 pi) / 2: no 0/0 at the turning point
        return 1.0 / np.sqrt(4 * p2 * np.sin(alpha - top + s / 2) * 0.5 * np.sinc(s / (2 * np.pi)))

    value, _ = quad(smooth, 0.0, top, weight="alg", wvar=(-0.5, 0.0), epsabs=0.0,
                    epsrel=1e-13, limit=200)  # fmt: skip
    return 2 * float(value)


def rocking_series(omega: float, ratio: float, p2: float, alpha: float) -> float:
    """``sum_j half_cycle(omega r^j)`` (s): each term by :func:`half_cycle` until it agrees
    with its small-angle form ``2 omega_j / (p^2 sin alpha)`` to 1e-13, the rest of the series
    then summed in that form, ``2 omega_J / (p^2 sin alpha (1 - r))``.

    >>> p2, alpha = 3 * 9.81 / (4 * 0.5099), 0.1974
    >>> tiny = rocking_series(1e-9, 0.9, p2, alpha)
    >>> round(float(tiny / (2e-9 / (p2 * np.sin(alpha) * 0.1))), 9)
    1.0
    """
    total = 0.0
    w = omega
    linear = 2.0 / (p2 * np.sin(alpha))
    for _ in range(100_000):
        if w == 0.0:
            return total
        term = half_cycle(w, p2, alpha)
        if abs(term / (linear * w) - 1.0) <= 1e-13:
            return total + linear * w / (1.0 - ratio)
        total += term
        w *= ratio
    return total + linear * w / (1.0 - ratio)  # pragma: no cover - r < 1 ends it first


def detect_rocking(records: list[RockRecord], body_mass: float, inertia_world: np.ndarray,
                   normal: np.ndarray, state: BodyState, pivot: np.ndarray,
                   other: np.ndarray, gravity: np.ndarray, kinetic: float,
                   theorem_fraction: float) -> Accumulation | None:  # fmt: skip
    """The rest of a rocking block's impacts summed, after the last of ``records`` (``state``:
    just after it, pivoting on ``pivot``, the other corner ``other``, both world points on
    the ground; ``normal``: the lamina's normal, world; ``kinetic``: its kinetic energy just
    after, J; ``theorem_fraction``: ``E_d / T'`` of that impact by the theorem), or None
    unless the last three impacts alternate between the two corners with the same ratio (to
    1e-7), with pivoting on one sticking corner between them, and the two corners are
    symmetric about the vertical through the centre of mass (the same ``R`` and ``alpha``,
    to 1e-6).

    At ``t_inf = t_k + sum_j half_cycle(omega_k r^j)`` the block rests on both corners where
    it was at impact ``k``. The energy of the series is ``T_k`` (all the kinetic energy);
    by the theorem, ``sum_j q (1 - q)^j T_k`` with ``q`` the last impact's fraction."""
    if len(records) < 3:
        return None
    a, b, c = records[-3:]
    if not (a.feature == c.feature != b.feature and b.pivoting and c.pivoting):
        return None
    ratios = [a.ratio, b.ratio, c.ratio]
    r = c.ratio
    if not 0 < r < 1 or max(ratios) - min(ratios) > ROCK_RATIO_TOLERANCE * r:
        return None
    g = float(np.linalg.norm(gravity))
    if g == 0:
        return None
    up = -gravity / g
    arms = []
    for point in (pivot, other):
        d = state.position - point
        size = float(np.linalg.norm(d))
        if abs(float(d @ normal)) > 1e-9 * size:
            return None
        arms.append((size, float(np.arctan2(np.linalg.norm(d - (d @ up) * up), d @ up))))
    (radius, alpha), (radius2, alpha2) = arms
    # symmetric to 1e-6: the corners' positions carry the contact phases' drift (1e-9 m)
    if abs(radius - radius2) > 1e-6 * radius or abs(alpha - alpha2) > 1e-6 or not (
            0 < alpha < np.pi / 2):  # fmt: skip
        return None
    w = state.angular_velocity
    d = state.position - pivot
    if float(np.cross(w, d) @ up) <= 0:  # the centre of mass must rise over the new pivot
        return None
    inertia_pivot = float(normal @ inertia_world @ normal) + body_mass * radius * radius
    p2 = body_mass * g * radius / inertia_pivot
    omega = abs(float(w @ normal))
    if np.cos(alpha) + omega * omega / (2 * p2) >= 1.0:
        return None  # it passes over the corner: no series
    span = rocking_series(omega, r, p2, alpha)
    end = BodyState(position=state.position.copy(), orientation=state.orientation.copy(),
                    velocity=np.zeros(3), angular_velocity=np.zeros(3))  # fmt: skip
    q = theorem_fraction
    return Accumulation(time=c.time + span, state=end, ratio=r,
                        dissipated_theorem=kinetic * q / (1.0 - (1.0 - q)) if q > 0 else 0.0,
                        start=c.time)  # fmt: skip

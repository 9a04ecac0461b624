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

from dataclasses import dataclass

import numpy as np

from carnot.simulate.events import Feature
from carnot.simulate.motion import BodyState, quat_about, quat_multiply

#: Relative agreement of successive restitution ratios that identifies the geometric series.
RATIO_TOLERANCE = 1e-9


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

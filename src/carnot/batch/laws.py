"""Contact-space laws of the batch kernels (frictionless and stick), and their registry.

Written once for :mod:`carnot.batch.ops`. Every law has one signature, in the contact frame
``(n, t1, t2)`` of :mod:`carnot.batch.contact_space`:

    law(k, w, e, mu) -> (p_n, p_1, p_2, regime, p_c, W_nc, W_nr, W_tc, W_tr, law_flags)

``k = (k_nn, k_n1, k_n2, k_11, k_12, k_22)`` the contact's inverse mass (1/kg), ``w = (w_n,
w_1, w_2)`` the relative velocity before (m/s), ``e`` the restitution coefficient, ``mu``
Coulomb's coefficient; out come the impulse ``a`` receives (N s), the regime code (below),
the normal impulse at maximum compression ``p_c`` and the works of the normal and tangential
impulses in compression and restitution (J; NaN where the law defines no impulse-space
process: frictionless and stick here), and a bit mask of law-specific warnings.

* ``frictionless`` (Newton, Poisson and Stronge coincide without friction):
  ``p_n = -(1 + e) w_n / k_nn``.
* ``stick`` (paper section 3.1: no slip after the impact, Newton's e in the normal
  direction): ``K P = w'' - w'`` with ``w'' = (-e w_n, 0, 0)``, solved by Cholesky.

Coulomb friction (slip, stick, reversal, under the three hypotheses) lives in
:mod:`carnot.batch.coulomb` with the same signature.

A uniform ball of 0.5 kg (``k_tt = 1/m + r^2/J = 2 + 5``) landing at 1 m/s while sliding
at 1 m/s: ``p_n = (1 + e) |w_n| m`` and ``P_t = -w_t / k_tt``.

>>> out = stick((2.0, 0.0, 0.0, 7.0, 0.0, 7.0), (-1.0, 1.0, 0.0), 0.5, 0.0)
>>> [round(float(x), 12) for x in out[:4]]
[0.75, -0.142857142857, 0.0, 1.0]
"""

from __future__ import annotations

import math
from typing import Any

from carnot.batch.ops import formula

#: Regime codes of the batch results (stable: they are written to files).
FRICTIONLESS, STICK = 0, 1
#: Coulomb friction (:mod:`carnot.batch.coulomb`), named as ``FrictionalImpulse.regime``
#: names the phases: ``slip`` throughout; slip that stopped and then stuck; slip that stopped
#: and resumed in the opposite direction (``reversal``) or in another one (``redirected``,
#: 3D); ``none``: not approaching, no impulse. A Coulomb contact that never slipped (at rest in
#: the tangent plane, inside the cone) is ``STICK``.
SLIP, SLIP_STICK, SLIP_REVERSAL, SLIP_REDIRECTED, NONE = 2, 3, 4, 5, 6

#: Regime names by code.
REGIME_NAMES: dict[int, str] = {
    FRICTIONLESS: "frictionless", STICK: "stick", SLIP: "slip", SLIP_STICK: "slip-stick",
    SLIP_REVERSAL: "slip-reversal", SLIP_REDIRECTED: "slip-redirected", NONE: "none",
}  # fmt: skip


NAN = math.nan


@formula
def frictionless(k: Any, w: Any, e: Any, mu: Any) -> Any:
    p_c = -w[0] / k[0]
    p_n = (1.0 + e) * p_c
    zero = 0.0 * p_n
    return (p_n, zero, zero, FRICTIONLESS + zero, p_c, NAN + zero, NAN + zero,
            NAN + zero, NAN + zero, zero)  # fmt: skip


@formula
def stick(k: Any, w: Any, e: Any, mu: Any) -> Any:
    # K = L D L^T (unit lower L, no square roots: a shorter chain than Cholesky's), then
    # forward, diagonal and back solves
    d0 = k[0]
    i0 = 1.0 / d0
    l10 = k[1] * i0
    l20 = k[2] * i0
    d1 = k[3] - l10 * k[1]
    i1 = 1.0 / d1
    l21 = (k[4] - l20 * k[1]) * i1
    d2 = k[5] - l20 * k[2] - l21 * (k[4] - l20 * k[1])
    i2 = 1.0 / d2
    b0, b1, b2 = -(1.0 + e) * w[0], -w[1], -w[2]
    y1 = b1 - l10 * b0
    y2 = b2 - l20 * b0 - l21 * y1
    p2 = y2 * i2
    p1 = y1 * i1 - l21 * p2
    p_n = b0 * i0 - l10 * p1 - l20 * p2
    zero = 0.0 * p_n
    return (p_n, p1, p2, STICK + zero, NAN + zero, NAN + zero, NAN + zero, NAN + zero,
            NAN + zero, zero)  # fmt: skip

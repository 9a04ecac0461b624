"""Coulomb's cone at impact, one contact in scalar operations: its projection and the law's
residual, each written once for every route that checks or solves the law.

The cone of a contact is ``K = {(p_n, p_t): |p_t| <= mu p_n}`` (N s): with ``mu = 0`` the ray
``p_n >= 0, p_t = 0``; with ``mu = inf`` (a contact *told to stick*) the half-space
``p_n >= 0``, whose loaded points keep their tangent and whose others go to zero. The law's
residual is the natural map of De Saxce's form, the measure Siconos reports for its ``fc3d``
solvers (``fc3d_compute_error.c``)::

    r = |P - proj_K(P - rho v_hat)| / rho   (m/s),   v_hat = (v_n + mu |w_t|, w_t),

with ``v_n = w_n'' + e w_n'`` (Newton's restitution folded into the normal velocity),
``w_t = w_t''`` and ``rho = 1 / G_nn``; it is zero exactly when Signorini's condition and
Coulomb's law hold.

Why scalars written as plain Python: the rule is per contact, and a function of floats is
what both of carnot's compilers take as it stands. The contact-space law and its
certificates run these functions as Python (:func:`carnot.laws.multiple.rows.
contact_residual`: a few floats a contact, where NumPy's per-call cost on 3-vectors was most
of the time), and the compiled loops compile these same functions (Numba: the multi-contact
batch kernel's leaves, :mod:`carnot.batch.multi_kernel`; the iterative solver's projection
of every contact, :mod:`carnot.solvers.kernels`). So the rule has one statement, and it
gives the same bits wherever it runs (tests/test_cone.py holds the compiled and the Python
runs to each other and the projection to its definition, the nearest point of the cone).

>>> project_onto_cone(0.0, 2.0, 0.0, 1.0)
(1.0, 1.0, 0.0)
>>> contact_law_residual(True, False, 0.5, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
0.0
"""

from __future__ import annotations

import math


def project_onto_cone(x_n: float, x_1: float, x_2: float, mu: float
                      ) -> tuple[float, float, float]:  # fmt: skip
    """The Euclidean projection of ``(x_n, x_1, x_2)`` on the cone ``{|p_t| <= mu p_n}``
    (exact and circular; ``mu = 0`` the ray ``p_n >= 0``; ``mu = inf`` the half-space of a
    contact told to stick: ``(max(x_n, 0), x_t)`` where ``x_n > 0``, else zero). A contact
    with one tangent row passes ``x_2 = 0``, none ``x_1 = x_2 = 0``.

    Inside the cone the point is kept; in its polar cone (``mu |x_t| <= -x_n``) it goes to
    the apex; otherwise to the surface, ``p_n = (x_n + mu |x_t|) / (1 + mu^2)`` and
    ``p_t = mu p_n x_t / |x_t|``.

    >>> project_onto_cone(-1.0, 0.0, 0.0, 0.0), project_onto_cone(2.0, 3.0, 4.0, math.inf)
    ((0.0, 0.0, 0.0), (2.0, 3.0, 4.0))
    >>> project_onto_cone(1.0, 0.0, 2.0, 0.5)
    (1.6, 0.0, 0.8)
    """
    if math.isinf(mu):
        # told to stick: the half-space; loaded, the tangent kept, else zero
        p_n = 0.0 if x_n < 0.0 else x_n  # (NumPy's maximum(x_n, 0): NaN kept)
        if not x_n > 0.0:
            return p_n, 0.0, 0.0
        return p_n, x_1, x_2
    nt = math.sqrt(x_1 * x_1 + x_2 * x_2)
    # (x_n >= 0: a frictionless contact, mu = 0 with no tangent rows, has nt = 0 <= mu x_n
    # for every x_n, a pull included; at x = 0, inside and polar agree)
    mu_nt = mu * nt
    inside = nt <= mu * x_n and x_n >= 0.0
    if inside:
        return x_n, x_1, x_2
    polar = mu_nt <= -x_n
    a = (x_n + mu_nt) / (1.0 + mu * mu)
    p_n = 0.0 if polar else a
    # (the tangent's scale: 0 in the polar cone or with no tangent, mu a / nt on the
    # surface, where nt is positive)
    scale = 0.0 if (polar or nt == 0.0) else mu * a / nt
    return p_n, x_1 * scale, x_2 * scale


def contact_law_residual(takes_part: bool, frictionless: bool, mu: float, rho: float,
                         p_n: float, p_1: float, p_2: float,
                         v_n: float, w_1: float, w_2: float) -> float:  # fmt: skip
    """The complementarity residual of one contact (m/s): zero exactly when its law holds.

    ``P = (p_n, p_1, p_2)`` its impulse (N s), ``v_n = w_n'' + e w_n'`` and ``(w_1, w_2)``
    its post-impact tangent velocity (m/s), ``rho = 1 / G_nn`` (kg); absent tangent rows
    pass zeros. A contact that does not take part (separating before) must receive nothing:
    ``|P| / rho``. A frictionless one: Signorini on the normal, nothing on the tangents,
    ``max(|min(p_n / rho, v_n)|, |p_t| / rho)``. One told to stick (``mu = inf``): Signorini
    and, loaded, ``|w_t''|``. Otherwise the natural map of the module docstring.

    >>> contact_law_residual(True, True, 0.0, 2.0, 1.0, 0.0, 0.0, 0.25, 0.0, 0.0)
    0.25
    >>> contact_law_residual(False, False, 0.5, 2.0, 0.0, 3.0, 4.0, 0.0, 0.0, 0.0)
    2.5
    """
    if not takes_part:
        return math.sqrt(p_n * p_n + p_1 * p_1 + p_2 * p_2) / rho
    if math.isinf(mu):
        normal = abs(min(p_n / rho, v_n))
        tangent = (math.sqrt(w_1 * w_1 + w_2 * w_2) if p_n > 0.0
                   else math.sqrt(p_1 * p_1 + p_2 * p_2) / rho)  # fmt: skip
        return max(normal, tangent)
    if frictionless:
        return max(abs(min(p_n / rho, v_n)), math.sqrt(p_1 * p_1 + p_2 * p_2) / rho)
    wt = math.sqrt(w_1 * w_1 + w_2 * w_2)
    q_n, q_1, q_2 = project_onto_cone(p_n - rho * (v_n + mu * wt), p_1 - rho * w_1,
                                      p_2 - rho * w_2, mu)  # fmt: skip
    d_n, d_1, d_2 = p_n - q_n, p_1 - q_1, p_2 - q_2
    return math.sqrt(d_n * d_n + d_1 * d_1 + d_2 * d_2) / rho

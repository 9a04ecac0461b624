"""Where the simultaneous law's enumeration finds no regime: a start from a smoothed law.

The simultaneous law (:mod:`carnot.laws.multiple.simultaneous`) enumerates regimes, and a
regime with contacts slipping in 3D needs a root of its slip angles, found by MINPACK from a
few starting directions. Where the answer slips slowly at several corners at once (a box
landing almost flat on uneven ground, sticking all round impossible by a hair: slip speeds of
1e-6 to 1e-4 of the impact's), those starts lie outside the root's basin and the enumeration
finds nothing, though an answer exists (the discrete frictional contact problem has a solution
whenever some velocity separates every contact strictly, as a free body's lift-off does:
Acary, Cadoux, Lemarechal and Malick, *A formulation of the linear discrete Coulomb friction
problem via convex optimization*, ZAMM 91, 2011, thm 3.3).

So before answering ``no_solution`` the law is smoothed and followed to the limit (a
homotopy; the smoothing of Fischer and Burmeister used by Chen and Mangasarian's smoothing
methods, *Math. Programming* 71, 1995; Siconos' ``fc3d`` solvers smooth Coulomb's law alike):

* Signorini-Newton: ``a + b - sqrt(a^2 + b^2 + 2 eps^2) = 0`` with ``a = G_nn P_n`` and
  ``b = w_n'' + e w_n'`` (m/s): at ``eps = 0`` exactly ``0 <= a  ⟂  b >= 0``;
* Coulomb: ``G_nn (P_t + mu P_n w_t'' / sqrt(|w_t''|^2 + eps^2)) = 0``: at ``eps = 0`` the impulse
  opposes the slip at the cone's edge; a sticking contact slips at a speed below ``eps``;
* told to stick: ``w_t'' = 0``; held rows: ``w_r'' = target``.

Each smoothed system is square and smooth; MINPACK's ``hybr`` (``scipy.optimize.root``, with
the exact Jacobian) solves it from the previous ``eps``'s answer, ``eps`` falling from the
velocity scale to 1e-10 of it (a step that fails is retried shorter). The result is only a
*start*: :func:`regime_of` reads its regime (separate, stick, slip and the slip directions)
and the law solves that regime exactly, to round-off, as any other.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from carnot.laws.multiple.rows import ContactRows, HeldRows

#: The smoothing ends at this fraction of the velocity scale (m/s relative): four orders
#: below the slowest slips it is there to resolve (1e-6), and no further, since a sticking
#: contact's smoothed law stiffens as ``1 / eps`` (its slip, about ``eps``, sets its impulse).
EPS_END = 1e-10
#: A contact slipping slower than this (relative to the velocity scale) at the end sticks.
STICK_BELOW = 1e-8
#: A smoothed system counts as solved when its residual (m/s) is below this fraction of the
#: velocity scale: a start, not an answer (the regime it names is then solved exactly).
SOLVED = 1e-6


def smoothed_impulses(
    delassus: np.ndarray,
    w_before: np.ndarray,
    contacts: Sequence[ContactRows],
    held: HeldRows | None,
    takes_part: Sequence[bool],
    scale: float,
) -> np.ndarray | None:
    """Row impulses (N s) solving the smoothed law at ``eps = EPS_END * scale``, followed
    from ``eps = scale``; None where the first smoothed system has no root.

    Two balls in a row, unit masses, the first at 1 m/s, ``e = 0``: both leave at 1/2 m/s,
    the impulse 1/2 N s (to the smoothing, 1e-10 of the scale):

    >>> p = smoothed_impulses(np.array([[2.0]]), np.array([-1.0]), [ContactRows(normal=0)],
    ...                       None, [True], 1.0)
    >>> round(float(p[0]), 9)
    0.5
    """
    g = np.asarray(delassus, dtype=float)
    w = np.asarray(w_before, dtype=float)
    blocks = [(c, [c.normal, *c.tangents] if c.kind != "frictionless" else [c.normal])
              for c, part in zip(contacts, takes_part, strict=True) if part]  # fmt: skip
    rows = [r for _, rs in blocks for r in rs] + (list(held.rows) if held is not None else [])
    if not rows:
        return np.zeros_like(w)
    index = np.array(rows)
    g_s = g[np.ix_(index, index)]
    w_s = w[index]
    n_rows = len(rows)

    def system(p: np.ndarray, eps: float) -> tuple[np.ndarray, np.ndarray]:
        u = w_s + g_s @ p
        f = np.empty(n_rows)
        jac = np.zeros((n_rows, n_rows))
        k = 0
        for c, rs in blocks:
            gnn = float(g[c.normal, c.normal])
            a = gnn * p[k]
            b = float(u[k]) + c.restitution * float(w[c.normal])
            q = math.sqrt(a * a + b * b + 2.0 * eps * eps)
            f[k] = a + b - q
            jac[k] = (1.0 - b / q) * g_s[k]
            jac[k, k] += (1.0 - a / q) * gnn
            t = slice(k + 1, k + len(rs))
            if len(rs) > 1 and c.kind == "told_to_stick":
                f[t] = u[t]
                jac[t] = g_s[t]
            elif len(rs) > 1:  # Coulomb, planar or 3D
                u_t = u[t]
                d2 = float(u_t @ u_t) + eps * eps
                r = math.sqrt(d2)
                s = u_t / r
                f[t] = gnn * (p[t] + c.friction * p[k] * s)  # (m/s, as the normal's)
                ds = (np.eye(len(u_t)) * d2 - np.outer(u_t, u_t)) / (d2 * r)
                jac[t] = gnn * c.friction * p[k] * (ds @ g_s[t])
                jac[t, t] += gnn * np.eye(len(u_t))
                jac[t, k] += gnn * c.friction * s
            k += len(rs)
        if held is not None:
            f[k:] = u[k:] - np.asarray(held.target, dtype=float)
            jac[k:] = g_s[k:]
        return f, jac

    # imported here: scipy.optimize costs 0.2 s at start-up, and only an impact whose 3D
    # slip the enumeration misses comes to this smoothing
    from scipy.optimize import root

    def solve(p: np.ndarray, eps: float) -> np.ndarray | None:
        sol = root(system, p, args=(eps,), jac=True, method="hybr", options={"xtol": 1e-13})
        good = float(np.max(np.abs(sol.fun))) <= SOLVED * scale
        return sol.x if good and np.all(np.isfinite(sol.x)) else None

    eps = scale
    p = solve(np.zeros(n_rows), eps)
    if p is None:
        return None
    factor = 10.0
    while eps > EPS_END * scale:
        trial = max(eps / factor, EPS_END * scale)
        nxt = solve(p, trial)
        if nxt is None:
            factor = math.sqrt(factor)  # a shorter step from the last answer
            if factor < 1.01:
                break  # stalled: the last answer may still show the regime
            continue
        p, eps = nxt, trial
        factor = min(factor * factor, 100.0)
    out = np.zeros_like(w)
    out[index] = p
    return out


def regime_of(
    delassus: np.ndarray,
    w_before: np.ndarray,
    contacts: Sequence[ContactRows],
    takes_part: Sequence[bool],
    impulses: np.ndarray,
    scale: float,
    edge: bool = False,
) -> tuple[tuple[str, ...], dict[int, np.ndarray]]:
    """The regime (the simultaneous law's pattern) and 3D slip directions of ``impulses``:
    a contact whose normal impulse is below 1e-9 of the scale separates; one slipping slower
    than :data:`STICK_BELOW` of the scale sticks; the others slip along their ``w_t''``.
    ``edge``: a 3D contact that would stick with its impulse within 1 % of the cone's edge
    slips instead (where the smoothing has not told a very slow slip from sticking).

    >>> g = np.eye(3); w = np.array([-1.0, 0.5, 0.0]); c = ContactRows(normal=0,
    ...     tangents=(1, 2), friction=0.1)
    >>> regime_of(g, w, [c], [True], np.array([1.0, -0.1, 0.0]), 1.0)[0]
    ('slip',)
    """
    w_after = w_before + delassus @ impulses
    pattern: list[str] = []
    directions: dict[int, np.ndarray] = {}
    for i, (c, part) in enumerate(zip(contacts, takes_part, strict=True)):
        if not part:
            pattern.append("out")
            continue
        if float(delassus[c.normal, c.normal]) * float(impulses[c.normal]) <= 1e-9 * scale:
            pattern.append("separate")
            continue
        if c.kind == "frictionless":
            pattern.append("closed")
            continue
        w_t = w_after[list(c.tangents)]
        speed = float(np.linalg.norm(w_t))
        at_edge = edge and c.kind == "spatial" and speed > 0.0 and float(
            np.linalg.norm(impulses[list(c.tangents)])) >= 0.99 * c.friction * float(
            impulses[c.normal])  # fmt: skip
        if c.kind == "told_to_stick" or (speed <= STICK_BELOW * scale and not at_edge):
            pattern.append("stick")
        elif c.kind == "planar":
            pattern.append("slip+" if w_t[0] > 0.0 else "slip-")
        else:
            pattern.append("slip")
            directions[i] = w_t / speed
    return tuple(pattern), directions

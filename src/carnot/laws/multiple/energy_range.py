"""The least and the most of a concave quadratic over a family of answers of any dimension.

A regime whose equations leave ``d`` impulses free has the answers ``z`` (``d`` numbers) of a
convex set ``F``: linear inequalities ``A z + c >= 0`` and second-order cones
``mu p_n(z) >= |p_t(z)|`` (``p_n = a_n + b_n . z``, ``p_t = a_t + B_t z``), ``z = 0`` a member.
Over it the dissipated energy is ``E(z) = e0 + e1 . z + z . E2 z`` with ``E2`` negative
semi-definite (``-1/2 L1^T G L1``, ``G`` the Delassus operator): concave.

* **The most** is a convex problem: maximized by SciPy's SLSQP (Kraft 1988), polished where
  ``F`` is a polytope by solving the active set's KKT system, with cones by Newton's method
  on it, and then *certified* apart from the solver: for multipliers ``mu_j >= 0``
  (non-negative least squares on the near-active constraints' gradients, SciPy's ``nnls``)
  the concave Lagrangian
  ``L = E + sum mu_j h_j`` (``h_j >= 0`` the constraints, each concave) bounds ``E`` on ``F``
  and lies below its tangent plane at the point ``z*`` found, so for every member
  ``E(z) <= E(z*) + mu . h(z*) + |grad L(z*)| R`` (``R`` the farthest member's distance from
  ``z*``, bounded by a box around ``F``): the most is between ``E(z*)`` (attained: ``z*`` is a
  member) and that bound (Boyd and Vandenberghe, *Convex Optimization*, 2004, sect. 5.5).
* **The least** is concave minimization: attained at an extreme point of ``F`` (Rockafellar,
  *Convex Analysis*, 1970, cor. 32.3.2). Where ``F`` is a polytope its vertices are enumerated:
  every ``d``-subset of the (distinct) constraints, solved and kept where it meets them all
  (a bounded count, :data:`MAX_SUBSETS`): the least is exact (to round-off). Where there are
  cones, the polytope with each cone's circumscribed 16-gon contains ``F``, and cutting planes
  tighten it (outer approximation: Hoffman 1981; Horst and Tuy 1996, ch. VI): its least
  vertex, where outside ``F``, is cut off by the tangent plane of the cone it violates most,
  and the new vertices are enumerated on the new plane alone; its least vertex value stays a
  certified lower bound. The attained value is the least ``E`` over members: those vertices
  pulled into ``F`` along the segment to ``z = 0`` (a member), the inscribed polygons'
  vertices, each refined by a local SLSQP minimization from it. Where the cuts (at most
  :data:`MAX_CUTS`) close the gap to 1e-9 of the energy scale the least is called exact;
  otherwise both are reported, so an exact least is never claimed where it is not proved.

``F`` unbounded (no vertex bounds it) or empty: None. The box around ``F`` comes from
``2 d`` linear programs (SciPy's HiGHS) over the outer polytope.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from scipy.optimize import linprog, minimize, nnls

#: The most ``d``-subsets of constraints a vertex enumeration solves (a bounded count); the
#: sides of a cone's polygons are chosen as many (up to :data:`MAX_SIDES`) as that allows.
MAX_SUBSETS, MIN_SIDES, MAX_SIDES = 60_000, 8, 16
#: The cutting planes at most that tighten the least's bound with cones (:func:`_cut`).
MAX_CUTS = 200

Cone = tuple[float, np.ndarray, np.ndarray, np.ndarray, float]  # a_n, b_n, a_t, B_t, mu


@dataclass(frozen=True, kw_only=True)
class EnergyRange:
    """The least and the most ``E`` (J) over ``F``: ``least`` and ``most`` are attained (the
    values at members), ``least_bound <= least`` and ``most_bound >= most`` certified (no
    member has less, or more); ``exact`` where both gaps are at round-off (a polytope whose
    vertices were all enumerated); ``points`` the two members attaining ``least`` and ``most``.
    """

    least: float
    most: float
    least_bound: float
    most_bound: float
    exact: bool
    points: tuple[np.ndarray, np.ndarray]


def energy(e0: float, e1: np.ndarray, e2: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``E(z) = e0 + e1 . z + z . E2 z`` (J) for ``z`` of shape ``(..., d)``.

    >>> float(energy(1.0, np.array([1.0, 0.0]), -np.eye(2), np.array([1.0, 2.0])))
    -3.0
    """
    return e0 + z @ e1 + np.einsum("...i,ij,...j->...", z, e2, z)


def _polygon(cones: list[Cone], sides: int, outer: bool,
             d: int) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The cones as linear inequalities ``A z + c >= 0``: each tangent plane's ``k``-gon,
    circumscribed about the circle ``|p_t| = mu p_n`` (``outer``: contains the cone) or
    inscribed in it (inside the cone); a cone of one tangent row is two inequalities, exact."""
    rows: list[np.ndarray] = []
    consts: list[float] = []
    for a_n, b_n, a_t, b_t, mu in cones:
        if len(a_t) == 1:
            dirs = np.array([[1.0], [-1.0]])
            factor = 1.0
        else:
            angle = 2.0 * math.pi * np.arange(sides) / sides
            dirs = np.stack([np.cos(angle), np.sin(angle)], axis=1)
            factor = 1.0 if outer else math.cos(math.pi / sides)
        # u . p_t <= f mu p_n  ->  (f mu b_n - B_t^T u) . z + (f mu a_n - u . a_t) >= 0
        rows.extend(factor * mu * b_n[None, :] - dirs @ b_t)
        consts.extend((factor * mu * a_n - dirs @ a_t).tolist())
    return np.array(rows).reshape(-1, d), np.array(consts)


def _distinct(a: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The inequalities scaled to unit rows (each slack a distance in ``z``), without those
    constant in ``z`` (kept by ``z = 0``) and without repeats (the same row and constant to
    1e-9 of the largest)."""
    norms = np.linalg.norm(a, axis=1)
    keep = norms > 1e-12 * max(float(norms.max(initial=0.0)), 1e-300)
    a, c, norms = a[keep], c[keep], norms[keep]
    a, c = a / norms[:, None], c / norms
    size = max(float(np.abs(c).max(initial=0.0)), 1e-300)
    key = np.round(np.column_stack([a, c / size]) * 1e9)
    _, first = np.unique(key, axis=0, return_index=True)
    first.sort()
    return a[first], c[first]


def _box(a: np.ndarray, c: np.ndarray) -> np.ndarray | None:
    """``[lo, hi]`` of each coordinate over ``A z + c >= 0`` (HiGHS), shape ``(2, d)``; None
    where a coordinate is unbounded or the set is empty."""
    d = a.shape[1]
    box = np.empty((2, d))
    for i in range(d):
        for side, sign in ((0, 1.0), (1, -1.0)):
            cost = np.zeros(d)
            cost[i] = sign
            res = linprog(cost, A_ub=-a, b_ub=c, bounds=[(None, None)] * d, method="highs")
            if res.status != 0:
                return None
            box[side, i] = res.x[i]
    return box


def _vertices(a: np.ndarray, c: np.ndarray, tol: float) -> np.ndarray | None:
    """Every vertex of ``{A z + c >= 0}`` (rows distinct, of unit norm): each ``d``-subset of
    the rows whose matrix is well conditioned (``|det| > 1e-10``), solved, kept where every
    row holds to ``tol``; None where the subsets are more than :data:`MAX_SUBSETS`."""
    m, d = a.shape
    if math.comb(m, d) > MAX_SUBSETS:
        return None
    if m < d:
        return np.zeros((0, d))
    subsets = np.array(list(combinations(range(m), d)), dtype=np.intp)
    mats, rhs = a[subsets], -c[subsets]
    # unit rows: |det| <= 1 (Hadamard), near 0 where the rows are near dependent
    ok = np.abs(np.linalg.det(mats)) > 1e-10
    if not ok.any():
        return np.zeros((0, d))
    z = np.linalg.solve(mats[ok], rhs[ok][..., None])[..., 0]
    feasible = np.all(z @ a.T + c >= -tol, axis=1)
    return z[feasible]


def _cut(a: np.ndarray, c: np.ndarray, verts: np.ndarray, row: np.ndarray, const: float,
         tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:  # fmt: skip
    """The polytope ``{A z + c >= 0}`` and its vertices with the row ``row . z + const >= 0``
    added (unit norm): the old vertices that meet it, and the new ones, each on the new row
    and ``d - 1`` old ones, solved and checked (incremental vertex enumeration); None where
    those subsets are more than :data:`MAX_SUBSETS`."""
    m, d = a.shape
    if math.comb(m, d - 1) > MAX_SUBSETS:
        return None
    a2, c2 = np.vstack([a, row]), np.append(c, const)
    kept = verts[verts @ row + const >= -tol]
    if d == 1:
        fresh = np.array([[-const / row[0]]])
    else:
        subsets = np.array(list(combinations(range(m), d - 1)), dtype=np.intp)
        mats = np.concatenate([a[subsets], np.broadcast_to(row, (len(subsets), 1, d))], axis=1)
        rhs = -np.concatenate([c[subsets], np.full((len(subsets), 1), const)], axis=1)
        ok = np.abs(np.linalg.det(mats)) > 1e-10
        fresh = np.linalg.solve(mats[ok], rhs[ok][..., None])[..., 0] if ok.any() else (
            np.zeros((0, d)))  # fmt: skip
    fresh = fresh[np.all(fresh @ a2.T + c2 >= -tol, axis=1)]
    return a2, c2, np.concatenate([kept, fresh])


def _cone_slack(cones: list[Cone], z: np.ndarray) -> np.ndarray:
    """``mu p_n(z) - |p_t(z)|`` of each cone at ``z`` of shape ``(..., d)``: ``(..., k)``."""
    if not cones:
        return np.zeros((*z.shape[:-1], 0))
    return np.stack([mu * (a_n + z @ b_n) - np.linalg.norm(a_t + z @ b_t.T, axis=-1)
                     for a_n, b_n, a_t, b_t, mu in cones], axis=-1)  # fmt: skip


def _slack(a: np.ndarray, c: np.ndarray, cones: list[Cone], z: np.ndarray) -> np.ndarray:
    """Every constraint's ``h_j(z)`` (``>= 0`` on ``F``), linear first, at ``z``."""
    return np.concatenate([z @ a.T + c, _cone_slack(cones, z)], axis=-1)


def _gradients(a: np.ndarray, cones: list[Cone], z: np.ndarray) -> np.ndarray:
    """Each constraint's gradient at ``z`` (a supergradient at a cone's apex, where
    ``p_t = 0``: ``mu b_n``), rows in the order of :func:`_slack`."""
    rows = [a]
    for _, b_n, a_t, b_t, mu in cones:
        p_t = a_t + b_t @ z
        norm = float(np.linalg.norm(p_t))
        rows.append((mu * b_n - (b_t.T @ p_t / norm if norm > 0.0 else 0.0))[None, :])
    return np.concatenate(rows, axis=0)


def _pull(a: np.ndarray, c: np.ndarray, cones: list[Cone], z: np.ndarray,
          tol: float) -> np.ndarray:  # fmt: skip
    """``t z`` with the largest ``t`` in ``[0, 1]`` whose constraints hold to ``tol`` (``F`` is
    convex and holds ``0``: the segment from ``0`` leaves it once), by bisection. The attained
    values are taken at points pulled with ``tol = 0``: members, not near ones."""
    if _slack(a, c, cones, z).min(initial=math.inf) >= -tol:
        return z
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _slack(a, c, cones, mid * z).min(initial=math.inf) >= -tol:
            lo = mid
        else:
            hi = mid
    return lo * z


def _constraints(a: np.ndarray, c: np.ndarray, cones: list[Cone]) -> list[dict]:
    """The constraints for SLSQP: the linear rows and each cone's ``mu p_n - |p_t|``."""
    out: list[dict] = []
    if len(c):
        out.append({"type": "ineq", "fun": lambda z: a @ z + c, "jac": lambda z: a})
    if cones:
        out.append({"type": "ineq", "fun": lambda z: _cone_slack(cones, z),
                    "jac": lambda z: _gradients(np.zeros((0, len(z))), cones, z)})  # fmt: skip
    return out


def _kkt_polish(e1: np.ndarray, e2: np.ndarray, a: np.ndarray, c: np.ndarray, z: np.ndarray,
                tol: float) -> np.ndarray:  # fmt: skip
    """The maximizer over a polytope to round-off from a near one ``z``: the active rows'
    KKT system ``2 E2 z + A_J^T mu = -e1``, ``A_J z = -c_J`` solved (least squares), rows with
    a negative multiplier dropped and solved again; ``z`` itself where no solve holds."""
    active = np.flatnonzero(a @ z + c <= 1e4 * tol)  # near-active: SLSQP's accuracy
    d = len(z)
    for _ in range(d + 2):
        k = len(active)
        mat = np.zeros((d + k, d + k))
        mat[:d, :d] = 2.0 * e2
        mat[:d, d:] = a[active].T
        mat[d:, :d] = a[active]
        sol = np.linalg.lstsq(mat, np.concatenate([-e1, -c[active]]), rcond=None)[0]
        cand, mult = sol[:d], sol[d:]
        if np.any(mult < 0.0):
            active = active[mult >= 0.0]
            continue
        if (a @ cand + c).min(initial=math.inf) >= -tol and np.allclose(
                mat @ sol, np.concatenate([-e1, -c[active]]), rtol=0.0, atol=1e-9 * (
                    float(np.abs(e1).max(initial=0.0)) + float(np.abs(e2).max()) * (
                        1.0 + float(np.abs(z).max())) + tol)):  # fmt: skip
            return cand
        break
    return z


def _newton_cones(e0: float, e1: np.ndarray, e2: np.ndarray, a: np.ndarray, c: np.ndarray,
                  cones: list[Cone], z: np.ndarray, box: np.ndarray,
                  tol: float) -> np.ndarray:  # fmt: skip
    """The maximizer over ``F`` with cones refined from a near one ``z``: Newton's method on
    the KKT system of the near-active constraints as equalities (a cone ``mu p_n - |p_t|``
    smooth off its apex, its Hessian ``-B_t^T (I - u u^T) B_t / |p_t|``), the multipliers by
    NNLS at each step; a step kept only where, pulled into ``F``, it lowers the certified
    bound (:func:`_upper_bound`); ``z`` itself otherwise."""
    best = z
    best_bound = _upper_bound(e1, e2, a, c, cones, z, box, float(energy(e0, e1, e2, z)), tol)
    d = len(z)
    for _ in range(8):
        slack = _slack(a, c, cones, z)
        near = np.flatnonzero(slack <= 1e4 * tol)
        grads = _gradients(a, cones, z)[near]
        grad_e = e1 + 2.0 * e2 @ z
        mult = nnls(grads.T, -grad_e)[0] if len(near) else np.zeros(0)
        hess = 2.0 * e2.copy()
        for j, mu_j in zip(near.tolist(), mult.tolist(), strict=True):
            if j < len(c):
                continue
            _, _, a_t, b_t, _ = cones[j - len(c)]
            p_t = a_t + b_t @ z
            norm = float(np.linalg.norm(p_t))
            if norm > 0.0:
                u = p_t / norm
                hess -= mu_j * b_t.T @ (np.eye(len(u)) - np.outer(u, u)) @ b_t / norm
        k = len(near)
        mat = np.zeros((d + k, d + k))
        mat[:d, :d] = hess
        mat[:d, d:] = grads.T
        mat[d:, :d] = grads
        rhs = -np.concatenate([grad_e + grads.T @ mult, slack[near]])
        step = np.linalg.lstsq(mat, rhs, rcond=None)[0][:d]
        z = _pull(a, c, cones, z + step, 0.0)
        bound = _upper_bound(e1, e2, a, c, cones, z, box, float(energy(e0, e1, e2, z)), tol)
        if bound < best_bound:
            best, best_bound = z, bound
        if not np.abs(step).max() > 1e-15 * (1.0 + float(np.abs(z).max())):
            break
    return best


def _upper_bound(e1: np.ndarray, e2: np.ndarray, a: np.ndarray, c: np.ndarray,
                 cones: list[Cone], z: np.ndarray, box: np.ndarray, value: float,
                 tol: float) -> float:  # fmt: skip
    """A bound on ``E`` over ``F`` from the member ``z`` (module docstring): ``E(z) + mu . h(z)
    + |grad L(z)| R``, the multipliers ``mu >= 0`` by NNLS on the near-active constraints."""
    grad_e = e1 + 2.0 * e2 @ z
    slack = _slack(a, c, cones, z)
    grads = _gradients(a, cones, z)
    near = slack <= 1e4 * tol  # near-active: SLSQP's accuracy
    mult = np.zeros(len(slack))
    if near.any():
        # grad E + sum mu_j grad h_j = 0: min |G^T mu + grad E| over mu >= 0
        mult[near] = nnls(grads[near].T, -grad_e)[0]
    resid = float(np.linalg.norm(grad_e + grads.T @ mult))
    reach = float(np.linalg.norm(np.maximum(np.abs(box[1] - z), np.abs(z - box[0]))))
    return value + float(mult @ np.maximum(slack, 0.0)) + resid * reach


def energy_range(e0: float, e1: np.ndarray, e2: np.ndarray, a: np.ndarray, c: np.ndarray,
                 cones: list[Cone], rel_tol: float = 1e-10) -> EnergyRange | None:  # fmt: skip
    """The least and the most ``E(z) = e0 + e1 . z + z . E2 z`` (J) over ``F = {A z + c >= 0,
    mu p_n(z) >= |p_t(z)| each cone}`` (``z = 0`` a member, ``E2`` negative semi-definite;
    ``A z + c`` met to ``rel_tol`` of the extent of ``F``, each row scaled to unit norm; the
    cones' impulses in the units of ``z``): :class:`EnergyRange` with
    the attained values and the certified bounds (the module docstring's methods); None where
    ``F`` is unbounded or empty.

    >>> # E = -|z|^2 over the square |z_i| <= 1: the most 0 at the centre, the least -2
    >>> r = energy_range(0.0, np.zeros(2), -np.eye(2), np.vstack([np.eye(2), -np.eye(2)]),
    ...                  np.ones(4), [])
    >>> (round(r.least, 12), round(r.most, 12), r.exact)
    (-2.0, 0.0, True)
    """
    d = len(e1)
    e2 = 0.5 * (e2 + e2.T)
    a = np.asarray(a, dtype=float).reshape(-1, d)
    c = np.maximum(np.asarray(c, dtype=float), 0.0)  # z = 0 a member: round-off kept in
    lin_a, lin_c = _distinct(a, c) if len(c) else (a, c)

    def count(sides: int) -> int:  # the d-subsets of the outer polytope's rows
        return math.comb(len(lin_c) + sum(2 if len(k[2]) == 1 else sides for k in cones), d)

    # the outer polytope: linear rows and each cone's circumscribed polygon, its sides as
    # many as the subset count allows
    n_sides = MIN_SIDES
    while n_sides < MAX_SIDES and count(2 * n_sides) <= MAX_SUBSETS:
        n_sides *= 2
    poly_a, poly_c = _polygon(cones, n_sides, True, d)
    out_a, out_c = _distinct(np.vstack([lin_a, poly_a]), np.concatenate([lin_c, poly_c])) \
        if cones else (lin_a, lin_c)
    if not len(out_c):
        return None
    box = _box(out_a, out_c)
    if box is None:
        return None
    extent = float(np.abs(box).max()) + 1e-300
    tol = rel_tol * extent  # a distance in z (the rows are unit) and the cones' impulses
    # the most: SLSQP from z = 0, pulled into F, polished on a polytope, bounded
    res = minimize(lambda z: -float(energy(e0, e1, e2, z)), np.zeros(d),
                   jac=lambda z: -(e1 + 2.0 * e2 @ z), method="SLSQP",
                   constraints=_constraints(lin_a, lin_c, cones),
                   options={"ftol": 1e-15, "maxiter": 500})  # fmt: skip
    z_most = _pull(lin_a, lin_c, cones, np.asarray(res.x, dtype=float), 0.0)
    if not cones:
        z_most = _pull(lin_a, lin_c, cones, _kkt_polish(e1, e2, lin_a, lin_c, z_most, tol), 0.0)
    else:
        z_most = _newton_cones(e0, e1, e2, lin_a, lin_c, cones, z_most, box, tol)
    if float(energy(e0, e1, e2, z_most)) < float(energy(e0, e1, e2, np.zeros(d))):
        z_most = np.zeros(d)
    most = float(energy(e0, e1, e2, z_most))
    most_bound = max(most, _upper_bound(e1, e2, lin_a, lin_c, cones, z_most, box, most, tol))
    # the least: the outer polytope's vertices (a bound; exact where there are no cones)
    verts = _vertices(out_a, out_c, tol)
    if verts is not None and len(verts):
        values = energy(e0, e1, e2, verts)
        least_bound = float(values.min())
        order = np.argsort(values)
    else:  # too many subsets: the box's corners bound the concave E from below
        corners = np.array(np.meshgrid(*box.T, indexing="ij")).reshape(d, -1).T
        least_bound = float(energy(e0, e1, e2, corners).min())
        verts, order = np.zeros((0, d)), np.zeros(0, dtype=np.intp)
    pulled: list[np.ndarray] = []
    if cones and len(verts):
        # cutting planes (outer approximation for concave minimization: Hoffman 1981; Horst
        # and Tuy, Global Optimization, 1996, ch. VI): the least vertex outside F is cut off
        # by the tangent plane of the cone it violates most, u . p_t <= mu p_n with u its
        # p_t's direction (every member meets it); the least vertex value stays a bound
        for _ in range(MAX_CUTS):
            values = energy(e0, e1, e2, verts)
            v = verts[int(np.argmin(values))]
            least_bound = float(values.min())
            pulled.append(_pull(lin_a, lin_c, cones, v, 0.0))
            slack = _cone_slack(cones, v)
            j = int(np.argmin(slack))
            best = min(float(energy(e0, e1, e2, z)) for z in pulled)
            if slack[j] >= -tol or best - least_bound <= 1e-12 * max(1.0, abs(best)):
                break
            a_n, b_n, a_t, b_t, mu = cones[j]
            u = (a_t + b_t @ v) / np.linalg.norm(a_t + b_t @ v)
            row, const = mu * b_n - b_t.T @ u, mu * a_n - float(u @ a_t)
            norm = float(np.linalg.norm(row))
            step = _cut(out_a, out_c, verts, row / norm, const / norm, tol)
            if step is None or not len(step[2]):
                break
            out_a, out_c, verts = step
        values = energy(e0, e1, e2, verts)
        least_bound = min(least_bound, float(values.min()))
        order = np.argsort(values)
    if not cones and len(verts):
        z_least = verts[order[0]]
        least = least_bound
    else:
        candidates = [np.zeros(d), z_most, *pulled] + [_pull(lin_a, lin_c, cones, verts[i], 0.0)
                                                      for i in order[:16]]  # fmt: skip
        if cones:
            in_a, in_c = _polygon(cones, n_sides, False, d)
            inner = _vertices(*_distinct(np.vstack([lin_a, in_a]),
                                         np.concatenate([lin_c, in_c])), tol)
            if inner is not None and len(inner):
                candidates.append(inner[np.argmin(energy(e0, e1, e2, inner))])
        refined = []
        for z0 in sorted(candidates, key=lambda z: float(energy(e0, e1, e2, z)))[:4]:
            loc = minimize(lambda z: float(energy(e0, e1, e2, z)), z0,
                           jac=lambda z: e1 + 2.0 * e2 @ z, method="SLSQP",
                           constraints=_constraints(lin_a, lin_c, cones),
                           options={"ftol": 1e-15, "maxiter": 200})  # fmt: skip
            refined.append(_pull(lin_a, lin_c, cones, np.asarray(loc.x, dtype=float), 0.0))
        candidates.extend(refined)
        z_least = min(candidates, key=lambda z: float(energy(e0, e1, e2, z)))
        least = float(energy(e0, e1, e2, z_least))
    least_bound = min(least_bound, least)
    scale = max(abs(most), abs(least), abs(e0), 1e-300) + float(np.abs(e1).max()) * extent
    exact = bool(least - least_bound <= 1e-9 * scale and most_bound - most <= 1e-9 * scale)
    return EnergyRange(least=least, most=most, least_bound=least_bound, most_bound=most_bound,
                       exact=exact, points=(z_least, z_most))

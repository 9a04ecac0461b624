"""Where bodies can touch, and when they next do.

A *feature* is one way two things can meet: a vertex of a convex body (or a sphere) against a
fixed plane, or two spheres. Its gap (m) is

    vertex k on plane (p, n):  g = n . (x + R s_k - p)
    sphere on plane:           g = n . (x - p) - r
    sphere a and sphere b:     g = |x_a - x_b| - (r_a + r_b)
    sphere a and box b:        g = |c - clamp(c, -h, h)| - r_a,  c = R_b^T (x_a - x_b)
                               (inside the box: minus the depth to the nearest face)
    vertex k of box a, box b:  the same with r_a = 0 and c = R_b^T (x_a + R_a s_k - x_b)
                               (vertex on face; two edges crossing are not found)

The next impact in free flight is the first downward zero of a gap. Closed form where the gap
is a quadratic in time (a sphere or a non-rotating body on a plane without ground motion, two
spheres always: gravity and the ground's inertia force cancel in their relative motion);
closed form too for the corners of a body turning at a constant rate on a plane without
ground motion (a sum of a quadratic and a sinusoid: :mod:`carnot.simulate.corners`, which
cannot miss a root between samples); otherwise the gaps are sampled (steps of at most 0.05
rad of rotation) and the crossing is refined by Brent's method (``scipy.optimize.brentq``,
``xtol`` 1e-15 s). A feature touching at
the start (``|g| <= eps``) is armed once it has opened by ``eps``; until then only a penetration
deeper than ``eps`` counts, so that a contact just released is not found again at once.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import brentq

from carnot.conventions import contact_frame
from carnot.keys import exact_key
from carnot.simulate.motion import BodyState, Flight, SimBody, quat_matrix
from carnot.simulate.shapes import Convex, Plane, Sphere
from carnot.vector3 import cross

#: Largest rotation (rad) between two samples of a gap.
SAMPLE_ANGLE = 0.05
#: Samples per window of the search.
WINDOW = 128
#: Corners of bodies turning at a constant rate found in closed form (False: sampled, the
#: route before; kept as the benchmark's in-run baseline and the tests' independent route).
CLOSED_FORM_CORNERS = True


@dataclass(frozen=True, kw_only=True)
class Feature:
    """``body`` (index of a movable body) meets ``plane`` (index of a fixed plane) at its
    ``vertex`` (-1: the sphere), or meets movable body ``other``: a sphere meets a sphere or
    a box, a box's ``vertex`` meets a box."""

    body: int
    plane: int = -1
    vertex: int = -1
    other: int = -1
    _hash: int = field(init=False, repr=False, compare=False, default=0)

    def __post_init__(self) -> None:
        # the hash worked out once: features key every dictionary of gaps, speeds and levels,
        # dozens of look-ups an event, where the generated hash builds a tuple each time
        object.__setattr__(self, "_hash", hash((self.body, self.plane, self.vertex, self.other)))

    def __hash__(self) -> int:
        return self._hash


@dataclass(frozen=True, kw_only=True, eq=False)
class Geometry:
    """A feature at one instant: gap (m), contact point (m), unit normal from ``b`` into ``a``
    (``a`` the feature's body), lever arm ``r_a`` (m) and the relative velocity (m/s)."""

    gap: float
    point: np.ndarray
    normal: np.ndarray
    lever_a: np.ndarray
    relative_velocity: np.ndarray

    @property
    def normal_velocity(self) -> float:
        return float(self.normal @ self.relative_velocity)

    def tangential_velocity(self) -> np.ndarray:
        w = self.relative_velocity
        return w - (self.normal @ w) * self.normal


def features(bodies: list[SimBody], planes: list[Plane]) -> list[Feature]:
    """Every feature of a scene: each vertex (or sphere) of each movable body on each plane,
    and each pair of movable spheres."""
    out: list[Feature] = []
    for i, body in enumerate(bodies):
        for p in range(len(planes)):
            if isinstance(body.shape, Sphere):
                out.append(Feature(body=i, plane=p))
            else:
                out.extend(Feature(body=i, plane=p, vertex=k)
                           for k in range(len(body.shape.vertices_body)))  # fmt: skip
    for i, a in enumerate(bodies):
        for j, b in enumerate(bodies):
            if j == i:
                continue
            box_b = isinstance(b.shape, Convex) and b.shape.half_extents is not None
            if isinstance(a.shape, Sphere):
                if isinstance(b.shape, Sphere) and j > i:
                    out.append(Feature(body=i, other=j))
                elif box_b:
                    out.append(Feature(body=i, other=j))  # a sphere and a box
            elif a.shape.half_extents is not None and box_b:  # each corner of a on box b
                out.extend(Feature(body=i, other=j, vertex=k)
                           for k in range(len(a.shape.vertices_body)))  # fmt: skip
    return out


def _tip_radius(shape: Sphere | Convex, vertex: int) -> float:
    """The radius that meets a box: a sphere's, or 0 for a corner."""
    return shape.radius if isinstance(shape, Sphere) and vertex < 0 else 0.0


def pair_scale(a: Sphere | Convex, b: Sphere | Convex) -> float:
    """The smallest of the radii and half extents of two bodies that can meet (m)."""
    sizes = [x.radius if isinstance(x, Sphere) else float(np.min(x.half_extents))  # type: ignore[arg-type]
             for x in (a, b)]  # fmt: skip
    return min(sizes)


def sphere_box(centre: np.ndarray, half: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Signed distance (m) from a point to a box (body axes, ``half`` extents), the nearest
    point of the box's surface and the unit normal there pointing towards the point (all in
    the box's axes). Outside: the clamped point; inside: the nearest face.

    >>> d, p, n = sphere_box(np.array([3.0, 0.5, 0.0]), np.array([1.0, 1.0, 1.0]))
    >>> d, p.tolist(), n.tolist()
    (2.0, [1.0, 0.5, 0.0], [1.0, 0.0, 0.0])
    """
    near = np.clip(centre, -half, half)
    d = centre - near
    dist = float(np.linalg.norm(d))
    if dist > 0:
        return dist, near, d / dist
    depth = half - np.abs(centre)
    k = int(np.argmin(depth))
    n = np.zeros(3)
    n[k] = 1.0 if centre[k] >= 0 else -1.0
    near = centre.copy()
    near[k] = n[k] * half[k]
    return -float(depth[k]), near, n


def geometry(f: Feature, bodies: list[SimBody], planes: list[Plane],
             states: list[BodyState]) -> Geometry:  # fmt: skip
    """The feature's gap, point, normal and relative velocity (see :class:`Geometry`)."""
    s = states[f.body]
    shape = bodies[f.body].shape
    if f.other >= 0 and isinstance(bodies[f.other].shape, Convex):
        o = states[f.other]
        half = bodies[f.other].shape.half_extents  # type: ignore[union-attr]
        assert half is not None
        tip = s.position
        if f.vertex >= 0:
            assert isinstance(shape, Convex)
            tip = s.position + s.rotation @ shape.vertices_body[f.vertex]
        rot = o.rotation
        dist, near, n_b = sphere_box(rot.T @ (tip - o.position), half)
        n = rot @ n_b
        point = o.position + rot @ near
        lever_a = point - s.position
        vb = o.velocity + cross(o.angular_velocity, point - o.position)
        va = s.velocity + cross(s.angular_velocity, lever_a)
        return Geometry(gap=dist - _tip_radius(shape, f.vertex), point=point, normal=n,
                        lever_a=lever_a, relative_velocity=va - vb)  # fmt: skip
    if f.other >= 0:
        o = states[f.other]
        ra, rb = shape.radius, bodies[f.other].shape.radius  # type: ignore[union-attr]
        d = s.position - o.position
        dist = float(np.linalg.norm(d))
        n = d / dist
        point = o.position + rb * n
        lever_a = point - s.position
        vb = o.velocity + cross(o.angular_velocity, point - o.position)
        va = s.velocity + cross(s.angular_velocity, lever_a)
        return Geometry(gap=dist - ra - rb, point=point, normal=n, lever_a=lever_a,
                        relative_velocity=va - vb)  # fmt: skip
    # a sphere or a corner on a plane: on Python floats (NumPy's per-call cost dominates
    # 3-vectors; this runs at every impact)
    plane = planes[f.plane]
    n = plane.normal
    if isinstance(shape, Sphere):
        lever_tip = sphere_tip(n.tolist(), shape.radius)
    else:
        lever_tip = (s.rotation @ shape.vertices_body[f.vertex]).tolist()
    gap, below, lever, rel = on_plane(n.tolist(), plane.point.tolist(), s.position.tolist(),
                                      lever_tip, s.velocity.tolist(),
                                      s.angular_velocity.tolist())  # fmt: skip
    return Geometry(gap=gap, point=np.array(below), normal=n, lever_a=np.array(lever),
                    relative_velocity=np.array(rel))  # fmt: skip


def sphere_tip(n: Sequence[float], radius: float) -> list[float]:
    """The lever ``-r n`` (m) from a sphere's centre to its lowest point on a plane of normal
    ``n``."""
    return [-radius * n[0], -radius * n[1], -radius * n[2]]


def on_plane(n: Sequence[float], p: Sequence[float], x: Sequence[float], tip: Sequence[float],
             v: Sequence[float], w: Sequence[float]
             ) -> tuple[float, list[float], list[float], list[float]]:  # fmt: skip
    """A tip (lever ``tip`` from the centre of mass ``x``) of a body moving with ``(v, w)``
    over the plane ``(p, n)``: its gap ``n . (x + tip - p)`` (m), the point on the plane below
    it (m), that point's lever from ``x`` and the body's velocity there ``v + w x r`` (m/s),
    on Python floats (:func:`geometry`'s route, and the lean event loop's: NumPy's per-call
    cost dominates 3-vectors).

    >>> on_plane([0, 1.0, 0], [0, 0, 0], [0, 2.0, 0], [0, -1.0, 0], [1.0, -3.0, 0], [0, 0, 1.0])
    (1.0, [0.0, 0.0, 0.0], [0.0, -2.0, 0.0], [3.0, -3.0, 0.0])
    """
    n0, n1, n2 = n
    x0, x1, x2 = x
    l0, l1, l2 = tip
    p0, p1, p2 = p
    gap = n0 * (x0 + l0 - p0) + n1 * (x1 + l1 - p1) + n2 * (x2 + l2 - p2)
    # the point on the plane below the tip, and its lever from the centre of mass
    l0, l1, l2 = l0 - gap * n0, l1 - gap * n1, l2 - gap * n2
    w0, w1, w2 = w
    v0, v1, v2 = v
    va = [v0 + w1 * l2 - w2 * l1, v1 + w2 * l0 - w0 * l2, v2 + w0 * l1 - w1 * l0]
    return gap, [x0 + l0, x1 + l1, x2 + l2], [l0, l1, l2], va


def sphere_gap_speed(n: Sequence[float], p: Sequence[float], x: Sequence[float],
                     v: Sequence[float], radius: float) -> tuple[float, float]:
    """A sphere's gap ``n . (x - p) - r`` (m) above the plane ``(p, n)`` and its normal
    velocity ``n . v`` (m/s; the spin does not move the lowest point along ``n``), on floats.

    >>> sphere_gap_speed([0, 1.0, 0], [0, 0, 0], [0, 2.0, 0], [0, -3.0, 0], 0.5)
    (1.5, -3.0)
    """
    n0, n1, n2 = n
    gap = n0 * (x[0] - p[0]) + n1 * (x[1] - p[1]) + n2 * (x[2] - p[2]) - radius
    return gap, n0 * v[0] + n1 * v[1] + n2 * v[2]


def sphere_quadratic(n: np.ndarray, p: np.ndarray, g: np.ndarray, x0: np.ndarray,
                     v0: np.ndarray, radius: float) -> tuple[float, float, float]:
    """``(a, b, c)``: a sphere's gap above the plane ``(p, n)`` in flight from ``(x0, v0)``
    under ``g``, ``a s^2 + b s + c`` (``a = n . g / 2``, ``b = n . v0``, ``c`` the gap now).

    >>> sphere_quadratic(np.array([0, 1.0, 0]), np.zeros(3), np.array([0, -9.81, 0]),
    ...                  np.array([0, 1.5, 0]), np.array([0, 2.0, 0]), 0.5)
    (-4.905, 2.0, 1.0)
    """
    return 0.5 * float(n @ g), float(n @ v0), float(n @ (x0 - p)) - radius


@dataclass(frozen=True, kw_only=True, eq=False)
class CornerGroup:
    """The corners of one convex body on one plane (``features``, in the order of ``vertices``
    (K, 3, body axes)): their gaps and speeds are worked out together."""

    body: int
    plane: int
    features: list[Feature]
    vertices: np.ndarray


def corner_groups(feats: list[Feature], bodies: list[SimBody]
                  ) -> tuple[list[CornerGroup], list[Feature]]:  # fmt: skip
    """``feats`` split into the corners of convex bodies on planes, grouped by body and plane,
    and the others."""
    grouped: dict[tuple[int, int], list[Feature]] = {}
    others: list[Feature] = []
    for f in feats:
        if f.other < 0 and isinstance(bodies[f.body].shape, Convex):
            grouped.setdefault((f.body, f.plane), []).append(f)
        else:
            others.append(f)
    groups = []
    for (i, p), members in grouped.items():
        shape = bodies[i].shape
        assert isinstance(shape, Convex)
        verts = np.ascontiguousarray(shape.vertices_body[[f.vertex for f in members]])
        groups.append(CornerGroup(body=i, plane=p, features=members, vertices=verts))
    return groups, others


def gaps_and_speeds(feats: list[Feature], bodies: list[SimBody], planes: list[Plane],
                    states: list[BodyState],
                    groups: tuple[list[CornerGroup], list[Feature]] | None = None
                    ) -> tuple[dict[Feature, float], dict[Feature, float]]:  # fmt: skip
    """Every feature's gap (m) and normal relative velocity (m/s), as :func:`geometry` gives
    them; the corners of a convex body on a plane all at once (``g_k = n . (x + r_k - p)``,
    ``w_n = n . v + r_k . (n x omega)`` with ``r_k = R s_k``: the velocity at the contact point
    ``tip - g n`` has the same normal component, ``n . (omega x n) = 0``). ``groups``:
    :func:`corner_groups` of ``feats``, worked out once by a caller that asks again and
    again."""
    corners, others = corner_groups(feats, bodies) if groups is None else groups
    gaps: dict[Feature, float] = {}
    speeds: dict[Feature, float] = {}
    for f in others:
        shape = bodies[f.body].shape
        if f.other < 0 and isinstance(shape, Sphere):  # a sphere on a plane: n . v, no spin
            s, plane = states[f.body], planes[f.plane]
            gaps[f], speeds[f] = sphere_gap_speed(plane.normal.tolist(), plane.point.tolist(),
                                                  s.position.tolist(), s.velocity.tolist(),
                                                  shape.radius)  # fmt: skip
            continue
        g = geometry(f, bodies, planes, states)
        gaps[f], speeds[f] = g.gap, g.normal_velocity
    for group in corners:
        s = states[group.body]
        plane = planes[group.plane]
        both = _kernels().corner_kinematics(
            group.vertices, s.orientation, s.position, s.velocity, s.angular_velocity,
            plane.normal, plane.point).tolist()
        gaps.update(zip(group.features, both[0], strict=True))
        speeds.update(zip(group.features, both[1], strict=True))
    return gaps, speeds


def quadratic_first_down_root(a: float, b: float, c: float, level: float, eps: float
                              ) -> float | None:  # fmt: skip
    """The first ``s > 0`` where ``a s^2 + b s + c`` crosses zero downward (or, when not
    armed and the gap does not open by ``eps`` first, crosses ``-eps``), by the stable form
    of the quadratic formula. A ball 1 m above the floor: ``sqrt(2/9.81)`` s.

    >>> round(quadratic_first_down_root(-4.905, 0.0, 1.0, 0.0, 1e-9), 12)  # drop from 1 m
    0.451523640986
    """
    if level < 0:
        # touching at the start: the gap's own zero if it opens by eps first, else the level
        apex = -b / (2 * a) if a < 0 else math.inf
        opens = apex > 0 and (c - b * b / (4 * a) if a < 0 else math.inf) > eps
        if not opens:
            c = c - level
    roots: list[float] = []
    if a == 0.0:
        if b != 0.0:
            roots = [-c / b]
    else:
        disc = b * b - 4 * a * c
        if disc < 0:
            return None
        q = -0.5 * (b + math.copysign(math.sqrt(disc), b))  # (math: on floats, NumPy's cost)
        roots = [q / a] + ([c / q] if q != 0.0 else [])
    good = sorted(float(r) for r in roots if r > 0 and 2 * a * r + b < 0)
    return good[0] if good else None


def quadratic_gap(f: Feature, flights: list[Flight], bodies: list[SimBody],
                  planes: list[Plane]) -> tuple[float, float, float] | None:  # fmt: skip
    """``(a, b, c)`` when the feature's gap is ``a s^2 + b s + c`` in this flight, else None."""
    fl = flights[f.body]
    if f.other >= 0 and isinstance(bodies[f.other].shape, Convex):
        return None  # a sphere and a box: sampled
    if f.other >= 0:
        fo = flights[f.other]
        dx = fl.state0.position - fo.state0.position
        dv = fl.state0.velocity - fo.state0.velocity
        if fl.ground is not None or fo.ground is not None:
            pass  # the ground's inertia force is the same on both: it cancels
        radius = bodies[f.body].shape.radius + bodies[f.other].shape.radius  # type: ignore
        # |dx + dv s|^2 - R^2: a quadratic in the squared distance, not in the gap itself;
        # its downward zero is the gap's.
        return float(dv @ dv), float(2 * dx @ dv), float(dx @ dx - radius * radius)
    if fl.ground is not None:
        return None
    shape = bodies[f.body].shape
    n, p = planes[f.plane].normal, planes[f.plane].point
    if isinstance(shape, Sphere):
        return sphere_quadratic(n, p, fl.gravity, fl.state0.position, fl.state0.velocity,
                                shape.radius)  # fmt: skip
    if fl.kind == "still":
        assert isinstance(shape, Convex)
        tip = fl.state0.position + fl.state0.rotation @ shape.vertices_body[f.vertex]
        c = float(n @ (tip - p))
    else:
        return None
    return 0.5 * float(n @ fl.gravity), float(n @ fl.state0.velocity), c


def gap_series(f: Feature, flights: list[Flight], bodies: list[SimBody], planes: list[Plane],
               s: np.ndarray) -> np.ndarray:  # fmt: skip
    """The feature's gap (m) at times ``s`` (N,) of the flights."""
    fl = flights[f.body]
    shape = bodies[f.body].shape
    if f.other >= 0 and isinstance(bodies[f.other].shape, Convex):
        half = bodies[f.other].shape.half_extents  # type: ignore[union-attr]
        assert half is not None
        if f.vertex >= 0:
            assert isinstance(shape, Convex)
            xa = fl.points(s, shape.vertices_body[f.vertex : f.vertex + 1])[:, 0, :]
        else:
            xa, _ = fl.translation_at(s)
        xb, _ = flights[f.other].translation_at(s)
        qb, _ = flights[f.other].rotation_at(s)
        local = np.einsum("nji,nj->ni", quat_matrix(qb), xa - xb)  # R^T (x_a - x_b)
        return np.array([sphere_box(c, half)[0] for c in local]) - _tip_radius(shape, f.vertex)
    if f.other >= 0:
        xa, _ = fl.translation_at(s)
        xb, _ = flights[f.other].translation_at(s)
        radius = shape.radius + bodies[f.other].shape.radius  # type: ignore[union-attr]
        return np.linalg.norm(xa - xb, axis=1) - radius
    n, p = planes[f.plane].normal, planes[f.plane].point
    if isinstance(shape, Sphere):
        x, _ = fl.translation_at(s)
        return (x - p) @ n - shape.radius
    tips = fl.points(s, shape.vertices_body[f.vertex : f.vertex + 1])[:, 0, :]
    return (tips - p) @ n


def next_contact(flights: list[Flight], bodies: list[SimBody], planes: list[Plane],
                 feats: list[Feature], horizon: float, levels: dict[Feature, float],
                 eps: float, groups: tuple[list[CornerGroup], list[Feature]] | None = None
                 ) -> float | None:  # fmt: skip
    """The time (s after the flights' start, <= ``horizon``) of the first gap closing, or
    None. ``levels``: 0 for the features open at the start, and for those touching the
    (negative) gap at which they count until they open (:func:`trigger_levels`). ``groups``:
    :func:`corner_groups` of ``feats``, when the caller keeps them."""
    best: float | None = None
    sampled: list[Feature] = []
    spinning: dict[tuple[int, int], list[Feature]] = {}  # (body, plane): its corners
    vertices: dict[tuple[int, int], np.ndarray] = {}
    if groups is not None and CLOSED_FORM_CORNERS:
        corners_of, feats = groups
        for group in corners_of:
            fl = flights[group.body]
            if fl.kind == "constant" and fl.ground is None:
                spinning[(group.body, group.plane)] = group.features
                vertices[(group.body, group.plane)] = group.vertices
            else:
                feats = [*feats, *group.features]
    for f in feats:
        if CLOSED_FORM_CORNERS and _spinning_corner(f, flights, bodies):
            spinning.setdefault((f.body, f.plane), []).append(f)
            continue
        coeffs = quadratic_gap(f, flights, bodies, planes)
        if coeffs is None:
            sampled.append(f)
            continue
        a, b, c = coeffs
        if f.other >= 0:
            # squared distance: arm/penetration tolerance on the distance, scaled
            radius = bodies[f.body].shape.radius + bodies[f.other].shape.radius  # type: ignore
            root = quadratic_first_down_root(a, b, c, 2 * radius * levels[f], 2 * radius * eps)
        else:
            root = quadratic_first_down_root(a, b, c, levels[f], eps)
        if root is not None and root <= horizon and (best is None or root < best):
            best = root
    for (i, p), corners in spinning.items():
        root = _corner_root(flights[i], bodies[i], planes[p], corners, horizon, levels, eps,
                            vertices.get((i, p)))  # fmt: skip
        if root is not None and (best is None or root < best):
            best = root
    if sampled:
        limit = horizon if best is None else best
        found = _sampled_root(flights, bodies, planes, sampled, limit, levels, eps)
        if found is not None and (best is None or found < best):
            best = found
    return best


def _kernels() -> Any:
    """:mod:`carnot.simulate.corners`, imported when first needed (it imports Numba: a third
    of a second that a scene without polyhedra need not pay)."""
    from carnot.simulate import corners

    return corners


def _spinning_corner(f: Feature, flights: list[Flight], bodies: list[SimBody]) -> bool:
    """A corner of a convex body on a plane, the body turning at a constant angular velocity
    without ground motion: its gap in closed form (:mod:`carnot.simulate.corners`)."""
    fl = flights[f.body]
    return (f.other < 0 and fl.kind == "constant" and fl.ground is None
            and isinstance(bodies[f.body].shape, Convex))  # fmt: skip


def _corner_root(flight: Flight, body: SimBody, plane: Plane, corners: list[Feature],
                 horizon: float, levels: dict[Feature, float], eps: float,
                 verts: np.ndarray | None = None) -> float | None:  # fmt: skip
    """The first closing of one body's ``corners`` on ``plane`` (all spinning: see
    :func:`_spinning_corner`; ``verts``, when given, their vertices in that order), by
    :func:`carnot.simulate.corners.first_corner_impact`."""
    if verts is None:
        shape = body.shape
        assert isinstance(shape, Convex)
        verts = np.ascontiguousarray(shape.vertices_body[[f.vertex for f in corners]])
    s0 = flight.state0
    root = _kernels().first_corner_impact(
        verts, s0.rotation, s0.position, s0.velocity, s0.angular_velocity, flight.gravity,
        plane.normal, plane.point, np.array([levels[f] for f in corners]), eps, horizon)
    return None if root == np.inf else float(root)


def _sample_step(flights: list[Flight], horizon: float, bodies: list[SimBody] | None = None,
                 feats: tuple[Feature, ...] | list[Feature] = ()) -> float:  # fmt: skip
    spin = max(float(np.linalg.norm(f.state0.angular_velocity)) for f in flights)
    step = horizon / 16
    if spin > 0:
        step = min(step, SAMPLE_ANGLE / spin)
    for f in feats:
        if f.other >= 0 and bodies is not None:
            # a sphere and a box: their relative motion is uniform in flight (gravity and
            # the ground's inertia force cancel) plus the box's turning; a tenth of the
            # sphere's radius per step, so that the sphere cannot cross a face unseen
            a, b = flights[f.body].state0, flights[f.other].state0
            speed = float(np.linalg.norm(a.velocity - b.velocity)) + (float(
                np.linalg.norm(b.angular_velocity)) * bodies[f.other].shape.size + float(
                np.linalg.norm(a.angular_velocity)) * bodies[f.body].shape.size)  # fmt: skip
            radius = pair_scale(bodies[f.body].shape, bodies[f.other].shape)
            if speed > 0:
                step = min(step, 0.1 * radius / speed)
    for fl in flights:
        if fl.ground is not None:
            step = min(step, fl.ground.search_step)
    return max(step, 1e-9)


def trigger_levels(gaps: dict[Feature, float], eps: float) -> dict[Feature, float]:
    """Each feature's trigger level (m): 0 when open (gap > ``eps``), else the smaller of
    ``-eps`` and its gap less ``eps`` (a feature already a little inside, by the round-off of
    an earlier event, must go deeper before it counts: nothing is found at the start).

    >>> f = Feature(body=0, plane=0)
    >>> trigger_levels({f: -3e-9}, 1e-9)[f]
    -4e-09
    """
    return {f: 0.0 if g > eps else min(-eps, g - eps) for f, g in gaps.items()}


def _window_gaps(flights: list[Flight], bodies: list[SimBody], planes: list[Plane],
                 feats: list[Feature], s: np.ndarray) -> dict[Feature, np.ndarray]:
    """Every feature's gap at the times ``s``: each body's vertices computed once."""
    tips: dict[int, np.ndarray] = {}
    out: dict[Feature, np.ndarray] = {}
    for f in feats:
        shape = bodies[f.body].shape
        if f.other >= 0 or isinstance(shape, Sphere):
            out[f] = gap_series(f, flights, bodies, planes, s)
            continue
        if f.body not in tips:
            tips[f.body] = flights[f.body].points(s, shape.vertices_body)
        plane = planes[f.plane]
        out[f] = (tips[f.body][:, f.vertex, :] - plane.point) @ plane.normal
    return out


def _sampled_root(flights: list[Flight], bodies: list[SimBody], planes: list[Plane],
                  feats: list[Feature], horizon: float, levels: dict[Feature, float],
                  eps: float) -> float | None:  # fmt: skip
    """The first closing of a sampled gap (module docstring): a feature open at the start
    closes where its gap falls below 0; one touching at the start where it falls below its
    level before opening by ``eps``, or below 0 after."""
    step = _sample_step(flights, horizon, bodies, feats)
    start = 0.0
    opened = {f: levels[f] >= 0 for f in feats}
    while start < horizon:
        stop = min(horizon, start + WINDOW * step)
        count = max(2, int(np.ceil((stop - start) / step)) + 1)
        s = np.linspace(start, stop, count)
        gaps = _window_gaps(flights, bodies, planes, feats, s)
        brackets: list[tuple[int, Feature, float]] = []  # (sample index, feature, level)
        for f in feats:
            g = gaps[f]
            first_open = 0
            if not opened[f]:
                wide = np.flatnonzero(g > eps)
                first_open = int(wide[0]) if wide.size else len(g)
                deep = np.flatnonzero(g[:first_open] < levels[f])
                if deep.size:
                    brackets.append((int(deep[0]), f, levels[f]))
                    continue
                if wide.size:
                    opened[f] = True
            if opened[f]:
                below = np.flatnonzero(g[first_open:] < 0.0)
                if below.size:
                    brackets.append((first_open + int(below[0]), f, 0.0))
        if brackets:
            # only the earliest brackets can hold the first zero
            first = min(j for j, _, _ in brackets)
            return min(_refine(f, flights, bodies, planes, s, gaps[f], j, level)
                       for j, f, level in brackets if j == first)  # fmt: skip
        start = stop
    return None


def _refine(f: Feature, flights: list[Flight], bodies: list[SimBody], planes: list[Plane],
            s: np.ndarray, g: np.ndarray, j: int, level: float) -> float:  # fmt: skip
    if j == 0:
        return float(s[0])

    shape = bodies[f.body].shape
    if f.other < 0 and isinstance(shape, Convex):
        vertex = shape.vertices_body[f.vertex]
        plane = planes[f.plane]
        flight = flights[f.body]

        def fn(t: float) -> float:
            return float(plane.normal @ (flight.point_at(t, vertex) - plane.point)) - level
    else:

        def fn(t: float) -> float:
            return float(gap_series(f, flights, bodies, planes, np.array([t]))[0]) - level

    return float(brentq(fn, float(s[j - 1]), float(s[j]), xtol=1e-15, rtol=8.9e-16))


#: Contact frames kept, by normal (:func:`frame`).
FRAMES_KEPT = 4096
_FRAMES: dict[tuple[float, ...], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def frame(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The contact frame of carnot's conventions (n, t1, t2), kept by the normal's floats
    (:func:`carnot.keys.exact_key`; planes are few and the dynamics ask for their frames at
    every step); at most :data:`FRAMES_KEPT`, all dropped when more are made."""
    key = exact_key(normal.tolist())
    out = _FRAMES.get(key)
    if out is None:
        if len(_FRAMES) >= FRAMES_KEPT:
            _FRAMES.clear()
        out = _FRAMES[key] = contact_frame(normal)
    return out

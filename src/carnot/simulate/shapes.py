"""Shapes of simulated bodies and the planes they meet.

A movable body is a ``Sphere`` (radius, m) or a ``Convex`` hull of vertices given in body axes
relative to the centre of mass (m): a box is the hull of its eight corners, a polygon (all
vertices in one plane) is a lamina such as a rocking block drawn in 2D or a rimless wheel. A
fixed obstacle is a ``Plane`` (a point on it and its unit normal, pointing out of the solid side).

Inertia from a shape (kg m^2, body axes, about the centre of mass): a solid sphere
``2/5 m r^2``; a convex polyhedron of uniform density (tetrahedra of the hull, SciPy's Qhull);
a polygon of uniform areal density (triangles of the hull). A hull whose uniform centroid is not
the origin needs ``inertia`` given (mass not spread uniformly: a hub with light spokes).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from carnot import validate
from carnot.errors import InputError

#: Polygon test: vertices within this fraction of the hull's size of one plane are a lamina.
FLAT_TOLERANCE = 1e-12


@dataclass(frozen=True, kw_only=True, eq=False)
class Sphere:
    """A sphere of ``radius`` (m) centred on the centre of mass.

    >>> Sphere(radius=0.1).size
    0.1
    """

    radius: float

    @property
    def size(self) -> float:
        """A length scale (m) for tolerances."""
        return self.radius


@dataclass(frozen=True, kw_only=True, eq=False)
class Convex:
    """The convex hull of ``vertices_body`` ((K, 3), m, body axes, relative to the centre of
    mass); only the vertices can touch a plane (a face or edge touches as its corners).

    >>> Convex(vertices_body=box_vertices([2.0, 2.0, 2.0])).size
    1.7320508075688772
    """

    vertices_body: np.ndarray

    @cached_property  # read at every impact (tolerances, the Zeno test): worked out once
    def size(self) -> float:
        """The largest distance of a vertex from the centre of mass (m)."""
        return float(np.max(np.linalg.norm(self.vertices_body, axis=1)))

    @cached_property
    def half_extents(self) -> np.ndarray | None:
        """``(a, b, c) / 2`` (m) when the hull is a box along the body axes centred on the
        centre of mass (its eight corners ``(+-a/2, +-b/2, +-c/2)``), else None.

        >>> Convex(vertices_body=box_vertices([2.0, 4.0, 6.0])).half_extents.tolist()
        [1.0, 2.0, 3.0]
        """
        v = self.vertices_body
        half = np.max(np.abs(v), axis=0)
        if len(v) != 8 or np.any(half <= 0):
            return None
        corners = {tuple(np.sign(row).astype(int)) for row in v}
        if len(corners) != 8 or not np.allclose(np.abs(v), half, rtol=1e-12, atol=0.0):
            return None
        return half


Shape = Sphere | Convex


@dataclass(frozen=True, kw_only=True, eq=False)
class Plane:
    """A fixed plane through ``point`` (m) with unit ``normal`` pointing into free space.

    ``gap(x) = n . (x - p)`` is the signed distance of a world point from it (m).

    >>> Plane(point=np.zeros(3), normal=np.array([0.0, 1.0, 0.0])).gap(np.array([0, 2.0, 0]))
    2.0
    """

    point: np.ndarray
    normal: np.ndarray

    def gap(self, x: np.ndarray) -> float:
        return float(self.normal @ (x - self.point))


def box_vertices(size: object, field: str = "size") -> np.ndarray:
    """The eight corners of a box with full edge lengths ``size = [a, b, c]`` (m) along the body
    axes, centred on the centre of mass: ``(+-a/2, +-b/2, +-c/2)``.

    >>> box_vertices([2.0, 4.0, 6.0])[0].tolist()
    [-1.0, -2.0, -3.0]
    """
    if not isinstance(size, (list, tuple, np.ndarray)) or len(size) != 3:
        raise InputError(field, "must be a list of 3 full edge lengths [a, b, c] in m", size)
    half = np.array([validate.positive_number(s, f"{field}[{i}]") for i, s in enumerate(size)])
    signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
    return signs * half / 2.0


def sphere_inertia(mass: float, radius: float) -> np.ndarray:
    """Solid sphere: ``2/5 m r^2`` about any axis (kg m^2).

    >>> float(sphere_inertia(5.0, 0.1)[0, 0])
    0.020000000000000004
    """
    return np.eye(3) * 0.4 * mass * radius * radius


def hull_mass_properties(vertices: np.ndarray, field: str) -> tuple[np.ndarray, np.ndarray]:
    """Centroid (m) and inertia per unit mass about the centroid (m^2, body axes) of the
    uniform convex hull of ``vertices``: a solid for a polyhedron, a lamina for a polygon.

    Polyhedron: the hull's facets fanned from an interior point into tetrahedra, each with the
    exact second moment ``vol/20 (sum_i p_i p_i^T + (sum_i p_i)(sum_i p_i)^T)``; polygon: the
    triangles of its 2D hull with ``area/12 (sum + (sum)(sum)^T)`` (the same formula, one
    dimension down). Inertia from second moments ``S``: ``J = tr(S) I - S``.

    >>> c, j = hull_mass_properties(box_vertices([2.0, 2.0, 2.0]), "v")
    >>> np.round(np.diag(j), 12).tolist()  # a cube of side 2: (b^2 + c^2)/12 = 2/3
    [0.666666666667, 0.666666666667, 0.666666666667]
    """
    from scipy.spatial import ConvexHull, QhullError

    pts = np.asarray(vertices, dtype=float)
    size = float(np.max(np.linalg.norm(pts - pts.mean(axis=0), axis=1)))
    centred = pts - pts.mean(axis=0)
    _, sing, vt = np.linalg.svd(centred, full_matrices=False)
    if size <= 0 or sing[1] <= FLAT_TOLERANCE * size:
        raise InputError(field, "must span a polygon or a polyhedron (not a point or a line)",
                         pts.tolist())  # fmt: skip
    flat = sing[2] <= FLAT_TOLERANCE * size * max(1.0, np.sqrt(len(pts)))
    try:
        if flat:
            plane_axes = vt[:2]
            hull = ConvexHull(centred @ plane_axes.T)
            ring = centred[hull.vertices]
            origin = ring.mean(axis=0)
            simplices = [(origin, ring[i], ring[(i + 1) % len(ring)]) for i in range(len(ring))]
            measures = [0.5 * np.linalg.norm(np.cross(b - a, c - a)) for a, b, c in simplices]
            factor, dim = 12.0, 3
        else:
            hull = ConvexHull(centred)
            origin = centred[hull.vertices].mean(axis=0)
            simplices = [(origin, *centred[s]) for s in hull.simplices]
            measures = [abs(np.linalg.det(np.array(s[1:]) - s[0])) / 6.0 for s in simplices]
            factor, dim = 20.0, 4
    except QhullError:
        raise InputError(field, "has no convex hull (degenerate vertices)", pts.tolist()) from None
    total = float(sum(measures))
    centroid = sum(m * sum(s) / dim for m, s in zip(measures, simplices, strict=True)) / total
    second = np.zeros((3, 3))
    for m, s in zip(measures, simplices, strict=True):
        rel = [p - centroid for p in s]
        acc = sum(rel)
        second += m / factor * (sum(np.outer(p, p) for p in rel) + np.outer(acc, acc))
    second /= total
    inertia = np.trace(second) * np.eye(3) - second
    return centroid + pts.mean(axis=0), inertia


def is_flat(vertices: np.ndarray) -> bool:
    """Whether the vertices lie in one plane (a polygon)."""
    centred = vertices - vertices.mean(axis=0)
    sing = np.linalg.svd(centred, compute_uv=False)
    size = float(np.max(np.linalg.norm(centred, axis=1)))
    return bool(sing[2] <= FLAT_TOLERANCE * size * max(1.0, np.sqrt(len(vertices))))

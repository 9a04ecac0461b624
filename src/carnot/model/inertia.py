"""Inertia tensors of common shapes, rotations and the parallel-axis theorem.

Every helper returns the inertia tensor about the centre of mass, in world axes, in kg m^2.
Axisymmetric shapes take their symmetry ``axis`` (any non-zero world vector); the others take
an ``orientation``: a rotation matrix whose columns are the shape's own x, y, z axes in world
components (identity by default). Formulas: any table of moments of inertia, e.g.
Meriam & Kraige, *Engineering Mechanics: Dynamics*, Appendix B.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from carnot import validate
from carnot.conventions import Vector

Matrix = np.ndarray


def frame_from_axis(axis: Any, field: str = "axis") -> Matrix:
    """A rotation whose third column is the unit ``axis`` (the rest chosen deterministically).

    >>> frame_from_axis([0, 0, 2])[:, 2].tolist()
    [0.0, 0.0, 1.0]
    """
    from carnot.conventions import contact_frame

    z = validate.unit_vector(axis, field)
    _, x, y = contact_frame(z)
    return np.column_stack([x, y, z])


def rotated(inertia_body: Any, orientation: Any) -> Matrix:
    """``R J R^T``: an inertia given in the body's axes, expressed in world axes."""
    rot = validate.rotation_matrix(orientation, "orientation")
    out = rot @ np.asarray(inertia_body, dtype=float) @ rot.T
    return 0.5 * (out + out.T)


def _axisymmetric(axial: float, transverse: float, axis: Any) -> Matrix:
    return rotated(np.diag([transverse, transverse, axial]), frame_from_axis(axis))


def solid_sphere(mass: float, radius: float) -> Matrix:
    """Solid sphere: ``2/5 m r^2`` about every axis.

    >>> float(solid_sphere(5.0, 0.1)[0, 0])
    0.020000000000000004
    """
    m = validate.positive_number(mass, "mass")
    r = validate.positive_number(radius, "radius")
    return np.eye(3) * 0.4 * m * r * r


def hollow_sphere(mass: float, radius: float) -> Matrix:
    """Thin spherical shell: ``2/3 m r^2`` about every axis."""
    m = validate.positive_number(mass, "mass")
    r = validate.positive_number(radius, "radius")
    return np.eye(3) * (2.0 / 3.0) * m * r * r


def solid_cylinder(mass: float, radius: float, length: float, axis: Any = (0, 0, 1)) -> Matrix:
    """Solid cylinder: axial ``m r^2/2``, transverse ``m (3 r^2 + L^2)/12``.

    >>> np.round(np.diag(solid_cylinder(2.0, 0.1, 0.0 + 1e-9)), 6).tolist()
    [0.005, 0.005, 0.01]
    """
    m = validate.positive_number(mass, "mass")
    r = validate.positive_number(radius, "radius")
    length_ = validate.positive_number(length, "length")
    return _axisymmetric(0.5 * m * r * r, m * (3 * r * r + length_**2) / 12.0, axis)


def hollow_cylinder(
    mass: float,
    radius: float,
    length: float,
    axis: Any = (0, 0, 1),
    inner_radius: float | None = None,
) -> Matrix:
    """Cylindrical tube with outer radius ``r2`` and inner radius ``r1`` (thin-walled,
    ``r1 = r2``, when ``inner_radius`` is not given): axial ``m (r1^2 + r2^2)/2``, transverse
    ``m (3 (r1^2 + r2^2) + L^2)/12``."""
    m = validate.positive_number(mass, "mass")
    r2 = validate.positive_number(radius, "radius")
    length_ = validate.positive_number(length, "length")
    r1 = r2 if inner_radius is None else validate.non_negative_number(inner_radius, "inner_radius")
    if r1 > r2:
        from carnot.errors import InputError

        raise InputError("inner_radius", f"must be <= radius ({r2:g})", r1)
    s = r1 * r1 + r2 * r2
    return _axisymmetric(0.5 * m * s, m * (3 * s + length_**2) / 12.0, axis)


def box(mass: float, size: Any, orientation: Any = None) -> Matrix:
    """Solid cuboid with edges ``size = [a, b, c]`` along its own x, y, z axes:
    ``m (b^2 + c^2)/12`` about x, and so on."""
    m = validate.positive_number(mass, "mass")
    a, b, c = (validate.positive_number(s, f"size[{i}]") for i, s in enumerate(_three(size)))
    body = np.diag([b * b + c * c, a * a + c * c, a * a + b * b]) * m / 12.0
    return rotated(body, np.eye(3) if orientation is None else orientation)


def rod(mass: float, length: float, radius: float, axis: Any = (1, 0, 0)) -> Matrix:
    """Thin rod along ``axis``: transverse ``m L^2/12`` (the slender limit), axial ``m r^2/2``.

    The radius enters only the axial moment, which textbook slender-rod formulas neglect; it
    must be > 0 so that the inertia stays invertible.

    >>> np.round(np.diag(rod(3.0, 2.0, 0.01)), 8).tolist()
    [0.00015, 1.0, 1.0]
    """
    m = validate.positive_number(mass, "mass")
    length_ = validate.positive_number(length, "length")
    r = validate.positive_number(radius, "radius")
    return _axisymmetric(0.5 * m * r * r, m * length_**2 / 12.0, axis)


def disc(mass: float, radius: float, axis: Any = (0, 0, 1)) -> Matrix:
    """Thin circular disc with normal ``axis``: axial ``m r^2/2``, diametral ``m r^2/4``."""
    m = validate.positive_number(mass, "mass")
    r = validate.positive_number(radius, "radius")
    return _axisymmetric(0.5 * m * r * r, 0.25 * m * r * r, axis)


def plate(mass: float, size: Any, orientation: Any = None) -> Matrix:
    """Thin rectangular plate with edges ``size = [a, b]`` along its own x and y axes (normal
    along its z): ``m b^2/12`` about x, ``m a^2/12`` about y, ``m (a^2 + b^2)/12`` about z."""
    m = validate.positive_number(mass, "mass")
    vals = list(size) if isinstance(size, (list, tuple, np.ndarray)) else [size]
    if len(vals) != 2:
        from carnot.errors import InputError

        raise InputError("size", "must be a list of 2 numbers [a, b]", size)
    a, b = (validate.positive_number(s, f"size[{i}]") for i, s in enumerate(vals))
    body = np.diag([b * b, a * a, a * a + b * b]) * m / 12.0
    return rotated(body, np.eye(3) if orientation is None else orientation)


def parallel_axis(inertia_com: Any, mass: float, offset: Any) -> Matrix:
    """Inertia about a point displaced by ``offset = point - x_C`` (m) from the centre of mass:
    ``J_O = J_C + m (|d|^2 I - d d^T)`` (Huygens-Steiner).

    >>> parallel_axis(np.zeros((3, 3)), 2.0, [0.0, 0.0, 1.0]).tolist()
    [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 0.0]]
    """
    d = validate.vector3(offset, "offset")
    m = validate.positive_number(mass, "mass")
    return np.asarray(inertia_com, dtype=float) + m * ((d @ d) * np.eye(3) - np.outer(d, d))


def _three(size: Any) -> list[Any]:
    vals = list(size) if isinstance(size, (list, tuple, np.ndarray)) else [size]
    if len(vals) != 3:
        from carnot.errors import InputError

        raise InputError("size", "must be a list of 3 numbers [a, b, c]", size)
    return vals


#: Shape name -> (helper, the keyword arguments it takes besides ``mass``).
SHAPES: dict[str, tuple[Any, tuple[str, ...], tuple[str, ...]]] = {
    # name: (function, required keys, optional keys)
    "sphere": (solid_sphere, ("radius",), ()),
    "solid_sphere": (solid_sphere, ("radius",), ()),
    "hollow_sphere": (hollow_sphere, ("radius",), ()),
    "solid_cylinder": (solid_cylinder, ("radius", "length"), ("axis",)),
    "cylinder": (solid_cylinder, ("radius", "length"), ("axis",)),
    "hollow_cylinder": (hollow_cylinder, ("radius", "length"), ("axis", "inner_radius")),
    "box": (box, ("size",), ("orientation",)),
    "rod": (rod, ("length", "radius"), ("axis",)),
    "disc": (disc, ("radius",), ("axis",)),
    "plate": (plate, ("size",), ("orientation",)),
}


def shape_inertia(shape: str, mass: float, **dimensions: Any) -> Matrix:
    """The inertia of a named shape (see :data:`SHAPES`).

    >>> float(shape_inertia("sphere", 5.0, radius=0.1)[1, 1])
    0.020000000000000004
    """
    func, _, _ = SHAPES[shape]
    return func(mass, **dimensions)


__all__ = [
    "Vector",
    "box",
    "disc",
    "frame_from_axis",
    "hollow_cylinder",
    "hollow_sphere",
    "parallel_axis",
    "plate",
    "rod",
    "rotated",
    "shape_inertia",
    "solid_cylinder",
    "solid_sphere",
]

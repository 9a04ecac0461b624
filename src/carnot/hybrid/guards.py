"""Guards and models for systems written by their users (the Python API): a point reaching a
plane, a joint reaching its stop, and the model that carries them (DESIGN.md section 10).

The named models build their own guards (:mod:`carnot.hybrid.models`); a model compiled from
``sympy.physics.mechanics`` (:func:`carnot.hybrid.mechanism.compile_mechanics`) takes these:

* :func:`plane_guard`: the point ``p(q)`` strikes the plane ``n . p = offset`` falling
  through it, ``G(x) = n . p(q) - offset``, ``D_x G = (n^T dp/dq, 0)``; after a strike that
  leaves it at rest on the plane, it is held there (its rows ``n^T dp/dq`` and
  ``t^T dp/dq``, ``t = (n_y, -n_x)``) while the plane pushes;
* :func:`stop_guard`: the coordinate ``q_k`` strikes its stop ``b`` (``q_k <= b``, or
  ``q_k >= b`` for a lower stop), ``G = b - q_k`` (``q_k - b``): a joint limit, one
  frictionless row on the coordinates, held through a chatter.

Neither moves the chart's origin nor relabels the coordinates: the model has a fixed base.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from carnot.errors import InputError
from carnot.hybrid.mechanism import Compiled
from carnot.hybrid.model import GapRows, Guard, HybridModel

#: A tangent row shorter than this (relative to the normal row) is no row: the point cannot
#: move along the plane.
NO_ROW = 1e-12


def plane_guard(mechanism: Compiled, point: str, *, normal: Sequence[float] = (0.0, 1.0),
                offset: float = 0.0, name: str | None = None) -> Guard:  # fmt: skip
    """The named point striking the plane ``n . p = offset`` (``n`` a 2-vector in the plane of
    motion, normalized here), from the side ``n`` points to.

    >>> import sympy as sp
    >>> from carnot.hybrid.mechanism import Body, Mechanism, compile_mechanism
    >>> th = sp.Symbol("th")
    >>> bob = (sp.sin(th), -sp.cos(th))
    >>> c = compile_mechanism(Mechanism(floating=(th,), coordinates=(th,), embedding=(th,),
    ...     bodies=(Body(mass=1.0, position=bob),), points={"bob": bob}, gravity=(0, -9.81)), {})
    >>> g = plane_guard(c, "bob", normal=(-1.0, 0.0), offset=-0.5)  # a wall at x = 0.5
    >>> round(g.function(np.array([0.0, 1.0])), 12), g.direction
    (0.5, -1)
    """
    n = np.asarray(normal, dtype=float)
    if n.shape != (2,) or not np.all(np.isfinite(n)) or not np.any(n):
        raise InputError("normal", "must be a non-zero 2-vector (the plane of motion)", normal)
    n = n / np.linalg.norm(n)
    if point not in mechanism.point_names:
        raise InputError("point", f"must be one of the model's points "
                         f"({', '.join(mechanism.point_names)})", point)  # fmt: skip
    size = mechanism.n

    def function(x: np.ndarray) -> float:
        return float(n @ mechanism.point_in_chart(point, x[:size]) - offset)

    def gradient(x: np.ndarray) -> np.ndarray:
        return np.concatenate([n @ mechanism.point_chart_jacobian(point, x[:size]),
                               np.zeros(size)])  # fmt: skip

    tangent = np.array([n[1], -n[0]])

    def rows(x: np.ndarray) -> GapRows:
        jac = mechanism.point_chart_jacobian(point, x[:size])
        bias = mechanism.point_chart_bias(point, x)
        row_n, row_t = n @ jac, tangent @ jac
        # a point that cannot move along the plane (a foot on a vertical slide) has no
        # tangent row: holding it would make the flow's constraint singular
        slides = float(np.linalg.norm(row_t)) > NO_ROW * max(1.0, float(np.linalg.norm(row_n)))
        return GapRows(normal=row_n, normal_bias=float(n @ bias),
                       tangent=row_t if slides else None, tangent_bias=float(tangent @ bias))

    eye = np.eye(size)
    return Guard(name=name or f"{point}_strikes", function=function, gradient=gradient,
                 direction=-1, striking=point, holding=(), relabel=eye, offset=np.zeros(size),
                 velocity_relabel=np.eye(mechanism.n_floating), moves_anchor=False,
                 normal=np.array([n[0], n[1], 0.0]), rows=rows)  # fmt: skip


def stop_guard(mechanism: Compiled, coordinate: int, bound: float, *, upper: bool = True,
               name: str | None = None) -> Guard:  # fmt: skip
    """The coordinate ``q_k`` (``k = coordinate``) striking its stop ``bound``: from below
    (``upper``, ``q_k <= bound``) or from above.

    >>> import sympy as sp
    >>> from carnot.hybrid.mechanism import Body, Mechanism, compile_mechanism
    >>> th = sp.Symbol("th")
    >>> c = compile_mechanism(Mechanism(floating=(th,), coordinates=(th,), embedding=(th,),
    ...     bodies=(Body(mass=1.0, position=(sp.sin(th), -sp.cos(th))),), points={},
    ...     gravity=(0, -9.81)), {})
    >>> stop_guard(c, 0, 0.2).function(np.array([0.0, 0.0]))
    0.2
    """
    size = mechanism.n
    if isinstance(coordinate, bool) or not isinstance(coordinate, int) or \
            not 0 <= coordinate < size:  # fmt: skip
        raise InputError("coordinate", f"must be an index in [0, {size - 1}]", coordinate)
    if mechanism.n_floating != size:
        raise InputError("coordinate", "a stop is on a fixed-base model's own coordinates",
                         show_value=False)  # fmt: skip
    sign = -1.0 if upper else 1.0
    row = np.zeros(2 * size)
    row[coordinate] = sign
    const = -sign * float(bound)

    def function(x: np.ndarray) -> float:
        return float(row @ x + const)

    eye = np.eye(size)
    return Guard(name=name or f"q{coordinate}_stop", function=function,
                 gradient=lambda x: row, direction=-1, striking=name or f"q{coordinate}_stop",
                 holding=(), relabel=eye, offset=np.zeros(size), velocity_relabel=eye,
                 moves_anchor=False, limit_row=row[:size].copy())  # fmt: skip


def motion_model(mechanism: Compiled, guards: Sequence[Guard], *, name: str = "model",
                 coordinates: Sequence[str] | None = None, gravity: Sequence[float] = (0.0, -9.81),
                 total_mass: float = 0.0, notes: str = "") -> HybridModel:  # fmt: skip
    """A fixed-base model in motion from a compiled mechanism and its guards (the floating
    coordinates are the model's own)."""
    names = tuple(coordinates) if coordinates is not None else tuple(
        f"q{k}" for k in range(mechanism.n))  # fmt: skip
    if len(names) != mechanism.n:
        raise InputError("coordinates", f"must name {mechanism.n} coordinates", list(names))
    if not guards:
        raise InputError("guards", "at least one guard (something to strike) is needed", [])
    return HybridModel(name=name, parameters={}, coordinates=names, floating=names,
                       mechanism=mechanism, guards=tuple(guards),
                       normal=np.array([0.0, 1.0, 0.0]), gravity=np.asarray(gravity, float),
                       total_mass=float(total_mass), notes=notes)  # fmt: skip

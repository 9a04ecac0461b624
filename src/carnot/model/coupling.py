"""The coupled parts of a system impact: the blocks of its Delassus operator.

Items ``i`` and ``j`` of a :class:`~carnot.model.system.SystemProblem` (contacts or
constraints) are coupled when ``G_ij = J_i M^-1 J_j^T`` is not zero (``J_i``: the item's
motion rows, 6 x n; ``G_ij``: how an impulse at ``j`` changes the relative velocity at ``i``,
1/kg). ``M^-1`` has the block structure of ``M``: two coordinates share a block when a chain
of nonzero entries of ``M`` joins them (one free body; one kinematic tree in MuJoCo), so
``G_ij`` can be nonzero only when ``J_i`` and ``J_j`` move coordinates of one block. The
parts are the connected components of the graph whose nodes are the coordinates and the items
and whose edges are the nonzero entries of ``M`` (coordinate to coordinate) and of each
item's ``J`` columns (item to coordinate). A fixed body (the world, a floor) has no
coordinates, so it links nothing. The test is on exact zeros: two items in different parts
have ``G_ij = 0`` exactly; two items in one part are coupled or, rarely, merely kept together
(a larger part gives the same answer).

With ``G`` block diagonal over the parts, ``w'' = w' + G Lambda`` splits part by part, and
a law that holds contact by contact (the simultaneous law: Signorini-Newton and Coulomb at
each contact, Glocker, *Set-Valued Force Laws*, 2001, ch. 7) is the product of the parts'
laws: a part's impulses and post-impact velocities are the same solved alone or with the rest
(its solutions are the products of the parts' solutions). What depends on the whole problem
is only what the law decides over all its contacts at once: the velocity scale of its
tolerances (1e-9 of the largest row velocity) and whether uniqueness is verified (a bound
on the number of regimes), and the sequential law's interleaving of sub-impacts across parts.

Three beads on a wire (coordinates x_1, x_2, x_3, unit masses): a stop at each end bead
gives two parts; a contact between beads 1 and 2 joins the first stop to it, one between
beads 2 and 3 joins all:

>>> import numpy as np
>>> from carnot.model.system import System, SystemContact, SystemProblem
>>> def contact(row):
...     return SystemContact(jacobian=[row, [0, 0, 0], [0, 0, 0]], normal=[1, 0, 0])
>>> stop_1, stop_3 = contact([1.0, 0, 0]), contact([0, 0, -1.0])
>>> beads_12, beads_23 = contact([-1.0, 1.0, 0]), contact([0, -1.0, 1.0])
>>> system = System(mass_matrix=np.eye(3), velocity=[-1.0, 0.0, 0.0])
>>> coupled_parts(SystemProblem(system=system, contacts=[stop_1, stop_3]))
((0,), (1,))
>>> coupled_parts(SystemProblem(system=system, contacts=[stop_1, stop_3, beads_12]))
((0, 2), (1,))
>>> coupled_parts(SystemProblem(system=system, contacts=[stop_1, stop_3, beads_12, beads_23]))
((0, 1, 2, 3),)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.model.system import SystemConstraint, SystemContact, SystemProblem
from carnot.space.contact_space import is_sparse


def part_labels(problem: SystemProblem) -> np.ndarray:
    """The part of each item (``problem.items``' order), labels 0, 1, ... in the order of the
    items' first appearance (module docstring)."""
    mass = problem.system.mass_matrix
    moved = np.array([moved_coordinates(item) for item in problem.items], dtype=bool)
    return coupled_labels(moved.reshape(len(problem.items), mass.shape[0]), mass)


def coupled_labels(moved: np.ndarray, mass_matrix: np.ndarray) -> np.ndarray:
    """The part of each of ``k`` items that move the coordinates ``moved`` (k, n; True where
    the item's rows have a nonzero column) of a system of mass matrix ``M`` (n, n): the
    connected components of the graph of the coordinates and the items, whose edges are the
    nonzero entries of ``M`` and of ``moved`` (module docstring), labels 0, 1, ... in the
    order of the items' first appearance. Exact zeros only: two items in different parts
    have ``G_ij = W_i M^-1 W_j^T = 0`` whatever the values.

    A union-find over the edges (plain Python: a few tens of microseconds for tens of items,
    linear in the edges; SciPy's ``connected_components`` costs about 0.15 ms here, mostly
    building its sparse graph: a quarter of a small multiple impact). Items that all move one
    coordinate are one part at once.

    >>> coupled_labels(np.array([[1, 0, 0], [0, 0, 1], [1, 1, 0]], dtype=bool), np.eye(3))
    array([0, 1, 0])
    >>> coupled_labels(np.array([[1, 0], [0, 1]], dtype=bool), np.array([[2.0, 1], [1, 2]]))
    array([0, 0])
    """
    k, n = moved.shape
    if is_sparse(moved) or is_sparse(mass_matrix):
        return _sparse_labels(moved, mass_matrix)
    if k == 0 or bool(np.any(np.all(moved, axis=0))):
        return np.zeros(k, dtype=int)
    parent = list(range(n + k))  # nodes: the coordinates, then the items

    def root(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]  # path halving
            x = parent[x]
        return x

    coord_a, coord_b = np.nonzero(np.triu(mass_matrix != 0.0, 1))
    item, coord = np.nonzero(moved)
    for x, y in zip((coord_a.tolist() + (item + n).tolist()),
                    (coord_b.tolist() + coord.tolist()), strict=True):  # fmt: skip
        rx, ry = root(x), root(y)
        if rx != ry:
            parent[rx] = ry
    first: dict[int, int] = {}
    return np.array([first.setdefault(root(n + i), len(first)) for i in range(k)], dtype=int)


def _sparse_labels(moved: Any, mass_matrix: Any) -> np.ndarray:
    """:func:`coupled_labels` for many bodies (``M`` or ``moved`` held sparse): the same
    components of the same graph, by SciPy's ``connected_components`` (linear in the edges,
    where the union-find's Python loop costs a microsecond an edge), labelled the same way.

    >>> import scipy.sparse as sp
    >>> moved = sp.csr_matrix(np.array([[1, 0, 0], [0, 0, 1], [1, 1, 0]], dtype=bool))
    >>> _sparse_labels(moved, sp.identity(3, format="csr"))
    array([0, 1, 0])
    """
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    k, n = moved.shape
    if k == 0:
        return np.zeros(0, dtype=int)
    mass_edges = sp.csr_matrix(mass_matrix) if is_sparse(mass_matrix) else \
        sp.csr_matrix(np.asarray(mass_matrix))  # fmt: skip
    mass_edges = (abs(mass_edges) > 0).astype(np.int8)
    item_edges = (abs(sp.csr_matrix(moved)) > 0).astype(np.int8)
    graph = sp.bmat([[mass_edges, item_edges.T], [item_edges, None]], format="csr")
    _, components = connected_components(graph, directed=False)
    item_parts = components[n:]
    parts, first = np.unique(item_parts, return_index=True)  # each part's first item
    rank = np.empty(len(parts), dtype=int)
    rank[np.argsort(first)] = np.arange(len(parts))  # parts by their first item
    return rank[np.searchsorted(parts, item_parts)]


def coupled_parts(problem: SystemProblem) -> tuple[tuple[int, ...], ...]:
    """The items (indices into ``problem.items``) of each part, parts in the order of their
    first item (module docstring)."""
    labels = part_labels(problem)
    count = int(labels.max()) + 1 if labels.size else 0
    return tuple(tuple(int(i) for i in np.flatnonzero(labels == p)) for p in range(count))


def coupled_items(problem: SystemProblem, seeds: Sequence[int]) -> np.ndarray:
    """Whether each item (``problem.items``' order) is in a part holding one of ``seeds``:
    the part grown from the seeds' coordinates, through ``M``'s nonzero entries and the
    items that move them, until it stops growing (the same parts as :func:`part_labels`, a
    fifth of the time for the one part an audit episode needs: no graph is built).

    >>> import numpy as np
    >>> from carnot.model.system import System, SystemContact, SystemProblem
    >>> jac = [[1.0, 0, 0], [0, 0, 0], [0, 0, 0]], [[0, 1.0, -1.0], [0, 0, 0], [0, 0, 0]]
    >>> p = SystemProblem(system=System(mass_matrix=[[2, 1, 0], [1, 2, 0], [0, 0, 1.0]],
    ...                                 velocity=[-1.0, 0, 0]),
    ...                   contacts=[SystemContact(jacobian=j, normal=[1, 0, 0]) for j in jac])
    >>> coupled_items(p, [0]).tolist()  # M couples coordinates 0 and 1
    [True, True]
    """
    moves = np.array([moved_coordinates(item) for item in problem.items])
    return coupled_mask(moves, problem.system.mass_matrix, seeds)


def coupled_mask(moved: np.ndarray, mass_matrix: np.ndarray, seeds: Sequence[int]) -> np.ndarray:
    """:func:`coupled_items` on arrays: whether each of ``k`` items that move the coordinates
    ``moved`` (k, n; True where the item's rows have a nonzero column) is in a part holding
    one of ``seeds`` (indices of items), for a mass matrix ``M`` (n, n). A caller that has
    the items' Jacobians before making the items (``carnot.model.mjcf``) decides here which
    to make.

    >>> coupled_mask(np.array([[1, 0, 0], [0, 0, 1], [0, 1, 0]], dtype=bool),
    ...              np.array([[2.0, 1, 0], [1, 2, 0], [0, 0, 1]]), [0]).tolist()
    [True, False, True]
    """
    linked = mass_matrix != 0.0
    coordinates = np.any(moved[list(seeds)], axis=0)
    while True:
        grown = np.any(linked[coordinates], axis=0)
        grown |= np.any(moved[np.any(moved[:, grown], axis=1)], axis=0)
        if np.array_equal(grown, coordinates):
            return np.asarray(np.any(moved[:, coordinates], axis=1))
        coordinates = grown


def moved_coordinates(item: SystemContact | SystemConstraint) -> np.ndarray:
    """The coordinates an item's motion rows ``J_i`` move (nonzero columns)."""
    moved = np.any(item.jacobian != 0.0, axis=0)
    if item.angular_jacobian is not None:
        moved |= np.any(item.angular_jacobian != 0.0, axis=0)
    return moved


def coupled_problem(problem: SystemProblem, seeds: Sequence[int]) -> SystemProblem:
    """``problem`` with only the items coupled to ``seeds`` (indices into ``problem.items``):
    the parts holding them (module docstring). The items keep their ``where`` (their place in
    the whole problem); the system (``M``, ``q'``) is the whole one, so the coordinates of the
    other parts keep their velocities.

    >>> import numpy as np
    >>> from carnot.model.system import System, SystemContact, SystemProblem
    >>> lone = SystemContact(jacobian=[[1.0, 0], [0, 0], [0, 0]], normal=[1, 0, 0])
    >>> other = SystemContact(jacobian=[[0, 1.0], [0, 0], [0, 0]], normal=[1, 0, 0],
    ...                       where="contacts[1]")
    >>> p = SystemProblem(system=System(mass_matrix=np.eye(2), velocity=[-1.0, -2.0]),
    ...                   contacts=[lone, other])
    >>> [c.where for c in coupled_problem(p, [1]).contacts]
    ['contacts[1]']
    >>> coupled_problem(p, [2])
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: seeds: must be indices of the problem's 2 items, got [2]
    """
    items = problem.items
    if not seeds or any(not 0 <= int(s) < len(items) for s in seeds):
        raise InputError("seeds", f"must be indices of the problem's {len(items)} items",
                         list(seeds))  # fmt: skip
    coupled = coupled_items(problem, [int(s) for s in seeds])
    keep = [item for item, kept in zip(items, coupled.tolist(), strict=True) if kept]
    return dataclasses.replace(
        problem,
        contacts=[i for i in keep if isinstance(i, SystemContact)],
        constraints=[i for i in keep if not isinstance(i, SystemContact)],
    )


__all__ = [
    "coupled_items", "coupled_labels", "coupled_mask", "coupled_parts", "coupled_problem",
    "moved_coordinates", "part_labels",
]  # fmt: skip

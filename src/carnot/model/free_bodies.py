"""Free rigid bodies as a producer of contact space, and their part of the report.

``u`` stacks ``(v, omega)`` of every movable body that some contact or constraint touches
(bodies in no item keep their motion and take no columns, so the cost follows the bodies
that take part); ``M`` is block diagonal ``(m I, J_C)``. The motion rows of an item at point
``p`` map ``u`` to the relative motion there (conventions.py):

    w = (v_a + omega_a x r_a) - (v_b + omega_b x r_b),      Omega = omega_a - omega_b,

and ``omega x r = -[r]_x omega``, so body ``a``'s columns are ``[[I, -[r_a]_x], [0, I]]`` and
body ``b``'s the same with ``r_b`` and the opposite sign.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from math import sqrt
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.model.bodies import RigidBody
from carnot.model.contacts import Item, PointConstraint
from carnot.model.problem import ImpactProblem
from carnot.result import BodyMotion, ItemOutcome, MomentumCheck
from carnot.space import ContactSpace, RowBlock
from carnot.vector3 import (
    cross_floats,
    dot_floats,
    length_floats,
    mat_vec_floats,
    norm,
)


@dataclass(frozen=True, kw_only=True, eq=False)
class FreeBodySpace:
    """The contact space of a problem of free bodies and which bodies own which columns:
    ``columns[name]`` is the slice of ``u`` of movable body ``name`` (absent: not in any
    item)."""

    space: ContactSpace
    columns: dict[str, slice]


#: Columns (6 per movable body) above which the contact space is held sparse.
SPARSE_FROM_COLUMNS = 300

def item_sides(item: Item) -> tuple[str, str | None]:
    """The bodies an item acts on: ``(a, b)`` of a contact, ``(body, other)`` of a
    constraint (``None``: the fixed world)."""
    if isinstance(item, PointConstraint):
        return item.body, item.other
    return item.a, item.b


def assemble(
    problem: ImpactProblem, items: Sequence[Item], blocks: Sequence[RowBlock]
) -> FreeBodySpace:
    """Stack the bodies that take part and the rows of ``blocks`` (one per item) into a
    :class:`~carnot.space.ContactSpace`.

    >>> from carnot.model.bodies import FixedBody
    >>> from carnot.model.contacts import PointContact
    >>> ball = RigidBody(mass=2.0, inertia_com=np.eye(3), velocity_com=[0, 0, -1.0], name="ball")
    >>> contact = PointContact(a="ball", b="floor", point=[0, 0, -1.0], normal=[0, 0, 1])
    >>> fb = assemble(ImpactProblem(bodies={"ball": ball, "floor": FixedBody(name="floor")},
    ...                             contacts=[contact]), [contact], [contact.rows()])
    >>> fb.space.delassus().tolist(), fb.columns
    ([[0.5]], {'ball': slice(0, 6, None)})
    """
    columns: dict[str, slice] = {}
    for item in items:
        for name in item_sides(item):
            if name is not None and name not in columns and not problem.bodies[name].fixed:
                columns[name] = slice(6 * len(columns), 6 * len(columns) + 6)
    n = 6 * len(columns)
    bodies = {name: problem.bodies[name] for name in columns}
    motions = [body.motion_com for body in bodies.values()]  # type: ignore[union-attr]
    u = np.concatenate(motions) if motions else np.zeros(0)
    sizes = [b.size for b in blocks]
    sparse = n > SPARSE_FROM_COLUMNS
    if sparse:
        import scipy.sparse as sp  # (many bodies only: one impact loads no SciPy)

        # many bodies: M, M^-1, the motion rows and W are block-sparse (each item's rows touch
        # at most two bodies' 6 columns), held so: dense, a thousand balls would need 1 GB
        mass: Any = _block_diagonal(sp, [b.mass_block for b in bodies.values()])  # type: ignore[union-attr]
        mass_inv: Any = _block_diagonal(sp, [b.mass_block_inv for b in bodies.values()])  # type: ignore[union-attr]
    else:
        mass = np.zeros((n, n))
        mass_inv = np.zeros((n, n))
        for name, s in columns.items():
            body = bodies[name]
            assert isinstance(body, RigidBody)
            mass[s, s] = body.mass_block
            mass_inv[s, s] = body.mass_block_inv
    motion: Any = None if sparse else np.zeros((6 * len(items), n))
    jacobian: Any = None if sparse else np.zeros((sum(sizes), n))
    triplets: dict[str, list[np.ndarray]] = {"mr": [], "mc": [], "mv": [], "jr": [], "jc": [],
                                             "jv": []}  # fmt: skip
    ends = list(itertools.accumulate(sizes))
    # every block's rows stacked: the closed form below, once for all the rows
    linear = np.concatenate([b.linear for b in blocks]) if blocks else np.zeros((0, 3))
    angular = np.concatenate([b.angular for b in blocks]) if blocks else np.zeros((0, 3))
    row_item = np.repeat(np.arange(len(items)), sizes)  # each row's item
    for side, sign in ((0, 1.0), (-1, -1.0)):
        levers = np.zeros((len(items), 3))
        placed: list[tuple[int, slice]] = []
        for k, (item, block) in enumerate(zip(items, blocks, strict=True)):
            name = item_sides(item)[side]
            if name is None or name not in columns:
                continue  # the fixed world or a fixed body: no columns
            lever = block.point - bodies[name].position_com  # type: ignore[union-attr]
            levers[k] = lever
            if not sparse:
                motion[6 * k : 6 * k + 6, columns[name]] = _point_motion(lever, sign)
            placed.append((k, columns[name]))
        if placed:
            values = _point_rows_all(np.repeat(levers, sizes, axis=0), linear, angular, sign)
            if sparse:
                # every placed item's entries at once, in the order of the items (so the
                # duplicates an item with both sides on one body adds are summed as before)
                ks = np.array([k for k, _ in placed])
                starts = np.array([cols.start for _, cols in placed])
                six = np.arange(6)
                triplets["mr"].append(np.repeat(6 * ks[:, None] + six, 6, axis=1).ravel())
                triplets["mc"].append(np.tile(starts[:, None] + six, 6).ravel())
                triplets["mv"].append(_point_motions(levers[ks], sign).ravel())
                first = np.full(len(items), -1)
                first[ks] = starts
                rows = np.flatnonzero(first[row_item] >= 0)
                triplets["jr"].append(np.repeat(rows, 6))
                triplets["jc"].append((first[row_item[rows]][:, None] + six).ravel())
                triplets["jv"].append(values[rows].ravel())
                continue
            if len(placed) == len(blocks) and all(cols == placed[0][1] for _, cols in placed):
                jacobian[:, placed[0][1]] = values  # every item on one body's side: at once
                continue
            for k, cols in placed:
                jacobian[ends[k] - sizes[k] : ends[k], cols] = values[ends[k] - sizes[k] : ends[k]]
    if sparse:

        def stacked(key: str) -> np.ndarray:
            return np.concatenate(triplets[key]) if triplets[key] else np.zeros(0)

        # (coo_matrix adds the entries of an item whose two sides are one body's columns)
        motion = sp.coo_matrix((stacked("mv"), (stacked("mr"), stacked("mc"))),
                               shape=(6 * len(items), n)).tocsr()  # fmt: skip
        jacobian = sp.coo_matrix((stacked("jv"), (stacked("jr"), stacked("jc"))),
                                 shape=(sum(sizes), n)).tocsr()  # fmt: skip
    space = ContactSpace(
        u_before=u, mass_matrix=mass, mass_matrix_inv=mass_inv, motion=motion,
        blocks=tuple(blocks), jacobian=jacobian,
    )  # fmt: skip
    return FreeBodySpace(space=space, columns=columns)


def _point_motion(lever: np.ndarray, sign: float) -> np.ndarray:
    """``sign [[I, -[r]_x], [0, I]]``: ``(v, omega) -> sign (v + omega x r, omega)``."""
    x, y, z = (sign * lever).tolist()
    out = _IDENTITY6 * sign
    out[0, 4], out[0, 5], out[1, 3], out[1, 5], out[2, 3], out[2, 4] = z, -y, -z, x, y, -x
    return out


def _point_motions(levers: np.ndarray, sign: float) -> np.ndarray:
    """:func:`_point_motion` of each lever at once (K x 6 x 6).

    >>> r = np.array([[0.1, -0.2, 0.3], [1.0, 2.0, 3.0]])
    >>> bool(np.array_equal(_point_motions(r, -1.0)[1], _point_motion(r[1], -1.0)))
    True
    """
    x, y, z = (sign * levers).T
    out = np.broadcast_to(_IDENTITY6 * sign, (levers.shape[0], 6, 6)).copy()
    out[:, 0, 4], out[:, 0, 5], out[:, 1, 3] = z, -y, -z
    out[:, 1, 5], out[:, 2, 3], out[:, 2, 4] = x, y, -x
    return out


def _block_diagonal(sp: Any, blocks: Sequence[np.ndarray]) -> Any:
    """The block-diagonal CSR matrix of equal square ``blocks``, every entry of each block
    stored (as ``scipy.sparse.block_diag(blocks, format="csr")`` stores them, the same
    matrix entry for entry, without its conversion of each block).

    >>> import scipy.sparse as sp
    >>> m = _block_diagonal(sp, [np.eye(2), 2 * np.eye(2)])
    >>> m.toarray().tolist(), m.nnz
    ([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 2.0, 0.0], [0.0, 0.0, 0.0, 2.0]], 8)
    """
    data = np.stack(blocks)
    count, size = data.shape[0], data.shape[1]
    return sp.bsr_matrix((data, np.arange(count), np.arange(count + 1)),
                         shape=(count * size, count * size)).tocsr()  # fmt: skip


def _point_rows_all(
    levers: np.ndarray, linear: np.ndarray, angular: np.ndarray, sign: float
) -> np.ndarray:
    """``sign [c_lin, r x c_lin + c_ang]`` for many rows at once (the columns of ``W`` of a
    body's side): row ``k`` has the lever ``levers[k]`` and the coefficients
    ``linear[k]``, ``angular[k]``; W_i = C_i J_i in closed form, ``c_lin . (omega x r) =
    omega . (r x c_lin)``.

    >>> _point_rows_all(np.array([[0, 0, -1.0]]), np.array([[0, 0, 1.0]]), np.zeros((1, 3)),
    ...                 -1.0).tolist()
    [[-0.0, -0.0, -1.0, -0.0, -0.0, -0.0]]
    """
    r0, r1, r2 = levers.T
    c0, c1, c2 = linear.T
    out = np.empty((levers.shape[0], 6))
    out[:, :3] = sign * linear
    out[:, 3] = sign * ((r1 * c2 - r2 * c1) + angular[:, 0])
    out[:, 4] = sign * ((r2 * c0 - r0 * c2) + angular[:, 1])
    out[:, 5] = sign * ((r0 * c1 - r1 * c0) + angular[:, 2])
    return out


_IDENTITY6 = np.eye(6)


def check_pins(problem: ImpactProblem, items: Sequence[Item], fb: FreeBodySpace) -> None:
    """A pin holds before the impact: its relative velocity must already be zero, to 1e-9 of
    the velocity scale of the bodies it joins (``|v| + |omega| |r|``: at a pin the point's own
    speed is zero, so it cannot set the scale)."""
    for k, item in enumerate(items):
        if not isinstance(item, PointConstraint) or item.kind != "pin":
            continue
        w, _ = fb.space.motion_at(k, fb.space.u_before)
        scale = 0.0
        for name in item_sides(item):
            body = problem.bodies[name] if name is not None else None
            if isinstance(body, RigidBody):
                lever = norm(item.point - body.position_com)
                scale += norm(body.velocity_com) + norm(body.angular_velocity) * lever
        if norm(w) > 1e-9 * scale:
            raise InputError(
                f"{item.where}",
                "a pin needs zero relative velocity at its point before the impact "
                "(|w'| <= 1e-9 of the bodies' velocity scale |v| + |omega| |r|; type = "
                '"fasten" is the sudden constraint); relative velocity w\' (m/s)',
                [float(x) for x in w],
            )


def momentum_check(
    problem: ImpactProblem,
    fb: FreeBodySpace,
    u_after: np.ndarray,
    outcomes: Sequence[ItemOutcome],
) -> MomentumCheck:
    """:func:`momentum_balance` of the bodies that own columns of ``fb``'s contact space."""
    before = fb.space.u_before.tolist()
    after = u_after.tolist()
    moves = []
    for name, s in fb.columns.items():
        body = problem.bodies[name]
        assert isinstance(body, RigidBody)
        moves.append((body, before[s.start : s.stop], after[s.start : s.stop]))
    return momentum_balance(problem, moves, outcomes)


def momentum_balance(
    problem: ImpactProblem,
    moves: Sequence[tuple[RigidBody, Sequence[float], Sequence[float]]],
    outcomes: Sequence[ItemOutcome],
) -> MomentumCheck:
    """Change of the movable bodies' linear momentum (kg m/s) and angular momentum about the
    world origin (kg m^2/s) against the impulses the fixed world gave them: a check of the
    whole pipeline by Newton-Euler, independent of the contact space. ``moves``: each body
    that moved with its ``(v, omega)`` before and after, six floats each. (Plain floats: a
    single impact's check is a few dozen products, cheaper than NumPy's calls.)"""
    # written out in scalars: this is a third of a single impact's cost in list arithmetic
    lx = ly = lz = hx = hy = hz = lin_scale = ang_scale = 0.0
    for body, before, after in moves:
        m = body.mass
        x0, x1, x2 = body.position_com.tolist()
        (j00, j01, j02), (j10, j11, j12), (j20, j21, j22) = body.inertia_com.tolist()
        v0, v1, v2, o0, o1, o2 = before
        pa, pb, pc = m * (after[0] - v0), m * (after[1] - v1), m * (after[2] - v2)  # m dv
        d0, d1, d2 = after[3] - o0, after[4] - o1, after[5] - o2  # d omega
        jd0 = j00 * d0 + j01 * d1 + j02 * d2
        jd1 = j10 * d0 + j11 * d1 + j12 * d2
        jd2 = j20 * d0 + j21 * d1 + j22 * d2
        xp0, xp1, xp2 = x1 * pc - x2 * pb, x2 * pa - x0 * pc, x0 * pb - x1 * pa  # x x m dv
        # angular momentum before about the origin: J omega + x x m v
        h0 = j00 * o0 + j01 * o1 + j02 * o2 + m * (x1 * v2 - x2 * v1)
        h1 = j10 * o0 + j11 * o1 + j12 * o2 + m * (x2 * v0 - x0 * v2)
        h2 = j20 * o0 + j21 * o1 + j22 * o2 + m * (x0 * v1 - x1 * v0)
        lx, ly, lz = lx + pa, ly + pb, lz + pc
        hx, hy, hz = hx + jd0 + xp0, hy + jd1 + xp1, hz + jd2 + xp2
        lin_scale += m * sqrt(v0 * v0 + v1 * v1 + v2 * v2) + sqrt(pa * pa + pb * pb + pc * pc)
        ang_scale += (sqrt(h0 * h0 + h1 * h1 + h2 * h2) + sqrt(jd0 * jd0 + jd1 * jd1 + jd2 * jd2)
                      + sqrt(xp0 * xp0 + xp1 * xp1 + xp2 * xp2))  # fmt: skip
    lin_change = [lx, ly, lz]
    ang_change = [hx, hy, hz]
    lin_ext = [0.0, 0.0, 0.0]
    ang_ext = [0.0, 0.0, 0.0]
    for o in outcomes:
        a_moves = not problem.bodies[o.a].fixed
        b_moves = o.b is not None and not problem.bodies[o.b].fixed
        if a_moves == b_moves:
            continue  # internal to the movable set, or (impossible) between fixed bodies
        sign = 1.0 if a_moves else -1.0
        p = o.impulse.tolist()
        r_x_p = cross_floats(o.point.tolist(), p)
        for i, m_p in enumerate(o.moment.tolist()):
            lin_ext[i] += sign * p[i]
            ang_ext[i] += sign * (r_x_p[i] + m_p)
    lin_res = [a - b for a, b in zip(lin_change, lin_ext, strict=True)]
    ang_res = [a - b for a, b in zip(ang_change, ang_ext, strict=True)]
    return MomentumCheck(
        linear_change=np.array(lin_change),
        linear_external=np.array(lin_ext),
        angular_change=np.array(ang_change),
        angular_external=np.array(ang_ext),
        linear_residual=length_floats(lin_res) / (lin_scale + 1e-300),
        angular_residual=length_floats(ang_res) / (ang_scale + 1e-300),
    )


def body_report(
    problem: ImpactProblem, fb: FreeBodySpace, u_after: np.ndarray
) -> tuple[dict[str, BodyMotion], float, float]:
    """Every body's motion before and after, and the kinetic energies ``E'`` and ``E''`` (J)
    by Koenig's formula body by body (paper eq. 5): the direct route of the ledger,
    independent of the assembled ``M``."""
    motions: dict[str, BodyMotion] = {}
    before = 0.0
    after = 0.0
    for name, body in problem.bodies.items():
        if not isinstance(body, RigidBody):
            motions[name] = fixed_motion(name)
            continue
        v1, om1 = body.velocity_com, body.angular_velocity
        s = fb.columns.get(name)
        v2, om2 = (v1, om1) if s is None else (u_after[s.start : s.start + 3], u_after[s][3:])
        v2, om2 = read_only(v2), read_only(om2)
        motions[name] = BodyMotion(
            name=name, fixed=False, velocity_before=v1, angular_velocity_before=om1,
            velocity_after=v2, angular_velocity_after=om2,
        )  # fmt: skip
        before += _koenig(body, v1, om1)
        after += _koenig(body, v2, om2)
    return motions, before, after


def _koenig(body: RigidBody, v: np.ndarray, omega: np.ndarray) -> float:
    """``1/2 (m v . v + omega . J_C omega)`` (J), paper eq. (5)."""
    v_, om = v.tolist(), omega.tolist()
    j_om = mat_vec_floats(body.inertia_com.tolist(), om)
    return 0.5 * (body.mass * dot_floats(v_, v_) + dot_floats(om, j_om))


@functools.lru_cache(maxsize=1024)
def fixed_motion(name: str) -> BodyMotion:
    """A fixed body's report: at rest before and after (immutable, so kept by name: a floor
    is reported at every impact)."""
    return BodyMotion(
        name=name, fixed=True, velocity_before=_ZERO3, angular_velocity_before=_ZERO3,
        velocity_after=_ZERO3, angular_velocity_after=_ZERO3,
    )  # fmt: skip


_ZERO3 = np.zeros(3)
_ZERO3.setflags(write=False)


def read_only(x: np.ndarray) -> np.ndarray:
    """A read-only float copy of ``x`` (a report's vectors cannot be changed in place)."""
    out = np.array(x, dtype=float)
    out.setflags(write=False)
    return out

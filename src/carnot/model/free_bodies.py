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

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from carnot.errors import InputError
from carnot.model.bodies import RigidBody
from carnot.model.contacts import Item, PointConstraint
from carnot.model.problem import ImpactProblem
from carnot.result import BodyMotion, ItemOutcome, MomentumCheck
from carnot.space import ContactSpace, RowBlock
from carnot.vector3 import (
    cross,
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
    mass = np.zeros((n, n))
    mass_inv = np.zeros((n, n))
    bodies = {name: problem.bodies[name] for name in columns}
    for name, s in columns.items():
        body = bodies[name]
        assert isinstance(body, RigidBody)
        mass[s, s] = body.mass_block
        mass_inv[s, s] = body.mass_block_inv
    motions = [body.motion_com for body in bodies.values()]  # type: ignore[union-attr]
    u = np.concatenate(motions) if motions else np.zeros(0)
    motion = np.zeros((6 * len(items), n))
    jacobian = np.zeros((sum(b.size for b in blocks), n))
    start = 0
    for k, (item, block) in enumerate(zip(items, blocks, strict=True)):
        rows = slice(start, start + block.size)
        start += block.size
        for name, sign in zip(item_sides(item), (1.0, -1.0), strict=True):
            if name is None or name not in columns:
                continue  # the fixed world or a fixed body: no columns
            cols = columns[name]
            lever = block.point - bodies[name].position_com  # type: ignore[union-attr]
            motion[6 * k : 6 * k + 6, cols] = _point_motion(lever, sign)
            # W_i = C_i J_i in closed form: c_lin . (omega x r) = omega . (r x c_lin)
            jacobian[rows, cols] = _point_rows(lever, block, sign)
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


def _point_rows(lever: np.ndarray, block: RowBlock, sign: float) -> np.ndarray:
    """``sign [c_lin, r x c_lin + c_ang]`` for each row of ``block``: its columns of ``W``."""
    r = lever.tolist()
    return np.array(
        [
            [sign * c for c in lin]
            + [sign * (a + b) for a, b in zip(cross_floats(r, lin), ang, strict=True)]
            for lin, ang in zip(block.linear.tolist(), block.angular.tolist(), strict=True)
        ]
    )


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
    """Change of the movable bodies' linear momentum (kg m/s) and angular momentum about the
    world origin (kg m^2/s) against the impulses the fixed world gave them: a check of the
    whole pipeline by Newton-Euler, independent of the contact space. (Plain floats: a
    single impact's check is a few dozen products, cheaper than NumPy's calls.)"""
    before = fb.space.u_before.tolist()
    after = u_after.tolist()
    lin_change = [0.0, 0.0, 0.0]
    ang_change = [0.0, 0.0, 0.0]
    lin_scale = 0.0
    ang_scale = 0.0
    for name, s in fb.columns.items():
        body = problem.bodies[name]
        assert isinstance(body, RigidBody)
        m = body.mass
        x = body.position_com.tolist()
        j = body.inertia_com.tolist()
        v1, om1 = before[s.start : s.start + 3], before[s.start + 3 : s.stop]
        m_dv = [m * (a - b) for a, b in zip(after[s.start : s.start + 3], v1, strict=True)]
        dom = [a - b for a, b in zip(after[s.start + 3 : s.stop], om1, strict=True)]
        j_dom = mat_vec_floats(j, dom)
        x_m_dv = cross_floats(x, m_dv)
        m_v = [m * c for c in v1]
        h_before = [a + b for a, b in zip(mat_vec_floats(j, om1), cross_floats(x, m_v),
                                          strict=True)]  # fmt: skip
        for i in range(3):
            lin_change[i] += m_dv[i]
            ang_change[i] += j_dom[i] + x_m_dv[i]
        lin_scale += m * length_floats(v1) + length_floats(m_dv)
        ang_scale += length_floats(h_before) + length_floats(j_dom) + length_floats(x_m_dv)
    lin_ext = np.zeros(3)
    ang_ext = np.zeros(3)
    for o in outcomes:
        a_moves = not problem.bodies[o.a].fixed
        b_moves = o.b is not None and not problem.bodies[o.b].fixed
        if a_moves == b_moves:
            continue  # internal to the movable set, or (impossible) between fixed bodies
        sign = 1.0 if a_moves else -1.0
        lin_ext += sign * o.impulse
        ang_ext += sign * (cross(o.point, o.impulse) + o.moment)
    lin = np.array(lin_change)
    ang = np.array(ang_change)
    return MomentumCheck(
        linear_change=lin,
        linear_external=lin_ext,
        angular_change=ang,
        angular_external=ang_ext,
        linear_residual=norm(lin - lin_ext) / (lin_scale + 1e-300),
        angular_residual=norm(ang - ang_ext) / (ang_scale + 1e-300),
    )


def body_report(
    problem: ImpactProblem, fb: FreeBodySpace, u_after: np.ndarray
) -> tuple[dict[str, BodyMotion], float, float]:
    """Every body's motion before and after, and the kinetic energies ``E'`` and ``E''`` (J)
    by Koenig's formula body by body (paper eq. 5): the direct route of the ledger,
    independent of the assembled ``M``."""
    zero = np.zeros(3)
    motions: dict[str, BodyMotion] = {}
    before = 0.0
    after = 0.0
    for name, body in problem.bodies.items():
        if not isinstance(body, RigidBody):
            motions[name] = BodyMotion(
                name=name, fixed=True, velocity_before=zero, angular_velocity_before=zero,
                velocity_after=zero, angular_velocity_after=zero,
            )  # fmt: skip
            continue
        v1, om1 = body.velocity_com, body.angular_velocity
        s = fb.columns.get(name)
        v2, om2 = (v1, om1) if s is None else (u_after[s.start : s.start + 3], u_after[s][3:])
        v2, om2 = _read_only(v2), _read_only(om2)
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


def _read_only(x: np.ndarray) -> np.ndarray:
    out = np.array(x, dtype=float)
    out.setflags(write=False)
    return out

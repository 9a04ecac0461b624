"""Assembly of the contact-space problem (DESIGN.md section 1).

Generalized velocity ``u`` stacks ``(v, omega)`` per movable body; the mass matrix ``M`` is
block diagonal ``(m I, J_C)``; each Jacobian row ``W_i`` maps ``u`` to a row velocity
``w_i = W_i u``. For a row ``(c_lin, c_ang)`` at point ``p`` (contacts.py):

    W_i[body a] = [ c_lin,  r_a x c_lin + c_ang]     W_i[body b] = -[ c_lin,  r_b x c_lin + c_ang]

because ``c_lin . (omega x r) = omega . (r x c_lin)``. An impulse ``Lambda`` on the rows changes
the velocities by ``M^-1 W^T Lambda``; the Delassus operator is ``G = W M^-1 W^T``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from carnot.bodies import RigidBody
from carnot.contacts import RowBlock
from carnot.problem import ImpactProblem


@dataclass(frozen=True, kw_only=True, eq=False)
class ContactSpace:
    """``u'``, ``M``, ``M^-1`` and the stacked Jacobian ``W`` of a problem (SI units)."""

    movable: tuple[str, ...]
    mass_matrix: np.ndarray
    mass_matrix_inv: np.ndarray
    u_before: np.ndarray
    jacobian: np.ndarray
    blocks: tuple[RowBlock, ...]
    slices: tuple[slice, ...]

    def columns(self, name: str) -> slice:
        """The six columns of ``u`` that belong to movable body ``name``."""
        i = self.movable.index(name)
        return slice(6 * i, 6 * i + 6)

    def delassus(self, rows: np.ndarray | slice | None = None) -> np.ndarray:
        """``G = W M^-1 W^T`` restricted to ``rows`` (all rows by default)."""
        w = self.jacobian if rows is None else self.jacobian[rows]
        return w @ self.mass_matrix_inv @ w.T


def body_jacobian(block: RowBlock, body: RigidBody, sign: float) -> np.ndarray:
    """The (k, 6) columns of ``block`` for one body; ``sign`` is +1 for ``a``, -1 for ``b``."""
    lever = block.point - body.position_com
    angular = np.cross(lever, block.linear) + block.angular
    return sign * np.hstack([block.linear, angular])


def assemble(problem: ImpactProblem, blocks: tuple[RowBlock, ...]) -> ContactSpace:
    """Stack the bodies and the rows of ``blocks`` into a :class:`ContactSpace`."""
    movable = problem.movable
    n = 6 * len(movable)
    mass = np.zeros((n, n))
    mass_inv = np.zeros((n, n))
    u = np.zeros(n)
    for i, name in enumerate(movable):
        body = problem.bodies[name]
        assert isinstance(body, RigidBody)
        s = slice(6 * i, 6 * i + 6)
        mass[s, s] = np.block(
            [[body.mass * np.eye(3), np.zeros((3, 3))], [np.zeros((3, 3)), body.inertia_com]]
        )
        mass_inv[s, s] = np.block(
            [
                [np.eye(3) / body.mass, np.zeros((3, 3))],
                [np.zeros((3, 3)), np.linalg.inv(body.inertia_com)],
            ]
        )
        u[s] = np.concatenate([body.velocity_com, body.angular_velocity])
    total = sum(b.size for b in blocks)
    jac = np.zeros((total, n))
    slices = []
    start = 0
    for block in blocks:
        rows = slice(start, start + block.size)
        slices.append(rows)
        sides: tuple[tuple[str | None, float], ...] = ((block.body_a, 1.0), (block.body_b, -1.0))
        for side, sign in sides:
            if side is None:
                continue
            body = problem.bodies[side]
            if isinstance(body, RigidBody):
                i = movable.index(side)
                jac[rows, 6 * i : 6 * i + 6] += body_jacobian(block, body, sign)
        start += block.size
    return ContactSpace(
        movable=movable,
        mass_matrix=mass,
        mass_matrix_inv=mass_inv,
        u_before=u,
        jacobian=jac,
        blocks=tuple(blocks),
        slices=tuple(slices),
    )

"""The paper's section 3, rebuilt from ordinary bodies, contacts and constraints.

Each example is a function that builds an :class:`~carnot.model.problem.ImpactProblem` for one
set of parameters, a grid of parameters, and a function that solves it and reads off the quantities
the paper names, in the paper's own axes and signs, keyed by the symbols of
:mod:`carnot.paper.formulas`.

Axes used to rebuild each figure (the figures themselves are not in the text we have):

* 3.1: edge at the origin, normal ``n = +y`` (edge into cylinder), tangent ``t = +x``, the
  cylinder's axis along ``z``, centre ``O = (0, r, 0)``, ``v'_O = v'(sin a, -cos a, 0)``,
  and the paper's ``omega`` clockwise (``omega_z = -omega``) so that ``v_At = v_Ot - r omega``.
* 3.2: pivot at the origin, the pendulum along ``-y`` with its mass spread uniformly over the
  struck length ``h`` that starts at ``l`` from the pivot (``J_O = m (l^2 + l h + h^2/3)``,
  which the printed ``E_d`` implies), turning with ``omega_z = omega'`` so that it moves along
  ``+x`` and strikes the plane ``x = 0`` face on; ``C`` the middle of the struck length.
  ``P_C`` and ``M_PC`` are magnitudes (``P_C = P . n``, ``M_PC = -M_P . z``).
* 3.3 planar: the plate in the ``xy`` plane, ``omega`` counterclockwise, and ``alpha`` measured
  counterclockwise from ``v'_O`` to ``OC``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp

from carnot.model import inertia
from carnot.model.bodies import FixedBody, RigidBody
from carnot.model.contacts import Fasten, Pin, PointContact
from carnot.model.problem import ImpactProblem
from carnot.paper import formulas as f
from carnot.solve import solve_impact

Params = dict[str, Any]
Measured = dict[sp.Symbol, float]


def _vector_values(symbols: sp.Matrix, values: Any) -> Measured:
    return {s: float(x) for s, x in zip(symbols, np.ravel(values), strict=True)}


# --------------------------------------------------------------------------------------------
# Section 3.1: a cylinder striking a sharp edge, without slip.


def cylinder_edge_problem(p: Params) -> ImpactProblem:
    """The cylinder (mass ``m``, radius ``r``, ``J_O = m r^2/2``) striking the edge with centre
    velocity ``v'_O`` at angle ``alpha`` and angular velocity ``omega'`` (section 3.1)."""
    m, r, v, a, w = p["m"], p["r"], p["v"], p["alpha"], p["omega"]
    cylinder = RigidBody(
        name="cylinder",
        mass=m,
        # A thin slice of the cylinder keeps J_O = m r^2/2 about its axis exactly; the other
        # moments play no part in the planar motion.
        inertia_com=inertia.solid_cylinder(m, r, r, axis=[0, 0, 1]),
        position_com=np.array([0.0, r, 0.0]),
        velocity_com=np.array([v * math.sin(a), -v * math.cos(a), 0.0]),
        angular_velocity=np.array([0.0, 0.0, -w]),
    )
    return ImpactProblem(
        title="Section 3.1: cylinder striking a sharp edge",
        bodies={"cylinder": cylinder, "edge": FixedBody(name="edge")},
        contacts=[
            PointContact(
                a="cylinder",
                b="edge",
                point=np.array([0.0, 0.0, 0.0]),
                normal=np.array([0.0, 1.0, 0.0]),
                restitution=p["e"],
                tangential="stick",
                where="contacts[0]",
            )
        ],
    )


def cylinder_edge_measure(p: Params) -> tuple[Measured, ImpactProblem]:
    """Solve 3.1 and read the paper's quantities off the result (paper axes and signs)."""
    problem = cylinder_edge_problem(p)
    res = solve_impact(problem)
    body = res.bodies["cylinder"]
    contact = res.contacts[0]
    n, t = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    return {
        f.m: p["m"], f.r: p["r"], f.v: p["v"], f.alpha: p["alpha"], f.omega1: p["omega"],
        f.e: p["e"],
        f.P_n: contact.impulse @ n,
        f.P_t: contact.impulse @ t,
        f.v2_On: body.velocity_after @ n,
        f.v2_Ot: body.velocity_after @ t,
        f.omega2: -body.angular_velocity_after[2],
        f.v1_An: contact.relative_velocity_before @ n,
        f.v1_At: contact.relative_velocity_before @ t,
        f.v2_An: contact.relative_velocity_after @ n,
        f.v2_At: contact.relative_velocity_after @ t,
        f.E_d: res.energy.dissipated,
        f.E_d_theorem: res.energy.dissipated_theorem,
    }, problem  # fmt: skip


def cylinder_edge_cases() -> Iterator[Params]:
    """A grid over mass, radius, speed, angle, spin and restitution (216 impacts)."""
    for m, r, v, a, w, e in itertools.product(
        (0.5, 2.0), (0.05, 0.2), (1.0, 4.0), (0.0, 0.3, 0.9), (-20.0, 0.0, 15.0), (0.0, 0.5, 1.0)
    ):
        yield {"m": m, "r": r, "v": v, "alpha": a, "omega": w, "e": e}


# --------------------------------------------------------------------------------------------
# Section 3.2: a pendulum striking a plane over a surface.


def pendulum_plane_problem(p: Params, *, given: tuple[float, float] | None = None) -> ImpactProblem:
    """The pendulum of section 3.2 (mass ``m`` spread over the struck length ``h`` that starts
    at ``l`` from the pivot) striking the plane with angular velocity ``omega'``.

    With ``given = (P_C, M_PC)`` the contact carries that impulse and moment instead of a law:
    the route that tests a printed impulse distribution.
    """
    m, l_, h, w = p["m"], p["l"], p["h"], p["omega"]
    centre = np.array([0.0, -(l_ + h / 2), 0.0])
    pendulum = RigidBody(
        name="pendulum",
        mass=m,
        # A thin rod along y: m h^2/12 about z, about its centre; the radius only sets the
        # axial moment, which the planar motion never engages.
        inertia_com=inertia.rod(m, h, h / 100, axis=[0, 1, 0]),
        position_com=centre,
        velocity_com=np.cross([0.0, 0.0, w], centre),
        angular_velocity=np.array([0.0, 0.0, w]),
    )
    normal = np.array([-1.0, 0.0, 0.0])
    if given is None:
        contact = PointContact(
            a="pendulum",
            b="plane",
            point=centre,
            normal=normal,
            restitution=p["e"],
            patch=np.array([[0.0, -l_, 0.0], [0.0, -(l_ + h), 0.0]]),
            where="contacts[0]",
        )
    else:
        p_c, m_pc = given
        contact = PointContact(
            a="pendulum",
            b="plane",
            point=centre,
            normal=normal,
            impulse=np.array([-p_c, 0.0, 0.0]),
            moment=np.array([0.0, 0.0, -m_pc]),
            where="contacts[0]",
        )
    return ImpactProblem(
        title="Section 3.2: pendulum striking a plane surface",
        bodies={"pendulum": pendulum, "plane": FixedBody(name="plane")},
        contacts=[contact],
        constraints=[Pin(body="pendulum", point=np.array([0.0, 0.0, 0.0]), where="constraints[0]")],
    )


def _pendulum_printed_impulses(p: Params) -> tuple[float, float]:
    m, l_, h, w, e = p["m"], p["l"], p["h"], p["omega"], p["e"]
    return 0.5 * m * w * (1 + e) * (2 * l_ + h), m * w * (1 + e) * h**2 / 12


def pendulum_plane_measure(p: Params) -> tuple[Measured, ImpactProblem]:
    """Solve 3.2 by its law and, separately, with the printed impulses given."""
    problem = pendulum_plane_problem(p)
    res = solve_impact(problem)
    body = res.bodies["pendulum"]
    m, h = p["m"], p["h"]
    x, z = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    # The split between pivot and plane is statically indeterminate; the motion is not. With no
    # pivot impulse (the paper's P_O = 0) the whole momentum change comes from the plane:
    # P_C = -m dv_C . x, and about the centre of mass C, M_PC = -(m h^2/12) d omega_z.
    dv = body.velocity_after - body.velocity_before
    dw = body.angular_velocity_after - body.angular_velocity_before
    given = solve_impact(pendulum_plane_problem(p, given=_pendulum_printed_impulses(p)))
    return {
        f.m: m, f.l_: p["l"], f.h: h, f.omega1: p["omega"], f.e: p["e"],
        f.omega2: body.angular_velocity_after @ z,
        f.v1_C: res.contacts[0].relative_velocity_before @ x,
        f.v2_C: res.contacts[0].relative_velocity_after @ x,
        f.P_C_needed: -m * (dv @ x),
        f.M_PC_needed: -(m * h**2 / 12) * (dw @ z),
        **_vector_values(f.P_O_given, given.constraints[0].impulse),
        f.omega2_given: given.bodies["pendulum"].angular_velocity_after @ z,
        f.E_d: res.energy.dissipated,
        f.E_d_theorem: res.energy.dissipated_theorem,
    }, problem  # fmt: skip


def pendulum_plane_cases() -> Iterator[Params]:
    """A grid over mass, arm, struck length, angular velocity and restitution (72 impacts)."""
    for m, l_, h, w, e in itertools.product(
        (0.5, 3.0), (0.0, 0.2, 1.0), (0.1, 0.5), (1.0, 7.0), (0.0, 0.4, 1.0)
    ):
        yield {"m": m, "l": l_, "h": h, "omega": w, "e": e}


# --------------------------------------------------------------------------------------------
# Section 3.3: the sudden fastening of a point of a body, in 3D and in the plane.


def _random_inertia(rng: np.random.Generator, scale: float) -> np.ndarray:
    """A random realizable inertia: random principal axes, moments obeying the triangle rule."""
    a, b = rng.uniform(0.2, 1.0, size=2)
    moments = np.array([a, b, rng.uniform(abs(a - b) + 0.05, a + b)]) * scale
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q @ np.diag(moments) @ q.T


def fasten_3d_problem(p: Params) -> ImpactProblem:
    """A free body (mass ``m``, ``J_C``) whose point ``O`` (velocity ``v'_O``) is suddenly
    fastened; ``OC`` from ``O`` to the centre of mass (section 3.3, figure 3a)."""
    oc = np.asarray(p["OC"])
    body = RigidBody(
        name="body",
        mass=p["m"],
        inertia_com=p["J_C"],
        position_com=p["O"] + oc,
        velocity_com=np.asarray(p["v_O"]) + np.cross(p["omega"], oc),
        angular_velocity=p["omega"],
    )
    return ImpactProblem(
        title="Section 3.3: sudden fastening of a point (3D)",
        bodies={"body": body},
        constraints=[Fasten(body="body", point=p["O"], where="constraints[0]")],
    )


def fasten_3d_measure(p: Params) -> tuple[Measured, ImpactProblem]:
    """Solve 3.3 (3D) and read ``omega''``, ``P`` and ``E_d``."""
    problem = fasten_3d_problem(p)
    res = solve_impact(problem)
    body = res.bodies["body"]
    j_o = inertia.parallel_axis(p["J_C"], p["m"], -np.asarray(p["OC"]))
    return {
        f.m: p["m"],
        **_vector_values(f.OC, p["OC"]),
        **_vector_values(f.v_O, p["v_O"]),
        **_vector_values(f.omega1_vec, p["omega"]),
        **{s: float(j_o[i, j]) for (i, j), s in zip(
            [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)],
            [f.J_O_xx, f.J_O_yy, f.J_O_zz, f.J_O_xy, f.J_O_xz, f.J_O_yz], strict=True)},
        **_vector_values(f.omega2_vec, body.angular_velocity_after),
        **_vector_values(f.P_vec, res.constraints[0].impulse),
        f.E_d: res.energy.dissipated,
        f.E_d_theorem: res.energy.dissipated_theorem,
    }, problem  # fmt: skip


def fasten_3d_cases() -> Iterator[Params]:
    """Forty random bodies (fixed seed) over two decades of mass and size."""
    rng = np.random.default_rng(20261122)
    for _ in range(40):
        m = 10 ** rng.uniform(-1, 1)
        size = 10 ** rng.uniform(-1, 0.5)
        yield {
            "m": m,
            "J_C": _random_inertia(rng, m * size**2),
            "O": rng.normal(size=3),
            "OC": rng.normal(size=3) * size,
            "v_O": rng.normal(size=3) * 3,
            "omega": rng.normal(size=3) * 5,
        }


def fasten_plate_problem(p: Params) -> ImpactProblem:
    """A plate (``a x b``, in the xy plane) in planar motion whose point ``O`` at distance
    ``l`` from its centre is suddenly fastened (section 3.3, figure 3b)."""
    m, l_, v, a, beta, w = p["m"], p["l"], p["v"], p["alpha"], p["beta"], p["omega"]
    oc = l_ * np.array([math.cos(beta + a), math.sin(beta + a), 0.0])
    v_o = v * np.array([math.cos(beta), math.sin(beta), 0.0])
    body = RigidBody(
        name="plate",
        mass=m,
        inertia_com=inertia.plate(m, p["size"]),
        position_com=oc,
        velocity_com=v_o + np.cross([0.0, 0.0, w], oc),
        angular_velocity=np.array([0.0, 0.0, w]),
    )
    return ImpactProblem(
        title="Section 3.3: sudden fastening of a point of a plate",
        bodies={"plate": body},
        constraints=[Fasten(body="plate", point=np.array([0.0, 0.0, 0.0]), where="constraints[0]")],
    )


def fasten_plate_measure(p: Params) -> tuple[Measured, ImpactProblem]:
    """Solve 3.3 (planar) and read ``omega''`` and ``E_d``."""
    problem = fasten_plate_problem(p)
    res = solve_impact(problem)
    a, b = p["size"]
    return {
        f.m: p["m"], f.l_: p["l"], f.v: p["v"], f.alpha: p["alpha"], f.omega1: p["omega"],
        f.J_O: p["m"] * (a * a + b * b) / 12 + p["m"] * p["l"] ** 2,
        f.omega2: res.bodies["plate"].angular_velocity_after[2],
        f.E_d: res.energy.dissipated,
        f.E_d_theorem: res.energy.dissipated_theorem,
    }, problem  # fmt: skip


def fasten_plate_cases() -> Iterator[Params]:
    """A grid over mass, plate shape, distance of ``O``, speed, angle and spin (576 impacts)."""
    for m, size, frac, v, a, beta, w in itertools.product(
        (1.0, 2.5),
        ((0.4, 0.3), (1.0, 0.2)),
        (0.0, 0.5, 1.0),
        (1.0, 3.0),
        (-2.0, -0.5, 0.0, 0.7, math.pi / 2, 3.0),
        (0.0, 1.0),
        (-4.0, 5.0),
    ):
        half_diagonal = 0.5 * math.hypot(*size)
        yield {
            "m": m,
            "size": size,
            "l": frac * half_diagonal,
            "v": v,
            "alpha": a,
            "beta": beta,
            "omega": w,
        }


@dataclass(frozen=True)
class Example:
    """One of the paper's examples: its grid of cases and how to solve and measure one."""

    id: str
    title: str
    cases: Callable[[], Iterator[Params]]
    measure: Callable[[Params], tuple[Measured, ImpactProblem]]


EXAMPLES: dict[str, Example] = {
    ex.id: ex
    for ex in (
        Example(
            "3.1", "cylinder striking a sharp edge", cylinder_edge_cases, cylinder_edge_measure
        ),
        Example("3.2", "pendulum striking a plane", pendulum_plane_cases, pendulum_plane_measure),
        Example("3.3-3d", "sudden fastening of a point (3D)", fasten_3d_cases, fasten_3d_measure),
        Example(
            "3.3-planar", "sudden fastening of a point of a plate", fasten_plate_cases,
            fasten_plate_measure,
        ),
    )
}  # fmt: skip

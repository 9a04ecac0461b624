"""The paper's section 3, rebuilt from ordinary bodies, contacts and constraints, and every
closed-form formula printed there transcribed as printed and checked against the solver.

Each example is a function that builds an :class:`~carnot.problem.ImpactProblem` for one set of
parameters, and a function that reads the quantities the paper names (in the paper's own axes
and signs) off the solved result. Each :class:`PrintedFormula` is a transcription, with its
place in the paper, evaluated over a grid of parameters and compared with

* the solver (an independent route: the simultaneous contact-space solve), and
* for energies, also the theorem's sum (``dissipated_theorem``) beside the direct difference.

A printed formula can be misprinted. The transcription stays as printed and the verdict says
``disagrees``; where a correction is evident it is checked separately (``corrected``) and
reported beside, never in place of, the printed form.

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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from carnot import inertia
from carnot.bodies import FixedBody, RigidBody
from carnot.contacts import Fasten, Pin, PointContact
from carnot.problem import ImpactProblem
from carnot.result import ImpactResult
from carnot.solve import solve_impact

Params = dict[str, Any]
Measured = dict[str, Any]
Evaluator = Callable[[Params, Measured], Any]

#: A printed formula "agrees" when it matches the solver to this relative difference.
AGREEMENT_TOLERANCE = 1e-9


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
        position_com=[0.0, r, 0.0],
        velocity_com=[v * math.sin(a), -v * math.cos(a), 0.0],
        angular_velocity=[0.0, 0.0, -w],
    )
    return ImpactProblem(
        title="Section 3.1: cylinder striking a sharp edge",
        bodies={"cylinder": cylinder, "edge": FixedBody(name="edge")},
        contacts=[
            PointContact(
                a="cylinder",
                b="edge",
                point=[0.0, 0.0, 0.0],
                normal=[0.0, 1.0, 0.0],
                restitution=p["e"],
                tangential="stick",
                where="contacts[0]",
            )
        ],
    )


def cylinder_edge_measure(p: Params) -> Measured:
    """Solve 3.1 and read the paper's quantities off the result (paper axes and signs)."""
    res = solve_impact(cylinder_edge_problem(p))
    body = res.bodies["cylinder"]
    contact = res.contacts[0]
    n, t = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    return {
        "P_n": contact.impulse @ n,
        "P_t": contact.impulse @ t,
        "v''_On": body.velocity_after @ n,
        "v''_Ot": body.velocity_after @ t,
        "omega''": -body.angular_velocity_after[2],
        "v'_An": contact.relative_velocity_before @ n,
        "v'_At": contact.relative_velocity_before @ t,
        "v''_An": contact.relative_velocity_after @ n,
        "v''_At": contact.relative_velocity_after @ t,
        "E_d": res.energy.dissipated,
        "E_d theorem": res.energy.dissipated_theorem,
        "J_O": p["m"] * p["r"] ** 2 / 2,
    }


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
        angular_velocity=[0.0, 0.0, w],
    )
    normal = [-1.0, 0.0, 0.0]
    if given is None:
        contact = PointContact(
            a="pendulum",
            b="plane",
            point=centre,
            normal=normal,
            restitution=p["e"],
            patch=[[0.0, -l_, 0.0], [0.0, -(l_ + h), 0.0]],
            where="contacts[0]",
        )
    else:
        p_c, m_pc = given
        contact = PointContact(
            a="pendulum",
            b="plane",
            point=centre,
            normal=normal,
            impulse=[-p_c, 0.0, 0.0],
            moment=[0.0, 0.0, -m_pc],
            where="contacts[0]",
        )
    return ImpactProblem(
        title="Section 3.2: pendulum striking a plane surface",
        bodies={"pendulum": pendulum, "plane": FixedBody(name="plane")},
        contacts=[contact],
        constraints=[Pin(body="pendulum", point=[0.0, 0.0, 0.0], where="constraints[0]")],
    )


def _pendulum_printed_impulses(p: Params) -> tuple[float, float]:
    m, l_, h, w, e = p["m"], p["l"], p["h"], p["omega"], p["e"]
    return 0.5 * m * w * (1 + e) * (2 * l_ + h), m * w * (1 + e) * h**2 / 12


def pendulum_plane_measure(p: Params) -> Measured:
    """Solve 3.2 by its law and, separately, with the printed impulses given."""
    res = solve_impact(pendulum_plane_problem(p))
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
        "omega''": body.angular_velocity_after @ z,
        "v'_C": res.contacts[0].relative_velocity_before @ x,
        "v''_C": res.contacts[0].relative_velocity_after @ x,
        "P_C (P_O = 0)": -m * (dv @ x),
        "M_PC (P_O = 0)": -(m * h**2 / 12) * (dw @ z),
        "P_O with printed P_C, M_PC": given.constraints[0].impulse,
        "omega'' with printed P_C, M_PC": given.bodies["pendulum"].angular_velocity_after @ z,
        "E_d": res.energy.dissipated,
        "E_d theorem": res.energy.dissipated_theorem,
        "flags": res.flag_codes(),
    }


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


def fasten_3d_measure(p: Params) -> Measured:
    """Solve 3.3 (3D) and read ``omega''``, ``P`` and ``E_d``."""
    res = solve_impact(fasten_3d_problem(p))
    body = res.bodies["body"]
    return {
        "omega''": body.angular_velocity_after,
        "P": res.constraints[0].impulse,
        "v''_C": body.velocity_after,
        "J_O": inertia.parallel_axis(p["J_C"], p["m"], -np.asarray(p["OC"])),
        "E_d": res.energy.dissipated,
        "E_d theorem": res.energy.dissipated_theorem,
    }


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
        angular_velocity=[0.0, 0.0, w],
    )
    return ImpactProblem(
        title="Section 3.3: sudden fastening of a point of a plate",
        bodies={"plate": body},
        constraints=[Fasten(body="plate", point=[0.0, 0.0, 0.0], where="constraints[0]")],
    )


def fasten_plate_measure(p: Params) -> Measured:
    """Solve 3.3 (planar) and read ``omega''`` and ``E_d``."""
    res = solve_impact(fasten_plate_problem(p))
    a, b = p["size"]
    return {
        "omega''": res.bodies["plate"].angular_velocity_after[2],
        "J_O": p["m"] * (a * a + b * b) / 12 + p["m"] * p["l"] ** 2,
        "E_d": res.energy.dissipated,
        "E_d theorem": res.energy.dissipated_theorem,
    }


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


# --------------------------------------------------------------------------------------------
# The printed formulas.


@dataclass(frozen=True, kw_only=True)
class PrintedFormula:
    """One formula of section 3 as printed, and how to check it.

    ``printed(p, q)`` evaluates the transcription (``p``: the case's parameters, ``q``: the
    quantities measured off the solver, for the formulas that combine them, like the theorem's
    form of ``E_d``); ``solver(p, q)`` is the solver's value of the same quantity, and
    ``theorem(p, q)`` the theorem's value where the quantity is an energy. ``scale(p, q)``
    (optional) sets the size a difference is measured against where the value itself can be 0.
    """

    id: str
    example: str
    where: str
    text: str
    printed: Evaluator
    solver: Evaluator
    theorem: Evaluator | None = None
    scale: Evaluator | None = None
    corrected_text: str | None = None
    corrected: Evaluator | None = None
    note: str = ""


@dataclass(frozen=True, kw_only=True)
class Verdict:
    """The outcome of checking one printed formula over its grid of cases."""

    id: str
    where: str
    printed: str
    verdict: str  # "agrees" or "disagrees"
    max_rel_diff: float
    max_rel_diff_solver: float
    max_rel_diff_theorem: float | None
    cases: int
    counterexample: dict[str, Any] | None = None
    corrected: dict[str, Any] | None = None
    note: str = ""
    extra: dict[str, Any] = field(default_factory=dict)


def _cross(a: Any, b: Any) -> np.ndarray:
    return np.cross(np.asarray(a, dtype=float), np.asarray(b, dtype=float))


def _j_o_inv_oc_x_vo(p: Params, q: Measured) -> np.ndarray:
    return np.linalg.solve(q["J_O"], _cross(p["OC"], p["v_O"]))


S31 = "section 3.1"
S32 = "section 3.2"
S33 = "section 3.3"

FORMULAS: tuple[PrintedFormula, ...] = (
    # ---- 3.1 -------------------------------------------------------------------------------
    PrintedFormula(
        id="3.1/v'_An",
        example="3.1",
        where=f"{S31}, velocity of the impact point A before",
        text="v'_An = -v'_O cos(alpha)",
        printed=lambda p, q: -p["v"] * math.cos(p["alpha"]),
        solver=lambda p, q: q["v'_An"],
    ),
    PrintedFormula(
        id="3.1/v'_At",
        example="3.1",
        where=f"{S31}, velocity of the impact point A before",
        text="v'_At = v'_O sin(alpha) - r omega'",
        printed=lambda p, q: p["v"] * math.sin(p["alpha"]) - p["r"] * p["omega"],
        solver=lambda p, q: q["v'_At"],
    ),
    PrintedFormula(
        id="3.1/eq-normal",
        example="3.1",
        where=f"{S31}, slipless collision equations (normal momentum)",
        text="m v''_On + m v'_O cos(alpha) = P_n",
        printed=lambda p, q: p["m"] * q["v''_On"] + p["m"] * p["v"] * math.cos(p["alpha"]),
        solver=lambda p, q: q["P_n"],
    ),
    PrintedFormula(
        id="3.1/eq-tangential",
        example="3.1",
        where=f"{S31}, slipless collision equations (tangential momentum)",
        text="m v''_Ot - m v'_O sin(alpha) = P_t",
        printed=lambda p, q: p["m"] * q["v''_Ot"] - p["m"] * p["v"] * math.sin(p["alpha"]),
        solver=lambda p, q: q["P_t"],
        scale=lambda p, q: p["m"] * p["v"],
    ),
    PrintedFormula(
        id="3.1/eq-angular",
        example="3.1",
        where=f"{S31}, slipless collision equations (angular momentum about O)",
        text="J_O (omega'' - v'_O / r) = -r P_t",
        printed=lambda p, q: q["J_O"] * (q["omega''"] - p["v"] / p["r"]),
        solver=lambda p, q: -p["r"] * q["P_t"],
        scale=lambda p, q: p["m"] * p["v"] * p["r"],
        corrected_text="J_O (omega'' - omega') = -r P_t",
        corrected=lambda p, q: q["J_O"] * (q["omega''"] - p["omega"]),
        note="the printed equation has v'_O/r where the angular velocity before, omega', "
        "belongs; the printed results below follow from the corrected equation",
    ),
    PrintedFormula(
        id="3.1/P_n",
        example="3.1",
        where=f"{S31}, results",
        text="P_n = m v'_O (1 + e) cos(alpha)",
        printed=lambda p, q: p["m"] * p["v"] * (1 + p["e"]) * math.cos(p["alpha"]),
        solver=lambda p, q: q["P_n"],
    ),
    PrintedFormula(
        id="3.1/P_t",
        example="3.1",
        where=f"{S31}, results",
        text="P_t = (m/3) (r omega' - v'_O sin(alpha))",
        printed=lambda p, q: p["m"] / 3 * (p["r"] * p["omega"] - p["v"] * math.sin(p["alpha"])),
        solver=lambda p, q: q["P_t"],
        scale=lambda p, q: p["m"] * p["v"],
    ),
    PrintedFormula(
        id="3.1/v''_On",
        example="3.1",
        where=f"{S31}, results",
        text="v''_On = e v'_O cos(alpha)",
        printed=lambda p, q: p["e"] * p["v"] * math.cos(p["alpha"]),
        solver=lambda p, q: q["v''_On"],
        scale=lambda p, q: p["v"],
    ),
    PrintedFormula(
        id="3.1/v''_Ot",
        example="3.1",
        where=f"{S31}, results",
        text="v''_Ot = (2/3) v'_O sin(alpha) + (1/3) r omega'",
        printed=lambda p, q: 2 / 3 * p["v"] * math.sin(p["alpha"]) + p["r"] * p["omega"] / 3,
        solver=lambda p, q: q["v''_Ot"],
        scale=lambda p, q: p["v"],
    ),
    PrintedFormula(
        id="3.1/omega''",
        example="3.1",
        where=f"{S31}, results",
        text="omega'' = (2/3) (v'_O / r) sin(alpha) + (1/3) omega'",
        printed=lambda p, q: 2 / 3 * p["v"] / p["r"] * math.sin(p["alpha"]) + p["omega"] / 3,
        solver=lambda p, q: q["omega''"],
        scale=lambda p, q: p["v"] / p["r"],
    ),
    PrintedFormula(
        id="3.1/friction",
        example="3.1",
        where=f"{S31}, condition against sliding",
        text="mu >= P_t / P_n = (r omega' - v'_O sin(alpha)) / (3 (1 + e) v'_O cos(alpha))",
        printed=lambda p, q: (p["r"] * p["omega"] - p["v"] * math.sin(p["alpha"]))
        / (3 * (1 + p["e"]) * p["v"] * math.cos(p["alpha"])),
        solver=lambda p, q: q["P_t"] / q["P_n"],
        scale=lambda p, q: 1.0,
        note="the ratio is signed as printed; the friction needed to stick is its absolute "
        "value, |P_t| / P_n (carnot reports that as friction_required)",
    ),
    PrintedFormula(
        id="3.1/E_d-theorem",
        example="3.1",
        where=f"{S31}, energy dissipated, theorem's form (eq. 16)",
        text="E_d = -1/2 [P_t (v'_At + v''_At) + P_n (v'_An + v''_An)]",
        printed=lambda p, q: -0.5
        * (q["P_t"] * (q["v'_At"] + q["v''_At"]) + q["P_n"] * (q["v'_An"] + q["v''_An"])),
        solver=lambda p, q: q["E_d"],
        theorem=lambda p, q: q["E_d theorem"],
        scale=lambda p, q: 0.5 * p["m"] * p["v"] ** 2,
    ),
    PrintedFormula(
        id="3.1/E_d",
        example="3.1",
        where=f"{S31}, energy dissipated, closed form",
        text="E_d = (m v'_O^2 / 2) [(1/3) (r omega' / v'_O - sin(alpha))^2 "
        "+ (1 - e^2) cos^2(alpha)]",
        printed=lambda p, q: p["m"]
        * p["v"] ** 2
        / 2
        * (
            (p["r"] * p["omega"] / p["v"] - math.sin(p["alpha"])) ** 2 / 3
            + (1 - p["e"] ** 2) * math.cos(p["alpha"]) ** 2
        ),
        solver=lambda p, q: q["E_d"],
        theorem=lambda p, q: q["E_d theorem"],
        scale=lambda p, q: 0.5 * p["m"] * p["v"] ** 2,
    ),
    # ---- 3.2 -------------------------------------------------------------------------------
    PrintedFormula(
        id="3.2/omega''",
        example="3.2",
        where=f"{S32}, results from [6]",
        text="omega'' = -e omega'",
        printed=lambda p, q: -p["e"] * p["omega"],
        solver=lambda p, q: q["omega''"],
        scale=lambda p, q: p["omega"],
    ),
    PrintedFormula(
        id="3.2/P_O",
        example="3.2",
        where=f"{S32}, results from [6] (pivot impulse)",
        text="P_Ot = P_On = 0",
        printed=lambda p, q: np.zeros(3),
        solver=lambda p, q: q["P_O with printed P_C, M_PC"],
        scale=lambda p, q: _pendulum_printed_impulses(p)[0],
        note="the split between pivot and plane is statically indeterminate; checked by "
        "applying the printed P_C and M_PC as given impulses with the pivot as a pin: the pin "
        "then needs no impulse",
    ),
    PrintedFormula(
        id="3.2/P_C",
        example="3.2",
        where=f"{S32}, results from [6]",
        text="P_C = (1/2) m omega' (1 + e) (2 l + h)",
        printed=lambda p, q: _pendulum_printed_impulses(p)[0],
        solver=lambda p, q: q["P_C (P_O = 0)"],
        note="compared with the plane's impulse that the solved motion needs when the pivot "
        "gives none (P_O = 0, as printed)",
    ),
    PrintedFormula(
        id="3.2/M_PC",
        example="3.2",
        where=f"{S32}, results from [6] (first form)",
        text="M_PC = P_C h^2 / (6 (2 l + h))",
        printed=lambda p, q: _pendulum_printed_impulses(p)[0]
        * p["h"] ** 2
        / (6 * (2 * p["l"] + p["h"])),
        solver=lambda p, q: q["M_PC (P_O = 0)"],
        note="compared with the moment the solved motion needs when the pivot gives none",
    ),
    PrintedFormula(
        id="3.2/M_PC-closed",
        example="3.2",
        where=f"{S32}, results from [6] (second form)",
        text="M_PC = (1/12) m omega' (1 + e) h^2",
        printed=lambda p, q: _pendulum_printed_impulses(p)[1],
        solver=lambda p, q: q["M_PC (P_O = 0)"],
    ),
    PrintedFormula(
        id="3.2/impulses-motion",
        example="3.2",
        where=f"{S32}, the printed impulse distribution, applied as given impulses",
        text="P_C, M_PC as printed => omega'' = -e omega'",
        printed=lambda p, q: q["omega'' with printed P_C, M_PC"],
        solver=lambda p, q: q["omega''"],
        scale=lambda p, q: p["omega"],
    ),
    PrintedFormula(
        id="3.2/v'_C",
        example="3.2",
        where=f"{S32}, velocity of C before",
        text="v'_C = (1/2) omega' (2 l + h)",
        printed=lambda p, q: 0.5 * p["omega"] * (2 * p["l"] + p["h"]),
        solver=lambda p, q: q["v'_C"],
    ),
    PrintedFormula(
        id="3.2/v''_C",
        example="3.2",
        where=f"{S32}, velocity of C after",
        text="v''_C = -(1/2) e omega' (2 l + h)",
        printed=lambda p, q: -0.5 * p["e"] * p["omega"] * (2 * p["l"] + p["h"]),
        solver=lambda p, q: q["v''_C"],
        scale=lambda p, q: p["omega"] * (2 * p["l"] + p["h"]),
    ),
    PrintedFormula(
        id="3.2/E_d-theorem",
        example="3.2",
        where=f"{S32}, energy dissipated, theorem's form (eq. 15)",
        text="E_d = (1/2) P (v'_C + v''_C) + (1/2) M (omega' + omega'')",
        printed=lambda p, q: 0.5 * _pendulum_printed_impulses(p)[0] * (q["v'_C"] + q["v''_C"])
        + 0.5 * _pendulum_printed_impulses(p)[1] * (p["omega"] + q["omega''"]),
        solver=lambda p, q: q["E_d"],
        theorem=lambda p, q: q["E_d theorem"],
        scale=lambda p, q: 0.5 * p["m"] * (p["omega"] * (p["l"] + p["h"])) ** 2,
        note="P and M as printed, magnitudes against the motion of C",
    ),
    PrintedFormula(
        id="3.2/E_d",
        example="3.2",
        where=f"{S32}, energy dissipated, closed form",
        text="E_d = (1/2) m (1 - e^2) (l^2 + l h + h^2/3) omega'^2",
        printed=lambda p, q: 0.5
        * p["m"]
        * (1 - p["e"] ** 2)
        * (p["l"] ** 2 + p["l"] * p["h"] + p["h"] ** 2 / 3)
        * p["omega"] ** 2,
        solver=lambda p, q: q["E_d"],
        theorem=lambda p, q: q["E_d theorem"],
        scale=lambda p, q: 0.5 * p["m"] * (p["omega"] * (p["l"] + p["h"])) ** 2,
    ),
    # ---- 3.3, three dimensions ---------------------------------------------------------------
    PrintedFormula(
        id="3.3/eq-linear",
        example="3.3-3d",
        where=f"{S33}, linear momentum equation",
        text="m [omega'' x OC - (v'_O + omega' x OC)] = P",
        printed=lambda p, q: p["m"]
        * (_cross(q["omega''"], p["OC"]) - (p["v_O"] + _cross(p["omega"], p["OC"]))),
        solver=lambda p, q: q["P"],
    ),
    PrintedFormula(
        id="3.3/eq-angular",
        example="3.3-3d",
        where=f"{S33}, angular momentum equation about O",
        text="[J]_O omega'' - ([J]_O omega' + m OC x v'_O) = 0",
        printed=lambda p, q: q["J_O"] @ q["omega''"]
        - (q["J_O"] @ p["omega"] + p["m"] * _cross(p["OC"], p["v_O"])),
        solver=lambda p, q: np.zeros(3),
        scale=lambda p, q: float(np.linalg.norm(q["J_O"] @ p["omega"]))
        + p["m"] * float(np.linalg.norm(_cross(p["OC"], p["v_O"]))),
    ),
    PrintedFormula(
        id="3.3/omega''",
        example="3.3-3d",
        where=f"{S33}, result",
        text="omega'' = omega' + m [J]_O^-1 (OC x v'_O)",
        printed=lambda p, q: p["omega"] + p["m"] * _j_o_inv_oc_x_vo(p, q),
        solver=lambda p, q: q["omega''"],
    ),
    PrintedFormula(
        id="3.3/P",
        example="3.3-3d",
        where=f"{S33}, result",
        text="P = -m v'_O - m OC x [J]_O^-1 (OC x v'_O)",
        printed=lambda p, q: -p["m"] * np.asarray(p["v_O"])
        - p["m"] * _cross(p["OC"], _j_o_inv_oc_x_vo(p, q)),
        solver=lambda p, q: q["P"],
        corrected_text="P = -m v'_O - m^2 OC x [J]_O^-1 (OC x v'_O)",
        corrected=lambda p, q: -p["m"] * np.asarray(p["v_O"])
        - p["m"] ** 2 * _cross(p["OC"], _j_o_inv_oc_x_vo(p, q)),
        note="the second term lacks a factor m: as printed it has units of velocity, not of "
        "impulse; it follows from the (correct) momentum equations with m^2",
    ),
    PrintedFormula(
        id="3.3/E_d",
        example="3.3-3d",
        where=f"{S33}, energy dissipated",
        text="E_d = (1/2) m v'_O^2 + (1/2) m v'_O . [OC x [J]_O^-1 (OC x v'_O)]",
        printed=lambda p, q: 0.5 * p["m"] * float(np.dot(p["v_O"], p["v_O"]))
        + 0.5 * p["m"] * float(np.dot(p["v_O"], _cross(p["OC"], _j_o_inv_oc_x_vo(p, q)))),
        solver=lambda p, q: q["E_d"],
        theorem=lambda p, q: q["E_d theorem"],
        scale=lambda p, q: 0.5 * p["m"] * float(np.dot(p["v_O"], p["v_O"])),
        corrected_text="E_d = (1/2) m v'_O^2 + (1/2) m^2 v'_O . [OC x [J]_O^-1 (OC x v'_O)]",
        corrected=lambda p, q: 0.5 * p["m"] * float(np.dot(p["v_O"], p["v_O"]))
        + 0.5
        * p["m"] ** 2
        * float(np.dot(p["v_O"], _cross(p["OC"], _j_o_inv_oc_x_vo(p, q)))),
        note="the same missing factor m as in P (E_d = -1/2 P . v'_O by eq. 16); the planar "
        "form below, which the paper derives from this one, has it",
    ),
    # ---- 3.3, the plane ------------------------------------------------------------------------
    PrintedFormula(
        id="3.3/omega''-planar",
        example="3.3-planar",
        where=f"{S33}, planar motion of a plate (figure 3b)",
        text="omega'' = omega' - m v'_O l sin(alpha) / J_O",
        printed=lambda p, q: p["omega"] - p["m"] * p["v"] * p["l"] * math.sin(p["alpha"]) / q["J_O"],
        solver=lambda p, q: q["omega''"],
        scale=lambda p, q: abs(p["omega"]) + p["v"] / math.hypot(*p["size"]),
        note="figure 3b is not in the text we have: alpha is taken counterclockwise from v'_O "
        "to OC (omega counterclockwise); measured the other way the sign of the second term "
        "flips. E_d holds either way (sin^2)",
    ),
    PrintedFormula(
        id="3.3/E_d-planar",
        example="3.3-planar",
        where=f"{S33}, planar motion of a plate (figure 3b)",
        text="E_d = (1/2) m v'_O^2 (1 - m l^2 sin^2(alpha) / J_O)",
        printed=lambda p, q: 0.5
        * p["m"]
        * p["v"] ** 2
        * (1 - p["m"] * p["l"] ** 2 * math.sin(p["alpha"]) ** 2 / q["J_O"]),
        solver=lambda p, q: q["E_d"],
        theorem=lambda p, q: q["E_d theorem"],
        scale=lambda p, q: 0.5 * p["m"] * p["v"] ** 2,
    ),
)

#: Example id -> (its cases, its measurement).
EXAMPLES: dict[str, tuple[Callable[[], Iterator[Params]], Callable[[Params], Measured]]] = {
    "3.1": (cylinder_edge_cases, cylinder_edge_measure),
    "3.2": (pendulum_plane_cases, pendulum_plane_measure),
    "3.3-3d": (fasten_3d_cases, fasten_3d_measure),
    "3.3-planar": (fasten_plate_cases, fasten_plate_measure),
}


def _rel_diff(value: Any, reference: Any, scale: float) -> float:
    diff = float(np.linalg.norm(np.asarray(value, dtype=float) - np.asarray(reference, dtype=float)))
    denominator = max(float(np.linalg.norm(np.asarray(reference, dtype=float))), scale, 1e-300)
    return diff / denominator


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return [float(x) for x in value.ravel()] if value.ndim == 1 else value.tolist()
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value)
    return value


def check_formula(formula: PrintedFormula, cases: list[tuple[Params, Measured]]) -> Verdict:
    """Evaluate one printed formula over the solved cases of its example."""
    worst_solver, worst_theorem, worst_corrected = 0.0, 0.0, 0.0
    worst_case: tuple[Params, Any, Any] | None = None
    for p, q in cases:
        scale = abs(float(formula.scale(p, q))) if formula.scale else 0.0
        printed = formula.printed(p, q)
        solver = formula.solver(p, q)
        d = _rel_diff(printed, solver, scale)
        if d > worst_solver or worst_case is None:
            worst_solver = max(worst_solver, d)
            worst_case = (p, printed, solver)
        if formula.theorem is not None:
            worst_theorem = max(worst_theorem, _rel_diff(printed, formula.theorem(p, q), scale))
        if formula.corrected is not None:
            worst_corrected = max(
                worst_corrected, _rel_diff(formula.corrected(p, q), solver, scale)
            )
    worst = max(worst_solver, worst_theorem)
    agrees = worst <= AGREEMENT_TOLERANCE
    counterexample = None
    if not agrees and worst_case is not None:
        p, printed, solver = worst_case
        counterexample = {
            "parameters": {k: _plain(v) for k, v in p.items()},
            "printed": _plain(printed),
            "solver": _plain(solver),
        }
    corrected = None
    if formula.corrected_text is not None:
        corrected = {
            "formula": formula.corrected_text,
            "verdict": "agrees" if worst_corrected <= AGREEMENT_TOLERANCE else "disagrees",
            "max_rel_diff": worst_corrected,
        }
    return Verdict(
        id=formula.id,
        where=formula.where,
        printed=formula.text,
        verdict="agrees" if agrees else "disagrees",
        max_rel_diff=worst,
        max_rel_diff_solver=worst_solver,
        max_rel_diff_theorem=worst_theorem if formula.theorem is not None else None,
        cases=len(cases),
        counterexample=counterexample,
        corrected=corrected,
        note=formula.note,
    )


def run_audit(formulas: tuple[PrintedFormula, ...] = FORMULAS) -> list[Verdict]:
    """Solve every example over its grid and check every printed formula.

    >>> verdicts = run_audit()
    >>> sorted(v.id for v in verdicts if v.verdict == "disagrees")
    ['3.1/eq-angular', '3.3/E_d', '3.3/P']
    """
    solved: dict[str, list[tuple[Params, Measured]]] = {}
    for example, (cases, measure) in EXAMPLES.items():
        if any(f.example == example for f in formulas):
            solved[example] = [(p, measure(p)) for p in cases()]
    return [check_formula(f, solved[f.example]) for f in formulas]


def verdict_to_dict(verdict: Verdict) -> dict[str, Any]:
    """A verdict as plain JSON-ready data (``carnot paper --json``)."""
    return {
        "id": verdict.id,
        "where": verdict.where,
        "printed": verdict.printed,
        "verdict": verdict.verdict,
        "max_rel_diff": verdict.max_rel_diff,
        "max_rel_diff_solver": verdict.max_rel_diff_solver,
        "max_rel_diff_theorem": verdict.max_rel_diff_theorem,
        "cases": verdict.cases,
        "counterexample": verdict.counterexample,
        "corrected": verdict.corrected,
        "note": verdict.note,
    }


def theorem_checks() -> list[dict[str, Any]]:
    """For every solved case of every example: the theorem against the direct difference.

    Returns one row per example: the number of impacts and the largest
    ``|E_d(direct) - E_d(theorem)| / E'``.
    """
    rows = []
    builders: dict[str, Callable[[Params], ImpactProblem]] = {
        "3.1": cylinder_edge_problem,
        "3.2": pendulum_plane_problem,
        "3.3-3d": fasten_3d_problem,
        "3.3-planar": fasten_plate_problem,
    }
    for example, (cases, _) in EXAMPLES.items():
        worst = 0.0
        count = 0
        for p in cases():
            res: ImpactResult = solve_impact(builders[example](p))
            e = res.energy
            worst = max(worst, abs(e.dissipated - e.dissipated_theorem) / max(e.before, 1e-300))
            count += 1
        rows.append({"example": example, "impacts": count, "max_rel_diff": worst})
    return rows

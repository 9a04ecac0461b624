"""Impacts during a simulation, each solved by :func:`carnot.solve_impact`.

At an impact instant the bodies' states become an :class:`carnot.ImpactProblem`: each movable
body a :class:`carnot.RigidBody` (its inertia in world axes ``R J_b R^T``), each plane a
:class:`carnot.FixedBody`, each *approaching* feature (normal velocity below ``-eps_v``) a
:class:`carnot.PointContact` with its pair's law. The solver's answer is the impact, with its
full ledger (impulses, ``E_d`` by the theorem and by the kinetic-energy difference).

Touching features that are not approaching (*closed*: the corner a rocking block pivots on)
get no impulse; that is an assumption, checked after the solve: each must separate or stay
closed (``w_n'' >= -eps_v``), as the complementarity law of DESIGN.md section 6 requires of a
contact that takes no impulse (Housner 1963's assumption for the rocking block: the old corner
lifts off). When it fails the impact is refused (it needs the complementarity law).

Several approaching features at once are solved simultaneously by the solver's equality law
(frictionless or sticking contacts under Newton's hypothesis: DESIGN.md section 6's
generalized Newton with every contact active). The answer is kept only when every normal
impulse is >= 0 and every closed contact separates: then it is also a solution of the
complementarity law (each contact ``0 <= P_n _|_ w_n'' + e w_n' = 0``), and it is flagged
``simultaneous_contacts`` to say so. Otherwise, and for simultaneous contacts with Coulomb
slip, Poisson's or Stronge's hypothesis, the impact is refused: it needs the complementarity
law (issue 14), not yet in this version.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.model import FixedBody, ImpactProblem, PointContact, RigidBody
from carnot.result import Flag, ImpactResult
from carnot.simulate.contacts import SimulationError
from carnot.simulate.events import Feature, Geometry, geometry
from carnot.simulate.motion import BodyState, SimBody
from carnot.simulate.shapes import Plane
from carnot.solve import solve_impact


@dataclass(frozen=True, kw_only=True)
class PairLaw:
    """The law between two things (from ``[[pairs]]``): restitution e, Coulomb friction mu,
    hypothesis, tangential rule."""

    restitution: float
    friction: float = 0.0
    law: str = "newton"
    tangential: str = "slip"


@dataclass(frozen=True, kw_only=True, eq=False)
class Impact:
    """One solved impact: the result, the features (in the result's contact order), the new
    states and the names of the things that met."""

    time: float
    result: ImpactResult
    features: list[Feature]
    states: list[BodyState]
    flags: tuple[Flag, ...]


def feature_names(f: Feature, bodies: list[SimBody], plane_names: list[str]) -> tuple[str, str]:
    a = bodies[f.body].name
    return a, (bodies[f.other].name if f.other >= 0 else plane_names[f.plane])


def solve_at(time: float, bodies: list[SimBody], planes: list[Plane], plane_names: list[str],
             states: list[BodyState], approaching: list[Feature], closed: list[Feature],
             law_of: Any, eps_v: float) -> Impact:  # fmt: skip
    """Solve the impact of ``approaching`` features at ``time`` (module docstring)."""
    geos = {f: geometry(f, bodies, planes, states) for f in (*approaching, *closed)}
    involved = sorted({f.body for f in approaching} | {f.other for f in approaching
                                                        if f.other >= 0})  # fmt: skip
    problem_bodies: dict[str, Any] = {}
    for i in involved:
        s, b = states[i], bodies[i]
        problem_bodies[b.name] = RigidBody(
            name=b.name, mass=b.mass, inertia_com=b.inertia_world(s.rotation),
            position_com=s.position, velocity_com=s.velocity,
            angular_velocity=s.angular_velocity)  # fmt: skip
    contacts = []
    for k, f in enumerate(approaching):
        a, b = feature_names(f, bodies, plane_names)
        if f.other < 0:
            problem_bodies.setdefault(b, FixedBody(name=b))
        law: PairLaw = law_of(f)
        g = geos[f]
        contacts.append(PointContact(
            a=a, b=b, point=g.point, normal=g.normal, restitution=law.restitution,
            law=law.law, friction=law.friction, tangential=law.tangential,  # type: ignore
            where=f"contacts[{k}]"))  # fmt: skip
    flags: list[Flag] = []
    if len(approaching) > 1:
        coulomb = [law_of(f) for f in approaching if law_of(f).friction > 0
                   and law_of(f).tangential == "slip"]  # fmt: skip
        if coulomb:
            raise SimulationError(
                f"at t = {time:.12g} s, {len(approaching)} contacts are struck at once with "
                "Coulomb friction: simultaneous frictional impacts need the complementarity "
                "law (issue 14), not in this version (make them stick or frictionless)"
            )
    try:
        result = solve_impact(ImpactProblem(bodies=problem_bodies, contacts=contacts,
                                            title=f"impact at t = {time:.12g} s"))  # fmt: skip
    except InputError as err:
        raise SimulationError(f"impact at t = {time:.12g} s: {err}") from None
    new_states = list(states)
    for i in involved:
        motion = result.bodies[bodies[i].name]
        s = states[i]
        new_states[i] = BodyState(position=s.position, orientation=s.orientation,
                                  velocity=np.array(motion.velocity_after),
                                  angular_velocity=np.array(motion.angular_velocity_after))
    if len(approaching) > 1:
        negative = [c.where for c in result.contacts if (c.normal_impulse or 0.0) < 0.0]
        if negative:
            raise SimulationError(
                f"at t = {time:.12g} s, {len(approaching)} contacts are struck at once and the "
                f"simultaneous equality solve pulls at {negative[0]} (a negative normal "
                "impulse): this impact needs the complementarity law (issue 14), not in this "
                "version"
            )
        flags.append(Flag(
            code="simultaneous_contacts", where="contacts",
            message=(f"{len(approaching)} contacts struck at once, solved together by the "
                     "equality law; every normal impulse is >= 0 and every other touching "
                     "contact separates, so this is also the generalized-Newton "
                     "complementarity answer (DESIGN.md section 6)")))  # fmt: skip
    for f in closed:
        after: Geometry = geometry(f, bodies, planes, new_states)
        if after.normal_velocity < -eps_v:
            raise SimulationError(
                f"at t = {time:.12g} s, a touching contact of {bodies[f.body].name!r} that "
                "took no impulse would move into its obstacle after the impact (normal "
                f"velocity {after.normal_velocity:.3g} m/s): the impact needs the "
                "complementarity law with this contact active (issue 14)"
            )
    if closed:
        flags.append(Flag(
            code="closed_contacts_released", where="contacts",
            message=(f"{len(closed)} touching contact(s) took no impulse and separate or stay "
                     "closed after the impact (the rocking assumption of Housner 1963: the "
                     "old pivot lifts off), checked")))  # fmt: skip
    return Impact(time=time, result=result, features=list(approaching), states=new_states,
                  flags=tuple(flags))

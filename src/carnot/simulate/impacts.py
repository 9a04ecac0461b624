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

Several approaching features at once are one problem for the solver's law of several
contacts (DESIGN.md section 6: by default the simultaneous law, generalized Newton with
Coulomb friction as a complementarity, each contact ``0 <= P_n _|_ w_n'' + e w_n' >= 0``),
flagged ``simultaneous_contacts``. Poisson's and Stronge's hypotheses with several contacts
are refused by the solver (they differ from Newton's there), so the impact is too.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.keys import exact_key
from carnot.model import FixedBody, ImpactProblem, PointConstraint, PointContact, RigidBody
from carnot.records import Record
from carnot.result import Flag, ImpactResult
from carnot.simulate.contacts import SimulationError
from carnot.simulate.events import Feature, geometry
from carnot.simulate.motion import BodyState, SimBody, quat_matrix
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


class Impact:
    """One solved impact: its time (s), the result, the features (in the result's contact
    order), the new states and the flags of the simulation's own checks.

    ``result`` is given, or made by ``later()`` when first read: the lean event loop
    (:mod:`carnot.simulate.lean`) keeps the solver's numbers and builds the rich
    :class:`carnot.ImpactResult` from them only for whoever reads it."""

    __slots__ = ("_later", "_result", "features", "flags", "states", "time")

    def __init__(self, *, time: float, features: list[Feature], states: list[BodyState],
                 flags: tuple[Flag, ...], result: ImpactResult | None = None,
                 later: Callable[[], ImpactResult] | None = None) -> None:  # fmt: skip
        if (result is None) == (later is None):
            raise TypeError("Impact takes result or later, one of them")
        self.time, self.features, self.states, self.flags = time, features, states, flags
        self._result, self._later = result, later

    @property
    def result(self) -> ImpactResult:
        if self._result is None:
            assert self._later is not None
            self._result, self._later = self._later(), None
        return self._result

    def __reduce__(self) -> tuple[Any, ...]:
        # pickled with its result built (``later`` is a closure)
        return _impact, (self.time, self.features, self.states, self.flags, self.result)


def _impact(time: float, features: list[Feature], states: list[BodyState],
            flags: tuple[Flag, ...], result: ImpactResult) -> Impact:  # fmt: skip
    """An unpickled :class:`Impact`."""
    return Impact(time=time, features=features, states=states, flags=flags, result=result)


@dataclass(frozen=True, kw_only=True, eq=False)
class Event(Record):
    """One event: time (s), kind (``impact``, ``contact_start``, ``contact_end``, ``stick``,
    ``slip``, ``rest``, ``accumulation``), the pairs of names involved, the solved impact (for
    an impact), and an energy record (for an accumulation)."""

    time: float
    kind: str
    contacts: list[tuple[str, str]]
    impact: Impact | None = None
    energy: dict[str, float] | None = None


def feature_names(f: Feature, bodies: list[SimBody], plane_names: list[str]) -> tuple[str, str]:
    a = bodies[f.body].name
    return a, (bodies[f.other].name if f.other >= 0 else plane_names[f.plane])


def solve_at(time: float, bodies: list[SimBody], planes: list[Plane], plane_names: list[str],
             states: list[BodyState], approaching: list[Feature], closed: list[Feature],
             law_of: Any, eps_v: float) -> Impact:  # fmt: skip
    """Solve the impact of ``approaching`` features at ``time`` (module docstring). A closed
    feature that would move into its obstacle after the impact joins the struck ones and the
    impact is solved again (a block landing flat on its side: the pivot corner takes an
    impulse too)."""
    struck = list(approaching)
    for _ in range(len(closed) + 1):
        impact = _solve(time, bodies, planes, plane_names, states, struck, law_of)
        resting = [f for f in closed if f not in struck]
        sinking = [f for f in resting
                   if geometry(f, bodies, planes, impact.states).normal_velocity < -eps_v]
        if not sinking:
            break
        struck.extend(sinking)
    else:  # pragma: no cover - each pass adds a feature, so the loop ends first
        raise SimulationError(f"impact at t = {time:.12g} s: no consistent set of contacts")
    if not resting:  # nothing else touched: the impact as solved
        return impact
    flags = [*impact.flags, Flag(
        code="closed_contacts_released", where="contacts",
        message=(f"{len(resting)} touching contact(s) took no impulse and separate or stay "
                 "closed after the impact (checked: the rocking assumption of Housner 1963, "
                 "the old pivot lifts off)"))]  # fmt: skip
    return Impact(time=time, result=impact.result, features=struck, states=impact.states,
                  flags=tuple(flags))


def settle_at(time: float, bodies: list[SimBody], planes: list[Plane], plane_names: list[str],
              states: list[BodyState], active: list[Any], law_of: Any) -> Impact:  # fmt: skip
    """Bring a body whose remaining motion on its closed contacts is below the velocity
    tolerance to rest on them: one plastic impact through :func:`carnot.solve_impact` that
    holds every closed contact. A sticking contact is fastened there (a
    :class:`carnot.PointConstraint` of kind ``fasten``: its relative velocity becomes zero,
    the bilateral equality of the paper's section 3.3); a slipping or frictionless one is a
    plastic frictionless contact. It stands for the accumulation of the ever smaller impacts
    that motion would still make (a rocking block settling on both corners); the series' time
    is collapsed, so a fastened corner may pull slightly (an impulse of the order of the
    tolerance): it is kept and flagged. (Plastic contacts alone would not do for a lamina on
    two corners: the law of several contacts lets the rising corner separate, and the motion
    below the tolerance would go on.)"""

    def settling(f: Feature) -> PairLaw:
        return PairLaw(restitution=0.0)

    held = [c.feature for c in active if c.mode == "stick"]
    struck = [c.feature for c in active if c.mode != "stick"]
    impact = _solve(time, bodies, planes, plane_names, states, struck, settling,
                    allow_tension=True, fastened=held)  # fmt: skip
    flag = Flag(code="settled", where="contacts", message=(
        "the remaining motion on the closed contacts was below the velocity tolerance: "
        "brought to rest by one plastic impact (the accumulation of the impacts it would "
        "still make)"))  # fmt: skip
    return Impact(time=time, result=impact.result, features=[*struck, *held],
                  states=impact.states, flags=(*impact.flags, flag))  # fmt: skip


# Caches of validated parts, keyed on values (carnot.keys) and bounded: a long-lived process
# (a sweep of thousands of simulations) keeps at most these many, whatever it simulates.
#: Bodies' templates kept (a body of a sweep's rows is the same from row to row).
TEMPLATES_KEPT = 256
#: Turned bodies kept (a ball, a block on its pivot or a body that does not turn meets
#: every impact in the same orientation).
ORIENTED_KEPT = 512
#: Plane contacts' templates kept (a plane, a pair's law).
PLANE_CONTACTS_KEPT = 4096


@functools.lru_cache(maxsize=TEMPLATES_KEPT)
def _template_of(key: tuple[str, float, tuple[float, ...]]) -> RigidBody:
    """The body of ``key`` (:attr:`SimBody.value_key`: name, mass, inertia entries) as a
    validated :class:`carnot.RigidBody` in its body axes, at rest at the origin: checked once
    (its inertia tensor's symmetry, positive definiteness and triangle inequality, all
    unchanged by a rotation), never solved itself."""
    name, mass, inertia = key
    return RigidBody(name=name, mass=mass, inertia_com=np.array(inertia[:9]).reshape(3, 3))


def body_template(body: SimBody) -> RigidBody:
    """The body's template (:func:`_template_of`)."""
    return _template_of(body.value_key)


@functools.lru_cache(maxsize=256)
def fixed_body(name: str) -> FixedBody:
    """The fixed body ``name`` (immutable, the same at every impact)."""
    return FixedBody(name=name)


@functools.lru_cache(maxsize=ORIENTED_KEPT)
def _oriented(key: tuple[str, float, tuple[float, ...]],
              orientation: tuple[float, ...]) -> RigidBody:  # fmt: skip
    """The body of ``key`` turned to the unit quaternion ``orientation``
    (:func:`carnot.keys.exact_key` of its floats): its inertia in world axes
    ``J = R J_b R^T`` and ``J^-1 = R J_b^-1 R^T``, rotated from the template's rather than
    validated and inverted again (:meth:`carnot.RigidBody.turned`: a sixth of an event's
    time when every impact met a new orientation, as a tumbling die's does)."""
    return _template_of(key).turned(quat_matrix(np.array(orientation[:4])))


def _rigid_body(body: SimBody, state: BodyState) -> RigidBody:
    """The body in ``state`` as a :class:`carnot.RigidBody`: the oriented template with the
    state's motion and position (:meth:`carnot.RigidBody.moved`: finite, checked; no bound:
    an impact may carry a computed state past the bound on inputs)."""
    if body.inertia_scalar:
        template = _template_of(body.value_key)
    else:
        try:
            template = _oriented(body.value_key, exact_key(state.orientation.tolist()))
        except InputError:
            raise SimulationError(f"the orientation of {body.name} is not a rotation: "
                                  f"{state.orientation}") from None  # fmt: skip
    try:
        return template.moved(state.position.tolist(), state.velocity.tolist(),
                              state.angular_velocity.tolist())  # fmt: skip
    except InputError:
        values = (state.position, state.velocity, state.angular_velocity)
        raise SimulationError(f"the state of {body.name} is not finite: {values}") from None


@functools.lru_cache(maxsize=PLANE_CONTACTS_KEPT)
def _plane_contact_of(a: str, b: str, normal: tuple[float, ...], law: PairLaw,
                      where: str) -> PointContact:  # fmt: skip
    """A validated :class:`carnot.PointContact` of body ``a`` on plane ``b`` (its unit normal:
    :func:`carnot.keys.exact_key` of its floats) with the pair's law, at the origin: a
    template that :func:`contact_at` moves to each impact's point (the plane and the law
    were validated with the scenario, and are the same at every impact). Never solved
    itself, so it caches no rows."""
    return PointContact(a=a, b=b, point=np.zeros(3), normal=np.array(normal[:3]),
                        restitution=law.restitution, law=law.law, friction=law.friction,
                        tangential=law.tangential, where=where)  # type: ignore[arg-type]


def plane_contact_template(a: str, b: str, normal: np.ndarray, law: PairLaw,
                   where: str) -> PointContact:  # fmt: skip
    """The template of the contact of body ``a`` on plane ``b`` (unit ``normal``) with the
    pair's ``law`` (:func:`_plane_contact_of`)."""
    return _plane_contact_of(a, b, exact_key(normal.tolist()), law, where)


def _contact(a: str, b: str, f: Feature, g: Any, law: PairLaw, where: str) -> PointContact:
    """The impact's contact at ``g.point`` (a plane's from its template:
    :func:`plane_contact_template`; between two bodies, whose normal changes, built and
    validated)."""
    if f.other >= 0:
        return PointContact(a=a, b=b, point=g.point, normal=g.normal,
                            restitution=law.restitution, law=law.law, friction=law.friction,
                            tangential=law.tangential, where=where)  # type: ignore[arg-type]
    return contact_at(plane_contact_template(a, b, g.normal, law, where), g.point.tolist())


def impact_problem(time: float, bodies: list[SimBody], planes: list[Plane],
                   plane_names: list[str], states: list[BodyState], approaching: list[Feature],
                   law_of: Any, fastened: Sequence[Feature] = ()
                   ) -> tuple[ImpactProblem, list[int]]:  # fmt: skip
    """The impact of ``approaching`` features (and ``fastened`` ones held) at ``time`` as
    :func:`carnot.solve_impact` takes it (module docstring), and the indices of the movable
    bodies in it. An :class:`carnot.errors.InputError` is a :class:`SimulationError` here."""
    if len(approaching) == 1 and not fastened and approaching[0].other < 0:
        # the common case: one body strikes one plane (the lean loop's impact too)
        f = approaching[0]
        return plane_problem(time, bodies[f.body], plane_names[f.plane], states[f.body],
                             planes[f.plane].normal,
                             geometry(f, bodies, planes, states).point.tolist(),
                             law_of(f)), [f.body]  # fmt: skip
    touched = [*approaching, *fastened]
    geos = {f: geometry(f, bodies, planes, states) for f in touched}
    if len(touched) == 1 and touched[0].other < 0:  # the common case: one body, one plane
        involved = [touched[0].body]
    else:
        involved = sorted({f.body for f in touched} | {f.other for f in touched
                                                        if f.other >= 0})  # fmt: skip
    problem_bodies: dict[str, Any] = {}
    for i in involved:
        state = states[i]
        problem_bodies[bodies[i].name] = _rigid_body(bodies[i], state)
    contacts = []
    for k, f in enumerate(approaching):
        a, b = feature_names(f, bodies, plane_names)
        if f.other < 0:
            problem_bodies.setdefault(b, fixed_body(b))
        contacts.append(_contact(a, b, f, geos[f], law_of(f), f"contacts[{k}]"))
    constraints = []
    for k, f in enumerate(fastened):
        a, b = feature_names(f, bodies, plane_names)
        if f.other < 0:
            problem_bodies.setdefault(b, fixed_body(b))
        constraints.append(PointConstraint(kind="fasten", body=a, point=geos[f].point,
                                           other=b, where=f"constraints[{k}]"))  # fmt: skip
    try:
        problem = ImpactProblem(bodies=problem_bodies, contacts=contacts,
                                constraints=constraints, title=impact_title(time))
    except InputError as err:
        raise SimulationError(f"impact at t = {time:.12g} s: {err}") from None
    return problem, involved


def plane_problem(time: float, body: SimBody, plane: str, state: BodyState,
                  normal: np.ndarray, point: list[float], law: PairLaw) -> ImpactProblem:
    """The impact of ``body`` in ``state`` on the fixed ``plane`` (unit ``normal``) at
    ``point`` (m, on the plane) with the pair's ``law``, as :func:`impact_problem` makes it:
    the body from its validated template (:func:`_rigid_body`), the contact from the
    plane's (:func:`plane_contact`), the problem of these validated parts
    (:meth:`carnot.ImpactProblem.one_contact`)."""
    rigid = _rigid_body(body, state)
    try:
        return ImpactProblem.one_contact(
            body=rigid, other=fixed_body(plane),
            contact=plane_contact(body.name, plane, normal, point, law),
            title=impact_title(time))  # fmt: skip
    except InputError as err:  # pragma: no cover - the parts name each other by construction
        raise SimulationError(f"impact at t = {time:.12g} s: {err}") from None


def plane_contact(name: str, plane: str, normal: np.ndarray, point: list[float],
                  law: PairLaw) -> PointContact:
    """The contact of body ``name`` on the fixed ``plane`` at ``point`` (m; checked finite):
    a copy of the plane's validated template (:func:`plane_contact_template`), as :func:`_contact`
    makes it."""
    return contact_at(plane_contact_template(name, plane, normal, law, "contacts[0]"), point)


def contact_at(template: PointContact, point: list[float]) -> PointContact:
    """A plane's contact ``template`` (:func:`plane_contact_template`) at ``point`` (m; checked
    finite: :meth:`carnot.PointContact.at`)."""
    try:
        return template.at(point)
    except InputError:
        raise SimulationError(f"{template.where}: the contact point is not finite: "
                              f"{np.array(point, dtype=float)}") from None  # fmt: skip


def impact_title(time: float) -> str:
    """The title of the impact at ``time`` (s)."""
    return f"impact at t = {time:.12g} s"


def _solve(time: float, bodies: list[SimBody], planes: list[Plane], plane_names: list[str],
           states: list[BodyState], approaching: list[Feature], law_of: Any,
           allow_tension: bool = False, fastened: Sequence[Feature] = ()
           ) -> Impact:  # fmt: skip
    problem, involved = impact_problem(time, bodies, planes, plane_names, states, approaching,
                                       law_of, fastened)  # fmt: skip
    flags: list[Flag] = []
    try:
        result = solve_impact(problem)
    except InputError as err:
        raise SimulationError(f"impact at t = {time:.12g} s: {err}") from None
    new_states = list(states)
    for i in involved:
        motion = result.bodies[bodies[i].name]
        s = states[i]
        v, w = np.array(motion.velocity_after), np.array(motion.angular_velocity_after)
        if bodies[i].plane_normal_body is not None:
            v, w = bodies[i].planar_velocity(s.rotation, v, w)
        new_states[i] = s.with_motion(v, w)  # (its rotation matrix kept: the same one)
    if len(approaching) > 1 and not allow_tension:
        negative = [c.where for c in result.contacts if (c.normal_impulse or 0.0) < 0.0]
        if negative:  # the complementarity law never pulls: a guard, not an expected path
            raise SimulationError(
                f"at t = {time:.12g} s, {len(approaching)} contacts are struck at once and the "
                f"impact pulls at {negative[0]} (a negative normal impulse)"
            )
        flags.append(Flag(
            code="simultaneous_contacts", where="contacts",
            message=(f"{len(approaching)} contacts struck at once, solved together by the "
                     f"{result.multiple_impact or 'equality'} law of several contacts "
                     "(DESIGN.md section 6)")))  # fmt: skip
    return Impact(time=time, result=result, features=list(approaching), states=new_states,
                  flags=tuple(flags))

"""What collides: bodies, contacts and constraints, checked against each other."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from carnot.errors import InputError
from carnot.laws.registry import MULTIPLE_IMPACT_NAMES
from carnot.model.bodies import Body, FixedBody, RigidBody
from carnot.model.contacts import PointConstraint, PointContact
from carnot.solvers.options import SolverOptions


@dataclass(frozen=True, kw_only=True, eq=False)
class ImpactProblem:
    """Bodies by name, contacts and constraints (solved simultaneously), and a title.

    ``multiple_impact``: the law of several unilateral point contacts at once
    (``simultaneous``, ``sequential``, ``dispersion``: DESIGN.md section 6); ``solver``: the
    simultaneous law's solver and its tolerance (DESIGN.md section 9; ``None``: ``auto``).

    >>> ball = RigidBody(mass=1.0, inertia_com=[[1, 0, 0], [0, 1, 0], [0, 0, 1]], name="ball")
    >>> ImpactProblem(bodies={"ball": ball}, contacts=[PointContact(
    ...     a="ball", b="wall", point=[0, 0, 0], normal=[1, 0, 0])])
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: contacts[0].b: unknown body (known: ball), got 'wall'
    """

    bodies: Mapping[str, Body]
    contacts: Sequence[PointContact] = ()
    constraints: Sequence[PointConstraint] = ()
    title: str = ""
    multiple_impact: str = "simultaneous"
    solver: SolverOptions | None = None
    movable: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "bodies", dict(self.bodies))
        object.__setattr__(self, "contacts", tuple(self.contacts))
        object.__setattr__(self, "constraints", tuple(self.constraints))
        for name, body in self.bodies.items():
            if not isinstance(body, (RigidBody, FixedBody)):
                raise InputError(f"bodies.{name}", "must be a RigidBody or FixedBody", body)
        object.__setattr__(self, "movable", _movable(self.bodies))
        known = ", ".join(self.bodies)
        for c in self.contacts:
            for key in ("a", "b"):
                name = getattr(c, key)
                if name not in self.bodies:
                    raise InputError(f"{c.where}.{key}", f"unknown body (known: {known})", name)
            if self.bodies[c.a].fixed and self.bodies[c.b].fixed:
                raise InputError(
                    c.where, "is a contact between two fixed bodies", f"{c.a} and {c.b}"
                )
        for k in self.constraints:
            if k.body not in self.bodies:
                raise InputError(f"{k.where}.body", f"unknown body (known: {known})", k.body)
            if self.bodies[k.body].fixed:
                raise InputError(f"{k.where}.body", "must be a movable body, not fixed", k.body)
            if k.other is not None and k.other not in self.bodies:
                raise InputError(f"{k.where}.other", f"unknown body (known: {known})", k.other)
        if self.multiple_impact not in MULTIPLE_IMPACT_NAMES:
            raise InputError(
                "multiple_impact", f"must be one of {', '.join(MULTIPLE_IMPACT_NAMES)}",
                self.multiple_impact,
            )  # fmt: skip
        if self.solver is not None and not isinstance(self.solver, SolverOptions):
            raise InputError("solver", "must be a SolverOptions", self.solver)
        if not self.contacts and not self.constraints:
            raise InputError("contacts", "at least one contact or constraint is needed", [])

    @classmethod
    def one_contact(cls, *, body: RigidBody, other: Body, contact: PointContact,
                    title: str = "") -> ImpactProblem:  # fmt: skip
        """The problem of one ``contact`` between the movable ``body`` (``contact.a``) and
        ``other`` (``contact.b``, fixed or movable), each part validated by its own
        constructor, under the default law of several contacts: what the constructor makes
        of ``bodies={body.name: body, other.name: other}`` and ``contacts=[contact]``, its
        checks reduced to those the parts leave (the types, the contact naming the two
        bodies), for producers that make thousands a second (``carnot simulate``'s impact of
        one body on a plane).

        >>> ball = RigidBody(mass=1.0, inertia_com=[[1, 0, 0], [0, 1, 0], [0, 0, 1]],
        ...                  name="ball")
        >>> c = PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1])
        >>> ImpactProblem.one_contact(body=ball, other=FixedBody(name="floor"), contact=c).movable
        ('ball',)
        >>> ImpactProblem.one_contact(body=ball, other=FixedBody(name="wall"), contact=c)
        Traceback (most recent call last):
        ...
        carnot.errors.InputError: contacts[0].b: must name the other body (wall), got 'floor'
        """
        if not isinstance(body, RigidBody):
            raise InputError(f"bodies.{getattr(body, 'name', '?')}", "must be a RigidBody", body)
        if not isinstance(other, (RigidBody, FixedBody)):
            raise InputError(f"bodies.{getattr(other, 'name', '?')}",
                             "must be a RigidBody or FixedBody", other)  # fmt: skip
        if not isinstance(contact, PointContact):
            raise InputError("contacts[0]", "must be a PointContact", contact)
        if contact.a != body.name:
            raise InputError(f"{contact.where}.a", f"must name the body ({body.name})",
                             contact.a)  # fmt: skip
        if contact.b != other.name:
            raise InputError(f"{contact.where}.b", f"must name the other body ({other.name})",
                             contact.b)  # fmt: skip
        bodies: dict[str, Body] = {body.name: body, other.name: other}
        out = object.__new__(cls)
        # (the fields as __post_init__ leaves them: a dict, tuples, the movable names)
        out.__dict__.update(bodies=bodies, contacts=(contact,), constraints=(), title=title,
                            multiple_impact="simultaneous", solver=None,
                            movable=_movable(bodies))  # fmt: skip
        return out


def _movable(bodies: Mapping[str, Body]) -> tuple[str, ...]:
    """The names of the movable bodies, in order."""
    return tuple(n for n, b in bodies.items() if isinstance(b, RigidBody))

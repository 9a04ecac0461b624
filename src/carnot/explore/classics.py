"""The classic impacts of ``carnot explore``: each turns a few slider values into a scenario
(format 1, as plain data) that carnot's own loader and solver then handle.

No physics here: a classic only places bodies, a contact point and a normal. Every value is
checked against its slider's bounds first (a request can carry anything), so that a bad one is
refused with a message naming the parameter, the bound and the value received.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from carnot import InputError

LAWS = ("newton", "poisson", "stronge")


@dataclass(frozen=True, kw_only=True)
class Parameter:
    """One slider (``choices`` empty) or one menu: its name, label, unit, bounds and default."""

    name: str
    label: str
    default: float | str
    unit: str = ""
    low: float = 0.0
    high: float = 1.0
    step: float = 0.01
    choices: tuple[str, ...] = ()

    def check(self, value: Any, field_name: str) -> float | str:
        """The value if it is within bounds; otherwise an ``InputError`` naming the field.

        >>> Parameter(name="e", label="e", default=0.5).check(1.5, "parameters.e")
        Traceback (most recent call last):
        ...
        carnot.errors.InputError: parameters.e: must be in [0.0, 1.0], got 1.5
        """
        if self.choices:
            if value not in self.choices:
                raise InputError(field_name, f"must be one of {', '.join(self.choices)}", value)
            return str(value)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(field_name, "must be a number", value)
        number = float(value)
        if not math.isfinite(number) or not self.low <= number <= self.high:
            raise InputError(field_name, f"must be in [{self.low}, {self.high}]", value)
        return number


def _restitution() -> Parameter:
    return Parameter(name="e", label="restitution e", default=0.5, step=0.05)


def _friction(default: float) -> Parameter:
    return Parameter(name="mu", label="friction mu", default=default, high=1.5, step=0.05)


def _law() -> Parameter:
    return Parameter(name="law", label="meaning of e", default="newton", choices=LAWS)


@dataclass(frozen=True, kw_only=True)
class Classic:
    """A classic impact: what the page shows about it and how its scenario is built."""

    name: str
    title: str
    description: str
    parameters: tuple[Parameter, ...]
    build: Callable[[Mapping[str, Any]], dict[str, Any]] = field(repr=False)

    def scenario(self, values: Mapping[str, Any]) -> dict[str, Any]:
        """The scenario (format 1, plain data) for these parameter values; absent ones take
        their defaults, unknown or out-of-bounds ones are refused.

        >>> CLASSICS["rod_ledge"].scenario({"d": 0.2})["contacts"][0]["point"]
        [0.2, 0.0, -0.01]
        >>> CLASSICS["rod_ledge"].scenario({"size": 1})
        Traceback (most recent call last):
        ...
        carnot.errors.InputError: parameters.size: unknown parameter (allowed: d, drop, slide, spin, e, mu, law), got 'size'
        """  # noqa: E501
        if not isinstance(values, Mapping):
            raise InputError("parameters", "must be an object of parameter values", values)
        known = {p.name: p for p in self.parameters}
        for key in values:
            if key not in known:
                allowed = ", ".join(known)
                raise InputError(
                    f"parameters.{key}", f"unknown parameter (allowed: {allowed})", key
                )
        checked = {
            p.name: p.check(values.get(p.name, p.default), f"parameters.{p.name}")
            for p in self.parameters
        }
        return self.build(checked)


def _cylinder_edge(v: Mapping[str, Any]) -> dict[str, Any]:
    # The paper's section 3.1 (examples/paper_cylinder_edge.toml): edge at the origin, normal
    # +y; the centre approaches at `speed`, `alpha` degrees from the normal.
    alpha = math.radians(v["alpha"])
    radius = 0.1
    return {
        "format": 1,
        "title": "Cylinder striking a sharp edge (the paper's section 3.1)",
        "bodies": {
            "cylinder": {
                "mass": 2.0, "shape": "solid_cylinder", "radius": radius, "length": 0.1,
                "axis": [0.0, 0.0, 1.0], "position": [0.0, radius, 0.0],
                "velocity": [v["speed"] * math.sin(alpha), -v["speed"] * math.cos(alpha), 0.0],
                "angular_velocity": [0.0, 0.0, v["spin"]],
            },
            "edge": {"fixed": True},
        },
        "contacts": [{
            "a": "cylinder", "b": "edge", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0],
            "restitution": v["e"], "friction": v["mu"], "law": v["law"],
        }],
    }  # fmt: skip


def _rod_ledge(v: Mapping[str, Any]) -> dict[str, Any]:
    # examples/rod_on_ledge.toml with the ledge's offset d from the centre as a slider, and a
    # sliding speed so that friction has something to oppose.
    return {
        "format": 1,
        "title": "A rod falling flat onto a ledge",
        "bodies": {
            "rod": {
                "mass": 1.2, "shape": "rod", "length": 1.0, "radius": 0.01,
                "axis": [1.0, 0.0, 0.0], "position": [0.0, 0.0, 0.0],
                "velocity": [v["slide"], 0.0, -v["drop"]],
                "angular_velocity": [0.0, v["spin"], 0.0],
            },
            "ledge": {"fixed": True},
        },
        "contacts": [{
            "a": "rod", "b": "ledge", "point": [v["d"], 0.0, -0.01], "normal": [0.0, 0.0, 1.0],
            "restitution": v["e"], "friction": v["mu"], "law": v["law"],
        }],
    }  # fmt: skip


def _sphere_spin(v: Mapping[str, Any]) -> dict[str, Any]:
    # examples/spinning_ball_bounce.toml, with Coulomb friction (slip allowed) instead of an
    # imposed grip, and side spin too.
    radius = 0.04
    return {
        "format": 1,
        "title": "A spinning ball bouncing on a rough floor",
        "bodies": {
            "ball": {
                "mass": 0.25, "shape": "sphere", "radius": radius,
                "position": [0.0, 0.0, radius], "velocity": [v["forward"], 0.0, -v["drop"]],
                "angular_velocity": [v["sidespin"], v["backspin"], 0.0],
            },
            "floor": {"fixed": True},
        },
        "contacts": [{
            "a": "ball", "b": "floor", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0],
            "restitution": v["e"], "friction": v["mu"], "law": v["law"],
        }],
    }  # fmt: skip


def _cradle(v: Mapping[str, Any]) -> dict[str, Any]:
    # Balls along x, touching; the first strikes the others. Every contact is solved at once
    # with Newton's e on each (today's solver); see the classic's description.
    count = int(round(v["balls"]))
    radius = 0.025
    bodies: dict[str, Any] = {}
    for k in range(count):
        bodies[f"ball{k + 1}"] = {
            "mass": 0.1, "shape": "sphere", "radius": radius,
            "position": [2 * radius * k, 0.0, 0.0],
            "velocity": [v["speed"] if k == 0 else 0.0, 0.0, 0.0],
        }  # fmt: skip
    contacts = [
        {
            "a": f"ball{k + 2}", "b": f"ball{k + 1}", "point": [radius * (2 * k + 1), 0.0, 0.0],
            "normal": [1.0, 0.0, 0.0], "restitution": v["e"],
        }  # fmt: skip
        for k in range(count - 1)
    ]
    return {"format": 1, "title": f"Newton's cradle, {count} balls", "bodies": bodies,
            "contacts": contacts}  # fmt: skip


CLASSICS: dict[str, Classic] = {
    c.name: c
    for c in (
        Classic(
            name="cylinder_edge",
            title="Cylinder on an edge",
            description="A solid cylinder (2 kg, radius 0.1 m) strikes a sharp edge: the "
            "paper's section 3.1, here with Coulomb friction (slip, stick or reversal). "
            "alpha is the angle of the centre's velocity from the edge's normal; spin is "
            "about the cylinder's axis (negative: clockwise).",
            parameters=(
                Parameter(name="speed", label="speed of the centre", unit="m/s", default=2.0,
                          low=0.1, high=5.0, step=0.1),
                Parameter(name="alpha", label="angle from the normal", unit="deg",
                          default=37.0, low=0.0, high=85.0, step=1.0),
                Parameter(name="spin", label="spin", unit="rad/s", default=-5.0, low=-40.0,
                          high=40.0, step=1.0),
                _restitution(), _friction(0.3), _law(),
            ),
            build=_cylinder_edge,
        ),  # fmt: skip
        Classic(
            name="rod_ledge",
            title="Rod on a ledge",
            description="A rod (1.2 kg, 1 m long) falls flat onto a ledge at a distance d "
            "from its centre, sliding along its length. Move d and watch the effective mass "
            "at the contact, m / (1 + 12 d^2 / L^2), and so the energy the impact takes: "
            "smaller the further the ledge is from the centre.",
            parameters=(
                Parameter(name="d", label="contact point from the centre", unit="m",
                          default=0.3, low=-0.5, high=0.5, step=0.01),
                Parameter(name="drop", label="falling speed", unit="m/s", default=2.0,
                          low=0.1, high=5.0, step=0.1),
                Parameter(name="slide", label="sliding speed", unit="m/s", default=0.5,
                          low=-3.0, high=3.0, step=0.1),
                Parameter(name="spin", label="spin about y", unit="rad/s", default=0.0,
                          low=-10.0, high=10.0, step=0.5),
                _restitution(), _friction(0.3), _law(),
            ),
            build=_rod_ledge,
        ),  # fmt: skip
        Classic(
            name="sphere_spin",
            title="Sphere with spin",
            description="A ball (0.25 kg, radius 0.04 m) with backspin and side spin lands "
            "on a rough floor: it slips, and grips if friction stops the slip in time.",
            parameters=(
                Parameter(name="forward", label="forward speed", unit="m/s", default=3.0,
                          low=-6.0, high=6.0, step=0.1),
                Parameter(name="drop", label="falling speed", unit="m/s", default=4.0,
                          low=0.1, high=8.0, step=0.1),
                Parameter(name="backspin", label="spin about y", unit="rad/s", default=-50.0,
                          low=-150.0, high=150.0, step=5.0),
                Parameter(name="sidespin", label="spin about x", unit="rad/s", default=0.0,
                          low=-150.0, high=150.0, step=5.0),
                Parameter(name="e", label="restitution e", default=0.8, step=0.05),
                _friction(0.5), _law(),
            ),
            build=_sphere_spin,
        ),  # fmt: skip
        Classic(
            name="cradle",
            title="Newton's cradle (simultaneous)",
            description="Balls in a row, touching; the first strikes the rest. Today carnot "
            "solves every contact at once with Newton's e on each (a generalized Newton "
            "law): with e = 1 and three balls the first rebounds at -v/3 and the others "
            "leave together at 2v/3, not the single ball a real cradle sends. The "
            "sequential and dispersion laws that reproduce a cradle are being built "
            "(issue 14).",
            parameters=(
                Parameter(name="balls", label="balls", default=3.0, low=2.0, high=5.0,
                          step=1.0),
                Parameter(name="speed", label="speed of the first ball", unit="m/s",
                          default=1.0, low=0.1, high=3.0, step=0.1),
                Parameter(name="e", label="restitution e", default=1.0, step=0.05),
            ),
            build=_cradle,
        ),  # fmt: skip
    )
}

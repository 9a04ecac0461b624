"""Impact laws, each seeing only contact space, in one registry."""

from __future__ import annotations

from carnot.laws.base import EqualityLaw
from carnot.laws.restitution import (
    Bilateral,
    NewtonRestitution,
    PoissonRestitution,
    StrongeRestitution,
)

#: Law name (the scenario's ``law`` key) -> law.
LAWS: dict[str, EqualityLaw] = {
    law.name: law for law in (NewtonRestitution(), PoissonRestitution(), StrongeRestitution())
}
LAW_NAMES: tuple[str, ...] = tuple(LAWS)
BILATERAL = Bilateral()

__all__ = ["BILATERAL", "LAWS", "LAW_NAMES", "EqualityLaw"]

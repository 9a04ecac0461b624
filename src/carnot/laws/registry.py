"""The one registry of restitution hypotheses, what each supports, and which rule a contact
follows: decided here once for the solver, the batch kernels and the sweeps.

A contact's rule: ``given`` (its impulse is given), ``stick`` (no slip after: an equality on its
normal and tangent rows), ``frictionless`` (an equality on its normal rows), or ``coulomb``
(friction that may slip: integrated in impulse space). Equalities of every contact and
constraint are solved together (:data:`carnot.laws.restitution.EQUALITY`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, Protocol

import numpy as np

from carnot.errors import InputError
from carnot.laws.base import Support

#: Each hypothesis (the scenario's ``law`` key) and what it supports. Poisson's and Stronge's
#: differ from Newton's as soon as the normal velocity is not affine in one normal impulse
#: (laws/restitution.py): they are kept to one point contact, frictionless or with Coulomb slip.
HYPOTHESES: dict[str, Support] = {
    "newton": Support(stick=True, patch=True, simultaneous=True, coulomb_slip=True),
    "poisson": Support(stick=False, patch=False, simultaneous=False, coulomb_slip=True),
    "stronge": Support(stick=False, patch=False, simultaneous=False, coulomb_slip=True),
}
LAW_NAMES: tuple[str, ...] = tuple(HYPOTHESES)
#: The laws of several unilateral point contacts at once (carnot.laws.multiple), the first the
#: default; only the first handles friction.
MULTIPLE_IMPACT_NAMES: tuple[str, ...] = ("simultaneous", "sequential", "dispersion")

Rule = Literal["given", "stick", "frictionless", "coulomb"]


def contact_rule(*, tangential: str, friction: Any, given: bool = False) -> Rule:
    """The rule of a contact (see the module docstring); ``friction`` may be an array (the
    batch's): ``frictionless`` only when every entry is 0.

    >>> contact_rule(tangential="slip", friction=0.3), contact_rule(tangential="stick", friction=0)
    ('coulomb', 'stick')
    """
    if given:
        return "given"
    if tangential == "stick":
        return "stick"
    return "frictionless" if _all_zero(friction) else "coulomb"


def check_hypothesis(name: Any, field: str) -> str:
    """``name`` if it is a known hypothesis, else an :class:`InputError` naming ``field``."""
    if not isinstance(name, str) or name not in HYPOTHESES:
        raise InputError(field, f"must be one of {', '.join(LAW_NAMES)}", name)
    return name


class ContactSpec(Protocol):
    """What the registry reads of a contact (``carnot.model.PointContact`` has it)."""

    @property
    def where(self) -> str: ...
    @property
    def law(self) -> str: ...
    @property
    def friction(self) -> float: ...
    @property
    def tangential(self) -> str: ...
    @property
    def is_given(self) -> bool: ...
    @property
    def patch(self) -> Any: ...


def several_contacts(contacts: Sequence[ContactSpec]) -> bool:
    """Whether a multiple-impact law applies: two or more unilateral point contacts with a law
    (a contact over a surface or with a given impulse is not one of them)."""
    return sum(1 for c in contacts if not c.is_given and c.patch is None) >= 2


def check_supported(
    contacts: Sequence[ContactSpec],
    fastened: Sequence[str] = (),
    multiple_impact: str = "simultaneous",
) -> None:
    """Refuse what the hypotheses and the multiple-impact laws do not support (:data:`HYPOTHESES`)
    rather than answer it with another law; ``fastened``: where the problem's sudden
    fastenings are."""
    law_contacts = [c for c in contacts if not c.is_given]
    if several_contacts(contacts) and multiple_impact != "simultaneous":
        for c in law_contacts:
            if c.friction > 0 or c.tangential == "stick":
                field, value = ((f"{c.where}.friction", c.friction) if c.friction > 0
                                else (f"{c.where}.tangential", c.tangential))  # fmt: skip
                raise InputError(
                    field,
                    f"must be frictionless with multiple_impact = {multiple_impact!r} (a "
                    "frictionless law of several contacts; \"simultaneous\" handles friction)",
                    value,
                )
    several = several_contacts(contacts)
    unilateral_rows = sum(
        (1 if c.patch is None else 2) + (2 if c.tangential == "stick" else 0) for c in law_contacts
    )
    for c in law_contacts:
        support = HYPOTHESES[c.law]
        rule = contact_rule(tangential=c.tangential, friction=c.friction)
        if rule == "coulomb":
            if c.patch is not None:
                raise InputError(
                    f"{c.where}.friction",
                    "Coulomb friction with slip over a contact patch is not supported (the "
                    'impulse-space integration is for point contacts): give tangential = '
                    '"stick", friction = 0, or a point contact',
                    c.friction,
                )
            if len(law_contacts) > 1 and not several:
                raise InputError(
                    f"{c.where}.friction",
                    "Coulomb friction with slip beside a contact over a surface is not "
                    "supported: give the surface contact as its corner points",
                    c.friction,
                )
            if fastened and not several:
                raise InputError(
                    fastened[0],
                    "a sudden fastening together with a frictional contact has no defined "
                    "order of events in this version; a pin (already at rest) is supported",
                    "fasten",
                )
            continue
        wanted_stick = rule == "stick" and not support.stick
        wanted_patch = c.patch is not None and not support.patch
        if wanted_stick or wanted_patch or (unilateral_rows > 1 and not support.simultaneous):
            raise InputError(
                f"{c.where}.law",
                "Poisson's and Stronge's hypotheses differ from Newton's here (sticking, a "
                "surface contact or several simultaneous contacts); this version supports "
                "them for a single point contact, frictionless or with Coulomb friction "
                '(tangential = "slip", the default)',
                c.law,
            )


def _all_zero(value: Any) -> bool:
    if isinstance(value, (int, float)):
        return value == 0
    if isinstance(value, np.ndarray | np.generic):
        return not np.any(value)
    return False  # a lazy or device array: the Coulomb law handles its mu = 0 entries

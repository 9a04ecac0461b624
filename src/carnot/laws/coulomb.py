"""Coulomb friction with slip as a law of the common contract: ``resolve(K, w', params)``.

``K`` is the contact's 3x3 effective inverse mass in its frame ``(n, t1, t2)`` (persistent
constraints folded in by the pipeline), ``w'`` its relative velocity in that frame; the impact
is integrated in impulse space (:func:`carnot.laws.friction.integrate_impact`) and the process
record (phases, works, samples) comes back with the impulses.
"""

from __future__ import annotations

import numpy as np

from carnot.laws.base import LawAnswer, LawParams
from carnot.laws.friction import integrate_impact


class CoulombLaw:
    """One point contact with Coulomb friction under a restitution hypothesis.

    A sphere (1 kg, I = 2/5 kg m^2 at radius 1 m) landing at 1 m/s while sliding at 1 m/s,
    mu = 0.1, e = 0.5 under Poisson: gross slip, ``P_t = -mu P_n`` (Brach 1991, ch. 4):

    >>> K = np.diag([1.0, 1 + 1 / 0.4, 1 + 1 / 0.4])
    >>> COULOMB.resolve(K, np.array([-1.0, 1.0, 0.0]), LawParams(
    ...     roles=("normal", "tangent", "tangent"), restitution=0.5, friction=0.1,
    ...     hypothesis="poisson")).impulses.round(12).tolist()
    [1.5, -0.15, 0.0]
    """

    name = "coulomb"

    def resolve(self, delassus: np.ndarray, w_before: np.ndarray, params: LawParams) -> LawAnswer:
        process = integrate_impact(
            delassus, w_before, friction=params.friction,
            restitution=float(np.asarray(params.restitution)), hypothesis=params.hypothesis,
        )  # fmt: skip
        return LawAnswer(impulses=process.impulse, redundant=np.zeros(3, dtype=bool),
                         process=process)  # fmt: skip


COULOMB = CoulombLaw()

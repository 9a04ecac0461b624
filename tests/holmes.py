"""Holmes' ball on a vibrating table in closed form, shared by the tests of the simulator
(tests/test_vibrating_table.py) and of its periodic orbits (tests/test_simulate_cycle.py).

Holmes, *The dynamics of repeated impacts with a sinusoidally vibrating table*, J. Sound Vib.
84 (1982): a ball with restitution ``e`` on a table moving by ``A sin(w t + phi)``; its
period-1 orbit (one impact per forcing period ``T``) has ``Gamma cos(phi) = pi (1 - e) /
(1 + e)`` with ``Gamma = A w^2 / g``, and the exact map's period doubling is at
``Gamma sin(phi) = 2 (1 + e^2) / (1 + e)^2``.
"""

from __future__ import annotations

import math

G = 9.81
E = 0.5
FREQUENCY = 5.0  # Hz
W = 2 * math.pi * FREQUENCY
T = 1 / FREQUENCY
RADIUS = 0.02
#: Holmes' right-hand side pi (1 - e) / (1 + e).
HOLMES = math.pi * (1 - E) / (1 + E)
#: The exact map's period-doubling bound on Gamma sin(phi): 2 (1 + e^2) / (1 + e)^2.
DOUBLING = 2 * (1 + E * E) / (1 + E) ** 2


def orbit(gamma_sin: float) -> tuple[float, float]:
    """``(Gamma, phi)`` of the period-1 orbit with ``Gamma sin(phi) = gamma_sin``."""
    return math.hypot(HOLMES, gamma_sin), math.atan2(gamma_sin, HOLMES)


def amplitude(gamma: float) -> float:
    """The table's amplitude ``A = Gamma g / w^2`` (m)."""
    return gamma * G / W**2

"""
A tumbling box lands on a corner: 3D slip that turns
=====================================================

``examples/box_corner_rough_floor.toml``: the inverse mass at the corner couples both tangent
directions with the normal, so the slip direction turns (by about 84 degrees) while the box
slides; no closed form exists and the impact is integrated in impulse space (DOP853). The
hodograph on the right is the slip velocity in the contact plane as the impulse grows.
"""

import numpy as np

import carnot
from carnot.io.scenario import load_scenario
from carnot.plot import plot_impact

result = carnot.solve_impact(load_scenario("../../examples/box_corner_rough_floor.toml"))
contact = result.contacts[0]
turn = sum(phase.turn for phase in contact.process.phases)
print("regime:", contact.regime, "| slip turned by", round(float(np.degrees(turn)), 1), "deg")
print("E_d direct - theorem (J):", result.energy.dissipated - result.energy.dissipated_theorem)
fig = plot_impact(result)

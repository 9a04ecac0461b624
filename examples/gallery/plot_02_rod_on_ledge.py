"""
A rod on a ledge: the effective mass at the contact
====================================================

``examples/rod_on_ledge.toml``: a rod falling flat onto a ledge at a distance ``d`` from its
centre. The scenario is read once with :func:`carnot.io.scenario.read_scenario_data`, the
contact point moved, and each case solved with :func:`carnot.solve_impact`. The closed form
(Stronge, *Impact Mechanics*, 2000, ch. 2-3) is
``E_d = (1 - e^2) m v^2 / (2 (1 + 12 d^2 / L^2))``.
"""

import copy

import matplotlib.pyplot as plt
import numpy as np

import carnot
from carnot.io.scenario import parse_scenario, read_scenario_data

data = read_scenario_data("../../examples/rod_on_ledge.toml")
m, v, e = 1.2, 2.0, 0.4
offsets = np.linspace(-0.5, 0.5, 41)
dissipated, omega = [], []
for d in offsets:
    case = copy.deepcopy(data)
    case["contacts"][0]["point"][0] = float(d)
    result = carnot.solve_impact(parse_scenario(case))
    dissipated.append(result.energy.dissipated)
    omega.append(result.bodies["rod"].angular_velocity_after[1])

fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.4))
ax1.plot(offsets, (1 - e**2) * m * v**2 / (2 * (1 + 12 * offsets**2)), color="0.6", lw=4,
         label="closed form")
ax1.plot(offsets, dissipated, ".", color="#1f4e9c", label="carnot")
ax1.set_xlabel("ledge offset d (m)")
ax1.set_ylabel("E_d (J)")
ax1.legend()
ax2.plot(offsets, omega, color="#c0392b")
ax2.set_xlabel("ledge offset d (m)")
ax2.set_ylabel("angular velocity after, y (rad/s)")
fig.tight_layout()

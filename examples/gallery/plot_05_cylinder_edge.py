"""
The paper's cylinder on an edge, over the angle of incidence
=============================================================

``examples/paper_cylinder_edge.toml`` (the paper's section 3.1): a cylinder strikes a sharp
edge without slipping. Its printed result,
``E_d = (m v^2 / 2) [(1/3)(r omega / v - sin alpha)^2 + (1 - e^2) cos^2 alpha]``,
against carnot's solve over the angle ``alpha`` of the centre's velocity from the normal.
"""

import copy
import math

import matplotlib.pyplot as plt
import numpy as np

import carnot
from carnot.io.scenario import parse_scenario, read_scenario_data

data = read_scenario_data("../../examples/paper_cylinder_edge.toml")
m, r, v, omega, e = 2.0, 0.1, 2.0, 5.0, 0.5
alphas = np.radians(np.linspace(0, 80, 33))
solved = []
for a in alphas:
    case = copy.deepcopy(data)
    case["bodies"]["cylinder"]["velocity"] = [v * math.sin(a), -v * math.cos(a), 0.0]
    solved.append(carnot.solve_impact(parse_scenario(case)).energy.dissipated)
printed = m * v**2 / 2 * ((r * omega / v - np.sin(alphas)) ** 2 / 3
                          + (1 - e**2) * np.cos(alphas) ** 2)

fig, ax = plt.subplots(figsize=(6, 3.6))
ax.plot(np.degrees(alphas), printed, color="0.6", lw=4, label="the paper's formula")
ax.plot(np.degrees(alphas), solved, ".", color="#1f4e9c", label="carnot")
ax.set_xlabel("alpha (deg)")
ax.set_ylabel("E_d (J)")
ax.legend()
fig.tight_layout()
print("largest relative difference:", np.max(np.abs(np.array(solved) / printed - 1)))

"""
A rimless wheel and a compass walker settling onto their gaits
==============================================================

``examples/motion/``: McGeer's rimless wheel (8 spokes, a 0.08 rad slope) started below
its speed, and Goswami's compass walker on a 3 degree slope started off its gait. Each
strike is solved by ``solve_impact``; the energy each takes converges to the one of the
limit cycle that ``find_cycle`` finds, where the strikes take what the slope gives: for the
wheel, McGeer's closed form ``E_d = 1/2 m l^2 (1 - cos^2 2a) omega-^2`` at
``omega* = cot(2a) sqrt(4 (g/l) sin a sin slope)``.
"""

import math

import matplotlib.pyplot as plt
import numpy as np

from carnot.hybrid.cycle import find_cycle
from carnot.hybrid.models import named_model
from carnot.hybrid.simulate import simulate

fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
cases = [
    (named_model("rimless_wheel", {"spokes": 8, "slope": 0.08}),
     np.array([0.08 - math.pi / 8, 0.9]), 12.0, "rimless wheel"),
    (named_model("compass_gait"), np.array([-0.22, 0.32, 1.2, 0.3]), 6.0, "compass gait"),
]
for ax, (model, start, duration, label) in zip(axes, cases, strict=True):
    run = simulate(model, start, duration)
    e_d = [e.strike.result.energy.dissipated for e in run.events if e.strike is not None]
    orbit = find_cycle(model, start)
    ax.plot(range(1, len(e_d) + 1), e_d, "o-", color="#1f4e9c", ms=3, label="each strike")
    ax.axhline(orbit.energy["impacts"], color="0.5", ls="--",
               label=f"limit cycle (|multiplier| {np.max(np.abs(orbit.multipliers)):.2f})")
    ax.set_title(label)
    ax.set_xlabel("strike")
    ax.set_ylabel("E_d (J)")
    ax.legend(fontsize=8)
    print(label, "ledger residual", run.energy["residual"], "J")
fig.tight_layout()

alpha, g = math.pi / 8, 9.81
omega = math.sqrt(4 * g * math.sin(alpha) * math.sin(0.08)) / math.tan(2 * alpha)
mcgeer = 0.5 * (1 - math.cos(2 * alpha) ** 2) * (omega / math.cos(2 * alpha)) ** 2
print("the wheel's cycle: E_d", find_cycle(*cases[0][:2]).energy["impacts"], "McGeer", mcgeer)

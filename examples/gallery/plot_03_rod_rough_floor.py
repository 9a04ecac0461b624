"""
Friction in impulse space: slip, then reversal
===============================================

``examples/rod_rough_floor.toml`` (Stronge, *Impact Mechanics*, 2000, ch. 5): an inclined rod
strikes a rough floor. The normal impulse ``p`` is the clock; the slip stops during
compression and, since the friction is below the value that would hold it, reverses. The
picture is :func:`carnot.plot.plot_impact` (``carnot solve FILE --plot OUT``).
"""

import carnot
from carnot.io.scenario import load_scenario
from carnot.plot import plot_impact

result = carnot.solve_impact(load_scenario("../../examples/rod_rough_floor.toml"))
contact = result.contacts[0]
print("regime:", contact.regime)
print("E_d direct, theorem, work route (J):", result.energy.dissipated,
      result.energy.dissipated_theorem,
      -(contact.process.work_normal_compression + contact.process.work_normal_restitution
        + contact.process.work_tangential_compression
        + contact.process.work_tangential_restitution))
fig = plot_impact(result)

"""
A ball on a floor: where the energy goes as e varies
=====================================================

``examples/ball_on_floor.toml`` solved for eleven coefficients of restitution at once with
:func:`carnot.batch.point_impacts`, and the dissipated energy compared by three routes: the
direct difference of the kinetic energies ``E' - E''``, the theorem's sum
``-1/2 P . (w' + w'')``, and the textbook closed form ``(1 - e^2) m v_z^2 / 2``.
"""

import matplotlib.pyplot as plt
import numpy as np

from carnot.batch import BatchBodies, point_impacts
from carnot.model.inertia import solid_sphere

m, radius, v_z = 0.5, 0.1, -3.0
e = np.linspace(0.0, 1.0, 11)
ball = BatchBodies(mass=m, inertia_com=solid_sphere(m, radius), position_com=[0, 0, radius],
                   velocity_com=[1.0, 0.0, v_z])
out = point_impacts(ball, None, [0, 0, 0], [0, 0, 1], e)

fig, ax = plt.subplots(figsize=(6, 3.6))
fine = np.linspace(0, 1, 200)
ax.plot(fine, (1 - fine**2) * m * v_z**2 / 2, color="0.6", lw=4, label="closed form")
ax.plot(e, out.dissipated, "o", color="#1f4e9c", label="E' - E'' (direct)")
ax.plot(e, out.dissipated_theorem, "x", color="#c0392b", ms=9, label="theorem")
ax.set_xlabel("coefficient of restitution e")
ax.set_ylabel("dissipated energy E_d (J)")
ax.legend()
fig.tight_layout()

print("largest |direct - theorem| (J):", np.max(np.abs(out.dissipated - out.dissipated_theorem)))

"""Many impacts at once: point impacts over arrays with leading batch dimensions.

One impact is the ``()`` case; every argument broadcasts against the others. The formulas
follow the single-impact solver's formulation (DESIGN.md section 1) written out for one point
contact, once, for two backends (:mod:`carnot.batch.ops`): compiled by Numba for NumPy input,
or as array code for any array-API namespace (Dask input is solved chunk by chunk by the
compiled kernel). Laws: frictionless, stick, and Coulomb friction under Newton, Poisson and
Stronge (:mod:`carnot.batch.coulomb`). The answers equal :func:`carnot.solve_impact`'s
(tested to 1e-12 times cond(K); 3D slip that turns: to the integrator's tolerance).
"""

from carnot.batch.kernels import BatchBodies, BatchImpacts, point_impacts
from carnot.batch.laws import FRICTIONLESS, REGIME_NAMES, STICK

__all__ = ["FRICTIONLESS", "REGIME_NAMES", "STICK", "BatchBodies", "BatchImpacts",
           "point_impacts"]  # fmt: skip

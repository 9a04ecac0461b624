"""Many impacts at once: array kernels with leading batch dimensions (issue #5, first part).

One impact is the ``()`` case; every argument broadcasts against the others. The kernels
follow the formulation of the single-impact solver (DESIGN.md section 1) written out for one
point contact, so that their answers equal :func:`carnot.solve_impact`'s (tested to 1e-12).
"""

from carnot.batch.kernels import BatchBodies, BatchImpacts, point_impacts

__all__ = ["BatchBodies", "BatchImpacts", "point_impacts"]

"""Systems in motion: hybrid simulation in generalized coordinates, walkers, periodic orbits
and their stability (DESIGN.md section 10, issue 34).

The layout follows the physics:

* :mod:`~carnot.hybrid.mechanism`: a planar mechanism written once in SymPy (its masses'
  positions in floating coordinates, a chart of minimal coordinates), compiled into ``M(q)``,
  ``h(q, q')``, the flow's exact linearization and the impact's floating ``M_f`` and
  Jacobians;
* :mod:`~carnot.hybrid.model` and :mod:`~carnot.hybrid.models`: guards, relabelling, the
  tangent chart of the linearizations (``x (+) dx``: an MJCF model's quaternions perturbed
  on their sphere), and the named models (compass gait, simplest walker, rimless wheel
  with the papers' parameters; a double pendulum with a stop; a hopping leg);
* :mod:`~carnot.hybrid.flow`: the flow between strikes and the guard's crossing, contacts
  held in it (sticking, sliding, released);
* :mod:`~carnot.hybrid.strike`: the strike, one :func:`carnot.solve_impact` in floating
  coordinates, read back in the new chart;
* :mod:`~carnot.hybrid.simulate`: the run, its ledger and saltation matrices;
* :mod:`~carnot.hybrid.cycle`: the return map, Newton shooting, Floquet multipliers;
* :mod:`~carnot.hybrid.section`: the section of an orbit through held contacts (the held
  manifold, its tangent space) and the symmetry it returns up to (``shift``, ``cyclic``);
* :mod:`~carnot.hybrid.mjcf`: a model from an MJCF file, moved by MuJoCo's own ``M`` and
  bias forces, its strikes built as ``carnot from-mjcf`` builds them;
* :mod:`~carnot.hybrid.scenario`, :mod:`~carnot.hybrid.output`, :mod:`~carnot.hybrid.command`:
  the ``[model]`` file, what is printed, ``carnot cycle``.
"""

from typing import Any

_LAZY = {
    "named_model": "carnot.hybrid.models",
    "MODEL_NAMES": "carnot.hybrid.models",
    "simulate": "carnot.hybrid.simulate",
    "saltation_matrix": "carnot.hybrid.simulate",
    "find_cycle": "carnot.hybrid.cycle",
    "return_map": "carnot.hybrid.cycle",
    "finite_difference_jacobian": "carnot.hybrid.cycle",
    "floquet_multipliers": "carnot.hybrid.cycle",
    "finite_difference_multipliers": "carnot.hybrid.cycle",
    "section_jacobian": "carnot.hybrid.cycle",
    "Law": "carnot.hybrid.model",
    "tangent_step": "carnot.hybrid.model",
    "tangent_difference": "carnot.hybrid.model",
    "load_model_scenario": "carnot.hybrid.scenario",
    "mjcf_model": "carnot.hybrid.mjcf",
    "parse_model_scenario": "carnot.hybrid.scenario",
}

__all__ = list(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'carnot.hybrid' has no attribute {name!r}")

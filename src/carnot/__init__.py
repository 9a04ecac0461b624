"""carnot: rigid-body impact mechanics with exact energy bookkeeping.

The theorem of *An extension of Carnot's theorem for rigid body collisions*: the kinetic
energy dissipated in an impact equals ``-1/2 sum[P . (w' + w'') + M_P . (Omega' + Omega'')]``.

The public names are bound when first read (PEP 562): ``import carnot`` loads no NumPy, so
that ``carnot --help`` costs little more than Python itself, while ``from carnot import
solve_impact`` and ``carnot.RigidBody`` work as with eager imports.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from carnot.errors import CarnotError, ConstraintConflictError, InputError
    from carnot.model import (
        Fasten,
        FixedBody,
        ImpactProblem,
        Pin,
        PointConstraint,
        PointContact,
        RigidBody,
    )
    from carnot.result import ImpactResult
    from carnot.solve import solve_impact

__version__ = "0.1.0"

#: Each public name and the module that defines it.
_WHERE = {
    "CarnotError": "errors",
    "ConstraintConflictError": "errors",
    "InputError": "errors",
    "Fasten": "model",
    "FixedBody": "model",
    "ImpactProblem": "model",
    "Pin": "model",
    "PointConstraint": "model",
    "PointContact": "model",
    "RigidBody": "model",
    "ImpactResult": "result",
    "solve_impact": "solve",
}


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use and then kept in this module;
    or a sub-module (``carnot.model`` after a bare ``import carnot``, as eager imports gave)."""
    from importlib import import_module

    if name in _WHERE:
        value = getattr(import_module(f"carnot.{_WHERE[name]}"), name)
        globals()[name] = value  # the next read is a plain attribute
        return value
    if not name.startswith("_"):
        try:
            return import_module(f"carnot.{name}")
        except ModuleNotFoundError as err:
            if err.name != f"carnot.{name}":  # a sub-module that failed to import its own
                raise
    raise AttributeError(f"module 'carnot' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_WHERE})


__all__ = [
    "CarnotError",
    "ConstraintConflictError",
    "Fasten",
    "FixedBody",
    "ImpactProblem",
    "ImpactResult",
    "InputError",
    "Pin",
    "PointConstraint",
    "PointContact",
    "RigidBody",
    "__version__",
    "solve_impact",
]

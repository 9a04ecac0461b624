"""Errors raised for bad input.

Every message names the field (for scenario files: the file and the key path), the bound
that was violated and the value received, so that a user can fix the input without reading
the source.
"""

from __future__ import annotations

from typing import Any


class CarnotError(Exception):
    """Base class of every error carnot raises on purpose."""


class InputError(CarnotError, ValueError):
    """A value that breaks a stated bound.

    >>> str(InputError("bodies.ball.mass", "must be > 0", -1.0))
    'bodies.ball.mass: must be > 0, got -1.0'
    """

    def __init__(self, field: str, problem: str, value: Any = None, *, show_value: bool = True):
        self.field = field
        self.problem = problem
        self.value = value
        self.show_value = show_value
        message = f"{field}: {problem}"
        if show_value:
            message += f", got {_show(value)}"
        super().__init__(message)


class ConstraintConflictError(InputError):
    """Contacts and constraints whose velocity requirements contradict each other."""


def _show(value: Any) -> str:
    try:
        import numpy as np

        if isinstance(value, np.ndarray):
            return repr(value.tolist())
    except ImportError:  # pragma: no cover - numpy is a dependency
        pass
    return repr(value)

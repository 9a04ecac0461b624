"""Frozen dataclasses made from their complete fields at once.

The ``__init__`` that :func:`dataclasses.dataclass` generates for a frozen class sets each
field by ``object.__setattr__``: for a result of 26 fields made at every impact of a
simulation that is a tenth of the result's cost. :class:`Record` gives such a class a public
constructor with the same outcome and none of that cost: :meth:`Record.from_fields` takes
every field ``__init__`` takes, by name and in the order of their declaration, fills the new
instance's ``__dict__`` with them (what the generated ``__init__`` leaves there) and then runs
the class's ``__post_init__``, if it has one, so that whatever the class checks or derives on
construction it still does. Anything else (a field missing, one too many, another order) is a
``TypeError``, as the generated ``__init__`` would raise.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, TypeVar

_R = TypeVar("_R", bound="Record")


class Record:
    """A base of frozen dataclasses that adds :meth:`from_fields` (module docstring).

    >>> @dataclasses.dataclass(frozen=True, kw_only=True)
    ... class Pair(Record):
    ...     left: float
    ...     right: float = 0.0
    >>> Pair.from_fields({"left": 1.0, "right": 2.0})
    Pair(left=1.0, right=2.0)
    >>> Pair.from_fields({"left": 1.0})
    Traceback (most recent call last):
    ...
    TypeError: Pair.from_fields takes every field in order: left, right; got left
    """

    __slots__ = ()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "from_fields" not in cls.__dict__:  # (each class its own: not a base's builder)
            type.__setattr__(cls, "from_fields", Record.__dict__["from_fields"])

    @classmethod
    def from_fields(cls: type[_R], values: dict[str, Any]) -> _R:
        """The instance ``cls(**values)`` would make, ``values`` naming every field that
        ``__init__`` takes, defaults included, in the order of their declaration. (The first
        call makes the class its own builder, which later calls go to directly: a
        ``staticmethod`` in the class, as the generated ``__init__`` is made for it.)"""
        builder = _builder(cls)
        type.__setattr__(cls, "from_fields", staticmethod(builder))
        return builder(values)


def _builder(cls: type[_R]) -> Callable[[dict[str, Any]], _R]:
    """:meth:`Record.from_fields` for ``cls``: its field names and ``__post_init__`` bound."""
    names = tuple(f.name for f in dataclasses.fields(cls) if f.init)  # type: ignore[arg-type]
    post_init = getattr(cls, "__post_init__", None)

    def from_fields(values: dict[str, Any], names: tuple[str, ...] = names,
                    new: Any = object.__new__, post_init: Any = post_init) -> _R:  # fmt: skip
        if tuple(values) != names:
            raise TypeError(f"{cls.__name__}.from_fields takes every field in order: "
                            f"{', '.join(names)}; got {', '.join(values)}")  # fmt: skip
        out = new(cls)
        out.__dict__.update(values)
        if post_init is not None:
            post_init(out)
        return out

    from_fields.__doc__ = Record.from_fields.__doc__
    return from_fields

__all__ = ["Record"]

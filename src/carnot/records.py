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
    #: (the class these are of, its ``__init__``'s field names in order, its __post_init__)
    _record_fields: tuple[Any, tuple[str, ...], Any] = (None, (), None)

    @classmethod
    def from_fields(cls: type[_R], values: dict[str, Any]) -> _R:
        """The instance ``cls(**values)`` would make, ``values`` naming every field that
        ``__init__`` takes, defaults included, in the order of their declaration."""
        owner, names, post_init = cls._record_fields
        if owner is not cls:  # (worked out once per class, on the first call)
            names = tuple(f.name for f in dataclasses.fields(cls)  # type: ignore[arg-type]
                          if f.init)  # fmt: skip
            post_init = getattr(cls, "__post_init__", None)
            type.__setattr__(cls, "_record_fields", (cls, names, post_init))
        if tuple(values) != names:
            raise TypeError(f"{cls.__name__}.from_fields takes every field in order: "
                            f"{', '.join(names)}; got {', '.join(values)}")  # fmt: skip
        out = object.__new__(cls)
        out.__dict__.update(values)
        if post_init is not None:
            post_init(out)
        return out

__all__ = ["Record"]

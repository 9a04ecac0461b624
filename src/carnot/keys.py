"""Cache keys made of values.

A cache of things worked out from numbers must be keyed on the numbers, not on the identity
of the object that holds them (a new object with the same numbers misses, and the cache keeps
every object it ever saw alive) nor on their raw bytes (a float and an integer array, or two
shapes, can share them). :func:`exact_key` is the key of a short sequence of floats: the
floats themselves, unrounded; and, since ``0.0 == -0.0`` (so a tuple of floats would take one
for the other) while the sign of a zero can reach an answer's bits (``-0.0`` in a rotation
matrix makes ``-0.0`` in a product), the signs of its zeros after them. A NaN read from an
array (a new float each time) equals no other, so a key holding one finds nothing, and what
it keys is worked out again: never the wrong entry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence


def exact_key(values: Sequence[float]) -> tuple[float, ...]:
    """The floats ``values`` as a hashable key: equal keys for the same floats, bit for bit
    (the sign of a zero included), and the floats themselves first (``key[:len(values)]``).
    One cache keys sequences of one length (a normal's 3, a quaternion's 4): a key of 3
    floats and zeros' signs may equal one of 4 floats.

    >>> exact_key([0.0, 1.0]) == exact_key([-0.0, 1.0])
    False
    >>> exact_key([0.5, 1.0])
    (0.5, 1.0)
    >>> exact_key([-0.0, 2.0])[:2]
    (-0.0, 2.0)
    """
    key = tuple(values)
    if 0.0 in key:  # (-0.0 too) the zeros' signs, in order, after the floats
        return key + tuple([math.copysign(1.0, x) for x in key if x == 0.0])
    return key


__all__ = ["exact_key"]

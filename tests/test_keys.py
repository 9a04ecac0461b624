"""Cache keys made of values (carnot.keys): equal keys exactly for the same floats, bit for
bit, checked against the floats' bytes (the independent route)."""

from __future__ import annotations

import struct

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from carnot.keys import exact_key

_FLOATS = st.lists(st.sampled_from([0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, -2.5]), min_size=3,
                   max_size=3)  # fmt: skip


@given(_FLOATS, _FLOATS)
def test_equal_keys_are_the_same_bits(a: list[float], b: list[float]) -> None:
    same_bits = struct.pack("3d", *a) == struct.pack("3d", *b)
    assert (exact_key(a) == exact_key(b)) == same_bits
    if same_bits:
        assert hash(exact_key(a)) == hash(exact_key(b))


@given(st.lists(st.floats(allow_nan=False), min_size=4, max_size=4))
def test_the_floats_come_first(values: list[float]) -> None:
    key = exact_key(values)
    assert [struct.pack("d", x) for x in key[:4]] == [struct.pack("d", x) for x in values]


def test_a_signed_zero_is_another_key_and_a_nan_finds_nothing() -> None:
    assert exact_key([0.0, 1.0, 0.0]) != exact_key([0.0, 1.0, -0.0])
    # (a NaN read from an array is a new float each time: never equal to another)
    nan = np.array([np.nan, 1.0, 0.0])
    assert exact_key(nan.tolist()) != exact_key(nan.tolist())

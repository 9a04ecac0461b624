"""carnot.io.json_text.dumps against the standard library's json.dumps(indent=2,
allow_nan=False): the same text for every document a result holds, and the same error (or the
same text, by handing over) for what it does not write itself."""

from __future__ import annotations

import json
import math
from collections import OrderedDict
from enum import IntEnum
from typing import Any

import numpy as np
import pytest

from carnot.io.json_text import dumps


def _reference(obj: Any) -> str:
    return json.dumps(obj, indent=2, allow_nan=False)


def _random_document(rng: np.random.Generator, depth: int = 0) -> Any:
    kind = int(rng.integers(0, 9 if depth < 4 else 6))
    if kind == 0:
        return float(rng.normal() * 10.0 ** int(rng.integers(-300, 300)))
    if kind == 1:
        return int(rng.integers(-10**9, 10**9))
    if kind == 2:
        return [None, True, False][int(rng.integers(0, 3))]
    if kind == 3:  # escapes, non-ASCII, control characters, quotes
        return "".join(rng.choice(list('ab"\\\n\t\x01é€😀 [],{}:'), size=int(rng.integers(0, 8))))
    if kind == 4:
        return -0.0 if rng.random() < 0.5 else 0.0
    if kind == 5:
        return [float(x) for x in rng.normal(size=int(rng.integers(0, 4)))]
    if kind == 6:
        return [_random_document(rng, depth + 1) for _ in range(int(rng.integers(0, 4)))]
    if kind == 7:
        return tuple(_random_document(rng, depth + 1) for _ in range(int(rng.integers(0, 3))))
    return {str(k) + "é" * (k % 2): _random_document(rng, depth + 1)
            for k in range(int(rng.integers(0, 5)))}


@pytest.mark.parametrize("seed", range(200))
def test_the_same_text_as_the_standard_library(seed: int) -> None:
    doc = _random_document(np.random.default_rng(seed))
    assert dumps(doc) == _reference(doc)


def test_a_simulation_document_is_written_the_same() -> None:
    from carnot.simulate import parse_simulation, run
    from carnot.simulate.output import to_dict, to_json

    sim = parse_simulation({
        "format": 1, "simulation": {"duration": 1.0},
        "bodies": {"die": {"mass": 0.02, "shape": "box", "size": [0.02, 0.02, 0.02],
                           "position": [0.0, 0.3, 0.0], "angular_velocity": [3.0, -2.0, 7.0]},
                   "floor": {"fixed": True, "plane": {"point": [0, 0, 0], "normal": [0, 1, 0]}}},
        "pairs": [{"a": "die", "b": "floor", "restitution": 1.0}]})  # fmt: skip
    result = run(sim)
    assert to_json(result) == _reference(to_dict(result))


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, [1.0, math.nan],
                                 {"a": {"b": [math.inf]}}])  # fmt: skip
def test_a_number_that_is_not_finite_is_the_standard_librarys_error(bad: Any) -> None:
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        dumps(bad)


class _Level(IntEnum):
    HIGH = 2


@pytest.mark.parametrize("other", [
    {3: "int key", 2.5: "float key", None: "none key", True: "bool key"},
    [_Level.HIGH, OrderedDict(a=1)],
    {"a": np.float64(1.5)},  # (a float subclass: handed over)
])  # fmt: skip
def test_what_it_does_not_write_itself_is_handed_over(other: Any) -> None:
    assert dumps(other) == _reference(other)


def test_what_json_cannot_write_is_its_error() -> None:
    with pytest.raises(TypeError, match="not JSON serializable"):
        dumps({"a": {1, 2}})

"""Indented JSON text, the same bytes as ``json.dumps(obj, indent=2, allow_nan=False)``, faster.

With ``indent`` set, the standard library encodes in Python, by generators that yield a few
characters at a time (its C encoder does only the compact form): for ``carnot simulate
--json``, whose document holds some seventy numbers per impact, that was a third of the whole
command's time. :func:`dumps` writes the same text by plain recursion over the types a result
document holds (``dict`` with ``str`` keys, ``list``, ``tuple``, ``str``, ``int``, ``float``,
``bool``, ``None``), numbers by the same ``float.__repr__`` and ``int.__repr__``, strings by
the same C escaper (``json.encoder.encode_basestring_ascii``). Anything else (another type, a
key that is not a string, a number that is not finite: the standard library's error) is
handed to ``json.dumps`` itself, whole, so the text or the error is always the standard
library's. ``tests/test_json_text.py`` holds the two to each other.
"""

from __future__ import annotations

import json
from json.encoder import encode_basestring_ascii as _string
from math import isfinite
from typing import Any

_FLOAT = float.__repr__
_INT = int.__repr__


def finite_or_none(x: float | None) -> float | None:
    """A JSON number as result format 1 writes it: ``None`` where not finite (JSON has no
    NaN), ``-0.0`` written as ``0.0``.

    >>> finite_or_none(float("nan")), finite_or_none(-0.0), finite_or_none(2)
    (None, 0.0, 2.0)
    """
    if x is None or not isfinite(x):
        return None
    return float(x) + 0.0


def finite_list(x: Any) -> list[float | None]:
    """Every entry of an array (flattened) as :func:`finite_or_none` writes it."""
    import numpy as np

    return [finite_or_none(float(v)) for v in np.asarray(x, dtype=float).ravel()]


class _Other(Exception):
    """Something :func:`_write` does not write as the standard library would: handed to it."""


def dumps(obj: Any) -> str:
    """``json.dumps(obj, indent=2, allow_nan=False)``, the same text.

    >>> dumps({"a": [1.5, None, True], "b": {}, "c": "é"}) == json.dumps(
    ...     {"a": [1.5, None, True], "b": {}, "c": "é"}, indent=2, allow_nan=False)
    True
    """
    out: list[str] = []
    try:
        _write(obj, "\n", out)
    except (_Other, RecursionError):
        return json.dumps(obj, indent=2, allow_nan=False)
    return "".join(out)


def _write(obj: Any, newline: str, out: list[str]) -> None:
    """Append the text of ``obj`` to ``out``; ``newline``: a line break and the indentation
    of the line ``obj`` starts on."""
    kind = type(obj)
    if kind is dict:
        if not obj:
            out.append("{}")
            return
        inner = newline + "  "
        sep = "{" + inner
        for key, value in obj.items():
            if type(key) is not str:
                raise _Other
            # (a finite float, the commonest value, without a call)
            text = _FLOAT(value) if type(value) is float and isfinite(value) else \
                _scalar(value)  # fmt: skip
            if text is None:
                out.append(sep + _string(key) + ": ")
                _write(value, inner, out)
            else:
                out.append(sep + _string(key) + ": " + text)
            sep = "," + inner
        out.append(newline + "}")
    elif kind is list or kind is tuple:
        if not obj:
            out.append("[]")
            return
        inner = newline + "  "
        texts = [_FLOAT(value) if type(value) is float and isfinite(value) else _scalar(value)
                 for value in obj]  # fmt: skip
        if None not in texts:  # numbers, strings: one join (a vector)
            out.append("[" + inner + ("," + inner).join(texts) + newline + "]")  # type: ignore[arg-type]
            return
        sep = "[" + inner
        for value, text in zip(obj, texts, strict=True):
            if text is None:
                out.append(sep)
                _write(value, inner, out)
            else:
                out.append(sep + text)
            sep = "," + inner
        out.append(newline + "]")
    else:
        text = _scalar(obj)
        if text is None:
            raise _Other
        out.append(text)


def _scalar(obj: Any) -> str | None:
    """The text of a number, string, boolean or ``None``; ``None`` for a container (raises
    :class:`_Other` for what the standard library would write otherwise, or refuse)."""
    kind = type(obj)
    if kind is float:
        if not isfinite(obj):
            raise _Other
        return _FLOAT(obj)
    if kind is str:
        return _string(obj)
    if obj is None:
        return "null"
    if obj is True:
        return "true"
    if obj is False:
        return "false"
    if kind is int:
        return _INT(obj)
    if kind is dict or kind is list or kind is tuple:
        return None
    raise _Other


__all__ = ["dumps"]

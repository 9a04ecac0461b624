"""Reading an input file as data: at most a stated number of bytes, as text of a stated
encoding, every failure an :class:`~carnot.errors.InputError` naming the file (what every
reader of a user's file does first: scenarios, Siconos' problems)."""

from __future__ import annotations

from pathlib import Path

from carnot.errors import InputError


def read_text(path: str | Path, limit: int, kind: str, encoding: str, what: str) -> str:
    """The text of the file ``path``: at most ``limit`` bytes (a ``kind`` file's limit), in
    ``encoding`` (``what`` names the text expected, for the error).

    >>> read_text("/nonexistent.toml", 100, "scenario", "utf-8", "UTF-8 text")
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: /nonexistent.toml: cannot read the file (No such file or directory)
    """
    source = str(path)
    try:
        with open(path, "rb") as stream:
            raw = stream.read(limit + 1)
    except OSError as err:
        raise InputError(
            source, f"cannot read the file ({err.strerror})", show_value=False
        ) from None
    if len(raw) > limit:
        raise InputError(source, f"is larger than {limit} bytes (the limit on a {kind} file)",
                         show_value=False)  # fmt: skip
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError as err:
        raise InputError(source, f"is not {what} (byte {err.start})", show_value=False) from None

"""The line on stderr while a kernel compiles (issue 35): said on a kernel's first call in the
process when it takes long, not for a compiled one, not for a quick one, not when silenced."""

from __future__ import annotations

import time

import pytest

from carnot.batch import compile_notice


class _Kernel:
    """A stand-in for a Numba dispatcher: ``signatures`` (none until its first call) and a
    first call that takes ``seconds``."""

    def __init__(self, seconds: float, signatures: tuple[str, ...] = ()):
        self.seconds = seconds
        self.signatures = signatures

    def __call__(self, x: int) -> int:
        time.sleep(self.seconds)
        self.signatures = ("(int64,)",)
        return x * 2


def test_a_long_first_call_is_announced(monkeypatch: pytest.MonkeyPatch,
                                        capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    monkeypatch.setattr(compile_notice, "NOTICE_AFTER", 0.05)
    monkeypatch.delenv("CARNOT_QUIET_COMPILE", raising=False)
    kernel = _Kernel(0.3)
    assert compile_notice.call_announcing(kernel, "the test kernel", 4) == 8
    err = capsys.readouterr().err
    assert err == ("carnot: compiling the test kernel (once: kept in Numba's cache for the "
                   "next runs)\n")  # fmt: skip
    assert compile_notice.call_announcing(kernel, "the test kernel", 1) == 2  # compiled now
    assert capsys.readouterr().err == ""


CASES = [(0.0, (), False), (0.3, ("(int64,)",), False), (0.3, (), True)]


@pytest.mark.parametrize(("seconds", "signatures", "quiet"), CASES)
def test_nothing_said_otherwise(seconds: float, signatures: tuple[str, ...], quiet: bool,
                                monkeypatch: pytest.MonkeyPatch,
                                capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    monkeypatch.setattr(compile_notice, "NOTICE_AFTER", 0.05)
    if quiet:
        monkeypatch.setenv("CARNOT_QUIET_COMPILE", "1")
    else:
        monkeypatch.delenv("CARNOT_QUIET_COMPILE", raising=False)
    compile_notice.call_announcing(_Kernel(seconds, signatures), "the test kernel", 1)
    time.sleep(0.1)  # (a timer left running would print now)
    assert capsys.readouterr().err == ""

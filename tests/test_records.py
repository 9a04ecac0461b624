"""Frozen dataclasses from their complete fields (carnot.records.Record.from_fields): the
same instance as the generated ``__init__`` makes, ``__post_init__`` included."""

from __future__ import annotations

import dataclasses

import pytest

from carnot.records import Record
from carnot.result import Flag, ImpactResult, MomentumCheck


@dataclasses.dataclass(frozen=True, kw_only=True)
class _Checked(Record):
    mass: float
    doubled: float = dataclasses.field(init=False)

    def __post_init__(self) -> None:
        if self.mass <= 0:
            raise ValueError("mass must be positive")
        object.__setattr__(self, "doubled", 2 * self.mass)


def test_the_same_instance_as_init() -> None:
    fields = {"code": "c", "where": "w", "message": "m"}
    fast, slow = Flag.from_fields(fields), Flag(**fields)
    assert vars(fast) == vars(slow) and list(vars(fast)) == list(vars(slow))
    assert vars(_Checked.from_fields({"mass": 2.0})) == vars(_Checked(mass=2.0))


def test_post_init_checks_still_run() -> None:
    with pytest.raises(ValueError, match="mass must be positive"):
        _Checked.from_fields({"mass": -1.0})


@pytest.mark.parametrize("fields", [
    {"code": "c", "where": "w"}, {"where": "w", "code": "c", "message": "m"},
    {"code": "c", "where": "w", "message": "m", "x": 1}])  # fmt: skip
def test_every_field_in_order_or_a_type_error(fields) -> None:
    with pytest.raises(TypeError, match="every field in order"):
        Flag.from_fields(fields)


def test_a_later_momentum_is_made_when_read() -> None:
    check = MomentumCheck(linear_change=None, linear_external=None, angular_change=None,
                          angular_external=None, linear_residual=0.0, angular_residual=0.0)
    names = [f.name for f in dataclasses.fields(ImpactResult)]
    values = dict.fromkeys(names)
    values.update(title="t", bodies={}, contacts=(), constraints=(), warnings=(), stages=(),
                  alternatives=(), solver_groups=(), momentum_later=lambda: check)
    result = ImpactResult.from_fields(values)
    assert "momentum" not in vars(result)  # (as ImpactResult.__post_init__ leaves it)
    assert result.momentum is check


def test_a_subclass_builds_its_own() -> None:
    @dataclasses.dataclass(frozen=True, kw_only=True)
    class More(_Checked):
        extra: int = 0

    _Checked.from_fields({"mass": 1.0})  # (the base's builder made first)
    more = More.from_fields({"mass": 1.0, "extra": 3})
    assert type(more) is More and more.extra == 3 and more.doubled == 2.0

"""Jacobian rows of contacts and constraints."""

from __future__ import annotations

import numpy as np
import pytest

from carnot.errors import InputError
from carnot.model.contacts import Fasten, Pin, PointContact


def _contact(**kw) -> PointContact:
    return PointContact(**{"a": "a", "b": "b", "point": [0, 0, 0], "normal": [0, 0, 1], **kw})


@pytest.mark.parametrize(
    "kwargs, rows",
    [
        ({}, 1),
        ({"tangential": "stick"}, 3),
        ({"patch": [[0, 0, 0]]}, 1),
        ({"patch": [[1, 0, 0], [-1, 0, 0]]}, 2),
        ({"patch": [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]]}, 3),
        ({"patch": [[1, 0, 0], [-1, 0, 0], [0, 1, 0]], "tangential": "stick"}, 6),
        ({"impulse": [0, 0, 1]}, 6),
    ],
)
def test_row_counts(kwargs, rows) -> None:
    assert _contact(**kwargs).rows().size == rows


def test_fasten_and_pin_have_three_rows() -> None:
    assert Fasten(body="a", point=[0, 0, 0]).rows().size == 3
    assert Pin(body="a", point=[0, 0, 0], other="b").rows().size == 3


def test_patch_rows_are_the_normal_velocities_of_its_points() -> None:
    """Each patch point's normal velocity n . (w + Omega x r_k) lies in the span of the rows."""
    patch = np.array([[0.3, 0.1, 0.0], [-0.2, 0.4, 0.0], [0.1, -0.5, 0.0]])
    block = _contact(patch=patch).rows()
    rows = np.hstack([block.linear, block.angular])
    for r in patch:
        functional = np.concatenate([[0, 0, 1], np.cross(r, [0, 0, 1])])
        coef, *_ = np.linalg.lstsq(rows.T, functional, rcond=None)
        assert np.allclose(rows.T @ coef, functional)


def test_patch_off_the_contact_plane_is_refused() -> None:
    with pytest.raises(InputError, match=r"contacts\[0\]\.patch\[1\]: must lie in the contact"):
        _contact(patch=[[1, 0, 0], [0, 1, 0.1]])


def test_moment_needs_an_impulse() -> None:
    with pytest.raises(InputError, match="moment: needs an impulse"):
        _contact(moment=[0, 0, 1])

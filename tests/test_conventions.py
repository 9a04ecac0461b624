"""The contact frame rule of conventions.py."""

from __future__ import annotations

import numpy as np
import pytest

from carnot.conventions import contact_frame


@pytest.mark.parametrize("normal", [[0, 0, 1], [1, 0, 0], [0, -1, 0], [1, 2, 3], [-0.3, 0.1, 5]])
def test_frame_is_orthonormal_and_right_handed(normal) -> None:
    n, t1, t2 = contact_frame(np.array(normal, dtype=float))
    frame = np.column_stack([n, t1, t2])
    assert np.allclose(frame.T @ frame, np.eye(3), atol=1e-15)
    assert np.linalg.det(frame) == pytest.approx(1.0)
    assert np.allclose(np.cross(n, t1), t2)


def test_t1_is_the_least_aligned_axis_projected() -> None:
    n, t1, _ = contact_frame(np.array([0.0, 0.6, 0.8]))
    assert np.allclose(t1, [1.0, 0.0, 0.0])  # x is the axis least aligned with n
    n, t1, _ = contact_frame(np.array([0.8, 0.0, 0.6]))
    assert np.allclose(t1, [0.0, 1.0, 0.0])
    # A tie (x and y equally unaligned) takes the first.
    _, t1, _ = contact_frame(np.array([0.0, 0.0, 1.0]))
    assert np.allclose(t1, [1.0, 0.0, 0.0])

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


def test_the_batch_kernel_compiles_the_same_frame_rule() -> None:
    """One statement of the frame: the multi-contact batch kernel's ``frame`` is
    :func:`carnot.conventions.contact_frame_into` compiled by Numba, and gives the bits that
    ``solve_impact``'s Python call of it gives, on normals of every direction and length,
    ties included; and the rule is the one the module states (the least aligned world axis
    projected, ``t2 = n x t1``), checked apart from it with NumPy."""
    from carnot.batch import multi_kernel

    rng = np.random.default_rng(33)
    normals = [*rng.normal(size=(200, 3)) * rng.uniform(1e-3, 1e3, (200, 1)),
               [0.0, 0.0, 1.0], [1.0, 1.0, 0.0], [0.0, -1.0, -1.0], [2.0, 2.0, 2.0]]  # fmt: skip
    compiled = np.empty((3, 3))
    for normal in np.asarray(normals):
        n, t1, t2 = contact_frame(normal)
        multi_kernel.frame(normal, compiled)
        assert compiled.tobytes() == np.array([n, t1, t2]).tobytes()
        unit = normal / np.linalg.norm(normal)
        axis = np.eye(3)[np.argmin(np.abs(unit))]
        projected = axis - (axis @ unit) * unit
        assert np.allclose(n, unit, atol=1e-15)
        assert np.allclose(t1, projected / np.linalg.norm(projected), atol=1e-15)
        assert np.allclose(t2, np.cross(unit, t1), atol=1e-15)

"""Shape helpers against the standard table of moments of inertia (Meriam & Kraige,
*Engineering Mechanics: Dynamics*, Appendix B), rotations, and Huygens-Steiner."""

from __future__ import annotations

import numpy as np
import pytest

from carnot.errors import InputError
from carnot.model import inertia


def test_table() -> None:
    m = 3.0
    assert np.allclose(inertia.solid_sphere(m, 0.2), np.eye(3) * 0.4 * m * 0.04)
    assert np.allclose(inertia.hollow_sphere(m, 0.2), np.eye(3) * 2 / 3 * m * 0.04)
    assert np.allclose(np.diag(inertia.solid_cylinder(m, 0.2, 1.0)),
                       [m * (3 * 0.04 + 1) / 12] * 2 + [m * 0.04 / 2])  # fmt: skip
    assert np.allclose(np.diag(inertia.hollow_cylinder(m, 0.2, 1.0)),
                       [m * (6 * 0.04 + 1) / 12] * 2 + [m * 0.04])  # fmt: skip
    assert np.allclose(np.diag(inertia.hollow_cylinder(m, 0.2, 1.0, inner_radius=0.1)),
                       [m * (3 * 0.05 + 1) / 12] * 2 + [m * 0.05 / 2])  # fmt: skip
    assert np.allclose(np.diag(inertia.box(m, [1.0, 2.0, 3.0])),
                       np.array([4 + 9, 1 + 9, 1 + 4]) * m / 12)  # fmt: skip
    assert np.allclose(np.diag(inertia.rod(m, 2.0, 0.01, axis=[0, 0, 1])),
                       [m * 4 / 12, m * 4 / 12, m * 1e-4 / 2])  # fmt: skip
    assert np.allclose(np.diag(inertia.disc(m, 0.5)), [m * 0.25 / 4] * 2 + [m * 0.25 / 2])
    assert np.allclose(np.diag(inertia.plate(m, [1.0, 2.0])), np.array([4, 1, 5]) * m / 12)


def test_axis_and_orientation_rotate_the_tensor() -> None:
    along_x = inertia.solid_cylinder(2.0, 0.1, 1.0, axis=[3.0, 0, 0])
    assert along_x[0, 0] == pytest.approx(2.0 * 0.01 / 2)
    tilted = inertia.solid_cylinder(2.0, 0.1, 1.0, axis=[1.0, 1.0, 0.0])
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    assert axis @ tilted @ axis == pytest.approx(2.0 * 0.01 / 2)
    assert np.trace(tilted) == pytest.approx(np.trace(along_x))
    quarter = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    turned = inertia.box(1.0, [1.0, 2.0, 3.0], orientation=quarter)
    assert np.allclose(np.diag(turned), np.array([1 + 9, 4 + 9, 1 + 4]) / 12)


def test_parallel_axis_rod_about_its_end() -> None:
    """A slender rod about its end: m L^2/3."""
    m, length = 2.0, 1.5
    j_c = inertia.rod(m, length, 1e-3, axis=[1, 0, 0])
    j_end = inertia.parallel_axis(j_c, m, [length / 2, 0, 0])
    assert j_end[1, 1] == pytest.approx(m * length**2 / 3)
    assert j_end[0, 0] == pytest.approx(j_c[0, 0])


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda: inertia.solid_sphere(-1.0, 0.1), "mass"),
        (lambda: inertia.solid_sphere(1.0, 0.0), "radius"),
        (lambda: inertia.hollow_cylinder(1.0, 0.1, 1.0, inner_radius=0.2), "inner_radius"),
        (lambda: inertia.box(1.0, [1.0, 2.0]), "size"),
        (lambda: inertia.box(1.0, [1.0, 1.0, 1.0], orientation=np.eye(3) * 2), "orientation"),
    ],
)
def test_bad_dimensions(call, field) -> None:
    with pytest.raises(InputError) as err:
        call()
    assert err.value.field == field

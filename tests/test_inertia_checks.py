"""The batch kernels' inertia check: one statement (``carnot.batch.rigid.factor``), which the
one-contact formulas run (here on NumPy arrays) and the multi-contact kernel's
``inverse_inertia`` compiles (it adds only the adjugate's determinant being positive and
finite): symmetric, positive definite and realizable (each principal moment at most the sum
of the other two), with the same slack. Both runs checked against a third route, the
principal moments from NumPy's ``eigvalsh``, on tensors rotated at random, away from the
boundary by 1e-6 relative, and on the boundary itself (a thin plate, ``J_3 = J_1 + J_2``,
which every flat body reaches)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from carnot.batch import multi_kernel, rigid


def _tensor(moments: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    return rotation @ np.diag(moments) @ rotation.T


def _by_eigenvalues(j: np.ndarray) -> bool:
    moments = np.linalg.eigvalsh(0.5 * (j + j.T))
    # (round-off of the rotation and of eigvalsh: far below the 1e-6 margins of the cases)
    slack = 1e-9 * float(np.sum(moments))
    return bool(moments[0] > 0 and moments[2] <= moments[0] + moments[1] + slack)


def test_the_two_compiled_inertia_checks_agree_with_the_principal_moments() -> None:
    rng = np.random.default_rng(14)
    rotations = Rotation.random(300, random_state=rng).as_matrix()
    cases = []
    for rotation in rotations:
        a, b = rng.uniform(0.1, 10.0, 2)
        for third, margin in ((a + b, 0.0), (a + b, -1e-6), (a + b, 1e-6),
                              (rng.uniform(abs(a - b), a + b), 0.0), (-0.5 * a, 0.0)):
            c = third * (1.0 + margin) if third > 0 else third
            cases.append(_tensor(np.array([a, b, c]), rotation))
    cases.append(np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]))  # asymmetric
    inv = np.empty((3, 3))
    seen = set()
    for j in cases:
        compiled = bool(multi_kernel.inverse_inertia(np.ascontiguousarray(j), inv))
        _, formula = rigid.factor(tuple(np.array([x]) for x in j.ravel()))
        expected = _by_eigenvalues(j) and np.allclose(j, j.T, rtol=0, atol=1e-12)
        assert compiled == bool(formula[0]) == expected, j
        if compiled:
            assert np.allclose(inv @ j, np.eye(3), atol=1e-10)
        seen.add(compiled)
    assert seen == {True, False}

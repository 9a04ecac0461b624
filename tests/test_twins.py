"""The twin implementations that remain (scalar NumPy for one impact, formula modules compiled
for batches) held together: one source for each rule where the idiom allows, a test where it
does not (issue 13).

- the contact frame rule: ``carnot.conventions.contact_frame`` vs ``carnot.batch.contact_space
  .frame``, including the ties of the rule (equal smallest components);
- Newton's target and sticking: the single-impact equality law (``carnot.laws.EQUALITY`` on
  ``(G, w')``) vs the batch laws ``frictionless`` and ``stick`` on the same ``K`` and ``w'``;
- the law choice: ``carnot.laws.contact_rule`` decides for both (batch's ``_law`` reads it).
"""

from __future__ import annotations

import numpy as np
import pytest

from carnot.batch import contact_space as batch_space
from carnot.batch import kernels
from carnot.batch import laws as batch_laws
from carnot.conventions import contact_frame
from carnot.laws import EQUALITY, LawParams, contact_rule

TIES = [[1.0, 1.0, 0.0], [1.0, 1.0, 1.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [-2.0, 0.0, 2.0],
        [1.0, -1.0, 1.0], [3.0, 4.0, 4.0]]  # fmt: skip


@pytest.mark.parametrize("normal", TIES + np.random.default_rng(3).normal(size=(40, 3)).tolist())
def test_the_contact_frame_rule_is_one_rule(normal: list[float]) -> None:
    n, t1, t2 = contact_frame(np.array(normal))
    bn, bt1, bt2 = batch_space.frame(np.array(normal))
    np.testing.assert_allclose(np.array(bn, dtype=float), n, rtol=0, atol=4e-16)
    np.testing.assert_allclose(np.array(bt1, dtype=float), t1, rtol=0, atol=4e-16)
    np.testing.assert_allclose(np.array(bt2, dtype=float), t2, rtol=0, atol=4e-16)


def _spd(rng: np.random.Generator) -> np.ndarray:
    a = rng.normal(size=(3, 3))
    return a @ a.T + 0.5 * np.eye(3)


@pytest.mark.parametrize("seed", range(10))
def test_newton_and_stick_are_one_rule(seed: int) -> None:
    rng = np.random.default_rng(seed)
    k = _spd(rng)
    w = rng.normal(size=3)
    w[0] = -abs(w[0])
    e = float(rng.uniform(0, 1))
    packed = (k[0, 0], k[0, 1], k[0, 2], k[1, 1], k[1, 2], k[2, 2])
    frictionless = EQUALITY.resolve(k[:1, :1], w[:1], LawParams(roles=("normal",), restitution=e))
    batch_free = batch_laws.frictionless(packed, tuple(w), e, 0.0)
    assert float(batch_free[0]) == pytest.approx(frictionless.impulses[0], rel=1e-14)
    stick = EQUALITY.resolve(k, w, LawParams(roles=("normal", "tangent", "tangent"),
                                             restitution=e))  # fmt: skip
    batch_stick = batch_laws.stick(packed, tuple(w), e, 0.0)
    np.testing.assert_allclose(np.array(batch_stick[:3], dtype=float), stick.impulses,
                               rtol=1e-12, atol=1e-12 * np.abs(stick.impulses).max())  # fmt: skip
    # both end where Newton's rule says: w'' = (-e w_n, 0, 0)
    np.testing.assert_allclose(w + k @ stick.impulses, [-e * w[0], 0, 0], atol=1e-12)


@pytest.mark.parametrize(("tangential", "friction", "rule", "key"), [
    ("slip", 0.0, "frictionless", "frictionless"),
    ("slip", 0.4, "coulomb", "coulomb_poisson"),
    ("stick", 0.4, "stick", "stick"),
    ("slip", np.array([0.0, 0.0]), "frictionless", "frictionless"),
    ("slip", np.array([0.0, 0.2]), "coulomb", "coulomb_poisson"),
])  # fmt: skip
def test_the_law_choice_is_made_once(tangential: str, friction: object, rule: str,
                                     key: str) -> None:  # fmt: skip
    assert contact_rule(tangential=tangential, friction=friction) == rule
    assert kernels._law(tangential, "poisson", friction) == key

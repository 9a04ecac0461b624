"""Impact maps in closed form from SymPy mechanics models (carnot.symbolic.generalized): the
compass gait's heel strike against Goswami, Thuilot and Espiau's closed-form transition
(INRIA research report 2996, 1996; see tests/test_walkers.py for the matrices), exactly at
rational points of the unit circle with the masses, lengths and rates left as symbols, and
against carnot's numeric solve."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from test_walkers import STATES, compass_gait, goswami_transition

from carnot import solve_impact
from carnot.symbolic.generalized import compass_gait_model, derive_impact_map


@pytest.fixture(scope="module")
def heel_strike():
    method, contact, symbols = compass_gait_model()
    return derive_impact_map(method, [contact], simplify=False), symbols


def test_heel_strike_map_is_goswamis_exactly(heel_strike) -> None:
    out, s = heel_strike
    m, mh, a, b = s["m"], s["m_H"], s["a"], s["b"]
    ll = a + b
    rate_ns, rate_s = sp.symbols("rate_ns rate_s")
    # a rational point of the circle for each leg: exact arithmetic, no trigonometry to simplify
    sin_ns, cos_ns, sin_s, cos_s = (
        -sp.Rational(3, 5),
        sp.Rational(4, 5),
        sp.Rational(5, 13),
        sp.Rational(12, 13),
    )
    trig = {
        sp.sin(s["theta_ns"]): sin_ns,
        sp.cos(s["theta_ns"]): cos_ns,
        sp.sin(s["theta_s"]): sin_s,
        sp.cos(s["theta_s"]): cos_s,
    }
    before = sp.Matrix(
        [-ll * rate_s * cos_s, -ll * rate_s * sin_s, rate_ns, rate_s]
    )  # foot at rest
    after = out.matrix.xreplace(trig) * before
    c = cos_ns * cos_s + sin_ns * sin_s  # cos 2 alpha
    q_minus = sp.Matrix(
        [[-m * a * b, -m * a * b + (mh * ll**2 + 2 * m * a * ll) * c], [0, -m * a * b]]
    )
    q_plus = sp.Matrix(
        [
            [m * b * (b - ll * c), m * ll * (ll - b * c) + m * a**2 + mh * ll**2],
            [m * b**2, -m * b * ll * c],
        ]
    )
    residual = q_plus * sp.Matrix([after[3], after[2]]) - q_minus * sp.Matrix([rate_ns, rate_s])
    assert [sp.cancel(r) for r in residual] == [0, 0]


def test_heel_strike_map_matches_the_numeric_solve(heel_strike) -> None:
    out, s = heel_strike
    for theta_ns, theta_s, rate_ns, rate_s in STATES:
        values = {
            s["m"]: 5.0,
            s["m_H"]: 10.0,
            s["a"]: 0.5,
            s["b"]: 0.5,
            s["theta_ns"]: theta_ns,
            s["theta_s"]: theta_s,
        }
        matrix = np.array(out.matrix.xreplace(values).evalf(), dtype=float)
        numeric = solve_impact(compass_gait(theta_ns, theta_s, rate_ns, rate_s))
        before = numeric.system.velocity_before
        assert np.allclose(matrix @ before, numeric.system.velocity_after, rtol=1e-12, atol=1e-14)
        expected = goswami_transition(theta_ns, theta_s, np.array([rate_ns, rate_s]))
        assert np.allclose((matrix @ before)[[3, 2]], expected, rtol=1e-12, atol=0)
        speeds = dict(zip(out.speeds, before.tolist(), strict=True))
        # the speeds first: they contain the angles (theta'(t) = Derivative(theta(t), t))
        dissipated = float(out.dissipated.xreplace(speeds).xreplace(values))
        theorem = float(out.dissipated_theorem.xreplace(speeds).xreplace(values))
        assert dissipated == pytest.approx(numeric.energy.dissipated, rel=1e-11)
        assert theorem == pytest.approx(dissipated, rel=1e-11)
        assert math.isfinite(dissipated) and dissipated > 0

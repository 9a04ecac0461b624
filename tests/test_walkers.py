"""Walkers and classics in generalized coordinates, against their published closed forms.

* **Compass gait heel strike**: Goswami, Thuilot and Espiau, *Compass-like biped robot, Part I:
  stability and bifurcation of passive gaits*, INRIA research report 2996 (1996), and
  Int. J. Robotics Research 17 (1998): legs of length ``l = a + b`` with a point mass ``m`` at
  ``a`` from the foot, hip mass ``m_H``; their nominal walker ``m = 5 kg``, ``m_H = 10 kg``,
  ``a = b = 0.5 m``. The transition (conservation of the whole walker's angular momentum about
  the new stance foot and of the trailing leg's about the hip) is
  ``Q+(alpha) theta'+ = Q-(alpha) theta'-`` with ``theta = (theta_ns, theta_s)``, ``alpha``
  the half inter-leg angle and

      Q- = [[-m a b, -m a b + (m_H l^2 + 2 m a l) cos 2 alpha], [0, -m a b]],
      Q+ = [[m b (b - l cos 2 alpha), m l (l - b cos 2 alpha) + m a^2 + m_H l^2],
            [m b^2, -m b l cos 2 alpha]],

  the legs swapping roles (``theta'+`` is in the new labelling). carnot solves the heel strike
  as a sticking, plastic contact of the swing foot in the walker's floating coordinates (hip
  position and the two leg angles), the trailing foot free.
* **Rimless wheel**: McGeer, *Passive dynamic walking*, Int. J. Robotics Research 9 (1990): a
  wheel of mass ``m`` and inertia ``I`` about its hub, spokes of length ``l`` at ``2 alpha``
  from each other; the new spoke's foot sticks and the old one leaves:
  ``omega+ / omega- = (I + m l^2 cos 2 alpha) / (I + m l^2)``, ``cos 2 alpha`` for a point-mass
  hub (the spoke then pushes only along itself).
* **Kane and Levinson's double pendulum** (Kane and Levinson, *Dynamics: Theory and
  Applications*, McGraw-Hill 1985; Stronge, Proc. R. Soc. Lond. A 431, 1990): a double
  pendulum striking a rough floor; Newton's kinematic restitution with Coulomb friction can
  return more kinetic energy than there was, Stronge's energetic restitution (the impact
  integrated in impulse space, Darboux and Keller) never does. In joint angles, as for free
  bodies (tests/test_friction.py), carnot flags the gain.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from chains import Chain

from carnot import solve_impact
from carnot.io.scenario import load_problem
from carnot.model.system import System, SystemContact, SystemProblem

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "systems"

# Goswami et al.'s nominal walker
M_LEG, M_HIP, A, B = 5.0, 10.0, 0.5, 0.5
L = A + B


def compass_gait(theta_ns: float, theta_s: float, rate_ns: float, rate_s: float) -> SystemProblem:
    """The walker at heel strike in coordinates (x_hip, y_hip, theta_ns, theta_s): angles from
    the downward vertical, a leg at ``theta`` runs from the hip along ``(sin t, -cos t)``; the
    stance foot is at rest before the impact (the hip's velocity follows from ``rate_s``)."""

    def leg(theta: float, d: float) -> np.ndarray:  # the point at d from the hip, 3 x 4
        jac = np.zeros((3, 4))
        jac[:2, :2] = np.eye(2)
        jac[:2, 2 if leg_is_ns(theta) else 3] = d * np.array([math.cos(theta), math.sin(theta)])
        return jac

    def leg_is_ns(theta: float) -> bool:
        return theta == theta_ns

    hip = np.zeros((3, 4))
    hip[:2, :2] = np.eye(2)
    mass = M_HIP * hip.T @ hip
    for theta in (theta_ns, theta_s):
        j = leg(theta, B)
        mass += M_LEG * j.T @ j
    stance_foot = leg(theta_s, L)
    hip_rate = -L * rate_s * np.array([math.cos(theta_s), math.sin(theta_s)])
    velocity = np.array([*hip_rate, rate_ns, rate_s])
    assert np.linalg.norm(stance_foot @ velocity) < 1e-15
    foot = leg(theta_ns, L)
    point = np.array([L * math.sin(theta_ns), -L * math.cos(theta_ns), 0.0])
    return SystemProblem(
        title="Compass gait heel strike (Goswami, Thuilot and Espiau 1996)",
        system=System(
            mass_matrix=mass,
            velocity=velocity,
            coordinates=("x_hip", "y_hip", "theta_ns", "theta_s"),
        ),
        contacts=[
            SystemContact(
                jacobian=foot,
                normal=[0, 1, 0],
                point=point,
                restitution=0.0,
                tangential="stick",
                name="swing_foot",
            )
        ],
    )


def goswami_transition(theta_ns: float, theta_s: float, rates: np.ndarray) -> np.ndarray:
    """Goswami et al.'s closed-form transition: ``theta'+ = Q+^-1 Q- theta'-``."""
    c = math.cos(theta_ns - theta_s)  # cos 2 alpha
    m, mh, a, b, ll = M_LEG, M_HIP, A, B, L
    q_minus = np.array([[-m * a * b, -m * a * b + (mh * ll**2 + 2 * m * a * ll) * c],
                        [0.0, -m * a * b]])  # fmt: skip
    q_plus = np.array([[m * b * (b - ll * c), m * ll * (ll - b * c) + m * a**2 + mh * ll**2],
                       [m * b**2, -m * b * ll * c]])  # fmt: skip
    return np.linalg.solve(q_plus, q_minus @ rates)


def reduced_energy(theta_ns: float, theta_s: float, rates: np.ndarray) -> float:
    """``1/2 theta'^T M(theta) theta'`` of the walker on its stance foot (Goswami et al.)."""
    c = math.cos(theta_ns - theta_s)
    mass = np.array([[M_LEG * B**2, -M_LEG * L * B * c],
                     [-M_LEG * L * B * c, (M_HIP + M_LEG) * L**2 + M_LEG * A**2]])  # fmt: skip
    return float(0.5 * rates @ mass @ rates)


#: States at heel strike (theta_ns, theta_s, rate_ns, rate_s), rad and rad/s, the walker
#: walking towards -x (the swing foot ahead at theta_ns < 0, the hip moving forward and down):
#: near the period-one gait of Goswami et al.'s walker on a 3 degree slope, and a wider step.
STATES = [(-0.32, 0.22, 0.38, 1.09), (-0.45, 0.35, -0.2, 1.3)]


@pytest.mark.parametrize("state", STATES)
def test_compass_gait_heel_strike_is_goswamis_map(state: tuple[float, ...]) -> None:
    theta_ns, theta_s, rate_ns, rate_s = state
    r = solve_impact(compass_gait(*state))
    after = r.system.velocity_after
    # the old swing leg is the new stance leg: Goswami's (theta'_ns+, theta'_s+)
    expected = goswami_transition(theta_ns, theta_s, np.array([rate_ns, rate_s]))
    assert np.allclose([after[3], after[2]], expected, rtol=1e-12, atol=0)
    before_e = reduced_energy(theta_ns, theta_s, np.array([rate_ns, rate_s]))
    after_e = reduced_energy(theta_s, theta_ns, expected)  # relabelled: cos 2 alpha is even
    assert r.energy.before == pytest.approx(before_e, rel=1e-13)
    assert r.energy.after == pytest.approx(after_e, rel=1e-12)
    assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, rel=1e-12)
    assert r.contacts[0].normal_impulse > 0 and r.warnings == ()
    # the trailing foot leaves the ground: its velocity after points up
    trailing = np.array([[1.0, 0, 0, L * math.cos(theta_s)], [0, 1.0, 0, L * math.sin(theta_s)]])
    assert (trailing @ after)[1] > 0


def rimless_wheel(alpha: float, rate: float, inertia: float, mass: float = 2.0,
                  length: float = 0.8) -> SystemProblem:  # fmt: skip
    """The wheel in (x_hub, y_hub, phi) rolling over its old foot at the origin with angular
    velocity ``rate`` (clockwise < 0: moving to +x), its next spoke meeting the ground at
    ``2 alpha`` ahead; with ``inertia = 0`` the hub is a point mass in (x_hub, y_hub) and the
    new spoke (massless, pinned at its foot) pushes along itself only."""
    hub = length * np.array([math.sin(alpha), math.cos(alpha), 0.0])  # ahead of the old foot
    new_foot = hub + length * np.array([math.sin(alpha), -math.cos(alpha), 0.0])
    spoke = (hub - new_foot) / length  # from the new foot to the hub
    omega = np.array([0.0, 0.0, rate])
    v_hub = np.cross(omega, hub)  # about the old foot at the origin
    if inertia == 0.0:
        return SystemProblem(
            system=System(
                mass_matrix=np.eye(2) * mass, velocity=v_hub[:2], coordinates=("x_hub", "y_hub")
            ),  # fmt: skip
            contacts=[
                SystemContact(
                    jacobian=[[1, 0], [0, 1], [0, 0]],
                    normal=spoke,
                    point=hub,
                    restitution=0.0,
                    name="new_spoke",
                )
            ],  # fmt: skip
        )
    r_foot = new_foot - hub
    jac = np.array([[1.0, 0, -r_foot[1]], [0, 1.0, r_foot[0]], [0, 0, 0]])  # v + omega x r
    return SystemProblem(
        system=System(
            mass_matrix=np.diag([mass, mass, inertia]),
            velocity=[*v_hub[:2], rate],
            coordinates=("x_hub", "y_hub", "phi"),
        ),  # fmt: skip
        contacts=[
            SystemContact(
                jacobian=jac,
                normal=[0, 1, 0],
                point=new_foot,
                restitution=0.0,
                tangential="stick",
                name="new_foot",
            )
        ],  # fmt: skip
    )


@pytest.mark.parametrize("alpha", [math.pi / 10, math.pi / 6, 0.4])
@pytest.mark.parametrize("inertia", [0.0, 0.05, 0.4])
def test_rimless_wheel_velocity_ratio(alpha: float, inertia: float) -> None:
    mass, length, rate = 2.0, 0.8, -1.7
    r = solve_impact(rimless_wheel(alpha, rate, inertia, mass, length))
    after = r.system.velocity_after
    hub = length * np.array([math.sin(alpha), math.cos(alpha)])
    lever = hub - np.array([2 * length * math.sin(alpha), 0.0])  # from the new foot
    # the hub moves at right angles to the new spoke: omega+ = (r x v) / l^2
    omega_after = (lever[0] * after[1] - lever[1] * after[0]) / length**2
    ratio = (inertia + mass * length**2 * math.cos(2 * alpha)) / (inertia + mass * length**2)
    assert omega_after / rate == pytest.approx(ratio, rel=1e-13)
    if inertia:
        assert after[2] == pytest.approx(omega_after, rel=1e-13)
    e_before = 0.5 * (inertia + mass * length**2) * rate**2
    assert r.energy.before == pytest.approx(e_before, rel=1e-14)
    assert r.energy.dissipated == pytest.approx(e_before * (1 - ratio**2), rel=1e-12)
    assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, rel=1e-12)
    assert r.warnings == ()


def kane_levinson(law: str) -> SystemProblem:
    """A double pendulum of two uniform bars (1 kg and 0.8 kg; 1 m and 0.7 m) in its joint
    angles, the tip striking a rough floor (e = 1, mu = 0.8) while sliding."""
    chain = Chain(masses=[1.0, 0.8], lengths=[1.0, 0.7],
                  angles=[math.radians(-80), math.radians(-60)], rates=[-1.0, -2.5])  # fmt: skip
    return SystemProblem(
        system=System(
            mass_matrix=chain.mass_matrix(), velocity=chain.velocity, coordinates=chain.coordinates
        ),  # fmt: skip
        contacts=[
            SystemContact(
                jacobian=chain.jacobian(1, 0.7),
                normal=[0, 1, 0],
                point=chain.point(1, 0.7),
                restitution=1.0,
                friction=0.8,
                law=law,
                name="tip",
            )
        ],  # fmt: skip
    )


def test_kane_levinson_double_pendulum_gains_energy_under_newton_only() -> None:
    newton = solve_impact(kane_levinson("newton"))
    assert newton.contacts[0].regime == "slip-stick"
    assert newton.energy.after > newton.energy.before  # the direct route
    assert newton.energy.dissipated == pytest.approx(newton.energy.dissipated_theorem, rel=1e-12)
    flags = {w.code: w for w in newton.warnings}
    assert "energy_gain" in flags and "Newton" in flags["energy_gain"].message
    stronge = solve_impact(kane_levinson("stronge"))
    assert stronge.energy.dissipated > 0 and stronge.warnings == ()
    poisson = solve_impact(kane_levinson("poisson"))
    assert poisson.energy.dissipated > 0


# ------------------------------------------------------------------------ examples/systems


def _same_problem(a: SystemProblem, b: SystemProblem) -> None:
    assert np.allclose(a.system.mass_matrix, b.system.mass_matrix, rtol=1e-15, atol=1e-15)
    assert np.allclose(a.system.velocity, b.system.velocity, rtol=1e-15, atol=1e-15)
    for c, d in zip(a.contacts, b.contacts, strict=True):
        assert np.allclose(c.jacobian, d.jacobian, rtol=1e-15, atol=1e-15)
        assert np.allclose(c.contact.normal, d.contact.normal, rtol=1e-15, atol=1e-15)


EXAMPLE_FILES = {
    "compass_gait.toml": lambda: compass_gait(*STATES[0]),
    "rimless_wheel.toml": lambda: rimless_wheel(math.pi / 6, -1.7, 0.05),
    "kane_levinson_double_pendulum.toml": lambda: kane_levinson("stronge"),
}


@pytest.mark.parametrize("name", EXAMPLE_FILES)
def test_examples_hold_the_tested_systems(name: str) -> None:
    """Each file in examples/systems/ is the problem a test above checks against its
    published closed form (the files were written by carnot.io.system_scenario from them)."""
    problem = load_problem(EXAMPLES / name)
    assert isinstance(problem, SystemProblem)
    _same_problem(problem, EXAMPLE_FILES[name]())
    r = solve_impact(problem)
    assert r.energy.dissipated == pytest.approx(r.energy.dissipated_theorem, rel=1e-12)
    assert r.warnings == ()
    lines = (EXAMPLES / name).read_text().splitlines()
    assert sum(ln.startswith("#") for ln in lines[: lines.index("format = 1")]) >= 3

"""The dispersion (LZB) law with e < 1, and a box landing flat on four corners.

Sources and routes:

* Liu, Zhao and Brogliato, *Frictionless multiple impacts in multibody systems. I. Theoretical
  framework*, Proc. R. Soc. A 464 (2008) 3193-3211: the energetic restitution at each contact,
  the potential energy growing by ``-w dP`` while the contact compresses and falling by
  ``-w dP / e^2`` while it expands, until it is empty. The same rule is the "BiStiffness"
  compliance of the authors' group's implementation in Siconos
  (``Kernel/src/simulationTools/OSNSMultipleImpact.cpp``, ``ComputeEnerContact``). No published
  table of numbers for e < 1 could be found (searched: the 2008 Part I; the 2009 Part II, with
  Newton's cradle and the chains of Ceanga and Hurmuzlu 2001; Nguyen and Brogliato, *Multiple
  Impacts in Dissipative Granular Chains*, Springer 2014; Siconos's examples, whose reference
  outputs are at e = 1), so the second route here is an independent computation, not a table.
* The second route: the law's time-domain form, integrated by SciPy in body coordinates. Each
  contact is a compliant element ``F = k s^p`` whose *apparent* indentation ``s`` grows with the
  approach, ``ds/dt = -w``, and falls ``1/e^2`` times faster while the contact recedes (LZB's
  rule: ``E = k s^(p+1)/(p+1)``, so ``dE = F ds = -F w dt / e^2``: a loading stiffness ``k`` and an
  unloading stiffness ``k/e^2`` for p = 1: the bi-stiffness compliance of LZB 2008 and of
  Siconos's "BiStiffness"). A contact that has given back its energy is open, with the dent it
  keeps: it closes again when the bodies come back to the point where it opened.
  The rate ``-w (1 if w < 0 else 1/e^2)`` is continuous in ``w``, so this route has no
  events at all (the law's phases end at events: the end of each compression, each opening and
  closing; ties between them broke the box landing flat): its switches come from the
  integrator's step control alone. Bodies, forces and velocities are written out by hand here
  (a chain of balls; a box in 3D with ``omega x r``), not taken from carnot's Jacobians.
* The theorem (``E_d = -1/2 sum P.(w' + w'')``) against the direct kinetic-energy difference, to
  1e-12 of the energy, in every test.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
from carnot.errors import InputError
from carnot.laws.multiple import ContactRows, resolve_dispersion


def compliant_hysteretic(
    u0: np.ndarray,
    velocity: Callable[[np.ndarray], np.ndarray],
    acceleration: Callable[[np.ndarray], np.ndarray],
    k: np.ndarray,
    p: np.ndarray,
    e: np.ndarray,
    t_scale: float,
) -> np.ndarray:
    """The second route: integrate ``du/dt = acceleration(F)`` with the contacts' normal
    velocities ``w = velocity(u)`` and forces ``F_i = k_i s_i^p_i`` where ``s_i > 0``, until no
    contact is pressed and none approaches. Returns the final ``u``.

    ``s_i`` is the apparent indentation while positive and the gap to the dent (the point where
    the contact opened) while negative: ``ds/dt = -w``, or ``-w / e^2`` while pressed and
    receding. Every contact starts at ``s = 0``. No events: the right-hand side is continuous
    in ``w`` and in ``s`` except for the rate's jump where a receding contact opens (``s``
    stays continuous), which the step control resolves."""
    n_u = len(u0)
    rate = 1.0 / np.asarray(e, dtype=float) ** 2

    def rhs(_t: float, yy: np.ndarray) -> np.ndarray:
        u, s = yy[:n_u], yy[n_u:]
        w = velocity(u)
        force = k * np.maximum(s, 0.0) ** p
        ds = np.where((s > 0.0) & (w > 0.0), -w * rate, -w)
        return np.concatenate([acceleration(force), ds])

    y = np.concatenate([u0, np.zeros(len(k))])
    for _ in range(1000):
        if np.all(y[n_u:] <= 0.0) and np.all(velocity(y[:n_u]) >= 0.0):
            return y[:n_u]
        sol = solve_ivp(rhs, (0.0, 5.0 * t_scale), y, method="DOP853", rtol=1e-12,
                        atol=1e-16 * t_scale)  # fmt: skip
        y = sol.y[:, -1]
    raise AssertionError("the compliant contacts did not all open")


# ------------------------------------------------------------------------------ chains


def chain_time_domain(masses: list[float], v: float, k: list[float], p: list[float],
                      e: list[float]) -> np.ndarray:  # fmt: skip
    """Balls on a line, touching, the first at ``v``: contact i between balls i and i+1,
    ``w_i = u_(i+1) - u_i``, its force pushing ball i+1 forward and ball i back."""
    mass = np.array(masses, dtype=float)
    u0 = np.zeros(len(masses))
    u0[0] = v

    def acc(force: np.ndarray) -> np.ndarray:
        a = np.zeros(len(mass))
        a[1:] += force
        a[:-1] -= force
        return a / mass

    t_scale = (float(np.max(mass)) / (min(k) * v ** (max(p) - 1.0))) ** (1.0 / (min(p) + 1.0))
    k_, p_, e_ = (np.array(x, dtype=float) for x in (k, p, e))
    return compliant_hysteretic(u0, lambda u: np.diff(u), acc, k_, p_, e_, t_scale)


def _chain_law(masses: list[float], v: float, k: list[float], p: list[float],
               e: list[float]) -> tuple[np.ndarray, object]:  # fmt: skip
    n = len(masses)
    jac = np.zeros((n - 1, n))
    for i in range(n - 1):
        jac[i, i], jac[i, i + 1] = -1.0, 1.0
    minv = np.diag(1.0 / np.array(masses))
    u = np.zeros(n)
    u[0] = v
    contacts = [ContactRows(normal=i, restitution=e[i], stiffness=k[i], exponent=p[i])
                for i in range(n - 1)]  # fmt: skip
    out = resolve_dispersion(jac @ minv @ jac.T, jac @ u, contacts)
    u2 = u + minv @ jac.T @ out.impulses
    e1 = 0.5 * float(np.sum(np.array(masses) * u * u))
    direct = e1 - 0.5 * float(np.sum(np.array(masses) * u2 * u2))
    theorem = -0.5 * float(out.impulses @ (jac @ u + jac @ u2))
    assert theorem == pytest.approx(direct, rel=1e-12, abs=1e-12 * e1)
    assert direct >= -1e-12 * e1  # never a gain
    return u2, out


@pytest.mark.parametrize(
    ("masses", "k", "p", "e"),
    [
        # the three-ball cradle, Hertz contacts, one restitution (LZB 2009 Part II's case)
        ([1.0, 1.0, 1.0], [1.0, 1.0], [1.5, 1.5], [0.8, 0.8]),
        ([1.0, 1.0, 1.0], [1.0, 1.0], [1.5, 1.5], [0.3, 0.3]),
        # unequal masses, stiffnesses and restitutions: contacts open and close again
        ([1.0, 2.0, 0.7], [1.0, 3.0], [1.5, 1.5], [0.6, 0.9]),
        ([2.0, 1.0, 1.0, 1.5], [2.0, 1.0, 0.5], [1.0, 1.0, 1.0], [0.5, 0.7, 0.95]),
        # a light ball between heavy ones, linear contacts: several rounds of compression
        ([3.0, 0.5, 3.0, 0.5], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [0.7, 0.7, 0.7]),
    ],
)
def test_dissipative_chain_equals_the_time_domain_law(masses: list, k: list, p: list,
                                                      e: list) -> None:  # fmt: skip
    v = 1.3
    u2, out = _chain_law(masses, v, k, p, e)
    expected = chain_time_domain(masses, v, k, p, e)
    np.testing.assert_allclose(u2, expected, rtol=0, atol=1e-6 * v)
    assert out.flags == ()  # type: ignore[attr-defined]
    assert float(np.sum(np.array(masses) * u2)) == pytest.approx(masses[0] * v, rel=1e-12)


def test_the_time_domain_route_can_fail() -> None:
    """The second route tells the laws apart: at e = 0.5 the three-ball cradle under the
    dispersion law is not the elastic chain's outcome, nor the simultaneous law's
    ``((1 - 2e)/3, (1 + e)/3, (1 + e)/3) v`` (Glocker 2001)."""
    e = 0.5
    td = chain_time_domain([1.0] * 3, 1.0, [1.0, 1.0], [1.5, 1.5], [e, e])
    elastic = chain_time_domain([1.0] * 3, 1.0, [1.0, 1.0], [1.5, 1.5], [1.0, 1.0])
    newton = np.array([(1 - 2 * e) / 3, (1 + e) / 3, (1 + e) / 3])
    assert np.max(np.abs(td - elastic)) > 1e-2
    assert np.max(np.abs(td - newton)) > 1e-2


# ------------------------------------------------------------------------------ box


_M, _DIMS = 2.0, (0.4, 0.3, 0.2)
_CORNERS = ((1, 1), (-1, 1), (-1, -1), (1, -1))


def _box_problem(e: float, omega: tuple[float, float, float], v=(0.0, 0.0, -1.0),
                 k=(1.0, 1.0, 1.0, 1.0)) -> ImpactProblem:  # fmt: skip
    """A 2 kg box, 0.4 x 0.3 x 0.2 m, landing flat on its four bottom corners (floor z = 0)."""
    a, b, c = _DIMS
    inertia = _M / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    box = RigidBody(name="box", mass=_M, inertia_com=inertia, position_com=[0, 0, c / 2],
                    velocity_com=list(v), angular_velocity=list(omega))  # fmt: skip
    contacts = [PointContact(a="box", b="floor", point=[sx * a / 2, sy * b / 2, 0.0],
                             normal=[0, 0, 1], restitution=e, stiffness=k[i],
                             where=f"corner{i}")
                for i, (sx, sy) in enumerate(_CORNERS)]  # fmt: skip
    return ImpactProblem(bodies={"floor": FixedBody(name="floor"), "box": box},
                         contacts=contacts, multiple_impact="dispersion")  # fmt: skip


def box_time_domain(e: float, omega: tuple[float, float, float], v=(0.0, 0.0, -1.0),
                    k=(1.0, 1.0, 1.0, 1.0), p: float = 1.5) -> np.ndarray:  # fmt: skip
    """The box's ``(v, omega)`` after its corners' compliant elements have all opened: Newton
    and Euler with the corner forces ``F_i z`` at ``r_i`` (the configuration fixed, as in the
    impact), the corner velocities ``w_i = z . (v + omega x r_i)``."""
    a, b, c = _DIMS
    inertia = _M / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    inv_inertia = np.linalg.inv(inertia)
    r = np.array([[sx * a / 2, sy * b / 2, -c / 2] for sx, sy in _CORNERS])
    z = np.array([0.0, 0.0, 1.0])

    def velocity(u: np.ndarray) -> np.ndarray:
        return (u[:3] + np.cross(u[3:], r)) @ z  # each corner's v + omega x r_i, along z

    def acc(force: np.ndarray) -> np.ndarray:
        torque = np.cross(r, force[:, None] * z).sum(axis=0)
        return np.concatenate([np.sum(force) * z / _M, inv_inertia @ torque])

    u0 = np.concatenate([np.array(v, dtype=float), np.array(omega, dtype=float)])
    t_scale = (_M / min(k)) ** (1.0 / (p + 1.0))
    return compliant_hysteretic(u0, velocity, acc, np.array(k, dtype=float), np.full(4, p),
                                np.full(4, e), t_scale)  # fmt: skip


def _box_checks(res) -> np.ndarray:  # type: ignore[no-untyped-def]
    en = res.energy
    assert en.dissipated == pytest.approx(en.dissipated_theorem, rel=1e-12, abs=1e-12 * en.before)
    assert en.dissipated >= -1e-12 * en.before, "energy gained"
    b = res.bodies["box"]
    return np.concatenate([b.velocity_after, b.angular_velocity_after])


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_box_landing_flat_is_continuous_in_the_tilt(e: float) -> None:
    """Four corners of equal stiffness end their compression at the same instant (a tie by
    symmetry, or within 1e-16 with a tiny tilt). The law switched only the corner whose event
    fired: at e = 0 with a 1e-6 rad/s tilt the box left at 0.35 m/s spinning at 1.4 rad/s
    (a corner gave its energy back elastically), and without tilt at e = 0.5 and 1 the phases
    stalled (flagged ``stage_limit``). Now the outcome is continuous in the tilt, unflagged:
    flat, every corner leaves at ``-e`` times its approach (one contact's rule, each corner
    seeing the same history)."""
    flat = _box_checks(res := solve_impact(_box_problem(e, (0.0, 0.0, 0.0))))
    assert not [f for f in res.flag_codes() if f != "statically_indeterminate"]
    np.testing.assert_allclose(flat, [0, 0, e, 0, 0, 0], atol=1e-9)
    for tilt in (1e-9, 1e-6, 1e-3):
        tilted = _box_checks(res := solve_impact(_box_problem(e, (tilt, 0.0, 0.0))))
        assert not [f for f in res.flag_codes() if f != "statically_indeterminate"]
        # continuous: the change is of the order of the tilt's corner speed (0.15 tilt m/s)
        assert np.max(np.abs(tilted - flat)) <= 10.0 * tilt


@pytest.mark.parametrize(
    ("e", "omega", "k"),
    [
        (1.0, (0.3, 0.0, 0.0), (1.0, 1.0, 1.0, 1.0)),
        (0.5, (0.3, 0.0, 0.0), (1.0, 1.0, 1.0, 1.0)),
        (0.5, (0.2, -0.4, 0.0), (1.0, 1.0, 1.0, 1.0)),
        (0.7, (0.0, 0.0, 0.0), (1.0, 2.0, 1.0, 0.5)),  # unequal stiffness: it tips over
        (0.2, (0.1, 0.05, 0.0), (1.0, 1.0, 1.0, 1.0)),
    ],
)
def test_box_landing_equals_the_time_domain_law(e: float, omega: tuple, k: tuple) -> None:
    """Redundant contacts (four corners, three normal freedoms: the Delassus matrix has rank
    3) need no special rule in the LZB law: its compliant elements decide the split, as they
    do in time. The box's outcome equals the time-domain route's to 1e-6."""
    res = solve_impact(_box_problem(e, omega, k=k))
    got = _box_checks(res)
    expected = box_time_domain(e, omega, k=k)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-6)
    assert not [f for f in res.flag_codes() if f != "statically_indeterminate"]


# ------------------------------------------------------------------------------ LZB's algorithm


def lzb_stepping(g: np.ndarray, w0: np.ndarray, k: list, p: list, e: list,
                 n_steps: int) -> np.ndarray:  # fmt: skip
    """A third route: LZB's own algorithm, as the authors' group implements it in Siconos
    (``OSNSMultipleImpact``, "BiStiffness"): explicit steps ``dP`` of the primary contact's
    impulse (the contact holding the most energy; the fastest approaching while none holds
    any), the others' steps in the ratio of their forces ``F_i / F_r`` with ``F = ((p+1) E)^(p /
    (p+1)) k^(1/(p+1))``, a contact with no energy yet taking ``E_i = |w_i dP|`` for its first
    step; each contact's energy grows by ``-w_m dP_i`` compressing and falls by ``-w_m dP_i /
    e^2`` expanding (``w_m`` the step's mean velocity), at least 0, emptied at once when e = 0.
    An open contact takes part again as soon as it approaches. First order in ``dP``. Returns
    the final velocities."""
    w = np.array(w0, dtype=float)
    k_, p_, e_ = (np.asarray(x, dtype=float) for x in (k, p, e))
    energy = np.zeros(len(w))
    dp = float(np.sum(np.abs(w) / np.diag(g))) / n_steps
    c = (1.0 + p_) ** (p_ / (1.0 + p_)) * k_ ** (1.0 / (1.0 + p_))
    q = p_ / (1.0 + p_)
    tol_e = 1e-14 * float(np.sum(w * w / np.diag(g)))
    inv_e2 = np.where(e_ > 0.0, 1.0 / np.maximum(e_, 1e-300) ** 2, 0.0)
    for _ in range(50 * n_steps):
        loaded = energy > tol_e
        if not loaded.any():
            if np.all(w >= -1e-12):
                return w
            r = int(np.argmin(w))
            ratio = np.where(w < 0.0, ((c / c[r]) * np.abs(w) ** q / abs(w[r]) ** q[r]) ** (1 + p_)
                             * dp ** ((p_ - p_[r]) / (1.0 + p_[r])), 0.0)  # fmt: skip
        else:
            r = int(np.argmax(energy))
            f_r = c[r] * energy[r] ** q[r]
            first = np.where(w < 0.0, (c * np.abs(w * dp) ** q / f_r) ** (1.0 + p_), 0.0)
            ratio = np.where(loaded, c * energy**q / f_r, first)
        step = ratio * dp
        w_mean = w + 0.5 * (g @ step)
        w = w + g @ step
        energy = np.where(w_mean <= 0.0, energy - w_mean * step, energy - w_mean * step * inv_e2)
        energy = np.where((w_mean > 0.0) & (e_ == 0.0), 0.0, np.maximum(energy, 0.0))
    raise AssertionError("LZB's steps did not end")


def test_lzb_algorithm_and_the_two_reactivations() -> None:
    """The three-ball cradle at e = 0.2 (Hertz): the middle ball's first contact opens and
    closes again. LZB's algorithm (an open contact acts again once it approaches) converges, at
    first order in its step, to the law with ``reactivation="approach"``; the default ("gap":
    the contact acts again once the bodies are back where it opened, as the compliant dynamics
    do) differs by 1.4e-4 m/s, beyond the step's error at 16000 steps (2.6e-5)."""
    jac = np.array([[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]])
    g, w = jac @ jac.T, jac @ np.array([1.0, 0.0, 0.0])
    contacts = [ContactRows(normal=i, restitution=0.2) for i in range(2)]
    approach = resolve_dispersion(g, w, contacts, reactivation="approach")
    gap = resolve_dispersion(g, w, contacts)
    stepped = lzb_stepping(g, w, [1.0, 1.0], [1.5, 1.5], [0.2, 0.2], 16_000)
    assert np.max(np.abs(stepped - approach.w_after)) < 5e-5
    assert np.max(np.abs(stepped - gap.w_after)) > 1e-4
    # the default is the time-domain (compliant) route's answer, the other is not
    td = chain_time_domain([1.0] * 3, 1.0, [1.0, 1.0], [1.5, 1.5], [0.2, 0.2])
    np.testing.assert_allclose(jac.T @ gap.impulses + [1.0, 0.0, 0.0], td, atol=1e-6)
    assert np.max(np.abs(jac.T @ approach.impulses + [1.0, 0.0, 0.0] - td)) > 1e-5
    for out in (gap, approach):
        u2 = np.array([1.0, 0.0, 0.0]) + jac.T @ out.impulses
        direct = 0.5 - 0.5 * float(u2 @ u2)
        assert out.dissipated == pytest.approx(direct, rel=1e-12)


def test_reactivation_is_checked() -> None:
    with pytest.raises(InputError, match=r"reactivation: must be one of gap, approach"):
        resolve_dispersion([[2.0]], [-1.0], [ContactRows(normal=0)], reactivation="velocity")

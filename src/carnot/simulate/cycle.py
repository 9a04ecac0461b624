"""Periodic orbits of free bodies: the return map at an impact, Newton shooting, and the
multipliers by two routes (DESIGN.md section 10, issue 34 items 3 and 5).

**The section** is the state just after an impact of the simulator (:func:`carnot.simulate.
run`). Its coordinates ``x`` (:class:`Layout`) are, in this order: the time ``tau`` (s) of
the impact when the ground oscillates (:class:`carnot.simulate.ground.Oscillation`; the
forcing makes the phase part of the state), then for each movable body its position (m) and
velocity (m/s), relative to the fixed bodies, and, for a body that turns on the guess's
return, its orientation (a rotation vector, rad, about the current orientation, world axes;
not for a sphere, whose orientation nothing sees) and its angular velocity (rad/s).

**The return map** ``P`` simulates from ``x`` to the ``k``-th next impact instant (``k`` =
``strikes``) and reads the state just after it. With ground motion of period ``T`` the
orbit's condition is ``P(x) = x`` with the time advanced by ``m T``: the time coordinate of
``P(x)`` is ``tau + t_k - m T``, ``m = max(1, round(t_k / T))`` the number of forcing periods
the flight took (reported). Without ground motion the time is no coordinate (the flow is
autonomous) and the period is the flight time.

**Newton shooting**: on the section the struck contacts' gaps vanish, ``g_i(x) = 0``, so ``x``
moves in the tangent space ``T = ker Dg`` (orthonormal basis ``U``, :func:`tangent_basis`), and
``P`` maps into the section: its Jacobian has a zero eigenvalue per struck contact, which is
not a multiplier of the motion and is removed by working on ``T``: ``A = U^T DP U``. Newton's
step solves ``(A - I) d = -U^T (P(x) - x)`` by least squares (minimum norm: below), halved
until the residual falls; it stops at ``|P(x) - x| <= tolerance max(1, |x|)`` (SI units, the
norm over all coordinates), or says it did not converge, with the residual it reached.

**What the multipliers leave out, and why.** A forced system has no trivial multiplier 1:
shifting the start along the orbit shifts it against the table's phase, which the map sees.
What it does have are *symmetries*: the scene is unchanged by a translation ``d`` along every
plane (``d . n = 0`` for every normal; gravity and the ground's motion are uniform), so
``P(x + d) = P(x) + d`` and ``A d = d`` exactly: a family of orbits, not a stability. The
common velocity along ``d``, and a turning sphere's angular velocity, are candidates that
no force may change (a ball's horizontal velocity on a frictionless table: ``A c = c + t_k d``);
a candidate joins the neutral subspace ``S`` when ``(A - I) c`` lies in ``S`` (to
``NEUTRAL_TOLERANCE``; with friction it does not, and its multiplier stays). The orbit is
``stable`` when every multiplier left lies inside the unit circle by more than
``UNIT_CIRCLE`` (one on it is a family, such as a lossless ball's bounces by energy). ``S`` is then
invariant, ``A = [[A_SS, *], [0, A_WW]]`` in an orthonormal basis ``(S, W)``, and the
multipliers are the eigenvalues of ``A_WW = W^T A W``; those of ``A_SS`` (all 1) are reported
as ``neutral``. For a ball on a vibrating table what remains is Holmes' 2 x 2 map: the phase
and the normal velocity. Newton's least-squares step leaves the neutral translations where the
guess put them.

**Two routes to DP.** Central differences of ``P`` along ``U`` (step ``FD_STEP``), always;
and, where the bodies only translate between impacts and every event of the period is a single
impact in free flight, saltation matrices (Aizerman and Gantmacher 1958; Kong, Payne, Council
and Johnson 2023): in the extended state ``z = (t, p, v)``, ``z' = F(z) = (1, v, g - a_g(t))``,
the flight's Jacobian is exact,

    dp/dp0 = I, dp/dv0 = s I, dv/dv0 = I,
    dp/dt0 = -(v_g(t0 + s) - v_g(t0) - a_g(t0) s),  dv/dt0 = -(a_g(t0 + s) - a_g(t0)),

and each impact on the gap ``G`` with reset ``R`` (the velocity jump of
:func:`carnot.simulate.impacts.solve_at`, differenced centrally) contributes

    DP = DR (I - F- DG / (DG F-)) Phi,

the same product as :mod:`carnot.hybrid.cycle`. An impact whose approach speed ``|DG F-|`` is
below ``GRAZING`` of the scene's speed is *grazing*: the map is not differentiable there, so
no multiplier is returned, and it is flagged.

The energy per period is the simulator's ledger over exactly one period (in the ground's
frame): ``impacts``, ``sliding`` and ``ground_work`` (J); on the orbit the state returns,
so ``ground_work = impacts + sliding`` to the ledger's residual (reported).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from carnot.errors import InputError
from carnot.simulate.contacts import SimulationError
from carnot.simulate.events import Feature, features, gaps_and_speeds, geometry
from carnot.simulate.ground import Oscillation
from carnot.simulate.impacts import Event, Impact, feature_names, solve_at
from carnot.simulate.loop import Simulation, mechanical_energy, run, scales
from carnot.simulate.motion import BodyState, quat_from_rotvec, quat_multiply
from carnot.simulate.shapes import Sphere

#: The most Newton steps, and how often a step may be halved.
MAX_NEWTON = 40
MAX_HALVINGS = 12
#: The step of the finite-difference routes (in each coordinate's SI unit, relative above 1).
FD_STEP = 1e-6
#: The longest flight (s) one return may take before it counts as no return.
MAX_PERIOD = 100.0
#: How far ``(A - I) c`` may leave the neutral subspace, relative to ``max(1, |A|) |c|``.
NEUTRAL_TOLERANCE = 1e-6
#: An impact approaching slower than this fraction of the scene's speed is grazing.
GRAZING = 1e-6
#: A multiplier within this of the unit circle is on it (neutral: a family of orbits, not
#: stability), beyond the routes' accuracy (about 1e-10 by saltation, 1e-7 by differences).
UNIT_CIRCLE = 1e-6
#: Impacts closer than this (s) are one impact instant.
SAME_INSTANT = 1e-12


class ReturnFailed(Exception):
    """The motion from a state did not come back to the section: no impact within
    ``MAX_PERIOD``, the bodies came to rest, or the simulator refused the run."""


@dataclass(frozen=True, kw_only=True, eq=False)
class Layout:
    """Which coordinates the section has: ``forced`` (the time first), the bodies'
    ``names``, per body ``spins`` (its angular velocity is a coordinate) and ``orients`` (its
    orientation is, as a rotation vector).

    >>> Layout(forced=True, names=("ball",), spins=(False,), orients=(False,)).coordinates
    ('time', 'ball.position.x', 'ball.position.y', 'ball.position.z', 'ball.velocity.x', 'ball.velocity.y', 'ball.velocity.z')
    """  # noqa: E501

    forced: bool
    names: tuple[str, ...]
    spins: tuple[bool, ...]
    orients: tuple[bool, ...]

    @property
    def coordinates(self) -> tuple[str, ...]:
        out = ["time"] if self.forced else []
        for name, spin, orient in zip(self.names, self.spins, self.orients, strict=True):
            groups = ["position", "velocity"] + (["orientation"] if orient else []) + (
                ["angular_velocity"] if spin else [])  # fmt: skip
            out += [f"{name}.{g}.{a}" for g in groups for a in "xyz"]
        return tuple(out)

    @property
    def size(self) -> int:
        return len(self.coordinates)

    def slots(self, body: int) -> dict[str, int]:
        """Where body ``body``'s groups start in ``x`` (``position``, ``velocity`` and, when
        present, ``orientation``, ``angular_velocity``)."""
        k = 1 if self.forced else 0
        for i in range(body):
            k += 6 + 3 * self.orients[i] + 3 * self.spins[i]
        out = {"position": k, "velocity": k + 3}
        k += 6
        if self.orients[body]:
            out["orientation"] = k
            k += 3
        if self.spins[body]:
            out["angular_velocity"] = k
        return out


@dataclass(frozen=True, kw_only=True, eq=False)
class SectionPoint:
    """A state on the section: the ``time`` (s, of the impact; 0 without forcing) and every
    movable body's state just after it (relative to the fixed bodies)."""

    time: float
    states: tuple[BodyState, ...]


def displace(point: SectionPoint, layout: Layout, dx: np.ndarray) -> SectionPoint:
    """``point`` moved by ``dx`` in the section's coordinates (an orientation by the rotation
    ``Rot(dx_orientation) R``, world axes); coordinates the layout leaves out are kept.

    >>> import numpy as np
    >>> s = BodyState(position=np.zeros(3), orientation=np.array([1.0, 0, 0, 0]),
    ...               velocity=np.zeros(3), angular_velocity=np.zeros(3))
    >>> lay = Layout(forced=True, names=("ball",), spins=(False,), orients=(False,))
    >>> p = displace(SectionPoint(time=0.0, states=(s,)), lay, np.arange(7.0))
    >>> p.time, p.states[0].velocity.tolist()
    (0.0, [4.0, 5.0, 6.0])
    """
    time = point.time + (float(dx[0]) if layout.forced else 0.0)
    out = []
    for i, s in enumerate(point.states):
        at = layout.slots(i)
        q = s.orientation
        if "orientation" in at:
            k = at["orientation"]
            q = quat_multiply(quat_from_rotvec(np.asarray(dx[k: k + 3], dtype=float)), q)
            q = q / np.linalg.norm(q)
        w = s.angular_velocity
        if "angular_velocity" in at:
            k = at["angular_velocity"]
            w = w + dx[k: k + 3]
        p, v = at["position"], at["velocity"]
        out.append(BodyState(position=s.position + dx[p: p + 3], orientation=q,
                             velocity=s.velocity + dx[v: v + 3], angular_velocity=w))  # fmt: skip
    return SectionPoint(time=time, states=tuple(out))


def difference(a: SectionPoint, b: SectionPoint, layout: Layout) -> np.ndarray:
    """``a - b`` in the section's coordinates (an orientation as the rotation vector of
    ``R_a R_b^T``), so that ``displace(b, layout, difference(a, b, layout))`` is ``a``."""
    out = [a.time - b.time] if layout.forced else []
    for i, (sa, sb) in enumerate(zip(a.states, b.states, strict=True)):
        out += list(sa.position - sb.position) + list(sa.velocity - sb.velocity)
        if layout.orients[i]:
            out += list(_rotvec(quat_multiply(sa.orientation, sb.orientation * [1, -1, -1, -1])))
        if layout.spins[i]:
            out += list(sa.angular_velocity - sb.angular_velocity)
    return np.array(out, dtype=float)


def _rotvec(q: np.ndarray) -> np.ndarray:
    """The rotation vector (rad) of the unit quaternion ``q = [w, x, y, z]``."""
    q = q if q[0] >= 0 else -q
    s = float(np.linalg.norm(q[1:]))
    if s < 1e-300:
        return np.zeros(3)
    return 2.0 * math.atan2(s, float(q[0])) * q[1:] / s


def vector(point: SectionPoint, layout: Layout) -> np.ndarray:
    """The point's coordinates as a vector (orientations as 0: they are kept as quaternions
    and only their displacements are coordinates)."""
    zero = SectionPoint(time=0.0, states=tuple(
        BodyState(position=np.zeros(3), orientation=s.orientation, velocity=np.zeros(3),
                  angular_velocity=np.zeros(3)) for s in point.states))  # fmt: skip
    return difference(point, zero, layout)


# --- the return map ------------------------------------------------------------------------


def forcing_period(sim: Simulation) -> float | None:
    """The ground's period ``T`` (s), ``None`` when the ground does not move; ground motion
    that is not periodic has no periodic orbits (InputError naming the key)."""
    if sim.ground is None:
        return None
    if isinstance(sim.ground, Oscillation):
        return sim.ground.period
    key = "ground_pulse" if hasattr(sim.ground, "shape") else "ground_motion"
    raise InputError(f"simulation.{key}", "ends: a periodic orbit needs ground that keeps "
                     "moving (ground_oscillation) or none", show_value=False)  # fmt: skip


def _started(sim: Simulation, point: SectionPoint, duration: float) -> Simulation:
    """``sim`` from ``point``: its states at 0, the ground's phase moved on by ``point.time``
    (the simulator's clock starts at 0)."""
    ground = sim.ground
    if isinstance(ground, Oscillation):
        turn = math.fmod(ground.angular_frequency * point.time, 2 * math.pi)
        ground = replace(ground, phase=ground.phase + turn)
    return replace(sim, initial=list(point.states), ground=ground, duration=duration)


@dataclass(frozen=True, kw_only=True, eq=False)
class Return:
    """One return: the ``point`` just after the ``k``-th impact instant (its ``time`` the
    start's plus ``flight``), the ``flight`` (s), the ``events`` up to it, the ``impacts`` of
    the period and the ``struck`` features of the last, and with ``energy`` the ledger over
    exactly this stretch (J: ``impacts``, ``sliding``, ``ground_work``, ``residual``)."""

    point: SectionPoint
    flight: float
    events: tuple[Event, ...]
    impacts: tuple[Impact, ...]
    struck: tuple[Feature, ...]
    energy: dict[str, float] | None


def return_map(sim: Simulation, point: SectionPoint, strikes: int = 1, *,
               energy: bool = False) -> Return:  # fmt: skip
    """Simulate from ``point`` to the ``strikes``-th next impact instant (ReturnFailed if none
    comes within ``MAX_PERIOD`` s).

    >>> from carnot.simulate import load_simulation
    >>> sim = load_simulation("examples/simulate/ball_on_vibrating_table.toml")
    >>> r = return_map(sim, SectionPoint(time=0.0, states=tuple(sim.initial)))
    >>> round(r.flight, 12), round(float(r.point.states[0].velocity[1]), 12)
    (0.2, 0.654)
    """
    period = forcing_period(sim) or 1.0
    horizon = 1.5 * strikes * period
    while True:
        try:
            res = run(_started(sim, point, horizon))
        except (SimulationError, InputError) as err:
            raise ReturnFailed(f"the simulator stopped: {err}") from None
        instants: list[int] = []  # the last impact event of each impact instant
        for k, ev in enumerate(res.events):
            if ev.kind != "impact":
                continue
            if instants and ev.time - res.events[instants[-1]].time <= SAME_INSTANT:
                instants[-1] = k
            else:
                instants.append(k)
        # the k-th instant is complete only once an event after it, or the end, is later
        if len(instants) > strikes or (len(instants) == strikes and any(
                e.time - res.events[instants[-1]].time > SAME_INSTANT
                for e in res.events[instants[-1] + 1:])):  # fmt: skip
            break
        if any(ev.kind == "rest" for ev in res.events):
            raise ReturnFailed("the bodies came to rest before the next impact")
        if horizon >= MAX_PERIOD:
            raise ReturnFailed(f"{len(instants)} impact(s) within {MAX_PERIOD:g} s, "
                               f"{strikes} wanted")  # fmt: skip
        horizon = min(2 * horizon, MAX_PERIOD)
    last = instants[strikes - 1]
    hit = res.events[last].impact
    assert hit is not None
    events = tuple(res.events[: last + 1])
    after = SectionPoint(time=point.time + hit.time, states=tuple(hit.states))
    ledger = None
    if energy:
        # the run went on past the k-th impact: the same run from there to its end takes
        # the rest away, leaving the ledger of exactly one period
        rest = run(_started(sim, after, horizon - hit.time)).energy
        led = res.energy
        ledger = {"impacts": led.impacts - rest.impacts, "sliding": led.sliding - rest.sliding,
                  "ground_work": led.ground_work - rest.ground_work}  # fmt: skip
        ledger["residual"] = (mechanical_energy(sim, list(point.states)) + ledger["ground_work"]
                              - ledger["impacts"] - ledger["sliding"]
                              - mechanical_energy(sim, list(after.states)))  # fmt: skip
    impacts = tuple(ev.impact for ev in events if ev.impact is not None and ev.kind == "impact")
    return Return(point=after, flight=hit.time, events=events, impacts=impacts,
                  struck=tuple(hit.features), energy=ledger)  # fmt: skip


def periods_of(flight: float, period: float | None) -> int:
    """``m = max(1, round(flight / T))``: the forcing periods a flight took (0 unforced).

    >>> periods_of(0.4000001, 0.2), periods_of(0.05, 0.2), periods_of(1.3, None)
    (2, 1, 0)
    """
    return 0 if period is None else max(1, round(flight / period))


def residual_vector(ret: Return, point: SectionPoint, layout: Layout, shift: float
                    ) -> np.ndarray:  # fmt: skip
    """``P(x) - x``, the return's time less ``shift`` (``m T``)."""
    back = SectionPoint(time=ret.point.time - shift, states=ret.point.states)
    return difference(back, point, layout)


# --- the section's tangent space and the two routes to DP ----------------------------------


def complement_basis(rows: np.ndarray, n: int) -> np.ndarray:
    """An orthonormal basis (columns) of the vectors of ``R^n`` orthogonal to ``rows``, made
    of the coordinate axes where it can be (each axis projected, the longest first, then
    Gram-Schmidt): the section's coordinates stay recognisable.

    >>> complement_basis(np.array([[0.0, 1.0, 0.0]]), 3).T.tolist()
    [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    rows = np.atleast_2d(np.asarray(rows, dtype=float))
    if rows.size == 0:
        return np.eye(n)
    u, s, vt = np.linalg.svd(rows)
    rank = int(np.sum(s > 1e-12 * max(1.0, float(s[0]) if len(s) else 1.0)))
    span = vt[:rank]
    proj = np.eye(n) - span.T @ span
    order = np.argsort(-np.linalg.norm(proj, axis=0), kind="stable")
    basis: list[np.ndarray] = []
    for j in order:
        c = proj[:, j].copy()
        for b in basis:
            c -= (b @ c) * b
        norm = float(np.linalg.norm(c))
        if norm > 1e-8:
            basis.append(c / norm)
        if len(basis) == n - rank:
            break
    out = np.array(basis).T
    # coordinate order, and each axis pointing its own way (a stable, readable layout)
    lead = np.argmax(np.abs(out), axis=0)
    keep = np.argsort(lead, kind="stable")
    out = out[:, keep]
    return out * np.sign(out[np.argmax(np.abs(out), axis=0), np.arange(out.shape[1])])


def gap_gradients(sim: Simulation, layout: Layout, point: SectionPoint,
                  struck: tuple[Feature, ...]) -> np.ndarray:  # fmt: skip
    """``Dg``: each struck feature's gap (m) differentiated along the section's coordinates,
    by central differences (step ``FD_STEP``; exact for a sphere on a plane, linear)."""
    n = layout.size
    out = np.zeros((len(struck), n))
    for j in range(n):
        dx = np.zeros(n)
        dx[j] = FD_STEP
        up, down = displace(point, layout, dx), displace(point, layout, -dx)
        for i, f in enumerate(struck):
            out[i, j] = (geometry(f, sim.bodies, sim.planes, list(up.states)).gap
                         - geometry(f, sim.bodies, sim.planes, list(down.states)).gap
                         ) / (2 * FD_STEP)  # fmt: skip
    return out


def tangent_basis(sim: Simulation, layout: Layout, point: SectionPoint,
                  struck: tuple[Feature, ...]) -> np.ndarray:  # fmt: skip
    """``U``: an orthonormal basis of the section's tangent space ``ker Dg`` at ``point``."""
    return complement_basis(gap_gradients(sim, layout, point, struck), layout.size)


def finite_difference_jacobian(sim: Simulation, layout: Layout, point: SectionPoint,
                               basis: np.ndarray, strikes: int, shift: float
                               ) -> np.ndarray:  # fmt: skip
    """``DP U`` by central differences of the return map along each column of ``basis``
    (``shift``: the ``m T`` held fixed)."""
    out = np.zeros((layout.size, basis.shape[1]))
    for j in range(basis.shape[1]):
        h = FD_STEP
        up = return_map(sim, displace(point, layout, h * basis[:, j]), strikes)
        down = return_map(sim, displace(point, layout, -h * basis[:, j]), strikes)
        out[:, j] = difference(up.point, down.point, layout) / (2 * h)
    return out


def saltation_jacobian(sim: Simulation, layout: Layout, point: SectionPoint, ret: Return
                       ) -> np.ndarray | None:  # fmt: skip
    """``DP`` (``layout.size`` square) through the flights' exact Jacobians and each impact's
    saltation (module docstring), or ``None`` where this route does not reach: a body that
    turns, an event that is not one impact of one feature (a contact phase, a Zeno series,
    several contacts at once)."""
    if any(layout.spins) or any(layout.orients):
        return None
    if any(ev.kind != "impact" or ev.impact is None or len(ev.impact.features) != 1
           for ev in ret.events):  # fmt: skip
        return None
    started = _started(sim, point, 1.0)
    ground = started.ground
    nb = len(sim.bodies)
    n = 1 + 6 * nb  # the extended state z = (t, p_1, v_1, ..., p_n, v_n)
    g = np.asarray(sim.gravity, dtype=float)

    def a_g(t: float) -> np.ndarray:
        return np.zeros(3) if ground is None else ground.accel(t)

    def v_g(t: float) -> np.ndarray:
        return np.zeros(3) if ground is None else ground.velocity(t)

    _, eps_v = scales(sim)
    total = np.eye(n)
    t0 = 0.0
    states = list(point.states)
    for ev in ret.events:
        hit = ev.impact
        assert hit is not None
        s = hit.time - t0
        phi = np.eye(n)
        minus: list[BodyState] = []
        for b, st in enumerate(states):
            p, v = 1 + 6 * b, 4 + 6 * b
            phi[p: p + 3, v: v + 3] = s * np.eye(3)
            phi[p: p + 3, 0] = -(v_g(t0 + s) - v_g(t0) - a_g(t0) * s)
            phi[v: v + 3, 0] = -(a_g(t0 + s) - a_g(t0))
            minus.append(replace(st, position=hit.states[b].position,
                                 velocity=st.velocity + g * s - (v_g(t0 + s) - v_g(t0))))
        feature = hit.features[0]
        f_minus = np.zeros(n)
        f_minus[0] = 1.0
        for b, st in enumerate(minus):
            f_minus[1 + 6 * b: 4 + 6 * b] = st.velocity
            f_minus[4 + 6 * b: 7 + 6 * b] = g - a_g(hit.time)
        grad = np.zeros(n)
        for b in range(nb):
            for a in range(3):
                dp = np.zeros(3)
                dp[a] = FD_STEP
                up = [replace(st, position=st.position + dp) if k == b else st
                      for k, st in enumerate(minus)]  # fmt: skip
                down = [replace(st, position=st.position - dp) if k == b else st
                        for k, st in enumerate(minus)]  # fmt: skip
                grad[1 + 6 * b + a] = (geometry(feature, sim.bodies, sim.planes, up).gap
                                       - geometry(feature, sim.bodies, sim.planes, down).gap
                                       ) / (2 * FD_STEP)  # fmt: skip
        crossing = float(grad @ f_minus)
        project = np.eye(n) - np.outer(f_minus, grad) / crossing
        reset = np.eye(n)
        for b in range(nb):
            for j, what in ((1, "position"), (4, "velocity")):
                for a in range(3):
                    col = j + 6 * b + a
                    d = np.zeros(3)
                    d[a] = FD_STEP * max(1.0, abs(float(getattr(minus[b], what)[a])))
                    out = []
                    for sign in (1.0, -1.0):
                        moved = [replace(st, **{what: getattr(st, what) + sign * d})
                                 if k == b else st for k, st in enumerate(minus)]  # fmt: skip
                        after = solve_at(hit.time, sim.bodies, sim.planes, sim.plane_names,
                                         moved, [feature], [], started.law_of, eps_v).states
                        out.append(np.concatenate([st.velocity for st in after]))
                    diff = (out[0] - out[1]) / (2 * d[a])
                    reset[:, col] = 0.0
                    reset[col, col] = 1.0 if what == "position" else 0.0
                    for k in range(nb):
                        reset[4 + 6 * k: 7 + 6 * k, col] = diff[3 * k: 3 * k + 3]
        total = reset @ project @ phi @ total
        t0, states = hit.time, list(hit.states)
    if not layout.forced:
        total = total[1:, 1:]
    return total


# --- neutral directions and multipliers ----------------------------------------------------


def translations(sim: Simulation) -> np.ndarray:
    """Unit directions ``d`` (rows) along every plane, ``d . n = 0`` for each normal: moving
    every body by ``d`` changes no gap, no force."""
    normals = np.array([pl.normal for pl in sim.planes], dtype=float).reshape(-1, 3)
    return complement_basis(normals, 3).T


def neutral_candidates(sim: Simulation, layout: Layout) -> tuple[list[np.ndarray], list[str],
                                                                 list[np.ndarray], list[str]]:
    """The symmetries (every body translated along each of :func:`translations`) and the
    candidates (the common velocity along it; each turning sphere's angular velocity about
    each axis) as vectors of the section's coordinates, with their names."""
    n = layout.size
    sym: list[np.ndarray] = []
    cand: list[np.ndarray] = []
    sym_names: list[str] = []
    cand_names: list[str] = []
    for d in translations(sim):
        shown = "[" + ", ".join(f"{c:.6g}" for c in d + 0.0) + "]"
        for group, into, names in (("position", sym, sym_names),
                                   ("velocity", cand, cand_names)):  # fmt: skip
            vec = np.zeros(n)
            for b in range(len(layout.names)):
                k = layout.slots(b)[group]
                vec[k: k + 3] = d
            into.append(vec)
            names.append(f"translation along {shown}" if group == "position"
                         else f"velocity along {shown}")  # fmt: skip
    for b, body in enumerate(sim.bodies):
        if layout.spins[b] and isinstance(body.shape, Sphere):
            k = layout.slots(b)["angular_velocity"]
            for a, axis in enumerate("xyz"):
                vec = np.zeros(n)
                vec[k + a] = 1.0
                cand.append(vec)
                cand_names.append(f"{body.name}.angular_velocity.{axis}")
    return sym, sym_names, cand, cand_names


@dataclass(frozen=True, kw_only=True, eq=False)
class Multipliers:
    """The multipliers off the neutral subspace (complex, largest modulus first), those on
    it (``neutral``) and the names of its directions."""

    multipliers: np.ndarray
    neutral: np.ndarray
    neutral_names: tuple[str, ...]


def split_multipliers(jacobian: np.ndarray, basis: np.ndarray, symmetries: list[np.ndarray],
                      candidates: list[np.ndarray], names: list[str]) -> Multipliers:
    """The eigenvalues of ``A = U^T (DP U)`` less those of its neutral subspace (module
    docstring). ``jacobian`` is ``DP U``; ``symmetries`` and ``candidates`` are vectors of the
    section's coordinates, ``names`` theirs in that order.

    >>> a = np.array([[1.0, 0.2, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.5]])
    >>> m = split_multipliers(a, np.eye(3), [np.eye(3)[0]], [np.eye(3)[1]], ["x", "vx"])
    >>> m.multipliers.tolist(), m.neutral_names
    ([(0.5+0j)], ('x', 'vx'))
    """
    a = basis.T @ jacobian
    m = a.shape[0]
    scale = max(1.0, float(np.linalg.norm(a)))
    q = np.zeros((m, 0))
    chosen: list[str] = []

    def add(c: np.ndarray) -> np.ndarray | None:
        c = c - q @ (q.T @ c)
        norm = float(np.linalg.norm(c))
        return None if norm <= 1e-8 else c / norm

    k = 0
    for vec in symmetries:  # exact: P(x + d) = P(x) + d
        c = add(basis.T @ vec)
        if c is not None:
            q = np.column_stack([q, c])
            chosen.append(names[k])
        k += 1
    for vec in candidates:
        c = basis.T @ vec
        moved = (a - np.eye(m)) @ c
        off = moved - q @ (q.T @ moved)
        unit = add(c)
        if unit is not None and float(np.linalg.norm(off)) <= NEUTRAL_TOLERANCE * scale * \
                float(np.linalg.norm(c)):  # fmt: skip
            q = np.column_stack([q, unit])
            chosen.append(names[k])
        k += 1
    w = complement_basis(q.T, m) if q.shape[1] else np.eye(m)
    rest = np.linalg.eigvals(w.T @ a @ w) if w.shape[1] else np.zeros(0, dtype=complex)
    neutral = np.linalg.eigvals(q.T @ a @ q) if q.shape[1] else np.zeros(0, dtype=complex)
    order = np.argsort(-np.abs(rest), kind="stable")
    return Multipliers(multipliers=rest[order].astype(complex),
                       neutral=neutral.astype(complex), neutral_names=tuple(chosen))


# --- Newton shooting -----------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True, eq=False)
class FreeCycle:
    """A periodic orbit of free bodies, or the attempt: ``point`` on the section, the
    ``layout`` of its coordinates, ``period`` (s: the flight of one period), ``forcing_periods``
    ``m`` (0 unforced), ``strikes``; ``multipliers`` (complex; ``None`` grazing or without a
    return) with the ``neutral`` ones left out and their directions; ``route`` (``saltation``
    or ``finite_difference``) and, from the other route where both reach, ``check``;
    ``stable``, ``residual`` |P(x) - x|, ``converged``, ``iterations``, the ``impacts`` of one
    period, ``energy`` over it (J), ``constraints`` (the struck contacts' names), ``flags``,
    ``guess_time`` (s: when the file's state was not on the section, the time of the first
    impact it was flown to) and ``jacobian`` ``A`` on the tangent space."""

    simulation: Simulation
    layout: Layout
    point: SectionPoint
    period: float
    forcing_period: float | None
    forcing_periods: int
    strikes: int
    multipliers: np.ndarray | None
    neutral: np.ndarray | None
    neutral_names: tuple[str, ...]
    route: str | None
    check: np.ndarray | None
    stable: bool | None
    residual: float
    converged: bool
    iterations: int
    impacts: tuple[Impact, ...]
    energy: dict[str, float]
    constraints: tuple[tuple[str, str], ...]
    flags: tuple[str, ...]
    guess_time: float | None
    jacobian: np.ndarray | None


def touching(sim: Simulation, point: SectionPoint) -> tuple[Feature, ...]:
    """The features touching at ``point`` (gap within the simulator's ``eps``)."""
    feats = features(sim.bodies, sim.planes)
    eps, _ = scales(sim)
    gaps, _ = gaps_and_speeds(feats, sim.bodies, sim.planes, list(point.states))
    return tuple(f for f in feats if abs(gaps[f]) <= eps)


def layout_of(sim: Simulation, ret: Return | None) -> Layout:
    """The section's coordinates for ``sim``: a body's rotation is in them when it turns at
    the start or after any impact of ``ret`` (the guess's return), its orientation only when
    it is not a sphere."""
    turning = []
    for b, s0 in enumerate(sim.initial):
        spin = float(np.linalg.norm(s0.angular_velocity)) > 0.0
        if ret is not None:
            spin = spin or any(float(np.linalg.norm(hit.states[b].angular_velocity)) > 0.0
                               for hit in ret.impacts)  # fmt: skip
        turning.append(spin)
    return Layout(forced=sim.ground is not None, names=tuple(b.name for b in sim.bodies),
                  spins=tuple(turning), orients=tuple(
                      t and not isinstance(b.shape, Sphere) for t, b in zip(
                          turning, sim.bodies, strict=True)))  # fmt: skip


def find_cycle(sim: Simulation, *, strikes: int = 1, tolerance: float = 1e-11,
               check: bool = False) -> FreeCycle:  # fmt: skip
    """A periodic orbit through ``strikes`` impacts by Newton shooting from the scenario's
    state (a guess; flown to its first impact if not just after one), its multipliers by
    saltation where that route reaches (else by finite differences; ``check``: both).

    >>> from carnot.simulate import load_simulation
    >>> sim = load_simulation("examples/simulate/ball_on_vibrating_table.toml")
    >>> c = find_cycle(sim)
    >>> c.converged, c.stable, c.route, c.forcing_periods, len(c.multipliers)
    (True, True, 'saltation', 1, 2)
    """
    period_t = forcing_period(sim)
    if not features(sim.bodies, sim.planes):
        raise InputError("bodies", "can strike nothing (no plane and no pair of bodies that "
                         "can meet): no impact, no section", show_value=False)  # fmt: skip
    point = SectionPoint(time=0.0, states=tuple(sim.initial))
    guess_time = None
    try:
        if not touching(sim, point):
            first = return_map(sim, point, 1)
            point, guess_time = first.point, first.point.time
        ret = return_map(sim, point, strikes)
    except ReturnFailed as err:
        return _failed(sim, point, strikes, period_t, guess_time, str(err))
    layout = layout_of(sim, ret)
    x_norm = float(np.linalg.norm(vector(point, layout)))
    shift = periods_of(ret.flight, period_t) * (period_t or 0.0)
    r = residual_vector(ret, point, layout, shift)
    residual = float(np.linalg.norm(r))
    iterations = 0
    basis = jac = None
    while True:
        struck = touching(sim, point) or ret.struck
        basis = tangent_basis(sim, layout, point, struck)
        try:
            jac = _jacobian(sim, layout, point, ret, basis, strikes, shift)
        except ReturnFailed:  # a neighbour does not return as this point does
            jac = None
        if jac is None or residual <= tolerance * max(1.0, x_norm) or iterations >= MAX_NEWTON:
            break
        iterations += 1
        a = basis.T @ jac
        step = np.linalg.lstsq(a - np.eye(a.shape[0]), -(basis.T @ r), rcond=1e-10)[0]
        alpha = 1.0
        for _ in range(MAX_HALVINGS):
            trial = displace(point, layout, alpha * (basis @ step))
            try:
                new = return_map(sim, trial, strikes)
            except ReturnFailed:
                alpha /= 2
                continue
            new_shift = periods_of(new.flight, period_t) * (period_t or 0.0)
            new_r = residual_vector(new, trial, layout, new_shift)
            if float(np.linalg.norm(new_r)) < residual:
                point, ret, r, shift = trial, new, new_r, new_shift
                residual = float(np.linalg.norm(r))
                x_norm = float(np.linalg.norm(vector(point, layout)))
                break
            alpha /= 2
        else:
            break  # no step lowers the residual: not converged
    converged = residual <= tolerance * max(1.0, x_norm)
    final = return_map(sim, point, strikes, energy=True)
    flags: list[str] = []
    speed = max(math.sqrt(float(np.linalg.norm(sim.gravity)) * max(
        b.shape.size for b in sim.bodies)), max(float(np.linalg.norm(s.velocity))
                                                 for s in point.states), 1e-6)  # fmt: skip
    approach = min((abs(float(np.asarray(c.relative_velocity_before) @ np.asarray(c.normal)))
                    for hit in final.impacts for c in hit.result.contacts), default=math.inf)
    if approach <= GRAZING * speed:
        flags.append("grazing")
    if not converged:
        flags.append("not_converged")
    salt = saltation_jacobian(sim, layout, point, final)
    route = "saltation" if salt is not None else "finite_difference"
    mult = neutral = other = None
    names: tuple[str, ...] = ()
    if jac is None:
        flags.append("not_differentiable")
    if "grazing" not in flags and jac is not None:
        sym, sym_names, cand, cand_names = neutral_candidates(sim, layout)
        primary = salt @ basis if salt is not None else jac
        split = split_multipliers(primary, basis, sym, cand, sym_names + cand_names)
        mult, neutral, names = split.multipliers, split.neutral, split.neutral_names
        if check and salt is not None:
            try:
                fd = finite_difference_jacobian(sim, layout, point, basis, strikes, shift)
                other = split_multipliers(fd, basis, sym, cand,
                                          sym_names + cand_names).multipliers  # fmt: skip
            except ReturnFailed:
                other = None
    stable = None if mult is None or not converged or len(mult) == 0 else bool(
        np.all(np.abs(mult) < 1.0 - UNIT_CIRCLE))  # fmt: skip
    m = periods_of(final.flight, period_t)
    constraints = tuple(feature_names(f, sim.bodies, sim.plane_names) for f in final.struck)
    assert final.energy is not None
    return FreeCycle(simulation=sim, layout=layout, point=point, period=final.flight,
                     forcing_period=period_t, forcing_periods=m, strikes=strikes,
                     multipliers=mult, neutral=neutral, neutral_names=names,
                     route=None if mult is None else route, check=other, stable=stable,
                     residual=residual, converged=converged, iterations=iterations,
                     impacts=final.impacts, energy=final.energy, constraints=constraints,
                     flags=tuple(flags), guess_time=guess_time,
                     jacobian=None if jac is None else basis.T @ jac)  # fmt: skip


def _jacobian(sim: Simulation, layout: Layout, point: SectionPoint, ret: Return,
              basis: np.ndarray, strikes: int, shift: float) -> np.ndarray:  # fmt: skip
    """``DP U`` for Newton: by saltation where it reaches (one return already flown), else
    by finite differences."""
    salt = saltation_jacobian(sim, layout, point, ret)
    if salt is not None:
        return salt @ basis
    return finite_difference_jacobian(sim, layout, point, basis, strikes, shift)


def _failed(sim: Simulation, point: SectionPoint, strikes: int, period_t: float | None,
            guess_time: float | None, why: str) -> FreeCycle:  # fmt: skip
    layout = layout_of(sim, None)
    nan = float("nan")
    return FreeCycle(simulation=sim, layout=layout, point=point, period=nan,
                     forcing_period=period_t, forcing_periods=0, strikes=strikes,
                     multipliers=None, neutral=None, neutral_names=(), route=None, check=None,
                     stable=None, residual=math.inf, converged=False, iterations=0, impacts=(),
                     energy={"impacts": nan, "sliding": nan, "ground_work": nan,
                             "residual": nan},
                     constraints=(), flags=("not_converged", "no_return"), guess_time=guess_time,
                     jacobian=None)  # fmt: skip

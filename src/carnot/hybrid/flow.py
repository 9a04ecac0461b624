"""The flow between impacts and the strike: integrate ``M q'' + h = 0`` until a guard is
crossed, then solve the strike as one impact (DESIGN.md section 10).

The flow is integrated by the Dormand-Prince method of order 8 (DOP853: explicit Runge-Kutta,
an error estimate of orders 5 and 3, a dense output of order 7) at relative and absolute
tolerance ``TOLERANCE``, by two steppers of SciPy's that take the same method's steps:

* the *compiled* one, Hairer's DOP853 (``scipy.integrate.ode``), takes the steps: a callback
  after each accepted step evaluates the watched functions at its end, and stops the
  integrator at the first step in which one of them crosses zero in its direction. It has no
  dense output, but its loop is compiled: a walker's step costs ~60 us less per Runge-Kutta
  step than the Python loop of SciPy's ``DOP853`` class, most of a leg's time where the flow
  itself is one compiled call (~1.4 us);
* the *dense* one, SciPy's ``DOP853`` class, takes that step again from its start (the same
  size first) and locates the crossing on the step's dense output, the root of ``G(x(t))``
  by Brent's method to a few units of round-off in time (as ``solve_ivp`` locates its
  events). The loop over its steps is carnot's own, not ``solve_ivp``'s, so that an arming
  (mid-stance) inside a step arms the strike for the rest of that same step. Where the event
  lets the leg go on (an arming), the compiled stepper takes over again from that step's end.

An event that goes on is not located at all where nothing could follow it in the step: every
function watched after it is still short of its crossing at the step's end (strictly), so the
dense route's search of the rest of the step would find nothing either. The two routes agree
to the integrator's tolerance (their step-size controllers differ in detail, not in order or
tolerance); ``fly(..., compiled=False)`` takes the dense route alone, as does a leg flown
from inside another's callback (SciPy's compiled integrator holds one call per thread). A
failure of the compiled stepper (too small a step, its stiffness test) hands the rest of the
leg to the dense one, which raises where it fails too.

Only armed guards are watched, and only their crossings in the stated
direction. A state that starts on a guard's surface, leaving it (a rimless wheel rocking back
off the spoke it just struck with), is watched for the guard's rate ``G' = D_x G f`` turning
back first: the root at the start is never found again, and the return is.

Contacts held closed (:class:`Hold`: a joint at its stop, a point on its plane, a pair of
MJCF geoms on its contact points, each sticking or sliding) constrain the flow through their
gap rows (:func:`held_solution`, :func:`held_flow`); their forces are watched, each change
(``release``, ``slip_start``, ``stick``, a held pair's next point striking: ``join``) a
root on the dense output as for a guard; a slide's stop, where the held flow is not smooth,
is then found again on the flow itself (:func:`_polish`). Where the held flow's steps fall
below round-off (a sliding point's normal force without bound) the leg ends ``singular``.
Where the model has dampers or a hold slides, the work they take is integrated beside the
state (two more components; none otherwise, so that the other models' steps are the
same).

With ``variational=True`` the linearization ``Phi' = A(x) Phi``, ``A = d flow / d x`` (exact,
from the mechanism's symbolic derivatives; an MJCF model's by central differences; with
contacts held, the held flow's by central differences, :func:`held_flow_jacobian`), is
integrated beside the state: ``Phi(t)`` is the flow's Jacobian ``d x(t) / d x(t0)``, from
which saltation matrices build the monodromy. Both are in the tangent chart
(:func:`carnot.hybrid.model.tangent_step`, ``2 n x 2 n``; ``x + dx`` where ``nq == n``): an
MJCF model's free or ball joint perturbs its quaternion on its sphere.
"""

from __future__ import annotations

import math
import threading
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from carnot.hybrid.model import GapRows, Guard, HybridModel

#: The integrator's relative and absolute tolerance.
TOLERANCE = 1e-12
#: The largest time one leg of the flow may take (s), against a walker that never strikes.
MAX_FLIGHT = 1e3
EPS = float(np.finfo(float).eps)


@dataclass(frozen=True, kw_only=True, eq=False)
class Leg:
    """The flow from ``t0`` to ``t1`` (s): the state there ``x1``, ``phi`` (the flow's
    Jacobian, with ``variational``), and why it ended: ``guard`` (the strike's guard),
    ``"fall"``, ``"end"`` (the time limit), a hold's ``"release"``, ``"slip_start"``,
    ``"stick"`` or ``"drift"`` (:func:`held_drift`; ``guard`` the held one), or
    ``"singular"`` (the flow with contacts held could not go on: its steps fell below
    round-off); ``evaluations``: the flow's, by both steppers (module docstring);
    ``damping`` and ``sliding``: the work the dampers and the sliding holds' friction took
    over the leg (J, >= 0); ``from_rest``: a ``"stick"`` that ends a slide from rest which
    turned back before its speed had left zero by ``SLIDE_START`` (not a slide's stop)."""

    t0: float
    t1: float
    x1: np.ndarray
    phi: np.ndarray | None
    ended: str
    guard: Guard | None
    evaluations: int
    damping: float = 0.0
    sliding: float = 0.0
    from_rest: bool = False


@dataclass(frozen=True, kw_only=True)
class Hold:
    """A guard held closed in the flow: ``index`` (in the model's guards), ``points`` (how
    many of the guard's contact points are held: those with the smallest gaps; 1 for a point
    on a plane or a joint's stop) and ``slip``: 0 sticking (the gap's rows held, and the
    tangents' where the points can slide), +1 or -1 sliding, each point's tangent rows then
    carrying Coulomb's force ``-mu F_n d`` against its slip direction ``d``
    (:func:`slide_direction`). ``direction`` gives each point's reference direction ``u``
    in its tangent coordinates (unit k-vectors, k = 2 in space; ``()``: one tangent row,
    ``u = slip``, the plane's ``+t`` or ``-t``): the slide that the hold started with, which
    ``d`` follows as the slip velocity turns; in space a point whose ``direction`` is empty
    sticks while the others slide. ``anchors``, where the guard's points have
    labels (:class:`~carnot.hybrid.model.GapRows`), are the held points' labels when the
    hold began: each held point is the one nearest its anchor (a box's corner), so that a
    point closing beside them is told apart from them however small the gaps. A joint's stop
    holds its one row (frictionless)."""

    index: int
    slip: int = 0
    direction: tuple[tuple[float, ...], ...] = ()
    points: int = 1
    anchors: tuple[tuple[float, ...], ...] = ()

    def reference(self, i: int) -> np.ndarray:
        """The ``i``-th point's reference slip direction ``u`` (tangent coordinates)."""
        if not self.direction:
            return np.array([float(self.slip)])
        return self.slip * np.asarray(self.direction[i], dtype=float)

    def slides(self, i: int) -> bool:
        """Whether the ``i``-th point slides (in space each point has its own regime: an
        empty ``direction[i]`` sticks, the box pivoting on a corner while the others
        slide)."""
        return bool(self.slip) and (not self.direction or len(self.direction[i]) > 0)


def gap_rows(model: HybridModel, guard: Guard, x: np.ndarray) -> GapRows | tuple[GapRows, ...]:
    """The held guard's rows at ``x``: a stop's ``limit_row`` (its gap linear in the chart:
    no bias, no tangent), or the guard's own ``rows`` (one point, or a tuple of points)."""
    if guard.limit_row is not None:
        q = x[: model.nq]
        return GapRows(normal=np.asarray(guard.limit_row) @ model.mechanism.embed_jacobian(q))
    if guard.rows is None:
        raise ValueError(f"the guard {guard.name!r} cannot be held in the flow")
    return guard.rows(x)


def contact_points(model: HybridModel, guard: Guard, x: np.ndarray) -> tuple[GapRows, ...]:
    """Every contact point of the guard at ``x`` (:func:`gap_rows` as a tuple)."""
    rows = gap_rows(model, guard, x)
    return rows if isinstance(rows, tuple) else (rows,)


def _held_indices(hold: Hold, points: tuple[GapRows, ...]) -> list[int]:
    """Which of the guard's ``points`` the hold holds: each anchor's nearest point (by
    label, in the anchors' order), or, without anchors, the ``hold.points`` of smallest gap
    in the guard's order."""
    if hold.anchors and points and all(p.label is not None for p in points):
        labels = np.array([p.label for p in points], dtype=float)
        free = np.ones(len(points), dtype=bool)
        out = []
        for anchor in hold.anchors:
            if not free.any():
                break
            offsets = labels - np.asarray(anchor)
            squares = np.where(free, np.einsum("ij,ij->i", offsets, offsets), np.inf)
            near = int(np.argmin(squares))
            free[near] = False
            out.append(near)
        return out
    if len(points) <= hold.points:
        return list(range(len(points)))
    return sorted(int(i) for i in np.argsort([p.gap for p in points], kind="stable")[: hold.points])


def held_points(model: HybridModel, hold: Hold, x: np.ndarray) -> tuple[GapRows, ...]:
    """The points that ``hold`` holds at ``x`` (:func:`_held_indices`)."""
    points = contact_points(model, model.guards[hold.index], x)
    return tuple(points[i] for i in _held_indices(hold, points))


def point_friction(point: GapRows, friction: float | None) -> float | None:
    """A held point's coefficient of friction: the law's ``friction`` where given, else the
    point's own (an MJCF contact's), else ``None`` (a point that sticks whatever the force,
    as the walker papers' feet do)."""
    return friction if friction is not None else point.friction


def slide_direction(u: np.ndarray, v_t: np.ndarray, blend: float) -> np.ndarray:
    """The unit slip direction ``d`` that Coulomb's force opposes, ``F_t = -mu F_n d``, at the
    slip velocity ``v_t`` (m/s, tangent coordinates) of a point sliding with reference ``u``:

        d = w / |w|,     w = sign(u . v_t) v_t + blend u

    which is ``v_t / |v_t|`` while the slip is within 90 degrees of ``u`` (the watch turns
    the reference at 60: :func:`slide_margin`), up to ``blend / |v_t|`` (``blend`` is
    ``SLIDE_START`` of the state's scale, 1e-10 m/s or so) where ``v_t`` is not along ``u``.
    With one tangent row ``d = u = slip``: the planar rule. Through the slide's stop
    (``v_t -> 0`` along ``u``) ``d`` stays smooth (the sign turns with ``v_t``), so the flow
    is smooth across the stop, and the stop is a root on the dense output as in the plane.

    >>> slide_direction(np.array([1.0, 0.0]), np.array([3.0, 4.0]), 0.0).tolist()
    [0.6, 0.8]
    >>> slide_direction(np.array([-1.0]), np.array([0.5]), 1e-10).tolist()
    [-1.0]
    """
    w = np.sign(float(u @ v_t)) * v_t + blend * u
    size = float(np.linalg.norm(w))
    return u if size == 0.0 else w / size


#: The tangent of the angle (60 degrees) between a slide's reference and its slip velocity
#: at which the reference is turned to the velocity: ``u . v_t = |v_perp| / tan 60``.
TURN_COTANGENT = 1.0 / np.sqrt(3.0)


def slide_margin(u: np.ndarray, v_t: np.ndarray) -> float:
    """``u . v_t - |v_t - (u . v_t) u| / tan 60`` (m/s): positive while the slip velocity is
    within 60 degrees of the reference ``u``; it falls through zero where the slide stops
    (``v_t -> 0``) or turns past 60 degrees. With one tangent row it is ``s v_t``."""
    along = float(u @ v_t)
    across = float(np.linalg.norm(v_t - along * u)) if v_t.size > 1 else 0.0
    return along - TURN_COTANGENT * across


#: Singular values of the held system below this (relative to its largest) are zero: the
#: held rows are dependent (a box flat on a table: four corners, three independent rows).
RANK_TOLERANCE = 1e-9


@dataclass(frozen=True, eq=False)
class HeldSolution:
    """The held flow at one state: ``flow`` (d x / dt), each hold's points' forces
    ``normal`` (p,) and ``tangent`` (p x k; k = 0 where a point cannot slide), ``rank`` of
    the held system and ``unique``: whether the motion is determined (the system's null
    space has no part in ``q''``: the forces are then not unique where rows are dependent,
    and carnot takes those of least norm); ``rows`` the held rows (one per constraint held
    at the acceleration level: each point's normal, and its tangents where it sticks);
    ``solution`` the system's solution ``(q'', forces)``, ``basis`` its null space
    (orthonormal columns) and ``normal_at`` each hold's normal forces' places in it."""

    flow: np.ndarray
    normal: tuple[np.ndarray, ...]
    tangent: tuple[np.ndarray, ...]
    rank: int
    unique: bool
    rows: np.ndarray
    solution: np.ndarray
    basis: np.ndarray
    normal_at: tuple[tuple[int, ...], ...]
    _support: dict[int, float] = field(default_factory=dict, repr=False)

    def support(self, j: int) -> float:
        """The ``j``-th hold's margin of support (N): its least normal force where its forces
        are unique, else the most that its least normal force can be among the forces that
        give the same accelerations (:func:`support_margin`): zero where no pushing forces
        hold it any longer (a box tipping over an edge)."""
        if j not in self._support:
            at = list(self.normal_at[j])
            self._support[j] = (support_margin(self.solution, self.basis, at) if
                                self.basis.size else float(np.min(self.solution[at])) if at
                                else 0.0)  # fmt: skip
        return self._support[j]


_LAST: list[Any] = [None, None]  # the last held solution: its key, and it


def held_solution(model: HybridModel, held: tuple[Hold, ...], x: np.ndarray,
                  friction: float | None = None) -> HeldSolution:  # fmt: skip
    """The flow with the guards ``held`` closed, and their points' forces (N, or N m at a
    joint):

        M q'' = -h + sum_i (J_n,i - mu_i d_i^T J_t,i)^T F_n,i + J_t,i^T F_t,i
        J_n,i q'' + b_n,i = 0,   J_t,i q'' + b_t,i = 0 where i sticks

    over every held point ``i`` (``b`` the rows' biases: the gap's and the slide's
    acceleration stay zero; a sliding point carries ``F_t = -mu F_n d`` on its tangent rows
    instead of holding them, ``d`` its :func:`slide_direction`, ``mu`` its
    :func:`point_friction`). ``F_n >= 0`` pushes the point off its surface (the joint off its
    stop); the hold ends where it would pull. The system is solved through its singular value
    decomposition, rank found at ``RANK_TOLERANCE``: where the held rows are dependent (more
    rows than the chart can honour: four corners of a box flat on a table) the forces are not
    unique, and those of least norm are taken; the motion is unique when no null vector of
    the system moves ``q''`` (``unique``)."""
    key = (model, held, friction, np.asarray(x, dtype=float).tobytes())
    if _LAST[0] is not None and _LAST[0][0] is model and _LAST[0][1:] == key[1:]:
        return _LAST[1]
    n = model.n
    q, qd = x[: model.nq], x[model.nq :]
    rows: list[np.ndarray] = []  # the held rows (acceleration constraints)
    forces: list[np.ndarray] = []  # the directions of each unknown force, in the chart
    biases: list[float] = []
    # each point's (normal unknown, tangent unknowns, -mu d where it slides)
    where: list[list[tuple[int, list[int], np.ndarray | None]]] = []
    blend = _slide_scale(x)
    for hold in held:
        here: list[tuple[int, list[int], np.ndarray | None]] = []
        for i, r in enumerate(held_points(model, hold, x)):
            k = len(forces)
            rows.append(r.normal)
            biases.append(r.normal_bias)
            tangents = r.tangents()
            if tangents is None:
                forces.append(r.normal)
                here.append((k, [], None))
            elif hold.slides(i):
                rows_t = tangents[0]
                mu = point_friction(r, friction) or 0.0
                d = slide_direction(hold.reference(i), rows_t @ qd, blend)
                forces.append(r.normal - mu * d @ rows_t)
                here.append((k, [], -mu * d))
            else:
                rows_t, bias_t = tangents
                forces += [r.normal, *rows_t]
                rows += list(rows_t)
                biases += [float(b) for b in bias_t]
                here.append((k, list(range(k + 1, k + 1 + len(rows_t))), None))
        where.append(here)
    m = model.mechanism.mass(q)
    k = len(rows)
    kkt = np.zeros((n + k, n + k))
    kkt[:n, :n] = m
    kkt[:n, n:] = -np.array(forces).T
    kkt[n:, :n] = np.array(rows)
    rhs = np.concatenate([-model.mechanism.bias(q, qd), -np.array(biases)])
    u_, s_, vt = np.linalg.svd(kkt)
    rank = int(np.sum(s_ > RANK_TOLERANCE * s_[0]))
    normal_at = tuple(tuple(n + kn for kn, _, _ in here) for here in where)  # the F_n unknowns
    basis = vt[rank:].T
    if rank == n + k:  # independent rows: the one solution (by LU, as before several points)
        sol = np.linalg.solve(kkt, rhs)
    else:  # the least-norm forces, made to push where they can
        sol = vt[:rank].T @ ((u_[:, :rank].T @ rhs) / s_[:rank])
        sol = least_distance(sol, basis, [i for at in normal_at for i in at])
    null = vt[rank:, :n]
    unique = not null.size or float(np.max(np.abs(null))) <= 1e3 * RANK_TOLERANCE
    lam = sol[n:]
    normal, tangent = [], []
    for point_unknowns in where:
        f_n = np.array([lam[kn] for kn, _, _ in point_unknowns])
        width = max((len(kt) if c is None else c.size for _, kt, c in point_unknowns),
                    default=0)  # fmt: skip
        f_t = np.zeros((len(point_unknowns), width))
        for i, (kn, kt, coulomb) in enumerate(point_unknowns):
            if coulomb is not None:
                f_t[i] = coulomb * lam[kn]
            elif kt:
                f_t[i] = lam[kt]
        normal.append(f_n)
        tangent.append(f_t)
    out = HeldSolution(flow=np.concatenate([model.mechanism.position_rate(q, qd), sol[:n]]),
                       normal=tuple(normal), tangent=tuple(tangent), rank=rank,
                       unique=unique, rows=np.array(rows).reshape(k, n), solution=sol,
                       basis=basis, normal_at=normal_at)  # fmt: skip
    _LAST[:] = [key, out]
    return out


def least_distance(sol: np.ndarray, basis: np.ndarray, normal: list[int]) -> np.ndarray:
    """The solution nearest ``sol`` (the least-norm one) in ``sol + basis z`` (the null space
    of the held system, orthonormal columns) whose normal forces ``normal`` (indices) are all
    ``>= 0``: ``min |z|`` subject to ``G z >= h``, ``G = basis[normal]``, ``h = -sol[normal]``,
    a least-distance programme solved by non-negative least squares (Lawson and Hanson,
    *Solving Least Squares Problems*, 1974, chapter 23: ``u >= 0`` minimizing
    ``|[G^T; h^T] u - e_(d+1)|``, then ``z = -r[:d] / r[d]`` from its residual ``r``).
    ``sol`` itself where its normal forces push already, or where no such solution exists.

    >>> sol = np.array([3.0, -1.0])  # two forces, one unknown combination (1, 1) / sqrt 2
    >>> least_distance(sol, np.array([[1.0], [1.0]]) / np.sqrt(2), [0, 1]).round(12).tolist()
    [4.0, 0.0]
    """
    from scipy.optimize import nnls

    if not basis.size or not normal or float(np.min(sol[normal])) >= 0.0:
        return sol
    g, h = basis[normal], -sol[normal]
    d = basis.shape[1]
    e = np.vstack([g.T, h[None, :]])
    f = np.zeros(d + 1)
    f[-1] = 1.0
    u, _ = nnls(e, f)
    r = e @ u - f
    if abs(float(r[-1])) <= 1e-12:  # infeasible: no pushing forces give these accelerations
        return sol
    return np.asarray(sol + basis @ (-r[:d] / r[-1]), dtype=float)


def support_margin(sol: np.ndarray, basis: np.ndarray, normal: list[int]) -> float:
    """``max over z of min_i (sol + basis z)[normal_i]`` (N): the most that the least of the
    normal forces ``normal`` can be among the held system's solutions (a linear programme,
    by SciPy's HiGHS; ``z`` bounded by a thousand times the forces' size, where antagonistic
    points could push without bound). Positive while pushing forces can hold the points; it
    falls through zero where none can (the release of a pair held on several points)."""
    from scipy.optimize import linprog

    if not normal:
        return 0.0
    lowest = float(np.min(sol[normal]))
    g = basis[normal]
    if not g.size or not np.any(np.abs(g) > RANK_TOLERANCE):
        return lowest
    d = basis.shape[1]
    bound = 1e3 * max(1.0, float(np.max(np.abs(sol[normal]))))
    # variables (z, s): maximize s subject to s - g z <= sol[normal]
    a_ub = np.hstack([-g, np.ones((len(normal), 1))])
    res = linprog(np.concatenate([np.zeros(d), [-1.0]]), A_ub=a_ub, b_ub=sol[normal],
                  bounds=[(-bound, bound)] * d + [(None, None)], method="highs")  # fmt: skip
    return float(-res.fun) if res.status == 0 else lowest


def held_flow(model: HybridModel, held: tuple[Hold, ...], x: np.ndarray,
              friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The flow with the guards ``held`` closed (:func:`held_solution`), and each hold's
    force ``(F_n, F_t)``: its points' normal forces summed, and their tangential force, signed
    along ``t`` where the hold is one point with one tangent row (a point on a plane in a
    planar model), else the magnitude of the points' tangential forces summed."""
    sol = held_solution(model, held, x, friction)
    out = np.zeros((len(held), 2))
    for j, (f_n, f_t) in enumerate(zip(sol.normal, sol.tangent, strict=True)):
        out[j, 0] = float(np.sum(f_n))
        if f_t.shape[1] == 1 and len(f_n) == 1:
            out[j, 1] = float(f_t[0, 0])
        elif f_t.size:
            out[j, 1] = float(np.linalg.norm(np.sum(f_t, axis=0)))
    return sol.flow, out


#: The relative step of the held flow's central differences (:func:`held_flow_jacobian`).
HELD_FLOW_STEP = 1e-5
#: With contacts held, the flow's Jacobian is integrated scaled by this (:func:`fly`): its
#: error is held to ``TOLERANCE / PHI_SCALE``, above the noise of the held field's Jacobian
#: (:func:`held_flow_jacobian`), where at ``TOLERANCE`` the steps would shrink to chase it
#: (a rimless wheel's linearized return took more than 10 min, 1.5 s so).
PHI_SCALE = 1e-4


def held_flow_jacobian(model: HybridModel, held: tuple[Hold, ...], x: np.ndarray,
                       friction: float | None = None) -> np.ndarray:  # fmt: skip
    """``A_h = d f_h / d x`` (2n x 2n, ``nq == n``) of the held flow ``f_h`` (the flow of
    :func:`held_solution`, the holds' regimes fixed), by central differences: column ``j``
    is ``(f_h(x + h e_j) - f_h(x - h e_j)) / 2 h``, ``h = HELD_FLOW_STEP max(1, |x_j|)``.

    Differences, not symbols: the held flow solves the held system at each state, with the
    rows and their biases of MuJoCo's contacts (an MJCF pair's, themselves central
    differences along the flow) or of a compiled mechanism's points, and neither gives its
    derivative in closed form; an MJCF model's free flow is differenced the same way
    (:meth:`carnot.hybrid.mjcf.MujocoMechanism.flow_jacobian`). The truncation is
    ``O(h^2)`` (1e-10 of the field's third derivative), the round-off ``eps |f_h| / h``
    (1e-11), and the rows' biases' own round-off (an MJCF pair's, ``eps / HOLD_STEP``,
    1e-13) divided by ``h``: ``A_h`` to about 1e-8 (a rimless wheel's multiplier to 2e-7
    at h = 1e-6, 1e-5 and 1e-4 alike: tests/test_hybrid_mjcf_cycle.py). Off the held
    contacts' manifold (a gap, or a held row's velocity, not zero) ``f_h`` is the same
    system's solution, so that ``A_h`` is that of a smooth field on a neighbourhood, whose
    flow keeps the manifold.

    >>> from carnot.hybrid.models import named_model
    >>> leg = named_model("hopping_leg")  # the foot held on the ground: y_foot'' = 0
    >>> a = held_flow_jacobian(leg, (Hold(index=0),), np.array([0.45, 0.0, 0.0, 0.0]))
    >>> [round(float(v), 6) for v in a[3]], round(float(a[2, 0]), 3)  # (k = 1e4 N/m, M = 10 kg)
    ([0.0, 0.0, 0.0, 0.0], -1000.0)
    """
    if model.nq != model.n:
        raise ValueError("the held flow's Jacobian is built where nq == n only")
    x = np.asarray(x, dtype=float)
    n2 = x.size
    out = np.zeros((n2, n2))
    for j in range(n2):
        h = HELD_FLOW_STEP * max(1.0, abs(float(x[j])))
        up, down = x.copy(), x.copy()
        up[j] += h
        down[j] -= h
        out[:, j] = (held_solution(model, held, up, friction).flow
                     - held_solution(model, held, down, friction).flow) / (2 * h)  # fmt: skip
    return out


def held_margins(model: HybridModel, held: tuple[Hold, ...], j: int, x: np.ndarray,
                 friction: float | None) -> tuple[float, float]:  # fmt: skip
    """The ``j``-th hold's margins at ``x``: its support (N, ``HeldSolution.support``: its
    points' least normal force ``min F_n,i`` where the forces are unique; the hold is
    released where it falls through zero) and its sticking points' least cone margin
    ``min (mu_i F_n,i - |F_t,i|)`` (N; a sticking point slips where it falls through zero;
    ``inf`` where no sticking point has a cone)."""
    sol = held_solution(model, held, x, friction)
    points = held_points(model, held[j], x)
    f_n, f_t = sol.normal[j], sol.tangent[j]
    cone = np.inf
    for i, r in enumerate(points):
        mu = point_friction(r, friction)
        if mu is not None and r.tangent is not None and not held[j].slides(i):
            cone = min(cone, mu * float(f_n[i]) - float(np.linalg.norm(f_t[i])))
    return sol.support(j), cone


def has_cone(model: HybridModel, hold: Hold, x: np.ndarray, friction: float | None) -> bool:
    """Whether any held point of ``hold`` can slide with friction (has tangent rows and a
    coefficient)."""
    guard = model.guards[hold.index]
    if guard.limit_row is not None:
        return False
    return any(r.tangent is not None and point_friction(r, friction) is not None
               for r in held_points(model, hold, x))  # fmt: skip


def sliding_power(model: HybridModel, held: tuple[Hold, ...], x: np.ndarray,
                  friction: float | None) -> float:  # fmt: skip
    """The power the sliding holds' friction takes at ``x``, ``-sum_i F_t,i . v_t,i`` (W,
    >= 0)."""
    sol = held_solution(model, held, x, friction)
    qd = x[model.nq :]
    power = 0.0
    for j, hold in enumerate(held):
        if not hold.slip:
            continue
        for i, r in enumerate(held_points(model, hold, x)):
            tangents = r.tangents()
            if tangents is not None and sol.tangent[j].shape[1] and hold.slides(i):
                power -= float(sol.tangent[j][i] @ (tangents[0] @ qd))
    return power


Watched = tuple[Callable[[np.ndarray], float], int, str, int]
#: The events that change what a leg watches and let it go on: an arming, a guard's rate
#: turning back, a slide's start. Every other kind ends the leg.
GOES_ON = frozenset({"arm", "turn", "slide", "join_turn"})
#: The compiled stepper's limit on steps in one call (none, in effect: a leg is bounded by
#: ``MAX_FLIGHT``, as the dense stepper's is).
MAX_STEPS = 10**9

# SciPy's compiled DOP853 keeps the callbacks of the call in progress per thread, and a
# second call from inside a callback (a guard that flies a model itself) would overwrite
# them: such a nested leg takes the dense route only.
_COMPILED = threading.local()


def fly(model: HybridModel, x0: np.ndarray, t0: float, t_end: float, *,
        variational: bool = False, tolerance: float = TOLERANCE,
        held: tuple[Hold, ...] = (), friction: float | None = None,
        compiled: bool = True) -> Leg:  # fmt: skip
    """Integrate from ``(t0, x0)`` until a guard strikes (armings in between re-arm and go
    on), the model falls, a held contact or stop releases (``ended = "release"``, ``guard``
    the held one), a sticking hold's force leaves the cone of ``friction``
    (``"slip_start"``), a sliding one's slide stops (``"stick"``), a stance foot's force
    would pull (``"lift"``) or leave the cone (``"slip"``; ``None``: the foot sticks
    whatever the force), or ``t_end``.

    Beside the state, where the model has dampers or a hold slides, the work they take is
    integrated (``Leg.damping``: ``int sum c l'^2 dt``; ``Leg.sliding``:
    ``int sum mu F_n s v_t dt``, ``v_t = J_t q'``), J.

    ``compiled=False`` takes every step with the dense stepper (the second route: the same
    events, to the integrator's tolerance; module docstring).

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8, "slope": 0.08})
    >>> leg = fly(wheel, np.array([0.08 - np.pi / 8, 1.0]), 0.0, 10.0)
    >>> leg.ended, round(float(leg.x1[0]), 12) == round(0.08 + np.pi / 8, 12)
    ('next_spoke', True)
    """
    n2 = model.nq + model.n
    m2 = 2 * model.n  # Phi's size: the tangent chart's (carnot.hybrid.model.tangent_step)
    mech = model.mechanism
    damping = getattr(mech, "damping_power", None)
    sliding = [j for j, h in enumerate(held) if h.slip]
    quad = 2 if damping is not None or sliding else 0  # the works' slots after the state
    # with contacts held, Phi is integrated as PHI_SCALE Phi: the same linear equation, its
    # error held to TOLERANCE / PHI_SCALE (1e-8) where the state's is TOLERANCE (the held
    # field's Jacobian, central differences, is smooth to about 1e-7 only: held_flow_jacobian)
    phi_scale = PHI_SCALE if held else 1.0
    if held and variational and model.nq != model.n:
        raise ValueError("the held flow's linearization is built where nq == n only (no free "
                         "or ball joint)")

    def state_rate(x: np.ndarray) -> np.ndarray:
        if not held:
            return mech.flow(x) if not quad else np.concatenate([mech.flow(x), _works(x)])
        f = held_solution(model, held, x, friction).flow
        if not quad:
            return f
        works = _works(x)
        if sliding:  # the friction's power: -F_t . v_t = mu F_n d . v_t >= 0
            works[1] = sliding_power(model, held, x, friction)
        return np.concatenate([f, works])

    def _works(x: np.ndarray) -> np.ndarray:
        return np.array([0.0 if damping is None else damping(x), 0.0])

    calls = [0]  # the flow's evaluations, by both steppers
    fast = None  # the free flow on floats, which the compiled stepper calls itself
    if variational:

        def rhs(t: float, y: np.ndarray) -> Any:
            calls[0] += 1
            x = y[:n2]
            phi = y[n2 + quad :].reshape(m2, m2)
            a = (held_flow_jacobian(model, held, x, friction) if held
                 else mech.flow_jacobian(x))  # fmt: skip
            return np.concatenate([state_rate(x), (a @ phi).ravel()])

        y = np.concatenate([x0, np.zeros(quad), phi_scale * np.eye(m2).ravel()])
    elif held or quad:

        def rhs(t: float, y: np.ndarray) -> Any:
            calls[0] += 1
            return state_rate(y[:n2])

        y = np.concatenate([np.asarray(x0, dtype=float), np.zeros(quad)])
    elif (on_floats := getattr(mech, "flow_on_floats", None)) is not None:
        # the free flow, one compiled call on the state's floats: the integrator's inner loop
        # (a walker's step). Its list goes to the integrators as it is (both make their own
        # array of it: mech.flow's two arrays were 0.8 us of its 1.9)

        def rhs(t: float, y: np.ndarray) -> Any:
            calls[0] += 1
            return on_floats(*y.tolist())

        y = np.array(x0, dtype=float)
        fast = on_floats
    else:  # the free flow (a mechanism without its flow in closed form)

        def rhs(t: float, y: np.ndarray) -> Any:
            calls[0] += 1
            return mech.flow(y)

        y = np.array(x0, dtype=float)
    watch = _Watch(model, held, friction, np.asarray(x0, dtype=float), n2)
    t_stop = min(t_end, t0 + MAX_FLIGHT)
    t_old, y_old, step = t0, y, None
    while True:
        until = np.inf  # the dense stepper goes on to the end
        if compiled and not getattr(_COMPILED, "busy", False):
            run = _compiled_steps(rhs, t_old, y_old, t_stop, step, tolerance, watch,
                                  on_floats=fast, calls=calls)  # fmt: skip
            if run.why == "end":
                return _leg(t0, _Stop(t_stop, run.y, "end", -1), model, held, n2, quad,
                            variational, calls[0], phi_scale)  # fmt: skip
            t_old, y_old, step = run.t, run.y, run.step
            compiled = run.why == "crossed"  # (else it failed: the dense stepper goes on)
            until = run.t + (run.step or 0.0) if compiled else np.inf
            if step is not None:  # (a last step may end an ulp past t_stop)
                step = min(step, t_stop - t_old)
        try:
            out = _dense_steps(rhs, t_old, y_old, t_stop, step, tolerance, watch, until)
        except FlowFailure as failure:
            if not held or variational:
                raise
            # with contacts held: the held system grew singular (a sliding point's normal
            # force without bound, Painleve's paradox), the leg ends where the steps failed
            out = _Stop(failure.t, failure.y, "singular", -1)
        if isinstance(out, _Stop):
            leg = _leg(t0, out, model, held, n2, quad, variational, calls[0], phi_scale)
            if out.kind == "stick" and not watch.started[out.k]:
                leg = replace(leg, from_rest=True)
            return leg
        t_old, y_old, step = out


class FlowFailure(RuntimeError):
    """The dense stepper could not go on (its step below the spacing of the numbers at
    ``t``, the vector there ``y``)."""

    def __init__(self, message: str, *, t: float, y: np.ndarray) -> None:
        super().__init__(message)
        self.t, self.y = t, y


@dataclass(frozen=True)
class _Stop:
    """Where a leg ends: the time ``t``, the integrated vector ``y`` there, the event's
    ``kind`` and its index ``k`` (a guard's, or a hold's position)."""

    t: float
    y: np.ndarray
    kind: str
    k: int


class _Watch:
    """What a leg watches, and each watched function's value at the last step's end
    (``values``, by ``(kind, index)``): the armed guards (``armed``), those that must turn
    back first (``turning``), the holds' slides that have started (``started``). The
    functions are built again only when an event that goes on (:data:`GOES_ON`) changes
    them."""

    def __init__(self, model: HybridModel, held: tuple[Hold, ...], friction: float | None,
                 x0: np.ndarray, n2: int) -> None:  # fmt: skip
        self.model, self.held, self.friction, self.n2 = model, held, friction, n2
        held_index = {h.index for h in held}
        self.armed = [g.arming is None and k not in held_index
                      for k, g in enumerate(model.guards)]  # fmt: skip
        # a guard that the leg starts on, moving off it, must turn back (its rate
        # G' = D_x G f crossing zero) before it can strike: else the root at t0 itself would
        # be found again
        self.turning = [self.armed[k] and _leaving(model, g, x0)
                        for k, g in enumerate(model.guards)]  # fmt: skip
        # a slide that starts from rest (a stick leaving its cone) is watched for stopping
        # only once its speed has left zero by SLIDE_START; before that, for turning back
        self.scale = _slide_scale(x0) if held else 0.0
        self.started = [abs(_slide_speed(model, h, x0)) > self.scale for h in held]
        self.x0 = x0
        # a held pair's next point that the leg starts on, leaving (just struck, bouncing):
        # its normal speed must turn back first, as a guard's rate does
        self.leaving = [_next_leaving(model, h, x0) for h in held]
        self._functions: list[Watched] | None = None
        self.values: dict[tuple[str, int], float] = {}

    def functions(self) -> list[Watched]:
        if self._functions is None:
            self._functions = _watched(self.model, self.armed, self.turning, self.n2,
                                       self.friction) + _held_watch(
                self.model, self.held, self.friction, self.started, self.scale,
                self.x0, self.leaving)  # fmt: skip
        return self._functions

    def ends(self, y: np.ndarray) -> dict[tuple[str, int], float]:
        """Each watched function at ``y``."""
        x = y[: self.n2]
        return {(kind, k): fn(x) for fn, _, kind, k in self.functions()}

    def crossed(self, y_old: np.ndarray, y: np.ndarray
                ) -> tuple[dict[tuple[str, int], float], list[Watched]]:  # fmt: skip
        """Each watched function at ``y`` (:meth:`ends`), and those that cross zero in their
        direction from the step's start (their ``values``, or their value at ``y_old`` where
        newly watched) to there: one pass, at every step's end."""
        x = y[: self.n2]
        ends: dict[tuple[str, int], float] = {}
        out = []
        values = self.values
        for w in self.functions():
            fn, direction, kind, k = w
            g = ends[(kind, k)] = fn(x)
            g_old = values.get((kind, k))
            if g_old is None:
                g_old = fn(y_old[: self.n2])
            if (g_old < 0 <= g) if direction > 0 else (g_old > 0 >= g):  # (_crosses)
                out.append(w)
        return ends, out

    def go_on(self, kind: str, k: int) -> None:
        """The event ``kind`` (in :data:`GOES_ON`) of the guard or hold ``k``."""
        if kind == "turn":
            self.turning[k] = False
        elif kind == "join_turn":
            self.leaving[k] = False
        elif kind == "slide":
            self.started[k] = True
        else:
            self.armed[k] = True
        self._functions = None

    def passes(self, kind: str, k: int, y: np.ndarray) -> bool:
        """Whether the step that ends at ``y``, in which only ``kind`` (in :data:`GOES_ON`)
        of ``k`` crossed, can go on without locating it: after it, every watched function
        is still short of its crossing at ``y`` (strictly), so that none could be found
        between the event and the step's end (the dense route's search would find none).
        If so the watch is changed and ``values`` set; else both are left as they were."""
        before = (list(self.armed), list(self.turning), list(self.started), list(self.leaving),
                  self._functions)  # fmt: skip
        self.go_on(kind, k)
        ends = self.ends(y)
        if all(_short(direction, ends[(kind_, j)]) for _, direction, kind_, j in
               self.functions()):  # fmt: skip
            self.values = ends
            return True
        self.armed, self.turning, self.started, self.leaving, self._functions = before
        return False


def _crosses(direction: int, g_old: float, g_new: float) -> bool:
    """Whether ``g`` crosses zero in ``direction`` (+1 rising, -1 falling) over a step: from
    strictly before zero to at or past it."""
    return g_old < 0 <= g_new if direction > 0 else g_old > 0 >= g_new


def _short(direction: int, g: float) -> bool:
    """Whether ``g`` is strictly short of a crossing in ``direction``."""
    return g < 0 if direction > 0 else g > 0


@dataclass(frozen=True)
class _Run:
    """The compiled stepper's stop: ``why`` ``"end"`` (it reached the leg's end: ``y``
    there), ``"crossed"`` (a watched function crossed in the step of size ``step`` from
    ``(t, y)``) or ``"failed"`` (``(t, y)`` its last accepted step's end, ``step`` its
    size)."""

    why: str
    t: float
    y: np.ndarray
    step: float | None


def _compiled_steps(rhs: Callable[[float, np.ndarray], Any], t0: float,
                    y0: np.ndarray, t_stop: float, first: float | None, tolerance: float,
                    watch: _Watch, *, on_floats: Callable[..., Any] | None = None,
                    calls: list[int] | None = None) -> _Run:  # fmt: skip
    """Step from ``(t0, y0)`` with SciPy's compiled DOP853 (``scipy.integrate.ode``), the
    watched functions evaluated at each accepted step's end, until one crosses zero in its
    direction (unless only an event that goes on, with nothing that could follow it in the
    step: :meth:`_Watch.passes`), or ``t_stop``. ``first`` is the first step's size
    (``None``: the integrator's own guess). ``on_floats`` (with ``calls``, the count of its
    evaluations): the flow ``rhs`` makes, called here on the state's floats (``rhs``'s own
    frame an evaluation less, a twentieth of a walker's leg)."""
    from scipy.integrate import ode

    last: list[Any] = [t0, y0, first]  # the last accepted step's end and size
    crossed: list[float] = []  # the end of the step in which a function crossed
    raised: list[BaseException] = []
    started: list[bool] = []

    def solout(t: float, y: np.ndarray) -> int:
        if not started:  # (it is called at the start too)
            started.append(True)
            return 0
        try:
            y_new = np.array(y)
            ends, hit = watch.crossed(last[1], y_new)
            if not hit:
                watch.values = ends
            elif not (len(hit) == 1 and hit[0][2] in GOES_ON
                      and watch.passes(hit[0][2], hit[0][3], y_new)):  # fmt: skip
                crossed.append(t)
                return -1
            last[:] = [t, y_new, t - last[0]]
            return 0
        except BaseException as e:  # (kept: SciPy's wrapper does not pass it on)
            raised.append(e)
            return -1

    def flow(t: float, y: np.ndarray) -> Any:
        try:
            return rhs(t, y)
        except BaseException as e:  # SciPy's wrapper replaces it by a ValueError of its own
            raised.append(e)
            raise

    if on_floats is not None and calls is not None:

        def flow(t: float, y: np.ndarray) -> Any:
            calls[0] += 1
            try:
                return on_floats(*y.tolist())
            except BaseException as e:  # (as above)
                raised.append(e)
                raise

    # (the step's growth and cut bounded as the DOP853 class bounds them, 10 and 0.2: with
    # Hairer's own 6 and 0.333 a free sphere's quaternion drifted from unit norm twice as far)
    solver = ode(flow).set_integrator("dop853", rtol=tolerance, atol=tolerance,
                                      nsteps=MAX_STEPS, first_step=first or 0.0,
                                      ifactor=10.0, dfactor=0.2)  # fmt: skip
    solver.set_solout(solout)
    solver.set_initial_value(y0, t0)
    _COMPILED.busy = True
    try:
        with warnings.catch_warnings():  # a failure is read from the return code below
            warnings.simplefilter("ignore")
            solver.integrate(t_stop)
    except BaseException:
        if raised:
            raise raised[0].with_traceback(raised[0].__traceback__) from None
        raise
    finally:
        _COMPILED.busy = False
    if raised:
        raise raised[0].with_traceback(raised[0].__traceback__) from None
    t, y, step = last
    if crossed:
        return _Run(why="crossed", t=t, y=y, step=crossed[0] - t)
    if not solver.successful():
        return _Run(why="failed", t=t, y=y, step=step)
    return _Run(why="end", t=t_stop, y=y, step=step)


def _dense_steps(rhs: Callable[[float, np.ndarray], Any], t_old: float,
                 y_old: np.ndarray, t_stop: float, first: float | None, tolerance: float,
                 watch: _Watch, until: float
                 ) -> _Stop | tuple[float, np.ndarray, float | None]:  # fmt: skip
    """Step from ``(t_old, y_old)`` with SciPy's ``DOP853`` class, each crossing located on
    the step's dense output: the leg's end (a :class:`_Stop`), or, after the first step in
    which an event went on or that reached ``until``, that step's end and size."""
    from scipy.integrate import DOP853

    n2 = watch.n2
    solver = DOP853(rhs, t_old, y_old, t_stop, rtol=tolerance, atol=tolerance,
                    first_step=first)  # fmt: skip
    while True:
        message = solver.step()
        if message is not None:
            raise FlowFailure(f"the integrator stopped at t = {solver.t:g}: {message}",
                              t=float(solver.t), y=np.array(solver.y))  # fmt: skip
        t_new, y_new = solver.t, solver.y
        dense = None
        lo = t_old  # the step's part still to search: each event that goes on moves it on
        while True:
            found: tuple[float, str, int, Callable[[np.ndarray], float]] | None = None
            ends: dict[tuple[str, int], float] = {}
            for fn, direction, kind, k in watch.functions():
                g_old = watch.values.get((kind, k)) if lo == t_old else None
                if g_old is None:  # a function watched from inside this step, or new
                    g_old = fn((dense(lo) if lo > t_old and dense is not None else y_old)[:n2])
                g_new = ends[(kind, k)] = fn(y_new[:n2])
                if _crosses(direction, g_old, g_new):
                    if dense is None:
                        dense = solver.dense_output()
                    root = _root(fn, dense, lo, t_new, n2)
                    if found is None or root < found[0]:
                        found = (root, kind, k, fn)
            if found is None:
                watch.values = ends
                break
            root, kind, k, fn_root = found
            if kind in ROUGH_ROOTS:  # (the step's interpolant is not to be trusted there)
                assert dense is not None
                return _Stop(*_polish(rhs, fn_root, dense, t_old, y_old, root, tolerance, n2),
                             kind, k)  # fmt: skip
            if kind not in GOES_ON:
                return _Stop(root, np.asarray(dense(root), dtype=np.float64), kind, k)  # type: ignore[misc]
            watch.go_on(kind, k)
            lo = root
        if solver.status == "finished":
            return _Stop(t_new, np.array(y_new), "end", -1)
        if until < np.inf and (lo > t_old or t_new >= until):  # back to the compiled stepper
            return t_new, np.array(y_new), solver.step_size
        t_old, y_old = t_new, np.array(y_new)


#: The events at whose root the flow is not smooth, located on the flow itself
#: (:func:`_polish`), not on the dense output of the step that crosses it: a slide's stop.
ROUGH_ROOTS = frozenset({"stick"})
#: The most Newton steps of :func:`_polish`.
POLISH_STEPS = 8


def _polish(rhs: Callable[[float, np.ndarray], Any], fn: Callable[[np.ndarray], float],
            dense: Any, t_old: float, y_old: np.ndarray, root: float, tolerance: float,
            n2: int) -> tuple[float, np.ndarray]:  # fmt: skip
    """The root of ``fn`` (a slide's margin, :func:`slide_margin`) along the flow itself
    near ``root``, its root on the dense output of the step from ``(t_old, y_old)``: the
    time (s) and the integrated vector there. Newton's iteration

        t <- t - g(t) / g',     g(t) = fn(x(t)),

    from ``root``, ``x(root)`` integrated from the step's start (the same method and
    tolerance, its steps ending there), each next ``x(t)`` from the last (a step of the
    correction's size), ``g'`` the dense output's slope at ``root`` (central differences
    over a thousandth of the step; it need not be exact); it ends where ``|g|`` no longer
    falls (at the integration's noise), that iterate of least ``|g|`` kept.

    Why: at a slide's stop the held flow is not smooth. Coulomb's direction ``d = v_t /
    |v_t|`` (:func:`slide_direction`) turns at a rate ``1 / |v_t|`` as the slip ``v_t``
    falls to zero, so the step that crosses the stop loses its order there, and so does
    its interpolant, unnoticed by its error estimate: for a sphere slipping at ``u0 = 3.5``
    m/s, a 1.3e-5 s step across its stop had the state off by 7e-10 inside it, the slip by
    7.5e-11 m/s and the stop by 1.1e-11 s (the closed form ``2 |u0| / (7 mu g)``), against
    2e-14 s where the stepping (on other BLAS kernels) happened to cross it in 2e-7 s. The
    integration from the step's start to ``root`` does not cross the stop, or by that
    error only: it is the flow to its tolerance (its steps shorten as the slip falls), and
    the slip falls linearly to the stop (``-(7/2) mu g`` for the sphere), so that one or
    two corrections end the iteration. The dense output's root and vector stand where an
    integration fails."""
    from scipy.integrate import DOP853

    def flow(t_a: float, y_a: np.ndarray, t_b: float) -> np.ndarray | None:
        if abs(t_b - t_a) <= 4 * EPS * max(1.0, abs(t_a)):
            return np.array(y_a, dtype=float)
        solver = DOP853(rhs, t_a, y_a, t_b, rtol=tolerance, atol=tolerance,
                        first_step=abs(t_b - t_a))  # fmt: skip
        while solver.status == "running":
            if solver.step() is not None:
                return None
        return np.array(solver.y, dtype=float) if solver.status == "finished" else None

    fallback = (root, np.asarray(dense(root), dtype=np.float64))
    delta = 1e-3 * (float(dense.t_max) - float(dense.t_min))
    slope = (fn(dense(root + delta)[:n2]) - fn(dense(root - delta)[:n2])) / (2 * delta)
    y = flow(t_old, y_old, root)
    if y is None or not math.isfinite(slope) or slope == 0.0:
        return fallback
    t, g = root, fn(y[:n2])
    for _ in range(POLISH_STEPS):
        t_next = min(max(t - g / slope, t_old), float(dense.t_max))
        if g == 0.0 or abs(t_next - t) <= 4 * EPS * max(1.0, abs(t)):
            break
        y_next = flow(t, y, t_next)
        if y_next is None:
            break
        g_next = fn(y_next[:n2])
        if not abs(g_next) < abs(g):  # (at the integration's noise)
            break
        t, y, g = t_next, y_next, g_next
    return t, y


#: A slide's speed (relative to the state's size, m/s) below which it has not yet started.
SLIDE_START = 1e-10


def _slide_scale(x: np.ndarray) -> float:
    return SLIDE_START * max(1.0, float(np.linalg.norm(x)))


def _slide_speed(model: HybridModel, hold: Hold, x: np.ndarray) -> float:
    """A sliding hold's least :func:`slide_margin` over its points (m/s; > 0 while each
    slides within 60 degrees of its reference; ``s v_t`` for one point with one tangent
    row)."""
    if not hold.slip:
        return 0.0
    qd = x[model.nq :]
    out = np.inf
    for i, r in enumerate(held_points(model, hold, x)):
        tangents = r.tangents()
        if tangents is not None and hold.slides(i):
            out = min(out, slide_margin(hold.reference(i), tangents[0] @ qd))
    return 0.0 if out == np.inf else float(out)


#: The gap (m) reported for a pair's next point where MuJoCo finds none near closing.
NO_NEXT = 1.0


def _next_point(model: HybridModel, hold: Hold, x: np.ndarray) -> GapRows | None:
    """The point of the hold's guard that it does not hold with the least gap, if any."""
    points = contact_points(model, model.guards[hold.index], x)
    held = set(_held_indices(hold, points))
    others = [p for i, p in enumerate(points) if i not in held]
    return min(others, key=lambda p: p.gap) if others else None


def next_gap(model: HybridModel, hold: Hold, x: np.ndarray) -> float:
    """The least gap of the hold's guard's points that it does not hold (m; ``NO_NEXT``
    where there is none): a held box's next corner, which strikes where it falls through
    zero."""
    point = _next_point(model, hold, x)
    return NO_NEXT if point is None else float(point.gap)


def next_rate(model: HybridModel, hold: Hold, x: np.ndarray) -> float:
    """The normal speed ``J_n q'`` (m/s) of the point :func:`next_gap` measures (0 where
    there is none)."""
    point = _next_point(model, hold, x)
    return 0.0 if point is None else float(point.normal @ x[model.nq :])


#: A held pair's rows' speed (m/s, relative to ``max(1, |q'|)``) past which its held points
#: are no longer those the flow holds (:func:`held_drift`).
DRIFT = 1e-9


def held_drift(model: HybridModel, hold: Hold, x: np.ndarray) -> float:
    """``max_i |A_i q'| - DRIFT max(1, |q'|)`` (m/s) over the rows ``A_i`` that ``hold``
    holds (each point's normal, its tangents where it sticks). The held flow keeps
    ``A q'`` at zero (to round-off, from :func:`carnot.hybrid.simulate.settle`) while its
    points are the same; it crosses zero where the rows jump: a held point that MuJoCo no
    longer lists, another of the pair's points taking its place (a mesh's vertex that
    becomes the deepest as it reaches the plane). The held forces would do work
    ``F . A q'`` on the new point's speed, which no ledger books: the leg ends there
    (``Leg.ended = "drift"``)."""
    qd = x[model.nq :]
    worst = 0.0
    for i, r in enumerate(held_points(model, hold, x)):
        worst = max(worst, abs(float(r.normal @ qd)))
        tangents = r.tangents()
        if tangents is not None and not hold.slides(i):
            worst = max(worst, float(np.max(np.abs(tangents[0] @ qd))))
    return worst - DRIFT * max(1.0, float(np.linalg.norm(qd)))


def _next_leaving(model: HybridModel, hold: Hold, x: np.ndarray) -> bool:
    """Whether the hold's next point is on its surface at ``x`` (``|gap| <= ON_SURFACE``
    of the state's size), leaving it."""
    guard = model.guards[hold.index]
    if guard.rows is None or not guard.several:
        return False
    size = max(1.0, float(np.linalg.norm(x)))
    return abs(next_gap(model, hold, x)) <= ON_SURFACE * size and next_rate(model, hold, x) > 0


def _held_watch(model: HybridModel, held: tuple[Hold, ...], friction: float | None,
                started: list[bool], scale: float, x0: np.ndarray, leaving: list[bool]
                ) -> list[tuple[Callable[[np.ndarray], float], int, str, int]]:  # fmt: skip
    """What the holds watch (function, direction, kind, the hold's position): the least
    normal force of its points falling through zero (``release``); a sticking hold's least
    cone margin ``mu F_n - |F_t|`` falling through zero (``slip_start``); a sliding hold's
    :func:`_slide_speed` falling through zero (``stick``: a point's slide stops, or turns
    past 60 degrees from its reference), or, before it has started (``slide``, rising
    through ``scale``), falling through ``-scale``; a pair of geoms held on some of its
    points, the next point's gap falling through zero (``join``: it strikes), or, where the
    leg starts with it leaving the surface, its normal speed turning back first
    (``join_turn``), and its held rows' speed rising through zero (``drift``:
    :func:`held_drift`)."""
    out: list[tuple[Callable[[np.ndarray], float], int, str, int]] = []
    for j, hold in enumerate(held):
        out.append((_held_force(model, held, j, friction, 0), -1, "release", j))
        guard = model.guards[hold.index]
        if leaving[j]:
            out.append((partial(next_rate, model, hold), -1, "join_turn", j))
        elif guard.rows is not None and guard.several:
            out.append((partial(next_gap, model, hold), -1, "join", j))
        if guard.rows is not None and guard.several:
            out.append((partial(held_drift, model, hold), 1, "drift", j))
        if not has_cone(model, hold, x0, friction):
            continue
        count = len(held_points(model, hold, x0))
        if not all(hold.slides(i) for i in range(count)):  # a point sticks
            out.append((_held_force(model, held, j, friction, 1), -1, "slip_start", j))
        if not any(hold.slides(i) for i in range(count)):
            continue
        if started[j]:
            out.append((_speed_past(model, hold, 0.0), -1, "stick", j))
        else:
            out.append((_speed_past(model, hold, -scale), -1, "stick", j))
            out.append((_speed_past(model, hold, scale), 1, "slide", j))
    return out


def _speed_past(model: HybridModel, hold: Hold, level: float
                ) -> Callable[[np.ndarray], float]:  # fmt: skip
    """``s v_t - level``: a sliding hold's speed past ``level`` (m/s)."""
    return lambda x: _slide_speed(model, hold, x) - level


def _held_force(model: HybridModel, held: tuple[Hold, ...], j: int, friction: float | None,
                which: int) -> Callable[[np.ndarray], float]:  # fmt: skip
    """The ``j``-th hold's least normal force (``which = 0``), or its least cone margin
    ``mu F_n - |F_t|`` (``which = 1``): :func:`held_margins`."""
    return lambda x: held_margins(model, held, j, x, friction)[which]


def stance_margins(model: HybridModel, x: np.ndarray, friction: float | None
                   ) -> tuple[float, float]:  # fmt: skip
    """A stance foot's ground force ``F`` (N) against what the ground can give: ``F_n``
    (>= 0: it pushes) and ``mu F_n - |F_t|`` (>= 0: inside the cone; ``inf`` where the foot
    sticks whatever the force)."""
    return _stance_watch(model, friction)(x)


def _stance_watch(model: HybridModel, friction: float | None
                  ) -> Callable[[np.ndarray], tuple[float, float]]:  # fmt: skip
    """:func:`stance_margins` of the states given it, the plane's normal and the
    mechanism's force on floats looked up once (the lift watch runs at every step's end)."""
    on_floats = getattr(model.mechanism, "support_on_floats", None)
    support = model.mechanism.support  # type: ignore[attr-defined]
    n_x, n_y = np.asarray(model.normal, dtype=float).tolist()[:2]

    def margins(x: np.ndarray) -> tuple[float, float]:
        if on_floats is not None:
            f_x, f_y = on_floats(*np.asarray(x, dtype=float).tolist())
        else:
            f_x, f_y = support(x).tolist()
        f_n = n_x * f_x + n_y * f_y
        if friction is None:  # (the lift watch: no cone to measure)
            return f_n, np.inf
        t_x, t_y = f_x - f_n * n_x, f_y - f_n * n_y
        return f_n, friction * f_n - math.sqrt(t_x * t_x + t_y * t_y)

    return margins


def _watched(model: HybridModel, armed: list[bool], turning: list[bool], n2: int,
             friction: float | None = None
             ) -> list[tuple[Callable[[np.ndarray], float], int, str, int]]:  # fmt: skip
    """The functions watched now: (function, direction, kind, guard index)."""
    out: list[tuple[Callable[[np.ndarray], float], int, str, int]] = []
    for k, g in enumerate(model.guards):
        if turning[k]:
            out.append((_rate(model, g), g.direction, "turn", k))
        elif armed[k]:
            out.append((g.function, g.direction, "strike", k))
        elif g.arming is not None:
            out.append((g.arming, g.arming_direction, "arm", k))
    if model.fall is not None:
        out.append((model.fall, -1, "fall", -1))
    if model.stance and getattr(model.mechanism, "support", None) is not None:
        lift = _stance_watch(model, None)
        out.append((lambda x: lift(x)[0], -1, "lift", -1))
        if friction is not None:
            slip = _stance_watch(model, friction)
            out.append((lambda x: slip(x)[1], -1, "slip", -1))
    return out


def _root(fn: Callable[[np.ndarray], float], dense: Any, lo: float, hi: float, n2: int) -> float:
    """The crossing in ``[lo, hi]`` on the step's dense output, by Brent's method to a few
    units of round-off (SciPy's own event location)."""
    from scipy.optimize import brentq

    at = _dense_floats(dense, n2)
    return float(brentq(lambda t: fn(at(t)), lo, hi, xtol=4 * EPS, rtol=4 * EPS))


#: The most components of the state for which :func:`_dense_floats` evaluates the dense
#: output on Python floats (above, NumPy's own evaluation is the quicker).
DENSE_FLOATS_UP_TO = 12


def _dense_floats(dense: Any, n2: int) -> Callable[[float], np.ndarray]:
    """``t -> dense(t)[:n2]``: the state's part of the step's dense output. SciPy's DOP853
    interpolant (``Dop853DenseOutput``: ``x = (t - t_old) / h``, ``y = 0``, then for each of
    its coefficient rows ``F`` from the last, ``y = (y + F_k) x`` and ``(y + F_k) (1 - x)``
    by turns, and ``y + y_old``) is evaluated here on Python floats for ``n2`` components at
    most :data:`DENSE_FLOATS_UP_TO`: the same IEEE operations in the same order on each
    component, so the same bits (``tests/test_hybrid_flow_routes.py``), at a quarter of
    NumPy's cost for a walker's four (9 -> 2.3 us; Brent's method takes about ten). Any
    other dense output, or more components, is called as it is."""
    rows = getattr(dense, "F", None)
    if type(dense).__name__ != "Dop853DenseOutput" or rows is None or n2 > DENSE_FLOATS_UP_TO:
        return lambda t: dense(t)[:n2]
    coefficients = np.asarray(rows, dtype=float)[::-1, :n2].tolist()
    t_old, h = float(dense.t_old), float(dense.h)
    y_old = np.asarray(dense.y_old, dtype=float)[:n2].tolist()

    def at(t: float) -> np.ndarray:
        x = (t - t_old) / h
        x1 = 1 - x
        out = []
        for j, start in enumerate(y_old):
            y = 0.0
            for i, row in enumerate(coefficients):
                y = (y + row[j]) * (x if i % 2 == 0 else x1)
            out.append(y + start)
        return np.array(out)

    return at


#: |G(x)| below this (relative to |D_x G| |x|) is on the guard's surface.
ON_SURFACE = 1e-12


def _rate(model: HybridModel, g: Guard) -> Callable[[np.ndarray], float]:
    """``G'(x) = D_x G(x) . f(x)``, the guard's rate along the flow."""
    return lambda x: float(g.gradient(x) @ model.mechanism.flow(x))


def _leaving(model: HybridModel, g: Guard, x: np.ndarray) -> bool:
    """Whether ``x`` is on the guard's surface, moving off it (against its direction)."""
    grad = g.gradient(x)
    # (|v| as sqrt(v . v): np.linalg.norm's own formula for a vector, without its dispatch)
    size = max(1.0, math.sqrt(float(np.dot(grad, grad))) * math.sqrt(float(np.dot(x, x))))
    on = abs(g.function(x)) <= ON_SURFACE * size
    return on and g.direction * float(grad @ model.mechanism.flow(x)) < 0


def _leg(t0: float, stop: _Stop, model: HybridModel, held: tuple[Hold, ...], n2: int,
         quad: int, variational: bool, evaluations: int, phi_scale: float = 1.0
         ) -> Leg:  # fmt: skip
    """The leg from ``t0`` to ``stop``, the vector there read as the state, the works and
    ``Phi``."""
    y = stop.y
    guard: Guard | None = None
    ended = stop.kind
    if stop.kind == "strike":
        guard = model.guards[stop.k]
        ended = guard.name
    elif stop.kind in ("release", "slip_start", "stick", "drift"):
        guard = model.guards[held[stop.k].index]
    elif stop.kind == "join":  # a held pair's next point strikes: the pair's strike
        guard = model.guards[held[stop.k].index]
        ended = guard.name
    x1 = np.array(y[:n2])
    works = np.array(y[n2 : n2 + quad]) if quad else np.zeros(2)
    m2 = 2 * model.n
    phi = np.array(y[n2 + quad :]).reshape(m2, m2) / phi_scale if variational else None
    return Leg(t0=t0, t1=stop.t, x1=x1, phi=phi, ended=ended, guard=guard,
               evaluations=evaluations, damping=float(works[0]),
               sliding=float(works[1]))  # fmt: skip

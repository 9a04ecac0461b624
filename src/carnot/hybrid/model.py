"""A hybrid model: a compiled mechanism, the guards where it strikes, and what each strike
relabels (DESIGN.md section 10).

Between impacts the model moves in its chart (minimal coordinates ``q``, the stance foot or
the pivot at the chart's origin ``anchor``). A :class:`Guard` is a surface ``G(q) = 0``
crossed in a stated direction: the heel strike of a walker, the next spoke of a rimless
wheel. Some guards are *armed* only after another surface is crossed first: a walker's heel
strike is armed at mid-stance, once the swing foot has passed the stance foot, because a rigid
straight-legged walker's swing foot touches the ground when the legs are parallel (foot
scuffing); as Garcia et al. (1998) and Goswami et al. (1996) do, that touch is ignored (a
real walker lifts its foot: knees, or stepping stones).

At the strike the model is solved as one impact in *floating* coordinates (the stance foot
free too, so that it lifts off or holds as the law says) by :func:`carnot.solve_impact`; the
state after is then read in the chart of the new stance: ``q+ = A q- + c`` (the legs exchange
roles) and the floating velocity relabelled by ``P_f`` (``q_f' -> P_f q_f'``), of which the
chart's velocity is the exact preimage when the new stance point is at rest.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

if TYPE_CHECKING:
    from carnot.model.system import SystemProblem


class Mechanics(Protocol):
    """What the flow, the strike and the ledger ask of a model's mechanism: a compiled
    symbolic one (:class:`carnot.hybrid.mechanism.Compiled`) or one backed by MuJoCo
    (:class:`carnot.hybrid.mjcf.MujocoMechanism`). Units: q in the model's coordinates, M in
    kg m^2 (or kg), h in N m (or N), V in J.

    The state is ``x = (q, v)``: ``nq`` positions and ``n`` velocities. For most mechanisms
    ``nq == n`` and ``v = q'``; an MJCF model with free or ball joints has unit quaternions
    among its positions (``nq > n``), and ``q' = position_rate(q, v)`` is not ``v`` there.
    M, h and every contact's Jacobian are in velocity space (n); ``flow_jacobian`` (2n x 2n)
    is in the tangent chart (:func:`tangent_step`: the identity where ``nq == n``)."""

    @property
    def n(self) -> int: ...
    @property
    def nq(self) -> int: ...
    def position_rate(self, q: np.ndarray, qd: np.ndarray, /) -> np.ndarray: ...
    @property
    def n_floating(self) -> int: ...
    @property
    def rods(self) -> Mapping[str, str]: ...
    def mass(self, q: np.ndarray, /) -> np.ndarray: ...
    def bias(self, q: np.ndarray, qd: np.ndarray, /) -> np.ndarray: ...
    def potential(self, q: np.ndarray, /) -> float: ...
    def flow(self, x: np.ndarray, /) -> np.ndarray: ...
    def flow_jacobian(self, x: np.ndarray, /) -> np.ndarray: ...
    def embed(self, q: np.ndarray, /) -> np.ndarray: ...
    def embed_jacobian(self, q: np.ndarray, /) -> np.ndarray: ...
    def floating_mass(self, qf: np.ndarray, /) -> np.ndarray: ...
    def point(self, name: str, qf: np.ndarray, /) -> np.ndarray: ...
    def point_jacobian(self, name: str, qf: np.ndarray, /) -> np.ndarray: ...
    def rod_foot(self, name: str, q: np.ndarray, /) -> np.ndarray: ...
    def point_in_chart(self, name: str, q: np.ndarray, /) -> np.ndarray: ...


@dataclass(frozen=True, kw_only=True)
class Law:
    """The ground's law at a strike: ``restitution`` e, ``friction`` mu (``None``: the
    contact sticks, as the walker papers assume) and the Newton/Poisson/Stronge ``law``."""

    restitution: float = 0.0
    friction: float | None = None
    law: str = "newton"


@dataclass(frozen=True, kw_only=True, eq=False)
class GapRows:
    """A closed contact point's rows in the chart at one state, for holding it in the flow:
    the gap's gradient ``normal`` (n, ``d g / d q``) and ``normal_bias`` (the gap's
    acceleration is ``normal . q'' + normal_bias``, m/s^2), and, where the point can slide,
    its ``tangent`` rows with ``tangent_bias``: one row (n, and a float) in the plane of a
    planar model (``d s / d q``, ``s`` the point's displacement along the plane's unit
    tangent ``t = (n_y, -n_x)``), or ``k`` rows (k x n, and k biases) in space, the relative
    velocity along each of the contact frame's tangents (an MJCF contact: k = 2).

    ``gap`` (m) is the point's distance (0 for a point held on its plane: an MJCF pair's
    rows list MuJoCo's contacts near closing, held or not); ``friction``, where given, is the
    point's own coefficient (MuJoCo's combination of the two geoms'), used where the law
    gives none; ``label``, where given, tells a pair's points apart: the contact point in
    one body's own frame (m), which a box's corner keeps as it moves."""

    normal: np.ndarray
    normal_bias: float = 0.0
    tangent: np.ndarray | None = None
    tangent_bias: float | np.ndarray = 0.0
    gap: float = 0.0
    friction: float | None = None
    label: np.ndarray | None = None

    def tangents(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The tangent rows as a ``k x n`` array and their ``k`` biases (``None``: the point
        cannot slide)."""
        if self.tangent is None:
            return None
        rows = np.atleast_2d(np.asarray(self.tangent, dtype=float))
        return rows, np.atleast_1d(np.asarray(self.tangent_bias, dtype=float))


@dataclass(frozen=True, kw_only=True, eq=False)
class Guard:
    """A strike surface ``function(x) = 0`` of the state ``x = (q, q')``, crossed with
    ``direction`` (+1 rising, -1 falling), armed once ``arming(x)`` has crossed zero with
    ``arming_direction`` (``None``: always armed), with its ``gradient(x)`` (``nq + n``:
    ``d G / d q`` in position space, then ``d G / d v``), so that its rate along the flow is
    ``gradient(x) . flow(x)``.

    ``striking`` names the mechanism point that strikes (``holding``: the points in contact
    before, which take part in the impact), ``relabel`` and ``offset`` give ``q+ = A q- + c``
    and ``velocity_relabel`` the floating velocity's ``P_f``; ``moves_anchor``: the struck
    point becomes the chart's origin. ``relabel`` is ``nq x nq`` (positions), ``P_f``
    ``n_f x n_f`` (velocities).

    A joint's stop has ``limit_row``, the gap's gradient ``d g / d q_f`` (constant, in
    floating coordinates; ``g = bound - q_k`` or ``q_k - bound``): its strike is one
    frictionless row on the coordinates, and a chatter against it ends with the joint *held*
    at the stop (the flow constrained, ``g = 0``) until the stop's force would pull.
    ``normal`` (3, world) is the struck plane's, where it is not the model's ground.

    ``problem(x, law)``, when given, builds the strike's impact itself (a
    :class:`~carnot.model.system.SystemProblem` in the chart's coordinates, which are then
    the floating ones): a model from MJCF, whose contacts MuJoCo finds at the event; with
    ``resting=True`` (contacts are held) the closed contacts at rest take part too. Such a
    guard is a *contact* between two bodies: one that stays closed after its strike, pressed
    by the flow, and that carnot cannot hold, ends the run (``contact_persists``).

    ``rows(x)``, when given, makes the guard a contact that can be *held* in the flow after a
    strike leaves it closed and at rest (a point on a plane: one :class:`GapRows`; a pair of
    MJCF geoms: a tuple of them, one per contact point MuJoCo finds near closing, the held
    ones those nearest their anchors): sticking, or sliding against Coulomb's force, until
    the force that holds it falls to zero; ``several`` says that ``rows`` gives a tuple.

    ``reach`` (m), where given, is the gap within which ``problem`` finds the strike's
    contacts (an MJCF guard's ``STRIKE_GAP``): the strike's central differences
    (:func:`carnot.hybrid.strike.reset_jacobian`) move the gap by a tenth of it at most."""

    name: str
    function: Callable[[np.ndarray], float]
    gradient: Callable[[np.ndarray], np.ndarray]
    direction: int
    striking: str
    holding: tuple[str, ...]
    relabel: np.ndarray
    offset: np.ndarray
    velocity_relabel: np.ndarray
    moves_anchor: bool = True
    arming: Callable[[np.ndarray], float] | None = None
    arming_direction: int = 1
    limit_row: np.ndarray | None = None
    normal: np.ndarray | None = None
    problem: Callable[..., SystemProblem] | None = None
    rows: Callable[[np.ndarray], GapRows | tuple[GapRows, ...]] | None = None
    several: bool = False
    reach: float | None = None


@dataclass(frozen=True, kw_only=True, eq=False)
class HybridModel:
    """A named model with its ``parameters``, chart ``coordinates`` (names), the compiled
    ``mechanism``, floating coordinate names ``floating``, its ``guards``, the ground's unit
    ``normal`` (3, world), ``gravity`` (2, world, m/s^2), ``total_mass`` (kg), a ``fall``
    surface (the run ends when ``fall(x)`` falls through zero: the hip reaching the ground)
    and ``notes`` (what the model leaves out, said in reports). ``stance``: the chart's
    origin is a foot on the ground, the model's only support, which can only push: where the
    ground's force on it (``mechanism.support``) would pull, or leave the friction cone, the
    foot would lift or slip, and the run stops there, flagged."""

    name: str
    parameters: Mapping[str, float]
    coordinates: tuple[str, ...]
    floating: tuple[str, ...]
    mechanism: Mechanics
    guards: tuple[Guard, ...]
    normal: np.ndarray
    gravity: np.ndarray
    total_mass: float
    fall: Callable[[np.ndarray], float] | None = None
    notes: str = ""
    slope: float = 0.0
    stance: bool = False

    @property
    def n(self) -> int:
        """The chart's number of velocity coordinates (that of its positions for every model
        but an MJCF one with free or ball joints: :attr:`nq`)."""
        return self.mechanism.n

    @property
    def nq(self) -> int:
        """The chart's number of position coordinates: the state is ``x = (q, v)``, ``nq +
        n`` entries."""
        return self.mechanism.nq

    def energy(self, x: np.ndarray, anchor: np.ndarray) -> float:
        """``E = 1/2 v^T M v + V(q) - m_tot g . anchor`` (J): kinetic plus potential, the
        chart's origin at ``anchor`` (2, world, m)."""
        q, qd = x[: self.nq], x[self.nq :]
        kinetic = 0.5 * qd @ self.mechanism.mass(q) @ qd
        potential = self.mechanism.potential(q) - self.total_mass * self.gravity @ anchor
        return float(kinetic + potential)

    def kinetic(self, x: np.ndarray) -> float:
        """``1/2 v^T M(q) v`` (J)."""
        q, qd = x[: self.nq], x[self.nq :]
        return float(0.5 * qd @ self.mechanism.mass(q) @ qd)


def require_velocity_chart(model: HybridModel, what: str) -> None:
    """Refuse ``what`` (periodic orbits, phase portraits: built on a state whose positions
    and velocities pair one to one) for a model with ``nq != n`` (an MJCF model's free or
    ball joint: a quaternion's four positions for three angular velocities), in one line.

    Saltation matrices, the flow's linearization and the return map's derivative are built
    there, in the tangent chart (:func:`tangent_step`). Newton shooting is not: a passive
    MJCF model with a free or ball joint has no isolated periodic orbit to find (a free
    body's horizontal position and heading are neutral, multipliers 1; with no actuators
    its strikes take energy, ``e < 1``, and it comes to rest, or keep it, ``e = 1``, and its
    orbits come in families, another multiplier 1).
    """
    if model.nq != model.n:
        from carnot.errors import InputError

        raise InputError(model.name, f"{what} are not supported yet for a model with free or "
                         f"ball joints ({model.nq} positions for {model.n} velocities)",
                         show_value=False)  # fmt: skip


# The tangent chart: perturbations of the state x = (q, v) are 2n numbers ``dx = (dq, dv)``,
# ``dq`` in velocity space (MuJoCo's convention: ``mj_integratePos(q, dq, 1)``). Where
# ``nq == n`` the chart is the identity (``x (+) dx = x + dx``); an MJCF model with free or
# ball joints has unit quaternions among its positions, and its mechanism's
# ``integrate_position(q, dq)`` (``mj_integratePos``) and ``difference_position(q0, q1)``
# (``mj_differentiatePos``, its inverse) are the chart.


def _chart(model: HybridModel) -> Any:
    mech = model.mechanism
    if not hasattr(mech, "integrate_position"):
        require_velocity_chart(model, "saltation matrices")
    return mech


def tangent_step(model: HybridModel, x: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """``x (+) dx``: the state ``x = (q, v)`` (``nq + n``) moved by the tangent perturbation
    ``dx = (dq, dv)`` (``2 n``): ``(q (+) dq, v + dv)``, ``q (+) dq = q + dq`` where ``nq ==
    n``, else ``mj_integratePos(q, dq, 1)`` (a quaternion turned by ``exp(dq / 2)`` in its
    body's axes).

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8})
    >>> tangent_step(wheel, np.array([0.1, 1.0]), np.array([0.5, -1.0])).tolist()
    [0.6, 0.0]
    """
    nq, n = model.nq, model.n
    x, dx = np.asarray(x, dtype=float), np.asarray(dx, dtype=float)
    if nq == n:
        return x + dx
    q = _chart(model).integrate_position(x[:nq], dx[:n])
    return np.concatenate([q, x[nq:] + dx[n:]])


def tangent_difference(model: HybridModel, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``y (-) x`` (``2 n``): the tangent perturbation ``dx`` at ``x`` with ``x (+) dx = y``
    (:func:`tangent_step`): ``y - x`` where ``nq == n``, else ``mj_differentiatePos``.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel", {"spokes": 8})
    >>> tangent_difference(wheel, np.array([0.1, 1.0]), np.array([0.6, 0.0])).tolist()
    [0.5, -1.0]
    """
    nq, n = model.nq, model.n
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if nq == n:
        return y - x
    dq = _chart(model).difference_position(x[:nq], y[:nq])
    return np.concatenate([dq, y[nq:] - x[nq:]])


def tangent_flow(model: HybridModel, x: np.ndarray) -> np.ndarray:
    """The flow in the tangent chart (``2 n``): ``(v, v')``, the velocities and the
    accelerations (``d/dt (q(t) (-) q(0)) = v`` at ``t = 0``: MuJoCo's ``qvel`` is that rate;
    where ``nq == n`` this is the flow itself, ``q' = v``)."""
    nq = model.nq
    f = model.mechanism.flow(x)
    return f if nq == model.n else np.concatenate([np.asarray(x[nq:], dtype=float), f[nq:]])


def position_map(model: HybridModel, q: np.ndarray) -> np.ndarray:
    """``E(q) = d (q (+) dq) / d dq`` at ``dq = 0`` (``nq x n``): the identity where ``nq ==
    n``, else the columns ``position_rate(q, e_j)`` (the rate is linear in the velocity; a
    quaternion's four rows of ``1/2 quat (x) (0, e_j)``, orthogonal to ``quat``)."""
    nq, n = model.nq, model.n
    if nq == n:
        return np.eye(n)
    mech = model.mechanism
    return np.column_stack([mech.position_rate(q, e) for e in np.eye(n)])


def tangent_gradient(model: HybridModel, guard: Guard, x: np.ndarray) -> np.ndarray:
    """``D_x G`` in the tangent chart (``2 n``): ``(d G / d q) E(q)`` (:func:`position_map`)
    on the positions, ``d G / d v`` on the velocities; ``D_x G . tangent_flow(x)`` is the
    guard's rate ``G'``."""
    nq = model.nq
    grad = np.asarray(guard.gradient(x), dtype=float)
    if nq == model.n:
        return grad
    return np.concatenate([grad[:nq] @ position_map(model, x[:nq]), grad[nq:]])

"""Systems in motion from MJCF files (the optional extra ``carnot[mujoco]``; DESIGN.md
section 10): ``carnot simulate model.xml --keyframe K --duration T``.

The state is ``x = (q, v)``, MuJoCo's ``qpos`` (``nq`` numbers) and ``qvel`` (``nv``). Between
strikes the model moves under MuJoCo's own dynamics:

    M(q) v' + h(q, v) = 0,      M = mj_fullM (armature included, nv x nv),
                                h = qfrc_bias - qfrc_passive   (N m or N)
    q' = position_rate(q, v)

where a hinge's or a slide's position rate is its velocity (rad/s, m/s: ``nq == nv`` for a
model of hinges and slides, and ``q' = v``), and a free or ball joint's (``nq = nv + 1`` for
each) is, as MuJoCo defines its ``qvel``: a free joint's position ``p' = v_lin`` (world axes),
and for a free or ball joint's unit quaternion ``quat = [w, x, y, z]``

    quat' = 1/2 quat (x) (0, omega),   omega the angular velocity in the body's own axes

(the Hamilton product; checked against ``mj_integratePos`` in tests/test_hybrid_mjcf_free.py,
whose central differences it matches to 1e-11). The quaternions' norms are invariants of
this flow, so they drift off 1 only at the integrator's tolerance (3e-14 after 3 s of the
tests' spherical pendulum); carnot does not renormalize the state during a leg (a jump the
integrator would not see), but normalizes each quaternion at the start (the keyframe's
``qpos``) and in every position it hands MuJoCo (``mj_normalizeQuat`` on the scratch copy:
``M``, ``h``, ``V``, the gaps, and the strike's contacts and Jacobians).

``qfrc_bias`` holds gravity (the model's ``opt.gravity``), Coriolis and centrifugal forces;
``qfrc_passive`` the joints' springs and dampers (and gravity compensation). The flow is
MuJoCo's ``qacc`` in a copy of the model with its constraints, contacts and actuators
switched off (the contacts and stops are carnot's, rigid; actuators are left out: the
motion is passive). The energy is ``E = 1/2 v^T M v + V(q)``, ``V`` MuJoCo's potential
(``mjENBL_ENERGY``: gravity and springs, J). The joints' dampers (``dof_damping``: a force
``-c_k v_k``) take ``W_dampers = int sum_k c_k v_k^2 dt``, integrated beside the flow and
counted in the ledger; tendon dampers and the medium's drag (``opt.density``,
``opt.viscosity``) are not counted yet: with them the ledger's residual is their work.

Saltation matrices (``carnot simulate --saltation``) and the flow's Jacobian are built for
every joint in the tangent chart ``x (+) dx = (q (+) dq, v + dv)``, ``q (+) dq =
mj_integratePos(q, dq, 1)`` (:meth:`MujocoMechanism.integrate_position`,
:func:`carnot.hybrid.model.tangent_step`): ``2 nv`` numbers, the positions' perturbation in
velocity space (the identity chart where ``nq == nv``). The flow's Jacobian is by central
differences of MuJoCo's ``qacc``, step ``FLOW_STEP`` relative: exact to about 1e-9, not
symbolic. ``carnot cycle model.xml`` finds a periodic orbit of a model of hinges and slides,
its contacts held in the flow as the simulator holds them, up to a declared symmetry
(:mod:`carnot.hybrid.section`); with a free or ball joint it is refused in one line naming
the joint.

**Guards.** One per pair of geoms that can collide by MuJoCo's rules (``contype`` and
``conaffinity``, bodies welded together or parent and child filtered, ``<exclude>``, and
every explicit ``<pair>``): ``G(q)`` the pair's signed distance (``mj_geomDistance``, m),
struck when it falls through 0; its gradient ``d G / d q`` by central differences
(``GAP_STEP``) in position space (a quaternion's four entries too: ``G`` sees them
normalized, so the gradient has no part along the quaternion), its rate
``G' = (d G / d q) . q'``. At the strike the impact is built as ``carnot from-mjcf`` builds
it at that state, in velocity space (``qvel-`` to ``qvel+``; ``qpos`` unchanged)
(:func:`carnot.model.mjcf.mjcf_problem`: MuJoCo's contacts within ``STRIKE_GAP`` that
approach, their points and normals from ``mj_collision``, Jacobians from ``mj_jac``,
friction as MuJoCo combines it, ``condim`` 1 frictionless, the joint limits MuJoCo enforces
there) and solved by :func:`carnot.solve_impact`, with the law's restitution (MuJoCo has
none: ``--restitution``, or the model's ``<custom><numeric name="carnot_restitution">``,
default 0). Each hinge or slide with a range (``limited``) has two stops, ``q_k - lo >= 0``
and ``hi - q_k >= 0`` (``q_k`` at the joint's ``qposadr``, its row at its ``dofadr``), struck
and held as the double pendulum's elbow is. A ball joint with a range (a cone: its
rotation's angle ``theta = 2 atan2(|v|, |w|)`` of its quaternion ``[w, v]`` at most ``r``,
MuJoCo's ``range[1]``) has one stop, ``g = r - theta >= 0`` (MuJoCo's own limit distance,
``efc_pos``), whose row on the joint's three angular velocities is ``-n`` (the rotation's unit
axis, the same in the parent's and the child's axes: ``theta' = n . w``): struck as the
contacts are (MuJoCo's limit row within ``STRIKE_GAP``), and held where it comes to rest,
the gap's acceleration ``-n . w' - cot(theta / 2) |w_perp|^2 / 2`` (``w_perp`` the angular
velocity across the axis: the axis turns at ``n' = ((theta / 2) cot(theta / 2) w_perp +
(theta / 2) n x w) / theta``).

A contact that stays closed after its strike, pressed by the flow (a link coming to rest on
a table, a box dropped flat), is **held** in the flow (:mod:`carnot.hybrid.flow`,
:mod:`carnot.hybrid.simulate`) on the contact points MuJoCo finds between the pair's geoms
(:func:`pair_contacts`: ``mj_collision`` in a copy whose margins are ``WATCH_GAP``, so
that the held points and the next to close are listed): each point's rows are its contact
frame times the relative Jacobian at the point (its normal's, and its two tangents' unless
``condim`` 1), with its gap, MuJoCo's combined friction, and a label (the point in the
moving body's frame) that tells a pair's points apart. The rows' biases ``(d/dt J) qvel``
are a fourth-order central difference of the rows along the flow (``HOLD_STEP``):
``mj_jacDot`` is a material point's, and misses the contact point's own motion over a
curved surface (a rolling sphere's). Torsional and rolling friction (``condim`` 4, 6) are
not held: such a pair is held as ``condim`` 3.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from carnot.errors import InputError
from carnot.hybrid.model import GapRows, Guard, HybridModel, Law
from carnot.model.mjcf import dof_names, keyframe_id, load_mujoco, mjcf_problem
from carnot.model.system import SystemProblem

#: The gap (m) within which MuJoCo's contacts take part in a strike (from-mjcf's default).
STRIKE_GAP = 1e-6
#: The step of the gap's central differences (rad or m).
GAP_STEP = 1e-6
#: The relative step of the flow Jacobian's central differences.
FLOW_STEP = 1e-6
#: Distances beyond this (m) are not computed (mj_geomDistance's distmax): only the
#: crossing of zero matters.
DISTMAX = 1e3
#: The model's custom numeric that gives the strikes' restitution.
RESTITUTION_KEY = "carnot_restitution"
#: A state whose geoms overlap by more than this (m) is refused.
OVERLAP = 1e-9
#: The gap (m) within which MuJoCo's contacts of a held pair are listed: the held points
#: and the next ones to close (a box's corners); less than any geom's thickness.
WATCH_GAP = 1e-3
#: The displacement (m or rad, of ``|q'| tau``) of the held rows' central difference along
#: the flow.
HOLD_STEP = 1e-3
#: The factor by which that difference's step is shortened (twice at most) where a point
#: leaves MuJoCo's list within it.
HOLD_SHRINK = 16.0
#: A held contact's normal speed, relative to the velocity's size, at or below which it
#: takes part in a strike as a resting contact.
HELD_SPEED = 1e-8

_HINGE, _SLIDE = 3, 2  # mjtJoint
_FREE, _BALL = 0, 1


def drop_xml() -> Path:
    """A small MJCF file for the examples here: a ball (2 kg, radius 0.1 m) on a vertical
    slide ``height``, its bottom 1 m above a frictionless floor (written to a scratch
    folder)."""
    import tempfile

    path = Path(tempfile.mkdtemp(prefix="carnot-")) / "drop.xml"
    path.write_text('''<mujoco model="drop"><worldbody>
  <geom name="floor" type="plane" size="1 1 .1" condim="1"/>
  <body pos="0 0 1.1"><joint name="height" type="slide" axis="0 0 1"/>
    <geom name="ball" type="sphere" size="0.1" mass="2" condim="1"/></body>
</worldbody></mujoco>''', encoding="utf-8")
    return path


def quaternion_rate(quat: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """``d quat / dt = 1/2 quat (x) (0, omega)`` (1/s): the rate of a joint's orientation
    ``quat = [w, x, y, z]`` turning at ``omega`` (3, rad/s) in the joint's own (child) frame,
    MuJoCo's frame for a free or ball joint's angular velocity (``mj_integratePos`` turns
    ``quat`` by ``quat (x) exp(omega h / 2)``; tests/test_hybrid_mjcf_free.py checks the
    two against each other). ``(x)`` is the Hamilton product (e.g. Kuipers, *Quaternions and
    Rotation Sequences*, 1999), here with a pure quaternion ``(0, omega)`` on the right:

    >>> (quaternion_rate(np.array([1.0, 0, 0, 0]), np.array([0.0, 0, 2.0])) + 0.0).tolist()
    [0.0, 0.0, 0.0, 1.0]
    """
    w, x, y, z = (float(c) for c in quat)
    a, b, c = (float(o) for o in omega)
    return 0.5 * np.array([-x * a - y * b - z * c, w * a + y * c - z * b,
                           w * b - x * c + z * a, w * c + x * b - y * a])  # fmt: skip


@dataclass(frozen=True, kw_only=True, eq=False)
class JointLayout:
    """Where each joint's positions and velocities lie in ``qpos`` and ``qvel``: the scalar
    joints' (hinges, slides) ``scalar_q`` and ``scalar_v`` (index arrays, one entry each),
    the free joints' ``free`` and the ball joints' ``ball`` as ``(qposadr, dofadr)`` pairs
    (a free joint: 3 positions, then a quaternion; 3 linear, then 3 angular velocities; a
    ball joint: a quaternion, 3 angular velocities)."""

    nq: int
    scalar_q: np.ndarray
    scalar_v: np.ndarray
    free: tuple[tuple[int, int], ...] = ()
    ball: tuple[tuple[int, int], ...] = ()

    @property
    def quaternions(self) -> bool:
        """Whether any position is a quaternion's (``nq != nv``)."""
        return bool(self.free or self.ball)


def joint_layout(mujoco: Any, model: Any) -> JointLayout:
    """The model's :class:`JointLayout`, from ``jnt_type``, ``jnt_qposadr``, ``jnt_dofadr``."""
    scalar_q, scalar_v, free, ball = [], [], [], []
    for j in range(model.njnt):
        kind, qa, va = int(model.jnt_type[j]), int(model.jnt_qposadr[j]), int(model.jnt_dofadr[j])
        if kind == _FREE:
            free.append((qa, va))
        elif kind == _BALL:
            ball.append((qa, va))
        else:
            scalar_q.append(qa)
            scalar_v.append(va)
    return JointLayout(nq=int(model.nq), scalar_q=np.array(scalar_q, dtype=int),
                       scalar_v=np.array(scalar_v, dtype=int), free=tuple(free),
                       ball=tuple(ball))  # fmt: skip


def damper_power(damping: np.ndarray, nq: int, x: np.ndarray) -> float:
    """``sum_k c_k v_k^2`` (W): the power MuJoCo's joint dampers take at the state ``x =
    (qpos, qvel)``, ``c = dof_damping`` (N m s/rad or N s/m): their force in ``qfrc_passive``
    is ``-c_k v_k``.

    >>> damper_power(np.array([0.5, 0.0]), 2, np.array([0.0, 0.0, 2.0, 3.0]))
    2.0
    """
    v = x[nq:]
    return float(damping @ (v * v))


def position_rate(layout: JointLayout, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q' = dq/dt`` (nq) from ``v`` = MuJoCo's ``qvel`` (nv): a hinge's or a slide's ``v``
    itself (rad/s, m/s); a free joint's position rate its linear velocity (world axes, m/s,
    as MuJoCo's ``qvel`` gives it) and its quaternion's :func:`quaternion_rate` of its
    angular velocity (body axes); a ball joint's quaternion likewise.

    >>> layout = JointLayout(nq=7, scalar_q=np.zeros(0, int), scalar_v=np.zeros(0, int),
    ...                      free=((0, 0),))
    >>> rate = position_rate(layout, np.array([0, 0, 1, 1.0, 0, 0, 0]),
    ...                      np.array([1.0, 0, -2, 0, 0, 2]))
    >>> (rate + 0.0).tolist()  # (x, y, z) at (1, 0, -2) m/s; turning about z at 2 rad/s
    [1.0, 0.0, -2.0, 0.0, 0.0, 0.0, 1.0]
    """
    if not layout.quaternions:  # hinges and slides: q' = v, as before free joints came
        return np.array(v, dtype=float)
    out = np.zeros(layout.nq)
    out[layout.scalar_q] = v[layout.scalar_v]
    for qa, va in layout.free:
        out[qa : qa + 3] = v[va : va + 3]
        out[qa + 3 : qa + 7] = quaternion_rate(q[qa + 3 : qa + 7], v[va + 3 : va + 6])
    for qa, va in layout.ball:
        out[qa : qa + 4] = quaternion_rate(q[qa : qa + 4], v[va : va + 3])
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class MujocoMechanism:
    """A mechanism whose numbers come from MuJoCo (the module's formulas): ``nq`` positions
    (``qpos`` = the chart's ``q``, quaternions included) and ``n`` velocities (``qvel``;
    ``q' = position_rate(q, qvel)``, which is ``qvel`` itself where every joint is a hinge or
    a slide), ``model`` the flow's copy of the MjModel (constraints, contacts and actuators
    off, energy on) and ``data`` its MjData, a scratch buffer that every call overwrites (not
    state); ``layout`` where each joint's numbers lie. Every call into MuJoCo sees the
    positions' quaternions normalized (``mj_normalizeQuat`` on the scratch copy). The chart
    is the floating coordinates (``embed`` the identity): no relabelling, no moving origin.

    >>> ball = mjcf_model(drop_xml()).model.mechanism  # 2 kg on a vertical slide, 1 m up
    >>> ball.mass(np.zeros(1)).tolist(), ball.bias(np.zeros(1), np.ones(1)).tolist()
    ([[2.0]], [19.62])
    >>> ball.flow(np.array([0.0, 3.0])).tolist(), round(ball.potential(np.zeros(1)), 12)
    ([3.0, -9.81], 21.582)
    """

    n: int
    model: Any = field(repr=False)
    data: Any = field(repr=False)
    mj: Any = field(repr=False)
    layout: JointLayout = field(repr=False)
    rods: Mapping[str, str] = field(default_factory=dict)
    #: ``damping_power(x)``: the joints' dampers' power ``sum_k c_k v_k^2`` (W,
    #: :func:`damper_power`), integrated beside the flow for the ledger; ``None`` for a model
    #: without dampers (so that its flow is integrated as before, with no extra component).
    damping_power: Callable[[np.ndarray], float] | None = field(default=None, repr=False)

    @property
    def nq(self) -> int:
        """The positions' number: MuJoCo's ``nq`` (``n`` + 1 per free or ball joint)."""
        return self.layout.nq

    @property
    def n_floating(self) -> int:
        """The floating coordinates are the chart's velocities: ``n``."""
        return self.n

    def position_rate(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``q'`` from ``qvel`` (:func:`position_rate`)."""
        return position_rate(self.layout, q, qd)

    def normalized(self, q: np.ndarray) -> np.ndarray:
        """``q`` with each quaternion made unit (``mj_normalizeQuat``; a copy): the flow
        keeps their norms to its tolerance only."""
        out = np.array(q, dtype=float)
        if self.layout.quaternions:
            self.mj.mj_normalizeQuat(self.model, out)
        return out

    def integrate_position(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """``q (+) dq`` (nq): ``q`` moved along the velocity-space perturbation ``dq`` (n) for
        a unit time, ``mj_integratePos(q, dq, 1)`` (a quaternion turned by ``exp(dq / 2)`` in
        its body's axes, then made unit; hinges and slides ``q + dq``): the tangent chart of
        the saltation matrices (:func:`carnot.hybrid.model.tangent_step`)."""
        out = np.array(q, dtype=float)
        self.mj.mj_integratePos(self.model, out, np.asarray(dq, dtype=float), 1.0)
        return out

    def difference_position(self, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
        """``q1 (-) q0`` (n): the perturbation ``dq`` with ``q0 (+) dq = q1``,
        ``mj_differentiatePos(q0, q1, 1)`` (:meth:`integrate_position`'s inverse)."""
        out = np.zeros(self.n)
        self.mj.mj_differentiatePos(self.model, out, 1.0, np.asarray(q0, dtype=float),
                                    np.asarray(q1, dtype=float))  # fmt: skip
        return out

    def _set_qpos(self, q: np.ndarray) -> Any:
        d = self.data
        d.qpos[:] = q
        if self.layout.quaternions:  # MuJoCo's kinematics wants unit quaternions
            self.mj.mj_normalizeQuat(self.model, d.qpos)
        return d

    def _forward(self, q: np.ndarray, qd: np.ndarray) -> Any:
        d = self._set_qpos(q)
        d.qvel[:] = qd
        self.mj.mj_forward(self.model, d)
        return d

    def mass(self, q: np.ndarray) -> np.ndarray:
        """``M(q)``: MuJoCo's ``mj_fullM`` (n x n; kg m^2, kg)."""
        d = self._forward(q, np.zeros(self.n))
        out = np.zeros((self.n, self.n))
        self.mj.mj_fullM(self.model, d, out)
        return 0.5 * (out + out.T)

    def bias(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``h = qfrc_bias - qfrc_passive`` (n; N m, N)."""
        d = self._forward(q, qd)
        return np.array(d.qfrc_bias) - np.array(d.qfrc_passive)

    def potential(self, q: np.ndarray) -> float:
        """``V(q)``: MuJoCo's potential energy, gravity and springs (J)."""
        return float(self._forward(q, np.zeros(self.n)).energy[0])

    def acceleration(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``q'' = -M^-1 h``: MuJoCo's ``qacc`` with no constraint and no actuator."""
        return np.array(self._forward(q, qd).qacc)

    def flow(self, x: np.ndarray) -> np.ndarray:
        """``d/dt (q, v) = (position_rate(q, v), qacc)`` (``v = q'`` for hinges and slides)."""
        q, v = x[: self.nq], x[self.nq :]
        return np.concatenate([self.position_rate(q, v), self.acceleration(q, v)])

    def flow_jacobian(self, x: np.ndarray) -> np.ndarray:
        """``A = d flow / d x`` (2n x 2n) by central differences (step ``FLOW_STEP``
        relative), in the tangent chart (:meth:`integrate_position`; ``x + dx`` where ``nq ==
        n``): the variational equation ``dx' = A dx`` of a perturbation ``dx = (dq, dv)``.
        Where ``nq != n``, ``A = [[C, I], [d qacc / d dq, d qacc / d v]]``: ``dq' = dv + C
        dq``, ``C`` zero but on each quaternion's three angular dofs, ``-[omega]x`` (a
        perturbation ``quat (x) exp(dq / 2)`` of ``quat' = 1/2 quat (x) (0, omega)`` turns at
        ``dq' = d omega - omega x dq``), and ``d qacc / d dq`` through the chart."""
        n2 = 2 * self.n
        out = np.zeros((n2, n2))
        if self.nq == self.n:
            for j in range(n2):
                h = FLOW_STEP * max(1.0, abs(float(x[j])))
                up, down = np.array(x, dtype=float), np.array(x, dtype=float)
                up[j] += h
                down[j] -= h
                out[:, j] = (self.flow(up) - self.flow(down)) / (2 * h)
            return out
        n, nq = self.n, self.nq
        q, v = np.asarray(x[:nq], dtype=float), np.asarray(x[nq:], dtype=float)
        out[:n, n:] = np.eye(n)
        for va in [va + 3 for _, va in self.layout.free] + [va for _, va in self.layout.ball]:
            w = v[va : va + 3]
            out[va : va + 3, va : va + 3] = -np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]],
                                                       [-w[1], w[0], 0.0]])  # fmt: skip
        for j in range(n):
            step = np.zeros(n)
            step[j] = FLOW_STEP
            out[n:, j] = (self.acceleration(self.integrate_position(q, step), v)
                          - self.acceleration(self.integrate_position(q, -step), v)
                          ) / (2 * FLOW_STEP)  # fmt: skip
        for j in range(n):
            h = FLOW_STEP * max(1.0, abs(float(v[j])))
            up, down = v.copy(), v.copy()
            up[j] += h
            down[j] -= h
            out[n:, n + j] = (self.acceleration(q, up) - self.acceleration(q, down)) / (2 * h)
        return out

    def embed(self, q: np.ndarray) -> np.ndarray:
        """The identity: the chart is MuJoCo's coordinates (``qpos``, nq)."""
        return np.array(q, dtype=float)

    def embed_jacobian(self, q: np.ndarray) -> np.ndarray:
        """The identity on the velocities (n x n: ``qvel`` is the floating velocity)."""
        return np.eye(self.n)

    def floating_mass(self, qf: np.ndarray) -> np.ndarray:
        """``M`` itself."""
        return self.mass(qf)

    def distance(self, geom1: int, geom2: int, q: np.ndarray) -> float:
        """The signed distance (m) of two geoms at ``q`` (``mj_geomDistance``; negative when
        they overlap)."""
        d = self._set_qpos(q)
        self.mj.mj_kinematics(self.model, d)
        return float(self.mj.mj_geomDistance(self.model, d, geom1, geom2, DISTMAX, None))

    def _no_points(self, name: str) -> np.ndarray:
        raise NotImplementedError(
            f"an MJCF model has no named planar point ({name!r}): its guards build their strikes"
        )

    def point(self, name: str, qf: np.ndarray) -> np.ndarray:
        """Not defined: an MJCF model's strikes are built by their guards."""
        return self._no_points(name)

    def point_jacobian(self, name: str, qf: np.ndarray) -> np.ndarray:
        """Not defined (see :meth:`point`)."""
        return self._no_points(name)

    def rod_foot(self, name: str, q: np.ndarray) -> np.ndarray:
        """Not defined (see :meth:`point`)."""
        return self._no_points(name)

    def point_in_chart(self, name: str, q: np.ndarray) -> np.ndarray:
        """Not defined (see :meth:`point`)."""
        return self._no_points(name)


@dataclass(frozen=True, kw_only=True, eq=False)
class MjcfMotion:
    """An MJCF model in motion: the hybrid ``model``, the ``state`` x = (qpos, qvel) of the
    keyframe (or ``qpos0`` at rest), the ``law`` of its strikes, a ``title``, and the geom
    ``pairs`` (ids, MuJoCo's order) its contact guards watch; ``quaternion_joints`` names
    its free and ball joints (``"free joint 'ball'"``), for what is not built for them yet."""

    model: HybridModel
    state: np.ndarray
    law: Law
    title: str
    pairs: tuple[tuple[int, int], ...]
    quaternion_joints: tuple[str, ...] = ()


def enabled(mujoco: Any, model: Any, flag: str) -> bool:
    """Whether the model leaves on what MuJoCo's disable ``flag`` (a ``mjtDisableBit`` name)
    and ``mjDSBL_CONSTRAINT`` (every constraint) turn off: its ``<option><flag .../>``.

    >>> import mujoco
    >>> m = mujoco.MjModel.from_xml_string('<mujoco><option><flag contact="disable"/>'
    ...                                    '</option><worldbody/></mujoco>')
    >>> enabled(mujoco, m, "mjDSBL_CONTACT"), enabled(mujoco, m, "mjDSBL_LIMIT")
    (False, True)
    """
    bits = mujoco.mjtDisableBit
    return not int(model.opt.disableflags) & (int(getattr(bits, flag))
                                              | int(bits.mjDSBL_CONSTRAINT))


def colliding_pairs(mujoco: Any, model: Any) -> tuple[tuple[int, int], ...]:
    """The geom pairs ``(g1, g2)``, ``g1 < g2``, that MuJoCo's collision can report: every
    explicit ``<pair>``, and every other pair of geoms on bodies not welded together, not
    parent and child (unless ``filterparent`` is disabled or one is the world), one's
    ``contype`` meeting the other's ``conaffinity``, and not ``<exclude>``-d.

    >>> import mujoco
    >>> m = mujoco.MjModel.from_xml_string('''<mujoco><worldbody>
    ...   <geom name="table" type="plane" size="1 1 .1"/>
    ...   <body pos="0 0 1"><joint type="hinge" axis="0 1 0"/>
    ...     <geom size=".1" contype="0" conaffinity="0"/>
    ...     <body pos=".5 0 0"><joint type="hinge" axis="0 1 0"/><geom size=".1"/></body>
    ...   </body></worldbody></mujoco>''')
    >>> colliding_pairs(mujoco, m)  # the table and the second link; the first has neither bit
    ((0, 2),)

    None where the model disables contacts (``<flag contact="disable"/>``, as dm_control's
    cart-pole; or every constraint).
    """
    if not enabled(mujoco, model, "mjDSBL_CONTACT"):  # (MuJoCo's flag: no contact at all)
        return ()
    explicit = {(int(min(a, b)), int(max(a, b)))
                for a, b in zip(model.pair_geom1, model.pair_geom2, strict=True)}  # fmt: skip
    excluded = {int(s) for s in model.exclude_signature}
    weld, parent = model.body_weldid, model.body_parentid
    filterparent = not model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT)
    contype, conaffinity, body = model.geom_contype, model.geom_conaffinity, model.geom_bodyid
    out = set(explicit)
    for g1 in range(model.ngeom):
        for g2 in range(g1 + 1, model.ngeom):
            b1, b2 = int(body[g1]), int(body[g2])
            w1, w2 = int(weld[b1]), int(weld[b2])
            if w1 == w2:  # one body, or bodies welded together (the world's statics too)
                continue
            p1, p2 = int(weld[parent[w1]]), int(weld[parent[w2]])
            if filterparent and w1 and w2 and (w1 == p2 or w2 == p1):
                continue
            if not (contype[g1] & conaffinity[g2] or contype[g2] & conaffinity[g1]):
                continue
            if (min(b1, b2) << 16) + max(b1, b2) in excluded:
                continue
            out.add((g1, g2))
    return tuple(sorted(out))


def mjcf_model(path: str | Path, *, keyframe: str | int | None = None,
               restitution: float | None = None, friction: float | None = None,
               law: str = "newton") -> MjcfMotion:  # fmt: skip
    """The MJCF model at ``path`` in motion (module docstring), in the state of
    ``keyframe`` (name or index; ``None``: ``qpos0`` at rest), its strikes under
    ``restitution`` (``None``: the model's ``carnot_restitution``, or 0), ``friction``
    (``None``: MuJoCo's) and ``law``. Errors name the file: an equality, a tendon limit,
    nothing to strike, geoms that overlap at the start.

    >>> motion = mjcf_model(drop_xml(), restitution=0.5)
    >>> [g.name for g in motion.model.guards], motion.model.coordinates, motion.law.restitution
    (['ball/floor'], ('height',), 0.5)
    >>> round(motion.model.guards[0].function(motion.state), 12)  # the gap (m)
    1.0
    """
    mujoco = load_mujoco()
    source = str(path)
    try:
        original = mujoco.MjModel.from_xml_path(source)
    except (ValueError, OSError) as err:
        message = " ".join(str(err).split())[:300]
        raise InputError(source, f"cannot read the MJCF model ({message})",
                         show_value=False) from None  # fmt: skip
    _check_supported(mujoco, original, source)
    names = [mujoco.mj_id2name(original, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"
             for g in range(original.ngeom)]  # fmt: skip
    pairs = colliding_pairs(mujoco, original)
    limited = [j for j in range(original.njnt) if original.jnt_limited[j]
               and enabled(mujoco, original, "mjDSBL_LIMIT")]  # fmt: skip
    cones = [j for j in limited if int(original.jnt_type[j]) == _BALL]
    stops = [j for j in limited if j not in cones]  # hinges, slides
    if not pairs and not limited:
        raise InputError(source, "has nothing to strike: no two geoms can collide (contype/"
                         "conaffinity, welded or parent bodies, exclude) and no joint has a "
                         "range", show_value=False)  # fmt: skip
    mechanism = _mechanism(mujoco, original)
    # MuJoCo's midphase (the bounding-volume tree over a body's geoms) ignores the geoms'
    # margins (MuJoCo 4.0): a body of several geoms, a rimless wheel's feet, has its contacts
    # within the margin missed. The copies that list contacts within a gap skip it (a saving
    # of time only: the pairs it would keep are all tried).
    midphase = int(mujoco.mjtDisableBit.mjDSBL_MIDPHASE)
    strikes = copy.copy(original)  # MuJoCo's contacts at the event: margins of STRIKE_GAP
    strikes.geom_margin[:] = np.maximum(strikes.geom_margin, STRIKE_GAP)
    strikes.opt.disableflags |= midphase
    for j in limited:  # (and the limit rows, which MuJoCo instantiates within their margin:
        # a cone's strike, and a stop's struck while a contact is held)
        strikes.jnt_margin[j] = max(float(strikes.jnt_margin[j]), STRIKE_GAP)
    strike_data = mujoco.MjData(strikes)
    holds = copy.copy(original)  # MuJoCo's contacts near closing, for the held rows
    holds.geom_margin[:] = np.maximum(holds.geom_margin, WATCH_GAP)
    holds.opt.disableflags |= midphase
    hold_data = mujoco.MjData(holds)
    title = Path(source).name + (f" at keyframe {keyframe}" if keyframe is not None else "")
    guards = [_contact_guard(mechanism, strikes, strike_data, holds, hold_data, g1, g2,
                             f"{names[g2]}/{names[g1]}", title) for g1, g2 in pairs]  # fmt: skip
    for j in stops:
        joint = mujoco.mj_id2name(original, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
        lo, hi = (float(v) for v in original.jnt_range[j])
        at = (int(original.jnt_qposadr[j]), int(original.jnt_dofadr[j]))
        guards += [_stop(mechanism, at, lo, 1.0, f"{joint} lower stop", joint),
                   _stop(mechanism, at, hi, -1.0, f"{joint} upper stop", joint)]
    for j in cones:
        joint = mujoco.mj_id2name(original, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
        at = (int(original.jnt_qposadr[j]), int(original.jnt_dofadr[j]))
        guards.append(_cone(mechanism, strikes, strike_data, at, float(original.jnt_range[j][1]),
                            joint, title))  # fmt: skip
    damped = bool(np.any(original.dof_damping > 0))
    # tendon dampers and the medium's drag (opt.density, opt.viscosity) are in qfrc_passive
    # too, but their power is not integrated: the ledger's residual is their work
    uncounted = bool(np.any(original.tendon_damping > 0) or original.opt.density > 0
                     or original.opt.viscosity > 0)  # fmt: skip
    # (MuJoCo's dry joint and tendon friction is a constraint, disabled in the flow with the
    # others: a model that has some moves without it, and says so)
    dry = enabled(mujoco, original, "mjDSBL_FRICTIONLOSS") and bool(
        np.any(original.dof_frictionloss > 0)
        or (original.ntendon and np.any(original.tendon_frictionloss > 0)))
    notes = ("MuJoCo's M and bias forces (actuators left out); contacts between geoms rigid, "
             "struck as carnot from-mjcf builds them; joint ranges as stops"
             + ("; the joints' dampers' work in the ledger (dampers)" if damped else "")
             + ("; dry joint and tendon friction (frictionloss) left out" if dry else "")
             + ("; the work of tendon dampers and of the medium's drag is not in the ledger: "
                "its residual" if uncounted else ""))
    model = HybridModel(
        name=Path(source).stem, parameters={}, coordinates=position_names(mujoco, original),
        floating=dof_names(mujoco, original), mechanism=mechanism, guards=tuple(guards),
        normal=np.array([0.0, 0.0, 1.0]), gravity=np.zeros(2),
        total_mass=float(np.sum(original.body_mass)), notes=notes,
    )  # fmt: skip
    state = _state(mujoco, original, keyframe, source)
    nq = mechanism.nq  # the start is an event: its quaternions made unit
    state = np.concatenate([mechanism.normalized(state[:nq]), state[nq:]])
    where = f"keyframe {keyframe}" if keyframe is not None else "qpos0"
    for g, (g1, g2) in zip(guards, pairs, strict=False):
        gap = g.function(state)
        if gap < -OVERLAP:
            raise InputError(f"{source}: {where}", f"starts with {names[g1]} and {names[g2]} "
                             f"overlapping by {-gap:.3g} m", show_value=False)  # fmt: skip
    e = _restitution(mujoco, original, source) if restitution is None else restitution
    if not 0.0 <= e <= 1.0:
        raise InputError("restitution", "must be in [0, 1]", e)
    return MjcfMotion(model=model, state=state, title=title, pairs=pairs,
                      law=Law(restitution=float(e), friction=friction, law=law),
                      quaternion_joints=quaternion_joints(mujoco, original))  # fmt: skip


def quaternion_joints(mujoco: Any, model: Any) -> tuple[str, ...]:
    """The model's free and ball joints, each as ``"free joint 'name'"`` (or ``ball``)."""
    out = []
    for j in range(model.njnt):
        kind = int(model.jnt_type[j])
        if kind in (_FREE, _BALL):
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
            out.append(f"{'free' if kind == _FREE else 'ball'} joint {name!r}")
    return tuple(out)


#: The names of a free joint's seven positions and a ball joint's four, after the joint's.
FREE_POSITIONS = (".x", ".y", ".z", ".qw", ".qx", ".qy", ".qz")
BALL_POSITIONS = (".qw", ".qx", ".qy", ".qz")


def position_names(mujoco: Any, model: Any) -> tuple[str, ...]:
    """A name per position (``qpos`` entry): a hinge's or a slide's the joint's (as
    :func:`carnot.model.mjcf.dof_names`), a free joint's ``name.x`` ... ``name.qz``, a ball
    joint's ``name.qw`` ... ``name.qz``."""
    out: list[str] = []
    for j in range(model.njnt):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
        kind = int(model.jnt_type[j])
        suffixes = FREE_POSITIONS if kind == _FREE else BALL_POSITIONS if kind == _BALL else ("",)
        out += [name + suffix for suffix in suffixes]
    return tuple(out)


def _check_supported(mujoco: Any, model: Any, source: str) -> None:
    """No active equality, no tendon limit: what the flow and the guards can carry (but
    where the model's own flags disable them)."""
    active = [k for k in range(model.neq) if model.eq_active0[k]]  # (inactive at the start:
    # MuJoCo moves the model without it until a controller turns it on, and so does carnot)
    if active and enabled(mujoco, model, "mjDSBL_EQUALITY"):
        k = active[0]
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, k) or f"equality{k}"
        raise InputError(f"{source}: equality {name!r}", "is not held in motion yet (the "
                         "flow has no equality constraint)", show_value=False)  # fmt: skip
    if (model.ntendon and np.any(model.tendon_limited)
            and enabled(mujoco, model, "mjDSBL_LIMIT")):  # fmt: skip
        raise InputError(f"{source}: tendon", "limits are not stops in motion yet",
                         show_value=False)  # fmt: skip


def _mechanism(mujoco: Any, original: Any) -> MujocoMechanism:
    flow = copy.copy(original)
    off = mujoco.mjtDisableBit
    flow.opt.disableflags |= int(off.mjDSBL_CONSTRAINT | off.mjDSBL_CONTACT
                                 | off.mjDSBL_ACTUATION | off.mjDSBL_SENSOR)  # fmt: skip
    flow.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    # the gaps of general convex pairs (GJK/EPA) to round-off, not to MuJoCo's 1e-6 m
    flow.opt.ccd_tolerance = 1e-12
    flow.opt.ccd_iterations = max(int(flow.opt.ccd_iterations), 200)
    damping = np.array(original.dof_damping, dtype=float)
    power = (partial(damper_power, damping, int(original.nq)) if np.any(damping > 0)
             else None)  # fmt: skip
    return MujocoMechanism(n=int(original.nv), model=flow, data=mujoco.MjData(flow), mj=mujoco,
                           layout=joint_layout(mujoco, original),
                           damping_power=power)  # fmt: skip


def _strike_problem(mech: MujocoMechanism, strikes: Any, strike_data: Any, title: str
                    ) -> Callable[..., SystemProblem]:  # fmt: skip
    """A guard's strike: the impact ``carnot from-mjcf`` builds at the state ``x`` (MuJoCo's
    contacts and limit rows within ``STRIKE_GAP`` of the model ``strikes``), under ``law``;
    with ``resting`` (contacts are held in the flow) the closed contacts at rest take part
    too, a held one's normal speed at most ``HELD_SPEED`` of the velocity's size."""
    nq = mech.nq

    def problem(x: np.ndarray, law: Law, resting: bool = False) -> SystemProblem:
        qvel = np.asarray(x[nq:], dtype=float)
        return mjcf_problem(strikes, qpos=mech.normalized(x[:nq]).tolist(), qvel=qvel.tolist(),
                            restitution=law.restitution, law=law.law, friction=law.friction,
                            tangential="slip", gap=STRIKE_GAP, data=strike_data,
                            title=title, resting=resting,
                            rest_speed=HELD_SPEED * max(1.0, float(np.linalg.norm(qvel)))
                            )  # fmt: skip

    return problem


#: One contact of a pair: ``(dist, rows, pos, friction, frictionless, label)``
#: (:func:`pair_contacts`).
PairContact = tuple[float, np.ndarray, np.ndarray, float, bool, np.ndarray]


def pair_contacts(mech: MujocoMechanism, holds: Any, hold_data: Any, g1: int, g2: int,
                  q: np.ndarray) -> list[PairContact]:  # fmt: skip
    """MuJoCo's contacts between the geoms ``g1`` and ``g2`` at ``q`` within ``WATCH_GAP``
    (the model ``holds``, its margins that gap; ``mj_kinematics``, ``mj_comPos``,
    ``mj_collision``), in MuJoCo's order: each ``(dist, rows, pos, friction,
    frictionless, label)``, ``rows`` the contact frame times the relative Jacobian at the contact
    point (3 x nv: the normal's row, then the frame's two tangents'; ``J = J_a(p) - J_b(p)``,
    ``a`` the body of MuJoCo's ``geom[1]``, as :func:`carnot.model.mjcf.mjcf_problem`
    builds a contact), ``friction`` MuJoCo's combined sliding coefficient (0 with
    ``condim`` 1, ``frictionless``), ``label`` the point in the frame of ``g2``'s body (or
    ``g1``'s, where ``g2`` is the world's)."""
    key = (id(hold_data), np.asarray(q, dtype=float).tobytes())
    found = _COLLIDED.get(key)
    if found is None or found[0] is not hold_data:
        found = (hold_data, _collide(mech, holds, hold_data, q))
        if len(_COLLIDED) >= COLLIDED_STATES:
            del _COLLIDED[next(iter(_COLLIDED))]
        _COLLIDED[key] = found
    pair = (min(g1, g2), max(g1, g2))
    return [c for p, c in found[1] if p == pair]


#: How many states' collisions are kept: one state's rows and their difference along the
#: flow are five states, which every held pair of the model shares.
COLLIDED_STATES = 16
_COLLIDED: dict[tuple[int, bytes], tuple[Any, list[tuple[tuple[int, int], PairContact]]]] = {}


def _collide(mech: MujocoMechanism, holds: Any, hold_data: Any, q: np.ndarray
             ) -> list[tuple[tuple[int, int], PairContact]]:  # fmt: skip
    """Every contact MuJoCo finds at ``q`` in ``holds``, with its pair (:func:`pair_contacts`)."""
    mj, d = mech.mj, hold_data
    d.qpos[:] = q
    if mech.layout.quaternions:
        mj.mj_normalizeQuat(holds, d.qpos)
    mj.mj_kinematics(holds, d)
    mj.mj_comPos(holds, d)
    mj.mj_collision(holds, d)
    out = []
    bodies = holds.geom_bodyid
    for i in range(int(d.ncon)):
        c = d.contact[i]
        a, b = int(c.geom[0]), int(c.geom[1])
        g1, g2 = min(a, b), max(a, b)
        point = np.array(c.pos, dtype=float)
        jac = np.zeros((3, mech.n))
        for body, sign in ((int(bodies[b]), 1.0), (int(bodies[a]), -1.0)):
            if body:
                part = np.zeros((3, mech.n))
                mj.mj_jac(holds, d, part, None, point, body)
                jac += sign * part
        frame = np.array(c.frame, dtype=float).reshape(3, 3)
        dim = int(c.dim)
        body = int(bodies[g2]) or int(bodies[g1])  # the label's frame: a moving body's
        label = np.array(d.xmat[body]).reshape(3, 3).T @ (point - np.array(d.xpos[body]))
        out.append(((g1, g2), (float(c.dist), frame @ jac, point,
                               float(c.friction[0]) if dim > 1 else 0.0, dim == 1,
                               label)))  # fmt: skip
    return out


def _contact_guard(mech: MujocoMechanism, strikes: Any, strike_data: Any, holds: Any,
                   hold_data: Any, g1: int, g2: int, name: str, title: str) -> Guard:  # fmt: skip
    """The pair ``g1``, ``g2``: struck where its distance falls through zero (module
    docstring), held on the contacts MuJoCo finds between them (:func:`pair_contacts`)."""
    n, nq = mech.n, mech.nq

    def gap(x: np.ndarray) -> float:
        return mech.distance(g1, g2, x[:nq])

    def gradient(x: np.ndarray) -> np.ndarray:
        # d G / d qpos, a quaternion's four entries too: G sees them normalized, so the
        # gradient has no part along a quaternion, and G' = grad . q' holds on the flow
        out = np.zeros(nq + n)
        q = np.array(x[:nq], dtype=float)
        for j in range(nq):
            h = GAP_STEP * max(1.0, abs(float(q[j])))
            up, down = q.copy(), q.copy()
            up[j] += h
            down[j] -= h
            out[j] = (mech.distance(g1, g2, up) - mech.distance(g1, g2, down)) / (2 * h)
        return out

    last: list[Any] = [None, ()]  # the last state's rows (the flow asks for them often)

    def rows(x: np.ndarray) -> tuple[GapRows, ...]:
        # each contact's rows at the state, and their biases by a central difference along
        # the flow, of fourth order: b = d/dt (rows(q)) qvel, d/dt r = (8 (r(tau) - r(-tau))
        # - (r(2 tau) - r(-2 tau))) / (12 tau), r(s) = rows(q + s q') (mj_jacDot is a
        # material point's: it misses the contact point's own motion over a curved surface,
        # the curvature term R |w_perp|^2 of a rolling sphere's gap)
        key = np.asarray(x, dtype=float).tobytes()
        if last[0] == key:
            return last[1]
        q = mech.normalized(x[:nq])
        v = np.asarray(x[nq:], dtype=float)
        here = pair_contacts(mech, holds, hold_data, g1, g2, q)
        rate = mech.position_rate(q, v)
        size = float(np.linalg.norm(rate))
        biases = [np.zeros(3) for _ in here]
        if size > 0 and here:
            tau = HOLD_STEP / size
            near = [pair_contacts(mech, holds, hold_data, g1, g2, q + s * tau * rate)
                    for s in (1, -1, 2, -2)]  # fmt: skip
            points = np.array([c[2] for c in here])
            labels = np.array([c[5] for c in here])
            for i in range(len(here)):
                r1, r_1, r2, r_2 = (_match(found, points, labels, i, abs(s) * HOLD_STEP)
                                    for found, s in zip(near, (1, -1, 2, -2), strict=True))
                step = tau
                while (r1 is None or r_1 is None) and step > tau * HOLD_SHRINK**-2:
                    # it leaves MuJoCo's list within the step (a vertex that another takes
                    # over from): a second difference over a shorter one
                    step /= HOLD_SHRINK
                    r1, r_1 = (_match(pair_contacts(mech, holds, hold_data, g1, g2,
                                                    q + s * step * rate), points, labels, i,
                                      HOLD_STEP * step / tau)
                               for s in (1, -1))  # fmt: skip
                    r2 = None
                if r1 is None or r_1 is None:  # a point fast off its surface, never held,
                    continue  # needs no bias (a held one's drift is watched: flow.py)
                if r2 is None or r_2 is None:
                    biases[i] = (r1 - r_1) @ v / (2 * step)
                else:
                    biases[i] = (8 * (r1 - r_1) - (r2 - r_2)) @ v / (12 * step)
        out = tuple(GapRows(normal=r[0], normal_bias=float(b[0]),
                            tangent=None if smooth else r[1:3], tangent_bias=b[1:3], gap=dist,
                            friction=None if smooth else mu, label=label)
                    for (dist, r, _, mu, smooth, label), b in zip(here, biases, strict=True)
                    )  # fmt: skip
        last[:] = [key, out]
        return out

    return Guard(name=name, function=gap, gradient=gradient, direction=-1, striking=name,
                 holding=(), relabel=np.eye(nq), offset=np.zeros(nq),
                 velocity_relabel=np.eye(n), moves_anchor=False,
                 problem=_strike_problem(mech, strikes, strike_data, f"{title}: {name}"),
                 rows=rows, several=True, reach=STRIKE_GAP)  # fmt: skip


def _match(found: list[PairContact], points: np.ndarray, labels: np.ndarray, i: int,
           reach: float) -> np.ndarray | None:  # fmt: skip
    """The rows of the contact in ``found`` (a neighbouring state's, ``|dq| = reach`` away)
    that is the ``i``-th of ``points`` (this state's contact points, world, m; ``labels``
    theirs, in a body's frame): the ``i``-th of ``found`` where it lies nearest
    ``points[i]``, else the nearest, provided that ``points[i]`` is in turn the point of
    ``points`` nearest it, and that its label is within ``reach`` (m) of ``labels[i]`` (a
    vertex keeps its label; a rolling sphere's moves by its roll, at most the step);
    ``None`` where there is none such. A point that MuJoCo no longer lists there (a mesh's
    vertex that its plane collider, which lists the deepest vertex and a few of its
    neighbours, leaves out) is not matched to another: the difference of two points' rows
    is no bias."""
    if not found:
        return None
    point = points[i]
    offsets = np.array([c[2] for c in found]) - point
    squares = np.einsum("ij,ij->i", offsets, offsets)
    near = int(np.argmin(squares))
    at = i if i < len(found) and squares[i] <= squares[near] else near
    back = points - found[at][2]
    if int(np.argmin(np.einsum("ij,ij->i", back, back))) != i:
        return None  # the nearest there is another point's
    if float(np.linalg.norm(found[at][5] - labels[i])) > reach:
        return None  # another point, which MuJoCo lists there in this one's place
    return found[at][1]


def _stop(mech: MujocoMechanism, where: tuple[int, int], bound: float, sign: float, name: str,
          joint: str) -> Guard:  # fmt: skip
    """A hinge's or a slide's stop: ``g = sign (q_k - bound) >= 0`` (``k`` its position,
    ``where = (qposadr, dofadr)``), its gradient ``d g / d x`` (``sign`` at ``k``) and its
    row ``d g / d qvel`` (``sign`` at the joint's dof: its rate is the joint's velocity)."""
    n, nq = mech.n, mech.nq
    k, dof = where
    row = np.zeros(n)
    row[dof] = sign
    grad = np.zeros(nq + n)
    grad[k] = sign
    return Guard(name=name, function=lambda x: sign * (float(x[k]) - bound),
                 gradient=lambda x: grad.copy(), direction=-1, striking=f"limit {joint}",
                 holding=(), relabel=np.eye(nq), offset=np.zeros(nq),
                 velocity_relabel=np.eye(n), moves_anchor=False, limit_row=row)  # fmt: skip


def cone_angle(quat: np.ndarray) -> float:
    """A ball joint's rotation angle ``theta = 2 atan2(|v|, |w|)`` (rad, in ``[0, pi]``) of its
    quaternion ``[w, v]`` (``q`` and ``-q`` the same rotation), as MuJoCo measures its cone.

    >>> round(cone_angle(np.array([np.cos(0.35), 0.0, np.sin(0.35), 0.0])), 12)
    0.7
    """
    return 2.0 * math.atan2(float(np.linalg.norm(quat[1:4])), abs(float(quat[0])))


def _cone(mech: MujocoMechanism, strikes: Any, strike_data: Any, where: tuple[int, int],
          bound: float, joint: str, title: str) -> Guard:  # fmt: skip
    """A ball joint's cone (module docstring): ``g = bound - theta``, its gradient in position
    space (``d theta / d quat``, of the normalized quaternion: no part along it), struck as
    :func:`carnot.model.mjcf.mjcf_problem` builds it (MuJoCo's limit row ``-n`` and the
    contacts then closed), held by :class:`GapRows` ``(-n, -cot(theta/2) |w_perp|^2 / 2)``."""
    n, nq = mech.n, mech.nq
    k, dof = where
    name = f"{joint} cone"

    def parts(x: np.ndarray) -> tuple[float, np.ndarray, float]:
        quat = np.asarray(x[k : k + 4], dtype=float)
        quat = quat / np.linalg.norm(quat)
        if quat[0] < 0.0:  # the same rotation, its angle in [0, pi]
            quat = -quat
        size = float(np.linalg.norm(quat[1:]))
        theta = cone_angle(quat)
        axis = quat[1:] / size if size > 0.0 else np.zeros(3)
        return theta, axis, float(quat[0])

    def gap(x: np.ndarray) -> float:
        return bound - parts(x)[0]

    def gradient(x: np.ndarray) -> np.ndarray:
        # theta = 2 atan2(s, c), s = |v|, c = w on the unit sphere: d theta = 2 (c ds - s dc),
        # ds = n . dv; the normalization's part along the quaternion taken out
        theta, axis, c = parts(x)
        quat = np.asarray(x[k : k + 4], dtype=float)
        size = float(np.linalg.norm(quat))
        sign = 1.0 if quat[0] >= 0.0 else -1.0
        d = 2.0 * sign * np.concatenate([[-math.sin(theta / 2)], c * axis]) / size
        d -= (d @ quat) * quat / size**2
        out = np.zeros(nq + n)
        out[k : k + 4] = -d
        return out

    def rows(x: np.ndarray) -> GapRows:
        theta, axis, _ = parts(x)
        omega = np.asarray(x[nq + dof : nq + dof + 3], dtype=float)
        across = omega - (axis @ omega) * axis
        row = np.zeros(n)
        row[dof : dof + 3] = -axis
        bias = -0.5 * float(across @ across) / math.tan(theta / 2)
        return GapRows(normal=row, normal_bias=bias)

    return Guard(name=name, function=gap, gradient=gradient, direction=-1,
                 striking=f"limit {joint}", holding=(), relabel=np.eye(nq),
                 offset=np.zeros(nq), velocity_relabel=np.eye(n), moves_anchor=False,
                 problem=_strike_problem(mech, strikes, strike_data, f"{title}: {name}"),
                 rows=rows, reach=STRIKE_GAP)  # fmt: skip


def _state(mujoco: Any, model: Any, keyframe: str | int | None, source: str) -> np.ndarray:
    """x = (qpos, qvel) of the keyframe, or (qpos0, 0)."""
    if keyframe is None:
        return np.concatenate([np.array(model.qpos0, dtype=float), np.zeros(model.nv)])
    index = keyframe_id(mujoco, model, keyframe, source)
    return np.concatenate([np.array(model.key_qpos[index], dtype=float),
                           np.array(model.key_qvel[index], dtype=float)])  # fmt: skip


def _restitution(mujoco: Any, model: Any, source: str) -> float:
    """The model's ``<custom><numeric name="carnot_restitution" data="e"/>``, or 0."""
    index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, RESTITUTION_KEY)
    if index < 0:
        return 0.0
    adr, size = int(model.numeric_adr[index]), int(model.numeric_size[index])
    values = [float(v) for v in model.numeric_data[adr : adr + size]]
    if size != 1 or not 0.0 <= values[0] <= 1.0:
        raise InputError(f"{source}: custom numeric {RESTITUTION_KEY}",
                         "must be one number in [0, 1]", values)  # fmt: skip
    return values[0]

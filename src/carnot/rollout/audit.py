"""An exact per-step energy audit of a MuJoCo rollout, with its impact episodes.

**The discrete theorem.** MuJoCo's Euler step (``mj_Euler``: ``engine_forward.c``) and its
implicit ones (``mj_implicitSkip``) update the velocity from ``v0`` to ``v1`` with the mass
matrix ``M0 = M(q0)`` of the step's start:

    M0 (v1 - v0) = h [ f_smooth + J^T lambda ] + h D (v1 - v0)

where ``f_smooth = qfrc_smooth`` (gravity and Coriolis ``-qfrc_bias``, ``qfrc_passive``,
``qfrc_actuator``, the applied forces), ``J^T lambda = efc_J^T efc_force`` the constraint
forces, and ``D`` the velocity derivative the integrator treats implicitly (Euler: minus the
joint damping on the diagonal; implicitfast/implicit: ``qDeriv``). Multiplying by the mean
velocity ``(v0 + v1)/2`` and using the symmetry of ``M0`` gives, exactly,

    1/2 v1^T M0 v1 - 1/2 v0^T M0 v0 = sum_rows h lambda_r J_r (v0 + v1)/2 + h f . (v0 + v1)/2

the paper's theorem (eq. 11: the work of an impulse is the impulse times the mean of the
velocities before and after) applied to every constraint row, one step at a time. carnot
splits it per contact pair and per joint limit / equality / friction-loss row and reports the
``residual`` (round-off for these integrators), and apart the integrator's own terms: the
change of ``M`` over the step, ``1/2 v1^T (M1 - M0) v1`` (``mass_change``) and the potential
energy MuJoCo computes (``mj_energy``). RK4 (four force evaluations per step) and the
discrete integrator have no such split: they are reported as unsupported, never approximated.

**Episodes.** A contact pair (two geoms) starts an impact episode in the step in which it
pushes (a nonzero constraint force) while its normal relative velocity approaches faster than
``min_speed``; the episode ends at the first step in which it no longer pushes. MuJoCo's
effective restitution is ``e = -w_n'' / w_n'`` (the pair's normal velocity right after the
last pushing step over the one before the first), its tangential restitution
``e_t = -(w_t'' . t) / |w_t'|`` along the initial slip direction ``t``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from carnot.errors import CarnotError, InputError
from carnot.keys import exact_key
from carnot.laws.registry import LAW_NAMES, MULTIPLE_IMPACT_NAMES
from carnot.model.mjcf import EQUALITY_KINDS, load_mujoco
from carnot.rollout.inplace import (
    ACC_OTHER,
    ACC_PAIRS,
    ACTUATOR,
    BIAS,
    BUFFERS,
    CAPACITY,
    CDOF,
    CHECK,
    CHECKED,
    CLOCK,
    CODES,
    DATA,
    DERIV,
    ENERGY,
    FULL,
    GROW,
    LAYOUT,
    LAYOUT_SIZE,
    MASS,
    NQ,
    OPEN,
    OPEN_COUNT,
    OTHER_WIDTH,
    PAIR_CAPACITY,
    PAIRS,
    PARAMS,
    PASSIVE,
    QPOS,
    QVEL,
    ROWS,
    SMOOTH,
    SPARSE,
    STATES,
    STEP,
    SUBTREE_COM,
    TABLE,
    USED_OTHER,
    USED_PAIRS,
    VALUES,
    WEIGHTS,
    WEIGHTS_SIZE,
    WRONG_TIME,
    XIPOS,
    check_moving,
    data_fields,
    observe_in_place,
)
from carnot.rollout.kernel import (
    APPROACHING,
    CALM,
    COLUMNS,
    NEEDS_KINDS,
    OTHER_KINDS,
    StepArrays,
    layout_of,
    other_width,
    pair_sums,
    step_sums,
)

#: The integrators whose step has the exact split (MuJoCo's enum names, lower case).
EXACT_INTEGRATORS = ("euler", "implicit", "implicitfast")

#: The sources of generalized force whose work the audit reports per step.
SOURCES = ("constraints", "gravity", "coriolis", "passive", "actuator", "applied", "implicit")

#: The most geom pairs the audit tables (a 2048-geom model: 38 MiB of totals).
MAX_PAIR_TABLE = 2048 * 2048

#: Which contacts the rigid reference solves (:class:`RigidSettings`' ``scope``).
RIGID_SCOPES = ("coupled", "scene")

_CONTACT = 5  # mjCNSTR_CONTACT_FRICTIONLESS; the pyramidal (6) and elliptic (7) follow
_ROW_KINDS = {0: "equality", 1: "dof friction", 2: "tendon friction", 3: "joint limit",
              4: "tendon limit"}  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class RigidSettings:
    """The rigid impact law of the reference (carnot's outcome from each episode's
    pre-impact state): Newton/Poisson/Stronge ``law`` with coefficient ``restitution``,
    ``tangential`` slip (Coulomb) or stick, ``friction`` (None: MuJoCo's, from the geoms)
    and the law of several contacts at once; ``scope``: which contacts touching then are
    solved, ``"coupled"`` (the default: those coupled to the episode's pair through the
    Delassus operator, :mod:`carnot.model.coupling`) or ``"scene"`` (all of them at once);
    ``gap`` (m): the contacts within it are the reference's (None: the model's largest geom
    margin, at least 1e-6 m); ``equality`` (``pin``, ``fasten``, ``ignore``) and ``drift``
    (the pins' stated tolerance, m/s) what MuJoCo's equalities become, ``limits`` whether its
    joint and tendon limits take part (:func:`carnot.model.mjcf.mjcf_problem`).

    >>> RigidSettings(restitution=1.5)
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: restitution: must be in [0, 1], got 1.5
    """

    restitution: float = 0.0
    law: str = "newton"
    tangential: str = "slip"
    friction: float | None = None
    multiple_impact: str = "simultaneous"
    scope: str = "coupled"
    gap: float | None = None
    equality: str = "pin"
    drift: float | None = None
    limits: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.restitution) and 0.0 <= self.restitution <= 1.0):
            raise InputError("restitution", "must be in [0, 1]", self.restitution)
        for key, number in (("friction", self.friction), ("gap", self.gap),
                            ("drift", self.drift)):  # fmt: skip
            if number is not None and not (math.isfinite(number) and number >= 0):
                raise InputError(key, "must be a finite number >= 0", number)
        for name, value, known in (
            ("law", self.law, LAW_NAMES),
            ("tangential", self.tangential, ("slip", "stick")),
            ("multiple_impact", self.multiple_impact, MULTIPLE_IMPACT_NAMES),
            ("scope", self.scope, RIGID_SCOPES),
            ("equality", self.equality, EQUALITY_KINDS),
        ):
            if value not in known:
                raise InputError(name, f"must be one of {', '.join(known)}", value)


@dataclass(frozen=True, kw_only=True)
class StepLedger:
    """Per-step energies (J) of a rollout of ``count`` steps of ``timestep`` (s).

    ``time``, the works (``work[source]``, J, one entry per step), ``mass_change`` and
    ``residual`` have one entry per step; ``energy`` (MuJoCo's ``mj_energy`` total),
    ``kinetic`` and ``potential`` one per state (count + 1). For every step k, exactly
    (``exact``):

        kinetic[k+1] - kinetic[k] = sum_s work[s][k] + mass_change[k] + residual[k]

    ``by_constraint``: the total work of each contact pair / limit / equality (J);
    ``constraint_work``: ``work["constraints"]`` of each step split by the rows' kind
    (``contacts``, ``limits``, ``equalities``, ``friction_loss``: J, one entry per step).
    """

    integrator: str
    exact: bool
    reason: str
    timestep: float
    time: np.ndarray
    energy: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    work: Mapping[str, np.ndarray]
    mass_change: np.ndarray
    residual: np.ndarray
    by_constraint: Mapping[str, float]
    constraint_work: Mapping[str, np.ndarray] = field(default_factory=dict)

    @property
    def count(self) -> int:
        """The number of steps audited."""
        return int(self.time.size)

    @property
    def max_abs_residual(self) -> float:
        """The largest absolute residual of a step (J); NaN where the split is unsupported."""
        if not self.exact or self.residual.size == 0:
            return math.nan if not self.exact else 0.0
        return float(np.max(np.abs(self.residual)))


@dataclass(frozen=True, kw_only=True)
class Episode:
    """One impact episode of a contact pair (module docstring): times (s), energies (J),
    velocities (m/s), the mean contact ``point`` (world, m) of its first step and, when
    asked, carnot's rigid outcome from the pre-impact state. ``first_step``: the index of its
    first step in the ledger (its steps are ``first_step`` to ``first_step + steps - 1``);
    ``split``: where its :attr:`energy_lost` went (:data:`SPLIT_KEYS`, J removed: the
    negated works of its steps; None where the integrator has no exact split)."""

    pair: tuple[str, str]
    start: float
    end: float
    steps: int
    complete: bool
    energy_before: float
    energy_after: float
    contact_work: float
    normal_velocity_before: float
    normal_velocity_after: float
    tangential_velocity_before: np.ndarray
    tangential_velocity_after: np.ndarray | None
    qpos_before: np.ndarray
    qvel_before: np.ndarray
    qvel_after: np.ndarray
    point: np.ndarray
    rigid: Any = None
    rigid_error: str = ""
    rigid_normal_velocity_after: float = math.nan
    rigid_tangential_velocity_after: np.ndarray | None = None
    first_step: int = -1
    split: Mapping[str, float] | None = None

    @property
    def energy_lost(self) -> float:
        """The drop of MuJoCo's own total energy (``mj_energy``) over the episode (J)."""
        return self.energy_before - self.energy_after

    @property
    def effective_restitution(self) -> float:
        """MuJoCo's ``e = -w_n'' / w_n'``."""
        return -self.normal_velocity_after / self.normal_velocity_before

    @property
    def tangential_restitution(self) -> float | None:
        """``e_t = -(w_t'' . t) / |w_t'|`` (None without slip before, below
        :data:`NO_SLIP` of the approach speed, or without the tangential rows: a
        frictionless contact; :attr:`tangential_note` says which)."""
        return _tangential_restitution(
            self.tangential_velocity_before, self.tangential_velocity_after,
            self.normal_velocity_before,
        )  # fmt: skip

    @property
    def tangential_note(self) -> str:
        """Why there is no :attr:`tangential_restitution` (empty where there is one).

        >>> import numpy as np
        >>> e = Episode(pair=("floor", "ball"), start=0.0, end=0.01, steps=5, complete=True,
        ...             energy_before=1.0, energy_after=0.5, contact_work=-0.5,
        ...             normal_velocity_before=-1.0, normal_velocity_after=0.2,
        ...             tangential_velocity_before=np.array([1e-9, 0, 0]),
        ...             tangential_velocity_after=np.array([0.3, 0, 0]), qpos_before=np.zeros(1),
        ...             qvel_before=np.zeros(1), qvel_after=np.zeros(1), point=np.zeros(3))
        >>> e.tangential_restitution is None, e.tangential_note
        (True, 'no slip before')
        """
        if self.tangential_velocity_after is None:
            return "frictionless"
        return "no slip before" if self.tangential_restitution is None else ""

    @property
    def rigid_restitution(self) -> float:
        """The rigid reference's ``-w_n'' / w_n'`` for this pair (NaN without one)."""
        return -self.rigid_normal_velocity_after / self.normal_velocity_before

    @property
    def rigid_tangential_restitution(self) -> float | None:
        """The rigid reference's ``e_t`` for this pair."""
        return _tangential_restitution(
            self.tangential_velocity_before, self.rigid_tangential_velocity_after,
            self.normal_velocity_before,
        )  # fmt: skip

    @property
    def rigid_flags(self) -> tuple[str, ...]:
        """The rigid reference's warning codes (DESIGN.md section 9), in order."""
        return () if self.rigid is None else tuple(self.rigid.flag_codes())

    @property
    def rigid_unique(self) -> bool | None:
        """Whether the reference's velocities are the only ones the law allows: the
        certificate's ``velocities_unique`` (several contacts), True for one contact's law
        (it has one answer), None where not verified or without a reference."""
        if self.rigid is None:
            return None
        cert = self.rigid.solver
        if cert is None:
            return False if "multiple_solutions" in self.rigid_flags else True
        return cert.velocities_unique

    @property
    def rigid_dissipated_range(self) -> tuple[float, float] | None:
        """The least and the most E_d (J) over the reference and its alternatives where the
        law has several answers (``multiple_solutions``); without alternatives, the
        certificate's range where it spans a family of answers; else None."""
        if self.rigid is None:
            return None
        if not self.rigid.alternatives:
            cert = self.rigid.solver
            span = None if cert is None else cert.dissipated_range
            return span if span is not None and span[0] != span[1] else None
        values = [float(r.energy.dissipated) for r in (self.rigid, *self.rigid.alternatives)]
        return min(values), max(values)

    @property
    def rigid_verdict(self) -> str:
        """Why the reference gives no numbers to compare (empty where it does): not computed
        (:attr:`rigid_error`), or a law that found no answer (``no_solution``: its impulses
        are zero, not an outcome), stopped short (``not_converged``) or broke its own
        conditions (:data:`FAILED_FLAGS`)."""
        if self.rigid is None:
            return f"no reference: {self.rigid_error}" if self.rigid_error else ""
        failed = [c for c in self.rigid_flags if c in FAILED_FLAGS]
        if failed:
            return f"no rigid answer ({', '.join(failed)})"
        return f"no reference: {self.rigid_error}" if self.rigid_error else ""

    @property
    def rigid_dissipated(self) -> float:
        """The rigid reference's E_d (J; NaN without one)."""
        return math.nan if self.rigid is None else float(self.rigid.energy.dissipated)


#: The slip before an episode, relative to its approach speed ``|w_n'|``, below which no
#: tangential restitution is reported: the ratio ``-(w_t'' . t)/|w_t'|`` then divides by a
#: contact's round-off or sticking drift (2.4e5 and -1.3e8 on Unitree's feet), not by a slip.
NO_SLIP = 1e-4

#: The reference's flags that leave it without an outcome to compare (``rigid_verdict``):
#: no answer, a solver stopped short, or an answer that breaks the law's own conditions or
#: the arithmetic (a contact that pulls; a ledger whose two routes disagree: Go2's calf
#: limit and a self-contact of the same leg make the Delassus operator singular and the
#: iterative answer carries 1e13 N s impulses that cancel).
FAILED_FLAGS = ("no_solution", "not_converged", "negative_normal_impulse", "ledger_not_closed")

#: The keys of an episode's ``split`` (J removed over its steps): its own pair's contact
#: rows, the other contacts', the joint and tendon limits', the equalities', friction loss's,
#: damping (``qfrc_passive``: springs and dampers, and the implicit damping), the
#: actuators', and the rest (gravity against the potential's change, Coriolis against the
#: change of ``M``, applied forces, the residual).
SPLIT_KEYS = ("pair", "other_contacts", "limits", "equalities", "friction_loss", "damping",
              "actuators", "rest")  # fmt: skip


def _tangential_restitution(
    before: np.ndarray, after: np.ndarray | None, normal_before: float
) -> float | None:
    speed = float(np.linalg.norm(before))
    if after is None or not speed > max(1e-9, NO_SLIP * abs(normal_before)):
        return None
    return -float(np.dot(after, before)) / speed**2


def _episode_split(episode: Episode, table: Mapping[str, np.ndarray]) -> dict[str, float]:
    """Where an episode's :attr:`Episode.energy_lost` went (:data:`SPLIT_KEYS`), from its
    steps' rows of the ledger: each term the negated work over them; ``rest`` what remains."""
    k = episode.first_step
    rows = slice(k, k + episode.steps)

    def total(*names: str) -> float:
        return float(sum(np.sum(table[n][rows]) for n in names))

    kinds = ("equality", "dof_friction", "tendon_friction", "joint_limit", "tendon_limit")
    contacts = total("constraints") - total(*kinds)
    out = {
        "pair": -episode.contact_work,
        "other_contacts": -(contacts - episode.contact_work),
        "limits": -total("joint_limit", "tendon_limit"),
        "equalities": -total("equality"),
        "friction_loss": -total("dof_friction", "tendon_friction"),
        "damping": -total("passive", "implicit"),
        "actuators": -total("actuator"),
    }
    out["rest"] = episode.energy_lost - sum(out.values())
    return out


@dataclass(frozen=True, kw_only=True)
class AuditReport:
    """The audit of a rollout: its episodes and its step ledger; ``warnings``: sentences
    about what the audit could not check (a replay without what the model needs)."""

    episodes: tuple[Episode, ...]
    steps: StepLedger
    settings: RigidSettings | None
    min_speed: float
    title: str = ""
    warnings: tuple[str, ...] = ()


@dataclass
class _Open:  # an episode under way (mutable while the rollout runs)
    pair: tuple[str, str]
    start_step: int
    start: float
    energy_before: float
    wn_before: float
    wt_before: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    point: np.ndarray
    work: float = 0.0
    wn_after: float = 0.0
    wt_after: list[float] | None = None
    qvel_after: np.ndarray = field(default_factory=lambda: np.zeros(0))
    steps: int = 0


class EnergyAudit:
    """The energy audit of a rollout, fed step by step from the caller's own loop.

    Construct it on the state the rollout starts from, then call :meth:`observe` after
    every ``mujoco.mj_step(model, data)`` (or :meth:`step`, which steps and observes), and
    :meth:`finish` at the end. It switches on ``mjENBL_ENERGY`` in ``model.opt`` (MuJoCo's
    own energy) and never changes ``data``. Each step is read from ``data`` in place, in one
    compiled call (:mod:`carnot.rollout.inplace`), where MjData's layout checks out; through
    MuJoCo's bindings otherwise.

    ``rigid``: the law of the rigid reference of each episode (None: no reference);
    ``min_speed`` (m/s): the approach speed that opens an episode (default ``2 |g| h``: a
    resting contact's per-step jitter stays below it).

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string(
    ...     '<mujoco><worldbody><body><freejoint/><geom size=".1"/></body></worldbody></mujoco>')
    >>> data = mujoco.MjData(model)
    >>> data.qvel[:] = [1.0, 0.0, 2.0, 3.0, 1.0, 0.5]
    >>> audit = EnergyAudit(model, data)
    >>> for _ in range(100):
    ...     mujoco.mj_step(model, data)
    ...     audit.observe()
    >>> report = audit.finish()
    >>> report.steps.count, report.steps.max_abs_residual < 1e-14, report.episodes
    (100, True, ())
    """

    def __init__(
        self,
        model: Any,
        data: Any,
        *,
        rigid: RigidSettings | None = None,
        min_speed: float | None = None,
        title: str = "",
    ) -> None:
        mujoco = load_mujoco()
        self._mj = mujoco
        self.model, self.data = model, data
        model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
        self.rigid, self.title = rigid, title
        self._h = float(model.opt.timestep)
        integrator = mujoco.mjtIntegrator(int(model.opt.integrator)).name
        self.integrator = integrator.removeprefix("mjINT_").lower()
        self.exact, self.reason = _exact(mujoco, model, self.integrator)
        gravity = np.array(model.opt.gravity, dtype=float)
        if model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_GRAVITY):
            gravity = np.zeros(3)
        if min_speed is None:
            min_speed = max(2.0 * float(np.linalg.norm(gravity)) * self._h, 1e-6)
        if not (math.isfinite(min_speed) and min_speed > 0):
            raise InputError("min_speed", "must be a finite number > 0 (m/s)", min_speed)
        self.min_speed = float(min_speed)
        euler_damping = _euler_damping(mujoco, model) if self.integrator == "euler" else None
        self._ngeom = int(model.ngeom)
        self._names = [
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"
            for g in range(model.ngeom)
        ]
        self._pyramidal = int(model.opt.cone) == int(mujoco.mjtCone.mjCONE_PYRAMIDAL)
        self._scratch: Any = None
        # the references solved, by what decides them (:meth:`_solved`)
        self._solved_by_key: dict[tuple[Any, ...], Any] = {}
        self._coupled_by_state: dict[tuple[Any, ...], list[Any]] = {}
        self._fixed_of: Any = None
        self._rows_read: tuple[Any, ...] = ()
        self._arrays: Any = None
        # views of data's qpos and qvel, taken once (MjData's fixed arrays never move)
        self._qpos_view, self._qvel_view = data.qpos, data.qvel
        # the state before step k in row k % 2 of two, (qpos, qvel) in a row: the compiled
        # step copies the state after it into the other; the clock: [t, h, the last step's
        # start] (s)
        nq = int(model.nq)
        self._states = np.zeros((2, nq + int(model.nv)))
        self._states[0, :nq], self._states[0, nq:] = data.qpos, data.qvel
        self._slots = tuple((row[:nq], row[nq:]) for row in self._states)
        self._clock = np.array([float(data.time), self._h, float(data.time)])
        # one row a step (kernel.COLUMNS), doubled when full: rows written in place, not a
        # Python float per number (their allocation and the garbage collector's passes over
        # a long rollout's millions of objects stall the loop)
        self._table = np.zeros((1024, len(COLUMNS)))
        self._count = 0
        self._no_index = np.zeros(0, dtype=np.int32)
        self._no_kinds = (self._no_index, self._no_index)
        # the rows' J (v0 + v1) and J v1, grown to the largest nefc seen
        self._buffers = np.zeros((2, 16))
        # whether rows other than contacts' were seen (then efc_type and efc_id are read)
        self._kinds = False
        # the pairs' sums of a step (kernel.pair_sums) and the codes of the open episodes
        self._codes, self._values = np.zeros(16, np.int64), np.zeros((16, 14))
        self._open_codes = np.zeros(16, np.int64)
        npairs = int(model.ngeom) ** 2
        if npairs > MAX_PAIR_TABLE:
            raise InputError(
                "model", f"has {model.ngeom} geoms: the audit's table of geom pairs holds at "
                f"most {int(math.sqrt(MAX_PAIR_TABLE))}", show_value=False,
            )  # fmt: skip
        width = other_width(model)
        self._accumulators = (np.zeros(npairs), np.zeros(npairs, dtype=np.int8),
                              np.zeros((OTHER_KINDS, width)),
                              np.zeros((OTHER_KINDS, width), dtype=np.int8))  # fmt: skip
        self._layout = layout_of(
            model, gravity, np.zeros(model.nv) if euler_damping is None else euler_damping,
            implicit=self.integrator != "euler",
            pyramidal=self._pyramidal, min_speed=self.min_speed,
        )  # fmt: skip
        self._open: dict[int, _Open] = {}
        self._episodes: list[Episode] = []
        self._finished: AuditReport | None = None
        # the compiled step reading MjData in place (carnot.rollout.inplace), where its
        # fields' layout checks out and the step has the exact split
        self._params = self._in_place(mujoco, model, data) if self.exact else None

    @property
    def _q(self) -> np.ndarray:
        """The state's ``qpos`` (a view of its row)."""
        return self._slots[self._count % 2][0]

    @property
    def _v(self) -> np.ndarray:
        """The state's ``qvel`` (a view of its row)."""
        return self._slots[self._count % 2][1]

    @property
    def _t(self) -> float:
        """The state's time (s)."""
        return float(self._clock[0])

    def _in_place(self, mujoco: Any, model: Any, data: Any) -> np.ndarray | None:
        """The one argument of :func:`carnot.rollout.inplace.observe_in_place` (its
        :data:`~carnot.rollout.inplace.PARAMS`), or None where MjData's layout does not
        check out (:func:`~carnot.rollout.inplace.data_fields`)."""
        fields = data_fields(mujoco, data)
        if fields is None:
            return None
        p = np.zeros(len(PARAMS), dtype=np.int64)
        p[: fields.size] = fields
        p[DATA], p[SPARSE], p[NQ] = int(data._address), bool(mujoco.mj_isSparse(model)), model.nq
        for index, array in ((MASS, data.M), (CDOF, data.cdof), (XIPOS, data.xipos),
                             (SUBTREE_COM, data.subtree_com), (BIAS, data.qfrc_bias),
                             (PASSIVE, data.qfrc_passive), (ACTUATOR, data.qfrc_actuator),
                             (SMOOTH, data.qfrc_smooth), (DERIV, data.qDeriv),
                             (ENERGY, data.energy), (QPOS, data.qpos), (QVEL, data.qvel),
                             (LAYOUT, self._layout[0]), (WEIGHTS, self._layout[1]),
                             (ACC_PAIRS, self._accumulators[0]),
                             (USED_PAIRS, self._accumulators[1]),
                             (ACC_OTHER, self._accumulators[2]),
                             (USED_OTHER, self._accumulators[3]), (STATES, self._states),
                             (CLOCK, self._clock)):  # fmt: skip
            if not (array.flags.c_contiguous and array.dtype.itemsize in (1, 8)):
                return None  # not as the compiled step reads it
            p[index] = _address(array)
        p[LAYOUT_SIZE], p[WEIGHTS_SIZE] = self._layout[0].size, self._layout[1].size
        p[OTHER_WIDTH] = self._accumulators[2].shape[1]
        self._point(p)
        return p

    def _point(self, p: np.ndarray) -> None:
        """Write the addresses and sizes of the table and the buffers (grown) into ``p``."""
        p[TABLE], p[ROWS] = _address(self._table), self._table.shape[0]
        p[BUFFERS], p[CAPACITY] = _address(self._buffers), self._buffers.shape[1]
        p[CODES], p[VALUES] = _address(self._codes), _address(self._values)
        p[PAIR_CAPACITY] = self._codes.size
        p[OPEN], p[OPEN_COUNT] = _address(self._open_codes), len(self._open)

    # -- feeding -------------------------------------------------------------------------

    def step(self) -> None:
        """``mujoco.mj_step(model, data)`` then :meth:`observe`."""
        self._mj.mj_step(self.model, self.data)
        self.observe()

    def observe(self) -> None:
        """Record the step ``data`` has just taken (call it after every ``mj_step``)."""
        p = self._params
        if p is None:
            self._observe_bound()
            return
        answer = observe_in_place(p)
        k = self._count
        if answer == CALM and not self._open:
            self._count = k + 1
            return
        if answer == WRONG_TIME:  # nothing recorded: the bindings' route says why
            self._observe_bound()
            return
        if answer > APPROACHING:  # nothing recorded: make room or check, and again
            self._in_place_answer(int(answer))
            self.observe()
            return
        self._count = k + 1
        q0, v0 = self._slots[k % 2]
        present = self._present(int(p[PAIRS]))
        if present or self._open:
            v1 = self._slots[(k + 1) % 2][1]
            self._episodes_from(k, float(self._clock[2]), q0, v0, v1, present)
            self._sync_open(p)

    def _sync_open(self, p: np.ndarray) -> None:
        """Write the codes of the open episodes where the in-place step reads them."""
        opened = len(self._open)
        if opened > self._open_codes.size:
            self._open_codes = np.zeros(2 * opened, np.int64)
            self._point(p)
        self._open_codes[:opened] = list(self._open)
        p[OPEN_COUNT] = opened

    def _in_place_answer(self, answer: int) -> None:
        """Act on :func:`~carnot.rollout.inplace.observe_in_place`'s call for room or for a
        check of the moving fields."""
        p = self._params
        assert p is not None
        if answer == FULL:
            self._table = np.concatenate([self._table, np.zeros_like(self._table)])
        elif answer == GROW:
            size = 2 * max(int(self.data.nefc), int(self.data.ncon), 8)
            self._buffers = np.zeros((2, size))
            self._codes, self._values = np.zeros(size, np.int64), np.zeros((size, 14))
        elif answer == CHECK:
            checked = check_moving(self.data, p)
            if checked < 0:  # not where the layout puts them: the bindings' route
                self._params = None
            else:
                p[CHECKED] |= checked
        if self._params is not None:
            self._point(p)

    def _observe_bound(self) -> None:
        """:meth:`observe` through MuJoCo's bindings (each field read as a NumPy view)."""
        data = self.data
        if not abs(data.time - self._t - self._h) <= 1e-6 * self._h:  # NaN too
            raise InputError(
                "observe",
                f"must follow every mj_step (data.time went from {self._t:.9g} s to "
                f"{float(data.time):.9g} s, not one timestep of {self._h:g} s)",
                show_value=False,
            )  # fmt: skip
        q1, v1 = self._qpos_view.copy(), self._qvel_view.copy()
        if self.exact:
            forward = data  # mj_step leaves the start-of-step forward quantities in data
        else:  # RK4's data hold its last stage: evaluate the start of the step apart
            forward = self._forward_at(self._q, self._v, self._t)
        self.record(forward, self._t, self._q, self._v, q1, v1)

    def record(
        self,
        forward: Any,
        time: float,
        qpos: np.ndarray,
        qvel: np.ndarray,
        qpos_after: np.ndarray,
        qvel_after: np.ndarray,
    ) -> None:
        """Record one step from the state ``(qpos, qvel)`` at ``time`` (s) to ``(qpos_after,
        qvel_after)``, where ``forward`` is an ``MjData`` holding MuJoCo's forward quantities
        at the step's start (as ``mj_step`` leaves them). A replay feeds recorded states
        through this; :meth:`observe` feeds the caller's."""
        mujoco, model, h = self._mj, self.model, self._h
        v0, v1 = qvel, qvel_after
        k = self._count
        if k == self._table.shape[0]:
            self._table = np.concatenate([self._table, np.zeros_like(self._table)])
            if self._params is not None:
                self._point(self._params)
        self._count = k + 1
        # the rows' velocities: J v0 (the approach) and J (v0 + v1) (the work)
        if self.exact:  # J v0 is MuJoCo's efc_vel; the compiled step adds J v1
            jv0 = forward.efc_vel
            if self._buffers.shape[1] < jv0.size:
                self._buffers = np.zeros((2, 2 * jv0.size))
                if self._params is not None:
                    self._point(self._params)
            jsum = self._buffers[0]
            approaching: bool | None = self._split(forward, k, float(time), v0, v1, jv0, jsum)
            rows = self._rows_read
        else:
            rows = None
            nefc = forward.nefc
            self._table[k, :3] = float(time), *forward.energy
            jv0, jsum, approaching = np.empty(nefc), np.empty(nefc), None
            if nefc:
                mujoco.mj_mulJacVec(model, forward, jv0, v0)
                mujoco.mj_mulJacVec(model, forward, jsum, v0 + v1)
        self._episodes_step(k, forward, time, qpos, v0, v1, jv0, jsum, approaching, rows)
        q, v = self._slots[(k + 1) % 2]
        q[:], v[:] = qpos_after, qvel_after
        self._clock[0] = float(time) + h
        if self._params is not None:  # a step recorded apart from the in-place route
            self._params[STEP] = k + 1
            self._sync_open(self._params)

    # -- the split -----------------------------------------------------------------------

    def _split(
        self,
        forward: Any,
        k: int,
        time: float,
        v0: np.ndarray,
        v1: np.ndarray,
        jv0: np.ndarray,
        jsum: np.ndarray,
    ) -> bool:
        """Record step ``k``'s works (module docstring) in its row of the table; each is
        ``h f . (v0 + v1) / 2``. Fills ``jsum`` (the rows' ``J (v0 + v1)``, from ``jv0 =
        J v0``, MuJoCo's ``efc_vel``). Returns whether a contact approaches faster than
        ``min_speed``."""
        con = forward.contact
        geom, address, dim = con.geom, con.efc_address, con.dim
        force = forward.efc_force
        self._rows_read = (force, con, geom, address, dim)  # for the episodes' pairs
        if forward is not self._fixed_of:
            # MjData's arrays of fixed size stay where they are for the data's life (only
            # the constraint rows and contacts move, each step): their views are taken once
            self._fixed_of = forward
            pairs, used_pairs, other, used_other = self._accumulators
            self._arrays = StepArrays(
                forward.M, forward.cdof, forward.xipos, forward.subtree_com, forward.qfrc_bias,
                forward.qfrc_passive, forward.qfrc_actuator, forward.qfrc_smooth,
                forward.qDeriv, forward.energy, *self._layout, pairs, used_pairs, other,
                used_other,
            )  # fmt: skip
        jv1 = self._buffers[1, : force.size]
        if force.size:  # one MuJoCo call: cheaper than reading efc_J's four arrays
            self._mj.mj_mulJacVec(self.model, forward, jv1, v1)
        while True:
            kind, ident = (forward.efc_type, forward.efc_id) if self._kinds else self._no_kinds
            answer = step_sums(
                v0, v1, self._arrays, force, jv0, jv1, kind, ident, geom, address, dim, jsum,
                self._table, k, time,
            )  # fmt: skip
            if answer != NEEDS_KINDS:
                return bool(answer == APPROACHING)
            self._kinds = True  # from now on: a model with limits, equalities, friction loss

    def _groups(self) -> dict[str, float]:
        """The total work of each contact pair (geom1, geom2) and each other constraint
        (kind, object) over the rollout (J)."""
        pairs, used_pairs, other, used_other = self._accumulators
        totals = {int(c): float(pairs[c]) for c in np.flatnonzero(used_pairs)}
        width = other.shape[1]
        npairs = self._ngeom * self._ngeom
        for kind, ident in zip(*np.nonzero(used_other), strict=True):
            totals[npairs + int(kind) * (1 << 32) + int(ident)] = float(other[kind, ident])
        assert width > 0
        return {self._group_name(c): w for c, w in sorted(totals.items())}

    def _group_name(self, code: int) -> str:
        mujoco, model = self._mj, self.model
        pairs = self._ngeom * self._ngeom
        if code < pairs:
            g1, g2 = divmod(code, self._ngeom)
            return f"contact {self._names[g1]}/{self._names[g2]}"
        kind, ident = divmod(code - pairs, 1 << 32)
        obj = {0: mujoco.mjtObj.mjOBJ_EQUALITY, 1: mujoco.mjtObj.mjOBJ_DOF,
               2: mujoco.mjtObj.mjOBJ_TENDON, 3: mujoco.mjtObj.mjOBJ_JOINT,
               4: mujoco.mjtObj.mjOBJ_TENDON}.get(kind)  # fmt: skip
        name = mujoco.mj_id2name(model, obj, ident) if obj is not None else None
        return f"{_ROW_KINDS.get(kind, f'type {kind}')} {name or ident}"

    # -- episodes ------------------------------------------------------------------------

    def _episodes_step(
        self,
        k: int,
        forward: Any,
        time: float,
        qpos: np.ndarray,
        v0: np.ndarray,
        v1: np.ndarray,
        jv0: np.ndarray,
        jsum: np.ndarray,
        approaching: bool | None,
        rows: tuple[Any, ...] | None,
    ) -> None:
        if approaching is False and not self._open:  # the compiled step saw no approach
            return
        present = self._pairs(forward, jv0, jsum, rows)
        if present or self._open:
            self._episodes_from(k, time, qpos, v0, v1, present)

    def _episodes_from(
        self,
        k: int,
        time: float,
        qpos: np.ndarray,
        v0: np.ndarray,
        v1: np.ndarray,
        present: dict[int, list[float]],
    ) -> None:
        """Open, extend or close the episodes with step ``k``'s pairs (:meth:`_pairs`);
        MuJoCo's total energy at the step's start from its row of the table."""
        energy = float(self._table[k, 1] + self._table[k, 2])
        for code, row in present.items():
            wn0, wn1, force, work = row[0], row[1], row[2], row[3]
            opened = self._open.get(code)
            if opened is None:
                if force > 0 and wn0 < -self.min_speed:
                    g1, g2 = divmod(code, self._ngeom)
                    self._open[code] = _Open(
                        pair=(self._names[g1], self._names[g2]), start_step=k, start=time,
                        energy_before=energy, wn_before=wn0, wt_before=np.array(row[4:7]),
                        qpos=qpos.copy(), qvel=v0.copy(), work=work, wn_after=wn1,
                        point=np.array(row[10:13]), wt_after=row[7:10], qvel_after=v1.copy(),
                        steps=1,
                    )  # fmt: skip
            elif force > 0 and not (abs(wn0) < self.min_speed and abs(wn1) < self.min_speed):
                opened.work += work
                opened.wn_after = wn1
                opened.wt_after = row[7:10]
                opened.qvel_after = v1.copy()
                opened.steps += 1
            else:  # it no longer pushes, or it has come to rest (a resting contact)
                self._close(code, time, energy, complete=True)
        for code in [c for c in self._open if c not in present]:
            self._close(code, time, energy, complete=True)

    def _pairs(
        self, forward: Any, jv0: np.ndarray, jsum: np.ndarray, rows: tuple[Any, ...] | None
    ) -> dict[int, list[float]]:
        """The pairs that may open an episode or have one open: mean normal velocity before
        and after the step, total force and work of their rows, mean tangential velocity
        before and after, mean contact point, number of contacts: a row of
        :func:`carnot.rollout.kernel.pair_sums` by pair code (:meth:`_present`).
        ``rows``: the rows' forces and the contacts as the step read them (else read here)."""
        if rows is None:
            con = forward.contact
            rows = (forward.efc_force, con, con.geom, con.efc_address, con.dim)
        force, con, geom, address, dim = rows
        if not address.size:
            return {}
        if self._codes.size < address.size:
            self._codes = np.zeros(address.size, np.int64)
            self._values = np.zeros((address.size, 14))
            if self._params is not None:
                self._point(self._params)
        n = pair_sums(
            jv0, jsum[: jv0.size], force, address, dim, geom, con.frame, con.friction, con.pos,
            self._ngeom, self._pyramidal, 0.5 * self._h, self.min_speed,
            np.fromiter(self._open, np.int64, len(self._open)), self._codes, self._values,
        )  # fmt: skip
        return self._present(n)

    def _present(self, n: int) -> dict[int, list[float]]:
        """The first ``n`` pairs of the buffers :func:`~carnot.rollout.kernel.pair_sums`
        filled, by code: each its row of 14 numbers (:meth:`_pairs`; as Python floats, one
        conversion for them all: arrays made only of what an episode keeps)."""
        if not n:
            return {}
        return dict(zip(self._codes[:n].tolist(), self._values[:n].tolist(), strict=True))

    def _close(self, code: int, end: float, energy: float, *, complete: bool) -> None:
        o = self._open.pop(code)
        frictionless = bool(np.any(np.isnan(o.wt_before)))
        self._episodes.append(
            Episode(
                pair=o.pair, start=o.start, end=end, steps=o.steps, complete=complete,
                energy_before=o.energy_before, energy_after=energy, contact_work=o.work,
                normal_velocity_before=o.wn_before, normal_velocity_after=o.wn_after,
                tangential_velocity_before=np.zeros(3) if frictionless else o.wt_before,
                tangential_velocity_after=None if frictionless else np.array(o.wt_after),
                qpos_before=o.qpos, qvel_before=o.qvel, qvel_after=o.qvel_after,
                point=o.point, first_step=o.start_step,
            )
        )  # fmt: skip

    # -- the end -------------------------------------------------------------------------

    def _forward_at(self, qpos: np.ndarray, qvel: np.ndarray, time: float) -> Any:
        """An MjData apart (the caller's is left alone) holding the forward quantities of a
        state: its controls and activations as in the caller's data."""
        mujoco = self._mj
        if self._scratch is None:
            self._scratch = mujoco.MjData(self.model)
        scratch = self._scratch
        mujoco.mj_copyData(scratch, self.model, self.data)
        scratch.qpos[:], scratch.qvel[:], scratch.time = qpos, qvel, time
        mujoco.mj_forward(self.model, scratch)
        return scratch

    def finish(self) -> AuditReport:
        """Close the audit: the final state's energy (evaluated apart), the episodes still
        under way (``complete = False``), the rigid references. Idempotent."""
        if self._finished is not None:
            return self._finished
        final = self._forward_at(self._q, self._v, self._t)
        energy = float(final.energy[0] + final.energy[1])
        for code in list(self._open):
            self._close(code, self._t, energy, complete=False)
        n = self._count
        table = {c: self._table[:n, i].copy() for i, c in enumerate(COLUMNS)}
        ke = np.append(table["kinetic"], float(final.energy[1]))
        pe = np.append(table["potential"], float(final.energy[0]))
        if self.exact:
            work = {s: table[s] for s in SOURCES}
            mass_change = ke[1:] - table["kinetic_end"]
            residual = table["residual"]
        else:
            work = {s: np.full(n, math.nan) for s in SOURCES}
            mass_change = residual = np.full(n, math.nan)
        groups = self._groups()
        kinds: dict[str, np.ndarray] = {}
        if self.exact:
            kinds = {
                "limits": table["joint_limit"] + table["tendon_limit"],
                "equalities": table["equality"],
                "friction_loss": table["dof_friction"] + table["tendon_friction"],
            }
            kinds["contacts"] = table["constraints"] - sum(kinds.values())
        steps = StepLedger(
            integrator=self.integrator, exact=self.exact, reason=self.reason,
            timestep=self._h, time=table["time"], energy=ke + pe, kinetic=ke,
            potential=pe, work=work, mass_change=mass_change, residual=residual,
            by_constraint=groups, constraint_work=kinds,
        )  # fmt: skip
        episodes = tuple(sorted(self._episodes, key=lambda e: (e.start, e.pair)))
        if self.exact:
            episodes = tuple(
                dataclasses.replace(e, split=_episode_split(e, table)) for e in episodes
            )
        if self.rigid is not None:
            episodes = tuple(self._with_rigid(e, self.rigid) for e in episodes)
        self._finished = AuditReport(
            episodes=episodes, steps=steps, settings=self.rigid, min_speed=self.min_speed,
            title=self.title,
        )  # fmt: skip
        return self._finished

    def _reference_data(self) -> Any:
        """An MjData of the model's defaults for a reference, which sets its ``qpos`` and
        ``qvel`` and reads positions, ``M`` and contacts only: :meth:`_forward_at`'s,
        reset (``mj_resetData``, a few microseconds: as a new one, whose allocation costs
        about as much as five references)."""
        if self._scratch is None:
            self._scratch = self._mj.MjData(self.model)
        self._mj.mj_resetData(self.model, self._scratch)
        return self._scratch

    def reference_gap(self, settings: RigidSettings) -> float:
        """The gap (m) within which contacts take part in the references: ``settings.gap``,
        or the model's largest geom margin (at least 1e-6 m): what ``carnot from-mjcf
        --gap`` needs to rebuild them."""
        if settings.gap is not None:
            return settings.gap
        margin = float(np.max(self.model.geom_margin)) if self.model.ngeom else 0.0
        return max(margin, 1e-6)

    def _with_rigid(self, episode: Episode, settings: RigidSettings) -> Episode:
        """carnot's rigid outcome from the episode's pre-impact state (M and J from the model,
        the contacts that approach or touch at rest then): with ``scope = "coupled"`` only
        those coupled to the pair's own (:func:`carnot.model.coupling.coupled_problem`; the
        others' impulses are decoupled from the pair's, so the pair's answer is the same),
        with ``"scene"`` all of them."""
        from carnot.model.mjcf import mjcf_coupled_problem, mjcf_problem
        from carnot.solve import solve_impact

        g1, g2 = episode.pair
        no_contact = "the pair has no approaching contact then"
        state = {
            "qpos": episode.qpos_before.tolist(), "qvel": episode.qvel_before.tolist(),
            "restitution": settings.restitution, "law": settings.law,
            "tangential": settings.tangential, "friction": settings.friction,
            "gap": self.reference_gap(settings), "resting": True,
            "equality": settings.equality, "drift": settings.drift, "limits": settings.limits,
            "data": self._reference_data(),
        }  # fmt: skip
        try:
            if settings.scope == "coupled":  # only the coupled items are made
                coupled = self._coupled_made(episode, settings)
                if coupled is None:
                    coupled = mjcf_coupled_problem(
                        self.model, (g1, g2), multiple_impact=settings.multiple_impact, **state
                    )
                    if coupled is None:  # nothing of the pair's to solve: no reference
                        return dataclasses.replace(episode, rigid_error=no_contact)
                    self._coupled_by_state.setdefault(_state_key(episode, settings),
                                                      []).append(coupled)  # fmt: skip
                problem = coupled
            else:
                problem = mjcf_problem(self.model, **state)
                problem = dataclasses.replace(problem, multiple_impact=settings.multiple_impact)
            result = self._solved(episode, settings, problem, solve_impact)
        except CarnotError as err:
            return dataclasses.replace(episode, rigid_error=str(err))
        mine = [c for c in problem.contacts if c.name == f"{g2}/{g1}"]
        if not mine:
            return dataclasses.replace(episode, rigid=result, rigid_error=no_contact)
        assert result.system is not None  # a SystemProblem's result
        after = result.system.velocity_after
        normal = np.mean([float(c.normal @ c.jacobian @ after) for c in mine])
        tangent = np.mean(
            [c.jacobian @ after - (c.normal @ c.jacobian @ after) * c.normal for c in mine], axis=0
        )
        return dataclasses.replace(
            episode, rigid=result, rigid_normal_velocity_after=float(normal),
            rigid_tangential_velocity_after=None if episode.tangential_velocity_after is None
            else tangent,
        )  # fmt: skip

    def _coupled_made(self, episode: Episode, settings: RigidSettings) -> Any:
        """The coupled problem of the episode's pair made already, under the same
        ``settings``, for another episode in the same state (``qpos_before``,
        ``qvel_before``), or None.
        A pair's coupled problem is the parts (:mod:`carnot.model.coupling`) holding its
        contacts: where a problem made for another pair holds this pair's contacts and every
        one of its items is coupled to them, its parts are this pair's, so it is the problem
        :func:`~carnot.model.mjcf.mjcf_coupled_problem` would make again, item for item (feet
        landing together on a floating base: one part; Go2's first landing, four episodes,
        one problem; its making, ``mj_forward`` and the items' validation, was a fifth of the
        references' time)."""
        from carnot.model.coupling import coupled_items

        g1, g2 = episode.pair
        name = f"{g2}/{g1}"
        for problem in self._coupled_by_state.get(_state_key(episode, settings), ()):
            seeds = [k for k, c in enumerate(problem.contacts) if c.name == name]
            if seeds and bool(np.all(coupled_items(problem, seeds))):
                return problem
        return None

    def _solved(self, episode: Episode, settings: RigidSettings, problem: Any,
                solve: Any) -> Any:  # fmt: skip
        """``solve(problem)``, once for every episode whose reference is the same problem:
        one state (``qpos_before``, ``qvel_before``) under the same ``settings`` and the same
        items taking part, by name (MuJoCo's contacts and rows are a function of the state).
        Feet landing together open one episode each from the same step, and their
        coupled problems are the whole robot's: Go2's first landing is one problem four times,
        the dm_control humanoid's two feet one problem four times."""
        key = (*_state_key(episode, settings), tuple(c.name for c in problem.contacts),
               tuple(c.name for c in problem.constraints))  # fmt: skip
        if key not in self._solved_by_key:
            self._solved_by_key[key] = solve(problem)
        return self._solved_by_key[key]


def _state_key(episode: Episode, settings: RigidSettings) -> tuple[Any, ...]:
    """The key of an episode's reference state under ``settings``: its ``qpos_before`` and
    ``qvel_before`` by value, bit for bit (:func:`carnot.keys.exact_key`; the two have the
    model's fixed lengths, so the pair of keys is unambiguous)."""
    return (settings, exact_key(episode.qpos_before.tolist()),
            exact_key(episode.qvel_before.tolist()))  # fmt: skip


def _address(array: np.ndarray) -> int:
    """The address of an array's first entry (bytes)."""
    return int(array.__array_interface__["data"][0])


def _exact(mujoco: Any, model: Any, integrator: str) -> tuple[bool, str]:
    """Whether the step has the exact split, and why not."""
    if integrator not in EXACT_INTEGRATORS:
        return False, (
            f"the {integrator} integrator has no exact per-step split (RK4 evaluates the "
            "forces four times a step): use Euler, implicitfast or implicit; episodes and "
            "MuJoCo's energy are still reported"
        )
    if integrator == "euler" and _euler_damping(mujoco, model) is None:
        return False, (
            "Euler with polynomial or actuator damping (its implicit damping derivative is "
            "not reproduced here): use implicitfast"
        )
    if integrator == "implicitfast" and np.any(np.asarray(model.jnt_type) == 0):
        return True, (
            "implicitfast takes the gyroscopic term of a free body implicitly (mjd_freeMhat): "
            "that work is not split out and stays in the residual"
        )
    return True, ""


def _euler_damping(mujoco: Any, model: Any) -> np.ndarray | None:
    """The diagonal ``B`` Euler takes implicitly (``mj_EulerSkip``: ``M + h B``), or None
    where it is not the constant joint damping (polynomial or actuator damping)."""
    nv = int(model.nv)
    flags = int(model.opt.disableflags)
    if flags & int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP) or flags & int(
        mujoco.mjtDisableBit.mjDSBL_DAMPER
    ):
        return np.zeros(nv)
    if np.any(np.asarray(model.dof_dampingpoly) != 0):
        return None
    if np.any(np.asarray(model.actuator_damping) != 0) or np.any(
        np.asarray(model.actuator_dampingpoly) != 0
    ):
        return None
    return np.array(model.dof_damping, dtype=float)

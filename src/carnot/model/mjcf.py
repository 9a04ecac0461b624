"""Systems from MuJoCo models (the optional extra ``carnot[mujoco]``: the ``mujoco`` package).

From an MJCF file and a state (a keyframe, or ``qpos``/``qvel``) carnot builds the system in
MuJoCo's generalized coordinates (DESIGN.md section 7):

* ``M``: MuJoCo's joint-space inertia matrix, dense (``mj_fullM``), and ``q' = qvel``;
* one contact per contact MuJoCo detects (the position stage of ``mj_forward``) whose
  distance is at most ``gap`` (m) and whose bodies approach (for a model loaded from a file,
  with those that its margins, often 0, leave out within ``gap``: a body standing on the
  ground at a distance of round-off; :func:`detect_within`): point
  ``contact.pos``, normal the first row of ``contact.frame`` (MuJoCo's normal points from
  ``geom1`` into ``geom2``, so carnot's ``a`` is ``geom2``'s body and ``b`` ``geom1``'s),
  Jacobian the difference of the two bodies' point Jacobians at the contact point
  (``mj_jac``: ``J = J_a(p) - J_b(p)``, so ``w = J q'`` is the relative velocity of ``a``
  with respect to ``b``); friction
  ``contact.friction[0]`` (MuJoCo's combination of the two geoms' sliding friction; 0 for
  a frictionless contact, ``condim`` 1) unless given;
* MuJoCo has no coefficient of restitution (its contacts are soft): ``restitution`` and the
  hypothesis ``law`` are chosen by the caller, as is ``tangential``.

Contacts that separate are left out (a rigid impact gives them no impulse); resting contacts
(``n . w' = 0``) too, unless ``resting=True``. A contact MuJoCo declares frictionless
(``condim`` 1) stays frictionless whatever ``friction`` and ``tangential`` say: ``stick``
would otherwise hold its tangential rows, which MuJoCo never has.

**Joint and tendon limits** (``limits=True``, the default): each limit row MuJoCo
instantiates in that state (``efc_type`` ``mjCNSTR_LIMIT_JOINT`` or ``mjCNSTR_LIMIT_TENDON``:
the joint or tendon within its ``margin`` of the range's end) that approaches (or rests, with
``resting``) becomes a frictionless unilateral contact of its own, ``limit <joint>`` (or
``tendon limit <tendon>``): ``J``'s first row is MuJoCo's ``efc_J`` row (positive towards the
inside of the range, so ``w_n = efc_J q'`` and the limit approaches when it is negative), its
other rows zero (they carry nothing), the normal ``(1, 0, 0)``, no point. The law and the
restitution are the contacts'.

**Equality constraints** (each active ``<equality>`` element, :func:`equality_constraints`)
become constraints of the system, of the kind ``equality`` chooses: ``"pin"`` (the default:
the constraint holds before the impact, checked, and after it; MuJoCo's equalities are
persistent joints) or ``"fasten"`` (the impact imposes it, paper section 3.3), or
``"ignore"`` (left out):

* ``connect`` (a ball joint closing a loop, or attaching a body): the relative velocity of
  the two anchor points, ``J = J_1(p_1) - J_2(p_2)`` (``p_1`` the anchor on ``body1``,
  ``p_2`` its partner on ``body2``, computed by MuJoCo where the model is defined, or the two
  sites);
* ``weld``: the same rows at the weld point and the relative angular velocity,
  ``J_ang = Jr_1 - Jr_2`` (``mj_jac``'s rotational Jacobians);
* ``joint`` (``joint1 = p(joint2)``, ``p`` the polynomial ``polycoef`` in ``joint2 - joint2_0``;
  ``joint1`` fixed at a constant without ``joint2``): the one row ``q'_1 - p'(q_2) q'_2``
  (exact at the velocity level for any ``polycoef``), as the first row of ``J`` (rad/s or m/s,
  the coordinates' units; the other rows zero, so they carry nothing).

* ``tendon`` (``tendon1 = p(tendon2)``): MuJoCo's own equality row (``efc_J``, the row of
  ``efc_type`` ``mjCNSTR_EQUALITY`` and ``efc_id`` the equality), as the first row of ``J``.

Flex equalities are refused by name (or left out with ``"ignore"``).

MuJoCo's equalities are soft: they drift by a little each step (3.5e-7 m/s on the Robotiq
2F-85's connects), which carnot's pin (zero to 1e-9 of the velocity scale:
:func:`carnot.model.system.check_system_pins`) refuses. ``drift`` (m/s, rad/s and the joints'
units per second) states the drift a pin accepts: each equality is checked here,
``|J q'| <= drift`` (and ``|J_ang q'|``; an :class:`~carnot.errors.InputError` naming the
equality, its drift and the tolerance otherwise), and then imposed as MuJoCo imposes it every
step, ``J q'' = 0`` (the rows of a ``fasten``, as the result reports them: at a drift ``d``
the two differ by the drift's own energy, of order ``m d^2``).
"""

from __future__ import annotations

import copy
import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from carnot.errors import CarnotError, InputError
from carnot.model.system import System, SystemConstraint, SystemContact, SystemProblem

#: The install line the MuJoCo front end asks for when the extra is missing.
INSTALL = 'pip install "carnot[mujoco]"'


class MissingExtraError(CarnotError):
    """An optional extra that is not installed (the message says how to install it)."""


def load_mujoco() -> Any:
    """The ``mujoco`` module, or :class:`MissingExtraError` naming the extra to install."""
    try:
        import mujoco
    except ImportError:
        raise MissingExtraError(f"MuJoCo models need the optional extra: {INSTALL}") from None
    return mujoco


def mjcf_problem(
    path: str | Path | Any,
    *,
    keyframe: str | int | None = None,
    qpos: Sequence[float] | None = None,
    qvel: Sequence[float] | None = None,
    restitution: float = 0.0,
    law: str = "newton",
    tangential: str = "slip",
    friction: float | None = None,
    gap: float = 1e-6,
    resting: bool = False,
    title: str = "",
    equality: str = "pin",
    drift: float | None = None,
    limits: bool = True,
    data: Any = None,
    rest_speed: float = 0.0,
) -> SystemProblem:
    """The impact problem of the MJCF model at ``path`` (or of an ``MjModel`` already loaded)
    in the state of ``keyframe`` (name or index) and/or ``qpos``/``qvel`` (module docstring);
    ``equality``: the kind of constraint each active equality becomes (``pin``, ``fasten``,
    or ``ignore``), ``drift`` the pins' tolerance (None: carnot's own round-off bound);
    ``limits``: the joint and tendon limits as unilateral contacts; ``data``: an ``MjData``
    of that loaded model to work in, reused (its ``qpos``/``qvel`` overwritten; a new one by
    default: allocating it is half the cost here); ``rest_speed`` (m/s, with ``resting``): a
    contact separating at most this fast counts as resting (a contact held closed in carnot's
    flow, whose normal velocity is zero to the integrator's tolerance).

    >>> mjcf_problem("no/such/model.xml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: no/such/model.xml: cannot read the MJCF model (...)
    """
    mujoco = load_mujoco()
    source = str(path) if isinstance(path, (str, Path)) else "the model"
    if equality not in EQUALITY_KINDS:
        raise InputError("equality", f"must be one of {', '.join(EQUALITY_KINDS)}", equality)
    check_gap(gap)
    if isinstance(path, mujoco.MjModel):  # a model already loaded (carnot.rollout's audit)
        model = path
    else:
        try:
            model = mujoco.MjModel.from_xml_path(source)
        except (ValueError, OSError) as err:
            message = " ".join(str(err).split())[:300]
            raise InputError(
                source, f"cannot read the MJCF model ({message})", show_value=False
            ) from None
    data = mujoco.MjData(model) if data is None else data
    if keyframe is not None:
        mujoco.mj_resetDataKeyframe(model, data, keyframe_id(mujoco, model, keyframe, source))
    _check_drift_argument(drift)
    within = None if isinstance(path, mujoco.MjModel) else detect_within(model, gap)
    mass, q, found = _state(mujoco, model, data, qpos, qvel, gap, resting, source, limits,
                            rest_speed, within)
    contacts = [
        _system_contact(c, k, restitution, law, friction, tangential) for k, c in enumerate(found)
    ]
    system = System(
        mass_matrix=0.5 * (mass + mass.T), velocity=q, coordinates=dof_names(mujoco, model)
    )
    constraints = _equalities(mujoco, model, data, q, equality, drift, source)
    return SystemProblem(
        system=system,
        contacts=contacts,
        constraints=constraints,
        title=title
        or f"{Path(source).name}" + (f" at keyframe {keyframe}" if keyframe is not None else ""),
    )


def mjcf_coupled_problem(
    model: Any,
    pair: tuple[str, str],
    *,
    qpos: Sequence[float],
    qvel: Sequence[float],
    restitution: float = 0.0,
    law: str = "newton",
    tangential: str = "slip",
    friction: float | None = None,
    gap: float = 1e-6,
    resting: bool = False,
    equality: str = "pin",
    drift: float | None = None,
    limits: bool = True,
    multiple_impact: str = "simultaneous",
    data: Any = None,
) -> SystemProblem | None:
    """The items of :func:`mjcf_problem` (a loaded ``MjModel`` in the state ``qpos``,
    ``qvel``) coupled to the contacts of the geom ``pair`` (``(geom1, geom2)`` names, as
    MuJoCo orders them), under ``multiple_impact``: the same problem, item for item and
    bit for bit, as ``coupled_problem(mjcf_problem(...), seeds)`` with ``seeds`` the pair's
    contacts (:mod:`carnot.model.coupling`), but the uncoupled contacts are never made (their
    validation is most of the cost: an audit's references build one problem per impact). None
    where the pair has no contact in the problem.
    The tests check it against the whole problem's route (tests/test_audit_coupling.py).
    """
    mujoco = load_mujoco()
    source = "the model"
    if equality not in EQUALITY_KINDS:
        raise InputError("equality", f"must be one of {', '.join(EQUALITY_KINDS)}", equality)
    check_gap(gap)
    _check_drift_argument(drift)
    data = mujoco.MjData(model) if data is None else data
    mass, q, found = _state(mujoco, model, data, qpos, qvel, gap, resting, source, limits)
    name = f"{pair[1]}/{pair[0]}"
    seeds = [k for k, c in enumerate(found) if c.name == name]
    if not seeds:
        return None
    constraints = _equalities(mujoco, model, data, q, equality, drift, source)
    from carnot.model.coupling import coupled_mask, moved_coordinates

    # the coordinates each item moves, as moved_coordinates has them (contacts: no angular
    # rows), the contacts' in one pass
    moved = np.any(np.array([c.jacobian for c in found]) != 0.0, axis=1)
    if constraints:
        moved = np.vstack([moved, [moved_coordinates(c) for c in constraints]])
    mass = 0.5 * (mass + mass.T)
    kept = coupled_mask(moved, mass, seeds).tolist()
    contacts = [
        _system_contact(c, k, restitution, law, friction, tangential)
        for k, c in enumerate(found)
        if kept[k]
    ]
    system = System(
        mass_matrix=mass,
        velocity=q,
        coordinates=dof_names(mujoco, model),
    )
    return SystemProblem(
        system=system,
        contacts=contacts,
        constraints=[c for c, keep in zip(constraints, kept[len(found) :], strict=True) if keep],
        title=Path(source).name,
        multiple_impact=multiple_impact,
    )


def check_gap(gap: object) -> None:
    """``gap`` (m) must be a finite distance >= 0.

    >>> check_gap(-1.0)
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: gap: must be a finite distance >= 0 (m), got -1.0
    """
    if isinstance(gap, bool) or not isinstance(gap, int | float) or not (
            math.isfinite(gap) and gap >= 0.0):  # fmt: skip
        raise InputError("gap", "must be a finite distance >= 0 (m)", gap)


def detect_within(model: Any, gap: float) -> Any:
    """A copy of ``model`` whose geoms', joints' and tendons' margins are at least ``gap``
    (m), so that MuJoCo's collision and limit stages report every contact and limit within
    ``gap``, as ``carnot simulate`` does at a strike (:mod:`carnot.hybrid.mjcf`). MuJoCo
    reports a contact only where its distance is below the margins, 0 in most models, and a
    body placed on the ground touches it at a distance of round-off: dm_control's walker in
    its reference pose stands on its feet at 2e-17 m, which MuJoCo leaves out. Used for a
    model loaded from a file for one problem (a model handed in, an audit's, is read with
    its own margins)."""
    near = copy.copy(model)
    near.geom_margin[:] = np.maximum(near.geom_margin, gap)
    near.jnt_margin[:] = np.maximum(near.jnt_margin, gap)
    if near.ntendon:
        near.tendon_margin[:] = np.maximum(near.tendon_margin, gap)
    return near


@dataclass(frozen=True)
class _Found:
    """A contact MuJoCo detects, as a system contact needs it (:func:`mjcf_problem`)."""

    jacobian: np.ndarray
    normal: np.ndarray
    point: np.ndarray | None
    friction: float
    name: str
    frictionless: bool = False  # condim 1, or a limit: no tangential rows in MuJoCo


def _state(
    mujoco: Any,
    model: Any,
    data: Any,
    qpos: Sequence[float] | None,
    qvel: Sequence[float] | None,
    gap: float,
    resting: bool,
    source: str,
    limits: bool = True,
    rest_speed: float = 0.0,
    within: Any = None,
) -> tuple[np.ndarray, np.ndarray, list[_Found]]:
    """Set ``qpos``/``qvel`` (checked) in ``data``, run ``mj_fwdPosition`` (the position stage
    of ``mj_forward``: kinematics, ``M``, collision and the constraint rows, everything read
    here, the same numbers; without the velocity, actuation and acceleration stages and the
    constraint solver, which were four fifths of its cost on Go2): ``M`` (dense),
    ``q'`` and the contacts within ``gap`` that approach (or rest, with ``resting``), then
    (``limits``) the limit rows that do; an error where there is none. With ``resting``, a
    contact or limit separating at most ``rest_speed`` fast rests.

    ``within``: a copy of ``model`` whose margins are raised to ``gap`` (:func:`detect_within`),
    run in the same state for the contacts and limits that the model's own margins leave out:
    those of a pair of geoms, or of a joint, that MuJoCo did not report with the model's
    margins are added from it. A pair reported with them keeps MuJoCo's own contacts: a
    margin moves the contact points of meshes and other convex geoms (MPR and GJK inflate the
    shapes), and a state from a rollout is MuJoCo's."""
    rest = rest_speed if resting else 0.0
    for name, value, size, what in (
        ("qpos", qpos, model.nq, "model.nq"), ("qvel", qvel, model.nv, "model.nv")
    ):  # fmt: skip
        if value is None:
            continue
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{source}: {name}", f"must be {size} numbers", value) from None
        if arr.shape != (size,) or not np.all(np.isfinite(arr)):
            raise InputError(
                f"{source}: {name}",
                f"must be {size} finite numbers ({what} = {size}); {arr.size} numbers",
                np.ravel(arr).tolist(),
            )
        getattr(data, name)[:] = arr
    mujoco.mj_fwdPosition(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    q = np.array(data.qvel, dtype=float)
    found = _contacts(mujoco, model, data, q, gap, resting, rest)
    if limits:
        found += _limit_rows(mujoco, model, data, q, resting, rest)
    reported = int(data.ncon)
    if within is not None:
        near = mujoco.MjData(within)
        near.qpos[:], near.qvel[:] = data.qpos, data.qvel
        mujoco.mj_fwdPosition(within, near)
        pairs = {tuple(g) for g in data.contact.geom.tolist()}
        found += _contacts(mujoco, within, near, q, gap, resting, rest, skip=pairs)
        if limits:
            seen = {c.name for c in found}
            found += [c for c in _limit_rows(mujoco, within, near, q, resting, rest)
                      if c.name not in seen]  # fmt: skip
        reported = int(near.ncon)
    if not found:
        raise InputError(
            source,
            "has no approaching contact in this state (MuJoCo detects "
            f"{reported} contact(s) within the margins; gap = {gap:g} m)",
            show_value=False,
        )
    return mass, q, found


def _contacts(mujoco: Any, model: Any, data: Any, q: np.ndarray, gap: float, resting: bool,
              rest: float, skip: set[tuple[int, int]] | frozenset[tuple[int, int]] = frozenset()
              ) -> list[_Found]:  # fmt: skip
    """The contacts MuJoCo reported (after ``mj_fwdPosition``) within ``gap`` that approach (or
    rest, with ``resting``), but those of the geom pairs in ``skip``."""
    found: list[_Found] = []
    ncon = int(data.ncon)
    if ncon:  # the contacts' fields read at once (each read of a field costs a microsecond)
        contact = data.contact
        dist, geom, dim = contact.dist.tolist(), contact.geom.tolist(), contact.dim.tolist()
        frame, pos, mu = np.array(contact.frame), np.array(contact.pos), contact.friction[:, 0]
        bodies = model.geom_bodyid.tolist()
        names = _names(mujoco, model)[0]
    for i in range(ncon):
        if dist[i] > gap or (skip and tuple(geom[i]) in skip):
            continue
        normal, point = frame[i, :3], pos[i]  # rows of copies
        g1, g2 = geom[i]
        jacobian = _point_jacobian(mujoco, model, data, point, bodies[g2])
        if bodies[g1]:  # (against the world: J_a - 0, the same numbers, made at once)
            jacobian = jacobian - _point_jacobian(mujoco, model, data, point, bodies[g1])
        approach = float(normal @ jacobian @ q)
        if approach > rest or (approach == 0 and not resting):
            continue
        friction = float(mu[i]) if dim[i] > 1 else 0.0
        found.append(
            _Found(jacobian, normal, point, friction, f"{names[g2]}/{names[g1]}", dim[i] == 1)
        )
    return found


def _system_contact(
    found: _Found,
    index: int,
    restitution: float,
    law: str,
    friction: float | None,
    tangential: str,
) -> SystemContact:
    """The system contact of a contact found (``index``: its place among them all); one
    MuJoCo declares frictionless stays so (module docstring)."""
    if found.frictionless:
        friction, tangential = 0.0, "slip"
    return SystemContact(
        jacobian=found.jacobian,
        normal=found.normal,
        point=found.point,
        restitution=restitution,
        law=law,
        friction=found.friction if friction is None else friction,
        tangential=tangential,  # type: ignore[arg-type]
        name=found.name,
        where=f"contacts[{index}]",
    )


#: What an MJCF equality can become (:func:`mjcf_problem`'s ``equality``).
EQUALITY_KINDS = ("pin", "fasten", "ignore")


def _check_drift_argument(drift: float | None) -> None:
    if drift is not None and not (
        isinstance(drift, int | float) and math.isfinite(drift) and drift >= 0
    ):
        raise InputError("drift", "must be a finite number >= 0 (m/s)", drift)


def _equalities(
    mujoco: Any,
    model: Any,
    data: Any,
    q: np.ndarray,
    equality: str,
    drift: float | None,
    source: str,
) -> list[SystemConstraint]:
    """The equalities as ``equality`` asks (module docstring): none, fastened, pinned by
    carnot's own check, or pinned to the stated ``drift`` (checked here, then imposed).
    None where the model's flags disable equalities (MuJoCo does not enforce them)."""
    bits = mujoco.mjtDisableBit
    off = int(bits.mjDSBL_EQUALITY) | int(bits.mjDSBL_CONSTRAINT)
    if equality == "ignore" or int(model.opt.disableflags) & off:
        return []
    if equality == "fasten" or drift is None:
        return equality_constraints(mujoco, model, data, kind=equality, source=source)  # type: ignore[arg-type]
    out = equality_constraints(mujoco, model, data, kind="fasten", source=source)
    for item in out:
        for jac, unit in ((item.jacobian, "m/s"), (item.angular_jacobian, "rad/s")):
            if jac is None:
                continue
            moved = float(np.linalg.norm(jac @ q))
            if not moved <= drift:
                raise InputError(
                    f"{source}: equality {item.name!r}",
                    f"drifts by |J q'| = {moved:.3g} {unit} before the impact, more than the "
                    f"pin's stated drift {drift:g} (equality = \"fasten\" imposes it)",
                    show_value=False,
                )
    return out


#: MuJoCo's kinds of constraint row (``mjtConstraint``) that the front end reads.
_EQUALITY_ROW, _JOINT_LIMIT_ROW, _TENDON_LIMIT_ROW = 0, 3, 4


def _efc_row(mujoco: Any, model: Any, data: Any, row: int) -> np.ndarray:
    """Row ``row`` of MuJoCo's constraint Jacobian ``efc_J`` (nv entries), dense or sparse
    (``efc_J_rowadr``, ``efc_J_rownnz``, ``efc_J_colind``: compressed rows) as it is kept."""
    nv = int(model.nv)
    out = np.zeros(nv)
    if mujoco.mj_isSparse(model):
        start = int(data.efc_J_rowadr[row])
        end = start + int(data.efc_J_rownnz[row])
        out[np.asarray(data.efc_J_colind[start:end])] = data.efc_J[start:end]
    else:
        out[:] = np.asarray(data.efc_J).reshape(-1)[row * nv : (row + 1) * nv]
    return out


def _limit_rows(
    mujoco: Any, model: Any, data: Any, q: np.ndarray, resting: bool, rest: float = 0.0
) -> list[_Found]:
    """The joint and tendon limits MuJoCo instantiated (after ``mj_fwdPosition``) that approach
    (or rest, with ``resting``), as frictionless unilateral contacts (module docstring)."""
    types = np.asarray(data.efc_type)
    rows = np.flatnonzero((types == _JOINT_LIMIT_ROW) | (types == _TENDON_LIMIT_ROW))
    out: list[_Found] = []
    for r in rows.tolist():
        row = _efc_row(mujoco, model, data, r)
        approach = float(row @ q)
        if approach > rest or (approach == 0 and not resting):
            continue
        ident = int(data.efc_id[r])
        if int(types[r]) == _JOINT_LIMIT_ROW:
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, ident) or f"joint{ident}"
            label = f"limit {name}"
        else:
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TENDON, ident) or f"tendon{ident}"
            label = f"tendon limit {name}"
        jacobian = np.zeros((3, model.nv))
        jacobian[0] = row
        out.append(_Found(jacobian, np.array([1.0, 0.0, 0.0]), None, 0.0, label, True))
    return out


def equality_constraints(
    mujoco: Any,
    model: Any,
    data: Any,
    *,
    kind: Literal["pin", "fasten"] = "pin",
    source: str = "<model>",
) -> list[SystemConstraint]:
    """The model's active equality constraints in the state of ``data`` (after
    ``mj_forward``) as system constraints of ``kind`` (module docstring), named after the
    equality (``equality<k>`` when it has no name), numbered ``constraints[k]``."""
    out: list[SystemConstraint] = []
    eq_type = mujoco.mjtEq
    for index in range(model.neq):
        if not data.eq_active[index]:
            continue
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, index) or f"equality{index}"
        where = f"constraints[{len(out)}]"
        kind_of = int(model.eq_type[index])
        params = np.array(model.eq_data[index], dtype=float)
        if kind_of in (int(eq_type.mjEQ_CONNECT), int(eq_type.mjEQ_WELD)):
            weld = kind_of == int(eq_type.mjEQ_WELD)
            # MuJoCo's anchors: connect (body1's in data[0:3], body2's in data[3:6]), weld
            # (body2's in data[0:3], body1's in data[3:6]); sites give the points themselves
            local = (params[3:6], params[0:3]) if weld else (params[0:3], params[3:6])
            ends = [
                _equality_end(mujoco, model, data, index, side, local[side]) for side in (0, 1)
            ]
            (body_1, p_1), (body_2, p_2) = ends
            jac_1, rot_1 = _point_jacobians(mujoco, model, data, p_1, body_1)
            jac_2, rot_2 = _point_jacobians(mujoco, model, data, p_2, body_2)
            out.append(
                SystemConstraint(
                    kind=kind,
                    jacobian=jac_1 - jac_2,
                    angular_jacobian=rot_1 - rot_2 if weld else None,
                    point=p_1,
                    name=name,
                    where=where,
                )
            )
        elif kind_of == int(eq_type.mjEQ_JOINT):
            row = np.zeros(model.nv)
            joint_1, joint_2 = int(model.eq_obj1id[index]), int(model.eq_obj2id[index])
            row[_joint_dof(model, joint_1, name, source)] += 1.0
            if joint_2 >= 0:
                x = float(data.qpos[model.jnt_qposadr[joint_2]]) - float(
                    model.qpos0[model.jnt_qposadr[joint_2]]
                )
                c = params[:5]
                slope = c[1] + 2 * c[2] * x + 3 * c[3] * x**2 + 4 * c[4] * x**3  # p'(x)
                row[_joint_dof(model, joint_2, name, source)] -= slope
            jac = np.zeros((3, model.nv))
            jac[0] = row
            out.append(SystemConstraint(kind=kind, jacobian=jac, name=name, where=where))
        elif kind_of == int(eq_type.mjEQ_TENDON):
            rows = np.flatnonzero(
                (np.asarray(data.efc_type) == _EQUALITY_ROW) & (np.asarray(data.efc_id) == index)
            )
            if rows.size != 1:  # MuJoCo instantiates one row (none: equalities disabled)
                raise InputError(
                    f"{source}: equality {name!r}",
                    "has no constraint row in MuJoCo's state (equalities disabled?); "
                    'equality = "ignore" leaves every equality out',
                    int(rows.size),
                )
            jac = np.zeros((3, model.nv))
            jac[0] = _efc_row(mujoco, model, data, int(rows[0]))
            out.append(SystemConstraint(kind=kind, jacobian=jac, name=name, where=where))
        else:
            label = mujoco.mjtEq(kind_of).name.removeprefix("mjEQ_").lower()
            raise InputError(
                f"{source}: equality {name!r}",
                "is not supported (connect, weld, joint and tendon equalities are; equality "
                '= "ignore" leaves every equality out)',
                label,
            )
    return out


def _equality_end(
    mujoco: Any, model: Any, data: Any, index: int, side: int, local: np.ndarray
) -> tuple[int, np.ndarray]:
    """Side ``side`` (0: obj1, 1: obj2) of a connect or weld: its body and world point."""
    obj = int(model.eq_obj1id[index] if side == 0 else model.eq_obj2id[index])
    if int(model.eq_objtype[index]) == int(mujoco.mjtObj.mjOBJ_SITE):
        return int(model.site_bodyid[obj]), np.array(data.site_xpos[obj], dtype=float)
    rotation = np.asarray(data.xmat[obj], dtype=float).reshape(3, 3)
    return obj, np.asarray(data.xpos[obj], dtype=float) + rotation @ local


def _joint_dof(model: Any, joint: int, name: str, source: str) -> int:
    """The one degree of freedom of a hinge or slide joint (a joint equality's)."""
    if int(model.jnt_type[joint]) not in (2, 3):  # mjJNT_SLIDE, mjJNT_HINGE
        raise InputError(
            f"{source}: equality {name!r}",
            "couples a joint of several degrees of freedom (a joint equality needs hinge or "
            "slide joints)",
            int(model.jnt_type[joint]),
        )
    return int(model.jnt_dofadr[joint])


def _point_jacobians(
    mujoco: Any, model: Any, data: Any, point: np.ndarray, body: int
) -> tuple[np.ndarray, np.ndarray]:
    """``(J_body(p), Jr_body)`` (3 x nv each): the velocity of the point of ``body`` at
    ``p`` and the body's angular velocity (0: the world)."""
    jacp = np.zeros((3, model.nv))
    jacr = np.zeros((3, model.nv))
    if body != 0:
        mujoco.mj_jac(model, data, jacp, jacr, point, body)
    return jacp, jacr


def keyframe_id(mujoco: Any, model: Any, keyframe: str | int, source: str) -> int:
    """The index of ``keyframe`` (its name, or its index as an int or a string of digits) in
    ``model``; an :class:`InputError` naming ``source`` and the known keyframes otherwise."""
    if isinstance(keyframe, int) or (isinstance(keyframe, str) and keyframe.isdigit()):
        index = int(keyframe)
    else:
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
    if not 0 <= index < model.nkey:
        known = ", ".join(
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_KEY, k) or str(k)
            for k in range(model.nkey)
        ) or "none"
        raise InputError(f"{source}: keyframe", f"unknown keyframe (known: {known})", keyframe)
    return index


def _point_jacobian(mujoco: Any, model: Any, data: Any, point: np.ndarray, body: int) -> Any:
    """``J_body(p)`` (3 x nv): the velocity of the point of ``body`` at ``p`` (0: the world)."""
    jacp = np.zeros((3, model.nv))
    if body != 0:
        mujoco.mj_jac(model, data, jacp, None, point, body)
    return jacp


#: Each loaded model's geom and dof names (:func:`_names`), kept while the model lives.
_NAMES: weakref.WeakKeyDictionary[Any, tuple[tuple[str, ...], tuple[str, ...]]] = (
    weakref.WeakKeyDictionary()
)


def _names(mujoco: Any, model: Any) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The model's geom names (``geom<k>`` for a geom without one) and :func:`dof_names`,
    made once per model: an audit builds a problem per impact of one model, and the names
    cost a tenth of a millisecond each time. A model's names cannot change once it is
    compiled."""
    names = _NAMES.get(model)
    if names is None:
        geoms = tuple(
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"
            for g in range(model.ngeom)
        )
        names = geoms, _dof_names(mujoco, model)
        _NAMES[model] = names
    return names


def dof_names(mujoco: Any, model: Any) -> tuple[str, ...]:
    """A name per degree of freedom: the joint's name, with ``[k]`` for a joint of several
    (``free``: 6, ``ball``: 3)."""
    return _names(mujoco, model)[1]


def _dof_names(mujoco: Any, model: Any) -> tuple[str, ...]:
    names = []
    counts = np.bincount(model.dof_jntid, minlength=model.njnt)  # dofs of each joint
    for dof in range(model.nv):
        joint = int(model.dof_jntid[dof])
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) or f"joint{joint}"
        first = int(model.jnt_dofadr[joint])
        count = int(counts[joint])
        names.append(name if count == 1 else f"{name}[{dof - first}]")
    return tuple(names)

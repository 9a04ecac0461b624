"""Systems from MuJoCo models (the optional extra ``carnot[mujoco]``: the ``mujoco`` package).

From an MJCF file and a state (a keyframe, or ``qpos``/``qvel``) carnot builds the system in
MuJoCo's generalized coordinates (DESIGN.md section 7):

* ``M``: MuJoCo's joint-space inertia matrix, dense (``mj_fullM``), and ``q' = qvel``;
* one contact per contact MuJoCo detects (``mj_forward``) whose distance is at most ``gap``
  (m) and whose bodies approach: point ``contact.pos``, normal the first row of
  ``contact.frame`` (MuJoCo's normal points from ``geom1`` into ``geom2``, so carnot's ``a``
  is ``geom2``'s body and ``b`` ``geom1``'s), Jacobian the difference of the two bodies'
  point Jacobians at the contact point (``mj_jac``: ``J = J_a(p) - J_b(p)``, so ``w = J q'``
  is the relative velocity of ``a`` with respect to ``b``); friction ``contact.friction[0]``
  (MuJoCo's combination of the two geoms' sliding friction; 0 for a frictionless contact,
  ``condim`` 1) unless given;
* MuJoCo has no coefficient of restitution (its contacts are soft): ``restitution`` and the
  hypothesis ``law`` are chosen by the caller, as is ``tangential``.

Contacts that separate are left out (a rigid impact gives them no impulse); resting contacts
(``n . w' = 0``) too, unless ``resting=True``.

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

Tendon, flex and distance equalities are refused by name (or left out with ``"ignore"``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np

from carnot.errors import CarnotError, InputError
from carnot.model.system import System, SystemConstraint, SystemContact, SystemProblem

#: The install line the MuJoCo front end asks for when the extra is missing.
INSTALL = 'pip install "carnot[mujoco]"'


class MissingExtraError(CarnotError):
    """An optional extra that is not installed (the message says how to install it)."""


def _mujoco() -> Any:
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
    data: Any = None,
) -> SystemProblem:
    """The impact problem of the MJCF model at ``path`` (or of an ``MjModel`` already loaded)
    in the state of ``keyframe`` (name or index) and/or ``qpos``/``qvel`` (module docstring);
    ``equality``: the kind of constraint each active equality becomes (``pin``, ``fasten``,
    or ``ignore``); ``data``: an ``MjData`` of that loaded model to work in, reused (its
    ``qpos``/``qvel`` overwritten; a new one by default: allocating it is half the cost here).

    >>> mjcf_problem("no/such/model.xml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: no/such/model.xml: cannot read the MJCF model (...)
    """
    mujoco = _mujoco()
    source = str(path) if isinstance(path, (str, Path)) else "the model"
    if equality not in EQUALITY_KINDS:
        raise InputError("equality", f"must be one of {', '.join(EQUALITY_KINDS)}", equality)
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
        mujoco.mj_resetDataKeyframe(model, data, _keyframe_id(mujoco, model, keyframe, source))
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
                list(np.ravel(arr)),
            )
        getattr(data, name)[:] = arr
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    q = np.array(data.qvel, dtype=float)
    contacts: list[SystemContact] = []
    for i in range(data.ncon):
        con = data.contact[i]
        if con.dist > gap:
            continue
        normal = np.array(con.frame[:3], dtype=float)
        point = np.array(con.pos, dtype=float)
        body_b, body_a = (int(model.geom_bodyid[g]) for g in con.geom[:2])
        jacobian = _point_jacobian(mujoco, model, data, point, body_a) - _point_jacobian(
            mujoco, model, data, point, body_b
        )
        approach = float(normal @ jacobian @ q)
        if approach > 0 or (approach == 0 and not resting):
            continue
        names = [
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) or f"geom{int(g)}"
            for g in con.geom[:2]
        ]
        mu = float(con.friction[0]) if con.dim > 1 else 0.0
        where = f"contacts[{len(contacts)}]"
        contacts.append(
            SystemContact(
                jacobian=jacobian,
                normal=normal,
                point=point,
                restitution=restitution,
                law=law,
                friction=mu if friction is None else friction,
                tangential=tangential,  # type: ignore[arg-type]
                name=f"{names[1]}/{names[0]}",
                where=where,
            )
        )
    if not contacts:
        raise InputError(
            source,
            "has no approaching contact in this state (MuJoCo detects "
            f"{data.ncon} contact(s) within the margins; gap = {gap:g} m)",
            show_value=False,
        )
    system = System(
        mass_matrix=0.5 * (mass + mass.T), velocity=q, coordinates=dof_names(mujoco, model)
    )
    constraints = (
        [] if equality == "ignore"
        else equality_constraints(mujoco, model, data, kind=equality, source=source)  # type: ignore[arg-type]
    )  # fmt: skip
    return SystemProblem(
        system=system,
        contacts=contacts,
        constraints=constraints,
        title=title
        or f"{Path(source).name}" + (f" at keyframe {keyframe}" if keyframe is not None else ""),
    )


#: What an MJCF equality can become (:func:`mjcf_problem`'s ``equality``).
EQUALITY_KINDS = ("pin", "fasten", "ignore")


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
        else:
            label = mujoco.mjtEq(kind_of).name.removeprefix("mjEQ_").lower()
            raise InputError(
                f"{source}: equality {name!r}",
                "is not supported (connect, weld and joint equalities are; equality = "
                '"ignore" leaves every equality out)',
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


def _keyframe_id(mujoco: Any, model: Any, keyframe: str | int, source: str) -> int:
    if isinstance(keyframe, int) or (isinstance(keyframe, str) and keyframe.isdigit()):
        index = int(keyframe)
    else:
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, keyframe)
    if not 0 <= index < model.nkey:
        known = [
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_KEY, k) or str(k)
            for k in range(model.nkey)
        ]
        raise InputError(f"{source}: keyframe", f"unknown keyframe (known: {known})", keyframe)
    return index


def _point_jacobian(mujoco: Any, model: Any, data: Any, point: np.ndarray, body: int) -> Any:
    """``J_body(p)`` (3 x nv): the velocity of the point of ``body`` at ``p`` (0: the world)."""
    jacp = np.zeros((3, model.nv))
    if body != 0:
        mujoco.mj_jac(model, data, jacp, None, point, body)
    return jacp


def dof_names(mujoco: Any, model: Any) -> tuple[str, ...]:
    """A name per degree of freedom: the joint's name, with ``[k]`` for a joint of several
    (``free``: 6, ``ball``: 3)."""
    names = []
    counts = np.bincount(model.dof_jntid, minlength=model.njnt)  # dofs of each joint
    for dof in range(model.nv):
        joint = int(model.dof_jntid[dof])
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) or f"joint{joint}"
        first = int(model.jnt_dofadr[joint])
        count = int(counts[joint])
        names.append(name if count == 1 else f"{name}[{dof - first}]")
    return tuple(names)

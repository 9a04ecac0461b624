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
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from carnot.errors import CarnotError, InputError
from carnot.model.system import System, SystemContact, SystemProblem

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
) -> SystemProblem:
    """The impact problem of the MJCF model at ``path`` (or of an ``MjModel`` already loaded)
    in the state of ``keyframe`` (name or index) and/or ``qpos``/``qvel`` (module docstring).

    >>> mjcf_problem("no/such/model.xml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: no/such/model.xml: cannot read the MJCF model (...)
    """
    mujoco = _mujoco()
    source = str(path) if isinstance(path, (str, Path)) else "the model"
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
    data = mujoco.MjData(model)
    if keyframe is not None:
        mujoco.mj_resetDataKeyframe(model, data, _keyframe_id(mujoco, model, keyframe, source))
    for name, value, size in (("qpos", qpos, model.nq), ("qvel", qvel, model.nv)):
        if value is None:
            continue
        arr = np.asarray(value, dtype=float)
        if arr.shape != (size,) or not np.all(np.isfinite(arr)):
            raise InputError(f"{source}: {name}", f"must be {size} finite numbers", list(value))
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
    return SystemProblem(
        system=system,
        contacts=contacts,
        title=title
        or f"{Path(source).name}" + (f" at keyframe {keyframe}" if keyframe is not None else ""),
    )


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
    for dof in range(model.nv):
        joint = int(model.dof_jntid[dof])
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, joint) or f"joint{joint}"
        first = int(model.jnt_dofadr[joint])
        count = int(np.sum(model.dof_jntid == joint))
        names.append(name if count == 1 else f"{name}[{dof - first}]")
    return tuple(names)

"""The per-step sums of the energy audit in one compiled loop (Numba).

A step's audit is a dozen dot products over ``nv`` and ``nefc`` entries; as separate NumPy
or MuJoCo calls their overhead (a microsecond each) exceeds MuJoCo's own step for a small
scene, so they run here in one pass over MuJoCo's arrays (:func:`step_sums`): ``M0 v1``
from ``MjData.M``, gravity's generalized force from ``cdof`` (as ``mj_jac`` walks a body's
chain), the works (module :mod:`carnot.rollout.audit`), each constraint row's work added to
its group (contact pair, or kind and object), and whether any contact approaches faster than
``min_speed`` (the episodes' fast path); the pairs of an impact in :func:`pair_sums`.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from numba.core import types
from numba.experimental import structref

#: The kinds of constraint rows before the contacts (mjtConstraint 0..4).
OTHER_KINDS = 5


#: The columns of the audit's table, one row per step (:func:`step_sums`).
COLUMNS = ("time", "potential", "kinetic", "constraints", "gravity", "coriolis", "passive",
           "actuator", "applied", "implicit", "kinetic_end", "residual", "equality",
           "dof_friction", "tendon_friction", "joint_limit", "tendon_limit")  # fmt: skip

#: The first of the columns of the rows' work by kind (mjtConstraint 0..4, as ``OTHER_KINDS``);
#: the contacts' rows hold ``constraints`` less their sum.
KIND_COLUMN = 12

#: ``layout``'s header: nv, nbody, ngeom, nC, nD, pyramidal cones, implicit D.
_HEADER = 7

#: :func:`step_sums`' answers: no contact approaches, one does, the rows' kinds are needed.
CALM, APPROACHING, NEEDS_KINDS = 0, 1, 2


def layout_of(
    model: Any,
    gravity: np.ndarray,
    damping: np.ndarray,
    *,
    implicit: bool,
    pyramidal: bool,
    min_speed: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The model's constants that :func:`step_sums` reads, packed in two arrays (one
    argument each: a compiled call costs about 0.1 us an argument, a tenth of a step).

    ``layout`` (int64): the header (``nv``, ``nbody``, ``ngeom``, ``nC``, ``nD``, whether
    the cones are pyramidal, ``D`` implicit), then
    ``M_rowadr``, ``M_rownnz``, ``M_colind`` (the lower triangle of ``M`` that ``MjData.M``
    holds), ``dof_parentid``, each body's last dof of its chain (``mj_jac``'s start: the
    first ancestor with dofs, -1 for none) and ``body_rootid``, ``D_rowadr``, ``D_rownnz``,
    ``D_colind`` (``qDeriv``'s pattern). ``weights`` (float64): ``min_speed`` (m/s), ``h/2``
    (s), ``gravity`` (m/s^2, 3; zero where it is disabled), ``body_mass`` (kg), the diagonal
    ``damping`` that Euler takes implicitly (N s/m or N m s/rad, one per dof);
    ``implicit``: whether ``D`` is ``qDeriv``.

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string(
    ...     '<mujoco><worldbody><body><joint/><geom size=".1"/></body></worldbody></mujoco>')
    >>> layout, weights = layout_of(model, np.array([0, 0, -9.81]), np.zeros(1),
    ...                             implicit=False, pyramidal=True, min_speed=0.04)
    >>> layout[:7].tolist(), weights[:5].tolist()
    ([1, 2, 1, 1, 1, 1, 0], [0.04, 0.001, 0.0, 0.0, -9.81])
    """
    nv, nbody = int(model.nv), int(model.nbody)
    start = np.full(nbody, -1, dtype=np.int64)
    for body in range(1, nbody):
        chain = body
        while chain and not model.body_dofnum[chain]:  # mj_jac: skip fixed bodies
            chain = int(model.body_parentid[chain])
        if chain:
            start[body] = int(model.body_dofadr[chain]) + int(model.body_dofnum[chain]) - 1
    header = [nv, nbody, int(model.ngeom), int(model.nC), int(model.nD), pyramidal, implicit]
    layout = np.concatenate([
        np.array(header), model.M_rowadr, model.M_rownnz, model.M_colind, model.dof_parentid,
        start, model.body_rootid, model.D_rowadr, model.D_rownnz, model.D_colind,
    ]).astype(np.int64)  # fmt: skip
    weights = np.concatenate([[min_speed, 0.5 * float(model.opt.timestep)], gravity,
                              model.body_mass, damping]).astype(np.float64)  # fmt: skip
    return layout, weights


#: The fields of :class:`StepArrays`.
STEP_ARRAYS = ("mass", "cdof", "xipos", "subtree_com", "bias", "passive", "actuator", "smooth",
               "deriv", "energy", "layout", "weights", "acc_pairs", "used_pairs", "acc_other",
               "used_other")  # fmt: skip


@structref.register
class _StepArraysType(types.StructRef):
    """Numba's type of :class:`StepArrays` (its fields typed as given, literals widened)."""

    def preprocess_fields(self, fields):  # type: ignore[no-untyped-def]
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class StepArrays(structref.StructRefProxy):
    """The arrays :func:`step_sums` reads or adds to that stay where they are for an
    audit's life (:data:`STEP_ARRAYS`): MjData's of fixed size (``M``, ``cdof``, ``xipos``,
    ``subtree_com``, ``qfrc_bias``, ``qfrc_passive``, ``qfrc_actuator``, ``qfrc_smooth``,
    ``qDeriv``, ``energy``: views, read as MuJoCo fills them), the model's constants
    (:func:`layout_of`) and the totals per group, gathered once into one argument (each
    array passed to a compiled function costs about a tenth of a microsecond, a step's
    audit passes about thirty)."""


structref.define_proxy(StepArrays, _StepArraysType, list(STEP_ARRAYS))


@numba.njit(cache=True)
def step_sums(  # type: ignore[no-untyped-def]
    v0, v1, arrays, efc_force, efc_vel, jv1, efc_type, efc_id, geom, address, dim, jsum,
    table, step, time,
):  # fmt: skip
    """One step's audit in one pass (module docstring), from MuJoCo's data at the step's
    start: in ``arrays`` (:class:`StepArrays`) ``mass`` (``MjData.M``: ``M0``'s lower
    triangle), ``cdof``, ``xipos``, ``subtree_com``, the generalized forces ``qfrc_bias``,
    ``qfrc_passive``, ``qfrc_actuator``, ``qfrc_smooth``, ``deriv`` (``qDeriv``) and
    ``energy``; then the constraint rows
    (``efc_force``, ``efc_vel = J v0``, ``jv1 = J v1`` from ``mj_mulJacVec``, ``efc_type``
    and ``efc_id``), the contacts' ``geom``, ``efc_address`` and ``dim``; the model's
    constants packed by :func:`layout_of`. The contacts' rows are found from the contacts
    (``efc_address``, and ``dim``: ``2 (dim - 1)`` pyramidal rows, ``dim`` elliptic ones);
    ``efc_type`` and ``efc_id`` are read only where other rows exist (limits, equalities,
    friction loss): without them (empty arrays) and with such rows, nothing is done and
    :data:`NEEDS_KINDS` is returned, for a call with them.

    Fills ``jsum[:nefc] = J (v0 + v1)`` (``efc_vel + jv1``), and row ``step`` of
    ``table`` (:data:`COLUMNS`): ``time`` (s), MuJoCo's ``energy`` (potential, kinetic: J)
    at the step's start, the works ``h/2 F . (v0 + v1)`` (J) of the constraints (``sum_r f_r
    (J (v0 + v1))_r``), gravity (``sum_b m_b g . J_b(xipos_b)``, ``J_b`` walked as
    ``mj_jac`` does), Coriolis (``-qfrc_bias`` less gravity), ``qfrc_passive``,
    ``qfrc_actuator``, the applied forces (``qfrc_smooth`` less the others), the implicit
    term (``D (v1 - v0)``: ``qDeriv``'s, or Euler's ``-B``), ``1/2 v1^T M0 v1`` and the
    residual of the step's balance (module :mod:`carnot.rollout.audit`), then the work of the
    rows of each kind other than contacts (equality, dof and tendon friction loss, joint and
    tendon limits: from :data:`KIND_COLUMN` on); adds each row's work to ``acc_pairs[geom1 *
    ngeom + geom2]`` (contacts) or ``acc_other[kind, id]``. Returns
    :data:`APPROACHING` if a contact's normal velocity ``(J v0)_n`` is below ``-min_speed``,
    else :data:`CALM` (or :data:`NEEDS_KINDS`). Its test:
    the audit's residual at round-off (tests/test_audit.py), and each piece against MuJoCo's
    own ``mj_mulM``, ``mj_mulJacVec``, ``mj_jacSubtreeCom`` (tests/test_audit_fast.py).
    """
    return step_core(
        v0, v1, arrays.mass, arrays.cdof, arrays.xipos, arrays.subtree_com, arrays.bias,
        arrays.passive, arrays.actuator, arrays.smooth, arrays.deriv, arrays.energy,
        arrays.layout, arrays.weights, arrays.acc_pairs, arrays.used_pairs, arrays.acc_other,
        arrays.used_other, efc_force, efc_vel, jv1, efc_type, efc_id, geom, address, dim, jsum,
        table, step, time,
    )  # fmt: skip


@numba.njit(cache=True)
def step_core(  # type: ignore[no-untyped-def]
    v0, v1, mass, cdof, xipos, subtree_com, bias, passive, actuator, smooth, deriv, energy,
    layout, weights, acc_pairs, used_pairs, acc_other, used_other, efc_force, efc_vel, jv1,
    efc_type, efc_id, geom, address, dim, jsum, table, step, time,
):  # fmt: skip
    """:func:`step_sums` with :class:`StepArrays`' fields one by one (the in-place step,
    :mod:`carnot.rollout.inplace`, makes them from MuJoCo's addresses)."""
    nv, nbody, ngeom, nm, nd = layout[0], layout[1], layout[2], layout[3], layout[4]
    pyramidal, implicit = layout[5] != 0, layout[6] != 0
    nefc = efc_force.shape[0]
    covered = 0  # the contacts' rows
    for n in range(address.shape[0]):
        if address[n] >= 0:
            covered += 2 * (dim[n] - 1) if pyramidal and dim[n] > 1 else dim[n]
    others = covered < nefc
    if others and efc_type.shape[0] < nefc:
        return NEEDS_KINDS
    o = _HEADER
    m_rowadr, m_rownnz = layout[o : o + nv], layout[o + nv : o + 2 * nv]
    o += 2 * nv
    m_colind = layout[o : o + nm]
    o += nm
    dof_parent = layout[o : o + nv]
    o += nv
    body_start, body_root = layout[o : o + nbody], layout[o + nbody : o + 2 * nbody]
    o += 2 * nbody
    d_rowadr, d_rownnz = layout[o : o + nv], layout[o + nv : o + 2 * nv]
    o += 2 * nv
    d_colind = layout[o : o + nd]
    min_speed, half_h = weights[0], weights[1]
    gx, gy, gz = weights[2], weights[3], weights[4]
    body_mass, damping = weights[5 : 5 + nbody], weights[5 + nbody : 5 + nbody + nv]
    # 1/2 v1^T M0 v1 from the lower triangle (each off-diagonal entry twice)
    ke = 0.0
    for i in range(nv):
        adr = m_rowadr[i]
        for k in range(adr, adr + m_rownnz[i]):
            j = m_colind[k]
            ke += (1.0 if j == i else 2.0) * mass[k] * v1[i] * v1[j]
    b = 0.0
    p = 0.0
    a = 0.0
    s = 0.0
    imp = 0.0
    for i in range(nv):
        vs = v0[i] + v1[i]
        b += bias[i] * vs
        p += passive[i] * vs
        a += actuator[i] * vs
        s += smooth[i] * vs
        if implicit:  # (qDeriv (v1 - v0))_i, qDeriv's sparse row i
            row = 0.0
            for k in range(d_rowadr[i], d_rowadr[i] + d_rownnz[i]):
                row += deriv[k] * (v1[d_colind[k]] - v0[d_colind[k]])
            imp += row * vs
        else:
            imp -= damping[i] * (v1[i] - v0[i]) * vs
    # gravity: each body's weight m_b g over its centre's velocity J_b(xipos_b) (v0 + v1),
    # J_b's columns the chain of dofs from the body to the root (cdof: angular, linear)
    g = 0.0
    for body in range(1, nbody):
        i = body_start[body]
        if i < 0 or body_mass[body] == 0.0:
            continue
        root = body_root[body]
        ox = xipos[body, 0] - subtree_com[root, 0]
        oy = xipos[body, 1] - subtree_com[root, 1]
        oz = xipos[body, 2] - subtree_com[root, 2]
        wx = 0.0
        wy = 0.0
        wz = 0.0
        ux = 0.0
        uy = 0.0
        uz = 0.0
        while i >= 0:
            vs = v0[i] + v1[i]
            wx += cdof[i, 0] * vs
            wy += cdof[i, 1] * vs
            wz += cdof[i, 2] * vs
            ux += cdof[i, 3] * vs
            uy += cdof[i, 4] * vs
            uz += cdof[i, 5] * vs
            i = dof_parent[i]
        ux += wy * oz - wz * oy  # u + w x offset: the centre's velocity
        uy += wz * ox - wx * oz
        uz += wx * oy - wy * ox
        g += body_mass[body] * (gx * ux + gy * uy + gz * uz)
    # the rows: J (v0 + v1) = J v0 (MuJoCo's efc_vel, of the step's start) + J v1, each
    # row's work to its group: the contacts' by contact, the others' by kind and object
    c = 0.0
    for r in range(nefc):
        jsum[r] = efc_vel[r] + jv1[r]
        c += half_h * efc_force[r] * jsum[r]
    for n in range(address.shape[0]):
        adr = address[n]
        if adr < 0:  # a contact without rows (in the margin's gap)
            continue
        rows = 2 * (dim[n] - 1) if pyramidal and dim[n] > 1 else dim[n]
        code = geom[n, 0] * ngeom + geom[n, 1]
        for r in range(adr, adr + rows):
            acc_pairs[code] += half_h * efc_force[r] * jsum[r]
        used_pairs[code] = 1
    row = table[step]
    for kind in range(OTHER_KINDS):
        row[KIND_COLUMN + kind] = 0.0
    if others:
        for r in range(nefc):
            kind = efc_type[r]
            if kind < OTHER_KINDS:
                work = half_h * efc_force[r] * jsum[r]
                acc_other[kind, efc_id[r]] += work
                used_other[kind, efc_id[r]] = 1
                row[KIND_COLUMN + kind] += work
    approaching = CALM
    for n in range(address.shape[0]):
        adr = address[n]
        if adr < 0:  # a contact without rows (in the margin's gap)
            continue
        wn = efc_vel[adr]
        if pyramidal and dim[n] > 1:  # rows J_n +- mu J_t: their mean is J_n
            wn = 0.5 * (wn + efc_vel[adr + 1])
        if wn < -min_speed:
            approaching = APPROACHING
            break
    gravity = half_h * g
    bias_work = half_h * b
    passive_work = half_h * p
    actuator_work = half_h * a
    row[0] = time
    row[1] = energy[0]
    row[2] = energy[1]
    row[3] = c
    row[4] = gravity
    row[5] = -bias_work - gravity  # Coriolis and centrifugal: -qfrc_bias less gravity
    row[6] = passive_work
    row[7] = actuator_work
    # qfrc_smooth = passive + actuator + applied - bias
    row[8] = half_h * s - passive_work - actuator_work + bias_work
    row[9] = half_h * imp
    row[10] = 0.5 * ke
    row[11] = row[10] - row[2] - (row[3] + row[4] + row[5] + row[6] + row[7] + row[8] + row[9])
    return approaching


def other_width(model: Any) -> int:
    """The largest object id a non-contact row can carry, plus one (equality, dof, tendon,
    joint)."""
    return int(max(model.neq, model.nv, model.ntendon, model.njnt, 1))


@numba.njit(cache=True)
def pair_sums(  # type: ignore[no-untyped-def]
    jv0, jsum, efc_force, address, dim, geom, frame, friction, pos,
    ngeom, pyramidal, half_h, min_speed, open_codes, codes, values,
):  # fmt: skip
    """Per contact pair (geom1, geom2) that pushes while approaching faster than
    ``min_speed``, or whose code is in ``open_codes``: its code in ``codes[j]`` and in
    ``values[j]``: the mean normal velocity before and after the step (``J v0``, ``J v1``,
    m/s), the total force (N) and work (J) of its rows, the mean tangential velocity before
    and after (world, m/s; NaN without friction rows: pyramidal rows are ``J_n +- mu_k
    J_tk``, elliptic ones the contact frame's), the mean contact point (m) and the number of
    contacts (14 columns). Returns the number of pairs.

    >>> import numpy as np
    >>> codes, values = np.zeros(1, np.int64), np.zeros((1, 14))
    >>> frame = np.array([[0.0, 0, 1, 1, 0, 0, 0, 1, 0]])
    >>> n = pair_sums(np.array([-1.0]), np.array([-1.5]), np.array([4.0]),
    ...               np.array([0], np.int32), np.array([1], np.int32),
    ...               np.array([[0, 1]], np.int32), frame, np.zeros((1, 5)), np.zeros((1, 3)),
    ...               2, True, 0.5, 0.1, np.zeros(0, np.int64), codes, values)
    >>> n, int(codes[0]), values[0, :4].tolist()
    (1, 1, [-1.0, -0.5, 4.0, -3.0])
    """
    n = 0
    jv1 = jsum - jv0
    for k in range(address.shape[0]):
        adr = address[k]
        if adr < 0:  # a contact without rows (in the margin's gap)
            continue
        code = geom[k, 0] * ngeom + geom[k, 1]
        frictional = pyramidal and dim[k] > 1
        wn0 = 0.5 * (jv0[adr] + jv0[adr + 1]) if frictional else jv0[adr]
        rows = 2 * (dim[k] - 1) if frictional else dim[k]
        force = 0.0
        work = 0.0
        for r in range(adr, adr + rows):
            force += efc_force[r]
            work += half_h * efc_force[r] * jsum[r]
        wanted = force > 0 and wn0 < -min_speed
        if not wanted:
            for c in open_codes:
                if c == code:
                    wanted = True
        if not wanted:
            continue
        j = 0
        while j < n and codes[j] != code:
            j += 1
        if j == n:
            codes[j] = code
            values[j, :] = 0.0
            n += 1
        wn1 = 0.5 * (jv1[adr] + jv1[adr + 1]) if frictional else jv1[adr]
        values[j, 0] += wn0
        values[j, 1] += wn1
        values[j, 2] += force
        values[j, 3] += work
        for axis in range(3):
            if dim[k] < 3:  # no tangential rows
                values[j, 4 + axis] = np.nan
                values[j, 7 + axis] = np.nan
                continue
            if pyramidal:  # (J_n + mu_k J_tk) - (J_n - mu_k J_tk) = 2 mu_k J_tk
                t1_0 = (jv0[adr] - jv0[adr + 1]) / (2 * friction[k, 0])
                t2_0 = (jv0[adr + 2] - jv0[adr + 3]) / (2 * friction[k, 1])
                t1_1 = (jv1[adr] - jv1[adr + 1]) / (2 * friction[k, 0])
                t2_1 = (jv1[adr + 2] - jv1[adr + 3]) / (2 * friction[k, 1])
            else:
                t1_0, t2_0 = jv0[adr + 1], jv0[adr + 2]
                t1_1, t2_1 = jv1[adr + 1], jv1[adr + 2]
            values[j, 4 + axis] += t1_0 * frame[k, 3 + axis] + t2_0 * frame[k, 6 + axis]
            values[j, 7 + axis] += t1_1 * frame[k, 3 + axis] + t2_1 * frame[k, 6 + axis]
        for axis in range(3):
            values[j, 10 + axis] += pos[k, axis]
        values[j, 13] += 1.0
    for j in range(n):  # sums to means, but for the force and the work
        count = values[j, 13]
        values[j, 0] /= count
        values[j, 1] /= count
        for column in range(4, 13):
            values[j, column] /= count
    return n

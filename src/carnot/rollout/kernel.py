"""The per-step sums of the energy audit in one compiled loop (Numba).

A step's audit is a dozen dot products over ``nv`` and ``nefc`` entries; as separate NumPy
calls their overhead (a microsecond each) exceeds MuJoCo's own step for a small scene, so
they run here in one pass: the works (module :mod:`carnot.rollout.audit`), each constraint
row's work added to its group (contact pair, or kind and object), and whether any contact
approaches faster than ``min_speed`` (the episodes' fast path).
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np

#: The kinds of constraint rows before the contacts (mjtConstraint 0..4).
OTHER_KINDS = 5


@numba.njit(cache=True)
def step_sums(  # type: ignore[no-untyped-def]
    v0, v1, mv, jac_com, weight, bias, passive, actuator, smooth,
    efc_force, jv0, jsum, efc_type, efc_id, geom, address, dim,
    pyramidal, min_speed, half_h, ngeom, acc_pairs, used_pairs, acc_other, used_other, out,
):  # fmt: skip
    """Fill ``out`` with ``1/2 v1 . mv`` (J, with ``mv = M0 v1``), the works ``h/2 F . (v0 +
    v1)`` (J) of gravity (``J_com^T weight``), ``qfrc_bias``, ``qfrc_passive``,
    ``qfrc_actuator``, ``qfrc_smooth``, the constraints' ``h/2 sum_r f_r (J (v0 + v1))_r``,
    and 1.0 if a contact's normal velocity ``(J v0)_n`` is below ``-min_speed`` (else 0.0);
    add each row's work to ``acc_pairs[geom1 * ngeom + geom2]`` (contacts) or
    ``acc_other[kind, id]``.

    >>> import numpy as np
    >>> out, z, one = np.zeros(8), np.zeros(0), np.ones(1)
    >>> zi, g2 = np.zeros(0, np.int32), np.zeros((0, 2), np.int32)
    >>> step_sums(one, one, 2 * one, np.zeros((3, 1)), np.zeros(3), one, one, 0 * one, one,
    ...           z, z, z, zi, zi, g2, zi, zi, True, 0.1, 0.5, 1, np.zeros(1),
    ...           np.zeros(1, np.int8), np.zeros((5, 1)), np.zeros((5, 1), np.int8), out)
    >>> out.tolist()
    [1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0]
    """
    ke = 0.0
    g = 0.0
    b = 0.0
    p = 0.0
    a = 0.0
    s = 0.0
    for i in range(v0.shape[0]):
        vs = v0[i] + v1[i]
        ke += v1[i] * mv[i]
        force = jac_com[0, i] * weight[0] + jac_com[1, i] * weight[1] + jac_com[2, i] * weight[2]
        g += force * vs
        b += bias[i] * vs
        p += passive[i] * vs
        a += actuator[i] * vs
        s += smooth[i] * vs
    c = 0.0
    for r in range(efc_force.shape[0]):
        w = half_h * efc_force[r] * jsum[r]
        c += w
        kind = efc_type[r]
        ident = efc_id[r]
        if kind >= OTHER_KINDS:  # a contact row: its id is the contact's index
            code = geom[ident, 0] * ngeom + geom[ident, 1]
            acc_pairs[code] += w
            used_pairs[code] = 1
        else:
            acc_other[kind, ident] += w
            used_other[kind, ident] = 1
    approaching = 0.0
    for k in range(address.shape[0]):
        adr = address[k]
        if adr < 0:  # a contact without rows (in the margin's gap)
            continue
        wn = jv0[adr]
        if pyramidal and dim[k] > 1:  # rows J_n +- mu J_t: their mean is J_n
            wn = 0.5 * (wn + jv0[adr + 1])
        if wn < -min_speed:
            approaching = 1.0
            break
    out[0] = 0.5 * ke
    out[1] = half_h * g
    out[2] = half_h * b
    out[3] = half_h * p
    out[4] = half_h * a
    out[5] = half_h * s
    out[6] = c
    out[7] = approaching


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

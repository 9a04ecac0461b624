"""MuJoCo's ``MjData`` read in place by the audit's compiled step (one call a step).

Each field of ``MjData`` read through MuJoCo's Python bindings costs about half a
microsecond (a NumPy view made per read); a step's audit reads a dozen (the constraint
rows and the contacts move in MuJoCo's arena every step), which was most of its cost. Here
the compiled step reads them where MuJoCo keeps them: the address of each field inside the
``mjData`` and ``mjContact`` structs is laid out, with :mod:`ctypes`, from the declarations
that MuJoCo's bindings ship (``mujoco.introspect.structs``: each field's C type, in order),
and checked against the bindings before use: the pointers of fifteen fixed-size arrays
(:data:`FIXED_FIELDS`: ``qpos`` ... ``qfrc_inverse``) must equal the bindings' own arrays'
addresses, the scalars ``time``, ``ncon`` and ``nefc`` their values, an ``mjContact``'s
``geom``, ``dim`` and ``efc_address`` the values written through the bindings and its
arrays' offsets theirs; at the first step with rows and with contacts, every moving pointer
the step reads, and the contacts' stride (:func:`check_moving`). Where anything differs
(another MuJoCo, an unknown type), the audit reads through the bindings as before.
"""

from __future__ import annotations

import ctypes
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

from carnot.rollout.kernel import APPROACHING, COLUMNS, OTHER_KINDS, pair_sums, step_core

#: The fields of ``mjData`` the compiled step reads in place (their offsets, in this order).
DATA_FIELDS = ("time", "ncon", "nefc", "contact", "efc_type", "efc_id", "efc_J_rownnz",
               "efc_J_rowadr", "efc_J_colind", "efc_J", "efc_vel", "efc_force")  # fmt: skip
#: Fixed-size arrays of ``mjData`` whose pointers are checked against the bindings' arrays
#: (the step reads most; they lie before and after the scalars it reads).
FIXED_FIELDS = ("qpos", "qvel", "qacc_warmstart", "xpos", "xipos", "cdof", "subtree_com", "M",
                "qfrc_bias", "qDeriv", "qfrc_passive", "qfrc_actuator", "qfrc_smooth",
                "qfrc_constraint", "qfrc_inverse")  # fmt: skip
#: The fields of ``mjContact`` it reads, then the struct's size.
CONTACT_FIELDS = ("geom", "dim", "efc_address", "frame", "friction", "pos")

_SCALARS: dict[str, Any] = {
    "mjtNum": ctypes.c_double, "float": ctypes.c_float, "int": ctypes.c_int,
    "unsigned int": ctypes.c_uint, "mjtSize": ctypes.c_int64, "size_t": ctypes.c_size_t,
    "uintptr_t": ctypes.c_size_t, "uint64_t": ctypes.c_uint64, "int64_t": ctypes.c_int64,
    "mjtBool": ctypes.c_bool, "mjtByte": ctypes.c_ubyte, "char": ctypes.c_char,
}  # fmt: skip


def _ctype(decl: Any, structs: dict[str, Any], made: dict[str, Any]) -> Any:
    """The ctypes type of one introspected C type (KeyError: one not known here)."""
    kind = type(decl).__name__
    if kind == "PointerType":
        return ctypes.c_void_p
    if kind == "ArrayType":
        inner = _ctype(decl.inner_type, structs, made)
        for extent in reversed(decl.extents):
            inner = inner * int(extent)
        return inner
    if kind != "ValueType":
        raise KeyError(kind)
    name = str(decl.name).removeprefix("const ").strip()
    if name in _SCALARS:
        return _SCALARS[name]
    return _struct(name, structs, made)


def _struct(name: str, structs: dict[str, Any], made: dict[str, Any]) -> Any:
    """The ctypes mirror of the introspected struct ``name`` (C's layout rules: ctypes')."""
    if name not in made:
        fields = [(f.name, _ctype(f.type, structs, made)) for f in structs[name].fields]
        made[name] = type(name, (ctypes.Structure,), {"_fields_": fields})
    return made[name]


def _address(array: np.ndarray) -> int:
    return int(array.__array_interface__["data"][0])


def data_fields(mujoco: Any, data: Any) -> np.ndarray | None:
    """The offsets (bytes) of :data:`DATA_FIELDS` in ``mjData``, then of
    :data:`CONTACT_FIELDS` in ``mjContact`` and ``sizeof(mjContact)`` (int64), checked
    against the bindings on ``data`` (module docstring); None where they cannot be trusted.

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_string(
    ...     '<mujoco><worldbody><body><freejoint/><geom size=".1"/></body></worldbody></mujoco>')
    >>> data_fields(mujoco, mujoco.MjData(model)) is not None
    True
    """
    try:
        from mujoco.introspect import structs as introspected

        structs = introspected.STRUCTS
        made: dict[str, Any] = {}
        mj_data = _struct("mjData", structs, made)
        mj_contact = _struct("mjContact", structs, made)
        base = int(data._address)
    except (ImportError, AttributeError, KeyError, TypeError):
        return None
    view = mj_data.from_address(base)
    # the fixed-size arrays (of MjData's buffer, not its arena): the same addresses
    checked = 0
    for name in FIXED_FIELDS:
        array = getattr(data, name, None)
        if not isinstance(array, np.ndarray):
            return None
        if array.size == 0:
            continue
        if getattr(view, name) != _address(array):
            return None
        checked += 1
    if checked < 10 or view.time != data.time or view.ncon != data.ncon:
        return None
    if view.nefc != data.nefc:
        return None
    if data.nefc and (view.efc_force != _address(data.efc_force)
                      or view.efc_J != _address(data.efc_J)):  # fmt: skip
        return None
    # an mjContact of the bindings' own: its fields where the mirror puts them
    contact = mujoco.MjContact()
    start = _address(contact.pos) - mj_contact.pos.offset
    contact.geom = [1234567, 7654321]
    contact.dim, contact.efc_address = 4, 3456789
    mirror = mj_contact.from_address(start)
    if (list(mirror.geom), mirror.dim, mirror.efc_address) != ([1234567, 7654321], 4, 3456789):
        return None
    for name in ("geom", "frame", "friction", "pos"):
        if _address(getattr(contact, name)) - start != getattr(mj_contact, name).offset:
            return None
    offsets = [getattr(mj_data, name).offset for name in DATA_FIELDS]
    offsets += [getattr(mj_contact, name).offset for name in CONTACT_FIELDS]
    return np.array([*offsets, ctypes.sizeof(mj_contact)], dtype=np.int64)


@intrinsic
def f64_at(typingctx, address):  # type: ignore[no-untyped-def]
    """The ``double *`` at ``address`` (an int64)."""

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.inttoptr(args[0], ir.DoubleType().as_pointer())

    return types.CPointer(types.float64)(types.int64), codegen


@intrinsic
def i32_at(typingctx, address):  # type: ignore[no-untyped-def]
    """The ``int *`` at ``address`` (an int64)."""

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.inttoptr(args[0], ir.IntType(32).as_pointer())

    return types.CPointer(types.int32)(types.int64), codegen


@intrinsic
def i64_at(typingctx, address):  # type: ignore[no-untyped-def]
    """The ``int64 *`` at ``address`` (an int64): a pointer field's value."""

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.inttoptr(args[0], ir.IntType(64).as_pointer())

    return types.CPointer(types.int64)(types.int64), codegen


def pointer_field(base: int, offset: int) -> int:
    """The pointer stored at ``base + offset`` (an address; 0 for NULL)."""
    return int(ctypes.c_void_p.from_address(base + offset).value or 0)


@intrinsic
def i8_at(typingctx, address):  # type: ignore[no-untyped-def]
    """The ``int8 *`` at ``address`` (an int64)."""

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.inttoptr(args[0], ir.IntType(8).as_pointer())

    return types.CPointer(types.int8)(types.int64), codegen


#: The entries of the compiled step's one argument (:func:`observe_in_place`), an int64
#: array: the offsets of :func:`data_fields`, then addresses (bytes) and sizes.
PARAMS = (*(f"at_{name}" for name in DATA_FIELDS), *(f"contact_{n}" for n in CONTACT_FIELDS),
          "contact_size", "data", "checked", "sparse", "nq", "step", "table", "rows",
          "buffers", "capacity", "states", "clock", "mass", "cdof", "xipos", "subtree_com",
          "bias", "passive", "actuator", "smooth", "deriv", "energy", "qpos", "qvel", "layout",
          "layout_size", "weights", "weights_size", "acc_pairs", "used_pairs", "acc_other",
          "used_other", "other_width", "open", "open_count", "codes", "values", "pairs",
          "pair_capacity")  # fmt: skip
_P = {name: k for k, name in enumerate(PARAMS)}
(AT_TIME, AT_NCON, AT_NEFC, AT_CONTACT, AT_TYPE, AT_ID, AT_ROWNNZ, AT_ROWADR, AT_COLIND, AT_J,
 AT_VEL, AT_FORCE, C_GEOM, C_DIM, C_ADDRESS, C_FRAME, C_FRICTION, C_POS, C_SIZE, DATA,
 CHECKED, SPARSE, NQ, STEP, TABLE, ROWS, BUFFERS, CAPACITY, STATES, CLOCK, MASS, CDOF, XIPOS,
 SUBTREE_COM, BIAS, PASSIVE, ACTUATOR, SMOOTH, DERIV, ENERGY, QPOS, QVEL, LAYOUT, LAYOUT_SIZE,
 WEIGHTS, WEIGHTS_SIZE, ACC_PAIRS, USED_PAIRS, ACC_OTHER, USED_OTHER, OTHER_WIDTH, OPEN,
 OPEN_COUNT, CODES, VALUES, PAIRS, PAIR_CAPACITY) = range(len(PARAMS))  # fmt: skip

#: :func:`observe_in_place`'s answers beyond :mod:`carnot.rollout.kernel`'s (CALM 0,
#: APPROACHING 1): ``data.time`` is not one step on; the table is full; the rows outgrow the
#: buffers; the moving fields are to be checked (the first step with rows). Nothing is
#: recorded with these: the caller acts and calls again.
WRONG_TIME, FULL, GROW, CHECK = 10, 11, 12, 13


def param_index(name: str) -> int:
    """The place of ``name`` in :data:`PARAMS`."""
    return _P[name]


@numba.njit(cache=True)
def observe_in_place(p):  # type: ignore[no-untyped-def]
    """One step's audit (:func:`carnot.rollout.kernel.step_core`) read in place from the
    ``mjData`` at ``p[DATA]`` (module docstring; ``p``: :data:`PARAMS`): copies ``qpos`` and
    ``qvel`` after the step into ``states[(step + 1) % 2]`` (the state before it is in
    ``states[step % 2]``, ``(qpos, qvel)`` in a row), makes ``J v1`` from ``efc_J`` (CSR
    or dense, as ``mj_mulJacVec``), ``J (v0 + v1)`` in ``buffers[0]``, the contacts'
    ``geom``, ``dim`` and ``efc_address``, then the sums into row ``step`` of the table (and,
    where a contact approaches or an episode is open, ``OPEN``'s codes, the pairs' sums
    into ``CODES`` and ``VALUES``: :func:`carnot.rollout.kernel.pair_sums`), and
    advances ``clock`` (``[t, h, the step's start]``, s) and ``p[STEP]``. Returns the
    kernel's CALM or APPROACHING, or one of :data:`WRONG_TIME`, :data:`FULL`, :data:`GROW`,
    :data:`CHECK` (nothing done)."""
    base = p[DATA]
    clock = numba.carray(f64_at(p[CLOCK]), 3)
    h = clock[1]
    now = f64_at(base + p[AT_TIME])[0]
    if not abs(now - clock[0] - h) <= 1e-6 * h:  # NaN too
        return WRONG_TIME
    step = p[STEP]
    if step >= p[ROWS]:
        return FULL
    ncon = i32_at(base + p[AT_NCON])[0]
    nefc = i32_at(base + p[AT_NEFC])[0]
    if nefc > p[CAPACITY] or ncon > p[PAIR_CAPACITY]:
        return GROW
    if (nefc > 0 and p[CHECKED] & 1 == 0) or (ncon > 0 and p[CHECKED] & 2 == 0):
        return CHECK
    layout = numba.carray(i64_at(p[LAYOUT]), p[LAYOUT_SIZE])
    weights = numba.carray(f64_at(p[WEIGHTS]), p[WEIGHTS_SIZE])
    nv, nbody, ngeom, nm, nd = layout[0], layout[1], layout[2], layout[3], layout[4]
    nq = p[NQ]
    states = numba.carray(f64_at(p[STATES]), (2, nq + nv))
    before, after = states[step % 2], states[(step + 1) % 2]
    qpos, qvel = numba.carray(f64_at(p[QPOS]), nq), numba.carray(f64_at(p[QVEL]), nv)
    for i in range(nq):
        after[i] = qpos[i]
    for i in range(nv):
        after[nq + i] = qvel[i]
    v0, v1 = before[nq:], after[nq:]
    buffers = numba.carray(f64_at(p[BUFFERS]), (2, p[CAPACITY]))
    jsum, jv1 = buffers[0], buffers[1]
    efc_force = numba.carray(f64_at(i64_at(base + p[AT_FORCE])[0]), nefc)
    efc_vel = numba.carray(f64_at(i64_at(base + p[AT_VEL])[0]), nefc)
    efc_type = numba.carray(i32_at(i64_at(base + p[AT_TYPE])[0]), nefc)
    efc_id = numba.carray(i32_at(i64_at(base + p[AT_ID])[0]), nefc)
    jacobian = i64_at(base + p[AT_J])[0]
    if p[SPARSE] != 0:
        rownnz = numba.carray(i32_at(i64_at(base + p[AT_ROWNNZ])[0]), nefc)
        rowadr = numba.carray(i32_at(i64_at(base + p[AT_ROWADR])[0]), nefc)
        colind = i32_at(i64_at(base + p[AT_COLIND])[0])
        values = f64_at(jacobian)
        for r in range(nefc):
            total = 0.0
            for k in range(rowadr[r], rowadr[r] + rownnz[r]):
                total += values[k] * v1[colind[k]]
            jv1[r] = total
    else:
        dense = numba.carray(f64_at(jacobian), (nefc, nv))
        for r in range(nefc):
            total = 0.0
            for i in range(nv):
                total += dense[r, i] * v1[i]
            jv1[r] = total
    contact, size = i64_at(base + p[AT_CONTACT])[0], p[C_SIZE]
    geom = np.empty((ncon, 2), dtype=np.int32)
    dim = np.empty(ncon, dtype=np.int32)
    address = np.empty(ncon, dtype=np.int32)
    for k in range(ncon):
        at = contact + k * size
        geom[k, 0] = i32_at(at + p[C_GEOM])[0]
        geom[k, 1] = i32_at(at + p[C_GEOM] + 4)[0]
        dim[k] = i32_at(at + p[C_DIM])[0]
        address[k] = i32_at(at + p[C_ADDRESS])[0]
    width = p[OTHER_WIDTH]
    # Numba's disk cache checks only this file's stamp, not kernel.py's: step_core and
    # COLUMNS are compiled into this function, so a change there needs this file touched
    # (or the cache cleared) to be seen (kernel.COLUMNS: 17 columns since issue 36)
    answer = step_core(
        v0, v1, numba.carray(f64_at(p[MASS]), nm), numba.carray(f64_at(p[CDOF]), (nv, 6)),
        numba.carray(f64_at(p[XIPOS]), (nbody, 3)),
        numba.carray(f64_at(p[SUBTREE_COM]), (nbody, 3)), numba.carray(f64_at(p[BIAS]), nv),
        numba.carray(f64_at(p[PASSIVE]), nv), numba.carray(f64_at(p[ACTUATOR]), nv),
        numba.carray(f64_at(p[SMOOTH]), nv), numba.carray(f64_at(p[DERIV]), nd),
        numba.carray(f64_at(p[ENERGY]), 2), layout, weights,
        numba.carray(f64_at(p[ACC_PAIRS]), ngeom * ngeom),
        numba.carray(i8_at(p[USED_PAIRS]), ngeom * ngeom),
        numba.carray(f64_at(p[ACC_OTHER]), (OTHER_KINDS, width)),
        numba.carray(i8_at(p[USED_OTHER]), (OTHER_KINDS, width)), efc_force, efc_vel, jv1,
        efc_type, efc_id, geom, address, dim, jsum,
        numba.carray(f64_at(p[TABLE]), (p[ROWS], len(COLUMNS))), step, clock[0],
    )  # fmt: skip
    p[PAIRS] = 0
    if answer == APPROACHING or p[OPEN_COUNT] > 0:  # the pairs of the episodes
        frame = np.empty((ncon, 9))
        friction = np.empty((ncon, 5))
        pos = np.empty((ncon, 3))
        for k in range(ncon):
            at = contact + k * size
            for i in range(9):
                frame[k, i] = f64_at(at + p[C_FRAME])[i]
            for i in range(5):
                friction[k, i] = f64_at(at + p[C_FRICTION])[i]
            for i in range(3):
                pos[k, i] = f64_at(at + p[C_POS])[i]
        p[PAIRS] = pair_sums(
            efc_vel, jsum[:nefc], efc_force, address, dim, geom, frame, friction, pos, ngeom,
            layout[5] != 0, weights[1], weights[0],
            numba.carray(i64_at(p[OPEN]), p[OPEN_COUNT]),
            numba.carray(i64_at(p[CODES]), p[PAIR_CAPACITY]),
            numba.carray(f64_at(p[VALUES]), (p[PAIR_CAPACITY], 14)),
        )  # fmt: skip
    clock[2] = clock[0]
    clock[0] = clock[0] + h
    p[STEP] = step + 1
    return answer


def check_moving(data: Any, fields: np.ndarray) -> int:
    """Which moving fields (the constraint rows' and the contacts') of ``data`` are where
    ``fields`` (:func:`data_fields`) puts them: bit 1 the rows' (checked where it has rows:
    each pointer against the bindings' array), bit 2 the contacts' (where it has contacts);
    -1 where one is not."""
    base = int(data._address)
    at = {name: int(fields[k]) for k, name in enumerate(DATA_FIELDS)}
    checked = 0
    if int(data.nefc):
        for name in DATA_FIELDS[4:]:
            if pointer_field(base, at[name]) != _address(getattr(data, name)):
                return -1
        checked |= 1
    if int(data.ncon):
        geom_offset = int(fields[len(DATA_FIELDS)])
        geom = data.contact.geom
        if pointer_field(base, at["contact"]) + geom_offset != _address(geom):
            return -1
        if geom.strides[0] != int(fields[len(DATA_FIELDS) + len(CONTACT_FIELDS)]):
            return -1  # sizeof(mjContact): the stride from one contact to the next
        checked |= 2
    return checked

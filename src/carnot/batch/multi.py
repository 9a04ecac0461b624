"""Many multi-contact impacts at once: the simultaneous law over arrays (issue 14, item 5).

Two entry points, both with leading batch dimensions ``(...)`` (one impact is ``()``):

* :func:`contact_space_impacts` ``(G (..., m, m), w' (..., m), layout, e (..., k), mu (...,
  k))``: any producer's contact space (:class:`carnot.space.ContactSpace` gives ``G`` and
  ``w'``); ``layout`` is the number of tangent rows of each contact (0, 1 or 2), whose rows
  are consecutive: its normal row, then its tangent rows;
* :func:`multi_impacts` ``(a, b, points (..., k, 3), normals (..., k, 3), e, mu)``: a free
  body ``a`` in ``k`` point contacts with a body ``b`` or a fixed obstacle (``b=None``), as
  :func:`carnot.solve_impact` models them: a contact has the tangent rows ``t1``, ``t2`` of
  :func:`carnot.conventions.contact_frame` when its friction is positive somewhere in the
  batch (3D Coulomb, the exact circular cone), a normal row only otherwise.

The law is :func:`carnot.laws.multiple.resolve_simultaneous` (Moreau/Glocker's generalized
Newton with Coulomb friction at impact, DESIGN.md section 6), compiled for one impact
(:mod:`carnot.batch.multi_kernel`, the same regime enumeration in the same order), run in
parallel over the batch, the reference's linear program for rank-deficient regimes included
(compiled too), the 3D cones tested exactly (the inscribed 32-gons, then cutting planes).
Should that program not finish (its pivot limit), the impact is solved by the reference
itself (``by_reference``: not seen in the tests and benchmarks); so is an impact in which no
regime holds (the reference then starts from the smoothed law: ``no_solution`` only where
that finds none either). The kernel's 3D slip roots come from the reference's own iteration
(``newton_broyden``), step for step. So each row is the answer of ``solve_impact`` on that
impact (tested to round-off times cond(G); velocities where the impulses are not unique),
except where an ill-conditioned slip system's iteration, steered by round-off, reaches
another of the impact's several answers (measured: ``benchmarks/same_answers.py``).

Limits (explicit; more is refused, naming the field): at most :data:`MAX_CONTACTS` = 8
contacts and :data:`MAX_ROWS` = 12 contact rows per impact (8 frictionless contacts, 6 planar
or 4 spatial frictional ones), and at most 4096 regimes to enumerate.

Flags per impact (boolean arrays): ``statically_indeterminate`` (impulses not unique,
velocities unique: the least-norm impulses of the widest regime are reported, as the
reference does), ``multiple_solutions`` (several outcomes with different velocities: the first
in the reference's order is reported; ``carnot.solve_impact`` lists the others),
``no_solution`` (no impulse meets the law: zero impulses), ``separating_contact_approaches``,
``not_converged`` (a row the reference solved, whose search for a 3D slip answer stopped
short of one: not a proof that none exists, zero impulses), ``energy_gain``,
``uniqueness_verified`` (False when more than two 3D frictional contacts
take part: as the reference, the regimes are then tried most likely first).

A contact separating before the impact takes no part in the kernel; where the others drive
it into its obstacle (the kernel's ``separating_contact_approaches``), the impact goes to the
reference law, :func:`carnot.solvers.resolve`, in which it takes part with e = 0, as in
``carnot.solve_impact`` (issue 33, item 3): such a row is ``by_reference``.

Where no contact has friction, a small kernel of its own runs first
(:func:`carnot.batch.multi_kernel.run_normal`, ``solve_rows_normal``: every impact whose
taking-part contacts have a clearly non-singular ``G``), and the whole kernel, compiled only
then, does the rest: a frictionless batch compiles in seconds, not minutes.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from carnot import validate
from carnot.batch.compile_notice import call_announcing
from carnot.batch.kernels import BatchBodies
from carnot.errors import InputError

#: The compiled loops are parallel (Numba): one at a time, whatever the caller's threads
#: (Numba's parallel loops must not be launched concurrently; a sweep runs chunks in threads).
_KERNEL_LOCK = threading.Lock()
#: Per-impact limits (see the module docstring).
MAX_CONTACTS = 8
MAX_ROWS = 12
#: Regime codes of :attr:`MultiImpacts.regime`, by name.
REGIME_NAMES: dict[int, str] = {0: "separate", 1: "frictionless", 2: "stick", 3: "slip"}
_CODES = {name: code for code, name in REGIME_NAMES.items()}
#: Flag names by bit (of :mod:`carnot.batch.multi_kernel`).
FLAG_BITS = (("statically_indeterminate", 1), ("multiple_solutions", 2), ("no_solution", 4),
             ("separating_contact_approaches", 8), ("not_converged", 32))  # fmt: skip
_UNVERIFIED = 16
_SEPARATING_APPROACHES = dict(FLAG_BITS)["separating_contact_approaches"]
#: Relative slack of the energy-gain flag (as carnot.batch.pipeline.FLAG_SLACK).
FLAG_SLACK = 1e-12


@dataclass(frozen=True, kw_only=True, eq=False)
class ContactSpaceImpacts:
    """What :func:`contact_space_impacts` gives, per impact: row ``impulses`` (N s) and
    ``w_after = w' + G impulses`` (m/s), each contact's ``regime`` (int8 codes of
    :data:`REGIME_NAMES`) and ``active``, the complementarity ``residual`` (m/s), the flags
    (boolean) and ``by_reference`` (solved by the reference law)."""

    impulses: Any
    w_after: Any
    regime: Any
    active: Any
    residual: Any
    dissipated: Any
    statically_indeterminate: Any
    multiple_solutions: Any
    no_solution: Any
    separating_contact_approaches: Any
    not_converged: Any
    uniqueness_verified: Any
    by_reference: Any


@dataclass(frozen=True, kw_only=True, eq=False)
class MultiImpacts:
    """What :func:`multi_impacts` gives, per impact: each contact's ``impulse`` (N s, world,
    what ``a`` receives, ``(..., k, 3)``), ``normal_impulse`` and ``dissipated_by_contact``
    (its share of the theorem, J), ``regime`` and ``active`` ``(..., k)``; the velocities
    after (``None`` for a fixed ``b``); ``before``, ``after``, ``dissipated`` (direct,
    ``E' - E''``), ``dissipated_theorem`` and Carnot's ``lost_velocities`` (J);
    ``residual`` (m/s); the flags; and
    ``by_reference``."""

    impulse: Any
    normal_impulse: Any
    dissipated_by_contact: Any
    regime: Any
    active: Any
    velocity_a: Any
    angular_velocity_a: Any
    velocity_b: Any | None
    angular_velocity_b: Any | None
    before: Any
    after: Any
    dissipated: Any
    dissipated_theorem: Any
    lost_velocities: Any
    residual: Any
    statically_indeterminate: Any
    multiple_solutions: Any
    no_solution: Any
    separating_contact_approaches: Any
    not_converged: Any
    energy_gain: Any
    uniqueness_verified: Any
    by_reference: Any


def _frozen(*arrays: np.ndarray) -> list[np.ndarray]:
    """Read-only views of the kernels' input arrays (C-contiguous already).

    Numba compiles a kernel once per combination of argument types, and a read-only array is
    another type than a writable one: whether ``np.ascontiguousarray(np.broadcast_to(x))``
    gives a read-only view or a writable copy depends on the caller's shapes, so the heavy
    kernels were compiled for four to eight combinations of the same inputs (minutes of a
    clean checkout's tests). As views, one combination, at no copy.
    """
    views = []
    for arr in arrays:
        view = arr.view()
        view.flags.writeable = False
        views.append(view)
    return views


def _layout(layout: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Normal rows, tangent rows (k, 2; -1 where none) and tangent counts of a layout."""
    counts = [int(t) for t in layout]
    if not counts:
        raise InputError("layout", "must list at least one contact", layout)
    if len(counts) > MAX_CONTACTS:
        raise InputError("layout", f"at most {MAX_CONTACTS} contacts per impact", len(counts))
    for c, t in enumerate(counts):
        if t not in (0, 1, 2):
            raise InputError(f"layout[{c}]", "must be 0, 1 or 2 tangent rows", t)
    m = len(counts) + sum(counts)
    if m > MAX_ROWS:
        raise InputError("layout", f"at most {MAX_ROWS} contact rows per impact", m)
    nrow = np.empty(len(counts), dtype=np.int64)
    trow = np.zeros((len(counts), 2), dtype=np.int64)
    r = 0
    for c, t in enumerate(counts):
        nrow[c] = r
        trow[c, :t] = np.arange(r + 1, r + 1 + t)
        r += 1 + t
    return nrow, trow, np.array(counts, dtype=np.int64), m


def _per_contact(value: Any, name: str, shape: tuple[int, ...], k: int) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    try:
        return np.ascontiguousarray(np.broadcast_to(arr, shape + (k,)))
    except ValueError:
        raise InputError(name, f"must broadcast to {shape + (k,)}", arr.shape) from None


def _check_coefficients(e: np.ndarray, mu: np.ndarray) -> None:
    validate.number_in(e, "restitution", 0.0, 1.0)
    validate.non_negative_number(mu, "friction")


def contact_space_impacts(delassus: Any, w_before: Any, layout: Any, restitution: Any,
                          friction: Any = 0.0) -> ContactSpaceImpacts:  # fmt: skip
    """The simultaneous law on a batch of contact spaces.

    ``delassus`` ``G`` (..., m, m; 1/kg, symmetric positive semi-definite), ``w_before``
    (..., m; m/s), ``layout`` the tangent-row count of each contact (rows consecutive),
    ``restitution`` and ``friction`` per contact (broadcast to ``(..., k)``).

    Three balls in a row, the first at 1 m/s into two touching ones, e = 0 and e = 1
    (simultaneous: ``((1-2e)/3, (1+e)/3, (1+e)/3) v``):

    >>> out = contact_space_impacts([[2.0, -1.0], [-1.0, 2.0]], [-1.0, 0.0], [0, 0],
    ...                             np.array([[0.0, 0.0], [1.0, 1.0]]))
    >>> out.impulses.round(12).tolist()
    [[0.666666666667, 0.333333333333], [1.333333333333, 0.666666666667]]
    """
    from carnot.batch.multi_kernel import UNDECIDED, solve_rows, solve_rows_normal

    nrow, trow, ntan, m = _layout(layout)
    k = len(nrow)
    g = np.asarray(delassus, dtype=float)
    w = np.asarray(w_before, dtype=float)
    if g.ndim < 2 or g.shape[-2:] != (m, m):
        raise InputError("delassus", f"must have trailing shape {(m, m)}", g.shape)
    if w.ndim < 1 or w.shape[-1] != m:
        raise InputError("w_before", f"must have trailing shape {(m,)}", w.shape)
    try:
        shape = tuple(np.broadcast_shapes(g.shape[:-2], w.shape[:-1],
                                          np.shape(restitution)[:-1] if np.ndim(restitution)
                                          else (), np.shape(friction)[:-1]
                                          if np.ndim(friction) else ()))  # fmt: skip
    except ValueError:
        raise InputError("inputs", "batch shapes do not broadcast together", None,
                         show_value=False) from None  # fmt: skip
    for name, arr in (("delassus", g), ("w_before", w)):
        if not np.all(np.isfinite(arr)):
            raise InputError(name, "must be finite", arr[~np.isfinite(arr)][:3])
    scale = np.max(np.abs(g), axis=(-2, -1), keepdims=True)
    asym = np.abs(g - np.swapaxes(g, -1, -2)) > 1e-9 * scale
    if np.any(asym):
        raise InputError("delassus", "must be symmetric (1e-9 relative)",
                         g[np.any(asym, axis=(-2, -1))][0])  # fmt: skip
    e = _per_contact(restitution, "restitution", shape, k)
    mu = _per_contact(friction, "friction", shape, k)
    _check_coefficients(e, mu)
    count = int(np.prod(shape))
    gf = np.ascontiguousarray(np.broadcast_to(g, shape + (m, m))).reshape(count, m, m)
    gf = 0.5 * (gf + np.swapaxes(gf, -1, -2))
    # (a writable copy, as ``gf``: the kernel's rows then have the types of the body route's
    # own work arrays, and its regime solvers compile once for both routes)
    wf = np.array(np.broadcast_to(w, shape + (m,)), dtype=float, order="C").reshape(count, m)
    ef, muf = e.reshape(count, k), mu.reshape(count, k)
    imp = np.empty((count, m))
    wa = np.empty((count, m))
    regime = np.empty((count, k), dtype=np.int8)
    active = np.empty((count, k), dtype=np.bool_)
    status = np.empty(count, dtype=np.int8)
    flags = np.empty(count, dtype=np.int8)
    residual = np.empty(count)
    ef, muf = _frozen(ef, muf)
    outputs: tuple[np.ndarray, ...] = (imp, wa, regime, active, status, flags, residual)
    if m == k:  # frictionless: the small kernel first, the regime solvers only if needed
        with _KERNEL_LOCK:
            call_announcing(solve_rows_normal, "the multi-contact batch kernel's frictionless "
                            "front", gf, wf, nrow, trow, ntan, ef, muf, *outputs)  # fmt: skip
        rest = np.flatnonzero(status == UNDECIDED)
        if len(rest):
            sub_e, sub_mu = _frozen(ef[rest], muf[rest])  # (gf[rest]: writable, as gf)
            sub_out = tuple(np.ascontiguousarray(full[rest]) for full in outputs)
            with _KERNEL_LOCK:
                _call_whole(solve_rows, gf[rest], wf[rest], nrow, trow, ntan, sub_e, sub_mu,
                            *sub_out)  # fmt: skip
            for full, sub in zip(outputs, sub_out, strict=True):
                full[rest] = sub
    else:
        with _KERNEL_LOCK:
            _call_whole(solve_rows, gf, wf, nrow, trow, ntan, ef, muf, *outputs)
    _too_many(status)
    by_reference = _by_reference(status, flags)
    for i in np.flatnonzero(by_reference).tolist():
        answer = _reference(gf[i], wf[i], nrow, ntan, ef[i], muf[i])
        imp[i], wa[i], regime[i], active[i], flags[i], residual[i] = answer
    out = {name: (flags & bit) != 0 for name, bit in FLAG_BITS}
    dissipated = -0.5 * np.einsum("ij,ij->i", imp, wf + wa)
    return ContactSpaceImpacts(
        impulses=imp.reshape(shape + (m,)), w_after=wa.reshape(shape + (m,)),
        regime=regime.reshape(shape + (k,)), active=active.reshape(shape + (k,)),
        residual=residual.reshape(shape), dissipated=dissipated.reshape(shape),
        uniqueness_verified=((flags & _UNVERIFIED) == 0).reshape(shape),
        by_reference=by_reference.reshape(shape),
        **{name: v.reshape(shape) for name, v in out.items()},
    )  # fmt: skip


def _too_many(status: np.ndarray) -> None:
    bad = np.flatnonzero(status == 3)
    if bad.size:
        raise InputError("contacts", "at most 4096 regimes can be enumerated by the "
                         "simultaneous law", f"impact {int(bad[0])}")  # fmt: skip


#: The kernel's statuses that send a row to the reference (carnot.batch.multi_kernel's
#: NEEDS_REFERENCE and NO_SOLUTION; not imported from it: that would import Numba here).
REFERENCE_STATUSES = (1, 2)


def _by_reference(status: np.ndarray, flags: np.ndarray) -> np.ndarray:
    """The rows the reference law solves: those the kernel could not finish, those in which
    no regime held (the reference's root finder, then its start from the smoothed law, may
    find one), and those in which a contact separating before the impact is driven into its
    obstacle (``separating_contact_approaches``: the kernel leaves such a contact out; the
    reference, :func:`carnot.solvers.resolve`, lets it take part, as ``solve_impact`` does).

    >>> _by_reference(np.array([0, 1, 2, 0, 0], dtype=np.int8),
    ...               np.array([0, 0, 0, 8, 1], dtype=np.int8)).tolist()
    [False, True, True, True, False]
    """
    return np.isin(status, REFERENCE_STATUSES) | ((flags & _SEPARATING_APPROACHES) != 0)


def _reference(g: np.ndarray, w: np.ndarray, nrow: np.ndarray, ntan: np.ndarray,
               e: np.ndarray, mu: np.ndarray) -> tuple[Any, ...]:  # fmt: skip
    """One impact by the enumeration of :func:`carnot.solvers.resolve`, as the kernel's
    outputs: impulses, velocities after, regimes, active, flag bits, residual. The law is
    run whole, as ``solve_impact`` runs it, every regime included even where the kernel
    found none to hold (its root finder reaches slip roots that the kernel's Newton
    iteration misses: a box landing on a tilted ground; issue 14), and every closed contact
    taking part: one separating before the impact that the others would drive into its
    obstacle takes part, with e = 0 (issue 33, item 3)."""
    from carnot.laws.multiple import ContactRows
    from carnot.solvers import SolverOptions, resolve

    contacts = [ContactRows(normal=int(n), tangents=tuple(range(int(n) + 1, int(n) + 1 + int(t))),
                            restitution=float(ec), friction=float(mc))
                for n, t, ec, mc in zip(nrow, ntan, e, mu, strict=True)]  # fmt: skip
    answer = resolve(g, w, contacts, options=SolverOptions(name="enumerate"))
    bits = sum(bit for name, bit in FLAG_BITS if name in answer.flags)
    if not answer.extra.get("uniqueness_verified", 1.0):
        bits |= _UNVERIFIED
    regimes = [_CODES[c.regime] for c in answer.contacts]
    return (answer.impulses, answer.w_after, regimes, [c.active for c in answer.contacts],
            bits, answer.residual)  # fmt: skip


# ----------------------------------------------------------------------- free bodies


def _field(value: Any, name: str, shape_core: tuple[int, ...]) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if isinstance(value, int | float) and shape_core == (3,):
        arr = np.full(3, float(value))
    if arr.shape[arr.ndim - len(shape_core):] != shape_core or arr.ndim < len(shape_core):
        raise InputError(name, f"must have trailing shape {shape_core}", arr.shape)
    if not np.all(np.isfinite(arr)):
        raise InputError(name, "must be finite", arr[~np.isfinite(arr)][:3])
    return arr


def multi_impacts(a: BatchBodies, b: BatchBodies | None, points: Any, normals: Any,
                  restitution: Any, friction: Any = 0.0) -> MultiImpacts:  # fmt: skip
    """The simultaneous law on a batch of impacts of body ``a`` with ``b`` (``None``: a fixed
    obstacle) at ``k`` point contacts.

    ``points`` (..., k, 3; m) and ``normals`` (..., k, 3; from ``b`` into ``a``, any non-zero
    length), ``restitution`` and ``friction`` per contact (broadcast to ``(..., k)``).

    A uniform rod (1 kg, 1 m, J = 1/12) falling flat at 1 m/s onto two supports at its
    ends, e = 0.5: both ends rebound at 0.5 m/s, the impulses 0.75 N s each.

    >>> rod = BatchBodies(mass=1.0, inertia_com=np.diag([1 / 12, 1 / 12, 1e-3]),
    ...                   position_com=[0, 0, 0], velocity_com=[0, 0, -1.0])
    >>> out = multi_impacts(rod, None, [[-0.5, 0, 0], [0.5, 0, 0]], [[0, 0, 1], [0, 0, 1]], 0.5)
    >>> out.normal_impulse.round(12).tolist(), out.velocity_a.round(12).tolist()
    ([0.75, 0.75], [0.0, 0.0, 0.5])
    """
    from carnot.batch.multi_kernel import UNDECIDED, run_normal
    from carnot.batch.multi_kernel import run as kernel

    run: Any = kernel  # (a Numba dispatcher: mypy does not see its signature)

    if not isinstance(a, BatchBodies):
        raise InputError("a", "must be a carnot.batch.BatchBodies", type(a).__name__)
    if b is not None and not isinstance(b, BatchBodies):
        raise InputError("b", "must be a carnot.batch.BatchBodies or None", type(b).__name__)
    pts = _field(points, "points", (3,))
    nrm = _field(normals, "normals", (3,))
    if pts.ndim < 2 or nrm.ndim < 2:
        raise InputError("points", "must be (..., k, 3): k contact points", pts.shape)
    k = pts.shape[-2]
    if nrm.shape[-2] != k:
        raise InputError("normals", f"must hold one normal per point ({k})", nrm.shape)
    sides: dict[str, dict[str, np.ndarray]] = {}
    for side, body in (("a", a), ("b", b)):
        if body is None:
            continue
        sides[side] = {
            "mass": _field(body.mass, f"{side}.mass", ()),
            "inertia": _field(body.inertia_com, f"{side}.inertia_com", (3, 3)),
            "x": _field(body.position_com, f"{side}.position_com", (3,)),
            "v": _field(body.velocity_com, f"{side}.velocity_com", (3,)),
            "om": _field(body.angular_velocity, f"{side}.angular_velocity", (3,)),
        }
        validate.positive_number(sides[side]["mass"], f"{side}.mass", unit=" kg")
    shapes = [pts.shape[:-2], nrm.shape[:-2], np.shape(restitution)[:-1]
              if np.ndim(restitution) > 1 else (), np.shape(friction)[:-1]
              if np.ndim(friction) > 1 else ()]  # fmt: skip
    cores = {"mass": 0, "inertia": 2, "x": 1, "v": 1, "om": 1}
    for fields_ in sides.values():
        shapes += [v.shape[: v.ndim - cores[n]] for n, v in fields_.items()]
    try:
        shape = tuple(np.broadcast_shapes(*shapes))
    except ValueError:
        raise InputError("inputs", "batch shapes do not broadcast together", None,
                         show_value=False) from None  # fmt: skip
    count = int(np.prod(shape))
    e = _per_contact(restitution, "restitution", shape, k).reshape(count, k)
    mu = _per_contact(friction, "friction", shape, k).reshape(count, k)
    _check_coefficients(e, mu)
    length = np.einsum("...i,...i->...", nrm, nrm)
    if np.any(~(length > 0)):
        raise InputError("normals", "must be non-zero", nrm[~(length > 0)][:3])
    tangential = np.any(mu > 0, axis=0).astype(np.int64)
    nrow, trow, ntan, m = _layout(2 * tangential)
    if len(nrow) != k:  # pragma: no cover - _layout keeps the contacts
        raise AssertionError

    def full(arr: np.ndarray, core: tuple[int, ...]) -> np.ndarray:
        return np.ascontiguousarray(np.broadcast_to(arr, shape + core)).reshape(
            (count,) + core)  # fmt: skip

    fixed = b is None
    body_b = sides.get("b") or {"mass": np.array(1.0), "inertia": np.eye(3), "x": np.zeros(3),
                                "v": np.zeros(3), "om": np.zeros(3)}  # fmt: skip
    args = []
    for fields_ in (sides["a"], body_b):
        args += [full(fields_["mass"], ()), full(fields_["inertia"], (3, 3)),
                 full(fields_["x"], (3,)), full(fields_["v"], (3,)), full(fields_["om"], (3,))]
    pts_f, nrm_f = full(pts, (k, 3)), full(nrm, (k, 3))
    *args, pts_f, nrm_f, e, mu = _frozen(*args, pts_f, nrm_f, e, mu)
    width = 17 + 5 * k
    floats = np.empty((count, width))  # (every row is written: finish, or the reference)
    regime = np.empty((count, k), dtype=np.int8)
    active = np.empty((count, k), dtype=np.bool_)
    status = np.zeros(count, dtype=np.int8)
    flags = np.zeros(count, dtype=np.int8)
    residual = np.full(count, np.nan)
    bad = np.zeros(count, dtype=np.int8)
    inputs = (*args, not fixed, pts_f, nrm_f, e, mu, nrow, trow, ntan, tangential)
    outputs = (floats, regime, active, status, flags, residual, bad)
    if m == k:  # frictionless: the small kernel first, the regime solvers only if needed
        with _KERNEL_LOCK:
            call_announcing(run_normal, "the multi-contact batch kernel's frictionless front",
                            *inputs, *outputs)  # fmt: skip
        rest = np.flatnonzero(status == UNDECIDED)
        if len(rest):
            _run_rows(run, rest, inputs, outputs)
    else:
        with _KERNEL_LOCK:
            _call_whole(run, *inputs, *outputs)
    if np.any(bad):
        i = int(np.argmax(bad != 0))
        side = "a" if bad[i] == 1 else "b"
        raise InputError(f"{side}.inertia_com", "must be symmetric positive definite and "
                         "realizable (each principal moment <= the sum of the other two)",
                         args[1 if side == "a" else 6][i])  # fmt: skip
    _too_many(status)
    by_reference = _by_reference(status, flags)
    if by_reference.any():
        _reference_bodies(np.flatnonzero(by_reference), args, not fixed, pts_f, nrm_f, e, mu,
                          nrow, ntan, tangential, m, floats, regime, active, flags,
                          residual)  # fmt: skip
    return _multi_result(floats, regime, active, flags, residual, by_reference, shape, k,
                         fixed)  # fmt: skip


#: What the first call of the whole multi-contact kernel compiles (the notice's words).
_WHOLE_KERNEL = "the multi-contact batch kernel (under a minute; its parts side by side)"


def _call_whole(kernel: Any, *args: Any) -> None:
    """``kernel(*args, *solvers)``, ``kernel`` one of the whole kernel's entry points (``run``,
    ``solve_rows``) and ``solvers`` the regime solvers it calls by their address
    (:func:`carnot.batch.multi_kernel.impact_solvers`); the first call in a process
    announced, as it may compile them all. Uncompiled, the entry point is compiled for the
    types of ``args`` and of the callbacks while child processes compile the callbacks."""
    from carnot.batch.multi_kernel import impact_solvers, solver_types

    if getattr(kernel, "signatures", ()):
        kernel(*args, *impact_solvers())
        return

    def first(*given: Any) -> None:
        import numba

        types = (*(numba.typeof(a) for a in given), *solver_types())
        kernel(*given, *impact_solvers(meanwhile=lambda: kernel.compile(types)))

    call_announcing(first, _WHOLE_KERNEL, *args)


def _run_rows(kernel: Any, rows: np.ndarray, inputs: tuple[Any, ...],
              outputs: tuple[np.ndarray, ...]) -> None:  # fmt: skip
    """The body kernel ``kernel`` on the impacts ``rows`` alone: their inputs gathered (the
    per-impact arrays, the first 14 of ``inputs``; read-only, the kernel's one type for
    them), solved, and the results written back into ``outputs``."""
    per_impact = _frozen(*(np.ascontiguousarray(a[rows]) for a in inputs[:10] + inputs[11:15]))
    sub_inputs = (*per_impact[:10], inputs[10], *per_impact[10:], *inputs[15:])
    sub_outputs = tuple(np.ascontiguousarray(out[rows]) for out in outputs)
    with _KERNEL_LOCK:
        _call_whole(kernel, *sub_inputs, *sub_outputs)
    for out, sub in zip(outputs, sub_outputs, strict=True):
        out[rows] = sub


def _reference_bodies(rows: np.ndarray, args: list[np.ndarray], movable_b: bool,
                      pts: np.ndarray, nrm: np.ndarray, e: np.ndarray, mu: np.ndarray,
                      nrow: np.ndarray, ntan: np.ndarray, tangential: np.ndarray, m: int,
                      floats: np.ndarray, regime: np.ndarray, active: np.ndarray,
                      flags: np.ndarray, residual: np.ndarray) -> None:  # fmt: skip
    """The impacts ``rows`` by the reference law, assembled and finished as in the kernel."""
    from carnot.batch.multi_kernel import assemble, finish

    for i in rows.tolist():
        ma, ja, xa, va, oa, mb, jb, xb, vb, ob = (arr[i] for arr in args)
        g, w, jac_a, jac_b, axes, inv_a, inv_b, _, _ = assemble(ma, ja, xa, va, oa, mb, jb, xb, vb,
                                                          ob, movable_b, pts[i], nrm[i],
                                                          tangential, m)  # fmt: skip
        g_law, w_law = g, w
        if np.array_equal(tangential > 0, mu[i] > 0):  # solve_impact's rows: the same layout
            own = _solve_impact_space(args, i, movable_b, pts[i], nrm[i], e[i], mu[i])
            if own is not None:
                g_law, w_law = own
        imp, wa, regime[i], active[i], flags[i], residual[i] = _reference(
            g_law, w_law, nrow, ntan, e[i], mu[i])
        finish(ma, ja, va, oa, mb, jb, vb, ob, movable_b, axes, tangential, jac_a, jac_b,
               inv_a, inv_b, np.asarray(imp, dtype=float), w, np.asarray(wa, dtype=float),
               floats[i])  # fmt: skip


def _solve_impact_space(args: list[np.ndarray], i: int, movable_b: bool, pts: np.ndarray,
                        nrm: np.ndarray, e: np.ndarray,
                        mu: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:  # fmt: skip
    """``G`` and ``w'`` of impact ``i`` as :func:`carnot.solve_impact` assembles them (its
    contact space, the same operations), or ``None`` where its bodies refuse the inputs.

    Bit for bit, because the law's answer can depend on the last bit of ``G``: on an
    ill-conditioned 3D slip system the root iteration converges or not, to one root or
    another, with ``G`` changed by 4e-16 (a box landing on a tilted ground, issue 14), and
    the batch's rows must be ``solve_impact``'s answers."""
    from carnot.model.bodies import FixedBody, RigidBody
    from carnot.model.contacts import Item, PointContact
    from carnot.model.free_bodies import assemble
    from carnot.model.problem import ImpactProblem

    ma, ja, xa, va, oa, mb, jb, xb, vb, ob = (arr[i] for arr in args)
    try:
        bodies: dict[str, Any] = {"a": RigidBody(name="a", mass=float(ma), inertia_com=ja,
                                                 position_com=xa, velocity_com=va,
                                                 angular_velocity=oa)}  # fmt: skip
        bodies["b"] = (RigidBody(name="b", mass=float(mb), inertia_com=jb, position_com=xb,
                                 velocity_com=vb, angular_velocity=ob)
                       if movable_b else FixedBody(name="b"))  # fmt: skip
        contacts = [PointContact(a="a", b="b", point=p, normal=n, restitution=float(ec),
                                 friction=float(mc), where=f"contacts[{k}]")
                    for k, (p, n, ec, mc)
                    in enumerate(zip(pts, nrm, e, mu, strict=True))]  # fmt: skip
        problem = ImpactProblem(bodies=bodies, contacts=contacts)
    except InputError:
        return None
    items: list[Item] = [*problem.contacts, *problem.constraints]
    space = assemble(problem, items, [item.rows() for item in items]).space
    # (as carnot.several's _solve_group: the group's rows, the velocities after no given
    # impulse)
    rows = np.array([r for index in range(len(items))
                     for r in range(space.slices[index].start, space.slices[index].stop)],
                    dtype=int)  # fmt: skip
    u_given = space.u_before + space.velocity_change(np.zeros(space.size))
    return space.delassus(rows), space.row_velocities(u_given, rows)


def _multi_result(floats: np.ndarray, regime: np.ndarray, active: np.ndarray,
                  flags: np.ndarray, residual: np.ndarray, by_reference: np.ndarray,
                  shape: tuple[int, ...], k: int, fixed: bool) -> MultiImpacts:  # fmt: skip
    def vec(col: int) -> np.ndarray:
        return floats[:, col : col + 3].reshape(shape + (3,))

    def scalar(col: int) -> np.ndarray:
        return floats[:, col].reshape(shape)

    base = 17
    before, after = scalar(12), scalar(13)
    bits = {name: ((flags & bit) != 0).reshape(shape) for name, bit in FLAG_BITS}
    return MultiImpacts(
        impulse=floats[:, base : base + 3 * k].reshape(shape + (k, 3)),
        normal_impulse=floats[:, base + 3 * k : base + 4 * k].reshape(shape + (k,)),
        dissipated_by_contact=floats[:, base + 4 * k : base + 5 * k].reshape(shape + (k,)),
        regime=regime.reshape(shape + (k,)), active=active.reshape(shape + (k,)),
        velocity_a=vec(0), angular_velocity_a=vec(3),
        velocity_b=None if fixed else vec(6), angular_velocity_b=None if fixed else vec(9),
        before=before, after=after, dissipated=scalar(14), dissipated_theorem=scalar(15),
        lost_velocities=scalar(16),
        residual=residual.reshape(shape),
        energy_gain=(after - before > FLAG_SLACK * before),
        uniqueness_verified=((flags & _UNVERIFIED) == 0).reshape(shape),
        by_reference=by_reference.reshape(shape), **bits,
    )  # fmt: skip

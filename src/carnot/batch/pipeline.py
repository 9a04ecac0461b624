"""One point impact end to end, for a batch: assemble, apply the law, update, keep the ledger.

Written once for :mod:`carnot.batch.ops`: :func:`impact` is the function of one impact
(scalars, compiled by Numba) or of a whole batch (arrays). Its steps follow the
spine of DESIGN.md section 1 for one point contact:

1. the inertia factors of ``a`` and ``b`` (:mod:`carnot.batch.rigid`) and the contact frame,
   ``K`` and ``w'`` (:mod:`carnot.batch.contact_space`);
2. the law, in contact space: ``P`` (:mod:`carnot.batch.laws`, :mod:`carnot.batch.coulomb`);
3. the velocities after (paper eq. 4): ``v'' = v' + P / m``, ``omega'' = omega' + J_C^-1
   (r x P)`` for ``a``, the same with ``-P`` for ``b``;
4. the ledger: ``E'``, ``E''`` by Koenig's formula (paper eq. 5), ``E_d = E' - E''``
   (direct), the theorem ``-1/2 P . (w' + w'')`` (paper eq. 11 and 16) split into its normal
   and tangential parts, Carnot's ``E_p = 1/2 P . K P`` (paper eq. 13), and the flags.

The outputs are two flat tuples, floats and small integers, in the order of
:data:`FLOAT_FIELDS` and :data:`INT_FIELDS` (name, width).
"""

from __future__ import annotations

from typing import Any

from carnot.batch.contact_space import frame, inverse_mass, k_times, lever_columns, to_world
from carnot.batch.laws import STICK, frictionless
from carnot.batch.ops import as_float, formula, select, sqrt
from carnot.batch.rigid import dot, factor, kinetic_energy, point_velocity, upper_solve

#: The contact law the pipeline applies (rebound per law by carnot.batch.ops.specialize).
law = frictionless

#: Float outputs of one impact, in order: (name, width).
FLOAT_FIELDS: tuple[tuple[str, int], ...] = (
    ("impulse", 3), ("normal_impulse", 1), ("velocity_a", 3), ("angular_velocity_a", 3),
    ("velocity_b", 3), ("angular_velocity_b", 3), ("relative_velocity_before", 3),
    ("relative_velocity_after", 3), ("before", 1), ("after", 1), ("dissipated", 1),
    ("dissipated_theorem", 1), ("dissipated_normal", 1), ("dissipated_tangential", 1),
    ("lost_velocities", 1), ("friction_required", 1), ("compression_impulse", 1),
    ("work_normal_compression", 1), ("work_normal_restitution", 1),
    ("work_tangential_compression", 1), ("work_tangential_restitution", 1),
)  # fmt: skip
#: Integer outputs (int8): the regime code, the flags, the law's flag bits, and whether the
#: inertia tensors were valid (checked in the kernel, where they are read anyway).
INT_FIELDS: tuple[tuple[str, int], ...] = (
    ("regime", 1), ("not_approaching", 1), ("negative_normal_impulse", 1),
    ("friction_insufficient", 1), ("energy_gain", 1), ("law_flags", 1),
    ("invalid_inertia_a", 1), ("invalid_inertia_b", 1), ("invalid_input", 1),
)  # fmt: skip
FLOAT_WIDTH = sum(w for _, w in FLOAT_FIELDS)
INT_WIDTH = sum(w for _, w in INT_FIELDS)

#: Relative slack of the flags: a negative normal impulse below ``1e-12 |P|``, an energy gain
#: below ``1e-12 E'`` and a friction excess below ``1e-12 mu`` are round-off.
FLAG_SLACK = 1e-12
NAN = float("nan")


@formula
def _sum3(v: Any) -> Any:
    return (v[0] + v[1]) + v[2]


@formula
def _sum9(j: Any) -> Any:
    return (((j[0] + j[1]) + (j[2] + j[3])) + ((j[4] + j[5]) + (j[6] + j[7]))) + j[8]


@formula
def impact(mass_a: Any, inertia_a: Any, x_a: Any, v_a: Any, omega_a: Any,
           mass_b: Any, inertia_b: Any, x_b: Any, v_b: Any, omega_b: Any,
           movable_b: Any, point: Any, normal: Any, e: Any, mu: Any) -> Any:  # fmt: skip
    """One impact (or one batch) under the contact law bound to ``law``.

    Arguments: for ``a`` then ``b``, mass (kg), inertia about the centre of mass (the nine
    world entries, kg m^2), centre-of-mass position (m), velocity (m/s), angular velocity
    (rad/s); ``movable_b`` (1 for a body, 0 for a fixed obstacle, which is passed as mass 1,
    unit inertia, position ``point`` and zero velocities); the contact point (m), the normal
    from ``b`` into ``a`` (any length), ``e`` and ``mu``. Vectors are tuples. Returns the
    tuples of :data:`FLOAT_FIELDS` and :data:`INT_FIELDS` values.

    A ball of 1 kg with J = 0.004 I falling at 2 m/s onto a floor, e = 0.5:

    >>> eye = (0.004, 0, 0, 0, 0.004, 0, 0, 0, 0.004)
    >>> floats, ints = impact(1.0, eye, (0, 0, 0.1), (0, 0, -2.0), (0, 0, 0),
    ...                       1.0, (1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0), (0, 0, 0), (0, 0, 0),
    ...                       (0, 0, 0), 0.0, (0, 0, 0), (0, 0, 1.0), 0.5, 0.0)
    >>> [float(x) for x in floats[:4]], float(floats[24])    # P (N s), P_n, E_d (J)
    ([0.0, 0.0, 3.0, 3.0], 1.5)
    """
    geo = geometry(mass_a, inertia_a, x_a, v_a, omega_a, mass_b, inertia_b, x_b, v_b,
                   omega_b, movable_b, point, normal)  # fmt: skip
    return finish(mass_a, inertia_a, x_a, v_a, omega_a, mass_b, inertia_b, x_b, v_b, omega_b,
                  movable_b, point, normal, e, mu, geo, law(geo[9], geo[11], e, mu))  # fmt: skip


@formula
def geometry(mass_a: Any, inertia_a: Any, x_a: Any, v_a: Any, omega_a: Any,
             mass_b: Any, inertia_b: Any, x_b: Any, v_b: Any, omega_b: Any,
             movable_b: Any, point: Any, normal: Any) -> Any:  # fmt: skip
    """Step 1 (the arguments of :func:`impact` but the law's): the inertia factors and
    their validity, the contact frame, the inverse masses, the lever columns, ``K`` and the
    relative velocity before, world and contact frame: ``(l_a, ok_a, l_b, ok_b, (n, t1,
    t2), 1/m_a, movable_b/m_b, c_a, c_b, k, w', w'_c)`` (``k`` is entry 9, ``w'_c`` 11)."""
    l_a, ok_a = factor(inertia_a)
    l_b, ok_b = factor(inertia_b)
    return factored_geometry(l_a, ok_a, l_b, ok_b, mass_a, x_a, v_a, omega_a, mass_b, x_b, v_b,
                             omega_b, movable_b, point, normal)  # fmt: skip


@formula
def factored_geometry(l_a: Any, ok_a: Any, l_b: Any, ok_b: Any, mass_a: Any, x_a: Any,
                      v_a: Any, omega_a: Any, mass_b: Any, x_b: Any, v_b: Any, omega_b: Any,
                      movable_b: Any, point: Any, normal: Any) -> Any:  # fmt: skip
    """:func:`geometry` from the inertia factors ``(L, ok)`` of ``a`` and ``b``
    (:func:`carnot.batch.rigid.factor`), which a caller solving one impact of the same
    bodies again can keep (:mod:`carnot.single`)."""
    n, t1, t2 = frame(normal)
    r_a = (point[0] - x_a[0], point[1] - x_a[1], point[2] - x_a[2])
    r_b = (point[0] - x_b[0], point[1] - x_b[1], point[2] - x_b[2])
    inv_mass_a = 1.0 / mass_a
    inv_mass_b = movable_b / mass_b
    c_a = lever_columns(l_a, r_a, n, t1, t2)
    c_b = lever_columns(l_b, r_b, n, t1, t2)
    k = inverse_mass(inv_mass_a + inv_mass_b, c_a, c_b)
    u_a = point_velocity(v_a, omega_a, r_a)
    u_b = point_velocity(v_b, omega_b, r_b)
    w1 = (u_a[0] - u_b[0], u_a[1] - u_b[1], u_a[2] - u_b[2])
    w1c = (dot(w1, n), dot(w1, t1), dot(w1, t2))
    return (l_a, ok_a, l_b, ok_b, (n, t1, t2), inv_mass_a, inv_mass_b, c_a, c_b, k, w1,
            w1c)  # fmt: skip


@formula
def finish(mass_a: Any, inertia_a: Any, x_a: Any, v_a: Any, omega_a: Any,
           mass_b: Any, inertia_b: Any, x_b: Any, v_b: Any, omega_b: Any, movable_b: Any,
           point: Any, normal: Any, e: Any, mu: Any, geo: Any, law_out: Any) -> Any:  # fmt: skip
    """Steps 3 and 4: from the arguments of :func:`impact`, their :func:`geometry` and the
    law's answer ``law_out`` (see :mod:`carnot.batch.laws`), the velocities after, the
    ledger (:func:`outcome`) and the flags (:func:`checks`): the tuples of
    :data:`FLOAT_FIELDS` and :data:`INT_FIELDS`."""
    floats = outcome(mass_a, inertia_a, v_a, omega_a, mass_b, inertia_b, v_b, omega_b,
                     movable_b, geo, law_out)  # fmt: skip
    ints = checks(mass_a, inertia_a, x_a, v_a, omega_a, mass_b, inertia_b, x_b, v_b, omega_b,
                  movable_b, point, normal, e, mu, geo, law_out, floats)  # fmt: skip
    return floats, ints


@formula
def outcome(mass_a: Any, inertia_a: Any, v_a: Any, omega_a: Any, mass_b: Any, inertia_b: Any,
            v_b: Any, omega_b: Any, movable_b: Any, geo: Any, law_out: Any) -> Any:  # fmt: skip
    """The velocities after and the ledger (:func:`finish`'s floats, :data:`FLOAT_FIELDS`)."""
    l_a, ok_a, l_b, ok_b, axes, inv_mass_a, inv_mass_b, c_a, c_b, k, w1, w1c = geo
    n, t1, t2 = axes
    p_n, p_1, p_2, regime, p_c, wnc, wnr, wtc, wtr, law_flags = law_out
    pc = (p_n, p_1, p_2)
    impulse = to_world(pc, n, t1, t2)
    # paper eq. 4: L^-1 (r x P) = sum_i P_i c_i, then J^-1 (r x P) = L^-T of that
    y_a = (p_n * c_a[0][0] + p_1 * c_a[1][0] + p_2 * c_a[2][0],
           p_n * c_a[0][1] + p_1 * c_a[1][1] + p_2 * c_a[2][1],
           p_n * c_a[0][2] + p_1 * c_a[1][2] + p_2 * c_a[2][2])  # fmt: skip
    y_b = (-(p_n * c_b[0][0] + p_1 * c_b[1][0] + p_2 * c_b[2][0]),
           -(p_n * c_b[0][1] + p_1 * c_b[1][1] + p_2 * c_b[2][1]),
           -(p_n * c_b[0][2] + p_1 * c_b[1][2] + p_2 * c_b[2][2]))  # fmt: skip
    dw_a = upper_solve(l_a, y_a)
    dw_b = upper_solve(l_b, y_b)
    v_a2 = (v_a[0] + impulse[0] * inv_mass_a, v_a[1] + impulse[1] * inv_mass_a,
            v_a[2] + impulse[2] * inv_mass_a)  # fmt: skip
    v_b2 = (v_b[0] - impulse[0] * inv_mass_b, v_b[1] - impulse[1] * inv_mass_b,
            v_b[2] - impulse[2] * inv_mass_b)  # fmt: skip
    om_a2 = (omega_a[0] + dw_a[0], omega_a[1] + dw_a[1], omega_a[2] + dw_a[2])
    om_b2 = (omega_b[0] + dw_b[0], omega_b[1] + dw_b[1], omega_b[2] + dw_b[2])
    # the ledger (paper eqs. 5, 11, 13, 16)
    before = (kinetic_energy(mass_a, inertia_a, v_a, omega_a)
              + movable_b * kinetic_energy(mass_b, inertia_b, v_b, omega_b))  # fmt: skip
    after = (kinetic_energy(mass_a, inertia_a, v_a2, om_a2)
             + movable_b * kinetic_energy(mass_b, inertia_b, v_b2, om_b2))  # fmt: skip
    kp = k_times(k, pc)
    w2c = (w1c[0] + kp[0], w1c[1] + kp[1], w1c[2] + kp[2])
    w2 = to_world(w2c, n, t1, t2)
    d_normal = -0.5 * p_n * (w1c[0] + w2c[0])
    d_tangential = -0.5 * (p_1 * (w1c[1] + w2c[1]) + p_2 * (w1c[2] + w2c[2]))
    lost = 0.5 * (p_n * kp[0] + p_1 * kp[1] + p_2 * kp[2])
    dissipated = before - after
    size_t = sqrt(p_1 * p_1 + p_2 * p_2)
    required = select(regime == STICK, size_t / p_n, NAN + 0.0 * p_n)
    return (impulse[0], impulse[1], impulse[2], p_n, v_a2[0], v_a2[1], v_a2[2],
            om_a2[0], om_a2[1], om_a2[2], v_b2[0], v_b2[1], v_b2[2],
            om_b2[0], om_b2[1], om_b2[2], w1[0], w1[1], w1[2], w2[0], w2[1], w2[2],
            before, after, dissipated, d_normal + d_tangential, d_normal, d_tangential,
            lost, required, p_c, wnc, wnr, wtc, wtr)  # fmt: skip


@formula
def checks(mass_a: Any, inertia_a: Any, x_a: Any, v_a: Any, omega_a: Any,
           mass_b: Any, inertia_b: Any, x_b: Any, v_b: Any, omega_b: Any, movable_b: Any,
           point: Any, normal: Any, e: Any, mu: Any, geo: Any, law_out: Any, floats: Any
           ) -> Any:  # fmt: skip
    """The flags of one impact (:data:`INT_FIELDS`) from the arguments of :func:`finish` and
    the floats :func:`outcome` made of them."""
    ok_a, ok_b, w1c = geo[1], geo[3], geo[11]
    p_n, p_1, p_2, regime, law_flags = law_out[0], law_out[1], law_out[2], law_out[3], law_out[9]
    before, dissipated, required = floats[22], floats[24], floats[29]
    size_p = sqrt(p_n * p_n + p_1 * p_1 + p_2 * p_2)
    sticks = regime == STICK
    # NaN (p_n = 0) counts as insufficient (required != required): no finite mu sticks it
    insufficient = (sticks & (mu > 0)
                    & ((required > mu * (1.0 + FLAG_SLACK)) | (required != required)))  # fmt: skip
    # the inputs' bounds, checked here where they are read anyway (the caller names the
    # field when a row fails): a sum is non-finite when any term is (or when it overflows,
    # which the caller's closer look then clears)
    # summed as a shallow tree: a chain of 44 additions would cost more than the impact
    total = ((((mass_a + mass_b) + (e + mu)) + (_sum3(point) + _sum3(normal)))
             + ((_sum3(x_a) + _sum3(v_a)) + (_sum3(omega_a) + _sum3(x_b)))
             + ((_sum3(v_b) + _sum3(omega_b)) + (_sum9(inertia_a) + _sum9(inertia_b))))
    in_bounds = ((total - total == 0.0) & (mass_a > 0) & (mass_b > 0) & (e >= 0) & (e <= 1)
                 & (mu >= 0) & (dot(normal, normal) > 0))  # fmt: skip
    ints = (as_float(regime), as_float(w1c[0] >= 0), as_float(p_n < -FLAG_SLACK * size_p),
            as_float(insufficient), as_float(dissipated < -FLAG_SLACK * before),
            as_float(law_flags), as_float(ok_a ^ True),
            as_float(ok_b ^ True), as_float(in_bounds ^ True))  # fmt: skip
    # (x ^ True is "not x" for arrays and scalars alike)
    return ints

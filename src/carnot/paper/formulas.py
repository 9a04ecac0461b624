"""The closed-form formulas printed in the paper's section 3, transcribed as printed.

One transcription, in SymPy, serves both audits: the numeric one (``carnot paper``) evaluates
it over grids of solved impacts, the symbolic one (``carnot paper --symbolic``) compares it
with the closed forms derived from the symbolic models. Every formula is an equation
``printed = reference``: ``printed`` is the paper's side, as printed; ``reference`` the
quantity it claims to give, written with the symbols of the quantities that the solver (or the
derivation) supplies. Equations of motion that the paper prints (its "collision equations")
are transcribed the same way, both sides as printed.

The paper's symbols, in plain names: ``v'_O`` the speed of the point ``O`` before, ``omega'``
and ``omega''`` the angular velocities before and after, ``P_n``, ``P_t`` the impulse's
components, and so on. The axes used to rebuild each figure are stated in
:mod:`carnot.paper.examples`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, TypeAlias

import sympy as sp

from carnot.symbolic.dimensions import (
    ANGULAR_VELOCITY,
    ENERGY,
    IMPULSE,
    INERTIA,
    LENGTH,
    MASS,
    MOMENT_IMPULSE,
    VELOCITY,
    Dimension,
)

#: A SymPy expression or a 3x1 matrix of them.
Expr: TypeAlias = Any


def _vec(name: str) -> sp.Matrix:
    return sp.Matrix([sp.Symbol(f"{name}_{axis}", real=True) for axis in "xyz"])


# Parameters ---------------------------------------------------------------------------------
m = sp.Symbol("m", positive=True)
r = sp.Symbol("r", positive=True)
v = sp.Symbol("v'_O", positive=True)
alpha = sp.Symbol("alpha", real=True)
omega1 = sp.Symbol("omega'", real=True)
e = sp.Symbol("e", nonnegative=True)
l_ = sp.Symbol("l", nonnegative=True)
h = sp.Symbol("h", positive=True)
J_O = sp.Symbol("J_O", positive=True)  # the plate's moment of inertia about O (3.3, planar)
OC = _vec("OC")
v_O = _vec("v'_O")
omega1_vec = _vec("omega'")
J_O_xx, J_O_yy, J_O_zz = sp.symbols("J_O_xx J_O_yy J_O_zz", positive=True)
J_O_xy, J_O_xz, J_O_yz = sp.symbols("J_O_xy J_O_xz J_O_yz", real=True)
J_O_tensor = sp.Matrix(
    [[J_O_xx, J_O_xy, J_O_xz], [J_O_xy, J_O_yy, J_O_yz], [J_O_xz, J_O_yz, J_O_zz]]
)

# Quantities the solver (or the derivation) supplies ------------------------------------------
P_n, P_t = sp.symbols("P_n P_t", real=True)
v2_On, v2_Ot = sp.symbols("v''_On v''_Ot", real=True)
omega2 = sp.Symbol("omega''", real=True)
v1_An, v1_At, v2_An, v2_At = sp.symbols("v'_An v'_At v''_An v''_At", real=True)
E_d = sp.Symbol("E_d", real=True)
E_d_theorem = sp.Symbol("E_d(theorem)", real=True)
v1_C, v2_C = sp.symbols("v'_C v''_C", real=True)
P_C_needed = sp.Symbol("P_C(P_O=0)", real=True)
M_PC_needed = sp.Symbol("M_PC(P_O=0)", real=True)
P_O_given = _vec("P_O(printed P_C, M_PC)")
omega2_given = sp.Symbol("omega''(printed P_C, M_PC)", real=True)
omega2_vec = _vec("omega''")
P_vec = _vec("P")

#: The dimension of every symbol above.
DIMENSIONS: dict[sp.Symbol, Dimension] = {
    m: MASS,
    r: LENGTH,
    v: VELOCITY,
    omega1: ANGULAR_VELOCITY,
    l_: LENGTH,
    h: LENGTH,
    J_O: INERTIA,
    P_n: IMPULSE,
    P_t: IMPULSE,
    v2_On: VELOCITY,
    v2_Ot: VELOCITY,
    omega2: ANGULAR_VELOCITY,
    v1_An: VELOCITY,
    v1_At: VELOCITY,
    v2_An: VELOCITY,
    v2_At: VELOCITY,
    E_d: ENERGY,
    E_d_theorem: ENERGY,
    v1_C: VELOCITY,
    v2_C: VELOCITY,
    P_C_needed: IMPULSE,
    M_PC_needed: MOMENT_IMPULSE,
    omega2_given: ANGULAR_VELOCITY,
    **{s: LENGTH for s in OC},
    **{s: VELOCITY for s in v_O},
    **{s: ANGULAR_VELOCITY for s in omega1_vec},
    **{s: ANGULAR_VELOCITY for s in omega2_vec},
    **{s: IMPULSE for s in P_vec},
    **{s: IMPULSE for s in P_O_given},
    **{s: INERTIA for s in J_O_tensor},
}


@dataclass(frozen=True, kw_only=True)
class PrintedFormula:
    """One formula of section 3: ``printed`` (as printed) against ``reference``.

    ``theorem`` (energies only) is the reference with the theorem's ``E_d`` in place of the
    direct difference. ``scale`` is the size a difference is measured against where the
    reference itself can be 0. ``corrected`` is an evident correction, checked and reported
    beside the printed form, never in its place.
    """

    id: str
    example: str
    where: str
    text: str
    printed: Expr
    reference: Expr
    theorem: Expr | None = None
    scale: Expr | None = None
    corrected_text: str | None = None
    corrected: Expr | None = None
    note: str = ""


S31, S32, S33 = "section 3.1", "section 3.2", "section 3.3"

# 3.1: the figure's caption gives J_O = m r^2 / 2.
_J_cyl = m * r**2 / 2
# 3.2: the printed impulses, P_C and then M_PC in its second form.
_P_C = sp.Rational(1, 2) * m * omega1 * (1 + e) * (2 * l_ + h)
_M_PC = sp.Rational(1, 12) * m * omega1 * (1 + e) * h**2
_J_O_inv_OC_x_v = J_O_tensor.inv() * OC.cross(v_O)

#: Short names for long sub-expressions, used when printing differences:
#: k = [J]_O^-1 (OC x v'_O).
ABBREVIATIONS: dict[sp.Basic, sp.Symbol] = {
    entry: sp.Symbol(f"k_{axis}", real=True)
    for entry, axis in zip(_J_O_inv_OC_x_v, "xyz", strict=True)
}
ABBREVIATION_TEXT = "k = [J]_O^-1 (OC x v'_O)"

FORMULAS: tuple[PrintedFormula, ...] = (
    # ---- 3.1 -----------------------------------------------------------------------------------
    PrintedFormula(
        id="3.1/v'_An", example="3.1", where=f"{S31}, velocity of the impact point A before",
        text="v'_An = -v'_O cos(alpha)",
        printed=-v * sp.cos(alpha), reference=v1_An,
    ),
    PrintedFormula(
        id="3.1/v'_At", example="3.1", where=f"{S31}, velocity of the impact point A before",
        text="v'_At = v'_O sin(alpha) - r omega'",
        printed=v * sp.sin(alpha) - r * omega1, reference=v1_At, scale=v,
    ),
    PrintedFormula(
        id="3.1/v''_At", example="3.1", where=f"{S31}, velocity of the impact point A after",
        text="v''_At = v''_Ot - r omega'' = 0",
        printed=v2_Ot - r * omega2, reference=sp.S.Zero, scale=v,
    ),
    PrintedFormula(
        id="3.1/eq-normal", example="3.1",
        where=f"{S31}, slipless collision equations (normal momentum)",
        text="m v''_On + m v'_O cos(alpha) = P_n",
        printed=m * v2_On + m * v * sp.cos(alpha), reference=P_n,
    ),
    PrintedFormula(
        id="3.1/eq-tangential", example="3.1",
        where=f"{S31}, slipless collision equations (tangential momentum)",
        text="m v''_Ot - m v'_O sin(alpha) = P_t",
        printed=m * v2_Ot - m * v * sp.sin(alpha), reference=P_t, scale=m * v,
    ),
    PrintedFormula(
        id="3.1/eq-angular", example="3.1",
        where=f"{S31}, slipless collision equations (angular momentum about O)",
        text="J_O (omega'' - v'_O / r) = -r P_t",
        printed=_J_cyl * (omega2 - v / r), reference=-r * P_t, scale=m * v * r,
        corrected_text="J_O (omega'' - omega') = -r P_t",
        corrected=_J_cyl * (omega2 - omega1),
        note="the printed equation has v'_O/r where the angular velocity before, omega', "
        "belongs (both are 1/s, so the dimensions cannot tell); the printed results follow "
        "from the corrected equation",
    ),
    PrintedFormula(
        id="3.1/restitution", example="3.1", where=f"{S31}, slipless collision equations",
        text="e = v''_On / (v'_O cos(alpha))",
        printed=e * v * sp.cos(alpha), reference=v2_On, scale=v,
        note="transcribed multiplied out, e v'_O cos(alpha) = v''_On, to hold at alpha = 90 deg",
    ),
    PrintedFormula(
        id="3.1/P_n", example="3.1", where=f"{S31}, results",
        text="P_n = m v'_O (1 + e) cos(alpha)",
        printed=m * v * (1 + e) * sp.cos(alpha), reference=P_n, scale=m * v,
    ),
    PrintedFormula(
        id="3.1/P_t", example="3.1", where=f"{S31}, results",
        text="P_t = (m/3) (r omega' - v'_O sin(alpha))",
        printed=m / 3 * (r * omega1 - v * sp.sin(alpha)), reference=P_t, scale=m * v,
    ),
    PrintedFormula(
        id="3.1/v''_On", example="3.1", where=f"{S31}, results",
        text="v''_On = e v'_O cos(alpha)",
        printed=e * v * sp.cos(alpha), reference=v2_On, scale=v,
    ),
    PrintedFormula(
        id="3.1/v''_Ot", example="3.1", where=f"{S31}, results",
        text="v''_Ot = (2/3) v'_O sin(alpha) + (1/3) r omega'",
        printed=sp.Rational(2, 3) * v * sp.sin(alpha) + r * omega1 / 3, reference=v2_Ot, scale=v,
    ),
    PrintedFormula(
        id="3.1/omega''", example="3.1", where=f"{S31}, results",
        text="omega'' = (2/3) (v'_O / r) sin(alpha) + (1/3) omega'",
        printed=sp.Rational(2, 3) * v / r * sp.sin(alpha) + omega1 / 3, reference=omega2,
        scale=v / r,
    ),
    PrintedFormula(
        id="3.1/friction", example="3.1", where=f"{S31}, condition against sliding",
        text="mu >= P_t / P_n = (r omega' - v'_O sin(alpha)) / (3 (1 + e) v'_O cos(alpha))",
        printed=(r * omega1 - v * sp.sin(alpha)) / (3 * (1 + e) * v * sp.cos(alpha)),
        reference=P_t / P_n, scale=sp.S.One,
        note="the ratio is signed as printed; the friction needed to stick is its absolute "
        "value |P_t| / P_n (carnot reports that as friction_required)",
    ),
    PrintedFormula(
        id="3.1/E_d-theorem", example="3.1",
        where=f"{S31}, energy dissipated, the theorem's form (eq. 16)",
        text="E_d = -1/2 [P_t (v'_At + v''_At) + P_n (v'_An + v''_An)]",
        printed=-(P_t * (v1_At + v2_At) + P_n * (v1_An + v2_An)) / 2,
        reference=E_d, theorem=E_d_theorem, scale=m * v**2 / 2,
    ),
    PrintedFormula(
        id="3.1/E_d", example="3.1", where=f"{S31}, energy dissipated, closed form",
        text="E_d = (m v'_O^2 / 2) [(1/3) (r omega' / v'_O - sin(alpha))^2 "
        "+ (1 - e^2) cos^2(alpha)]",
        printed=m * v**2 / 2
        * ((r * omega1 / v - sp.sin(alpha)) ** 2 / 3 + (1 - e**2) * sp.cos(alpha) ** 2),
        reference=E_d, theorem=E_d_theorem, scale=m * v**2 / 2,
    ),
    # ---- 3.2 -----------------------------------------------------------------------------------
    PrintedFormula(
        id="3.2/omega''", example="3.2", where=f"{S32}, results from [6]",
        text="omega'' = -e omega'",
        printed=-e * omega1, reference=omega2, scale=omega1,
    ),
    PrintedFormula(
        id="3.2/P_O", example="3.2", where=f"{S32}, results from [6] (the pivot's impulse)",
        text="P_Ot = P_On = 0",
        printed=sp.zeros(3, 1), reference=P_O_given, scale=_P_C,
        note="the split between pivot and plane is statically indeterminate; checked by "
        "applying the printed P_C and M_PC as given impulses with the pivot as a pin: the pin "
        "then needs no impulse",
    ),
    PrintedFormula(
        id="3.2/P_C", example="3.2", where=f"{S32}, results from [6]",
        text="P_C = (1/2) m omega' (1 + e) (2 l + h)",
        printed=_P_C, reference=P_C_needed,
        note="against the plane's impulse that the solved motion needs when the pivot gives "
        "none (P_O = 0, as printed)",
    ),
    PrintedFormula(
        id="3.2/M_PC", example="3.2", where=f"{S32}, results from [6] (first form)",
        text="M_PC = P_C h^2 / (6 (2 l + h))",
        printed=_P_C * h**2 / (6 * (2 * l_ + h)), reference=M_PC_needed,
        note="against the moment the solved motion needs when the pivot gives none",
    ),
    PrintedFormula(
        id="3.2/M_PC-closed", example="3.2", where=f"{S32}, results from [6] (second form)",
        text="M_PC = (1/12) m omega' (1 + e) h^2",
        printed=_M_PC, reference=M_PC_needed,
    ),
    PrintedFormula(
        id="3.2/impulses-motion", example="3.2",
        where=f"{S32}, the printed P_C and M_PC applied as given impulses",
        text="P_C, M_PC as printed => omega'' = -e omega'",
        printed=omega2_given, reference=omega2, scale=omega1,
    ),
    PrintedFormula(
        id="3.2/v'_C", example="3.2", where=f"{S32}, velocity of C before",
        text="v'_C = (1/2) omega' (2 l + h)",
        printed=omega1 * (2 * l_ + h) / 2, reference=v1_C,
    ),
    PrintedFormula(
        id="3.2/v''_C", example="3.2", where=f"{S32}, velocity of C after",
        text="v''_C = -(1/2) e omega' (2 l + h)",
        printed=-e * omega1 * (2 * l_ + h) / 2, reference=v2_C, scale=omega1 * (2 * l_ + h),
    ),
    PrintedFormula(
        id="3.2/E_d-theorem", example="3.2",
        where=f"{S32}, energy dissipated, the theorem's form (eq. 15)",
        text="E_d = (1/2) P (v'_C + v''_C) + (1/2) M (omega' + omega'')",
        printed=_P_C * (v1_C + v2_C) / 2 + _M_PC * (omega1 + omega2) / 2,
        reference=E_d, theorem=E_d_theorem, scale=m * (omega1 * (l_ + h)) ** 2 / 2,
        note="P and M are the printed P_C and M_PC, magnitudes against the motion of C",
    ),
    PrintedFormula(
        id="3.2/E_d", example="3.2", where=f"{S32}, energy dissipated, closed form",
        text="E_d = (1/2) m (1 - e^2) (l^2 + l h + h^2/3) omega'^2",
        printed=m * (1 - e**2) * (l_**2 + l_ * h + h**2 / 3) * omega1**2 / 2,
        reference=E_d, theorem=E_d_theorem, scale=m * (omega1 * (l_ + h)) ** 2 / 2,
    ),
    # ---- 3.3, three dimensions -------------------------------------------------------------------
    PrintedFormula(
        id="3.3/eq-linear", example="3.3-3d", where=f"{S33}, linear momentum equation",
        text="m [omega'' x OC - (v'_O + omega' x OC)] = P",
        printed=m * (omega2_vec.cross(OC) - (v_O + omega1_vec.cross(OC))), reference=P_vec,
    ),
    PrintedFormula(
        id="3.3/eq-angular", example="3.3-3d", where=f"{S33}, angular momentum equation about O",
        text="[J]_O omega'' - ([J]_O omega' + m OC x v'_O) = 0",
        printed=J_O_tensor * omega2_vec - (J_O_tensor * omega1_vec + m * OC.cross(v_O)),
        reference=sp.zeros(3, 1),
        scale=sp.sqrt((J_O_tensor * omega1_vec).dot(J_O_tensor * omega1_vec))
        + m * sp.sqrt(OC.cross(v_O).dot(OC.cross(v_O))),
    ),
    PrintedFormula(
        id="3.3/omega''", example="3.3-3d", where=f"{S33}, result",
        text="omega'' = omega' + m [J]_O^-1 (OC x v'_O)",
        printed=omega1_vec + m * _J_O_inv_OC_x_v, reference=omega2_vec,
    ),
    PrintedFormula(
        id="3.3/P", example="3.3-3d", where=f"{S33}, result",
        text="P = -m v'_O - m OC x [J]_O^-1 (OC x v'_O)",
        printed=-m * v_O - m * OC.cross(_J_O_inv_OC_x_v), reference=P_vec,
        corrected_text="P = -m v'_O - m^2 OC x [J]_O^-1 (OC x v'_O)",
        corrected=-m * v_O - m**2 * OC.cross(_J_O_inv_OC_x_v),
        note="the second term lacks a factor m: as printed it is a velocity, not an impulse; "
        "the paper's own momentum equations (above, which hold) give m^2",
    ),
    PrintedFormula(
        id="3.3/E_d", example="3.3-3d", where=f"{S33}, energy dissipated",
        text="E_d = (1/2) m v'_O^2 + (1/2) m v'_O . [OC x [J]_O^-1 (OC x v'_O)]",
        printed=m * v_O.dot(v_O) / 2 + m * v_O.dot(OC.cross(_J_O_inv_OC_x_v)) / 2,
        reference=E_d, theorem=E_d_theorem, scale=m * v_O.dot(v_O) / 2,
        corrected_text="E_d = (1/2) m v'_O^2 + (1/2) m^2 v'_O . [OC x [J]_O^-1 (OC x v'_O)]",
        corrected=m * v_O.dot(v_O) / 2 + m**2 * v_O.dot(OC.cross(_J_O_inv_OC_x_v)) / 2,
        note="the same missing factor m as in P (E_d = -1/2 P . v'_O by eq. 16): as printed the "
        "second term is a squared velocity; the planar form below, which the paper derives "
        "from this one, has it",
    ),
    # ---- 3.3, in the plane -------------------------------------------------------------------
    PrintedFormula(
        id="3.3/omega''-planar", example="3.3-planar",
        where=f"{S33}, planar motion of a plate (figure 3b)",
        text="omega'' = omega' - m v'_O l sin(alpha) / J_O",
        printed=omega1 - m * v * l_ * sp.sin(alpha) / J_O, reference=omega2,
        scale=sp.Abs(omega1) + v * sp.sqrt(m / J_O),
        note="figure 3b is not in the text we have: alpha is taken counterclockwise from v'_O "
        "to OC (omega counterclockwise); measured the other way the sign of the second term "
        "flips. E_d holds either way (sin^2)",
    ),
    PrintedFormula(
        id="3.3/E_d-planar", example="3.3-planar",
        where=f"{S33}, planar motion of a plate (figure 3b)",
        text="E_d = (1/2) m v'_O^2 (1 - m l^2 sin^2(alpha) / J_O)",
        printed=m * v**2 * (1 - m * l_**2 * sp.sin(alpha) ** 2 / J_O) / 2,
        reference=E_d, theorem=E_d_theorem, scale=m * v**2 / 2,
    ),
)  # fmt: skip

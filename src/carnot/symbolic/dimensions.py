"""Dimensional analysis of formulas: mass, length and time exponents of every term.

A printed formula whose two sides have different dimensions, or a sum whose terms do, is
wrong whatever the numbers; this catches many misprints by itself (a missing factor of a mass
or a length).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction

import sympy as sp


@dataclass(frozen=True)
class Dimension:
    """Exponents of mass, length and time.

    >>> str(Dimension(1, 1, -1))
    'M L T^-1'
    """

    mass: Fraction | int = 0
    length: Fraction | int = 0
    time: Fraction | int = 0

    def __mul__(self, other: Dimension) -> Dimension:
        return Dimension(self.mass + other.mass, self.length + other.length, self.time + other.time)

    def __pow__(self, k: Fraction | int) -> Dimension:
        return Dimension(self.mass * k, self.length * k, self.time * k)

    def __str__(self) -> str:
        parts = []
        for sym, exp in (("M", self.mass), ("L", self.length), ("T", self.time)):
            if exp == 1:
                parts.append(sym)
            elif exp != 0:
                parts.append(f"{sym}^{exp}")
        return " ".join(parts) or "1"


NONE = Dimension()
MASS = Dimension(1, 0, 0)
LENGTH = Dimension(0, 1, 0)
TIME = Dimension(0, 0, 1)
VELOCITY = Dimension(0, 1, -1)
ANGULAR_VELOCITY = Dimension(0, 0, -1)
IMPULSE = Dimension(1, 1, -1)
MOMENT_IMPULSE = Dimension(1, 2, -1)
INERTIA = Dimension(1, 2, 0)
ENERGY = Dimension(1, 2, -2)


class DimensionError(ValueError):
    """Terms of different dimensions added, or a function of a dimensional argument."""


def dimension_of(expr: sp.Basic, dims: Mapping[sp.Symbol, Dimension]) -> Dimension:
    """The dimension of ``expr`` given those of its symbols (unlisted symbols: dimensionless).

    >>> m, v = sp.symbols("m v")
    >>> str(dimension_of(m * v**2 / 2, {m: MASS, v: VELOCITY}))
    'M L^2 T^-2'
    >>> dimension_of(m + v, {m: MASS, v: VELOCITY})
    Traceback (most recent call last):
    ...
    carnot.symbolic.dimensions.DimensionError: m + v adds M to L T^-1
    """
    if isinstance(expr, sp.MatrixBase):
        found = {dimension_of(x, dims) for x in expr if x != 0}
        if len(found) > 1:
            raise DimensionError(f"the components of {expr} have different dimensions")
        return found.pop() if found else NONE
    expr = sp.sympify(expr)
    if expr.is_Symbol:
        return dims.get(expr, NONE)
    if expr.is_number:
        return NONE
    if isinstance(expr, sp.Add):
        terms = [(t, dimension_of(t, dims)) for t in expr.args if t != 0]
        first = terms[0][1]
        for _, d in terms[1:]:
            if d != first:
                raise DimensionError(f"{_short(expr)} adds {first} to {d}")
        return first
    if isinstance(expr, sp.Mul):
        out = NONE
        for factor in expr.args:
            out = out * dimension_of(factor, dims)
        return out
    if isinstance(expr, sp.Pow):
        base, exp = expr.args
        if dimension_of(exp, dims) != NONE:
            raise DimensionError(f"{expr} has a dimensional exponent")
        if not exp.is_number:
            if dimension_of(base, dims) != NONE:
                raise DimensionError(f"{expr}: a symbolic power of a dimensional base")
            return NONE
        return dimension_of(base, dims) ** Fraction(str(sp.Rational(exp)))
    if isinstance(expr, (sp.Abs,)):
        return dimension_of(expr.args[0], dims)
    if isinstance(expr, sp.Function):
        for arg in expr.args:
            if dimension_of(arg, dims) != NONE:
                raise DimensionError(f"{expr} takes a dimensional argument")
        return NONE
    raise DimensionError(f"cannot tell the dimension of {expr}")


def _short(expr: sp.Basic, width: int = 60) -> str:
    text = str(expr)
    return text if len(text) <= width else text[: width - 3] + "..."


def _is_zero(expr: sp.Basic) -> bool:
    if isinstance(expr, sp.MatrixBase):
        return all(x == 0 for x in expr)
    return sp.sympify(expr) == 0


def check_equation(
    lhs: sp.Basic, rhs: sp.Basic, dims: Mapping[sp.Symbol, Dimension]
) -> tuple[bool, str]:
    """Whether both sides are dimensionally consistent and alike; a sentence saying why not.

    >>> m, v, r, j = sp.symbols("m v r J")
    >>> check_equation(m * v, m * v + m * r * v / j, {m: MASS, v: VELOCITY, r: LENGTH, j: INERTIA})
    (False, 'm*v + m*r*v/J adds M L T^-1 to T^-1')
    """
    try:
        left = dimension_of(lhs, dims)
        right = dimension_of(rhs, dims)
    except DimensionError as err:
        return False, str(err)
    if _is_zero(lhs) or _is_zero(rhs):  # 0 has every dimension
        return True, f"both sides {right if _is_zero(lhs) else left}"
    if left != right:
        return False, f"the left side is {left}, the right side {right}"
    return True, f"both sides {left}"

"""Impact maps of systems in generalized coordinates, in closed form, from SymPy's mechanics.

From a ``sympy.physics.mechanics`` system (a ``KanesMethod`` or ``LagrangesMethod`` whose
equations have been formed) and its contact points, carnot derives the same contact-space
problem as the numeric core (DESIGN.md sections 1 and 7) with symbols:

    M(q)        the method's mass matrix (the coefficients of u' or q''),
    J_i(q)      d v_P / d u, the Jacobian of each contact point's velocity in the frame N,
    W           the rows of the contacts: the normal row n^T J (frictionless, restitution e),
                or all of J (a plastic contact that sticks: its velocity ends at zero; rows
                that are identically zero, the out-of-plane row of a planar model, dropped),
    G = W M^-1 W^T,   Lambda = G^-1 (target - W u-),   u+ = u- + M^-1 W^T Lambda,

so that the impact map is ``u+ = A(q) u-`` with ``A = I - M^-1 W^T G^-1 (W - T)`` (``T`` the
target's coefficients: ``-e n^T J`` on a normal row), and the dissipated energy is
``E_d = 1/2 u-^T (M - A^T M A) u-``, equal by the theorem to ``-1/2 Lambda^T W (u- + u+)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp

from carnot.errors import InputError


@dataclass(frozen=True, kw_only=True, eq=False)
class SymContactPoint:
    """A contact point of a SymPy mechanics model: the ``point`` (a ``Point`` whose velocity
    in ``frame`` is known), the ground's ``frame``, the ``normal`` (a ``Vector`` in that frame,
    from the ground into the system; any length) and the rule: ``stick`` (a plastic contact
    whose velocity ends at zero, e = 0) or ``frictionless`` with ``restitution`` e."""

    point: Any
    frame: Any
    normal: Any = None
    rule: str = "stick"
    restitution: Any = 0


@dataclass(frozen=True, kw_only=True, eq=False)
class SymImpactMap:
    """The closed-form impact: ``speeds`` (u), ``mass_matrix`` M(q), the rows ``rows`` (W),
    the map ``matrix`` A (``u+ = A u-``), ``impulses`` Lambda and ``velocity_after`` u+ as
    expressions in u-, and ``dissipated`` E_d and ``dissipated_theorem``."""

    speeds: sp.Matrix
    mass_matrix: sp.Matrix
    rows: sp.Matrix
    matrix: sp.Matrix
    impulses: sp.Matrix
    velocity_after: sp.Matrix
    dissipated: sp.Expr
    dissipated_theorem: sp.Expr


def _speeds(method: Any) -> sp.Matrix:
    """The generalized speeds: a KanesMethod's ``u``, a LagrangesMethod's ``q'``."""
    from sympy.physics.mechanics import KanesMethod, dynamicsymbols

    if isinstance(method, KanesMethod):
        return sp.Matrix(method.u)
    return sp.Matrix(method.q).diff(dynamicsymbols._t)


def point_jacobian(point: Any, frame: Any, speeds: sp.Matrix) -> sp.Matrix:
    """``J = d v_P / d u`` (3 x n) in ``frame``'s axes: the point's velocity is linear in the
    speeds.

    >>> from sympy.physics.mechanics import dynamicsymbols, Point, ReferenceFrame
    >>> x = dynamicsymbols("x"); N = ReferenceFrame("N"); O = Point("O")
    >>> P = O.locatenew("P", x * N.x); P.set_vel(N, x.diff() * N.x)
    >>> point_jacobian(P, N, sp.Matrix([x.diff()]))
    Matrix([
    [1],
    [0],
    [0]])
    """
    v = point.vel(frame).to_matrix(frame)
    return v.jacobian(speeds)


def derive_impact_map(
    method: Any, contacts: Sequence[SymContactPoint], *, simplify: bool = True
) -> SymImpactMap:
    """The impact map and dissipated energy of ``method`` (equations formed) at ``contacts``
    (module docstring).

    A point mass m on a line, x' < 0, hitting a wall at x = 0 with restitution e:

    >>> from sympy.physics.mechanics import (dynamicsymbols, Particle, Point,
    ...     ReferenceFrame, LagrangesMethod, Lagrangian)
    >>> x = dynamicsymbols("x"); m, e = sp.symbols("m e", positive=True)
    >>> N = ReferenceFrame("N"); O = Point("O"); O.set_vel(N, 0)
    >>> P = O.locatenew("P", x * N.x); P.set_vel(N, x.diff() * N.x)
    >>> method = LagrangesMethod(Lagrangian(N, Particle("p", P, m)), [x], frame=N)
    >>> _ = method.form_lagranges_equations()
    >>> out = derive_impact_map(method, [SymContactPoint(point=P, frame=N, normal=N.x,
    ...                                                  rule="frictionless", restitution=e)])
    >>> out.matrix, sp.factor(out.dissipated)
    (Matrix([[-e]]), -m*(e - 1)*(e + 1)*Derivative(x(t), t)**2/2)
    """
    speeds = _speeds(method)
    mass = sp.Matrix(method.mass_matrix)
    n = len(speeds)
    if mass.shape != (n, n):
        raise InputError("method.mass_matrix", f"must be {n} x {n} (one row per speed)",
                         mass.shape)  # fmt: skip
    rows: list[sp.Matrix] = []
    target: list[sp.Matrix] = []
    for k, c in enumerate(contacts):
        jac = point_jacobian(c.point, c.frame, speeds)
        if c.rule == "stick":
            for r in range(3):
                row = sp.simplify(jac[r, :])
                if any(v != 0 for v in row):  # identically zero: moves nothing, dropped
                    rows.append(row)
                    target.append(sp.zeros(1, n))
        elif c.rule == "frictionless":
            if c.normal is None:
                raise InputError(f"contacts[{k}].normal", "is required for a frictionless "
                                 "contact", show_value=False)  # fmt: skip
            unit = c.normal.to_matrix(c.frame)
            unit = unit / sp.sqrt((unit.T * unit)[0, 0])
            row = unit.T * jac
            rows.append(row)
            target.append(-c.restitution * row)
        else:
            raise InputError(f"contacts[{k}].rule", "must be 'stick' or 'frictionless'", c.rule)
    w = sp.Matrix.vstack(*rows)
    t = sp.Matrix.vstack(*target)
    # The algebra in rational functions: sin q_i and cos q_i as plain symbols (the mass
    # matrix first trig-simplified, so that sin^2 + cos^2 has become 1), each stage cancelled;
    # general simplification of a 4 x 4 mass matrix's inverse takes minutes instead.
    trig: dict[Any, sp.Symbol] = {}
    for k, q in enumerate(getattr(method, "q", [])):
        trig[sp.sin(q)] = sp.Symbol(f"_s{k}")
        trig[sp.cos(q)] = sp.Symbol(f"_c{k}")
    back = {v: k for k, v in trig.items()}
    mass_r = mass.applyfunc(sp.trigsimp).xreplace(trig)
    w_r, t_r = w.xreplace(trig), t.xreplace(trig)
    # polynomials throughout: M^-1 = adj(M) / det M, and with G_p = W adj(M) W^T,
    # A = I + adj(M) W^T adj(G_p) (T - W) / det G_p (det M cancels)
    adj_m = mass_r.adjugate().applyfunc(sp.expand)
    m_adj_wt = (adj_m * w_r.T).applyfunc(sp.expand)
    g_p = (w_r * m_adj_wt).applyfunc(sp.expand)
    det_g = sp.factor(g_p.det())
    core = (g_p.adjugate() * (t_r - w_r)).applyfunc(sp.expand)
    coupling = (mass_r.det() * core).applyfunc(sp.expand) / det_g  # Lambda = coupling u-
    matrix = sp.eye(n) + (m_adj_wt * core).applyfunc(sp.expand) / det_g
    if simplify:
        matrix = matrix.applyfunc(sp.factor)
        coupling = coupling.applyfunc(sp.factor)
    matrix, coupling = matrix.xreplace(back), coupling.xreplace(back)
    mass = mass.applyfunc(sp.trigsimp)
    u_after = matrix * speeds
    impulses = coupling * speeds
    dissipated = (speeds.T * (mass - matrix.T * mass * matrix) * speeds)[0, 0] / 2
    theorem = -(impulses.T * w * (speeds + u_after))[0, 0] / 2
    return SymImpactMap(speeds=speeds, mass_matrix=mass, rows=w, matrix=matrix,
                        impulses=impulses, velocity_after=u_after, dissipated=dissipated,
                        dissipated_theorem=theorem)  # fmt: skip


def compass_gait_model() -> tuple[Any, SymContactPoint, dict[str, Any]]:
    """Goswami, Thuilot and Espiau's compass walker (INRIA report 2996, 1996) as a
    ``LagrangesMethod`` in floating coordinates ``(x, y, theta_ns, theta_s)``: a hip mass
    ``m_H`` at ``(x, y)``, each leg a point mass ``m`` at ``b`` from the hip (``a`` from the
    foot, ``l = a + b``), angles from the downward vertical (a leg runs from the hip along
    ``(sin t, -cos t)``); the contact point is the swing foot, which sticks at heel strike.
    Returns the method, the contact and the symbols by name."""
    from sympy.physics.mechanics import (
        LagrangesMethod,
        Lagrangian,
        Particle,
        Point,
        ReferenceFrame,
        dynamicsymbols,
    )

    x, y, th_ns, th_s = dynamicsymbols("x y theta_ns theta_s")
    m, m_h, a, b = sp.symbols("m m_H a b", positive=True)
    frame = ReferenceFrame("N")
    origin = Point("O")
    origin.set_vel(frame, 0)
    hip = origin.locatenew("H", x * frame.x + y * frame.y)
    points = {"hip": hip}
    for name, th, dist in (("leg_ns", th_ns, b), ("leg_s", th_s, b), ("foot_ns", th_ns, a + b)):
        points[name] = hip.locatenew(name, dist * (sp.sin(th) * frame.x - sp.cos(th) * frame.y))
    for p in points.values():
        p.set_vel(frame, p.pos_from(origin).dt(frame))
    particles = [Particle("hip", hip, m_h), Particle("ns", points["leg_ns"], m),
                 Particle("s", points["leg_s"], m)]  # fmt: skip
    method = LagrangesMethod(Lagrangian(frame, *particles), [x, y, th_ns, th_s], frame=frame)
    method.form_lagranges_equations()
    contact = SymContactPoint(point=points["foot_ns"], frame=frame, rule="stick")
    symbols = {"x": x, "y": y, "theta_ns": th_ns, "theta_s": th_s, "m": m, "m_H": m_h,
               "a": a, "b": b}  # fmt: skip
    return method, contact, symbols

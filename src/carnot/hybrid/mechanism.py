"""A planar mechanism given by its masses' positions, compiled once into the numbers a flow
and an impact need (DESIGN.md section 10).

A model is written once, as SymPy expressions: the positions ``p_k`` (m) of its bodies'
centres of mass and their angles ``phi_k`` (rad) in *floating* coordinates ``q_f`` (the hip
or hub free in the plane, every link's angle), the named points that can strike (feet,
spoke tips), and a *chart*: the minimal coordinates ``q`` of the motion between impacts, with
the floating ones as functions of them, ``q_f = chi(q)`` (the stance foot at the origin).
From these alone carnot derives, by differentiation, everything else:

    M(q)     = sum_k m_k J_k^T J_k + I_k a_k^T a_k      J_k = d p_k / d q,  a_k = d phi_k / d q
    h(q, q') = C(q, q') q' + dV/dq + sum_d c_d l_d' dl_d/dq,
               C_ij = sum_l (dM_ij/dq_l - 1/2 dM_jl/dq_i) q'_l
    V(q)     = - sum_k m_k g . p_k + V_s(q)              g the gravity vector (m/s^2; J)

(``V_s`` the springs' stored energy, ``c_d`` and ``l_d`` the dampers' coefficients and
lengths, their power ``sum_d c_d l_d'^2``, W)

so that the flow is ``M q'' + h = 0``, and in floating coordinates the impact's mass matrix
``M_f(q_f)`` and each point's Jacobian ``d p / d q_f`` (3 x n_f, the plane's normal row zero)
for :func:`carnot.solve_impact`. The linearization of the flow (for saltation matrices and
the monodromy) uses ``dq''/dq_j = -M^-1 (dh/dq_j + dM/dq_j q'')`` and
``dq''/dq'_j = -M^-1 dh/dq'_j``: the derivatives are exact (symbolic), not differenced.

One symbolic source gives both charts, so the flow and the impact cannot disagree on a mass
or a length; compiling (``sympy.lambdify`` with common subexpressions) takes a fraction of a
second per model and is done once per model and parameter set. For up to
``SYMBOLIC_SOLVE`` coordinates the flow ``(q', -M^-1 h)`` is one compiled expression (the
solve done symbolically, by LU): the integrator calls it hundreds of times per step, and a
LAPACK call per evaluation would cost more than the physics.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
import sympy as sp

from carnot.errors import InputError


@dataclass(frozen=True, kw_only=True, eq=False)
class Body:
    """A body of a planar mechanism: ``mass`` (kg) at ``position`` (x, y: expressions of the
    floating coordinates, m), with ``inertia`` (kg m^2) about its centre and ``angle``
    (rad, an expression) when it has rotational inertia."""

    mass: Any
    position: tuple[Any, Any]
    inertia: Any = 0
    angle: Any = 0


@dataclass(frozen=True, kw_only=True, eq=False)
class Damper:
    """A linear damper of ``coefficient`` c (N s/m, or N m s where ``length`` is an angle)
    along ``length`` l (an expression of the floating coordinates, m): its force on the
    mechanism is ``Q = -c l' dl/dq`` and its power ``c l'^2`` (W), always taken (Rayleigh's
    dissipation function ``R = c l'^2 / 2``)."""

    coefficient: Any
    length: Any


@dataclass(frozen=True, kw_only=True, eq=False)
class Mechanism:
    """The symbolic model: ``floating`` coordinates (SymPy symbols), ``bodies``, named
    ``points`` (x, y expressions) that can strike, the chart ``coordinates`` (minimal symbols)
    with ``embedding`` (each floating coordinate as an expression of them) and ``gravity``
    (gx, gy), the gravity vector in the model's frame (m/s^2).

    ``rods`` are the feet of massless links: each names the point it is joined to (its
    ``anchor``, a point with mass) and gives the foot's position in the *chart's* coordinates.
    A massless rod pushes only along itself, so at a strike its foot acts on the anchor along
    the rod (from the foot to the anchor) and no floating coordinate carries the rod's
    rotation (which would have no inertia).

    ``potential`` is stored energy beyond gravity's (J, an expression of the floating
    coordinates: a spring ``k (l - l0)^2 / 2``); ``dampers`` take energy as the mechanism
    moves, and the ledger books their work apart (``Compiled.damping_power``)."""

    floating: tuple[sp.Symbol, ...]
    bodies: tuple[Body, ...]
    points: Mapping[str, tuple[Any, Any]]
    coordinates: tuple[sp.Symbol, ...]
    embedding: tuple[Any, ...]
    gravity: tuple[Any, Any]
    rods: Mapping[str, tuple[str, tuple[Any, Any]]] = field(default_factory=dict)
    potential: Any = 0
    dampers: tuple[Damper, ...] = ()


#: Up to this many coordinates, q'' = -M^-1 h is solved symbolically once (LU) and compiled
#: as one expression; beyond, each evaluation solves M numerically.
SYMBOLIC_SOLVE = 3


def _lambdify(args: Sequence[Any], expr: Any) -> Callable[..., Any]:
    return sp.lambdify(args, expr, modules="numpy", cse=True)


def _scalar_fn(args: Sequence[Any], expr: Any) -> Callable[[np.ndarray], float]:
    fn = _lambdify(args, expr)
    return lambda x: float(fn(*x))


def _point_bias(point: sp.Matrix, chart: Mapping[Any, Any], q: sp.Matrix, qd: sp.Matrix
                ) -> sp.Matrix:  # fmt: skip
    """``(d (J_p q') / d q) q'`` of a point in the chart (the part of its acceleration that
    ``q''`` does not give)."""
    return (point.subs(chart).jacobian(q) * qd).jacobian(q) * qd


def _lazy_matrix_fn(args: Sequence[Any], build: Callable[[], sp.Matrix]
                    ) -> Callable[..., np.ndarray]:  # fmt: skip
    """:func:`_matrix_fn` of ``build()``, derived and compiled on the first call: most runs
    never call it, and a sweep compiles a model per row."""
    compiled: list[Callable[..., np.ndarray]] = []

    def call(*values: Any) -> np.ndarray:
        if not compiled:
            compiled.append(_matrix_fn(args, build()))
        return compiled[0](*values)

    return call


def _matrix_fn(args: Sequence[Any], matrix: sp.Matrix) -> Callable[..., np.ndarray]:
    fn = _lambdify(args, matrix)

    def call(*values: Any) -> np.ndarray:
        return np.asarray(fn(*values), dtype=float)

    return call


@dataclass(frozen=True, kw_only=True, eq=False)
class Compiled:
    """The mechanism's numeric functions (each takes and returns NumPy arrays):

    * ``mass(q)`` M (n x n), ``bias(q, qd)`` h (n), ``potential(q)`` V (J);
    * ``acceleration(q, qd)`` q'' = -M^-1 h; ``flow(x)`` (q', q'') of the state x = (q, q');
      ``flow_jacobian(x)`` d flow / d x (2n x 2n);
    * ``embed(q)`` q_f, ``embed_jacobian(q)`` d q_f / d q (n_f x n);
    * ``floating_mass(qf)`` M_f, ``point(name, qf)`` (x, y) and ``point_jacobian(name, qf)``
      (3 x n_f), ``point_in_chart(name, q)``, its Jacobian ``point_chart_jacobian`` and
      ``point_chart_bias(name, x)``, the part of its acceleration not from ``q''``.
    """

    n: int
    n_floating: int
    mass: Callable[[np.ndarray], np.ndarray]
    bias: Callable[[np.ndarray, np.ndarray], np.ndarray]
    potential: Callable[[np.ndarray], float]
    embed: Callable[[np.ndarray], np.ndarray]
    embed_jacobian: Callable[[np.ndarray], np.ndarray]
    floating_mass: Callable[[np.ndarray], np.ndarray]
    _points: Mapping[str, Callable[..., np.ndarray]] = field(repr=False)
    _point_jacobians: Mapping[str, Callable[..., np.ndarray]] = field(repr=False)
    _chart_points: Mapping[str, Callable[..., np.ndarray]] = field(repr=False)
    _chart_point_jacobians: Mapping[str, Callable[..., np.ndarray]] = field(repr=False)
    _chart_point_biases: Mapping[str, Callable[..., np.ndarray]] = field(repr=False)
    _dh_dq: Callable[..., np.ndarray] = field(repr=False)
    _dh_dqd: Callable[..., np.ndarray] = field(repr=False)
    _dm_dq: Callable[..., np.ndarray] = field(repr=False)
    rods: Mapping[str, str] = field(default_factory=dict)

    _flow: Callable[..., Any] | None = field(default=None, repr=False)
    #: ``support(x)``: the ground's force (x, y, N) on the chart's origin where that origin
    #: is the model's only support (a walker's stance foot), ``None`` otherwise.
    support: Callable[[np.ndarray], np.ndarray] | None = field(default=None, repr=False)
    #: ``support_on_floats(*x)``: ``support(x)`` as the list ``[F_x, F_y]``, of the state's
    #: Python floats (the same numbers, no array either way: the lift watch's, at every
    #: step's end), where ``q''`` is in closed form; ``None`` otherwise.
    support_on_floats: Callable[..., list[float]] | None = field(default=None, repr=False)
    #: ``damping_power(x)``: the dampers' power ``sum c l'^2`` (W) at the state x, ``None``
    #: for a mechanism without dampers.
    damping_power: Callable[[np.ndarray], float] | None = field(default=None, repr=False)

    @property
    def nq(self) -> int:
        """The positions' number: ``n`` (the chart's velocities are its coordinates' rates)."""
        return self.n

    def position_rate(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``q' = qd`` itself (a copy)."""
        return np.array(qd, dtype=float)

    def acceleration(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """``q'' = -M(q)^-1 h(q, q')``."""
        if self._flow is not None:  # (Python floats: see flow)
            return np.array(self._flow(*np.asarray(q, dtype=float).tolist(),
                                       *np.asarray(qd, dtype=float).tolist())[self.n :],
                            dtype=float)  # fmt: skip
        return -np.linalg.solve(self.mass(q), self.bias(q, qd))

    def flow(self, x: np.ndarray) -> np.ndarray:
        """``d/dt (q, q') = (q', q'')``."""
        if self._flow is not None:  # one compiled expression: the integrator's inner call
            # (on Python floats: NumPy's scalars made the expression's arithmetic three times
            # slower, for the same IEEE results)
            return np.array(self._flow(*np.asarray(x, dtype=float).tolist()), dtype=float)
        q, qd = x[: self.n], x[self.n :]
        return np.concatenate([qd, self.acceleration(q, qd)])

    @property
    def flow_on_floats(self) -> Callable[..., list[float]] | None:
        """The flow as one compiled expression of the state's Python floats, returning the
        list ``[q', q'']`` (``None`` where ``q''`` is not in closed form): :meth:`flow`
        without its two arrays (0.8 us of its 1.9), for an integrator that takes any
        sequence (:func:`carnot.hybrid.flow.fly`). The same IEEE results as :meth:`flow`.

        >>> from carnot.hybrid.models import named_model
        >>> m = named_model("compass_gait").mechanism
        >>> x = np.array([-0.2, 0.3, 1.1, 0.4])
        >>> m.flow_on_floats(*x.tolist()) == m.flow(x).tolist()
        True
        """
        return self._flow

    def flow_jacobian(self, x: np.ndarray) -> np.ndarray:
        """``[[0, I], [dq''/dq, dq''/dq']]`` with ``dq''/dq_j = -M^-1 (dh/dq_j + dM/dq_j q'')``
        (exact: from the symbolic derivatives)."""
        n = self.n
        q, qd = x[:n], x[n:]
        m = self.mass(q)
        qdd = self.acceleration(q, qd)  # the flow's own q'' (one compiled call, no solve)
        dm = self._dm_dq(*q).reshape(n, n, n)  # [j] = dM/dq_j
        rhs_q = self._dh_dq(*q, *qd).reshape(n, n) + np.einsum("jik,k->ij", dm, qdd)
        out = np.zeros((2 * n, 2 * n))
        out[:n, n:] = np.eye(n)
        # both blocks from one factorization of M: -M^-1 [dh/dq + dM/dq q'' | dh/dq']
        out[n:] = -np.linalg.solve(m, np.hstack([rhs_q, self._dh_dqd(*q, *qd).reshape(n, n)]))
        return out

    @property
    def point_names(self) -> tuple[str, ...]:
        """The names of the points that can strike."""
        return tuple(self._points)

    def point(self, name: str, qf: np.ndarray) -> np.ndarray:
        """The named point's (x, y) in floating coordinates (m)."""
        return self._points[name](*qf).reshape(2)

    def point_jacobian(self, name: str, qf: np.ndarray) -> np.ndarray:
        """``d p / d q_f`` as 3 x n_f (the z row zero: the motion is planar)."""
        jac = np.zeros((3, self.n_floating))
        jac[:2] = self._point_jacobians[name](*qf).reshape(2, self.n_floating)
        return jac

    def rod_foot(self, name: str, q: np.ndarray) -> np.ndarray:
        """A massless rod's foot, (x, y) in the chart's coordinates (m)."""
        return self._chart_points[name](*q).reshape(2)

    def point_in_chart(self, name: str, q: np.ndarray) -> np.ndarray:
        """The named point's (x, y) in the chart's coordinates (m)."""
        return self._chart_points[name](*q).reshape(2)

    def point_chart_jacobian(self, name: str, q: np.ndarray) -> np.ndarray:
        """``d p / d q`` (2 x n)."""
        return self._chart_point_jacobians[name](*q).reshape(2, self.n)

    def point_chart_bias(self, name: str, x: np.ndarray) -> np.ndarray:
        """``(d (J_p q') / d q) q'`` (2, m/s^2) at the state ``x = (q, q')``: the point's
        acceleration is ``J_p q'' + `` this, ``J_p = d p / d q``."""
        return self._chart_point_biases[name](*x).reshape(2)


def compile_mechanism(mech: Mechanism, values: Mapping[sp.Symbol, float]) -> Compiled:
    """Substitute the parameter ``values`` and compile (see the module's formulas).

    >>> th, x, y = sp.symbols("theta x y")
    >>> pend = Mechanism(floating=(x, y, th), coordinates=(th,), embedding=(0, 0, th),
    ...     bodies=(Body(mass=2.0, position=(x + sp.sin(th), y - sp.cos(th))),),
    ...     points={"bob": (x + sp.sin(th), y - sp.cos(th))}, gravity=(0, -9.81))
    >>> c = compile_mechanism(pend, {})
    >>> c.mass(np.array([0.3])).tolist(), round(float(c.acceleration(np.array([0.3]),
    ...     np.array([0.0]))[0]), 9), round(-9.81 * float(np.sin(0.3)), 9)
    ([[2.0]], -2.899053227, -2.899053227)
    """
    subs = dict(values)
    qf = sp.Matrix(mech.floating)
    q = sp.Matrix(mech.coordinates)
    qd = sp.Matrix(sp.symbols(f"qd0:{len(q)}"))
    chart = dict(zip(mech.floating, mech.embedding, strict=True))
    gx, gy = (sp.sympify(v).subs(subs) for v in mech.gravity)

    def expr(e: Any) -> Any:
        return sp.sympify(e).subs(subs)

    mass_f = sp.zeros(len(qf), len(qf))
    mass_q = sp.zeros(len(q), len(q))
    potential = sp.Integer(0)
    moment = sp.zeros(2, 1)  # sum m_k p_k in the chart: the centre of mass times the mass
    total = sp.Integer(0)
    for body in mech.bodies:
        m = expr(body.mass)
        pos = sp.Matrix([expr(body.position[0]), expr(body.position[1])])
        ang = sp.Matrix([expr(body.angle)])
        inertia = expr(body.inertia)
        jf = pos.jacobian(qf)
        af = ang.jacobian(qf)
        mass_f += m * jf.T * jf + inertia * af.T * af
        pos_q = pos.subs(chart)
        jq = pos_q.jacobian(q)
        aq = ang.subs(chart).jacobian(q)
        mass_q += m * jq.T * jq + inertia * aq.T * aq
        potential -= m * (gx * pos_q[0] + gy * pos_q[1])
        moment += m * pos_q
        total += m
    mass_q = mass_q.applyfunc(sp.simplify)
    n = len(q)
    coriolis = sp.zeros(n, 1)
    for i in range(n):
        coriolis[i] = sum(
            (sp.diff(mass_q[i, j], q[k]) - sp.Rational(1, 2) * sp.diff(mass_q[j, k], q[i]))
            * qd[j] * qd[k]
            for j in range(n)
            for k in range(n)
        )
    potential += expr(mech.potential).subs(chart)  # springs: stored energy beyond gravity's
    bias = coriolis + sp.Matrix([sp.diff(potential, s) for s in q])
    power = sp.Integer(0)
    for damper in mech.dampers:  # Q = -c l' dl/dq: h gains c l' dl/dq, the power is c l'^2
        grad = sp.Matrix([expr(damper.length).subs(chart)]).jacobian(q)
        rate = (grad * qd)[0]
        bias += expr(damper.coefficient) * rate * grad.T
        power += expr(damper.coefficient) * rate**2
    embed = sp.Matrix([expr(e) for e in mech.embedding])
    points = {k: sp.Matrix([expr(v[0]), expr(v[1])]) for k, v in mech.points.items()}
    rod_feet = {k: sp.Matrix([expr(v[1][0]), expr(v[1][1])]) for k, v in mech.rods.items()}
    return _compile(q, qd, qf, chart, mass_q, bias, potential, mass_f, embed, points, rod_feet,
                    {k: v[0] for k, v in mech.rods.items()},
                    support=(moment / total, float(total), (float(gx), float(gy))),
                    damping=power if mech.dampers else None)


def _compile(q: sp.Matrix, qd: sp.Matrix, qf: sp.Matrix, chart: Mapping[Any, Any],
             mass_q: sp.Matrix, bias: sp.Matrix, potential: Any, mass_f: sp.Matrix,
             embed: sp.Matrix, points: Mapping[str, sp.Matrix],
             rod_feet: Mapping[str, sp.Matrix], rods: Mapping[str, str],
             support: tuple[sp.Matrix, float, tuple[float, float]] | None = None,
             damping: Any = None) -> Compiled:  # fmt: skip
    """Lambdify the chart's ``M``, ``h``, ``V`` and their derivatives, the embedding, the
    floating mass matrix and the points (one path for every source of a model).

    ``support`` = (the centre of mass in the chart, the total mass, gravity) where the chart's
    origin is the model's only support: the ground's force on it is then
    ``F = m_tot (a_com - g)``, ``a_com = J_c q'' + (d(J_c q')/dq) q'``. ``damping`` is the
    dampers' power (an expression of ``q, q'``, W), ``None`` without dampers."""
    n = len(q)
    dm = sp.Matrix([[sp.diff(mass_q[i, k], q[j]) for i in range(n) for k in range(n)]
                    for j in range(n)])  # fmt: skip
    args_q = list(q)
    args_x = [*q, *qd]
    flow_fn = None
    if n <= SYMBOLIC_SOLVE:  # q'' in closed form: one call per evaluation, no LAPACK
        qdd = mass_q.LUsolve(-bias)
        flow_fn = sp.lambdify(args_x, [*qd, *qdd], modules="math", cse=True)
    mass_fn = _matrix_fn(args_q, mass_q)
    bias_fn = _matrix_fn(args_x, bias)
    support_fn = support_floats = None
    if support is not None:
        com, m_tot, gravity = support
        jc = com.jacobian(q)
        terms_q = sp.Matrix.hstack(jc, (jc * qd).jacobian(q) * qd)
        g_vec = np.array(gravity)
        if flow_fn is not None:  # on Python floats (see Compiled.flow), q'' the flow's own
            accel = sp.Matrix(sp.symbols(f"qdd0:{n}", cls=sp.Dummy))  # F of (q, q', q''): 8 -> 2 us
            force = m_tot * (jc * accel + terms_q[:, n] - sp.Matrix(gravity))
            force_f = sp.lambdify([*args_x, *accel], list(force), modules="math", cse=True)

            def support_floats(*values: float) -> list[float]:
                return force_f(*values, *flow_fn(*values)[n:])

            def support_fn(x: np.ndarray) -> np.ndarray:
                return np.array(support_floats(*np.asarray(x, dtype=float).tolist()))
        else:
            terms = _matrix_fn(args_x, terms_q)

            def support_fn(x: np.ndarray) -> np.ndarray:
                blocks = terms(*np.asarray(x, dtype=float).tolist()).reshape(2, n + 1)
                qdd = -np.linalg.solve(mass_fn(*x[:n]), bias_fn(*x).reshape(n))
                return m_tot * (blocks[:, :n] @ qdd + blocks[:, n] - g_vec)
    pot_fn = _lambdify(args_q, potential)
    embed_fn = _matrix_fn(args_q, embed)
    embed_jac = _matrix_fn(args_q, embed.jacobian(q))
    mass_f_fn = _matrix_fn(list(qf), mass_f)
    return Compiled(
        n=n,
        n_floating=len(qf),
        mass=lambda v: mass_fn(*v),
        bias=lambda v, w: bias_fn(*v, *w).reshape(n),
        potential=lambda v: float(pot_fn(*v)),
        embed=lambda v: embed_fn(*v).reshape(len(qf)),
        embed_jacobian=lambda v: embed_jac(*v).reshape(len(qf), n),
        floating_mass=lambda v: mass_f_fn(*v),
        _points={k: _matrix_fn(list(qf), p) for k, p in points.items()},
        _point_jacobians={k: _matrix_fn(list(qf), p.jacobian(qf)) for k, p in points.items()},
        _chart_points={**{k: _matrix_fn(args_q, p.subs(chart)) for k, p in points.items()},
                       **{k: _matrix_fn(args_q, p) for k, p in rod_feet.items()}},
        _chart_point_jacobians={
            k: _matrix_fn(args_q, p.subs(chart).jacobian(q)) for k, p in points.items()
        },
        _chart_point_biases={  # (only a held contact asks for them: compiled on first use)
            k: _lazy_matrix_fn(args_x, partial(_point_bias, p, chart, q, qd))
            for k, p in points.items()
        },
        _dh_dq=_matrix_fn(args_x, bias.jacobian(q)),
        _dh_dqd=_matrix_fn(args_x, bias.jacobian(qd)),
        _dm_dq=_matrix_fn(args_q, dm),
        rods=dict(rods),
        _flow=flow_fn,
        support=support_fn,
        support_on_floats=support_floats,
        damping_power=None if damping is None else _scalar_fn(args_x, damping),
    )


def compile_mechanics(method: Any, *, potential: Any, points: Mapping[str, Any],
                      frame: Any, origin: Any, values: Mapping[Any, float] | None = None
                      ) -> Compiled:  # fmt: skip
    """A fixed-base planar model from ``sympy.physics.mechanics``, compiled once: a
    ``LagrangesMethod`` (``M q'' = f``) or a ``KanesMethod`` whose speeds are the coordinates'
    rates (``u = q'``), its equations formed; ``h = -f``. ``potential`` V(q) (J) gives the
    ledger's energy ``E = T + V``; ``points`` (name -> ``Point``) are where the model can
    strike, located from ``origin`` in ``frame`` (x, y: the plane of motion); ``values``
    substitutes parameters. The chart is the model's own coordinates (no floating base).

    >>> from sympy.physics.mechanics import (LagrangesMethod, Lagrangian, Particle, Point,
    ...     ReferenceFrame, dynamicsymbols)
    >>> th = dynamicsymbols("th")
    >>> N, O = ReferenceFrame("N"), Point("O")
    >>> O.set_vel(N, 0)
    >>> bob = O.locatenew("B", sp.sin(th) * N.x - sp.cos(th) * N.y)
    >>> bob.set_vel(N, bob.pos_from(O).dt(N))
    >>> part = Particle("p", bob, 2.0)
    >>> part.potential_energy = 2.0 * 9.81 * bob.pos_from(O).dot(N.y)
    >>> lm = LagrangesMethod(Lagrangian(N, part), [th])
    >>> _ = lm.form_lagranges_equations()
    >>> c = compile_mechanics(lm, potential=part.potential_energy, points={"bob": bob},
    ...                       frame=N, origin=O)
    >>> c.mass(np.array([0.3])).tolist(), round(float(c.acceleration(np.array([0.3]),
    ...     np.array([0.0]))[0]), 9)
    ([[2.0]], -2.899053227)
    """
    from sympy.physics.mechanics import KanesMethod, LagrangesMethod, dynamicsymbols

    subs = dict(values or {})
    t = dynamicsymbols._t
    if isinstance(method, LagrangesMethod):
        coords = list(method.q)
        rates = [c.diff(t) for c in coords]
        mass, forcing = method.mass_matrix, method.forcing
    elif isinstance(method, KanesMethod):
        coords, rates = list(method.q), list(method.u)
        kin = method.kindiffdict()
        if any(sp.simplify(kin[c.diff(t)] - u) != 0 for c, u in zip(coords, rates, strict=True)):
            raise InputError("method", "a KanesMethod's speeds must be its coordinates' rates "
                             "(u_i = q_i')", show_value=False)  # fmt: skip
        mass, forcing = method.mass_matrix, method.forcing
    else:
        raise InputError("method", "must be a sympy.physics.mechanics LagrangesMethod or "
                         "KanesMethod with its equations formed", type(method).__name__)
    n = len(coords)
    q = sp.Matrix(sp.symbols(f"q0:{n}"))
    qd = sp.Matrix(sp.symbols(f"qd0:{n}"))
    plain = {**{r: qd[k] for k, r in enumerate(rates)}, **{c: q[k] for k, c in enumerate(coords)}}
    if isinstance(method, KanesMethod):  # u's derivatives never appear in M and f
        plain.update({c.diff(t): qd[k] for k, c in enumerate(coords)})

    def plainly(e: Any) -> Any:
        return sp.sympify(e).subs(subs).subs(plain)

    mass_q = sp.Matrix(mass).applyfunc(plainly)
    bias = -sp.Matrix(forcing).applyfunc(plainly)
    pot = plainly(potential)
    pts = {}
    for name, point in points.items():
        r = point.pos_from(origin)
        pts[name] = sp.Matrix([plainly(r.dot(frame.x)), plainly(r.dot(frame.y))])
    for name, e in (("mass_matrix", mass_q), ("forcing", bias)):
        stray = sp.Matrix(e).free_symbols - set(q) - set(qd)
        if stray:
            raise InputError("values", f"must give every parameter of the method's {name}",
                             sorted(map(str, stray)))  # fmt: skip
    return _compile(q, qd, q, {}, mass_q, bias, pot, mass_q, sp.Matrix(list(q)), pts, {}, {})

"""Closed-form impact results: the numeric core's formulation, in SymPy.

    u'' = u' + M^-1 W^T Lambda,    G Lambda = target(w') - W u_g,    G = W M^-1 W^T

with the same rows (contacts.py), the same laws (Newton's restitution, stick, fasten, pin, a
given impulse) and the same choice for redundant rows: the minimum-norm ``Lambda``. Which rows
are redundant is decided exactly at a random rational point (a rank that drops only on special
parameter values is treated as full, as it is for almost every value).

A contact in a slip regime of Coulomb's law (``SymContact.slip = d``) keeps its normal row
``n . w`` but its impulse acts along ``n - mu d``: ``u'' = u' + M^-1 W_act^T Lambda`` and
``G = W M^-1 W_act^T``, no longer symmetric (Glocker, *Set-Valued Force Laws*, 2001, ch. 7).
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass

import sympy as sp

from carnot.errors import InputError
from carnot.symbolic.model import SymConstraint, SymContact, SymProblem, SymRigidBody

Simplifier = Callable[[sp.Expr], sp.Expr]


class SingularRegime(InputError):
    """A slip regime with no unique closed form (see :func:`derive_impact`)."""


def simplify_expr(expr: sp.Expr) -> sp.Expr:
    """A compact form: cancel to one fraction, then factor (fast and canonical enough for
    impact formulas, where ``simplify`` is often slow).

    >>> a, b = sp.symbols("a b", positive=True)
    >>> simplify_expr((a**2 - b**2) / (a + b))
    a - b
    """
    expr = sp.sympify(expr)
    if expr.is_number:
        return sp.nsimplify(expr) if expr.has(sp.Float) else expr
    out = sp.factor(sp.cancel(sp.together(expr)))
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class SymItemOutcome:
    """One contact or constraint: its impulse ``P`` and moment ``M_P`` (received by ``a``),
    the relative velocities at its point, and its term of the theorem."""

    where: str
    impulse: sp.Matrix
    moment: sp.Matrix
    normal_impulse: sp.Expr | None
    friction_required: sp.Expr | None
    relative_velocity_before: sp.Matrix
    relative_velocity_after: sp.Matrix
    dissipated: sp.Expr


@dataclass(frozen=True, kw_only=True, eq=False)
class SymbolicResult:
    """Closed forms of everything the numeric solver reports."""

    bodies: dict[str, tuple[sp.Matrix, sp.Matrix]]  # name -> (velocity, angular velocity) after
    contacts: tuple[SymItemOutcome, ...]
    constraints: tuple[SymItemOutcome, ...]
    energy_before: sp.Expr
    energy_after: sp.Expr
    dissipated: sp.Expr
    dissipated_theorem: sp.Expr
    lost_velocities: sp.Expr
    redundant: bool

    def expressions(self) -> dict[str, sp.Expr]:
        """Every scalar result by a dotted name (``bodies.A.velocity.0``, ``energy.dissipated``,
        ``contacts.0.impulse.1``, ...), in the layout of result format 1."""
        out: dict[str, sp.Expr] = {}
        for name, (v, w) in self.bodies.items():
            for i in range(3):
                out[f"bodies.{name}.velocity.{i}"] = v[i]
            for i in range(3):
                out[f"bodies.{name}.angular_velocity.{i}"] = w[i]
        for group, items in (("contacts", self.contacts), ("constraints", self.constraints)):
            for k, item in enumerate(items):
                for i in range(3):
                    out[f"{group}.{k}.impulse.{i}"] = item.impulse[i]
                for i in range(3):
                    out[f"{group}.{k}.moment.{i}"] = item.moment[i]
                if item.normal_impulse is not None:
                    out[f"{group}.{k}.normal_impulse"] = item.normal_impulse
                if item.friction_required is not None:
                    out[f"{group}.{k}.friction_required"] = item.friction_required
                out[f"{group}.{k}.dissipated"] = item.dissipated
        out["energy.before"] = self.energy_before
        out["energy.after"] = self.energy_after
        out["energy.dissipated"] = self.dissipated
        out["energy.dissipated_theorem"] = self.dissipated_theorem
        out["energy.lost_velocities"] = self.lost_velocities
        return out


def exact_contact_frame(normal: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
    """``(t1, t2)`` by the rule of :func:`carnot.conventions.contact_frame`, exactly, for a
    normal with numeric components."""
    n = normal / sp.sqrt(normal.dot(normal))
    mags = [abs(float(c)) for c in n]
    axis = sp.zeros(3, 1)
    axis[mags.index(min(mags))] = 1
    t1 = axis - axis.dot(n) * n
    t1 = (t1 / sp.sqrt(t1.dot(t1))).applyfunc(sp.radsimp)
    return t1, n.cross(t1).applyfunc(sp.radsimp)


def _impulse_rows(item: SymContact | SymConstraint, rows: sp.Matrix) -> sp.Matrix:
    """The directions the item's row impulses act along: its rows, but for a contact in a
    slip regime, whose one row measures ``n . w`` and whose impulse acts along ``n - mu d``."""
    if isinstance(item, SymContact) and item.slip is not None:
        return sp.Matrix.vstack(item.normal - item.friction * item.slip, sp.zeros(3, 1)).T
    return rows


def _rows(item: SymContact | SymConstraint) -> tuple[sp.Matrix, list[str]]:
    """The item's rows ``[c_lin, c_ang]`` (k x 6) and their roles (see contacts.py)."""
    if isinstance(item, SymConstraint):
        return sp.Matrix.hstack(sp.eye(3), sp.zeros(3, 3)), ["bilateral"] * 3
    n = item.normal
    if item.is_given:
        return sp.eye(6), ["given"] * 6
    sticks = item.tangential == "stick"
    if sticks:
        t1, t2 = item.tangents if item.tangents is not None else exact_contact_frame(n)
        tangents = [sp.Matrix(t1).reshape(3, 1), sp.Matrix(t2).reshape(3, 1)]
    if item.patch is None:
        normal_rows = [sp.Matrix.vstack(n, sp.zeros(3, 1)).T]
        tangent_rows = [sp.Matrix.vstack(t, sp.zeros(3, 1)).T for t in tangents] if sticks else []
    else:
        offsets = [p - item.point for p in item.patch]
        normal_rows = sp.Matrix.vstack(
            *[sp.Matrix.vstack(n, r.cross(n)).T for r in offsets]
        ).rowspace()
        tangent_rows = (
            sp.Matrix.vstack(
                *[sp.Matrix.vstack(t, r.cross(t)).T for r in offsets for t in tangents]
            ).rowspace()
            if sticks
            else []
        )
    rows = sp.Matrix.vstack(*normal_rows, *tangent_rows)
    return rows, ["normal"] * len(normal_rows) + ["tangent"] * len(tangent_rows)


def _split_metric(blocks: list) -> sp.Matrix:
    """``Q = diag_i(C_i S_i C_i^T)`` with ``S_i = diag(1, 1, 1, 1/L^2, 1/L^2, 1/L^2)``: the
    metric ``sum |P|^2 + |M_P|^2 / L^2`` on the row impulses (``L^2`` the mean squared
    distance of a patch's points from its contact point, 1 for other items)."""
    parts = []
    for item, _, _, rows, _, _ in blocks:
        length2 = sp.S.One
        if isinstance(item, SymContact) and item.patch is not None:
            length2 = sp.cancel(
                sum(((p - item.point).dot(p - item.point) for p in item.patch), sp.S.Zero)
                / len(item.patch)
            )
            if length2 == 0:
                length2 = sp.S.One
        weight = sp.diag(1, 1, 1, 1 / length2, 1 / length2, 1 / length2)
        parts.append(rows * weight * rows.T)
    return sp.diag(*parts)


def _given(item: SymContact) -> list[sp.Expr]:
    return list(item.impulse) + list(item.moment)


def _point_motion(
    problem: SymProblem, a: str, b: str | None, point: sp.Matrix, u: dict[str, tuple]
) -> tuple[sp.Matrix, sp.Matrix]:
    w = sp.zeros(3, 1)
    om = sp.zeros(3, 1)
    for name, sign in ((a, 1), (b, -1)):
        if name is None or problem.bodies[name].fixed:
            continue
        body = problem.bodies[name]
        assert isinstance(body, SymRigidBody)
        v, omega = u[name]
        w += sign * (v + omega.cross(point - body.position_com))
        om += sign * omega
    return w, om


def _random_point(exprs: list[sp.Expr], seed: int = 7) -> dict[sp.Symbol, sp.Rational]:
    rng = random.Random(seed)
    free: set[sp.Symbol] = set()
    for e in exprs:
        free |= sp.sympify(e).free_symbols
    return {s: sp.Rational(rng.randint(2, 97), rng.randint(2, 97)) for s in sorted(free, key=str)}


def derive_impact(
    problem: SymProblem, simplify: Simplifier | None = simplify_expr
) -> SymbolicResult:
    """Closed-form impulses, post-impact velocities and energies of ``problem``.

    >>> from carnot.symbolic.model import SymRigidBody, SymFixedBody, SymContact
    >>> ball = SymRigidBody(name="b", position_com=[0, 0, "r"], velocity_com=[0, 0, "-v"],
    ...                     angular_velocity=[0, 0, 0], principal=True)
    >>> res = derive_impact(SymProblem(bodies={"b": ball, "g": SymFixedBody(name="g")},
    ...     contacts=[SymContact(a="b", b="g", point=[0, 0, 0], normal=[0, 0, 1],
    ...                          restitution=sp.Symbol("e"))]))
    >>> res.bodies["b"][0].T, res.dissipated
    (Matrix([[0, 0, e*v]]), -m_b*v**2*(e - 1)*(e + 1)/2)
    """
    simp = simplify or (lambda x: x)
    items: list[SymContact | SymConstraint] = [*problem.contacts, *problem.constraints]
    movable = problem.movable
    col = {name: 6 * i for i, name in enumerate(movable)}
    ncols = 6 * len(movable)
    m_inv = sp.zeros(ncols, ncols)
    u1 = sp.zeros(ncols, 1)
    for name in movable:
        body = problem.bodies[name]
        assert isinstance(body, SymRigidBody)
        c = col[name]
        m_inv[c : c + 3, c : c + 3] = sp.eye(3) / body.mass
        m_inv[c + 3 : c + 6, c + 3 : c + 6] = body.inertia_com.inv()
        u1[c : c + 3, 0] = body.velocity_com
        u1[c + 3 : c + 6, 0] = body.angular_velocity
    def jacobian(item: SymContact | SymConstraint, rows: sp.Matrix) -> sp.Matrix:
        a, b = (item.a, item.b) if isinstance(item, SymContact) else (item.body, item.other)
        jac = sp.zeros(rows.rows, ncols)
        sides: tuple[tuple[str | None, int], ...] = ((a, 1), (b, -1))
        for side, sign in sides:
            if side is None or problem.bodies[side].fixed:
                continue
            body = problem.bodies[side]
            assert isinstance(body, SymRigidBody)
            lever = item.point - body.position_com
            for k in range(rows.rows):
                lin = rows[k, :3].T
                ang = lever.cross(lin) + rows[k, 3:].T
                for j in range(3):
                    jac[k, col[side] + j] += sign * lin[j]
                    jac[k, col[side] + 3 + j] += sign * ang[j]
        return jac

    blocks = []
    impulse_jacobians = []  # the rows the impulses act along (the rows themselves, but slip)
    for item in items:
        rows, roles = _rows(item)
        a, b = (item.a, item.b) if isinstance(item, SymContact) else (item.body, item.other)
        jac = jacobian(item, rows)
        acting = _impulse_rows(item, rows)
        impulse_jacobians.append(jac if acting is rows else jacobian(item, acting))
        blocks.append((item, a, b, acting, roles, jac))
    slipping = any(isinstance(item, SymContact) and item.slip is not None for item in items)
    w_all = sp.Matrix.vstack(*[blk[5] for blk in blocks]) if blocks else sp.zeros(0, ncols)
    w_act = sp.Matrix.vstack(*impulse_jacobians) if blocks else sp.zeros(0, ncols)
    lam = [sp.S.Zero] * w_all.rows
    law_rows: list[int] = []
    targets: list[sp.Expr] = []
    start = 0
    for item, _, _, rows, roles, jac in blocks:
        w_pre = jac * u1
        for k in range(rows.rows):
            if roles[k] == "given":
                assert isinstance(item, SymContact)
                lam[start + k] = _given(item)[k]
                continue
            law_rows.append(start + k)
            if roles[k] == "normal":
                assert isinstance(item, SymContact)
                targets.append(-item.restitution * w_pre[k])
            else:
                targets.append(sp.S.Zero)
        start += rows.rows
    lam_vec = sp.Matrix(lam) if lam else sp.zeros(0, 1)  # no items: a (0, 1) column
    u_given = u1 + m_inv * w_act.T * lam_vec
    redundant = False
    if law_rows:
        w_law = w_all.extract(law_rows, list(range(ncols)))
        rhs = sp.Matrix(targets) - w_law * u_given
        at = _random_point(list(w_law) + list(m_inv))
        numeric = w_law.subs(at)
        rank = numeric.rank()
        if slipping:
            # G = W M^-1 W_act^T is not symmetric; where it is singular for almost every value
            # (redundant rows, or Painleve's K_nn = mu K_nt) the regime has no unique answer
            g = w_law * m_inv * w_act.extract(law_rows, list(range(ncols))).T
            if rank < len(law_rows) or g.subs(at).rank() < len(law_rows):
                raise SingularRegime(
                    "contacts",
                    "a slip regime whose rows are redundant or whose G = W M^-1 (W - mu D)^T "
                    "is singular has no unique closed form",
                    len(law_rows),
                )
            sol = g.LUsolve(rhs)
        elif rank == len(law_rows):
            g = w_law * m_inv * w_law.T
            sol = g.LUsolve(rhs)
        else:
            redundant = True
            # W = B R with R independent rows, H = R M^-1 R^T: G L = b holds exactly when
            # B^T L = mu = H^-1 (B^T B)^-1 B^T b. Of those L, take the one that minimises
            # L^T Q L = sum |P|^2 + |M_P|^2 / L^2 (the numeric solver's choice, solve.py):
            # L = Q^-1 B (B^T Q^-1 B)^-1 mu.
            keep: list[int] = []
            for i in range(len(law_rows)):
                if numeric.extract(keep + [i], list(range(ncols))).rank() > len(keep):
                    keep.append(i)
            r_mat = w_law.extract(keep, list(range(ncols)))
            b_mat = (w_law * r_mat.T * (r_mat * r_mat.T).inv()).applyfunc(sp.cancel)
            h = r_mat * m_inv * r_mat.T
            mu = h.LUsolve((b_mat.T * b_mat).inv() * b_mat.T * rhs)
            q_inv = _split_metric(blocks).extract(law_rows, law_rows).inv()
            sol = q_inv * b_mat * (b_mat.T * q_inv * b_mat).LUsolve(mu)
        for i, row in enumerate(law_rows):
            lam_vec[row] = simp(sol[i])
    u2 = (u1 + m_inv * w_act.T * lam_vec).applyfunc(simp)
    before: dict[str, tuple] = {}
    after: dict[str, tuple] = {}
    for name in movable:
        c = col[name]
        before[name] = (u1[c : c + 3, 0], u1[c + 3 : c + 6, 0])
        after[name] = (u2[c : c + 3, 0], u2[c + 3 : c + 6, 0])
    outcomes: list[tuple[bool, SymItemOutcome]] = []
    start = 0
    for item, a, b, rows, _, _ in blocks:
        lam_i = lam_vec[start : start + rows.rows, 0]
        start += rows.rows
        impulse = (rows[:, :3].T * lam_i).applyfunc(simp)
        moment = (rows[:, 3:].T * lam_i).applyfunc(simp)
        w1, om1 = _point_motion(problem, a, b, item.point, before)
        w2, om2 = _point_motion(problem, a, b, item.point, after)
        dissipated = simp(-(impulse.dot(w1 + w2) + moment.dot(om1 + om2)) / 2)
        normal_impulse = friction = None
        if isinstance(item, SymContact):
            normal_impulse = simp(impulse.dot(item.normal))
            if item.tangential == "stick" and not item.is_given:
                p_t = impulse - normal_impulse * item.normal
                friction = simp(sp.sqrt(simp(p_t.dot(p_t))) / normal_impulse)
        outcomes.append(
            (
                isinstance(item, SymContact),
                SymItemOutcome(
                    where=item.where,
                    impulse=impulse,
                    moment=moment,
                    normal_impulse=normal_impulse,
                    friction_required=friction,
                    relative_velocity_before=w1.applyfunc(simp),
                    relative_velocity_after=w2.applyfunc(simp),
                    dissipated=dissipated,
                ),
            )
        )
    energy_before = sp.S.Zero
    energy_after = sp.S.Zero
    lost = sp.S.Zero
    for name in movable:
        body = problem.bodies[name]
        assert isinstance(body, SymRigidBody)
        (v1, w1_), (v2, w2_) = before[name], after[name]
        energy_before += body.kinetic_energy()
        energy_after += (body.mass * v2.dot(v2) + (w2_.T * body.inertia_com * w2_)[0, 0]) / 2
        dv, dw = v2 - v1, w2_ - w1_
        lost += (body.mass * dv.dot(dv) + (dw.T * body.inertia_com * dw)[0, 0]) / 2
    return SymbolicResult(
        bodies=after,
        contacts=tuple(o for is_c, o in outcomes if is_c),
        constraints=tuple(o for is_c, o in outcomes if not is_c),
        energy_before=simp(energy_before),
        energy_after=simp(energy_after),
        dissipated=simp(energy_before - energy_after),
        dissipated_theorem=simp(sum((o.dissipated for _, o in outcomes), sp.S.Zero)),
        lost_velocities=simp(lost),
        redundant=redundant,
    )

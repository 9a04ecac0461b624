"""The paper's section 2 as identities, proven with SymPy for general 3D bodies.

Every body has a general symmetric inertia tensor (six symbols), mass, centre-of-mass
velocity, angular velocity and the lever arm ``C_i O`` as free symbols; the impulse ``P`` and
the moment impulse ``M`` are free. The post-impact motion follows from the momentum laws
(paper eqs. 4 and 14): ``m_i (v''_i - v'_i) = (-1)^i P`` and
``[J]_i (omega''_i - omega'_i) = C_i O x (-1)^i P + (-1)^i M``, with ``[J]^-1 = adj[J]/det[J]``.

A proof: the difference of the two sides of the claimed equation, multiplied by the
denominators ``m_i det[J]_i^2`` (non-zero for a body), is expanded as a polynomial, first with
each ``det[J]_i`` held as a symbol and then with it written out; it expands to 0. The
identities of section 2 are sums over the bodies of each body's own (energies and the
alternating sums ``sum_i (-1)^(i+1) ...`` are term by term), so the difference is built as
one term per body, and each term is expanded over its own body's denominators: every term
vanishing proves the identity; where one does not, the whole difference over both bodies'
denominators decides, as a sum of terms could cancel.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import sympy as sp

from carnot.symbolic.model import inertia_symbols, vector_symbols


@dataclass(frozen=True, kw_only=True)
class Proof:
    """The outcome of one identity: ``holds`` is True when the difference expanded to 0."""

    id: str
    where: str
    statement: str
    holds: bool
    seconds: float
    residual: str
    note: str = ""


@dataclass(frozen=True)
class _Body:
    mass: sp.Symbol
    inertia: sp.Matrix
    det: sp.Symbol
    det_value: sp.Expr
    v1: sp.Matrix
    w1: sp.Matrix
    v2: sp.Matrix
    w2: sp.Matrix
    lever: sp.Matrix

    def energy(self, v: sp.Matrix, w: sp.Matrix) -> sp.Expr:
        return (self.mass * v.dot(v) + w.dot(self.inertia * w)) / 2

    def point_velocity(self, v: sp.Matrix, w: sp.Matrix) -> sp.Expr:
        return v + w.cross(self.lever)  # paper eq. (10): v_O = v_C + omega x C O


def _body(index: int, received_p: sp.Matrix, received_m: sp.Matrix) -> _Body:
    """Body ``index`` receiving the impulse ``received_p`` and moment ``received_m``."""
    mass = sp.Symbol(f"m_{index}", positive=True)
    inertia = inertia_symbols(str(index))
    det = sp.Symbol(f"det_J_{index}")
    v1 = vector_symbols(f"v_{index}")
    w1 = vector_symbols(f"omega_{index}")
    lever = vector_symbols(f"CO_{index}")
    v2 = v1 + received_p / mass
    w2 = w1 + inertia.adjugate() * (lever.cross(received_p) + received_m) / det
    return _Body(mass, inertia, det, inertia.det(), v1, w1, v2, w2, lever)


def _expands_to_zero(difference: sp.Expr, bodies: list[_Body]) -> tuple[bool, sp.Expr]:
    scale = sp.Mul(*[b.mass * b.det**2 for b in bodies])
    poly = sp.expand(difference * scale)
    poly = sp.expand(poly.subs({b.det: b.det_value for b in bodies}))
    return poly == 0, poly


def _two_bodies(with_moment: bool) -> tuple[list[_Body], sp.Matrix, sp.Matrix]:
    p = vector_symbols("P")
    m = vector_symbols("M") if with_moment else sp.zeros(3, 1)
    # Paper eq. (4)/(14): body i receives (-1)^i P and (-1)^i M.
    return [_body(1, -p, -m), _body(2, p, m)], p, m


def _sign(i: int) -> int:
    """``(-1)^(i+1)`` for body ``i + 1`` (bodies numbered from 1): the paper's alternating
    sums ``sum_i (-1)^(i+1) f(body_i)``, one term per body."""
    return 1 if i % 2 == 0 else -1


def _loss(b: _Body) -> sp.Expr:
    """One body's ``E' - E''``."""
    return b.energy(b.v1, b.w1) - b.energy(b.v2, b.w2)


def _lost(b: _Body) -> sp.Expr:
    """One body's share of Carnot's kinetic energy of the lost velocities, paper eq. (13)."""
    return b.energy(b.v1 - b.v2, b.w1 - b.w2)


#: A proof's difference as one term per body (the term of each depends on that body's symbols
#: and on P and M alone): their sum is the difference of the two sides.
Terms = list[tuple[sp.Expr, _Body]]


def _prove(
    id_: str,
    where: str,
    statement: str,
    build: Callable[[], Terms],
    note: str = "",
) -> Proof:
    start = time.perf_counter()
    terms = build()
    # each body's term vanishing proves the sum (and is a far smaller polynomial than the
    # sum over both bodies' denominators: 5 to 10 times faster); where one does not, the
    # sum itself decides (the terms of different bodies could cancel in P and M)
    holds = all(_expands_to_zero(term, [body])[0] for term, body in terms)
    residual = sp.S.Zero
    if not holds:
        holds, residual = _expands_to_zero(sum((t for t, _ in terms), sp.S.Zero),
                                           [b for _, b in terms])  # fmt: skip
    return Proof(
        id=id_,
        where=where,
        statement=statement,
        holds=holds,
        seconds=time.perf_counter() - start,
        residual="0" if holds else f"{len(sp.Add.make_args(residual))} non-zero terms",
        note=note,
    )


def _eq11() -> Terms:
    bodies, p, _ = _two_bodies(with_moment=False)
    return [(_loss(b) - _sign(i) * p.dot(b.point_velocity(b.v1, b.w1)
                                         + b.point_velocity(b.v2, b.w2)) / 2, b)
            for i, b in enumerate(bodies)]  # fmt: skip


def _eq15() -> Terms:
    bodies, p, m = _two_bodies(with_moment=True)
    return [(_loss(b) - _sign(i) * (p.dot(b.point_velocity(b.v1, b.w1)
                                          + b.point_velocity(b.v2, b.w2))
                                    + m.dot(b.w1 + b.w2)) / 2, b)
            for i, b in enumerate(bodies)]  # fmt: skip


def _eq16(received_sign: int) -> Callable[[], Terms]:
    def build() -> Terms:
        p, m = vector_symbols("P"), vector_symbols("M")
        body = _body(1, received_sign * p, received_sign * m)
        v_o = body.point_velocity(body.v1, body.w1) + body.point_velocity(body.v2, body.w2)
        claimed = -p.dot(v_o) / 2 - m.dot(body.w1 + body.w2) / 2
        return [(_loss(body) - claimed, body)]

    return build


def _eq12_13_condition() -> Terms:
    bodies, p, m = _two_bodies(with_moment=True)
    return [(_loss(b) - _lost(b) - _sign(i) * (p.dot(b.point_velocity(b.v2, b.w2))
                                               + m.dot(b.w2)), b)
            for i, b in enumerate(bodies)]  # fmt: skip


def _eq12_13_lost() -> Terms:
    bodies, p, m = _two_bodies(with_moment=True)
    return [(_lost(b) - _sign(i) * (p.dot(b.point_velocity(b.v1, b.w1)
                                          - b.point_velocity(b.v2, b.w2))
                                    + m.dot(b.w1 - b.w2)) / 2, b)
            for i, b in enumerate(bodies)]  # fmt: skip


PROOFS: tuple[tuple[str, str, str, Callable[[], Terms], str], ...] = (
    (
        "eq11",
        "section 2, eq. (11)",
        "E' - E'' = 1/2 P . sum (-1)^(i+1) (v'_Oi + v''_Oi)",
        _eq11,
        "",
    ),
    (
        "eq15",
        "section 2, eq. (15)",
        "E' - E'' = 1/2 P . sum (-1)^(i+1) (v'_Oi + v''_Oi) "
        "+ 1/2 M . sum (-1)^(i+1) (omega'_i + omega''_i)",
        _eq15,
        "",
    ),
    (
        "eq16",
        "section 2, eq. (16), P and M received by the body",
        "E_d = -P . (v'_O1 + v''_O1)/2 - M . (omega'_1 + omega''_1)/2",
        _eq16(+1),
        "holds when P and M are what the body receives from the obstacle (as the paper uses "
        "it in section 3 and carnot's conventions state)",
    ),
    (
        "eq16-eq4-labels",
        "section 2, eq. (16), with eq. (4)'s labels (body 1 receives -P, -M)",
        "E_d = -P . (v'_O1 + v''_O1)/2 - M . (omega'_1 + omega''_1)/2",
        _eq16(-1),
        "with eq. (4)'s labels, body 1 receives -P and eq. (15) gives +1/2 P . (...) "
        "+ 1/2 M . (...): eq. (16)'s signs hold only with P redefined as the impulse on the body",
    ),
    (
        "eq12-13-condition",
        "section 2, eqs. (12)-(13), Carnot's condition",
        "E_d - E_p = P . sum (-1)^(i+1) v''_Oi + M . sum (-1)^(i+1) omega''_i",
        _eq12_13_condition,
        "so E_d = E_p exactly when the impulse does no work on the post-impact relative velocities",
    ),
    (
        "eq12-13-lost",
        "section 2, eqs. (12)-(13), the lost velocities",
        "E_p = 1/2 P . sum (-1)^(i+1) (v'_Oi - v''_Oi) + 1/2 M . sum (-1)^(i+1) "
        "(omega'_i - omega''_i)",
        _eq12_13_lost,
        "with the condition above, E_d = E_p = 1/2 P . sum (-1)^(i+1) v'_Oi: eq. (12)",
    ),
)


def prove(ids: tuple[str, ...] | None = None) -> list[Proof]:
    """Run the proofs (all, or those named in ``ids``).

    >>> [p.holds for p in prove(("eq16", "eq16-eq4-labels"))]
    [True, False]
    """
    return [
        _prove(id_, where, statement, build, note)
        for id_, where, statement, build, note in PROOFS
        if ids is None or id_ in ids
    ]

"""The section of a periodic orbit through held contacts, and the symmetry it returns up to
(DESIGN.md section 10; :mod:`carnot.hybrid.cycle`).

**The section.** A period starts just after a strike. Where that strike leaves a contact
closed and at rest, the simulator holds it (:func:`carnot.hybrid.simulate.starting_holds`),
and the states just after such a strike lie on the held contacts' manifold

    M = { x : g_i(q) = 0 for each held point i,   A(q) v = 0 },

``g_i`` the point's gap (m) and ``A`` the held rows (each point's normal, and its tangents
where it sticks: :func:`carnot.hybrid.flow.held_solution`), which the held flow keeps. The
return map is smooth on ``M``, not off it (a state 1 um above the floor falls and strikes
first), so Newton's unknowns are ``M``'s: each iterate is put on ``M``
(:func:`on_section`: the gaps made zero by least-norm moves of the positions, then the
velocities along the held rows removed by the least kinetic change, as :func:`carnot.hybrid.
simulate.settle` does) and each step is taken in ``M``'s tangent space, whose basis
(:func:`tangent_basis`) is the null space of the constraints' Jacobian ``D_x (g, A v)`` (by
central differences, ``SECTION_STEP``). The same basis restricts the monodromy to ``M``: its
eigenvalues off ``M`` are those of directions the system cannot take (0: the plastic strike
takes them), not Floquet multipliers.

**The symmetry.** A walker advances along its floor; a rimless wheel's spokes are alike. Its
orbit is then periodic only up to a symmetry, which the user declares on the positions:

* ``shift`` (a coordinate and an amount, rad or m): the period returns that coordinate
  advanced by the amount, ``P(x) = x + s`` (a rimless wheel's pitch, ``2 pi / N``: spoke
  ``k + 1`` then stands where spoke ``k`` stood);
* ``cyclic`` (a coordinate): the motion does not depend on it (a slide along a flat floor
  under gravity along it or across it), so its value on the section is the guess's and its
  change over a period is free, reported as the ``advance`` (a step's length); it is left
  out of the fixed-point equations, and its multiplier 1 (a shifted orbit is an orbit) out of
  the multipliers. That the return map indeed does not depend on it is checked: the return
  map's Jacobian column ``D P e_k`` must be ``e_k`` (to ``CYCLIC_TOLERANCE``).

The fixed point solves ``P(x) - s - x = 0`` on the non-cyclic coordinates.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from carnot.errors import InputError
from carnot.hybrid.flow import Hold, held_points, held_solution
from carnot.hybrid.model import HybridModel, Law
from carnot.hybrid.simulate import TOUCH, settle, starting_holds

#: A guess's contact point within this gap (m) of closing, and its normal speed within
#: ``SECTION_SPEED`` of the state's speed scale ``max(1, |v|)``, is put on the section:
#: closed and at rest (a keyframe typed to a few digits).
SECTION_GAP = 1e-6
SECTION_SPEED = 1e-3
#: The step (m, rad; m/s, rad/s) of the constraints' central differences.
SECTION_STEP = 1e-7
#: Singular values of the constraints' Jacobian below this part of the largest are zero (a
#: planar model's contact has a tangent row that is zero).
SECTION_RANK = 1e-8
#: How far ``D P e_k`` may lie from ``e_k`` (absolute) for a coordinate said to be cyclic.
CYCLIC_TOLERANCE = 1e-6
#: The most Gauss-Newton steps that close the gaps.
CLOSING_STEPS = 20


@dataclass(frozen=True, kw_only=True, eq=False)
class Symmetry:
    """What the period returns up to: ``shift`` (nq: each position's advance, rad or m) and
    the ``cyclic`` positions' indices, with their ``names``."""

    shift: np.ndarray
    cyclic: tuple[int, ...]
    names: tuple[str, ...]

    @property
    def given(self) -> bool:
        """Whether any shift or cyclic coordinate is declared."""
        return bool(self.cyclic) or bool(np.any(self.shift))


def symmetry(model: HybridModel, shift: Mapping[str, float] | None = None,
             cyclic: Sequence[str] = ()) -> Symmetry:  # fmt: skip
    """The declared symmetry on the model's coordinates (by name), checked: each name a
    coordinate, each amount finite, no coordinate both shifted and cyclic.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel")
    >>> symmetry(wheel, {"theta": 0.5}).shift.tolist()
    [0.5]
    >>> symmetry(wheel, cyclic=["x"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: cyclic 'x': is not a coordinate of rimless_wheel (its ...theta)
    """
    names = tuple(model.coordinates)
    known = ", ".join(names)
    out = np.zeros(model.nq)
    for name, amount in (shift or {}).items():
        if name not in names:
            raise InputError(f"shift {name!r}", f"is not a coordinate of {model.name} (its "
                             f"coordinates: {known})", show_value=False)  # fmt: skip
        value = float(amount)
        if not np.isfinite(value):
            raise InputError(f"shift {name!r}", "must be a finite number (rad or m)", amount)
        out[names.index(name)] = value
    indices = []
    for name in cyclic:
        if name not in names:
            raise InputError(f"cyclic {name!r}", f"is not a coordinate of {model.name} (its "
                             f"coordinates: {known})", show_value=False)  # fmt: skip
        if shift and name in shift:
            raise InputError(f"cyclic {name!r}", "is shifted too: a coordinate is either "
                             "shifted by a known amount or cyclic", show_value=False)
        indices.append(names.index(name))
    if model.nq != model.n and (indices or np.any(out)):
        raise InputError("shift", "is built where positions and velocities pair (no free or "
                         "ball joint)", show_value=False)  # fmt: skip
    return Symmetry(shift=out, cyclic=tuple(sorted(set(indices))), names=names)


def residual(model: HybridModel, sym: Symmetry, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``y - s - x`` (2n, ``y = P(x)``), the cyclic positions' entries zero.

    >>> from carnot.hybrid.models import named_model
    >>> wheel = named_model("rimless_wheel")
    >>> sym = symmetry(wheel, {"theta": 0.5})
    >>> residual(wheel, sym, np.array([0.1, 1.0]), np.array([0.6, 1.25])).tolist()
    [0.0, 0.25]
    """
    out = np.asarray(y, dtype=float) - np.asarray(x, dtype=float)
    out[: model.nq] -= sym.shift
    out[list(sym.cyclic)] = 0.0
    return out


def _near_points(model: HybridModel, x: np.ndarray
                 ) -> list[tuple[int, int | None]]:  # fmt: skip
    """The contact points near closing and near rest at ``x``: ``(guard, point)`` (``None``:
    the guard's one point)."""
    v = x[model.nq :]
    speed = SECTION_SPEED * max(1.0, float(np.linalg.norm(v)))
    out: list[tuple[int, int | None]] = []
    for k, g in enumerate(model.guards):
        if g.rows is None:
            continue
        rows = g.rows(x)
        if isinstance(rows, tuple):
            out += [(k, i) for i, r in enumerate(rows)
                    if abs(r.gap) <= SECTION_GAP and abs(float(r.normal @ v)) <= speed]  # fmt: skip
        elif abs(g.function(x)) <= SECTION_GAP and abs(float(rows.normal @ v)) <= speed:
            out.append((k, None))
    return out


def _gaps(model: HybridModel, x: np.ndarray, points: list[tuple[int, int | None]]
          ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The points' gaps (m) and their gradients (rows, n) at ``x`` (a pair's point: the one
    nearest its former place in MuJoCo's order)."""
    gaps, rows = [], []
    for k, i in points:
        g = model.guards[k]
        assert g.rows is not None
        found = g.rows(x)
        if isinstance(found, tuple):
            r = found[min(i or 0, len(found) - 1)] if found else None
            if r is None:
                raise InputError("guess", f"loses its contact {g.name} while it is put on the "
                                 "section", show_value=False)  # fmt: skip
            gaps.append(r.gap)
            rows.append(r.normal)
        else:
            gaps.append(g.function(x))
            rows.append(found.normal)
    return np.array(gaps), np.array(rows).reshape(len(points), model.n)


def on_section(model: HybridModel, x: np.ndarray, law: Law
               ) -> tuple[np.ndarray, tuple[Hold, ...]]:  # fmt: skip
    """``x`` put on the section (module docstring) and the holds a run from it starts with:
    the contact points within ``SECTION_GAP`` of closing and ``SECTION_SPEED`` of rest
    closed (``q <- q - G^+ g``, Gauss-Newton on their gaps ``g``, ``G`` the gaps' rows, to
    ``TOUCH`` / 1000 or ``CLOSING_STEPS`` steps), their normal velocities and the tangential
    ones within ``SECTION_SPEED`` removed by the least kinetic change (``v <- v - M^-1 A^T
    (A M^-1 A^T)^+ A v``), then held as :func:`carnot.hybrid.simulate.starting_holds` holds
    them, and settled on their rows. Positions in m or rad, velocities in m/s or rad/s.
    ``nq == n``; a state with no contact near closing is returned as it is.

    >>> from carnot.hybrid.models import named_model
    >>> leg = named_model("hopping_leg")  # the foot 1e-8 m up, sinking at 1e-5 m/s
    >>> y, holds = on_section(leg, np.array([0.45, 1e-8, -0.5, -1e-5]), Law())
    >>> y.tolist(), holds
    ([0.45, 0.0, -0.5, 0.0], (Hold(index=0, slip=0, direction=(), points=1, anchors=()),))
    """
    x = np.array(x, dtype=float)
    nq = model.nq
    points = _near_points(model, x)
    if not points:
        return x, ()
    for _ in range(CLOSING_STEPS):
        gaps, rows = _gaps(model, x, points)
        if float(np.max(np.abs(gaps))) <= 1e-3 * TOUCH:
            break
        x[:nq] -= np.linalg.lstsq(rows, gaps, rcond=None)[0]
    q, v = x[:nq], x[nq:]
    speed = SECTION_SPEED * max(1.0, float(np.linalg.norm(v)))
    stop: list[np.ndarray] = []
    for k, i in points:
        g = model.guards[k]
        assert g.rows is not None
        found = g.rows(x)
        r = found[min(i or 0, len(found) - 1)] if isinstance(found, tuple) else found
        stop.append(r.normal)
        tangents = r.tangents()
        if tangents is not None and float(np.linalg.norm(tangents[0] @ v)) <= speed:
            stop += list(tangents[0])
    a = np.array(stop)
    m_inv_at = np.linalg.solve(model.mechanism.mass(q), a.T)
    lam = np.linalg.lstsq(a @ m_inv_at, a @ v, rcond=1e-12)[0]
    x = np.concatenate([q, v - m_inv_at @ lam])
    scale = max(abs(model.energy(x, np.zeros(2))), model.kinetic(x), 1e-300)
    holds = starting_holds(model, x, law.friction, scale)
    x = settle(model, holds, x, law.friction)[0]
    return x, holds


def _constraints(model: HybridModel, holds: tuple[Hold, ...], x: np.ndarray,
                 friction: float | None) -> np.ndarray:  # fmt: skip
    """``(g, A v)`` at ``x``: each held point's gap (m), then the held rows' velocities."""
    gaps: list[float] = []
    for h in holds:
        g = model.guards[h.index]
        if g.several:
            gaps += [float(r.gap) for r in held_points(model, h, x)]
        else:
            gaps.append(float(g.function(x)))
    rows = held_solution(model, holds, x, friction).rows
    return np.concatenate([gaps, rows @ x[model.nq :]])


def tangent_basis(model: HybridModel, x: np.ndarray, holds: tuple[Hold, ...], law: Law,
                  sym: Symmetry) -> np.ndarray:  # fmt: skip
    """An orthonormal basis (2n x d columns) of the section's tangent space at ``x`` less the
    cyclic positions' directions: the null space of ``D_x (g, A v)`` (:func:`_constraints`,
    central differences of step ``SECTION_STEP``) stacked with ``e_k^T`` for each cyclic
    ``k``; the identity's columns less the cyclic ones where nothing is held.

    >>> from carnot.hybrid.models import named_model
    >>> leg = named_model("hopping_leg")
    >>> b = tangent_basis(leg, np.array([0.45, 0.0, -0.5, 0.0]), (Hold(index=0),), Law(),
    ...                   symmetry(leg))
    >>> b.shape, (np.diag(b @ b.T).round(12) + 0.0).tolist()  # y_foot and its rate held
    ((4, 2), [1.0, 0.0, 1.0, 0.0])
    """
    n2 = 2 * model.n
    rows = [np.eye(n2)[k] for k in sym.cyclic]
    if holds:
        x = np.asarray(x, dtype=float)
        c = np.zeros((len(_constraints(model, holds, x, law.friction)), n2))
        for j in range(n2):
            up, down = x.copy(), x.copy()
            up[j] += SECTION_STEP
            down[j] -= SECTION_STEP
            c[:, j] = (_constraints(model, holds, up, law.friction)
                       - _constraints(model, holds, down, law.friction)) / (2 * SECTION_STEP)
        rows += list(c)
    if not rows:
        return np.eye(n2)
    a = np.array(rows)
    _, s, vt = np.linalg.svd(a)
    rank = int(np.sum(s > SECTION_RANK * s[0])) if s.size and s[0] > 0 else 0
    return np.asarray(vt[rank:].T)

"""The outcome of an impact read from contact space: each item's impulse, its share of the
theorem, the energy ledger (the direct difference and the theorem side by side) and the flags.

Paper eq. (11) (two bodies), (15) (with a moment impulse) and (16) (a fixed obstacle), written
with the conventions of ``conventions.py``:

    E_d = E' - E'' = -1/2 sum [P . (w' + w'') + M_P . (Omega' + Omega'')]

and Carnot's kinetic energy of the lost velocities (paper eq. 13)

    E_p = 1/2 du^T M du,     E_d - E_p = -sum [P . w'' + M_P . Omega'']   (paper eq. 12).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from carnot.conventions import contact_frame
from carnot.model.contacts import Item, PointContact
from carnot.result import EnergyLedger, Flag, ItemOutcome
from carnot.space import ContactSpace
from carnot.vector3 import cross, dot_floats, norm


def kinetic_energy(mass_matrix: np.ndarray, u: np.ndarray) -> float:
    """``1/2 u^T M u`` (J): Koenig's formula for stacked ``(v, omega)``.

    >>> kinetic_energy(np.diag([2.0, 2, 2, 1, 1, 1]), np.array([1.0, 0, 0, 0, 0, 2]))
    3.0
    """
    return float(0.5 * u @ mass_matrix @ u)


def lost_velocities(mass_matrix: np.ndarray, u_before: np.ndarray, u_after: np.ndarray) -> float:
    """Carnot's ``E_p = 1/2 (u'' - u')^T M (u'' - u')`` (J), paper eq. (13)."""
    du = u_after - u_before
    return float(0.5 * du @ mass_matrix @ du)


def theorem_terms(
    impulse: np.ndarray,
    moment: np.ndarray,
    normal: np.ndarray | None,
    w_before: np.ndarray,
    w_after: np.ndarray,
    omega_rel_before: np.ndarray,
    omega_rel_after: np.ndarray,
) -> tuple[float, float, float]:
    """One item's share of the theorem, split as (normal, tangential, moment) parts (J).

    ``normal``: ``-1/2 (P.n)(n.(w'+w''))``; tangential: ``-1/2 P_t . (w'+w'')``;
    moment: ``-1/2 M_P . (Omega'+Omega'')``. Without a normal (a fasten or pin) the whole force
    part is reported as normal.

    >>> theorem_terms(np.array([0, 0, 2.0]), np.zeros(3), np.array([0, 0, 1.0]),
    ...               np.array([0, 0, -1.0]), np.array([0, 0, 0.5]), np.zeros(3), np.zeros(3))
    (0.5, 0.0, 0.0)
    """
    w_sum = (w_before + w_after).tolist()
    moment_part = -0.5 * dot_floats(moment.tolist(), (omega_rel_before + omega_rel_after).tolist())
    p = impulse.tolist()
    if normal is None:
        return -0.5 * dot_floats(p, w_sum) + 0.0, 0.0, moment_part + 0.0
    n = normal.tolist()
    p_n = dot_floats(p, n)
    normal_part = -0.5 * p_n * dot_floats(n, w_sum)
    tangential_part = -0.5 * dot_floats([a - p_n * b for a, b in zip(p, n, strict=True)], w_sum)
    return normal_part + 0.0, tangential_part + 0.0, moment_part + 0.0


def item_outcomes(
    items: Sequence[Item],
    space: ContactSpace,
    impulses: np.ndarray,
    u_after: np.ndarray,
    processes: dict[int, Any],
    flags: list[Flag],
    states: dict[int, tuple[str, bool]] | None = None,
) -> list[ItemOutcome]:
    """Each item's impulse ``P = C_lin^T Lambda``, moment ``M_P = C_ang^T Lambda``, relative
    motion before and after (``(w, Omega) = J_i u``) and its share of the theorem; the flags
    of doubtful contacts are appended to ``flags``. ``states``: the regime and whether it took
    part of each contact of a multiple-impact law, by item index."""
    outcomes = []
    # every item's (w, Omega) before and after in one product each (space.motion_at, item
    # by item, was a tenth of the outcome stage of a 4-corner landing)
    # (each item's four 3-vectors as rows of one array: a row is one view, where unpacking
    # a (2, 3) block made three)
    before = (space.motion @ space.u_before).reshape(-1, 3)
    after = (space.motion @ u_after).reshape(-1, 3)
    for index, (item, block, rows) in enumerate(
        zip(items, space.blocks, space.slices, strict=True)
    ):
        lam = impulses[rows]
        impulse = block.linear.T @ lam
        moment = block.angular.T @ lam
        w1, om1, w2, om2 = before[2 * index], before[2 * index + 1], after[2 * index], \
            after[2 * index + 1]  # fmt: skip
        if isinstance(item, PointContact):
            # the law's regime and activity passed in, not replaced after: a dataclass
            # replace per contact was a tenth of a 4-corner landing's solve
            state = None if states is None else states.get(index)
            outcome = _contact_outcome(item, impulse, moment, w1, w2, om1, om2, flags,
                                       processes.get(index), several=states is not None,
                                       state=state)
            outcomes.append(outcome)  # fmt: skip
            continue
        d_n, d_t, d_m = theorem_terms(impulse, moment, None, w1, w2, om1, om2)
        outcomes.append(
            ItemOutcome(
                where=item.where, kind=item.kind, a=item.body, b=item.other, point=item.point,
                normal=None, impulse=impulse, moment=moment, normal_impulse=None,
                tangential_impulse=None, regime=item.kind, relative_velocity_before=w1,
                relative_velocity_after=w2, relative_angular_velocity_before=om1,
                relative_angular_velocity_after=om2, dissipated=d_n + d_t + d_m,
                dissipated_normal=d_n, dissipated_tangential=d_t, dissipated_moment=d_m,
            )
        )  # fmt: skip
    return outcomes


def energy_ledger(
    space: ContactSpace,
    impulses: np.ndarray,
    u_after: np.ndarray,
    outcomes: Sequence[ItemOutcome],
    *,
    before: float,
    after: float,
) -> EnergyLedger:
    """The ledger: ``before`` and ``after`` (J) from the model's own kinetic energy (the
    direct route, e.g. Koenig body by body), the theorem summed over the items, Carnot's
    ``E_p`` and the two sides of paper eq. (12)."""
    lost = lost_velocities(space.mass_matrix, space.u_before, u_after)
    return EnergyLedger(
        before=before,
        after=after,
        dissipated=before - after,
        dissipated_theorem=sum(o.dissipated for o in outcomes),
        lost_velocities=lost,
        carnot_defect=(before - after) - lost,
        carnot_condition=-float(impulses @ space.row_velocities(u_after)),
        dissipated_normal=sum(o.dissipated_normal for o in outcomes),
        dissipated_tangential=sum(o.dissipated_tangential for o in outcomes),
        dissipated_moment=sum(o.dissipated_moment for o in outcomes),
    )


def ledger_closes(ledger: EnergyLedger, tolerance: float = 1e-9) -> bool:
    """Whether the theorem and the direct difference agree to ``tolerance`` of the kinetic
    energies (the paper's theorem is exact, so a gap is lost digits, not physics).

    >>> ledger_closes(EnergyLedger(before=2.0, after=1.0, dissipated=1.0, dissipated_theorem=1.5,
    ...     lost_velocities=0.0, carnot_defect=0.0, carnot_condition=0.0, dissipated_normal=0.0,
    ...     dissipated_tangential=0.0, dissipated_moment=0.0))
    False
    """
    gap = abs(ledger.dissipated - ledger.dissipated_theorem)
    return gap <= tolerance * (abs(ledger.before) + abs(ledger.after))


def flag_energy_gain(
    ledger: EnergyLedger, contacts: Sequence[PointContact], processes: dict[int, Any]
) -> Flag | None:
    """``energy_gain`` when ``E'' > E'`` beyond round-off, with the likely cause: Coulomb
    friction under Newton's or Poisson's hypothesis (``processes``: the integrated contacts,
    by item index)."""
    if not ledger.dissipated < -1e-12 * max(ledger.before, 1e-300):
        return None
    cause = "".join(
        f"; {c.where} has Coulomb friction under {c.law.capitalize()}'s hypothesis, which "
        + ("can create energy when slip stops or reverses (Kane and Levinson's double "
           "pendulum, Stronge's rod); Stronge's energetic hypothesis never does"
           if c.law != "stronge" else "should not create energy: please report this")
        for k, c in enumerate(contacts)
        if k in processes
    )  # fmt: skip
    return Flag(
        code="energy_gain",
        where="energy",
        message=f"the impact gains {-ledger.dissipated:.6g} J of kinetic energy{cause}",
    )


def _contact_outcome(
    item: PointContact,
    impulse: np.ndarray,
    moment: np.ndarray,
    w1: np.ndarray,
    w2: np.ndarray,
    om1: np.ndarray,
    om2: np.ndarray,
    flags: list[Flag],
    process: Any = None,
    *,
    several: bool = False,
    state: tuple[str, bool] | None = None,
) -> ItemOutcome:
    """One contact's outcome; ``state``: the regime and activity a multiple-impact law gave."""
    n = item.normal
    p_n = float(impulse @ n)
    p_t = impulse - p_n * n
    d_n, d_t, d_m = theorem_terms(impulse, moment, n, w1, w2, om1, om2)
    # |P| + |M_P| as vector3.norm writes it, sqrt(a @ a), on the float arrays at hand
    scale = math.sqrt(float(impulse @ impulse)) + math.sqrt(float(moment @ moment)) + 1e-300
    friction_required: float | None = None
    centre: np.ndarray | None = None
    if item.is_given:
        regime = "given"
    else:
        regime = "stick" if item.sticks else "frictionless"
        if process is not None:
            regime = process.regime
            _flag_process(item, process, flags)
        if item.sticks:
            friction_required = norm(p_t) / p_n if p_n > 0 else float("inf")
        flags.extend(point_contact_flags(item, w_normal=float(n @ w1), normal_impulse=p_n,
                                         scale=scale, friction_required=friction_required,
                                         several=several))  # fmt: skip
        if item.patch is not None and p_n > 1e-12 * scale:
            centre = item.point + cross(n, moment) / p_n
            if not _inside_patch(centre, item.patch, n):
                flags.append(
                    Flag(
                        code="centre_of_pressure_outside_patch",
                        where=item.where,
                        message=(
                            f"the centre of pressure {np.round(centre, 9).tolist()} implied by "
                            f"the impulse at {item.where} lies outside the contact patch: the "
                            "pressure would have to pull somewhere"
                        ),
                    )
                )
    # (Record.from_fields: every field in declaration order, as ItemOutcome's __init__ sets
    # them; its 26 object.__setattr__ calls were a tenth of a contact's outcome)
    return ItemOutcome.from_fields({
        "where": item.where,
        "kind": "contact",
        "a": item.a,
        "b": item.b,
        "point": item.point,
        "normal": n,
        "impulse": impulse,
        "moment": moment,
        "normal_impulse": p_n,
        "tangential_impulse": p_t,
        "regime": regime if state is None else state[0],
        "relative_velocity_before": w1,
        "relative_velocity_after": w2,
        "relative_angular_velocity_before": om1,
        "relative_angular_velocity_after": om2,
        "dissipated": d_n + d_t + d_m,
        "dissipated_normal": d_n,
        "dissipated_tangential": d_t,
        "dissipated_moment": d_m,
        "friction_required": friction_required,
        "centre_of_pressure": centre,
        "law": None if item.is_given else item.law,
        "process": process,
        "active": None if state is None else state[1],
        "name": item.name,
        "generalized_impulse": None,
    })


def point_contact_flags(
    item: PointContact,
    *,
    w_normal: float,
    normal_impulse: float,
    scale: float,
    friction_required: float | None,
    several: bool = False,
) -> list[Flag]:
    """The flags of a contact's law outcome: ``not_approaching`` (``n . w' >= 0``, m/s; not
    with ``several``, where a multiple-impact law decides who acts), ``negative_normal_impulse``
    (``P_n < -1e-12 scale``, N s; ``scale`` = ``|P| + |M_P|``) and ``friction_insufficient``
    (sticking needs ``|P_t| / P_n`` above the contact's ``mu > 0``, to 1e-12 relative).

    >>> c = PointContact(a="a", b="b", point=[0, 0, 0], normal=[0, 0, 1], tangential="stick",
    ...                  friction=0.2)
    >>> [f.code for f in point_contact_flags(c, w_normal=-1.0, normal_impulse=1.0, scale=1.1,
    ...                                      friction_required=0.5)]
    ['friction_insufficient']
    """
    flags = []
    if w_normal >= 0.0 and not several:
        flags.append(
            Flag(
                code="not_approaching",
                where=item.where,
                message=(
                    f"the bodies are not approaching at {item.where} (n . w' = "
                    f"{w_normal:.6g} m/s >= 0); a contact law applied anyway"
                ),
            )
        )
    if normal_impulse < -1e-12 * scale:
        flags.append(
            Flag(
                code="negative_normal_impulse",
                where=item.where,
                message=(
                    f"the normal impulse at {item.where} is {normal_impulse:.6g} N s < 0: the "
                    "contact would have to pull; a unilateral contact cannot"
                ),
            )
        )
    if (friction_required is not None and item.friction > 0
            and friction_required > item.friction * (1 + 1e-12)):  # fmt: skip
        flags.append(
            Flag(
                code="friction_insufficient",
                where=item.where,
                message=(
                    f"sticking at {item.where} needs a friction coefficient of at least "
                    f"{friction_required:.6g}, more than the {item.friction:g} given: the "
                    "contact would slip"
                ),
            )
        )
    return flags


def ledger_flag(ledger: EnergyLedger) -> Flag:
    """``ledger_not_closed``: the theorem is exact, so a gap between its two routes is digits
    the input's scales left the arithmetic without, and the result is not to be trusted."""
    return Flag(
        code="ledger_not_closed",
        where="energy",
        message=(
            f"the theorem ({ledger.dissipated_theorem:.6g} J) and the direct difference "
            f"({ledger.dissipated:.6g} J) disagree beyond round-off: the input's scales leave "
            "the arithmetic too few digits; do not trust this result"
        ),
    )


def _flag_process(item: PointContact, process: Any, flags: list[Flag]) -> None:
    """Flags particular to an integrated frictional impact."""
    scale = abs(process.work_normal_compression) + 1e-300
    if process.work_normal > 1e-9 * scale:
        flags.append(
            Flag(
                code="normal_energy_gain",
                where=item.where,
                message=(
                    f"the normal impulse at {item.where} did net positive work "
                    f"({process.work_normal:.6g} J) under {item.law.capitalize()}'s hypothesis: "
                    "restitution gave back more than compression took"
                ),
            )
        )


def _inside_patch(point: np.ndarray, patch: np.ndarray, normal: np.ndarray) -> bool:
    """Whether ``point`` lies in the convex hull of the coplanar ``patch`` points (to 1e-9 of
    the patch size): the resultant of a pressure >= 0 always does."""
    from scipy.spatial import ConvexHull, QhullError

    _, t1, t2 = contact_frame(normal)
    origin = patch.mean(axis=0)
    pts = np.column_stack([(patch - origin) @ t1, (patch - origin) @ t2])
    x = np.array([(point - origin) @ t1, (point - origin) @ t2])
    size = max(float(np.max(np.linalg.norm(pts, axis=1))), 1e-300)
    tol = 1e-9 * size
    _, sing, vt = np.linalg.svd(pts, full_matrices=False)
    rank = int(np.sum(sing > 1e-9 * size))
    if rank == 0:
        return bool(np.linalg.norm(x) <= tol)
    if rank == 1:
        d = vt[0]
        s = pts @ d
        off = x - (x @ d) * d
        return bool(np.linalg.norm(off) <= tol and s.min() - tol <= x @ d <= s.max() + tol)
    try:
        hull = ConvexHull(pts)
    except QhullError:  # pragma: no cover - rank 2 points always have a hull
        return False
    return bool(np.all(hull.equations[:, :2] @ x + hull.equations[:, 2] <= tol))

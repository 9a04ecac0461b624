"""Solve an impact: every contact and constraint at once, then the ledger, checks and flags.

    u'' = u' + M^-1 W^T Lambda,     G Lambda = target(w') - W u_g,     G = W M^-1 W^T

where ``u_g`` is ``u'`` after the given impulses (contacts with ``impulse``) and after the
impulse of a contact with Coulomb friction, integrated first in impulse space with the pins
folded in (laws/friction.py, :func:`_integrate_contact`), and ``target`` is each equality
law's prescription for its rows (laws/). When ``G`` is singular the rows are redundant:
if the requirements are consistent the motion and ``E_d`` are still unique but the split of
the impulse among the redundant rows is not; carnot then reports the minimum-norm ``Lambda``
(``G^+ b``) and says so in ``warnings``. Every item's rows are orthonormal in the metric
``|P|^2 + |M_P|^2 / L^2`` (contacts.py; ``L`` the RMS distance of a patch's points from its
contact point), so this is the split that minimises ``sum |P|^2 + |M_P|^2 / L^2`` over the
items, whichever basis of the rows was used and whatever the unit of length. If
they are inconsistent, no impulse can meet them and the problem is refused.
"""

from __future__ import annotations

import numpy as np

from carnot.bodies import RigidBody
from carnot.contacts import PointConstraint, PointContact, RowBlock
from carnot.energy import kinetic_energy, lost_velocities, theorem_terms
from carnot.errors import ConstraintConflictError, InputError
from carnot.laws import BILATERAL, LAWS
from carnot.laws.friction import FrictionalImpulse, integrate_impact
from carnot.problem import ImpactProblem
from carnot.result import (
    BodyMotion,
    EnergyLedger,
    Flag,
    ImpactResult,
    ItemOutcome,
    MomentumCheck,
)
from carnot.system import ContactSpace, assemble

#: Relative size under which an eigenvalue of the Delassus operator counts as zero.
RANK_TOLERANCE = 1e-11
#: Relative residual above which simultaneous requirements count as contradictory.
CONFLICT_TOLERANCE = 1e-8


def solve_impact(problem: ImpactProblem) -> ImpactResult:
    """Solve ``problem`` and return the outcome with its energy ledger.

    >>> from carnot import RigidBody, FixedBody, PointContact, ImpactProblem
    >>> ball = RigidBody(mass=1.0, inertia_com=np.eye(3) * 0.004, velocity_com=[0, 0, -2.0],
    ...                  name="ball")
    >>> r = solve_impact(ImpactProblem(
    ...     bodies={"ball": ball, "floor": FixedBody(name="floor")},
    ...     contacts=[PointContact(a="ball", b="floor", point=[0, 0, -0.1], normal=[0, 0, 1],
    ...                            restitution=0.5)]))
    >>> r.bodies["ball"].velocity_after.tolist(), round(r.energy.dissipated, 12)
    ([0.0, 0.0, 1.0], 1.5)
    """
    _check_supported(problem)
    items: list[PointContact | PointConstraint] = [*problem.contacts, *problem.constraints]
    blocks = tuple(item.rows() for item in items)
    space = assemble(problem, blocks)
    flags: list[Flag] = []
    _check_pins(problem, space)

    u_before = space.u_before
    w_before = space.jacobian @ u_before
    impulses = np.zeros(space.jacobian.shape[0])
    law_rows: list[int] = []
    targets: list[float] = []
    frictional: tuple[int, PointContact] | None = None
    for index, (item, block, rows) in enumerate(zip(items, blocks, space.slices, strict=True)):
        if isinstance(item, PointContact) and item.is_given:
            impulses[rows] = item.given_row_impulses()
            continue
        if isinstance(item, PointContact) and item.slips_with_friction:
            frictional = (index, item)  # _check_supported allows one, beside constraints
            continue
        law = LAWS[item.law] if isinstance(item, PointContact) else BILATERAL
        restitution = item.restitution if isinstance(item, PointContact) else 0.0
        target = law.target_velocity(w_before[rows], block.roles, restitution=restitution)
        law_rows.extend(range(rows.start, rows.stop))
        targets.extend(target.tolist())
    u_given = u_before + space.mass_matrix_inv @ space.jacobian.T @ impulses
    processes: dict[int, FrictionalImpulse] = {}
    if frictional is not None:
        index, contact = frictional
        rows = space.slices[index]
        process = _integrate_contact(space, rows, np.array(law_rows, dtype=int), u_given, contact)
        processes[index] = process
        impulses[rows] = process.impulse  # rows (n, t1, t2): row impulses = frame components
        u_given = u_given + space.mass_matrix_inv @ space.jacobian[rows].T @ process.impulse
    if law_rows:
        idx = np.array(law_rows)
        w_law = space.jacobian[idx]
        rhs = np.array(targets) - w_law @ u_given
        lam, redundant = _solve_rows(space, idx, rhs, blocks)
        impulses[idx] = lam
        if redundant:
            flags.append(
                Flag(
                    code="statically_indeterminate",
                    where=", ".join(redundant),
                    message=(
                        f"the split of the impulse among {' and '.join(redundant)} is not unique "
                        "(redundant constraints); the motion and the dissipated energy are; "
                        "carnot reports the minimum-norm split"
                    ),
                )
            )
    u_after = u_before + space.mass_matrix_inv @ space.jacobian.T @ impulses
    return _outcome(problem, items, space, impulses, u_after, flags, processes)


def _integrate_contact(
    space: ContactSpace,
    rows: slice,
    other_rows: np.ndarray,
    u_given: np.ndarray,
    contact: PointContact,
) -> FrictionalImpulse:
    """The impulse-space integration of one frictional contact, with the bilateral
    constraints (``other_rows``: pins) holding throughout the impact.

    The constraint impulses follow the contact impulse ``P``: ``Lambda_k = -G_kk^+ (w_k +
    G_kc P)`` keeps the constraint rows at their target 0, so the contact sees the Schur
    complement ``K = G_cc - G_ck G_kk^+ G_kc`` and ``w' = w_c - G_ck G_kk^+ w_k``.
    """
    w_c = space.jacobian[rows] @ u_given
    g_cc = space.delassus(rows)
    k = g_cc
    if other_rows.size:
        w_k = space.jacobian[other_rows] @ u_given
        g_kk_pinv = np.linalg.pinv(space.delassus(other_rows), rcond=RANK_TOLERANCE, hermitian=True)
        g_ck = space.jacobian[rows] @ space.mass_matrix_inv @ space.jacobian[other_rows].T
        k = k - g_ck @ g_kk_pinv @ g_ck.T
        w_c = w_c - g_ck @ g_kk_pinv @ w_k
    k = 0.5 * (k + k.T)
    if not k[0, 0] > RANK_TOLERANCE * float(np.trace(g_cc)):
        raise InputError(
            f"{contact.where}",
            "the constraints leave this contact no freedom along its normal (the effective "
            "inverse mass n . K n is 0): it can take no impulse",
            float(k[0, 0]),
        )
    return integrate_impact(
        k, w_c, friction=contact.friction, restitution=contact.restitution,
        hypothesis=contact.law,
    )  # fmt: skip


def _check_supported(problem: ImpactProblem) -> None:
    """Refuse what this version would get wrong rather than answer it with another law."""
    unilateral_rows = sum(
        (1 if c.patch is None else 2) + (2 if c.sticks else 0)
        for c in problem.contacts
        if not c.is_given
    )
    law_contacts = [c for c in problem.contacts if not c.is_given]
    for c in problem.contacts:
        if c.is_given:
            continue
        if c.slips_with_friction:
            if c.patch is not None:
                raise InputError(
                    f"{c.where}.friction",
                    "Coulomb friction with slip over a contact patch is not supported (the "
                    'impulse-space integration is for point contacts): give tangential = '
                    '"stick", friction = 0, or a point contact',
                    c.friction,
                )
            if len(law_contacts) > 1:
                raise InputError(
                    f"{c.where}.friction",
                    "Coulomb friction with slip is integrated for one contact at a time (with "
                    "any pins and given impulses); simultaneous frictional contacts need "
                    "complementarity, which this version does not have: solve them one by one "
                    "or make the others frictionless",
                    c.friction,
                )
            fasten = [k.where for k in problem.constraints if k.kind == "fasten"]
            if fasten:
                raise InputError(
                    fasten[0],
                    "a sudden fastening together with a frictional contact has no defined "
                    "order of events in this version; a pin (already at rest) is supported",
                    "fasten",
                )
            continue
        if c.law != "newton" and (c.sticks or c.patch is not None or unilateral_rows > 1):
            raise InputError(
                f"{c.where}.law",
                "Poisson's and Stronge's hypotheses differ from Newton's here (sticking, a "
                "surface contact or several simultaneous contacts); this version supports "
                "them for a single point contact, frictionless or with Coulomb friction "
                '(tangential = "slip", the default)',
                c.law,
            )


def _check_pins(problem: ImpactProblem, space: ContactSpace) -> None:
    """A pin holds before the impact: its relative velocity must already be zero."""
    for k in problem.constraints:
        if k.kind != "pin":
            continue
        v_a = problem.bodies[k.body].velocity_of_point(k.point)
        v_b = np.zeros(3) if k.other is None else problem.bodies[k.other].velocity_of_point(k.point)
        w = v_a - v_b
        tol = 1e-9 * (np.linalg.norm(v_a) + np.linalg.norm(v_b))
        if np.linalg.norm(w) > tol:
            raise InputError(
                f"{k.where}",
                "a pin needs zero relative velocity at its point before the impact "
                "(|w'| <= 1e-9 of the point speeds; type = \"fasten\" is the sudden constraint); "
                "relative velocity w' (m/s)",
                [float(x) for x in w],
            )


def _solve_rows(
    space: ContactSpace, idx: np.ndarray, rhs: np.ndarray, blocks: tuple[RowBlock, ...]
) -> tuple[np.ndarray, list[str]]:
    """Minimum-norm solution of ``G Lambda = rhs``; the names of redundant items, if any."""
    g = space.delassus(idx)
    eigval, eigvec = np.linalg.eigh(g)
    top = max(float(eigval[-1]), 0.0)
    keep = eigval > RANK_TOLERANCE * top if top > 0 else np.zeros_like(eigval, dtype=bool)
    inv = np.zeros_like(eigval)
    inv[keep] = 1.0 / eigval[keep]
    lam = eigvec @ (inv * (eigvec.T @ rhs))
    if np.all(keep):
        return lam, []
    owner = _row_owner(space, blocks)[idx]
    null = eigvec[:, ~keep]
    scale = float(np.linalg.norm(rhs)) + 1e-300
    residual = null @ (null.T @ rhs)
    if np.linalg.norm(residual) > CONFLICT_TOLERANCE * scale:
        involved = list(dict.fromkeys(owner[np.flatnonzero(np.abs(residual) > 1e-6 * scale)]))
        raise ConstraintConflictError(
            " and ".join(involved),
            "these contacts and constraints contradict each other: no impulse gives the "
            "velocities they require (for instance a point fastened and also required to "
            "rebound); relative residual",
            float(np.linalg.norm(residual) / scale),
        )
    involved_rows = np.flatnonzero(np.max(np.abs(null), axis=1) > 1e-6)
    return lam, list(dict.fromkeys(owner[involved_rows]))


def _row_owner(space: ContactSpace, blocks: tuple[RowBlock, ...]) -> np.ndarray:
    owner = np.empty(space.jacobian.shape[0], dtype=object)
    for block, rows in zip(blocks, space.slices, strict=True):
        owner[rows] = block.where
    return owner


def _relative_motion(
    problem: ImpactProblem, block: RowBlock, space: ContactSpace, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``w`` (m/s) and ``Omega`` (rad/s) at the block's point for the state ``u``."""
    w = np.zeros(3)
    omega = np.zeros(3)
    for name, sign in ((block.body_a, 1.0), (block.body_b, -1.0)):
        if name is None or problem.bodies[name].fixed:
            continue
        s = space.columns(name)
        body = problem.bodies[name]
        assert isinstance(body, RigidBody)
        v, om = u[s][:3], u[s][3:]
        w += sign * (v + _cross(om, block.point - body.position_com))
        omega += sign * om
    return w, omega


def _outcome(
    problem: ImpactProblem,
    items: list[PointContact | PointConstraint],
    space: ContactSpace,
    impulses: np.ndarray,
    u_after: np.ndarray,
    flags: list[Flag],
    processes: dict[int, FrictionalImpulse],
) -> ImpactResult:
    u_before = space.u_before
    outcomes: list[ItemOutcome] = []
    for index, (item, block, rows) in enumerate(
        zip(items, space.blocks, space.slices, strict=True)
    ):
        lam = impulses[rows]
        impulse = block.linear.T @ lam
        moment = block.angular.T @ lam
        w1, om1 = _relative_motion(problem, block, space, u_before)
        w2, om2 = _relative_motion(problem, block, space, u_after)
        if isinstance(item, PointContact):
            outcomes.append(
                _contact_outcome(item, impulse, moment, w1, w2, om1, om2, flags,
                                 processes.get(index))
            )  # fmt: skip
        else:
            d_n, d_t, d_m = theorem_terms(impulse, moment, None, w1, w2, om1, om2)
            outcomes.append(
                ItemOutcome(
                    where=item.where,
                    kind=item.kind,
                    a=item.body,
                    b=item.other,
                    point=item.point,
                    normal=None,
                    impulse=impulse,
                    moment=moment,
                    normal_impulse=None,
                    tangential_impulse=None,
                    regime=item.kind,
                    relative_velocity_before=w1,
                    relative_velocity_after=w2,
                    relative_angular_velocity_before=om1,
                    relative_angular_velocity_after=om2,
                    dissipated=d_n + d_t + d_m,
                    dissipated_normal=d_n,
                    dissipated_tangential=d_t,
                    dissipated_moment=d_m,
                )
            )
    bodies: dict[str, BodyMotion] = {}
    after_bodies: dict[str, RigidBody] = {}
    for name, body in problem.bodies.items():
        if isinstance(body, RigidBody):
            s = space.columns(name)
            after = body.with_motion(u_after[s][:3], u_after[s][3:])
            after_bodies[name] = after
            bodies[name] = BodyMotion(
                name=name,
                fixed=False,
                velocity_before=body.velocity_com,
                angular_velocity_before=body.angular_velocity,
                velocity_after=after.velocity_com,
                angular_velocity_after=after.angular_velocity,
            )
        else:
            zero = np.zeros(3)
            bodies[name] = BodyMotion(
                name=name,
                fixed=True,
                velocity_before=zero,
                angular_velocity_before=zero,
                velocity_after=zero,
                angular_velocity_after=zero,
            )
    # Direct route: Koenig's formula body by body, independent of the assembled M.
    e_before = sum(b.kinetic_energy() for b in problem.bodies.values() if isinstance(b, RigidBody))
    e_after = sum(b.kinetic_energy() for b in after_bodies.values())
    w_after = space.jacobian @ u_after
    contact_outcomes = tuple(o for o in outcomes if o.kind == "contact")
    ledger = EnergyLedger(
        before=e_before,
        after=e_after,
        dissipated=e_before - e_after,
        dissipated_theorem=sum(o.dissipated for o in outcomes),
        lost_velocities=lost_velocities(space.mass_matrix, u_before, u_after),
        carnot_defect=(e_before - e_after)
        - lost_velocities(space.mass_matrix, u_before, u_after),
        carnot_condition=-float(impulses @ w_after),
        dissipated_normal=sum(o.dissipated_normal for o in outcomes),
        dissipated_tangential=sum(o.dissipated_tangential for o in outcomes),
        dissipated_moment=sum(o.dissipated_moment for o in outcomes),
    )
    if ledger.dissipated < -1e-12 * max(e_before, 1e-300):
        cause = "".join(
            f"; {c.where} has Coulomb friction under {c.law.capitalize()}'s hypothesis, which "
            + ("can create energy when slip stops or reverses (Kane and Levinson's double "
               "pendulum, Stronge's rod); Stronge's energetic hypothesis never does"
               if c.law != "stronge" else "should not create energy: please report this")
            for k, c in enumerate(problem.contacts)
            if k in processes
        )  # fmt: skip
        flags.append(
            Flag(
                code="energy_gain",
                where="energy",
                message=f"the impact gains {-ledger.dissipated:.6g} J of kinetic energy{cause}",
            )
        )
    assert abs(kinetic_energy(space.mass_matrix, u_before) - e_before) <= 1e-9 * (e_before + 1)
    return ImpactResult(
        title=problem.title,
        bodies=bodies,
        contacts=contact_outcomes,
        constraints=tuple(o for o in outcomes if o.kind != "contact"),
        energy=ledger,
        momentum=_momentum_check(problem, space, u_after, outcomes),
        warnings=tuple(flags),
        row_impulses=impulses,
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
    process: FrictionalImpulse | None = None,
) -> ItemOutcome:
    n = item.normal
    p_n = float(impulse @ n)
    p_t = impulse - p_n * n
    d_n, d_t, d_m = theorem_terms(impulse, moment, n, w1, w2, om1, om2)
    scale = float(np.linalg.norm(impulse)) + float(np.linalg.norm(moment)) + 1e-300
    friction_required: float | None = None
    centre: np.ndarray | None = None
    if item.is_given:
        regime = "given"
    else:
        regime = "stick" if item.sticks else "frictionless"
        if process is not None:
            regime = process.regime
            _flag_process(item, process, flags)
        if float(n @ w1) >= 0.0:
            flags.append(
                Flag(
                    code="not_approaching",
                    where=item.where,
                    message=(
                        f"the bodies are not approaching at {item.where} (n . w' = "
                        f"{float(n @ w1):.6g} m/s >= 0); a contact law applied anyway"
                    ),
                )
            )
        if p_n < -1e-12 * scale:
            flags.append(
                Flag(
                    code="negative_normal_impulse",
                    where=item.where,
                    message=(
                        f"the normal impulse at {item.where} is {p_n:.6g} N s < 0: the contact "
                        "would have to pull; a unilateral contact cannot"
                    ),
                )
            )
        if item.sticks:
            friction_required = float(np.linalg.norm(p_t) / p_n) if p_n > 0 else float("inf")
            if item.friction > 0 and friction_required > item.friction * (1 + 1e-12):
                flags.append(
                    Flag(
                        code="friction_insufficient",
                        where=item.where,
                        message=(
                            f"sticking at {item.where} needs a friction coefficient of at "
                            f"least {friction_required:.6g}, more than the {item.friction:g} "
                            "given: the contact would slip"
                        ),
                    )
                )
        if item.patch is not None and p_n > 1e-12 * scale:
            centre = item.point + _cross(n, moment) / p_n
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
    return ItemOutcome(
        where=item.where,
        kind="contact",
        a=item.a,
        b=item.b,
        point=item.point,
        normal=n,
        impulse=impulse,
        moment=moment,
        normal_impulse=p_n,
        tangential_impulse=p_t,
        regime=regime,
        relative_velocity_before=w1,
        relative_velocity_after=w2,
        relative_angular_velocity_before=om1,
        relative_angular_velocity_after=om2,
        dissipated=d_n + d_t + d_m,
        dissipated_normal=d_n,
        dissipated_tangential=d_t,
        dissipated_moment=d_m,
        friction_required=friction_required,
        centre_of_pressure=centre,
        law=None if item.is_given else item.law,
        process=process,
    )


def _flag_process(item: PointContact, process: FrictionalImpulse, flags: list[Flag]) -> None:
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

    from carnot.conventions import contact_frame

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


def _momentum_check(
    problem: ImpactProblem, space: ContactSpace, u_after: np.ndarray, outcomes: list[ItemOutcome]
) -> MomentumCheck:
    du = u_after - space.u_before
    lin_change = np.zeros(3)
    ang_change = np.zeros(3)
    lin_scale = 0.0
    ang_scale = 0.0
    for name in space.movable:
        body = problem.bodies[name]
        assert isinstance(body, RigidBody)
        s = space.columns(name)
        dv, dom = du[s][:3], du[s][3:]
        lin_change += body.mass * dv
        moment_of_dv = _cross(body.position_com, body.mass * dv)
        ang_change += body.inertia_com @ dom + moment_of_dv
        lin_scale += body.mass * float(np.linalg.norm(space.u_before[s][:3]) + np.linalg.norm(dv))
        ang_scale += float(
            np.linalg.norm(body.angular_momentum_about(np.zeros(3)))
            + np.linalg.norm(body.inertia_com @ dom)
            + np.linalg.norm(moment_of_dv)
        )
    lin_ext = np.zeros(3)
    ang_ext = np.zeros(3)
    for o in outcomes:
        a_moves = not problem.bodies[o.a].fixed
        b_moves = o.b is not None and not problem.bodies[o.b].fixed
        if a_moves == b_moves:
            continue  # internal to the movable set, or (impossible) between fixed bodies
        sign = 1.0 if a_moves else -1.0
        lin_ext += sign * o.impulse
        ang_ext += sign * (_cross(o.point, o.impulse) + o.moment)
    return MomentumCheck(
        linear_change=lin_change,
        linear_external=lin_ext,
        angular_change=ang_change,
        angular_external=ang_ext,
        linear_residual=float(np.linalg.norm(lin_change - lin_ext) / (lin_scale + 1e-300)),
        angular_residual=float(np.linalg.norm(ang_change - ang_ext) / (ang_scale + 1e-300)),
    )


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` of two 3-vectors, written out: ``np.cross`` spends about 25 us a call on its
    axis handling (this: under 1 us), which made it a third of a frictionless solve.

    >>> _cross(np.array([1.0, 0, 0]), np.array([0, 1.0, 0])).tolist()
    [0.0, 0.0, 1.0]
    """
    a_x, a_y, a_z = np.asarray(a, dtype=float).tolist()
    b_x, b_y, b_z = np.asarray(b, dtype=float).tolist()
    return np.array([a_y * b_z - a_z * b_y, a_z * b_x - a_x * b_z, a_x * b_y - a_y * b_x])

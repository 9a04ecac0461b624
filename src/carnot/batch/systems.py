"""Many impacts of systems in generalized coordinates at once: stacked ``M``, ``q'`` and
contact Jacobians (one model over many states), frictionless, sticking or with Coulomb
friction (slip, stick and reversal: :func:`solve_systems` with ``friction``).

The same contact space as the single impact (:mod:`carnot.model.system`), array by array over
a leading batch axis ``B``:

    W = rows of each contact (n^T J; with stick also t1^T J, t2^T J in the contact frame of
        conventions.contact_frame),      G = W M^-1 W^T,
    Lambda = G^+ (target(w') - w'),      q'' = q' + M^-1 W^T Lambda,

the target from the one equality law (:func:`carnot.laws.target_velocity`: ``-e w_n`` on
normal rows, 0 on tangent rows) and ``G^+`` the pseudo-inverse (eigenvalues under
``RANK_TOLERANCE`` of the largest dropped), so that rows that move nothing (a planar model's
out-of-plane tangent) take no impulse, as the single path's dropped rows. Energies by both
routes: ``E = 1/2 q'^T M q'`` before and after, and the theorem ``-1/2 Lambda . (w' + w'')``.
The answers equal :func:`carnot.solve_impact`'s (tested to 1e-12).

**Coulomb friction** (``friction > 0`` without ``stick``): the contact's rows in its frame
``(n, t1, t2)``, ``K = W M^-1 W^T`` (3 x 3) and ``w' = W q'`` go to the batch Coulomb law
(:func:`carnot.batch.coulomb.coulomb`, the single engine's rules: Darboux-Keller integration
in impulse space under Newton's, Poisson's or Stronge's hypothesis), and ``q'' = q' + M^-1
W^T P``. A tangent direction that no motion reaches (a planar model's out-of-plane tangent,
``K_tt d = 0``) gets the single path's decoupled stand-in ``K_nn d d^T`` and no impulse
(:func:`carnot.solve._unreached_tangents`, the same rule).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from carnot.batch.coulomb import HYPOTHESES as _COULOMB_LAWS
from carnot.batch.coulomb import coulomb
from carnot.batch.laws import FRICTIONLESS, STICK
from carnot.errors import InputError
from carnot.laws import target_velocity
from carnot.space import RANK_TOLERANCE, Role

#: The restitution hypotheses of the Coulomb law (``law``), by name.
HYPOTHESES = {name.removeprefix("coulomb_"): code for name, code in _COULOMB_LAWS.items()}


@dataclass(frozen=True, kw_only=True, eq=False)
class SystemBatch:
    """``velocity_after`` (B, n), ``impulses`` (B, c, 3) world impulses per contact (N s),
    ``energy_before``, ``energy_after``, ``dissipated_theorem`` (B,) in J; ``degenerate``
    (B,): states whose ``G`` had an eigenvalue dropped beyond the rows that move nothing at
    all (redundant or nearly singular rows: the single path warns or refuses there);
    ``ledger_not_closed`` (B,): states whose theorem and direct difference disagree beyond
    1e-9 of the kinetic energies (a nearly singular ``G`` left too few digits: the single
    path flags the same, ``ledger_not_closed``). Neither is returned silently as a number.
    ``regime`` (B,): the contact's regime code (:data:`carnot.batch.laws.REGIME_NAMES`:
    frictionless, stick, or the Coulomb law's slip, slip-stick, slip-reversal,
    slip-redirected, none); ``law_flags`` (B,): the Coulomb law's warning bits
    (:data:`carnot.batch.coulomb.NORMAL_WORK_GAIN`, ``HYPOTHESIS_ENERGY_GAIN``: Kane and
    Levinson's energy gain, ``JAM``, ``STEP_LIMIT``; 0 without friction).
    """

    velocity_after: np.ndarray
    impulses: np.ndarray
    energy_before: np.ndarray
    energy_after: np.ndarray
    dissipated_theorem: np.ndarray
    degenerate: np.ndarray
    ledger_not_closed: np.ndarray
    regime: np.ndarray | None = None
    law_flags: np.ndarray | None = None


def contact_frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`carnot.conventions.contact_frame` over arrays of normals (..., 3).

    >>> [t.tolist() for t in contact_frames(np.array([[0.0, 0.0, 2.0]]))]
    [[[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]]
    """
    n = normals / np.linalg.norm(normals, axis=-1, keepdims=True)
    axis = np.zeros_like(n)
    np.put_along_axis(axis, np.argmin(np.abs(n), axis=-1)[..., None], 1.0, axis=-1)
    t1 = axis - np.sum(axis * n, axis=-1, keepdims=True) * n
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    return n, t1, np.cross(n, t1)


def solve_systems(
    mass_matrix: np.ndarray,
    velocity: np.ndarray,
    jacobians: np.ndarray,
    normals: np.ndarray,
    restitution: np.ndarray | float,
    *,
    stick: bool = False,
    friction: np.ndarray | float = 0.0,
    law: str = "newton",
) -> SystemBatch:
    """Impacts of ``B`` states: ``mass_matrix`` (B, n, n), ``velocity`` (B, n),
    ``jacobians`` (B, c, 3, n), ``normals`` (B, c, 3), ``restitution`` (c,) or (B, c);
    ``stick``: every contact sticks; else ``friction`` (mu, a number, (c,) or (B, c)):
    Coulomb friction where it is positive, under the hypothesis ``law`` (``newton``,
    ``poisson``, ``stronge``; module docstring), frictionless where it is 0. One contact per
    state (c = 1): several are a complementarity problem, refused here.

    A point mass of 2 kg dropping on the floor at 1 m/s, e = 0.5:

    >>> out = solve_systems(np.eye(2)[None] * 2, np.array([[0.3, -1.0]]),
    ...     np.array([[[[1.0, 0], [0, 1], [0, 0]]]]), np.array([[[0, 1.0, 0]]]), 0.5)
    >>> out.velocity_after.tolist(), out.dissipated_theorem.round(12).tolist()
    ([[0.3, 0.5]], [0.75])
    """
    batch, contacts = normals.shape[:2]
    if contacts > 1:
        # several unilateral contacts are a complementarity problem (DESIGN.md section 6),
        # which the single path solves with the simultaneous law; these equalities would be
        # another law's answer, so they are refused rather than returned
        raise InputError(
            "normals",
            "several contacts per state need the simultaneous law (a contact may separate): "
            "solve them with carnot.solve_impact per state; this batch takes one contact, "
            "frictionless or sticking",
            contacts,
        )
    if law not in HYPOTHESES:
        raise InputError("law", f"must be one of {', '.join(HYPOTHESES)}", law)
    mu = np.broadcast_to(np.asarray(friction, dtype=float), (batch, contacts))
    if not np.all(mu >= 0):  # NaN too
        raise InputError("friction", "must be >= 0 (a Coulomb coefficient)", mu[~(mu >= 0)][:3])
    if not stick and np.any(mu > 0):
        return _coulomb_systems(mass_matrix, velocity, jacobians[:, 0], normals[:, 0],
                                restitution, mu[:, 0], HYPOTHESES[law])  # fmt: skip
    n, t1, t2 = contact_frames(normals)
    axes = np.stack([n, t1, t2], axis=2) if stick else n[:, :, None, :]  # (B, c, r, 3)
    per = axes.shape[2]
    w_rows = np.einsum("bcri,bcin->bcrn", axes, jacobians).reshape(batch, contacts * per, -1)
    roles: list[Role] = (["normal"] + ["tangent"] * (per - 1)) * contacts
    e = np.broadcast_to(np.asarray(restitution, dtype=float), (batch, contacts))
    e_rows = np.repeat(e, per, axis=1)
    w_before = np.einsum("bmn,bn->bm", w_rows, velocity)
    m_inv_wt = np.linalg.solve(mass_matrix, np.swapaxes(w_rows, 1, 2))  # (B, n, m)
    g = w_rows @ m_inv_wt
    g = 0.5 * (g + np.swapaxes(g, 1, 2))
    eigval, eigvec = np.linalg.eigh(g)
    top = np.maximum(eigval[:, -1:], 0.0)
    keep = eigval > RANK_TOLERANCE * top
    dead = np.sum(
        np.all(np.abs(w_rows) <= 1e-10 * np.abs(w_rows).max(axis=(1, 2), keepdims=True), axis=2),
        axis=1,
    )  # rows that move nothing: dropped, not degenerate
    inv = np.where(keep, 1.0 / np.where(keep, eigval, 1.0), 0.0)
    rhs = target_velocity(w_before, roles, e_rows) - w_before
    lam = np.einsum("bij,bj,bkj,bk->bi", eigvec, inv, eigvec, rhs)
    after = velocity + np.einsum("bnm,bm->bn", m_inv_wt, lam)
    w_after = np.einsum("bmn,bn->bm", w_rows, after)
    impulses = np.einsum("bcr,bcri->bci", lam.reshape(batch, contacts, per), axes)
    energy = 0.5 * np.einsum("bi,bij,bj->b", velocity, mass_matrix, velocity)
    energy_after = 0.5 * np.einsum("bi,bij,bj->b", after, mass_matrix, after)
    theorem = -0.5 * np.sum(lam * (w_before + w_after), axis=1)
    gap = np.abs(energy - energy_after - theorem)
    closes = gap <= 1e-9 * (np.abs(energy) + np.abs(energy_after))
    return SystemBatch(velocity_after=after, impulses=impulses, energy_before=energy,
                       energy_after=energy_after, dissipated_theorem=theorem,
                       degenerate=np.sum(~keep, axis=1) > dead,
                       ledger_not_closed=~closes,
                       regime=np.full(batch, STICK if stick else FRICTIONLESS, dtype=np.int8),
                       law_flags=np.zeros(batch, dtype=np.int8))  # fmt: skip


def _coulomb_systems(mass_matrix: np.ndarray, velocity: np.ndarray, jacobian: np.ndarray,
                     normal: np.ndarray, restitution: np.ndarray | float, mu: np.ndarray,
                     hypothesis: int) -> SystemBatch:  # fmt: skip
    """One contact with Coulomb friction per state (module docstring): ``jacobian`` (B, 3,
    n), ``normal`` (B, 3), ``mu`` (B,)."""
    batch = normal.shape[0]
    axes = np.stack(contact_frames(normal), axis=1)  # (B, 3, 3): rows n, t1, t2
    w_rows = axes @ jacobian  # (B, 3, n)
    m_inv_wt = np.linalg.solve(mass_matrix, np.swapaxes(w_rows, 1, 2))  # (B, n, 3)
    k = w_rows @ m_inv_wt
    k = 0.5 * (k + np.swapaxes(k, 1, 2))
    w_before = np.einsum("bmn,bn->bm", w_rows, velocity)
    k_law, w_law = _unreached_tangents(k, w_before)
    e = np.broadcast_to(np.asarray(restitution, dtype=float).reshape(-1), (batch,))
    out = coulomb(
        (k_law[:, 0, 0], k_law[:, 0, 1], k_law[:, 0, 2], k_law[:, 1, 1], k_law[:, 1, 2],
         k_law[:, 2, 2]),
        (w_law[:, 0], w_law[:, 1], w_law[:, 2]), np.ascontiguousarray(e), mu, hypothesis,
    )  # fmt: skip
    lam = np.stack([np.asarray(x, dtype=float) for x in out[:3]], axis=1)  # (B, 3)
    after = velocity + np.einsum("bnm,bm->bn", m_inv_wt, lam)
    w_after = np.einsum("bmn,bn->bm", w_rows, after)
    energy = 0.5 * np.einsum("bi,bij,bj->b", velocity, mass_matrix, velocity)
    energy_after = 0.5 * np.einsum("bi,bij,bj->b", after, mass_matrix, after)
    theorem = -0.5 * np.sum(lam * (w_before + w_after), axis=1)
    gap = np.abs(energy - energy_after - theorem)
    closes = gap <= 1e-9 * (np.abs(energy) + np.abs(energy_after))
    eig = np.linalg.eigvalsh(k)
    flags = np.asarray(out[9]).astype(np.int8)
    return SystemBatch(velocity_after=after, impulses=np.einsum("bm,bmi->bi", lam, axes)[:, None],
                       energy_before=energy, energy_after=energy_after,
                       dissipated_theorem=theorem,
                       degenerate=~(k[:, 0, 0] > RANK_TOLERANCE * eig[:, -1]),
                       ledger_not_closed=~closes,
                       regime=np.asarray(out[3]).astype(np.int8), law_flags=flags)  # fmt: skip


def _unreached_tangents(k: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`carnot.solve._unreached_tangents` over a batch: where exactly one tangent
    direction ``d`` has ``K_tt d = 0`` (below ``RANK_TOLERANCE`` of ``trace K``), ``K``
    becomes ``P K P + K_nn d d^T`` and ``w'`` becomes ``P w'`` (``P = I - d d^T``)."""
    eigval, eigvec = np.linalg.eigh(k[:, 1:, 1:])
    trace = np.trace(k, axis1=1, axis2=2)
    dead = (eigval[:, 0] <= RANK_TOLERANCE * trace) & (eigval[:, 1] > RANK_TOLERANCE * trace)
    if not np.any(dead):
        return k, w
    d = np.zeros((int(np.sum(dead)), 3))
    d[:, 1:] = eigvec[dead, :, 0]
    keep = np.eye(3) - np.einsum("bi,bj->bij", d, d)
    k, w = k.copy(), w.copy()
    k[dead] = keep @ k[dead] @ keep + k[dead, 0, 0][:, None, None] * np.einsum("bi,bj->bij", d, d)
    w[dead] = np.einsum("bij,bj->bi", keep, w[dead])
    return k, w

"""The energy ledger: the direct difference and the theorem, side by side.

Paper eq. (11) (two bodies), (15) (with a moment impulse) and (16) (a fixed obstacle), written
with the conventions of ``conventions.py``:

    E_d = E' - E'' = -1/2 sum [P . (w' + w'') + M_P . (Omega' + Omega'')]

and Carnot's kinetic energy of the lost velocities (paper eq. 13)

    E_p = 1/2 du^T M du,     E_d - E_p = -sum [P . w'' + M_P . Omega'']   (paper eq. 12).
"""

from __future__ import annotations

import numpy as np


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
    w_sum = w_before + w_after
    moment_part = -0.5 * float(moment @ (omega_rel_before + omega_rel_after))
    if normal is None:
        return -0.5 * float(impulse @ w_sum) + 0.0, 0.0, moment_part + 0.0
    p_n = float(impulse @ normal)
    normal_part = -0.5 * p_n * float(normal @ w_sum)
    tangential_part = -0.5 * float((impulse - p_n * normal) @ w_sum)
    return normal_part + 0.0, tangential_part + 0.0, moment_part + 0.0

"""The rows where the multi-contact batch and ``carnot.solve_impact`` disagree (issue 14), with
what each side answered and whether each answer is a genuine solution of the law.

Inputs: ``same_answers.py``'s cases (the box of :func:`bench_batch_multi.box` landing on four
corners, by default the "tilted sticking" one: mu 1.5, the ground normal tilted by up to
0.05 rad so that corners lift and the regimes mix). For every row whose regimes, flags or
velocities (to ``--tol`` m/s) differ, it prints both sides' regimes, flags, velocities after
and complementarity residuals, and for each side's answer the law's conditions evaluated here
from the Delassus matrix (NumPy, independent of both solvers: :func:`law_violation`), so a
row tells whether one side missed a genuine solution that the other found (a non-unique
problem, both answers valid) or whether one side's answer is wrong. It also says where each
side's regime stands in the law's order of trial and whether the reference's root finder
(MINPACK) finds the other side's regime.

Run: ``.venv/bin/python benchmarks/tilt_differences.py [--n 100] [--case "tilted sticking"]``.
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact  # noqa: E402
from carnot.batch import BatchBodies  # noqa: E402
from carnot.batch.multi import REGIME_NAMES, multi_impacts  # noqa: E402
from carnot.conventions import contact_frame  # noqa: E402


def delassus(mass: float, inertia: np.ndarray, x: np.ndarray, v: np.ndarray, om: np.ndarray,
             points: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                              np.ndarray]:  # fmt: skip
    """``G = W M^-1 W^T`` (1/kg), ``w' = W (v, omega)`` (m/s) and the frames ``(k, 3, 3)`` of a
    free body on a fixed ground, rows ``(n, t1, t2)`` per contact: the textbook assembly,
    written here apart from the kernel's and the law's."""
    frames = np.array([np.array(contact_frame(n)) for n in normals])
    rows = []
    for p, f in zip(points, frames, strict=True):
        r = p - x
        rows += [np.concatenate([d, np.cross(r, d)]) for d in f]
    jac = np.array(rows)
    minv = np.zeros((6, 6))
    minv[:3, :3] = np.eye(3) / mass
    minv[3:, 3:] = np.linalg.inv(inertia)
    return jac @ minv @ jac.T, jac @ np.concatenate([v, om]), frames


def law_violation(g: np.ndarray, w: np.ndarray, e: np.ndarray, mu: np.ndarray,
                  p: np.ndarray) -> float:  # fmt: skip
    """The largest violation (m/s; impulses times the largest diagonal entry of ``G``) of the
    simultaneous law by row impulses ``p`` (three rows per contact: n, t1, t2): a contact
    separating before receives nothing; ``0 <= P_n ⟂ w_n'' + e w_n' >= 0``; ``|P_t| <= mu
    P_n``; where it slips after (``|w_t''| > 1e-9`` of the velocity scale), ``P_t = -mu P_n
    w_t'' / |w_t''|`` (Glocker 2001, ch. 7: Coulomb's law at impact)."""
    scale = float(np.max(np.abs(w))) or 1.0
    gmax = float(np.max(np.diag(g)))
    after = w + g @ p
    worst = 0.0
    for c in range(len(e)):
        n, t = 3 * c, [3 * c + 1, 3 * c + 2]
        if w[n] > 1e-9 * scale:  # separating before: takes no part
            worst = max(worst, float(np.max(np.abs(p[3 * c:3 * c + 3]))) * gmax)
            continue
        a, b = p[n] * gmax, after[n] + e[c] * w[n]
        worst = max(worst, abs(min(a, b)))
        pt = p[t]
        worst = max(worst, (float(np.hypot(*pt)) - mu[c] * p[n]) * gmax)
        slip = float(np.hypot(*after[t]))
        if slip > 1e-9 * scale:
            worst = max(worst, float(np.max(np.abs(pt + mu[c] * p[n] * after[t] / slip))) * gmax)
    return worst


def law_order(g: np.ndarray, w: np.ndarray, e: np.ndarray, mu: np.ndarray) -> list[str]:
    """The regimes in the reference's order of trial (its first pass, the cones by their
    inscribed polygons), as '/'-joined names; 'out' for a contact separating before."""
    from carnot.conventions import RELATIVE_TOLERANCE
    from carnot.laws.multiple import ContactRows
    from carnot.laws.multiple.rows import velocity_scale
    from carnot.laws.multiple.simultaneous import _OPTIONS, _nearest_first, _predict

    contacts = tuple(ContactRows(normal=3 * c, tangents=(3 * c + 1, 3 * c + 2),
                                 restitution=float(e[c]), friction=float(mu[c]))
                     for c in range(len(e)))  # fmt: skip
    scale = velocity_scale(w, None)
    part = [i for i, c in enumerate(contacts) if w[c.normal] <= RELATIVE_TOLERANCE * scale]
    options = [_OPTIONS[contacts[i].kind] for i in part]
    ordered, _, overloaded = _predict(g, w, contacts, None, part, options, scale)
    base = tuple(o[0] for o in options)
    guess = tuple(o[0] for o in ordered)
    slid = tuple("slip" if o == "stick" else o for o in guess)
    first = [slid, guess, base] if overloaded else [base, slid, guess]
    names = []
    for choice in itertools.chain(dict.fromkeys(first),
                                  _nearest_first(ordered, slid, (base, guess, slid))):
        pattern = ["out"] * len(contacts)
        for i, o in zip(part, choice, strict=True):
            pattern[i] = o
        names.append("/".join(pattern))
    return names


def minpack_holds(g: np.ndarray, w: np.ndarray, e: np.ndarray, mu: np.ndarray,
                  pattern: str) -> int:
    """How many answers the reference's ``_solve_regime`` (MINPACK's hybr) finds in a regime."""
    from carnot.conventions import RELATIVE_TOLERANCE
    from carnot.laws.multiple import ContactRows
    from carnot.laws.multiple.rows import velocity_scale
    from carnot.laws.multiple.simultaneous import _OPTIONS, _predict, _solve_regime

    contacts = tuple(ContactRows(normal=3 * c, tangents=(3 * c + 1, 3 * c + 2),
                                 restitution=float(e[c]), friction=float(mu[c]))
                     for c in range(len(e)))  # fmt: skip
    scale = velocity_scale(w, None)
    part = [i for i, c in enumerate(contacts) if w[c.normal] <= RELATIVE_TOLERANCE * scale]
    _, predicted, _ = _predict(g, w, contacts, None, part,
                               [_OPTIONS[contacts[i].kind] for i in part], scale)
    return len(_solve_regime(g, w, contacts, None, tuple(pattern.split("/")), scale,
                             predicted, False))


def regime_names(regimes: np.ndarray) -> str:
    """The batch's regimes with the law's names ('closed' is the law's frictionless name;
    'out': separating before)."""
    return "/".join(REGIME_NAMES[int(r)] for r in regimes.tolist())


def pattern_free(name: str) -> str:
    return name.replace("frictionless", "closed")


def main() -> None:
    from same_answers import cases

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100)
    parser.add_argument("--case", default="tilted sticking")
    parser.add_argument("--tol", type=float, default=1e-9, help="velocities, m/s")
    parser.add_argument("--rows", help="comma-separated rows to show (default: differing)")
    args = parser.parse_args()
    body, points, normals, e, mu = cases(args.n)[args.case]
    out = multi_impacts(BatchBodies(**body), None, points, normals, e, mu)
    batch_v = np.concatenate([out.velocity_a, out.angular_velocity_a], axis=1)
    flag_names = ("statically_indeterminate", "multiple_solutions", "no_solution",
                  "separating_contact_approaches", "energy_gain")  # fmt: skip
    shown = 0
    rows = range(args.n) if not args.rows else [int(r) for r in args.rows.split(",")]
    for i in rows:
        contacts = [PointContact(a="body", b="ground", point=points[i, k], normal=normals[i, k],
                                 restitution=float(e[i, k]), friction=float(mu[i, k]),
                                 where=f"contacts[{k}]") for k in range(points.shape[1])]
        rigid = RigidBody(name="body", mass=float(body["mass"][i]),
                          inertia_com=body["inertia_com"][i], position_com=body["position_com"][i],
                          velocity_com=body["velocity_com"][i],
                          angular_velocity=body["angular_velocity"][i])  # fmt: skip
        res = solve_impact(ImpactProblem(bodies={"body": rigid, "ground": FixedBody(name="ground")},
                                         contacts=contacts))  # fmt: skip
        after = res.bodies["body"]
        api_v = np.concatenate([after.velocity_after, after.angular_velocity_after])
        g, w, frames = delassus(float(body["mass"][i]), body["inertia_com"][i],
                                body["position_com"][i], body["velocity_com"][i],
                                body["angular_velocity"][i], points[i], normals[i])  # fmt: skip
        api_regime = "/".join(c.regime for c in res.contacts)
        b_regime = regime_names(out.regime[i])
        api_flags = sorted(f for f in res.flag_codes() if f in flag_names)
        b_flags = sorted(f for f in flag_names if bool(getattr(out, f)[i]))
        if not out.uniqueness_verified[i]:
            b_flags.append("(unverified)")
        same = (pattern_free(api_regime) == pattern_free(b_regime)
                and api_flags == [f for f in b_flags if not f.startswith("(")]
                and np.max(np.abs(api_v - batch_v[i])) <= args.tol)
        if same and not args.rows:
            continue
        shown += 1
        p_b = np.einsum("kij,kj->ki", frames, out.impulse[i]).ravel()
        p_a = np.einsum("kij,kj->ki", frames, np.array([c.impulse for c in res.contacts])).ravel()
        order = law_order(g, w, e[i], mu[i])

        def pattern(name: str, w: np.ndarray = w) -> str:
            """The law's pattern of a regime ('out': separating before)."""
            scale = float(np.max(np.abs(w)))
            return "/".join("out" if w[3 * c] > 1e-9 * scale else
                            r.replace("frictionless", "closed")
                            for c, r in enumerate(name.split("/")))

        def place(name: str, order: list[str] = order) -> str:
            key = pattern(name)
            return str(order.index(key)) if key in order else "?"

        print(f"row {i}: by_reference {bool(out.by_reference[i])}")
        for label, reg, flags, vel, resid, p in (
                ("batch", b_regime, b_flags, batch_v[i], float(out.residual[i]), p_b),
                ("api  ", api_regime, api_flags, api_v, res.complementarity_residual, p_a)):
            violation = law_violation(g, w, e[i], mu[i], p)
            roots = minpack_holds(g, w, e[i], mu[i], pattern(reg))
            print(f"  {label} {reg:30s} (tried #{place(reg)}) flags {flags} residual "
                  f"{resid:.1e}\n        v'' {np.array2string(vel, precision=6)}\n"
                  f"        law violation (here, from G) {violation:.1e} m/s; "
                  f"MINPACK finds this regime: {roots}")
        print(f"  max |v_batch - v_api| {np.max(np.abs(api_v - batch_v[i])):.2e} m/s")
    print(f"{shown} of {len(rows)} rows shown ({args.case})")


if __name__ == "__main__":
    main()

"""Systems in motion (issue 34): a compass-gait step, a limit cycle with its multipliers, and a
100-slope bifurcation sweep, against a plain SciPy event loop on the same walker in the same
run.

* **The baseline**: the compass gait written by hand as the textbooks do (Goswami, Thuilot and
  Espiau 1996: ``M(q) q'' + C(q, q') q' + G(q) = 0`` in closed form, the heel strike by their
  ``Q+ / Q-`` matrices), integrated by ``scipy.integrate.solve_ivp`` (DOP853, the same
  tolerance 1e-12) with a terminal heel-strike event, one step from the same state.
* **carnot**: :func:`carnot.hybrid.cycle.return_map` on the named model (the flow compiled
  from the model's SymPy mechanism, the strike one :func:`carnot.solve_impact` with its
  ledger). Targets: a step <= 2 ms; a limit cycle with its multipliers <= 0.2 s; a 100-slope
  bifurcation sweep <= 60 s on 2 cores.

Run: ``.venv/bin/python benchmarks/bench_walkers.py [--slopes 100]``.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp
from timing import best_of

from carnot.hybrid.cycle import find_cycle, return_map
from carnot.hybrid.models import named_model

M, MH, A, B, SLOPE, G = 5.0, 10.0, 0.5, 0.5, 0.0524, 9.81
L = A + B
#: The period-one gait just after heel strike (stance, swing, rates), carnot's coordinates.
GAIT = np.array([-0.218699145234, 0.323499145234, 1.092522156319, 0.377019189923])


def _hand_flow(t: float, y: np.ndarray) -> list[float]:
    """Goswami et al.'s equations in (stance, swing) angles from the vertical, a leg's hip end
    at (l sin q, l cos q) from its foot."""
    st, sw, dst, dsw = y
    c = math.cos(st - sw)
    s = math.sin(st - sw)
    m11 = (MH + M) * L**2 + M * A**2
    m12 = -M * L * B * c
    m22 = M * B**2
    h1 = -M * L * B * s * dsw**2 - (MH * L + M * A + M * L) * G * math.sin(st)
    h2 = M * L * B * s * dst**2 + M * B * G * math.sin(sw)
    det = m11 * m22 - m12 * m12
    return [dst, dsw, (-m22 * h1 + m12 * h2) / det, (m12 * h1 - m11 * h2) / det]


def _strike_event(t: float, y: np.ndarray) -> float:
    return y[0] + y[1] - 2 * SLOPE if y[0] - y[1] > 0 else -1.0  # armed past mid-stance


_strike_event.terminal = True  # type: ignore[attr-defined]
_strike_event.direction = 1  # type: ignore[attr-defined]


def _hand_transition(y: np.ndarray) -> np.ndarray:
    st, sw, dst, dsw = y
    c = math.cos(st - sw)  # cos 2 alpha
    q_minus = np.array([[-M * A * B, -M * A * B + (MH * L**2 + 2 * M * A * L) * c],
                        [0.0, -M * A * B]])  # fmt: skip
    q_plus = np.array([[M * B * (B - L * c), M * L * (L - B * c) + M * A**2 + MH * L**2],
                       [M * B**2, -M * B * L * c]])  # fmt: skip
    # Goswami's (theta_ns, theta_s) run the other way round: theta = -q, ns = swing
    new = np.linalg.solve(q_plus, q_minus @ -np.array([dsw, dst]))
    return np.array([sw, st, -new[1], -new[0]])


def hand_step(y0: np.ndarray) -> np.ndarray:
    sol = solve_ivp(_hand_flow, (0.0, 5.0), y0, method="DOP853", rtol=1e-12, atol=1e-12,
                    events=_strike_event)  # fmt: skip
    return _hand_transition(sol.y_events[0][0])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--slopes", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args()
    print(f"python {platform.python_version()}, {os.cpu_count()} cores")
    walker = named_model("compass_gait")
    ours = return_map(walker, GAIT).x
    theirs = hand_step(GAIT)
    print(f"the two routes' step agree to {np.max(np.abs(ours - theirs)):.1e}")
    t_hand = best_of(lambda: hand_step(GAIT), args.repeat)
    t_ours = best_of(lambda: return_map(walker, GAIT), args.repeat)
    print(f"compass-gait step: carnot {t_ours * 1e3:.2f} ms, plain SciPy loop "
          f"{t_hand * 1e3:.2f} ms ({t_ours / t_hand:.2f}x; target <= 2 ms)")  # fmt: skip
    guess = np.array([-0.2187, 0.3234, 1.0918, 0.3772])
    t_cycle = best_of(lambda: find_cycle(walker, guess), 5)
    c = find_cycle(walker, guess)
    print(f"limit cycle with multipliers: {t_cycle * 1e3:.0f} ms ({c.iterations} Newton steps, "
          f"residual {c.residual:.1e}; target <= 200 ms)")  # fmt: skip
    from carnot.sweep import sweep_file

    with tempfile.TemporaryDirectory() as tmp:
        began = time.perf_counter()
        report = sweep_file("examples/motion/compass_gait.toml", f"{tmp}/slopes.csv",
                            vary=[f"model.parameters.slope=0.01:0.08:{args.slopes}"],
                            workers=2)  # fmt: skip
        wall = time.perf_counter() - began
    print(f"{args.slopes}-slope bifurcation sweep: {wall:.1f} s on 2 processes "
          f"({report.failed} rows without an orbit; target <= 60 s)")  # fmt: skip


if __name__ == "__main__":
    main()

"""Pictures of a model in motion (matplotlib, imported only when a picture is asked for):

* :func:`plot_cycle`: a periodic orbit's phase portrait (each coordinate against its rate
  over one period, the strikes' jumps drawn as dashed segments) beside its coordinates over
  time;
* :func:`plot_run`: a run's energy per strike (what each strike took, against the strike's
  number: a walker settling onto its gait) and its phase portrait.

The curves between strikes are sampled from the integrator's own dense output
(:func:`sampled`), so that a picture shows the flow carnot integrated.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from carnot.errors import InputError
from carnot.hybrid.flow import TOLERANCE, Hold, held_flow
from carnot.hybrid.model import HybridModel, require_velocity_chart
from carnot.plot_sweep import save_figure

#: Samples per leg of the flow.
SAMPLES = 200


def sampled(model: HybridModel, x0: np.ndarray, t0: float, t1: float,
            samples: int = SAMPLES, held: tuple[Hold, ...] = (),
            friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The flow from ``(t0, x0)`` sampled at ``samples`` times up to ``t1`` (s): the times
    and the states (samples x 2n), from SciPy's DOP853 at the integrator's tolerance, with
    the contacts ``held`` held (:func:`carnot.hybrid.flow.held_flow`)."""
    from scipy.integrate import solve_ivp

    def rate(_: float, y: np.ndarray) -> np.ndarray:
        return held_flow(model, held, y, friction)[0] if held else model.mechanism.flow(y)

    t = np.linspace(t0, t1, samples)
    sol = solve_ivp(rate, (t0, t1), x0, method="DOP853", rtol=TOLERANCE, atol=TOLERANCE,
                    t_eval=t)  # fmt: skip
    return sol.t, sol.y.T


def _portrait(axes: Any, model: HybridModel, legs: list[tuple[np.ndarray, np.ndarray]],
              jumps: list[tuple[np.ndarray, np.ndarray]]) -> None:  # fmt: skip
    n = model.n
    colours = ("#1f4e9c", "#c0392b", "#2e8b57", "#8e44ad")
    for k, name in enumerate(model.coordinates):
        colour = colours[k % len(colours)]
        for i, (_, xs) in enumerate(legs):
            axes.plot(xs[:, k], xs[:, n + k], color=colour, linewidth=1.4,
                      label=name if i == 0 else None)  # fmt: skip
        for before, after in jumps:
            axes.plot([before[k], after[k]], [before[n + k], after[n + k]], color=colour,
                      linestyle="--", linewidth=0.8)  # fmt: skip
    axes.set_xlabel("coordinate (rad or m)")
    axes.set_ylabel("rate (per s)")
    axes.grid(True, color="0.9", linewidth=0.6)
    axes.legend(loc="best", fontsize=9)


def plot_cycle(cycle: Any, path: str | Path | None = None) -> Figure:
    """A periodic orbit (a :class:`carnot.hybrid.cycle.Cycle` that converged): its phase
    portrait and its coordinates over one period."""
    model = cycle.model
    if not cycle.converged:
        raise InputError("--plot", "draws a periodic orbit: none was found", show_value=False)
    from carnot.hybrid.flow import fly

    legs, jumps = [], []
    x, t = np.array(cycle.state, dtype=float), 0.0
    for s in cycle.strikes:
        leg = fly(model, x, t, t + 100.0)
        legs.append(sampled(model, x, t, leg.t1))
        jumps.append((s.x_before, s.x_after))
        x, t = s.x_after, leg.t1
    fig = Figure(figsize=(12.0, 5.0), layout="constrained")
    left, right = fig.subplots(1, 2)
    _portrait(left, model, legs, jumps)
    left.set_title("phase portrait (dashed: the strikes)", fontsize=10)
    for k, name in enumerate(model.coordinates):
        for i, (ts, xs) in enumerate(legs):
            right.plot(ts, xs[:, k], color=("#1f4e9c", "#c0392b", "#2e8b57")[k % 3],
                       label=name if i == 0 else None)  # fmt: skip
    for ts, _ in legs:
        right.axvline(ts[-1], color="0.6", linewidth=0.8, linestyle=":")
    right.set_xlabel("time (s)")
    right.set_ylabel("coordinate")
    right.grid(True, color="0.9", linewidth=0.6)
    right.legend(loc="best", fontsize=9)
    mult = "" if cycle.multipliers is None else \
        f", largest |multiplier| {np.max(np.abs(cycle.multipliers)):.3f}"  # fmt: skip
    fig.suptitle(f"{model.name}: period {cycle.period:.6g} s{mult}", fontsize=12)
    return save_figure(fig, path)


def plot_run(run: Any, path: str | Path | None = None) -> Figure:
    """A run (a :class:`carnot.hybrid.simulate.HybridRun`): the energy each strike took, and
    the phase portrait of the whole run (each coordinate against its rate: refused where
    ``nq != n``, a free or ball joint's quaternion having no rate of its own in ``qvel``)."""
    model = run.model
    require_velocity_chart(model, "phase portraits")
    strikes = [e for e in run.events if e.strike is not None]
    fig = Figure(figsize=(12.0, 5.0), layout="constrained")
    left, right = fig.subplots(1, 2)
    e_d = [float(e.strike.result.energy.dissipated) for e in strikes]
    left.plot(range(1, len(e_d) + 1), e_d, marker="o", markersize=3, color="#1f4e9c")
    left.set_xlabel("strike")
    left.set_ylabel("energy the strike took, E_d (J)")
    left.grid(True, color="0.9", linewidth=0.6)
    left.set_title(f"{len(e_d)} strikes; the ledger's residual {run.energy['residual']:.2g} J",
                   fontsize=10)  # fmt: skip
    legs, jumps = [], []
    x, t = np.array(run.start, dtype=float), 0.0
    held: tuple[Any, ...] = ()
    for e in run.events:  # the flow between events, with the contacts held as they were
        if e.time > t and e.kind != "rest":  # (a rest event is dated at the run's end)
            legs.append(sampled(model, x, t, e.time, SAMPLES // 4, held, run.law.friction))
        if e.strike is not None:
            jumps.append((e.strike.x_before, e.strike.x_after))
        x, t, held = e.state, e.time, e.held
    if run.time > t and run.ended == "duration":
        legs.append(sampled(model, x, t, run.time, SAMPLES // 4, held, run.law.friction))
    if legs:
        _portrait(right, model, legs, jumps)
    right.set_title("phase portrait", fontsize=10)
    fig.suptitle(f"{model.name}: {run.time:g} s, ended: {run.ended}", fontsize=12)
    return save_figure(fig, path)


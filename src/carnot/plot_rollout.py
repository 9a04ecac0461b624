"""A rollout's energy over time with its impact episodes and the rigid reference beside
each (``carnot audit --plot OUT``; matplotlib's object-oriented API, no pyplot)."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from carnot.rollout.audit import AuditReport, Episode

#: The most episodes drawn as labelled bars; beyond, against time (:func:`plot_audit`).
MAX_LABELLED = 24
#: The most pairs given a colour of their own in the plot against time.
MAX_PAIRS = 8


def plot_audit(report: AuditReport, path: str | Path | None = None) -> Figure:
    """Top: MuJoCo's total, kinetic and potential energy (``mj_energy``, J) against time
    (s), each episode shaded, and at its end the energy the rigid law would have left
    (``E' - E_d``, a black bar). Bottom: each episode's loss, MuJoCo's (the whole system's,
    and its contact rows') against the rigid reference's: side by side, labelled by pair
    and time, up to :data:`MAX_LABELLED` episodes; beyond, against the episode's start
    time, one colour per pair (the :data:`MAX_PAIRS` pairs with the most episodes, the
    others grey), so that it stays legible with hundreds. Saved to ``path`` (PNG, SVG or
    PDF by the suffix) when given.

    >>> from carnot.rollout import RigidSettings, audit_model
    >>> report = audit_model("examples/audit/ball_drop.xml", keyframe="drop", duration=0.6,
    ...                      rigid=RigidSettings(restitution=0.5))
    >>> len(plot_audit(report).axes)
    2
    """
    s = report.steps
    time = np.append(s.time, s.time[-1] + s.timestep) if s.count else np.zeros(1)
    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    ax, ax_e = fig.subplots(2, 1, height_ratios=[2.2, 1.0])
    ax.plot(time, s.energy, label="total (mj_energy)", color="C0")
    ax.plot(time, s.kinetic, label="kinetic", color="C1", linewidth=0.8)
    ax.plot(time, s.potential, label="potential", color="C2", linewidth=0.8)
    span = max(float(time[-1] - time[0]), s.timestep)
    for k, e in enumerate(report.episodes):
        ax.axvspan(e.start, max(e.end, e.start + s.timestep), color="C3", alpha=0.25,
                   label="episodes" if k == 0 else None)  # fmt: skip
        if math.isfinite(e.rigid_dissipated) and not e.rigid_verdict:
            rigid_after = e.energy_before - e.rigid_dissipated
            ax.hlines(rigid_after, e.end, e.end + 0.03 * span, color="k", linewidth=2,
                      label="rigid law: E' - E_d" if k == 0 else None)  # fmt: skip
    ax.set_xlabel("time [s]")
    ax.set_ylabel("energy [J]")
    ax.legend(fontsize=8)
    _losses(ax_e, report.episodes)
    settings = report.settings
    law = "" if settings is None else (
        f" - rigid {settings.law} e = {settings.restitution:g}"
    )  # fmt: skip
    fig.suptitle(f"{report.title or 'MuJoCo rollout'}{law}", fontsize=10)
    if path is not None:
        fig.savefig(path)
    return fig


def _contact_rows(e: Episode) -> float:
    """What MuJoCo's contact rows took over the episode (J): this pair's and the other
    contacts' (the rigid reference's E_d is that of all the contacts it solves), or the
    pair's alone where the integrator has no split."""
    if e.split is None:
        return -e.contact_work
    return e.split["pair"] + e.split["other_contacts"]


def _losses(ax: Any, episodes: Sequence[Episode]) -> None:
    """Each episode's loss: MuJoCo's whole system's (``energy_lost``: damping, limits and
    actuators included) and its contact rows', against the rigid ``E_d`` (none where the
    reference has a verdict instead)."""
    system = [e.energy_lost for e in episodes]
    mujoco = [_contact_rows(e) for e in episodes]
    rigid = [math.nan if e.rigid_verdict else e.rigid_dissipated for e in episodes]
    ax.set_ylabel("energy lost [J]")
    if len(episodes) <= MAX_LABELLED:
        x = np.arange(len(episodes))
        ax.bar(x - 0.27, system, 0.27, label="MuJoCo: whole system", color="0.75")
        ax.bar(x, mujoco, 0.27, label="MuJoCo: contact rows", color="C0")
        ax.bar(x + 0.27, rigid, 0.27, label="rigid E_d", color="C1")
        labels = [f"{'/'.join(e.pair)}\n{e.start:.3f} s" for e in episodes]
        ax.set_xticks(x, labels, fontsize=7, rotation=0 if len(episodes) <= 8 else 90)
        ax.legend(fontsize=8)
    else:
        counts = Counter(e.pair for e in episodes)
        coloured = [pair for pair, _ in counts.most_common(MAX_PAIRS)]
        start = np.array([e.start for e in episodes])
        for k, pair in enumerate([*coloured, None]):
            mine = np.array([(e.pair == pair) if pair is not None else e.pair not in coloured
                             for e in episodes])  # fmt: skip
            if not mine.any():
                continue
            colour = f"C{k}" if pair is not None else "0.6"
            name = "/".join(pair) if pair is not None else f"{len(counts) - len(coloured)} more"
            ax.scatter(start[mine], np.array(mujoco)[mine], s=14, color=colour, label=name)
            ax.scatter(start[mine], np.array(rigid)[mine], s=22, color=colour, marker="x")
        ax.set_xlabel("episode start [s]  (dots: MuJoCo's contact rows, crosses: rigid E_d)")
        ax.legend(fontsize=7, ncols=3)

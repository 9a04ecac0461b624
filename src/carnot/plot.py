"""Pictures of a frictional impact in impulse space (matplotlib).

For a contact with Coulomb friction (laws/friction.py) the normal impulse ``p`` (N s) is the
clock of the impact. :func:`plot_impact` draws, against ``p``:

* the relative velocity at the contact: the normal component ``w_n`` and the slip (its
  components along the slip directions, or the signed slip when the motion is planar), with
  the phases (compression and restitution shaded; slip, stick, reversal and direction change
  marked at their normal impulse);
* the work done on the relative motion by the normal impulse (``W_n``) and by friction
  (``W_t``) and their sum, ``-E_d`` so far;
* for a 3D impact, the hodograph: the slip velocity in the contact plane, whose direction
  turns as the impulse grows.

It uses matplotlib's object-oriented API (no pyplot, no display needed) and is imported only
when a picture is asked for: the core does not need matplotlib.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from carnot.conventions import contact_frame
from carnot.errors import InputError
from carnot.laws.friction import FrictionalImpulse
from carnot.result import ImpactResult, ItemOutcome

_PHASE_COLOURS = {"compression": "#dbe9f6", "restitution": "#fbe5d6"}
_LABELS = {"impact": "", "stop": "stick", "reversal": "reversal",
           "direction_change": "new direction"}  # fmt: skip


def _frictional_contact(result: ImpactResult, contact: int | None) -> ItemOutcome:
    candidates = [k for k, o in enumerate(result.contacts) if o.process is not None]
    if contact is None:
        if not candidates:
            raise InputError(
                "plot",
                "needs a contact with Coulomb friction (friction > 0, tangential = \"slip\"): "
                "its history in impulse space is what is drawn; this result has none",
                [o.where for o in result.contacts],
            )
        contact = candidates[0]
    if not 0 <= contact < len(result.contacts) or result.contacts[contact].process is None:
        raise InputError(
            "plot.contact", "must be the index of a contact with Coulomb friction", contact
        )
    return result.contacts[contact]


def plot_impact(
    result: ImpactResult, path: str | Path | None = None, *, contact: int | None = None
) -> Figure:
    """Draw the impulse-space history of a frictional contact; save it to ``path`` (PNG,
    SVG or PDF by the suffix) when given. ``contact``: its index in ``result.contacts``
    (default: the first with Coulomb friction).

    >>> from carnot import FixedBody, ImpactProblem, PointContact, RigidBody, solve_impact
    >>> from carnot.model.inertia import solid_sphere
    >>> ball = RigidBody(name="ball", mass=1.0, inertia_com=solid_sphere(1.0, 0.1),
    ...                  position_com=[0, 0, 0.1], velocity_com=[1.0, 0, -1.0])
    >>> res = solve_impact(ImpactProblem(bodies={"ball": ball, "floor": FixedBody(name="f")},
    ...     contacts=[PointContact(a="ball", b="floor", point=[0, 0, 0], normal=[0, 0, 1],
    ...                            restitution=0.5, friction=0.5)]))
    >>> len(plot_impact(res).axes)
    2
    """
    outcome = _frictional_contact(result, contact)
    assert outcome.process is not None and outcome.normal is not None
    process = outcome.process.resampled(96)
    planar = _planar(process) is not None
    fig = Figure(figsize=(8.0, 7.0) if planar else (13.0, 7.0), layout="constrained")
    if planar:
        ax_v, ax_w = fig.subplots(2, 1, sharex=True)
    else:  # 3D: the hodograph of the slip beside, where its turning shows
        grid = fig.add_gridspec(2, 2, width_ratios=(1.6, 1.0))
        ax_v = fig.add_subplot(grid[0, 0])
        ax_w = fig.add_subplot(grid[1, 0], sharex=ax_v)
        _draw_hodograph(fig.add_subplot(grid[:, 1]), process, outcome)
    _draw_velocities(ax_v, process, outcome)
    _draw_works(ax_w, process)
    for ax in (ax_v, ax_w):
        _draw_phases(ax, process)
        ax.axhline(0.0, color="0.3", linewidth=0.8)
        ax.grid(True, color="0.9", linewidth=0.6)
        ax.set_xlim(0.0, max(float(process.impulse[0]), 1e-300))
    ax_w.set_xlabel("normal impulse p (N s)")
    hyp = process.hypothesis.capitalize()
    fig.suptitle(
        f"{result.title or 'Impact'} ({outcome.where})\n{hyp}'s hypothesis, "
        f"e = {process.restitution:g}, $\\mu$ = {process.friction:g}: {process.regime}",
        fontsize=11,
    )
    if path is not None:
        _save(fig, Path(path))
    return fig


def _save(fig: Figure, path: Path) -> None:
    """Save by the suffix; a suffix matplotlib cannot write, or a path that cannot be
    written, is an input error naming the path."""
    formats = fig.canvas.get_supported_filetypes()
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in formats:
        raise InputError(
            "plot", f"must end in a picture suffix ({', '.join(sorted(formats))})", str(path)
        )
    try:
        fig.savefig(path, dpi=150)
    except OSError as err:
        raise InputError("plot", f"cannot write the picture ({err.strerror})", str(path)) from None


def _planar(process: FrictionalImpulse) -> np.ndarray | None:
    """The one tangent direction of a planar impact (contact-frame components), if any."""
    dirs = [d for ph in process.phases for d in (ph.direction_start, ph.direction_end)
            if d is not None]  # fmt: skip
    if not dirs:
        return np.array([1.0, 0.0])
    ref = dirs[0]
    ok = all(abs(float(d[0] * ref[1] - d[1] * ref[0])) < 1e-9 for d in dirs)
    return ref if ok else None


def _draw_velocities(ax, process: FrictionalImpulse, outcome: ItemOutcome) -> None:  # type: ignore[no-untyped-def]
    s = process.samples
    p = s[:, 0]
    ax.plot(p, s[:, 1], color="#1f4e9c", linewidth=2.0, label="normal $w_n$")
    ref = _planar(process)
    assert outcome.normal is not None
    _, t1, t2 = contact_frame(outcome.normal)
    if ref is not None:
        axis = ref[0] * t1 + ref[1] * t2
        ax.plot(p, s[:, 2:4] @ ref, color="#c0392b", linewidth=2.0,
                label=f"slip along {np.round(axis, 3).tolist()}")  # fmt: skip
    else:
        ax.plot(p, s[:, 2], color="#c0392b", linewidth=1.6,
                label=f"slip along $t_1$ = {np.round(t1, 3).tolist()}")  # fmt: skip
        ax.plot(p, s[:, 3], color="#e67e22", linewidth=1.6,
                label=f"slip along $t_2$ = {np.round(t2, 3).tolist()}")  # fmt: skip
        ax.plot(p, np.hypot(s[:, 2], s[:, 3]), color="#7f8c8d", linestyle="--", linewidth=1.2,
                label="slip speed $|w_t|$")  # fmt: skip
    ax.set_ylabel("relative velocity at the contact (m/s)")
    ax.legend(loc="best", fontsize=8, framealpha=0.9)


def _draw_hodograph(ax, process: FrictionalImpulse, outcome: ItemOutcome) -> None:  # type: ignore[no-untyped-def]
    """The tangential relative velocity in the contact plane as the impulse grows: its
    direction is the slip direction, its length the slip speed; stick sits at the origin."""
    s = process.samples
    ax.plot(s[:, 2], s[:, 3], color="#c0392b", linewidth=2.0)
    ax.plot(s[0, 2], s[0, 3], "o", color="#c0392b", label="before the impact")
    ax.plot(s[-1, 2], s[-1, 3], "s", color="#1f4e9c", label="after the impact")
    p_c = process.compression_impulse
    at_c = s[int(np.argmin(np.abs(s[:, 0] - p_c)))]
    ax.plot(at_c[2], at_c[3], "D", color="0.3", label="maximum compression")
    for ph in process.phases[1:]:
        here = s[int(np.argmin(np.abs(s[:, 0] - ph.start)))]
        ax.annotate(_LABELS.get(ph.began, ph.began) or ph.regime, (here[2], here[3]),
                    textcoords="offset points", xytext=(6, 6), fontsize=8)  # fmt: skip
    ax.axhline(0.0, color="0.6", linewidth=0.8)
    ax.axvline(0.0, color="0.6", linewidth=0.8)
    ax.set_aspect("equal", adjustable="datalim")
    assert outcome.normal is not None
    _, t1, t2 = contact_frame(outcome.normal)
    ax.set_xlabel(f"slip along $t_1$ = {np.round(t1, 3).tolist()} (m/s)")
    ax.set_ylabel(f"slip along $t_2$ = {np.round(t2, 3).tolist()} (m/s)")
    ax.set_title("slip in the contact plane (hodograph)", fontsize=10)
    ax.grid(True, color="0.9", linewidth=0.6)
    ax.legend(loc="best", fontsize=8, framealpha=0.9)


def _draw_works(ax, process: FrictionalImpulse) -> None:  # type: ignore[no-untyped-def]
    s = process.samples
    p = s[:, 0]
    ax.plot(p, s[:, 4], color="#1f4e9c", linewidth=2.0, label="normal force $W_n$")
    ax.plot(p, s[:, 5], color="#c0392b", linewidth=2.0, label="friction $W_t$")
    ax.plot(p, s[:, 4] + s[:, 5], color="0.15", linewidth=1.4, linestyle="--",
            label="total $W_n + W_t = -E_d$ so far")  # fmt: skip
    ax.set_ylabel("work on the relative motion (J)")
    ax.legend(loc="best", fontsize=8, framealpha=0.9)


def _draw_phases(ax, process: FrictionalImpulse) -> None:  # type: ignore[no-untyped-def]
    p_c = process.compression_impulse
    p_f = float(process.impulse[0])
    ax.axvspan(0.0, p_c, color=_PHASE_COLOURS["compression"], zorder=0)
    ax.axvspan(p_c, p_f, color=_PHASE_COLOURS["restitution"], zorder=0)
    ax.axvline(p_c, color="0.45", linewidth=0.8)
    top = ax.get_ylim()[1]
    ax.text(p_c / 2, top, "compression", ha="center", va="bottom", fontsize=8, color="0.35")
    ax.text((p_c + p_f) / 2, top, "restitution", ha="center", va="bottom", fontsize=8,
            color="0.35")  # fmt: skip
    for ph in process.phases:
        if ph.start > 0:
            ax.axvline(ph.start, color="0.25", linestyle=":", linewidth=1.0)
            ax.annotate(_LABELS.get(ph.began, ph.began) or ph.regime, (ph.start, 0.02),
                        xycoords=("data", "axes fraction"), rotation=90, fontsize=8,
                        ha="right", va="bottom", color="0.25")  # fmt: skip
        mid = 0.5 * (ph.start + ph.end)
        name = {"reversal": "slip (reversed)", "direction_change": "slip (new direction)"}
        ax.annotate(name.get(ph.began, ph.regime), (mid, 0.95),
                    xycoords=("data", "axes fraction"), fontsize=9, ha="center", va="top",
                    color="0.1", weight="bold")  # fmt: skip

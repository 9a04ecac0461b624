"""``carnot simulate FILE``: the sub-command's arguments and its run (parsing and printing
only; the physics is in the rest of this package)."""

from __future__ import annotations

import argparse
import sys
from typing import Any


def add_simulate(sub: Any) -> None:
    """Register ``simulate`` on the CLI's sub-parsers."""
    p = sub.add_parser(
        "simulate",
        help="simulate motion with impacts, contacts and an energy ledger",
        description="Event-driven simulation of a scenario with [simulation] (DESIGN.md "
        "section 8): exact free flight, every impact solved by carnot's laws with its ledger, "
        "persistent contacts, Zeno accumulation, ground motion; or of a named model in motion "
        "with [model] (section 10: walkers, the rimless wheel). Prints a table of events, or "
        "the events, final state and energy ledger as JSON.",
    )
    p.add_argument("file", help="simulation scenario (.toml, or .json), or an MJCF model "
                   "(.xml: needs carnot[mujoco])")
    p.add_argument("--json", action="store_true", help="print the section 8 result (JSON)")
    p.add_argument("--trajectory", metavar="OUT.parquet",
                   help="write the sampled motion (needs pyarrow: carnot[sweep])")
    p.add_argument("--plot", metavar="OUT", help="draw the energy budget over time "
                   "(.png, .svg or .pdf)")
    p.add_argument("--animate", metavar="OUT", help="animate the motion in the x-y plane "
                   "(.gif, .mp4 with ffmpeg, or .html)")
    p.add_argument("--frames", type=int, default=200,
                   help="frames of the animation (default 200, at most 5000)")
    p.add_argument("--progress", action="store_true",
                   help="a progress bar on stderr (default: when stderr is a terminal)")
    p.add_argument("--saltation", action="store_true",
                   help="a [model] scenario or an MJCF model: add each impact's saltation matrix "
                   "(section 10; printed with --json)")
    p.add_argument("--keyframe", metavar="K", help="an MJCF model: start in this keyframe "
                   "(name or index; default: qpos0 at rest)")
    p.add_argument("--duration", type=float, metavar="T",
                   help="an MJCF model: how long to run (s; required)")
    p.add_argument("--restitution", type=float, metavar="E",
                   help="an MJCF model: e of every strike (default: the model's custom "
                   "numeric carnot_restitution, or 0)")
    p.set_defaults(run=run_command)


def run_command(args: argparse.Namespace) -> int:
    from carnot.errors import InputError
    from carnot.io.scenario import read_scenario_data

    if str(args.file).lower().endswith(".xml"):  # an MJCF model in motion (section 10)
        from carnot.hybrid.command import run_mjcf_simulation

        return run_mjcf_simulation(args)
    for option in ("keyframe", "duration", "restitution"):
        if getattr(args, option, None) is not None:
            raise InputError(f"--{option}", "is for an MJCF model (.xml); a scenario file "
                             "states it in [simulation] or [model]", show_value=False)
    data = read_scenario_data(args.file)
    if isinstance(data, dict) and "model" in data:  # a model in motion (DESIGN.md section 10)
        from carnot.hybrid.command import run_model_simulation

        return run_model_simulation(args, data)
    from carnot.simulate.contacts import SimulationError
    from carnot.simulate.loop import run
    from carnot.simulate.output import (
        ANIMATION_SUFFIXES,
        PLOT_SUFFIXES,
        animate,
        check_suffix,
        format_table,
        plot_energy,
        to_json,
        write_trajectory,
    )
    from carnot.simulate.scenario import load_simulation

    if args.plot:
        check_suffix(args.plot, "--plot", PLOT_SUFFIXES)
    if args.animate:
        check_suffix(args.animate, "--animate", ANIMATION_SUFFIXES)
    if not 2 <= args.frames <= 5000:
        raise InputError("--frames", "must be in [2, 5000]", args.frames)
    if args.trajectory:
        if not args.trajectory.lower().endswith(".parquet"):
            raise InputError("--trajectory", "must end in .parquet", args.trajectory)
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise InputError("--trajectory", "needs pyarrow: pip install 'carnot[sweep]'",
                             show_value=False) from None  # fmt: skip
    sim = load_simulation(args.file)
    bar = _progress(sim.duration, args.progress or sys.stderr.isatty())
    record = bool(args.plot or args.animate or args.trajectory)
    try:
        result = run(sim, record=record, progress=bar.update if bar is not None else None)
    except SimulationError as err:
        raise SimulationError(f"{args.file}: {err}") from None
    except InputError as err:
        raise type(err)(f"{args.file}: {err.field}", err.problem, err.value,
                        show_value=err.show_value) from None  # fmt: skip
    finally:
        if bar is not None:
            bar.close()
    if args.trajectory:
        write_trajectory(result, args.trajectory)
    if args.plot:
        plot_energy(result, args.plot)
    if args.animate:
        animate(result, args.animate, frames=args.frames)
    print(to_json(result) if args.json else format_table(result))
    return 0


class _Bar:
    def __init__(self, bar: Any, total: float) -> None:
        self.bar, self.done = bar, 0.0

    def update(self, t: float) -> None:
        if t > self.done:
            self.bar.update(t - self.done)
            self.done = t

    def close(self) -> None:
        self.bar.close()


def _progress(total: float, wanted: bool) -> _Bar | None:
    if not wanted:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return _Bar(tqdm(total=total, unit="s", file=sys.stderr, leave=False,
                     bar_format="{l_bar}{bar}| {n:.3f}/{total:.3f} s"), total)  # fmt: skip

"""``carnot cycle FILE`` and ``carnot simulate FILE`` on a ``[model]`` scenario: arguments,
runs and printing only (the physics is in the rest of this package)."""

from __future__ import annotations

import argparse
from typing import Any


def add_cycle(sub: Any) -> None:
    """Register ``cycle`` on the CLI's sub-parsers."""
    p = sub.add_parser(
        "cycle",
        help="a periodic orbit of a model in motion: period, state, Floquet multipliers",
        description="Find a periodic orbit of a [model] scenario (DESIGN.md section 10) by "
        "Newton shooting from the file's state: the return map at the strike, its "
        "linearization through saltation matrices, the Floquet multipliers, stability, and "
        "the energy the strikes take per period against the potential energy lost.",
    )
    p.add_argument("file", help="scenario (.toml, or .json) with a [model] table, or free "
                   "bodies with [simulation] (section 8: a ball on a vibrating table)")
    p.add_argument("--json", action="store_true", help="print the section 10 result (JSON)")
    p.add_argument("--strikes", type=int, default=None,
                   help="the period in strikes (default: [cycle] strikes, or 1)")
    p.add_argument("--plot", metavar="OUT", help="draw the orbit: its phase portrait and its "
                   "coordinates over one period (.png, .svg or .pdf)")
    p.add_argument("--check", action="store_true",
                   help="also print the multipliers from finite differences of the return map "
                   "(a second route)")  # fmt: skip
    p.set_defaults(run=run_cycle)


def run_cycle(args: argparse.Namespace) -> int:
    import numpy as np

    from carnot.errors import InputError
    from carnot.hybrid.cycle import find_cycle, finite_difference_jacobian
    from carnot.hybrid.output import cycle_to_dict, format_cycle
    from carnot.hybrid.scenario import MAX_STRIKES, load_model_scenario
    from carnot.io.json_text import dumps
    from carnot.io.scenario import read_scenario_data

    if str(args.file).lower().endswith(".xml"):  # an MJCF model: refused in one line
        from carnot.hybrid.mjcf import refuse_cycle

        refuse_cycle(args.file)
    data = read_scenario_data(args.file)
    if isinstance(data, dict) and "model" not in data and "simulation" in data:
        # free bodies (section 8): their return map is the simulator's (simulate/cycle.py)
        from carnot.simulate.cycle_command import run_free_cycle

        return run_free_cycle(args, data)
    if args.plot:
        from carnot.plot_sweep import check_plot_path

        check_plot_path(args.plot)
    sc = load_model_scenario(args.file, data)
    strikes = sc.strikes if args.strikes is None else args.strikes
    if not 1 <= strikes <= MAX_STRIKES:
        raise InputError("--strikes", f"must be in [1, {MAX_STRIKES}]", strikes)
    cycle = find_cycle(sc.model, sc.state, sc.law, steps=strikes, tolerance=sc.tolerance)
    fd = None
    if args.check and cycle.converged:
        jac = finite_difference_jacobian(sc.model, cycle.state, sc.law, steps=strikes)
        eig = np.linalg.eigvals(jac)
        fd = eig[np.argsort(-np.abs(eig), kind="stable")][: 2 * sc.model.n - 1]
    if args.json:
        out = cycle_to_dict(cycle, sc.title)
        if fd is not None:
            out["multipliers_finite_difference"] = [[float(z.real), float(z.imag)] for z in fd]
        print(dumps(out))
    else:
        text = format_cycle(cycle, sc.title)
        if fd is not None:
            text += "\n  finite differences: " + ", ".join(
                f"{z.real:.6f}{z.imag:+.6f}i" for z in fd)
        print(text)
    if args.plot and cycle.converged:
        from carnot.hybrid.plot import plot_cycle

        plot_cycle(cycle, args.plot)
    return 0


def run_model_simulation(args: argparse.Namespace, data: Any) -> int:
    """``carnot simulate`` on a ``[model]`` scenario."""
    from carnot.errors import InputError
    from carnot.hybrid.output import format_run, run_to_json
    from carnot.hybrid.scenario import load_model_scenario
    from carnot.hybrid.simulate import simulate

    for option in ("animate", "trajectory"):
        if getattr(args, option, None):
            raise InputError(f"--{option}", "is made for free-body scenarios; a [model] "
                             "scenario prints its events and ledger (--json) and draws them "
                             "(--plot)", show_value=False)  # fmt: skip
    if args.plot:
        from carnot.plot_sweep import check_plot_path

        check_plot_path(args.plot)
    sc = load_model_scenario(args.file, data)
    if sc.duration is None:
        raise InputError(f"{args.file}: simulation.duration", "is required by carnot simulate",
                         show_value=False)  # fmt: skip
    run = simulate(sc.model, sc.state, sc.duration, sc.law, saltation=args.saltation)
    print(run_to_json(run, sc.title) if args.json else format_run(run, sc.title))
    if args.plot:
        from carnot.hybrid.plot import plot_run

        plot_run(run, args.plot)
    return 0


def run_mjcf_simulation(args: argparse.Namespace) -> int:
    """``carnot simulate model.xml --keyframe K --duration T`` (carnot.hybrid.mjcf)."""
    from carnot import validate
    from carnot.errors import InputError
    from carnot.hybrid.mjcf import mjcf_model
    from carnot.hybrid.output import format_run, run_to_json
    from carnot.hybrid.scenario import MAX_DURATION
    from carnot.hybrid.simulate import simulate

    for option in ("plot", "animate", "trajectory"):
        if getattr(args, option, None):
            raise InputError(f"--{option}", "is drawn for free-body scenarios; an MJCF model "
                             "prints its events and ledger (--json)", show_value=False)
    if args.duration is None:
        raise InputError("--duration", "is required for an MJCF model (s)", show_value=False)
    duration = float(validate.positive_number(args.duration, "--duration", "s"))
    if duration > MAX_DURATION:
        raise InputError("--duration", f"must be <= {MAX_DURATION:g} s", duration)
    if args.restitution is not None:
        validate.number_in(args.restitution, "--restitution", 0.0, 1.0)
    motion = mjcf_model(args.file, keyframe=args.keyframe, restitution=args.restitution)
    run = simulate(motion.model, motion.state, duration, motion.law, saltation=args.saltation)
    print(run_to_json(run, motion.title) if args.json else format_run(run, motion.title))
    return 0

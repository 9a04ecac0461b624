"""``carnot cycle FILE`` and ``carnot simulate FILE`` on a ``[model]`` scenario: arguments,
runs and printing only (the physics is in the rest of this package)."""

from __future__ import annotations

import argparse
from typing import Any


def add_cycle(sub: Any) -> None:  # (its MJCF numbers below)
    """Register ``cycle`` on the CLI's sub-parsers."""
    p = sub.add_parser(
        "cycle",
        help="a periodic orbit of a model in motion: period, state, Floquet multipliers",
        description="Find a periodic orbit of a [model] scenario (DESIGN.md section 10) by "
        "Newton shooting from the file's state: the return map at the strike, its "
        "linearization through saltation matrices, the Floquet multipliers, stability, and "
        "the energy the strikes take per period against the potential energy lost. An MJCF "
        "model (.xml) starts from --keyframe, put on the section (the contacts within 1 um of "
        "closing closed and brought to rest); its contacts are held in the flow as carnot "
        "simulate holds them. A walker is periodic only up to a symmetry: --shift JOINT=AMOUNT "
        "says the period returns JOINT advanced by AMOUNT (a rimless wheel's pitch, 2 pi / N: "
        "its spokes are alike), --cyclic JOINT that the motion does not depend on JOINT's "
        "position (a slide along a flat floor), which is then left free and its change per "
        "period reported (advance); e.g. carnot cycle examples/motion/rimless_wheel.xml "
        "--keyframe post_strike --shift pitch=pi/4 --cyclic x. Free and ball joints are not "
        "supported yet.",
    )
    p.add_argument("file", help="scenario (.toml, or .json) with a [model] table, free "
                   "bodies with [simulation] (section 8: a ball on a vibrating table), or an "
                   "MJCF model (.xml: needs carnot[mujoco])")
    p.add_argument("--json", action="store_true", help="print the section 10 result (JSON)")
    p.add_argument("--strikes", type=int, default=None,
                   help="the period in strikes (default: [cycle] strikes, or 1)")
    p.add_argument("--plot", metavar="OUT", help="draw the orbit: its phase portrait and its "
                   "coordinates over one period (.png, .svg or .pdf)")
    p.add_argument("--check", action="store_true",
                   help="also print the multipliers from finite differences of the return map "
                   "(a second route)")  # fmt: skip
    p.add_argument("--keyframe", metavar="K", help="an MJCF model: the guess, a state just "
                   "after a strike (name or index; default: qpos0 at rest)")
    p.add_argument("--restitution", type=float, metavar="E",
                   help="an MJCF model: e of every strike (default: the model's custom "
                   "numeric carnot_restitution, or 0)")
    p.add_argument("--max-period", type=float, metavar="T", dest="max_period",
                   help=f"an MJCF model: the longest a period may take (s; default "
                   f"{MJCF_MAX_PERIOD:g}): a guess that never strikes again fails there")
    p.add_argument("--shift", action="append", default=None, metavar="JOINT=AMOUNT",
                   help="the period returns JOINT's position advanced by AMOUNT (rad or m: a "
                   "number, or a multiple of pi such as pi/4 or 2*pi/8); repeat for several "
                   "joints")  # fmt: skip
    p.add_argument("--cyclic", action="append", default=None, metavar="JOINT",
                   help="the motion does not depend on JOINT's position (checked): it is left "
                   "free, and its change over a period reported (advance); repeatable")
    p.set_defaults(run=run_cycle)


#: Newton's tolerance on an MJCF model's return (``|P(x) - s - x| <= tolerance max(1, |x|)``):
#: its held flow's rows come from MuJoCo's contacts, to about 1e-13 (a [model] scenario's is
#: [cycle] tolerance, default 1e-11).
MJCF_TOLERANCE = 1e-10
#: The longest an MJCF model's period may take, unless --max-period says (s).
MJCF_MAX_PERIOD = 10.0
#: The most --max-period may be (s).
MAX_MAX_PERIOD = 100.0


def parse_shifts(items: list[str] | None) -> dict[str, float]:
    """``--shift JOINT=AMOUNT`` items as ``{joint: amount}``: ``AMOUNT`` a number or a product
    and quotient of numbers and ``pi`` (``pi/4``, ``2*pi/8``, ``-0.5``); an InputError naming
    ``--shift`` otherwise.

    >>> parse_shifts(["pitch=pi/4", "x=0.5"]) == {"pitch": 0.7853981633974483, "x": 0.5}
    True
    >>> parse_shifts(["pitch"])
    Traceback (most recent call last):
    ...
    carnot.errors.InputError: --shift: must be JOINT=AMOUNT (e.g. pitch=pi/4), got 'pitch'
    """
    import ast
    import math

    from carnot.errors import InputError

    def value(node: ast.AST) -> float:
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and \
                not isinstance(node.value, bool):  # fmt: skip
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = value(node.operand)
            return -inner if isinstance(node.op, ast.USub) else inner
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
            left, right = value(node.left), value(node.right)
            if isinstance(node.op, ast.Mult):
                return left * right
            if right == 0:
                raise ValueError("division by zero")
            return left / right
        raise ValueError("not a number")

    out: dict[str, float] = {}
    for item in items or []:
        name, sep, text = item.partition("=")
        if not sep or not name.strip() or not text.strip():
            raise InputError("--shift", "must be JOINT=AMOUNT (e.g. pitch=pi/4)", item)
        try:
            amount = value(ast.parse(text.strip(), mode="eval").body)
        except (SyntaxError, ValueError):
            raise InputError(f"--shift {name.strip()}", "must be a number or a multiple of "
                             "pi (rad or m: 0.785, pi/4, 2*pi/8)", text) from None  # fmt: skip
        if not math.isfinite(amount):
            raise InputError(f"--shift {name.strip()}", "must be finite", text)
        if name.strip() in out:
            raise InputError(f"--shift {name.strip()}", "is given twice", show_value=False)
        out[name.strip()] = amount
    return out


def run_cycle(args: argparse.Namespace) -> int:
    import numpy as np

    from carnot.errors import InputError
    from carnot.hybrid.cycle import find_cycle, finite_difference_jacobian
    from carnot.hybrid.scenario import MAX_STRIKES, load_model_scenario
    from carnot.io.scenario import read_scenario_data

    if str(args.file).lower().endswith(".xml"):  # an MJCF model in motion
        return run_mjcf_cycle(args)
    for option in ("keyframe", "restitution", "max_period"):
        if getattr(args, option, None) is not None:
            flag = "--" + option.replace("_", "-")
            raise InputError(flag, "is for an MJCF model (.xml); a scenario file states it "
                             "in [model] or [simulation]", show_value=False)  # fmt: skip
    data = read_scenario_data(args.file)
    if isinstance(data, dict) and "model" not in data and "simulation" in data:
        # free bodies (section 8): their return map is the simulator's (simulate/cycle.py)
        from carnot.simulate.cycle_command import run_free_cycle

        for option in ("shift", "cyclic"):
            if getattr(args, option, None):
                raise InputError(f"--{option}", "is for a model in motion ([model] or .xml); "
                                 "free bodies return to their own state", show_value=False)
        return run_free_cycle(args, data)
    if args.plot:
        from carnot.plot_sweep import check_plot_path

        check_plot_path(args.plot)
    sc = load_model_scenario(args.file, data)
    strikes = sc.strikes if args.strikes is None else args.strikes
    if not 1 <= strikes <= MAX_STRIKES:
        raise InputError("--strikes", f"must be in [1, {MAX_STRIKES}]", strikes)
    cycle = find_cycle(sc.model, sc.state, sc.law, steps=strikes, tolerance=sc.tolerance,
                       shift=parse_shifts(args.shift), cyclic=args.cyclic or ())  # fmt: skip
    fd = None
    if args.check and cycle.converged:
        jac = finite_difference_jacobian(sc.model, cycle.state, sc.law, steps=strikes)
        eig = np.linalg.eigvals(jac)
        fd = eig[np.argsort(-np.abs(eig), kind="stable")][: 2 * sc.model.n - 1]
    print(cycle_report(cycle, sc.title, fd, as_json=args.json, digits=6))
    if args.plot and cycle.converged:
        from carnot.hybrid.plot import plot_cycle

        plot_cycle(cycle, args.plot)
    return 0


def run_mjcf_cycle(args: argparse.Namespace) -> int:
    """``carnot cycle model.xml --keyframe K [--shift JOINT=AMOUNT] [--cyclic JOINT]``: the
    periodic orbit of an MJCF model (:func:`carnot.hybrid.cycle.find_cycle`, its contacts
    held in the flow as the simulator holds them)."""
    from carnot import validate
    from carnot.errors import InputError
    from carnot.hybrid.cycle import find_cycle, finite_difference_multipliers
    from carnot.hybrid.mjcf import mjcf_model
    from carnot.hybrid.scenario import MAX_STRIKES

    if args.plot:
        raise InputError("--plot", "is drawn for [model] scenarios; an MJCF model prints its "
                         "orbit (--json)", show_value=False)  # fmt: skip
    strikes = 1 if args.strikes is None else args.strikes
    if not 1 <= strikes <= MAX_STRIKES:
        raise InputError("--strikes", f"must be in [1, {MAX_STRIKES}]", strikes)
    if args.restitution is not None:
        validate.number_in(args.restitution, "--restitution", 0.0, 1.0)
    max_period = MJCF_MAX_PERIOD if args.max_period is None else float(
        validate.positive_number(args.max_period, "--max-period", "s"))
    if max_period > MAX_MAX_PERIOD:
        raise InputError("--max-period", f"must be <= {MAX_MAX_PERIOD:g} s", max_period)
    shift = parse_shifts(args.shift)
    motion = mjcf_model(args.file, keyframe=args.keyframe, restitution=args.restitution)
    if motion.quaternion_joints:
        raise InputError(f"{args.file}: {motion.quaternion_joints[0]}", "carnot cycle "
                         "(periodic orbits) is not supported yet for free or ball joints (nq "
                         "!= nv)", show_value=False)  # fmt: skip
    try:
        cycle = find_cycle(motion.model, motion.state, motion.law, steps=strikes,
                           tolerance=MJCF_TOLERANCE, shift=shift, cyclic=args.cyclic or (),
                           max_period=max_period)  # fmt: skip
    except InputError as err:  # (a shift or cyclic name: the flag's)
        if err.field.startswith(("shift ", "cyclic ")):
            raise InputError(f"--{err.field}", err.problem, err.value,
                             show_value=err.show_value) from None  # fmt: skip
        raise
    fd = finite_difference_multipliers(cycle) if args.check and cycle.converged else None
    hint = None if cycle.converged or shift or args.cyclic else SYMMETRY_HINT
    print(cycle_report(cycle, motion.title, fd, as_json=args.json, digits=9, hint=hint))
    return 0


def cycle_report(cycle: Any, title: str, fd: Any, *, as_json: bool, digits: int,
                 hint: str | None = None) -> str:  # fmt: skip
    """``carnot cycle``'s output: the orbit's JSON (section 10) or text, with ``--check``'s
    finite-difference multipliers ``fd`` (None: not asked, or no orbit) and a ``hint``."""
    from carnot.hybrid.output import cycle_to_dict, format_cycle
    from carnot.io.json_text import dumps

    if as_json:
        out = cycle_to_dict(cycle, title)
        if fd is not None:
            out["multipliers_finite_difference"] = [[float(z.real), float(z.imag)] for z in fd]
        if hint:
            out["hint"] = hint
        return str(dumps(out))
    text = format_cycle(cycle, title)
    if fd is not None:
        text += "\n  finite differences: " + ", ".join(
            f"{z.real:.{digits}f}{z.imag:+.{digits}f}i" for z in fd)
    if hint:
        text += "\n  hint: " + hint
    return text


#: Said where an MJCF model's orbit is not found and no symmetry was declared.
SYMMETRY_HINT = ("no --shift or --cyclic was given: a wheel's pitch or a walker's position "
                 "along its floor advances every period, so such an orbit is periodic only up "
                 "to that symmetry (--shift pitch=pi/4, --cyclic x; docs/motion.md)")


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

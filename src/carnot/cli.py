"""The command line: ``carnot solve FILE [--json]``, ``carnot paper [--json] [--symbolic]``,
``carnot prove``, ``carnot derive FILE``, ``carnot sweep FILE --vary ... --out ...``. Thin:
parsing and printing only, no physics.

Bad input exits with status 2 and one line on stderr (``carnot: error: ...``), never a
traceback.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
from collections.abc import Sequence
from typing import Any

import carnot
from carnot.errors import CarnotError, InputError

EXIT_INPUT = 2


def _solve(args: argparse.Namespace) -> int:
    from carnot.io.results import result_to_json
    from carnot.io.scenario import load_problem
    from carnot.io.table import format_result
    from carnot.solve import solve_impact

    if args.contact is not None and not args.plot:
        raise InputError("--contact", "chooses the contact to draw: it goes with --plot",
                         args.contact)  # fmt: skip
    problem = load_problem(args.file)
    solver = None
    if args.solver is not None or args.trace_families:
        from dataclasses import replace

        from carnot.solvers.options import SolverOptions

        base = problem.solver or SolverOptions()
        try:
            solver = replace(base, name=args.solver or base.name,
                             trace_families=base.trace_families or args.trace_families)  # fmt: skip
        except InputError as err:
            raise InputError("--solver", err.problem, args.solver) from None
    try:
        result = solve_impact(problem, solver=solver)
    except InputError as err:  # found while solving: still name the file
        raise _in_file(args.file, err) from None
    except CarnotError as err:  # the frictional integration (a jam): the file and the contact
        # a system's contact carries its law as a free-body contact
        contacts: list[Any] = [getattr(c, "contact", c) for c in problem.contacts]
        slipping = [c.where for c in contacts if c.slips_with_friction]
        where = f"{slipping[0]}: " if len(slipping) == 1 else ""
        raise CarnotError(f"{args.file}: {where}{err}") from None
    proved = [w for w in result.warnings if w.code == "no_solution"]
    if proved:  # no answer exists (proved): a result would be a false answer (DESIGN.md s. 9)
        raise CarnotError(f"{args.file}: {proved[0].where}: no impulses meet the law's "
                          "conditions together (the contacts and constraints conflict): "
                          "the impact has no answer")  # fmt: skip
    if args.plot and result.multiple_impact is not None and args.contact is None:
        from carnot.plot_several import LEDGER_FROM, plot_laws, plot_ledger

        if len(result.contacts) >= LEDGER_FROM:  # many contacts: where the energy went
            plot_ledger(result, args.plot)
        else:  # a few: the laws side by side
            plot_laws(problem, args.plot)
    elif args.plot:
        from carnot.plot import plot_impact

        try:
            plot_impact(result, args.plot, contact=args.contact)
        except InputError as err:
            raise type(err)(
                f"{args.file}: --{err.field.replace('.', ' --')}", err.problem, err.value,
                show_value=err.show_value,
            ) from None  # fmt: skip
    print(result_to_json(result) if args.json else format_result(result))
    return 0


def _paper(args: argparse.Namespace) -> int:
    from carnot.io.audit_table import audit_to_json, format_audit
    from carnot.paper import run_audit, theorem_checks

    if args.symbolic:
        from carnot.paper.symbolic_audit import run_symbolic_audit

        verdicts, _ = run_symbolic_audit()
        if args.json:
            print(audit_to_json(verdicts))
        else:
            print(format_audit(verdicts, symbolic=True))
        return 0
    verdicts = run_audit()
    if args.json:
        print(audit_to_json(verdicts))
    else:
        print(format_audit(verdicts, theorem_checks()))
    return 0


def _prove(args: argparse.Namespace) -> int:
    from carnot.symbolic.proofs import prove

    proofs = prove()
    if args.json:
        print(json.dumps([p.__dict__ for p in proofs], indent=2, allow_nan=False))
        return 0
    print("Section 2 of the paper as identities, for general 3D bodies (SymPy)")
    for p in proofs:
        verdict = "identity" if p.holds else "NOT an identity"
        print(f"  {p.id:<18} {verdict:<16} {p.seconds:6.1f} s  {p.where}")
        print(f"  {'':<18} {p.statement}")
        if p.note:
            print(f"  {'':<18} note: {p.note}")
    return 0


def _derive(args: argparse.Namespace) -> int:
    from carnot.io.scenario import parse_scenario, read_scenario_data, shaped_bodies
    from carnot.laws.registry import several_contacts
    from carnot.symbolic.active_sets import derive_active_sets
    from carnot.symbolic.convert import default_symbols
    from carnot.symbolic.derive import (
        as_latex,
        as_python,
        as_text,
        derive_problem,
        several_as_latex,
        several_as_python,
        several_as_text,
    )

    data = read_scenario_data(args.file)
    problem = parse_scenario(data, args.file)
    if args.list:
        for key, name in default_symbols(problem).items():
            print(f"{name:<14} {key}")
        return 0
    specs = [s for s in (args.symbols or "").split(",") if s.strip()]
    try:
        if several_contacts(problem.contacts):  # one closed form per active set
            symbols, several = derive_active_sets(problem, specs, shaped_bodies(data))
        else:
            symbols, result = derive_problem(problem, specs, shaped_bodies(data))
    except InputError as err:  # a scenario key: name the file too (an option: as it is)
        if err.field.startswith("--"):
            raise
        raise _in_file(args.file, err) from None
    if several_contacts(problem.contacts):
        draw = (several_as_latex if args.latex else several_as_python if args.python
                else several_as_text)  # fmt: skip
        print(draw(symbols, several, problem.title))
        return 0
    render = as_latex if args.latex else as_python if args.python else as_text
    print(render(symbols, result, problem.title))
    return 0


def _in_file(file: str, err: InputError) -> InputError:
    """``err`` about a key of the scenario file ``file``, with the file named first."""
    return type(err)(f"{file}: {err.field}", err.problem, err.value, show_value=err.show_value)


def _sweep(args: argparse.Namespace) -> int:
    from carnot.sweep import sweep_file

    if args.plot:  # a bad picture path is refused before the sweep runs
        from carnot.plot_sweep import check_plot_path

        check_plot_path(args.plot)
    report = sweep_file(
        args.file, args.out, vary=args.vary, random=args.random, samples=args.samples,
        seed=args.seed, chunk_size=args.chunk_size, workers=args.workers,
        scheduler=args.scheduler, progress=args.progress or sys.stderr.isatty(),
        record=args.record, compiled=args.compiled,
    )  # fmt: skip
    unit = {"simulate": "simulations", "cycle": "orbits",
            "free_cycle": "orbits"}.get(report.route, "impacts")
    flagged = ", ".join(f"{k}: {v}" for k, v in report.flag_counts.items() if v)
    failed = f"; not computed: {report.failed}" if report.failed else ""
    flagged = f"; flagged {flagged}" if flagged else ""
    print(f"{report.rows} {unit} -> {report.path} ({report.route}, {report.runner}, "
          f"{report.seconds:.2f} s){flagged}{failed}")  # fmt: skip
    if report.failed:  # one line on stderr too: a script reading stdout alone must not miss it
        print(f"carnot: warning: {report.failed} of {report.rows} {unit} could not be "
              "computed: their results are NaN, the reason in the error column",
              file=sys.stderr)  # fmt: skip
    if args.plot:
        from carnot.plot_sweep import plot_sweep

        plot_sweep(report.path, args.plot)
        print(f"plot -> {args.plot}")
    return 0


def _from_mjcf(args: argparse.Namespace) -> int:
    from carnot.io.system_scenario import system_scenario_toml
    from carnot.model.mjcf import mjcf_problem

    problem = mjcf_problem(
        args.model, keyframe=args.keyframe, qpos=args.qpos, qvel=args.qvel,
        restitution=args.restitution, law=args.law, tangential=args.tangential,
        friction=args.friction, equality=args.equality, drift=args.drift,
        gap=1e-6 if args.gap is None else args.gap, resting=args.resting,
        limits=not args.no_limits,
    )  # fmt: skip
    text = system_scenario_toml(problem)
    if args.output:
        with open(args.output, "w", encoding="utf-8") as out:
            out.write(text)
    else:
        print(text, end="")
    return 0


def _add_from_mjcf(sub: Any) -> None:
    mjcf = sub.add_parser(
        "from-mjcf",
        help="write the [system] scenario of a MuJoCo model's impact (carnot[mujoco])",
        description="Build the system of an MJCF model in a keyframe's state and/or the given "
        "qpos and qvel (MuJoCo's mass matrix, each approaching contact's point Jacobian, "
        "normal and friction, each joint limit MuJoCo enforces then, each equality "
        "constraint's rows) and write it as a [system] scenario (TOML) to inspect, edit and "
        "solve with carnot solve. The options are carnot audit's, so that an episode's "
        "reference can be rebuilt from its qpos_before and qvel_before.",
    )
    mjcf.add_argument("model", help="MJCF file (.xml)")
    mjcf.add_argument("--keyframe", metavar="K", help="keyframe name or index")
    _add_mjcf_state_options(mjcf, "the positions", "the velocities before the impact")
    mjcf.add_argument("--resting", action="store_true",
                      help="keep the contacts at rest (n . w' = 0) too, as carnot audit's "
                      "references do")  # fmt: skip
    _add_mjcf_law_options(mjcf, "every contact", default_gap="1e-6 m")
    mjcf.add_argument("-o", "--output", metavar="FILE", help="write here instead of stdout")
    mjcf.set_defaults(run=_from_mjcf)
    _numbers_as_values(mjcf)


#: A negative number in any form NumPy prints (``-1e-05``, ``-1.e-05``, ``-.5``, ``-inf``,
#: ``-nan``): argparse's own pattern (``-\d+`` or ``-\d*.\d+``) takes ``-1e-5`` for an option.
_NEGATIVE_NUMBER = re.compile(
    r"^-(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf|infinity|nan)$", re.IGNORECASE
)


def _numbers_as_values(parser: argparse.ArgumentParser) -> None:
    """Let ``parser`` read every negative number as a value (``--qvel 0 0 -1e-5``): none of
    its options looks like one, so nothing becomes ambiguous. (argparse keeps its pattern
    in ``_negative_number_matcher``, the one attribute that decides this, in every Python
    since 2.7; tests/test_mjcf.py fails if that changes.)"""
    parser._negative_number_matcher = _NEGATIVE_NUMBER


def _add_mjcf_state_options(parser: Any, qpos_help: str, qvel_help: str) -> None:
    """``--qpos`` and ``--qvel`` (from-mjcf: the impact's state; audit: the rollout's start)."""
    parser.add_argument(
        "--qpos", type=float, nargs="+", metavar="Q",
        help=f"{qpos_help} (model.nq numbers; after the keyframe's, when both are given)",
    )  # fmt: skip
    parser.add_argument("--qvel", type=float, nargs="+", metavar="V",
                        help=f"{qvel_help} (model.nv numbers)")  # fmt: skip


def _add_mjcf_law_options(parser: Any, whose: str, *, default_gap: str) -> None:
    """The contact law options of a command that reads a MuJoCo model (from-mjcf, audit)."""
    parser.add_argument("--restitution", type=float, default=0.0,
                        help=f"e of {whose} (default 0)")  # fmt: skip
    parser.add_argument("--law", default="newton", help="newton | poisson | stronge")
    parser.add_argument("--tangential", choices=("slip", "stick"), default="slip",
                        help="slip (Coulomb) or stick; a contact MuJoCo declares "
                        "frictionless (condim 1) stays frictionless either way")  # fmt: skip
    parser.add_argument(
        "--friction", type=float, default=None,
        help=f"Coulomb mu of {whose} (default: MuJoCo's, from the geoms; condim 1 keeps 0)",
    )  # fmt: skip
    parser.add_argument("--gap", type=float, default=None, metavar="M",
                        help=f"the contacts within this distance (m) take part (default "
                        f"{default_gap})")  # fmt: skip
    parser.add_argument(
        "--equality", choices=("pin", "fasten", "ignore"), default="pin",
        help="what each equality constraint becomes: pin (held before and after, default), "
        "fasten (imposed by the impact), ignore (left out)",
    )  # fmt: skip
    parser.add_argument(
        "--drift", type=float, default=None, metavar="V",
        help="with --equality pin: the drift |J q'| (m/s, rad/s) a pin accepts before the "
        "impact (MuJoCo's equalities are soft; default: round-off only)",
    )  # fmt: skip
    parser.add_argument("--no-limits", action="store_true",
                        help="leave the joint and tendon limits out (default: each limit "
                        "MuJoCo enforces is a unilateral contact)")  # fmt: skip


def _audit(args: argparse.Namespace) -> int:
    from carnot.io.rollout_report import format_report, report_to_json
    from carnot.rollout import RigidSettings, audit_model, audit_recording

    rigid = RigidSettings(
        restitution=args.restitution, law=args.law, tangential=args.tangential,
        friction=args.friction, multiple_impact=args.multiple_impact, scope=args.rigid_scope,
        gap=args.gap, equality=args.equality, drift=args.drift, limits=not args.no_limits,
    )  # fmt: skip
    if args.rollout:
        names = ("keyframe", "duration", "qpos", "qvel")
        given = [n for n in names if getattr(args, n) is not None]
        if given:
            raise InputError("--rollout", f"replays a recording: --{given[0]} is for a rollout "
                             "run here", args.rollout)  # fmt: skip
        report = audit_recording(args.model, args.rollout, rigid=rigid, min_speed=args.min_speed)
    else:
        duration = 1.0 if args.duration is None else args.duration
        report = audit_model(args.model, keyframe=args.keyframe, duration=duration, rigid=rigid,
                             min_speed=args.min_speed, qpos=args.qpos,
                             qvel=args.qvel)  # fmt: skip
    if args.plot:
        from carnot.plot_rollout import plot_audit

        plot_audit(report, args.plot)
    print(report_to_json(report) if args.json else format_report(report))
    for warning in report.warnings:  # also where only the JSON is read
        print(f"carnot: warning: {warning}", file=sys.stderr)
    return 0


def _add_audit(sub: Any) -> None:
    audit = sub.add_parser(
        "audit",
        help="where a MuJoCo rollout's energy went, impact by impact (carnot[mujoco])",
        description="Run an MJCF model (or replay a recorded rollout) and audit every step "
        "exactly: the change of kinetic energy equals the work of each constraint row over "
        "the mean of its velocities before and after the step plus the work of gravity, "
        "passive and actuator forces (Euler, implicitfast, implicit). List each contact's "
        "impact episodes with the energy MuJoCo removed, its effective restitution, and "
        "carnot's rigid outcome from the same pre-impact state.",
    )
    audit.add_argument("model", help="MJCF file (.xml)")
    audit.add_argument("--keyframe", metavar="K", help="start from this keyframe (name or index)")
    _add_mjcf_state_options(audit, "the positions to start from",
                            "the velocities to start from")  # fmt: skip
    audit.add_argument("--duration", type=float, metavar="T", help="seconds to run (default 1)")
    audit.add_argument("--rollout", metavar="FILE.npz",
                       help="replay this recording (qpos, qvel; see docs/audit.md)")
    _add_mjcf_law_options(audit, "the rigid reference",
                          default_gap="the model's largest geom margin")  # fmt: skip
    audit.add_argument("--multiple-impact", default="simultaneous",
                       help="simultaneous | sequential | dispersion (several contacts at once)")
    audit.add_argument("--rigid-scope", default="coupled",
                       help="coupled (the contacts coupled to the episode's pair) | scene (all)")
    audit.add_argument("--min-speed", type=float, default=None, metavar="V",
                       help="approach speed (m/s) that opens an episode (default 2 |g| h)")
    audit.add_argument("--json", action="store_true", help="print the audit as JSON (format 1)")
    audit.add_argument("--plot", metavar="OUT", help="draw the energy over time with the "
                       "episodes and the rigid reference (.png, .svg, .pdf)")
    audit.set_defaults(run=_audit)
    _numbers_as_values(audit)


def _add_sweep(sub: Any) -> None:
    sweep = sub.add_parser(
        "sweep",
        help="solve a scenario over a grid or Monte Carlo samples of its values",
        description="Vary numbers of a scenario (key paths such as contacts.0.restitution or "
        "bodies.ball.velocity.2) over a grid (--vary) and/or by Monte Carlo (--random; "
        "combined, every grid point gets the same --samples draws) and write one row per "
        "impact (the varied values, impulses, velocities after, energies, regime, flags) to "
        "Parquet or CSV. One point contact runs in the batch kernel (any law, friction); "
        "anything else (several contacts, constraints, patches) in a slow loop over "
        "solve_impact. A simulation scenario ([simulation]) gives one row per run: the "
        "quantities of --record (overturned, max_tilt, impacts, energies, ...).",
    )
    sweep.add_argument("file", help="scenario file (.toml, or .json)")
    sweep.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="KEY=START:STOP:COUNT",
        help="a grid of COUNT values from START to STOP (repeat for a product)",
    )
    sweep.add_argument(
        "--random",
        action="append",
        default=[],
        metavar="KEY=DIST(...)",
        help="Monte Carlo: uniform(low, high), loguniform(low, high), "
        "normal(mu, sigma), lognormal(mu, sigma), truncnorm(mu, sigma, low, high)",
    )
    sweep.add_argument("--samples", type=_integer, help="Monte Carlo samples (with --random)")
    sweep.add_argument("--seed", type=_integer, help="random seed (with --random; default 0)")
    sweep.add_argument("--out", required=True, help="results file (.parquet or .csv)")
    sweep.add_argument(
        "--plot",
        metavar="OUT",
        help="draw the dissipated energy (and the "
        "regime) over the first one or two varied keys (.png, .svg, .pdf)",
    )
    sweep.add_argument(
        "--chunk-size",
        type=_integer,
        help="rows per chunk (default 16384; 512 on the solve_impact loop)",
    )
    sweep.add_argument(
        "--record", action="append", default=[], metavar="Q[,Q...]",
        help="simulation scenarios: the quantities of each run (default all: docs/simulation.md)",
    )  # fmt: skip
    sweep.add_argument(
        "--compiled", action=argparse.BooleanOptionalAction, default=None,
        help="take a compiled kernel whenever the scenario fits one (--no-compiled: never); "
        "default: only beyond 1000 rows of one contact or 100 of several, where the "
        "solve_impact loop would not finish before a cold kernel compiles",
    )  # fmt: skip
    sweep.add_argument("--workers", type=_integer,
                       help="local threads, processes for simulations (default: CPU count)")
    sweep.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run the chunks on this Dask scheduler (tcp://host:8786)",
    )
    sweep.add_argument(
        "--progress",
        action="store_true",
        help="a progress bar on stderr (default: when stderr is a terminal)",
    )
    sweep.set_defaults(run=_sweep)


def _one_line_errors(parser: argparse.ArgumentParser, command: str | None) -> None:
    """argparse's own errors (an unknown option, a missing argument) as one line on stderr
    naming the sub-command, status 2, instead of its usage block and a second line."""

    def one_line(message: str) -> Any:
        where = f"{command}: " if command else ""
        hint = f"carnot {command} --help" if command else "carnot --help"
        _refuse(Exception(f"{where}{message} (see {hint})"))
        raise SystemExit(EXIT_INPUT)

    parser.error = one_line  # type: ignore[method-assign]


def _integer(text: str) -> int:
    """An integer option; anything else is an input error (status 2), as argparse's."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (one sub-command per job)."""
    parser = argparse.ArgumentParser(
        prog="carnot",
        description="Rigid-body impact mechanics with exact energy bookkeeping.",
    )
    parser.add_argument("--version", action="version", version=f"carnot {carnot.__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    solve = sub.add_parser(
        "solve",
        help="solve the impact of a scenario file",
        description="Solve the impact described by a scenario file (TOML or JSON, format 1) "
        "and print a readable report, or result format 1 with --json.",
    )
    solve.add_argument("file", help="scenario file (.toml, or .json)")
    solve.add_argument("--json", action="store_true", help="print result format 1 (JSON)")
    solve.add_argument(
        "--plot",
        metavar="OUT",
        help="draw a frictional contact's relative velocity and work against the normal "
        "impulse, with its phases, to OUT (.png, .svg or .pdf); with several contacts, the "
        "outgoing velocities and each contact's dissipated energy under each multiple-impact "
        "law side by side; with 13 or more, where the energy went, contact by contact",
    )
    solve.add_argument(
        "--contact", type=int, default=None,
        help="with --plot: the index of the contact to draw (default: the first frictional one)",
    )  # fmt: skip
    solve.add_argument(
        "--solver", metavar="NAME", default=None,
        help="the solver of several contacts at once: auto (the default: enumerate where the "
        "regimes are few, iterate beyond), enumerate (every regime: exact, verifies "
        "uniqueness) or iterative (ADMM and Newton: scales to thousands of contacts); "
        "overrides the file's [solver] name, keeps its tolerance",
    )  # fmt: skip
    solve.add_argument(
        "--trace-families", action="store_true",
        help="where the answers of several contacts form a family along which the slip "
        "directions turn (a box sliding on four corners), trace it for the range of E_d over "
        "it (the certificate's dissipated_range; every regime tried: up to a second)",
    )  # fmt: skip
    solve.set_defaults(run=_solve)
    paper = sub.add_parser(
        "paper",
        help="reproduce the paper's section 3 and audit its printed formulas",
        description="Solve the paper's three examples over grids of parameters and compare "
        "every printed formula with the solver (and the theorem); --symbolic compares them "
        "with closed forms derived by SymPy instead.",
    )
    paper.add_argument("--json", action="store_true", help="one JSON object per formula")
    paper.add_argument("--symbolic", action="store_true", help="derive the closed forms with SymPy")
    paper.set_defaults(run=_paper)
    prove = sub.add_parser(
        "prove",
        help="prove the paper's section 2 identities with SymPy",
        description="Prove eqs. (11), (15), (16) and Carnot's condition (12)-(13) for general "
        "3D bodies with general symmetric inertia tensors: the difference of the two sides "
        "expands to 0.",
    )
    prove.add_argument("--json", action="store_true", help="one JSON object per identity")
    prove.set_defaults(run=_prove)
    derive = sub.add_parser(
        "derive",
        help="closed-form results of a scenario, with chosen values as symbols",
        description="Derive the closed forms of everything 'carnot solve' reports, with the "
        "values named by --symbols as SymPy symbols and every other number exact.",
    )
    derive.add_argument("file", help="scenario file (.toml, or .json)")
    derive.add_argument(
        "--symbols",
        help="comma-separated key paths (bodies.ball.mass, contacts.0.restitution, "
        "bodies.ball.velocity.2), each optionally KEY=NAME, or default names (m_ball, e): "
        "see --list",
    )
    derive.add_argument("--list", action="store_true", help="list the keys and default names")
    form = derive.add_mutually_exclusive_group()
    form.add_argument("--latex", action="store_true", help="print a LaTeX align* block")
    form.add_argument("--python", action="store_true", help="print a NumPy function's source")
    derive.set_defaults(run=_derive)
    _add_sweep(sub)
    _add_from_mjcf(sub)
    _add_audit(sub)
    from carnot.simulate.command import add_simulate  # argparse only: no numpy on import

    add_simulate(sub)
    from carnot.hybrid.command import add_cycle  # argparse only

    add_cycle(sub)

    def run_explore(args: argparse.Namespace) -> int:  # carnot explore: the teaching page
        from carnot.explore.server import serve

        serve(args.port, open_browser=not args.no_browser)
        return 0

    explore = sub.add_parser(
        "explore",
        help="an interactive page for teaching: classic impacts with sliders (local, offline)",
        description="Serve a web page on 127.0.0.1 (offline; Ctrl-C stops it) where one "
        "chooses a classic impact, moves its parameters with sliders and sees carnot's "
        "answer: the impulse, the velocities after, the Darboux-Keller path in impulse space "
        "and the energy ledger.",
    )
    explore.add_argument(
        "--port", type=_integer, default=8765, help="port on 127.0.0.1 (default 8765; 0: any)"
    )
    explore.add_argument("--no-browser", action="store_true", help="do not open a browser")
    explore.set_defaults(run=run_explore)
    return parser


def _finish_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Every parser's errors on one line (sub-commands added after build_parser included)."""
    _one_line_errors(parser, None)
    for action in _sub_actions(parser):
        for name, sub in action.choices.items():
            _one_line_errors(sub, name)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = _finish_parser(build_parser())
    args, extra = parser.parse_known_args(argv)
    if not hasattr(args, "run"):
        parser.print_help()  # on stdout: what a user typing "carnot" alone wants to see
        commands = ", ".join(_commands(parser))
        _refuse(Exception(f"a command is needed ({commands}; see carnot --help)"))
        return EXIT_INPUT
    if extra:  # reported by the sub-command's parser: its name and its --help
        _subparser(parser, args.command).error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        return int(args.run(args))
    except BrokenPipeError:  # the reader went away (carnot ... | head): not an input error
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes stdout
        return 1
    except (CarnotError, OSError) as err:  # OSError: a file that failed
        _refuse(err)
        return EXIT_INPUT


def _sub_actions(parser: argparse.ArgumentParser) -> list[Any]:
    group = parser._subparsers._group_actions if parser._subparsers else []
    return [a for a in group if isinstance(a, argparse._SubParsersAction)]


def _commands(parser: argparse.ArgumentParser) -> list[str]:
    return [name for action in _sub_actions(parser) for name in action.choices]


def _subparser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    for action in _sub_actions(parser):
        if command in action.choices:
            return action.choices[command]
    return parser  # pragma: no cover - args.command is always one of them


def _refuse(err: Exception) -> None:
    """The one line on stderr (a key or value with a line break must not make two)."""
    message = " ".join(str(err).splitlines())
    print(f"carnot: error: {message}", file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""The command line: ``carnot solve FILE [--json]``, ``carnot paper [--json] [--symbolic]``,
``carnot prove``, ``carnot derive FILE``. Thin: parsing and printing only, no physics.

Bad input exits with status 2 and one line on stderr (``carnot: error: ...``), never a
traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

import carnot
from carnot.errors import CarnotError, InputError

EXIT_INPUT = 2


def _solve(args: argparse.Namespace) -> int:
    from carnot.io.results import result_to_json
    from carnot.io.scenario import load_scenario
    from carnot.io.table import format_result
    from carnot.solve import solve_impact

    problem = load_scenario(args.file)
    try:
        result = solve_impact(problem)
    except InputError as err:  # found while solving: still name the file
        raise type(err)(
            f"{args.file}: {err.field}", err.problem, err.value, show_value=err.show_value
        ) from None
    print(result_to_json(result) if args.json else format_result(result))
    return 0


def _paper(args: argparse.Namespace) -> int:
    from carnot.io.audit_table import format_audit
    from carnot.paper import run_audit, theorem_checks, verdict_to_dict

    if args.symbolic:
        from carnot.symbolic.paper_audit import run_symbolic_audit

        verdicts, _ = run_symbolic_audit()
        if args.json:
            print(json.dumps([verdict_to_dict(v) for v in verdicts], indent=2))
        else:
            print(format_audit(verdicts, symbolic=True))
        return 0
    verdicts = run_audit()
    if args.json:
        print(json.dumps([verdict_to_dict(v) for v in verdicts], indent=2))
    else:
        print(format_audit(verdicts, theorem_checks()))
    return 0


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
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "run"):
        parser.print_help()
        return EXIT_INPUT
    try:
        return int(args.run(args))
    except CarnotError as err:
        print(f"carnot: error: {err}", file=sys.stderr)
        return EXIT_INPUT


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

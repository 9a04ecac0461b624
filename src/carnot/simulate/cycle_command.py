"""``carnot cycle FILE`` on a section 8 scenario of free bodies: reading the ``[cycle]``
table and ``--strikes``, printing the orbit (the physics is in :mod:`carnot.simulate.cycle`).
``carnot cycle`` itself is registered by :mod:`carnot.hybrid.command`, which sends a file
without ``[model]`` here."""

from __future__ import annotations

import argparse
from typing import Any


def run_free_cycle(args: argparse.Namespace, data: Any) -> int:
    """``carnot cycle`` on a section 8 scenario of free bodies (simulate/cycle.py): the
    ``[cycle]`` table, ``--strikes`` over it, the orbit printed as text or JSON."""
    from pathlib import Path

    from carnot.errors import InputError
    from carnot.simulate.cycle import find_cycle
    from carnot.simulate.cycle_output import format_free_cycle, free_cycle_to_json
    from carnot.simulate.scenario import MAX_STRIKES, cycle_settings, parse_simulation

    if isinstance(data, dict) and isinstance(data.get("simulation"), dict) and \
            "duration" not in data["simulation"]:  # fmt: skip
        # carnot cycle flies each return as long as it takes; the duration is simulate's
        data = {**data, "simulation": {**data["simulation"], "duration": 1.0}}
    try:
        strikes, tolerance = cycle_settings(data if isinstance(data, dict) else {})
        sim = parse_simulation(data, Path(args.file).parent)
        if args.strikes is not None:
            strikes = args.strikes
            if not 1 <= strikes <= MAX_STRIKES:
                raise InputError("--strikes", f"must be in [1, {MAX_STRIKES}]", strikes)
        cycle = find_cycle(sim, strikes=strikes, tolerance=tolerance, check=args.check)
    except InputError as err:
        if err.field.startswith("--"):
            raise
        raise type(err)(f"{args.file}: {err.field}", err.problem, err.value,
                        show_value=err.show_value) from None  # fmt: skip
    text = free_cycle_to_json if args.json else format_free_cycle
    print(text(cycle, sim.title))
    return 0

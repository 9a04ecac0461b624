"""``carnot simulate``: event-driven motion of rigid bodies with exact impacts and an energy
ledger for every one (DESIGN.md section 8).

Free flight is exact where a closed form exists (motion.py), impacts are found as zeros of the
gaps (events.py) and solved by :func:`carnot.solve_impact` (impacts.py), persistent contacts
follow the acceleration-level complementarity problem (contacts.py), Zeno series are summed
(zeno.py), ground motion is a prescribed acceleration record, a one-cycle pulse or a
sustained oscillation (ground.py); loop.py is the
loop (``run``), scenario.py the file format and output.py the reports.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from carnot.simulate.loop import Event, Ledger, Simulation, SimulationResult, run
    from carnot.simulate.scenario import load_simulation, parse_simulation

_WHERE = {"Event": "loop", "Ledger": "loop", "Simulation": "loop", "SimulationResult": "loop",
          "run": "loop", "load_simulation": "scenario", "parse_simulation": "scenario"}


def __getattr__(name: str) -> Any:
    """Lazy: the command line registers ``simulate`` (command.py) without importing SciPy."""
    if name not in _WHERE:
        raise AttributeError(f"module 'carnot.simulate' has no attribute {name!r}")
    from importlib import import_module

    return getattr(import_module(f"carnot.simulate.{_WHERE[name]}"), name)

__all__ = [
    "Event",
    "Ledger",
    "Simulation",
    "SimulationResult",
    "load_simulation",
    "parse_simulation",
    "run",
]

"""``carnot simulate``: event-driven motion of rigid bodies with exact impacts and an energy
ledger for every one (DESIGN.md section 8).

Free flight is exact where a closed form exists (motion.py), impacts are found as zeros of the
gaps (events.py) and solved by :func:`carnot.solve_impact` (impacts.py), persistent contacts
follow the acceleration-level complementarity problem (contacts.py), Zeno series are summed
(zeno.py), ground motion is a prescribed acceleration record (ground.py); run.py is the loop,
scenario.py the file format and output.py the reports.
"""

from carnot.simulate.run import Event, Ledger, Simulation, SimulationResult, run
from carnot.simulate.scenario import load_simulation, parse_simulation

__all__ = [
    "Event",
    "Ledger",
    "Simulation",
    "SimulationResult",
    "load_simulation",
    "parse_simulation",
    "run",
]

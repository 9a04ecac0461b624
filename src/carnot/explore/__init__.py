"""``carnot explore``: an interactive page for teaching impacts (local, offline).

Choose a classic (cylinder on an edge, rod on a ledge, sphere with spin, Newton's cradle), move
its sliders and see the impulse, the velocities after, the Darboux-Keller path in impulse space
and the energy ledger. The page only displays: every number comes from ``carnot.solve_impact``
through a JSON endpoint (:mod:`carnot.explore.server`).
"""

from carnot.explore.classics import CLASSICS, Classic, Parameter
from carnot.explore.server import make_server, serve, solve_request

__all__ = ["CLASSICS", "Classic", "Parameter", "make_server", "serve", "solve_request"]

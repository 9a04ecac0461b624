"""Several contacts at once (DESIGN.md section 6, issue 14): three multiple-impact laws that
see only contact space (the Delassus operator ``G``, the row velocities ``w'``, and per
contact its rows and parameters).

* :func:`resolve_simultaneous`: Moreau/Glocker generalized Newton with Coulomb friction, as a
  complementarity problem solved by regime enumeration (uniqueness verified).
* :func:`resolve_sequential`: pairwise sub-impacts, most negative normal velocity first.
* :func:`resolve_dispersion`: the energetic law of Liu, Zhao and Brogliato (2008).
"""

from collections.abc import Callable

from carnot.laws.multiple.dispersion import resolve_dispersion
from carnot.laws.multiple.rows import (
    FLAGS,
    Certificate,
    ContactOutcome,
    ContactRows,
    HeldRows,
    MultipleImpactOutcome,
    Stage,
    dissipated_by_row,
)
from carnot.laws.multiple.sequential import resolve_sequential
from carnot.laws.multiple.simultaneous import resolve_simultaneous

#: The multiple-impact laws by their scenario name (``multiple_impact = "..."``).
MULTIPLE_IMPACT_LAWS: dict[str, Callable[..., MultipleImpactOutcome]] = {
    "simultaneous": resolve_simultaneous,
    "sequential": resolve_sequential,
    "dispersion": resolve_dispersion,
}

__all__ = [
    "FLAGS",
    "MULTIPLE_IMPACT_LAWS",
    "Certificate",
    "ContactOutcome",
    "ContactRows",
    "HeldRows",
    "MultipleImpactOutcome",
    "Stage",
    "dissipated_by_row",
    "resolve_dispersion",
    "resolve_sequential",
    "resolve_simultaneous",
]

"""Draw the README's figure, docs/readme-figure.png: the impulse-space picture of
examples/rod_rough_floor.toml (slip, then reversal), as `carnot solve FILE --plot OUT` draws it.

Run from the repository root: ``.venv/bin/python docs/readme_figure.py``.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import carnot  # noqa: E402
from carnot.io.scenario import load_scenario  # noqa: E402
from carnot.plot import plot_impact  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

result = carnot.solve_impact(load_scenario(ROOT / "examples" / "rod_rough_floor.toml"))
figure = plot_impact(result, ROOT / "docs" / "readme-figure.png")
print("docs/readme-figure.png:", result.contacts[0].regime)

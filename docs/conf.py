"""Sphinx configuration of carnot's documentation (``make docs``: warnings are errors, offline).

Why Sphinx with the PyData theme and sphinx-gallery (rather than MkDocs Material with
mkdocstrings): the API reference comes from the docstrings with autodoc/autosummary, which
read carnot's doctest-bearing docstrings as they are; sphinx-gallery runs the example scripts
at build time and shows their figures, the pattern of NumPy, SciPy, Matplotlib and
scikit-learn; and the theme is the one those projects' readers already know. MyST lets the
prose pages be Markdown, like the README they came from.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # the gallery draws without a display

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT / "src"))
os.environ.setdefault("CARNOT_DOCS", "1")

import carnot  # noqa: E402

project = "carnot"
author = "the carnot developers"
copyright = "2026, the carnot developers"  # noqa: A001 - Sphinx's name
release = version = carnot.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip",
                    "generated/cli-help.md"]  # fmt: skip
templates_path = ["_templates"]
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3

# The API reference: autosummary writes one page per public name (the modules' __all__).
autosummary_generate = True
autosummary_ignore_module_all = False
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_typehints = "description"
autodoc_member_order = "bysource"

# Offline, to build and to read: no intersphinx (it would fetch inventories) and no MathJax (a
# CDN script); formulas are written as text, as in the docstrings.

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples" / "gallery"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "show_memory": False,
    "write_computation_times": False,  # its page loads scripts from a CDN: not offline
    "reset_modules_order": "both",
}

html_theme = "pydata_sphinx_theme"
html_title = f"carnot {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 4,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "**": ["sidebar-nav-bs"]}
html_show_sourcelink = False


def _write_cli_help(app: object) -> None:
    """docs/generated/cli-help.md: each command's --help, from the parser itself."""
    import argparse

    from carnot.cli import build_parser

    os.environ["COLUMNS"] = "90"  # argparse wraps to the terminal: the same page everywhere
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    parts = ["## carnot", "", "```text", parser.format_help().rstrip(), "```", ""]
    for name, command in sub.choices.items():
        parts += [f"## carnot {name}", "", "```text", command.format_help().rstrip(), "```", ""]
    out = DOCS / "generated" / "cli-help.md"
    out.parent.mkdir(exist_ok=True)
    text = "\n".join(parts)
    if not out.exists() or out.read_text(encoding="utf-8") != text:
        out.write_text(text, encoding="utf-8")


def setup(app: object) -> None:
    app.connect("builder-inited", _write_cli_help)  # type: ignore[attr-defined]

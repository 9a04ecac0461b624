"""The docs pages against the code: every `carnot ...` command in their shell blocks parses
with today's command line (a renamed option makes this fail, not a reader), every page is in
the site's table of contents, and the README links only to pages that exist. Building the
site itself (`make docs`, warnings as errors) is CI's step after this."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from carnot.cli import build_parser

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
PAGES = sorted(DOCS.glob("*.md"))


def _blocks(text: str) -> list[tuple[str, str]]:
    """The fenced code blocks of a Markdown page: (language, text)."""
    blocks, language, lines = [], None, []  # type: ignore[var-annotated]
    for line in text.splitlines():
        if line.startswith("```"):
            if language is None:
                language, lines = line[3:].strip(), []
            else:
                blocks.append((language, "\n".join(lines)))
                language = None
        elif language is not None:
            lines.append(line)
    return blocks


def _shell_commands() -> list[tuple[str, list[str]]]:
    found = []
    for page in PAGES:
        for language, block in _blocks(page.read_text(encoding="utf-8")):
            if language not in ("", "sh", "console"):
                continue
            for line in block.replace("\\\n", " ").splitlines():
                line = line.removeprefix("$ ").split(" > ")[0]
                if not line.startswith("carnot "):
                    continue
                argv = shlex.split(line, comments=True)
                if any(re.fullmatch(r"[A-Z]+|\[.*|.*\.\.\..*", a) for a in argv):
                    continue  # a usage line (FILE, [--list], KEY...), not a command
                found.append((page.name, argv))
    return found


COMMANDS = _shell_commands()


def test_the_pages_have_commands() -> None:
    assert len(COMMANDS) >= 10


@pytest.mark.parametrize(("page", "argv"), COMMANDS, ids=lambda x: x if isinstance(x, str)
                         else shlex.join(x))  # fmt: skip
def test_documented_commands_parse(page, argv) -> None:
    try:
        args = build_parser().parse_args(argv[1:])
    except SystemExit as done:  # argparse refused it (or --version printed and exited 0)
        assert done.code == 0, f"{page}: {shlex.join(argv)} does not parse (exit {done.code})"
        return
    assert hasattr(args, "run"), f"{page}: {shlex.join(argv)}"


def test_every_page_is_in_the_table_of_contents() -> None:
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"^([a-z_/]+)$", index, flags=re.M))
    pages = {p.stem for p in PAGES if p.stem != "index"} | {"api"}
    assert pages <= listed, pages - listed


def test_readme_links_exist() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    links = re.findall(r"\]\(((?:docs/)[^)#]+)\)", readme)
    assert links
    for link in links:
        assert (ROOT / link).exists(), link

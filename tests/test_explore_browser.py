"""carnot explore in a real browser: headless Chromium (Debian's, driven by Playwright) moves
the sliders of every classic, and every number the page shows is checked against
`carnot solve FILE --json` run in a separate process on the scenario the page displays.

Chromium comes from `make browser` (apt). Without it the test is skipped, except in CI
(CI=true), where it must run. Screenshots go to build/explore/ (a test artefact).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from carnot.explore import CLASSICS, make_server

ROOT = Path(__file__).resolve().parent.parent
ARTEFACTS = ROOT / "build" / "explore"
CONSOLE_SCRIPT = Path(sys.executable).parent / "carnot"
# Debian's /usr/bin/chromium is a shell wrapper around this binary.
CANDIDATES = ("/usr/lib/chromium/chromium", "/usr/bin/chromium", "/usr/bin/chromium-browser")


def _chromium() -> str | None:
    return next((c for c in CANDIDATES if os.access(c, os.X_OK)), shutil.which("chromium"))


@pytest.fixture(scope="module")
def page() -> Iterator[object]:
    executable = _chromium()
    if executable is None:
        if os.environ.get("CI") == "true":
            pytest.fail("CI must run the browser test: chromium is missing (run `make browser`)")
        pytest.skip("chromium is not installed (`make browser` installs it with apt)")
    from playwright.sync_api import sync_playwright

    server = make_server(0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(
                executable_path=executable, headless=True,
                args=["--no-sandbox", "--disable-dev-shm-usage"],
            )
            tab = browser.new_page(viewport={"width": 1280, "height": 1000})
            tab.goto(f"http://127.0.0.1:{server.server_address[1]}/")
            tab.wait_for_selector("body[data-state=ready]")
            yield tab
            browser.close()
    finally:
        server.shutdown()
        server.server_close()


def _settle(tab, seq_before: int) -> None:  # type: ignore[no-untyped-def]
    """Wait until the page shows the answer to a request newer than ``seq_before``."""
    tab.wait_for_function(
        "seq => document.body.dataset.state === 'ready' && +document.body.dataset.seq > seq",
        arg=seq_before,
    )


def _seq(tab) -> int:  # type: ignore[no-untyped-def]
    return int(tab.evaluate("document.body.dataset.seq"))


def _lookup(result: dict, key: str):  # type: ignore[no-untyped-def]
    node = result
    for part in key.split("."):
        node = node[int(part)] if isinstance(node, list) else node[part]
    return node


def _check_against_cli(tab, tmp_path: Path) -> int:  # type: ignore[no-untyped-def]
    """Every number shown (cells with data-key) against `carnot solve --json` on the scenario
    the page shows; returns how many were compared."""
    scenario = json.loads(tab.text_content("#scenario"))
    path = tmp_path / "scenario.json"
    path.write_text(json.dumps(scenario), encoding="utf-8")
    run = subprocess.run([str(CONSOLE_SCRIPT), "solve", str(path), "--json"],
                         capture_output=True, text=True, timeout=120)  # fmt: skip
    assert run.returncode == 0, run.stderr
    cli = json.loads(run.stdout)
    cells = tab.eval_on_selector_all(
        "[data-key]",
        "cells => cells.map(c => [c.dataset.key, c.dataset.value ?? null, c.textContent])",
    )
    assert cells, "the page shows no numbers"
    for key, value, text in cells:
        expected = _lookup(cli, key)
        if isinstance(expected, str):  # the regime
            assert text == expected, key
            continue
        shown = None if value == "null" else float(value)
        if expected is None:
            assert shown is None and text == "\u2014", key
            continue
        assert shown == pytest.approx(expected, rel=1e-12, abs=1e-12), key
        # The text is the same number to the 4 significant digits it shows.
        if abs(expected) < 5e-13:
            assert text == "0", key
        else:
            assert float(text) == pytest.approx(expected, rel=6e-4), (key, text)
    return len(cells)


def test_sliders_drive_carnot_and_the_page_shows_carnot_solve(page, tmp_path) -> None:
    tab = page
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    for name, classic in CLASSICS.items():
        before = _seq(tab)
        tab.select_option("#classic", name)
        _settle(tab, before)
        compared = _check_against_cli(tab, tmp_path)
        assert compared >= 10
        # Drive each slider as a user does: focus it and press keys (arrows move one step).
        moved = {}
        for p in classic.parameters:
            if p.choices:
                continue
            before = _seq(tab)
            slider = tab.locator(f"#p-{p.name}")
            slider.focus()
            for _ in range(3):
                tab.keyboard.press("ArrowRight" if p.default < p.high else "ArrowLeft")
            _settle(tab, before)
            moved[p.name] = float(slider.input_value())
            assert moved[p.name] != p.default, p.name
            assert tab.inner_text(f"#v-{p.name}") == slider.input_value()
        sent = json.loads(tab.evaluate("document.body.dataset.request"))
        assert sent["classic"] == name
        for key, value in moved.items():
            assert math.isclose(sent["parameters"][key], value), key
        _check_against_cli(tab, tmp_path)
        if any(p.choices for p in classic.parameters):  # a menu too: the meaning of e
            before = _seq(tab)
            tab.select_option("#p-law", "stronge")
            _settle(tab, before)
            assert json.loads(tab.text_content("#scenario"))["contacts"][0]["law"] == "stronge"
            _check_against_cli(tab, tmp_path)
            assert tab.locator("#path polyline").count() == 3  # w_n, w_t1, w_t2 drawn
        tab.screenshot(path=str(ARTEFACTS / f"explore-{name}.png"), full_page=True)


def test_friction_off_shows_no_path_and_bad_values_show_the_error(page) -> None:
    tab = page
    before = _seq(tab)
    tab.select_option("#classic", "rod_ledge")
    _settle(tab, before)
    before = _seq(tab)
    tab.locator("#p-mu").focus()
    tab.keyboard.press("Home")  # friction 0
    _settle(tab, before)
    assert tab.locator("#path polyline").count() == 0
    assert "no path to draw" in tab.inner_text("#path-note")
    # A value the slider cannot produce, sent as a crafted request would be: HTTP 400 with the
    # InputError's message, shown on the page.
    before = _seq(tab)
    tab.evaluate("""() => { const s = document.getElementById('p-e');
                            s.max = '5'; s.value = '3';
                            s.dispatchEvent(new Event('input')); }""")
    tab.wait_for_function(
        "seq => document.body.dataset.state === 'error' && +document.body.dataset.seq > seq",
        arg=before,
    )
    assert tab.inner_text("#error") == "parameters.e: must be in [0.0, 1.0], got 3"

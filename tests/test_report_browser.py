"""compare.html opened in a real browser (headless Chromium), as a reader would open it.

Needs Debian's chromium (``.ci/run`` installs it).  Without it the test is skipped, unless
AGRISYNTH_REQUIRE_BROWSER=1 (set by CI), where a missing browser is a failure.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from conftest import PLANTING
from report_fixtures import checked_run
from synthesis.compare import load_candidates, write_comparison

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
LAUNCH_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking"]


@pytest.fixture
def sync_playwright():
    """Playwright and Debian's Chromium, or a skip -- a failure when CI requires the browser test."""
    required = os.environ.get("AGRISYNTH_REQUIRE_BROWSER") == "1"
    missing = None
    if not Path(CHROMIUM).exists():
        missing = f"no headless Chromium at {CHROMIUM} (apt-get install chromium)"
    try:
        from playwright.sync_api import sync_playwright as launcher
    except ImportError:
        missing = missing or "playwright is not installed (pip install -e '.[test]')"
    if missing:
        (pytest.fail if required else pytest.skip)(missing)
    return launcher


def test_compare_page_in_headless_chromium(tmp_path, sync_playwright):
    runs = [checked_run(PLANTING / f"taiwan_example{k}.toml", tmp_path / "runs") for k in (1, 3, 4)]
    cands = load_candidates([folder for folder, _ in runs])
    page_path = write_comparison(cands, tmp_path / "compare")
    expected_red = {(r["name"], c.label) for c in cands for r in c.result.rules if not r["satisfied"]}

    console_errors: list[str] = []
    off_disk: list[str] = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("console", lambda m: console_errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: console_errors.append(str(e)))
            page.on("request", lambda r: off_disk.append(r.url) if not r.url.startswith("file://") else None)
            page.goto(page_path.as_uri(), wait_until="load")
            images = page.eval_on_selector_all(
                "img", "els => els.map(e => [e.getAttribute('src'), e.complete, e.naturalWidth, e.naturalHeight])")
            headers = page.eval_on_selector_all("table.rules tr:first-child th", "els => els.map(e => e.textContent)")
            red = page.eval_on_selector_all(
                "table.rules tr:not(.summary)",
                "rows => rows.flatMap(r => Array.from(r.cells).map((c, i) => [r.cells[0].textContent, i, "
                "c.classList.contains('fail'), getComputedStyle(c).backgroundColor]))")
            page.screenshot(path=str(tmp_path / "compare.png"), full_page=True)
        finally:
            browser.close()

    assert console_errors == []
    assert off_disk == []                   # the page works offline: nothing but local files
    assert [src for src, *_ in images] == ["paths.png", "kinematics.png", "linkage.png", "animation.gif"]
    assert all(complete and w > 0 and h > 0 for _, complete, w, h in images), images
    labels = [h.removesuffix(" (baseline)") for h in headers[3:]]
    assert labels == [c.label for c in cands]
    shown_red = {(rule, labels[i - 3]) for rule, i, is_fail, _ in red if is_fail}
    assert shown_red == expected_red and ("entry_angle", "taiwan_example1") in shown_red
    # and red means red on screen: the failing cells are painted the failure colour, the others not
    colours = {bg for _, _, is_fail, bg in red if is_fail}
    assert colours == {"rgb(253, 226, 226)"}
    assert (tmp_path / "compare.png").stat().st_size > 10_000

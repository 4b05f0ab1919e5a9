"""compare.html opened in a real browser (headless Chromium), as a reader would open it.

Needs Debian's chromium (``.ci/run`` installs it).  Without it the test is skipped, unless
AGRISYNTH_REQUIRE_BROWSER=1 (set by CI), where a missing browser is a failure.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest


from conftest import LIBRARY, PLANTING
from report_fixtures import checked_run
from synthesis.report.compare import load_candidates, write_comparison
from solving import agrisynth

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


#: the page may be no wider than the window: on screen at 1200 px, and printed on A4 (210 mm at 96 px/in
#: less Chromium's default 0.4 in margins = 717 px; 716 to be safe) with the print style sheet
WIDTHS = (("screen", 1200), ("print", 716))
OVERFLOW = """() => ({page: document.documentElement.scrollWidth,
  hidden: Array.from(document.querySelectorAll('.scroll')).filter(e => e.scrollWidth > e.clientWidth + 1).length,
  wider: Array.from(document.querySelectorAll('body *')).filter(e => e.getBoundingClientRect().right
                                                             > window.innerWidth + 0.5).map(e => e.tagName)})"""


def overflow(browser, page_path: Path) -> dict:
    """Per (media, width): the page's scroll width, how many table boxes hide columns behind a scroll bar, and
    the elements reaching past the window's right edge."""
    out = {}
    for media, width in WIDTHS:
        page = browser.new_page(viewport={"width": width, "height": 900})
        page.emulate_media(media=media)
        page.goto(page_path.as_uri(), wait_until="load")
        out[(media, width)] = page.evaluate(OVERFLOW)
        page.close()
    return out


def assert_fits(widths: dict) -> None:
    for (media, width), seen in widths.items():
        assert seen["page"] <= width and seen["hidden"] == 0 and seen["wider"] == [], (media, width, seen)


@pytest.mark.long
@pytest.mark.slow
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
            widths = overflow(browser, page_path)
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
    # three candidates and their 64-character spec hashes fit at 1200 px and on A4 (the hash wraps)
    assert_fits(widths)
    assert len({c.result.spec_sha256 for c in cands}) == 3


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_solve_report_in_headless_chromium(tmp_path, sync_playwright):
    """A solve's report: the given design beside the solution, with units, bounds and at-bound marks, on
    screen and on A4 without overflow."""
    text = (LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").read_text()
    for old, new in (('name = "cai2020_crank_rocker_synthesis"', 'name = "tight"'),
                     ("l7 = { init = 50.0, bounds = [5.0, 200.0] }", "l7 = { init = 50.0, bounds = [5.0, 52.0] }")):
        assert old in text, old
        text = text.replace(old, new)
    spec = tmp_path / "tight.toml"
    spec.write_text(text)
    proc = agrisynth("solve", str(spec), "--out", str(tmp_path), "--workers", "1", timeout=300)
    assert proc.returncode == 0, proc.stderr
    page_path = tmp_path / "tight" / "report.html"
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1200, "height": 900})
            page.goto(page_path.as_uri(), wait_until="load")
            rows = page.eval_on_selector_all("table.design tr", "rows => rows.map(r => Array.from(r.cells).map("
                                                                "c => c.innerText.replace(/\\s+/g, ' ').trim()))")
            widths = overflow(browser, page_path)
        finally:
            browser.close()
    assert rows[0] == ["variable", "unit", "bounds", "given (start 0)", "solved"]
    by_name = {r[0]: r for r in rows[1:]}
    assert by_name["l7"][:4] == ["l7", "mm", "[5, 52]", "50"]
    assert by_name["l7"][4] == "52 at upper bound"          # the smallest total length wants a longer crank
    assert by_name["l10"][:4] == ["l10", "mm", "fixed", "140"]
    assert "bound" not in by_name["l8"][4]
    assert_fits(widths)

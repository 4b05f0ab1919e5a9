"""Screenshots of the studio page of every kind it serves (docs/screenshots/studio/), as a user first sees it:
``python tests/studio_screenshots.py [OUT_DIR] [KIND ...]``; and of the report ``agrisynth solve --starts 8``
writes for a kind's studio spec: ``python tests/studio_screenshots.py --report KIND PNG`` (Debian's chromium and playwright;
not a test).

Each page is opened on its library spec (tests/studio_fixtures.STUDIO_SPECS), left to settle on the fine grid, the
animation stopped at a pose a third of the way round, and photographed at 1400 x 1000; a report down to the end of
its first figure, 1280 px wide."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from studio_fixtures import STUDIO_SPECS, running_studio  # noqa: E402
from test_report_browser import CHROMIUM, LAUNCH_FLAGS  # noqa: E402


def main(out: Path, kinds: list[str]) -> None:
    from playwright.sync_api import sync_playwright

    out.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_FLAGS)
        try:
            for kind in kinds or list(STUDIO_SPECS):
                with tempfile.TemporaryDirectory() as tmp, running_studio(STUDIO_SPECS[kind], Path(tmp)) as studio:
                    page = browser.new_page(viewport={"width": 1400, "height": 1000})
                    page.goto(studio.url)
                    page.wait_for_selector("body[data-ready='1']", timeout=60_000)
                    page.wait_for_function("() => Number(document.body.dataset.evaluations) > 0", timeout=60_000)
                    page.wait_for_timeout(1500)                  # a third of the way round the animation
                    if page.query_selector("#animate"):
                        page.uncheck("#animate")
                    page.screenshot(path=str(out / f"{kind}.png"), full_page=True)
                    page.close()
                    print(out / f"{kind}.png")
        finally:
            browser.close()


def report(kind: str, png: Path) -> None:
    """The solve report (8 starts) of ``kind``'s studio spec, from its top to the bottom of its first figure."""
    from playwright.sync_api import sync_playwright

    from solving import agrisynth

    with tempfile.TemporaryDirectory() as tmp:
        spec = STUDIO_SPECS[kind]
        proc = agrisynth("solve", str(spec), "--starts", "8", "--out", tmp, cwd=tmp, timeout=600)
        found = sorted(Path(tmp).glob("*/report.html"))
        assert found, proc.stderr
        page_path = found[0]
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_FLAGS)
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 900})
                page.goto(page_path.as_uri())
                page.wait_for_load_state("load")
                bottom = page.evaluate("() => { const i = document.querySelector('img'); "
                                       "return i ? i.getBoundingClientRect().bottom + window.scrollY + 16 : 900; }")
                png.parent.mkdir(parents=True, exist_ok=True)
                page.screenshot(path=str(png), full_page=True, clip={"x": 0, "y": 0, "width": 1280, "height": bottom})
                print(png)
            finally:
                browser.close()


if __name__ == "__main__":
    args = sys.argv[1:]
    if args[:1] == ["--report"]:
        report(args[1], Path(args[2]))
        sys.exit(0)
    target = Path(args.pop(0)) if args and not args[0] in STUDIO_SPECS else HERE.parent / "docs/screenshots/studio"
    main(target, args)

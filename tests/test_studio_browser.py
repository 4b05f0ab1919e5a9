"""agrisynth studio in headless Chromium, as a user drives it: drag a slider, watch the table and the drawing,
save the spec and check it, solve from here and compare with `agrisynth solve`.

Needs Debian's chromium and playwright (skipped without them, failed when AGRISYNTH_REQUIRE_BROWSER=1)."""

from __future__ import annotations

import contextlib
from urllib.parse import urlsplit

import pytest

from solving import agrisynth, strict_json
from studio_fixtures import STUDIO_SPECS, running_studio
from test_report_browser import CHROMIUM, LAUNCH_FLAGS, sync_playwright  # noqa: F401 - the fixture

pytest.importorskip("starlette")

#: every change of the body's data-grid attribute, in order (coarse while dragging, fine on release)
RECORD_GRIDS = """() => { window.__grids = [];
  new MutationObserver(() => window.__grids.push(document.body.dataset.grid))
    .observe(document.body, {attributes: true, attributeFilter: ["data-evaluations"]}); }"""
TABLE = """() => Array.from(document.querySelectorAll('#rules tbody tr')).map(r => ({
  name: r.dataset.rule, red: r.classList.contains('violated'),
  colour: getComputedStyle(r.cells[0]).color, value: r.cells[1].textContent}))"""


@contextlib.contextmanager
def studio_page(sync_playwright, studio):
    """A page on the studio, with every request recorded (any not to the studio is aborted) and console errors."""
    seen = {"requests": [], "left": [], "errors": []}
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_FLAGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})

            def route(r):
                seen["requests"].append(r.request.url)
                if urlsplit(r.request.url).netloc != f"127.0.0.1:{studio.port}":
                    seen["left"].append(r.request.url)
                    return r.abort()
                return r.continue_()
            page.route("**/*", route)
            page.on("console", lambda m: seen["errors"].append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: seen["errors"].append(str(e)))
            page.goto(studio.url)
            page.wait_for_selector("body[data-ready='1']", timeout=30_000)
            yield page, seen
        finally:
            browser.close()


def wait_for_evaluations(page, more_than: int) -> None:
    page.wait_for_function(f"() => Number(document.body.dataset.evaluations) > {more_than}", timeout=30_000)


def box_value(page, name: str) -> float:
    """The exact value a variable's number box holds (data-value); the box itself shows 10 significant digits of
    it, which this checks."""
    exact = float(page.get_attribute(f"#number-{name}", "data-value"))
    shown = page.input_value(f"#number-{name}")
    digits = shown.lstrip("-").replace(".", "").lstrip("0")
    assert len(digits.split("e")[0]) <= 10, (name, shown)
    assert float(shown) == float(f"{exact:.10g}"), (name, shown, exact)
    return exact


def fmt4(v) -> str:
    """The page's number format for a table value: 4 significant digits as JavaScript writes them."""
    if v is None:
        return "-"
    if abs(v) >= 1e5 or (abs(v) < 1e-3 and v != 0):
        return f"{v:.3e}".replace("e+0", "e+").replace("e-0", "e-")
    x = float(f"{v:.4g}")
    return str(int(x)) if x.is_integer() else repr(x)


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_drag_a_slider_and_the_table_follows_check(tmp_path, sync_playwright):
    """Drag l4 of the planting arm: coarse tables while dragging, the fine one on release, the drawing redrawn;
    red exactly where the check of the saved spec says violated; compare, animate, reset."""
    spec = STUDIO_SPECS["planting_fourbar"]
    with running_studio(spec, tmp_path / "studio") as studio, studio_page(sync_playwright, studio) as (page, seen):
        baseline = page.evaluate(TABLE)
        assert {r["name"] for r in baseline if r["red"]} == {"p1p2p3_collinearity", "entry_angle",
                                                            "transmission_angle_min"}
        path_before = page.get_attribute("#panel-main path[data-line='path (machine frame)']", "d")
        pose_before = page.get_attribute("#panel-main g.poses circle[data-joint='B']", "cx")
        page.uncheck("#animate")            # the drawn pose stays put, so a change of it is the design's
        page.evaluate(RECORD_GRIDS)
        count = int(page.get_attribute("body", "data-evaluations"))
        # drag l4 (64..96 mm, given 80: the thumb sits mid-way) to about a tenth of its range
        box = page.locator("#range-l4").bounding_box()
        y = box["y"] + box["height"] / 2
        page.mouse.move(box["x"] + box["width"] / 2, y)
        page.mouse.down()
        for k in range(1, 9):
            page.mouse.move(box["x"] + box["width"] * (0.5 - 0.05 * k), y)
            page.wait_for_timeout(40)
        page.mouse.up()
        # settled: a table drawn since the drag began (the first is a coarse one), nothing in flight or queued, and
        # the last one drawn is the fine one the release asked for
        page.wait_for_function(f"() => Number(document.body.dataset.evaluations) > {count} && "
                               "document.body.dataset.busy === '0' && document.body.dataset.grid === 'fine'",
                               timeout=30_000)
        grids = page.evaluate("window.__grids")
        l4 = box_value(page, "l4")
        assert 64 <= l4 < 72, l4
        assert "coarse" in grids and grids[-1] == "fine", grids
        assert page.get_attribute("#panel-main path[data-line='path (machine frame)']", "d") != path_before
        assert page.get_attribute("#panel-main g.poses circle[data-joint='B']", "cx") != pose_before
        table = page.evaluate(TABLE)
        status = page.inner_text("#status")
        assert status.startswith("fine grid (400 samples per phase, 3600 per crank turn)")

        page.click("#save")
        page.wait_for_function("() => document.body.dataset.saved", timeout=30_000)
        saved = page.get_attribute("body", "data-saved")

        # compare: the baseline drawn under the design (grey, dashed) and its margins beside the current ones
        assert page.locator("#panel-main g.baseline").count() == 0 and not page.is_visible("th.base")
        page.check("#compare")
        assert page.locator("#panel-main g.baseline path").count() == 1
        assert page.locator("#panel-ground g.baseline path").count() == 1 and page.is_visible("th.base")
        base_margins = page.eval_on_selector_all("#rules tbody td.base", "cells => cells.map(c => c.textContent)")
        assert base_margins[0] == "5"                  # p1p3_distance of the given design: 110 mm in 105 ... 115
        # animate: the pose moves along the cycle
        assert page.locator("#panel-main g.ghost-poses circle[data-joint='B']").count() == 1
        cx = page.get_attribute("#panel-main g.poses circle[data-joint='B']", "cx")
        page.check("#animate")
        page.wait_for_function(f"() => document.querySelector(\"#panel-main g.poses circle[data-joint='B']\")"
                               f".getAttribute('cx') !== '{cx}'", timeout=10_000)
        # reset: the given design and its table again
        count = int(page.get_attribute("body", "data-evaluations"))
        page.click("#reset")
        wait_for_evaluations(page, count)
        assert box_value(page, "l4") == 80.0
        assert [(r["name"], r["red"]) for r in page.evaluate(TABLE)] == [(r["name"], r["red"]) for r in baseline]
        # an evaluation the server refuses: no table or drawing of the earlier values beside the new ones
        page.route("**/api/evaluate*", lambda r: r.fulfill(status=500, content_type="application/json",
                                                            body='{"error": "internal error: made up by the test"}'))
        page.fill("#number-l4", "70")
        page.press("#number-l4", "Enter")
        page.wait_for_function("() => document.body.dataset.busy === '0' && !document.querySelector('#error').hidden",
                               timeout=30_000)
        assert page.inner_text("#error") == "internal error: made up by the test"
        assert page.evaluate(TABLE) == [] and page.inner_text("#verdict") == "(not evaluated)"
        assert page.locator("#panel-main").count() == 0 and page.get_attribute("body", "data-grid") == "none"
        seen["errors"] = [e for e in seen["errors"] if "500" not in e]        # the browser logs the refused fetch
        assert seen["left"] == [] and seen["errors"] == []
        assert all(urlsplit(u).hostname == "127.0.0.1" for u in seen["requests"]) and seen["requests"]

    # what `agrisynth check SAVED` evaluates (run in-process here: planting's check writes an animation; the
    # command itself is run on the saved spec of the solve test below)
    from synthesis import kinds
    from synthesis.spec import load_spec

    checked = kinds.checker("planting_fourbar")(load_spec(tmp_path / "studio" / saved)).to_json()
    assert checked["design"]["l4"] == l4
    assert [r["name"] for r in table] == [r["name"] for r in checked["rules"]]
    # red exactly where check says violated, and the drag changed which ones are
    assert {r["name"] for r in table if r["red"]} == {r["name"] for r in checked["rules"] if not r["satisfied"]}
    assert {r["name"] for r in table if r["red"]} != {r["name"] for r in baseline if r["red"]}
    assert all(r["colour"] == "rgb(187, 0, 0)" for r in table if r["red"])
    assert all(r["colour"] != "rgb(187, 0, 0)" for r in table if not r["red"])
    for row, rule in zip(table, checked["rules"]):
        assert row["value"] == fmt4(rule["value"]), (row, rule["value"])


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_solve_from_here_ends_where_agrisynth_solve_does(tmp_path, sync_playwright):
    """Type a start value, solve from here (one start: the page runs `agrisynth solve` in a worker process) and get
    what the same solve gets run again from the spec the page wrote; then "save spec" and `agrisynth check` on it
    reproduce the page's table."""
    spec = STUDIO_SPECS["crank_rocker"]
    with running_studio(spec, tmp_path / "studio") as studio, studio_page(sync_playwright, studio) as (page, seen):
        count = int(page.get_attribute("body", "data-evaluations"))
        page.fill("#number-l7", "42.5")
        page.press("#number-l7", "Enter")
        wait_for_evaluations(page, count)
        page.fill("#starts", "1")
        count = int(page.get_attribute("body", "data-evaluations"))
        page.click("#solve")
        page.wait_for_function("() => document.body.dataset.solve === 'finished'", timeout=120_000)
        wait_for_evaluations(page, count)
        state = page.inner_text("#solve-state")
        values = {v.name: box_value(page, v.name) for v in studio.session.free}
        # a solved value has more digits than a box shows: the box rounds it, the page keeps it whole
        shown = {v.name: page.input_value(f"#number-{v.name}") for v in studio.session.free}
        assert any(float(shown[n]) != x for n, x in values.items()), (shown, values)
        table = page.evaluate(TABLE)
        page.click("#save")
        page.wait_for_function("() => document.body.dataset.saved", timeout=30_000)
        saved = page.get_attribute("body", "data-saved")
        # reloaded, the page opens on the spec's values; the last run is only reported
        page.reload()
        page.wait_for_selector("body[data-ready='1'][data-solve='finished']", timeout=30_000)
        reloaded = {v.name: box_value(page, v.name) for v in studio.session.free}
        reload_state = page.inner_text("#solve-state")
        assert seen["left"] == [] and seen["errors"] == []
    assert reloaded == {v.name: v.value for v in studio.session.free} != values
    assert "cai2020_crank_rocker_synthesis_solve_1: finished" in reload_state and "not loaded" in reload_state
    run = tmp_path / "studio" / "cai2020_crank_rocker_synthesis_solve_1"
    assert "finished" in state and "status optimal" in state, state
    assert "; exit 0: every rule satisfied" in state or "; exit 1: solved, some rule violated" in state, state
    here_spec = run.with_suffix(".toml")
    from synthesis.studio.session import Session

    assert Session.open(here_spec).given()["l7"] == 42.5              # start 0 was the page's value
    ours = strict_json(run / "result.json")
    assert (run / "solved.toml").is_file() and (run / "report.html").is_file()
    # the solve `agrisynth solve HERE --starts 1` runs (core.solve_spec), again, in this process
    from synthesis.kinds import solve_spec
    from synthesis.spec import load_spec

    theirs = solve_spec(load_spec(here_spec), starts=1, workers=1)[0].to_json()
    assert ours["design"] == theirs["design"] and ours["objective"] == theirs["objective"]
    assert ours["solver"]["best_start"] == 0 and ours["solver"]["starts"] == 1
    bounds = {v.name: v.bounds for v in Session.open(spec).free}
    assert values == {name: min(max(theirs["design"][name], bounds[name][0]), bounds[name][1]) for name in values}
    assert values["l7"] != 42.5
    assert {r["name"] for r in table if r["red"]} == {r["name"] for r in theirs["rules"] if not r["satisfied"]}
    # "save spec" at the solution, then `agrisynth check` on it: the page's table, value for value
    proc = agrisynth("check", str(tmp_path / "studio" / saved), "--out", str(tmp_path / "checked"), cwd=tmp_path)
    checked = strict_json(tmp_path / "checked" / f"{saved.removesuffix('.toml')}-check" / "result.json")
    assert proc.returncode == (1 if any(r["red"] for r in table) else 0), proc.stderr
    assert {name: checked["design"][name] for name in values} == values
    assert [(r["name"], r["value"], r["red"]) for r in table] == [
        (r["name"], fmt4(r["value"]), not r["satisfied"]) for r in checked["rules"]]


@pytest.mark.long
@pytest.mark.slow
def test_guide_way_control_points_drag_solve_and_save(tmp_path, sync_playwright):
    """guide_way, whose design is the spline's 48 control points (the spec leaves them to the convex fit; the
    studio writes them out): a slider and a number box per coordinate, grouped per point; drag P4_y up and the
    undercut rule, violated by the fit, is met (coarse tables while dragging, the fine one on release, the claw
    path and the control polygon redrawn), red exactly where the check of the saved spec says violated; solve from
    here ends with the design `agrisynth solve` gets from the spec the page wrote; save spec at the solution and
    the check of it gives the page's table."""
    spec = STUDIO_SPECS["guide_way"]
    with running_studio(spec, tmp_path / "studio") as studio, studio_page(sync_playwright, studio) as (page, seen):
        free = studio.session.free
        assert len(free) == 48 and page.locator("div.group-list fieldset").count() == 24
        assert page.locator("fieldset[data-group='spline.control[4]'] input[type=range]:not([disabled])").count() == 2
        assert page.locator("#range-R").is_disabled() and page.locator("#number-R").is_disabled()
        assert page.inner_text(".var[data-var='P4_y'] .unit") == "mm"
        baseline = page.evaluate(TABLE)
        assert {r["name"] for r in baseline if r["red"]} == {"no_undercut"}
        polygon = "#panel-main path[data-line='spline.control_polygon']"
        claw = "#panel-main path[data-line='curves[0].claw']"
        polygon_before, claw_before = page.get_attribute(polygon, "d"), page.get_attribute(claw, "d")
        page.uncheck("#animate")
        page.evaluate(RECORD_GRIDS)
        count = int(page.get_attribute("body", "data-evaluations"))
        # drag P4_y (given: the fit, mid-way in fit -40 ... fit +40 mm) to about three quarters of its range
        page.locator("#range-P4_y").scroll_into_view_if_needed()
        box = page.locator("#range-P4_y").bounding_box()
        y = box["y"] + box["height"] / 2
        page.mouse.move(box["x"] + box["width"] / 2, y)
        page.mouse.down()
        for k in range(1, 6):
            page.mouse.move(box["x"] + box["width"] * (0.5 + 0.05 * k), y)
            page.wait_for_timeout(40)
        page.mouse.up()
        page.wait_for_function(f"() => Number(document.body.dataset.evaluations) > {count} && "
                               "document.body.dataset.busy === '0' && document.body.dataset.grid === 'fine'",
                               timeout=30_000)
        grids = page.evaluate("window.__grids")
        moved = box_value(page, "P4_y")
        given = {v.name: v.value for v in free}
        assert 15 < moved - given["P4_y"] < 25, moved - given["P4_y"]
        assert "coarse" in grids and grids[-1] == "fine", grids
        assert page.get_attribute(polygon, "d") != polygon_before and page.get_attribute(claw, "d") != claw_before
        table = page.evaluate(TABLE)
        page.click("#save")
        page.wait_for_function("() => document.body.dataset.saved", timeout=30_000)
        dragged_file = page.get_attribute("body", "data-saved")

        # solve from here, one start, from the dragged values
        page.fill("#starts", "1")
        count = int(page.get_attribute("body", "data-evaluations"))
        page.click("#solve")
        page.wait_for_function("() => document.body.dataset.solve === 'finished'", timeout=180_000)
        wait_for_evaluations(page, count)
        page.wait_for_function("() => document.body.dataset.busy === '0'", timeout=30_000)
        state = page.inner_text("#solve-state")
        solved_values = {v.name: box_value(page, v.name) for v in free}
        solved_table = page.evaluate(TABLE)
        page.evaluate("() => { delete document.body.dataset.saved; }")
        page.click("#save")
        page.wait_for_function("() => document.body.dataset.saved", timeout=30_000)
        solved_file = page.get_attribute("body", "data-saved")
        assert seen["left"] == [] and seen["errors"] == []

    from synthesis import kinds
    from synthesis.kinds import solve_spec
    from synthesis.spec import load_spec

    # the dragged design: red exactly where the check of the saved spec says violated, and the drag changed that
    checked = kinds.checker("guide_way")(load_spec(tmp_path / "studio" / dragged_file)).to_json()
    assert checked["design"]["P4_y"] == moved
    assert {r["name"] for r in table if r["red"]} == {r["name"] for r in checked["rules"] if not r["satisfied"]}
    assert {r["name"] for r in table if r["red"]} != {r["name"] for r in baseline if r["red"]}
    assert [(r["name"], r["value"]) for r in table] == [(r["name"], fmt4(r["value"])) for r in checked["rules"]]
    # solve from here = `agrisynth solve` (core.solve_spec, run again in this process) on the spec the page wrote,
    # whose start 0 is the page's values: the same design to the last digit (tolerance 1e-9 mm: the same IPOPT on
    # the same floats; a difference would mean the worker solved something else)
    run = tmp_path / "studio" / "smooth_redesign_solve_1"
    assert "finished" in state and "status optimal" in state, state
    here = load_spec(run.with_suffix(".toml"))
    assert here.model.spline.control[4][1].init == moved
    ours = strict_json(run / "result.json")
    assert (run / "solved.toml").is_file() and (run / "report.html").is_file()
    theirs = solve_spec(here, starts=1, workers=1)[0].to_json()
    names = [v.name for v in free]
    difference = max(abs(ours["design"][n] - theirs["design"][n]) for n in names)
    assert difference <= 1e-9, difference
    assert ours["objective"]["value"] == pytest.approx(theirs["objective"]["value"], abs=1e-12)
    assert ours["design"]["P4_y"] != moved                       # the solve moved the dragged point
    assert solved_values == {n: ours["design"][n] for n in names}   # the sliders hold the solution (inside bounds)
    assert {r["name"] for r in solved_table if r["red"]} == {r["name"] for r in ours["rules"] if not r["satisfied"]}
    # "save spec" at the solution, then check: the page's table, value for value
    again = kinds.checker("guide_way")(load_spec(tmp_path / "studio" / solved_file)).to_json()
    assert {n: again["design"][n] for n in names} == solved_values
    assert [(r["name"], r["value"], r["red"]) for r in solved_table] == [
        (r["name"], fmt4(r["value"]), not r["satisfied"]) for r in again["rules"]]


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_the_cam_page_turns_the_cam_against_its_roller(tmp_path, sync_playwright):
    """clamp_cam's page draws the cam's working profile and the roller as outlines placed in each pose; animated,
    the cam turns (its outline's points change) while no request leaves 127.0.0.1 and nothing logs an error."""
    with running_studio(STUDIO_SPECS["clamp_cam"], tmp_path / "studio") as studio, \
            studio_page(sync_playwright, studio) as (page, seen):
        page.wait_for_function("() => Number(document.body.dataset.evaluations) > 0", timeout=30_000)
        cam = "#panel-main g.poses polyline[data-outline='cam']"
        assert page.locator(cam).count() == 1
        assert page.locator("#panel-main g.poses polyline[data-outline='roller']").count() == 1
        before = page.get_attribute(cam, "points")
        assert len(before.split()) == 721                       # the closed 720-point profile
        # a chart of one curve is titled by it (the "follower" table holds only the pressure angle here)
        titles = page.eval_on_selector_all(".panel.chart h3", "hs => hs.map(h => h.textContent)")
        assert "follower: pressure_angle_deg (deg) over crank_deg" in titles, titles
        page.check("#animate")
        page.wait_for_function(f"() => document.querySelector(\"{cam}\").getAttribute('points') !== '{before}'",
                               timeout=10_000)
    assert not seen["left"] and not seen["errors"]


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_an_operating_range_s_verdict_line_names_the_nominal_point(tmp_path, sync_playwright):
    """On an envelope spec the page's verdict is the nominal point's, and it says so (a trial: "every rule
    satisfied" for a design that misses the entry angle at the range's top speed)."""
    from conftest import LIBRARY

    with running_studio(LIBRARY / "planting_arm/envelope_redesign_from_example1.toml", tmp_path / "studio") as studio, \
            studio_page(sync_playwright, studio) as (page, seen):
        wait_for_evaluations(page, 0)
        verdict = page.text_content("#verdict")
    from synthesis import kinds
    from synthesis.spec import load_spec

    loaded = load_spec(LIBRARY / "planting_arm/envelope_redesign_from_example1.toml")
    bad = len(kinds.checker(loaded.kind)(loaded).violated())          # what check says at the nominal point
    said = f"{bad} violated" if bad else "every rule satisfied"
    assert verdict == (f"{said} at the nominal operating point (forward_speed given as a range: this page evaluates "
                       "the nominal value only; solve re-checks every rule over the range)")
    assert not seen["errors"]


#: every text of the drawings and their legends: its computed font size, and the svg's pixels per viewBox unit
TEXT_SIZES = """() => ({
  svg: Array.from(document.querySelectorAll('#panels svg text')).map(t => parseFloat(getComputedStyle(t).fontSize)),
  legend: Array.from(document.querySelectorAll('#panels .legend span')).map(s => parseFloat(getComputedStyle(s).fontSize)),
  scale: Array.from(document.querySelectorAll('#panels svg')).map(s => s.getBoundingClientRect().width / s.viewBox.baseVal.width),
})"""
#: the main panel's axes: tick values and their x (or y) pixel, the scale bar's length in px and in mm
AXES = """() => { const root = document.querySelector('#panel-main svg');
  const ticks = (a) => Array.from(root.querySelectorAll(`text[data-tick-${a}]`)).map(t => [Number(t.dataset['tick' + a.toUpperCase()]), Number(t.getAttribute(a))]);
  const bar = root.querySelector('g.scale-bar'); const line = bar.querySelector('line');
  return { x: ticks('x'), y: ticks('y'), titles: Array.from(root.querySelectorAll('text.axis-title')).map(t => t.textContent),
           barMm: Number(bar.dataset.scaleMm), barPx: Number(line.getAttribute('x2')) - Number(line.getAttribute('x1')),
           barText: bar.querySelector('text').textContent }; }"""


def round_step(step: float) -> bool:
    """Whether ``step`` is 1, 2 or 5 x 10^k."""
    import math

    mantissa = step / 10 ** math.floor(math.log10(step) + 1e-9)
    return any(abs(mantissa - m) < 1e-6 for m in (1, 2, 5))


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_the_drawing_reads_at_a_glance(tmp_path, sync_playwright):
    """planting_fourbar in a 1280 px wide window: the drawing panel at least 60 % of the window, every label at
    least 11 px on screen, axes in mm with ticks at round values and a scale bar that is as long as it says, the
    soil surface and the seedbed bottom drawn as lines across the panel through P4 and the seedbed point; one arrow
    key moves l2 by its step (0.1 mm: 1/200 of 28 ... 42 mm is 0.07, at least 0.1 mm), shift ten steps."""
    spec = STUDIO_SPECS["planting_fourbar"]
    with running_studio(spec, tmp_path / "studio") as studio, studio_page(sync_playwright, studio) as (page, seen):
        page.set_viewport_size({"width": 1280, "height": 900})
        page.uncheck("#animate")
        page.wait_for_function("() => document.querySelector('#panel-main svg').viewBox.baseVal.width === "
                               "document.querySelector('#panel-main svg').getBoundingClientRect().width")
        panel = page.locator("#panel-main").bounding_box()
        assert panel["width"] >= 0.6 * 1280, panel
        sizes = page.evaluate(TEXT_SIZES)
        assert len(sizes["svg"]) >= 30 and min(sizes["svg"]) >= 11, sizes["svg"]
        assert sizes["legend"] and min(sizes["legend"]) >= 11, sizes["legend"]
        assert all(abs(s - 1) < 1e-6 for s in sizes["scale"]), sizes["scale"]     # one viewBox unit = one px
        axes = page.evaluate(AXES)
        assert axes["titles"] == ["x, mm", "y, mm"]
        for a in ("x", "y"):
            values = [v for v, _ in axes[a]]
            assert len(values) >= 4, axes[a]
            step = values[1] - values[0]
            assert round_step(step) and all(abs(v / step - round(v / step)) < 1e-9 for v in values), values
        (v0, x0), (v1, x1) = axes["x"][0], axes["x"][-1]
        px_per_mm = (x1 - x0) / (v1 - v0)
        (w0, y0), (w1, y1) = axes["y"][0], axes["y"][-1]
        assert (y0 - y1) / (w1 - w0) == pytest.approx(px_per_mm, rel=1e-6)         # equal scales: a true drawing
        assert round_step(axes["barMm"]) and axes["barText"] == f"{axes['barMm']:g} mm"
        assert axes["barPx"] == pytest.approx(axes["barMm"] * px_per_mm, rel=1e-6)
        # the soil surface: horizontal through P4 in both frames; the seedbed bottom through the seedbed point at
        # the design's seedbed tilt (-34.1 deg)
        for panel_id in ("panel-main", "panel-ground"):
            line = page.locator(f"#{panel_id} g.surface[data-surface='soil surface'] line")
            p4 = page.locator(f"#{panel_id} circle[data-point='P4']")
            y_a, y_b = float(line.get_attribute("y1")), float(line.get_attribute("y2"))
            assert y_a == pytest.approx(y_b) == pytest.approx(float(p4.get_attribute("cy")), abs=0.01)
            assert float(line.get_attribute("x2")) - float(line.get_attribute("x1")) > 1280   # across the panel
        seedbed = page.locator("#panel-main g.surface[data-surface='seedbed bottom'] line")
        ends = [float(seedbed.get_attribute(k)) for k in ("x1", "y1", "x2", "y2")]
        import math

        assert math.degrees(math.atan2(-(ends[3] - ends[1]), ends[2] - ends[0])) == pytest.approx(-34.1, abs=1e-6)
        point = page.locator("#panel-main circle[data-point='seedbed']")
        cx, cy = float(point.get_attribute("cx")), float(point.get_attribute("cy"))
        cross = (ends[2] - ends[0]) * (cy - ends[1]) - (ends[3] - ends[1]) * (cx - ends[0])
        assert abs(cross) / math.hypot(ends[2] - ends[0], ends[3] - ends[1]) < 0.05        # through the point
        assert page.locator("#panel-ground g.surface[data-surface='seedbed bottom']").count() == 0

        # an arrow key: one step of 0.1 mm from 35 (the fine grid at once), shift: ten steps
        assert page.get_attribute("#range-l2", "data-step") == "0.1"
        assert page.get_attribute("#range-l4", "data-step") == "0.2"                   # 32 mm / 200 = 0.16
        assert "key step 0.1 (shift 1)" in page.inner_text(".var[data-var='l2'] .bounds")
        for key, expected in (("ArrowRight", 35.1), ("Shift+ArrowRight", 36.1), ("ArrowDown", 36.0)):
            count = int(page.get_attribute("body", "data-evaluations"))
            page.focus("#range-l2")
            page.keyboard.press(key)
            page.wait_for_function(f"() => Number(document.body.dataset.evaluations) > {count} && "
                                   "document.body.dataset.busy === '0'", timeout=30_000)
            assert box_value(page, "l2") == expected, key
            assert page.get_attribute("body", "data-grid") == "fine"
        # a wider window: the drawing follows (still one px per viewBox unit)
        page.set_viewport_size({"width": 1600, "height": 900})
        page.wait_for_function("() => Math.abs(document.querySelector('#panel-main svg').viewBox.baseVal.width - "
                               "document.querySelector('#panel-main svg').getBoundingClientRect().width) < 0.5")
        assert page.locator("#panel-main").bounding_box()["width"] >= 0.6 * 1600
        assert seen["left"] == [] and seen["errors"] == []


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_typed_value_the_page_cannot_take_is_refused_in_words_and_a_stopped_server_is_said(tmp_path,
                                                                                           sync_playwright):
    """An empty number box (the browser's value "", which Number() reads as 0) or one outside the bounds keeps the
    page's value and says why: no evaluation at 0, nothing saved at 0.  An empty starts box reaches the server as
    text, not as 0.  When the server stops, the page says so and shows no solve as running."""
    spec = STUDIO_SPECS["planting_fourbar"]
    with running_studio(spec, tmp_path / "studio") as studio, studio_page(sync_playwright, studio) as (page, seen):
        count = int(page.get_attribute("body", "data-evaluations"))
        before = page.input_value("#number-seedbed_y")
        assert float(before) != 0.0
        page.fill("#number-seedbed_y", "")
        page.press("#number-seedbed_y", "Tab")
        assert page.inner_text("#error") == f"seedbed_y: the typed value is not a number; kept {before} mm"
        assert page.input_value("#number-seedbed_y") == before
        page.fill("#number-l2", "50")
        page.press("#number-l2", "Tab")
        assert page.inner_text("#error").startswith("l2: 50 lies outside its bounds [28, 42]; kept 35 mm")
        page.wait_for_timeout(300)
        assert int(page.get_attribute("body", "data-evaluations")) == count      # nothing evaluated
        page.fill("#starts", "")
        page.click("#solve")
        page.wait_for_function("() => !document.getElementById('error').hidden && "
                               "document.getElementById('error').textContent.startsWith('starts')", timeout=10_000)
        assert "got '(empty)'" in page.inner_text("#error"), page.inner_text("#error")
        studio.stop()
        page.fill("#number-l2", "36")
        page.press("#number-l2", "Tab")
        page.wait_for_function("() => document.body.dataset.solve === 'gone'", timeout=10_000)
        assert "is not answering" in page.inner_text("#error")
        assert page.inner_text("#solve-state").startswith("server stopped")
        assert page.is_disabled("#solve") and page.is_disabled("#cancel")
        assert not seen["left"]

"""Latency of agrisynth studio (a benchmark, not a pass/fail test; run with
`pytest -m benchmark --benchmark-enable -n 0 -s tests/test_studio_bench.py`):
time from a slider's input event to the evaluated rule table drawn in the page, per kind, in headless Chromium.

Coarse: ``input`` events (a slider moving); fine: ``change`` (released).  Each input waits for the table
of the one before.  The figures (median, 95th percentile, ms; and the medians of the server's evaluation and
of the page's drawing) go into the benchmark's extra_info and are printed.
"""

from __future__ import annotations

import statistics

import pytest

from studio_fixtures import MOVED, STUDIO_SPECS, running_studio
from test_report_browser import CHROMIUM, LAUNCH_FLAGS, sync_playwright  # noqa: F401 - the fixture

pytest.importorskip("starlette")
pytestmark = pytest.mark.benchmark

#: kinds whose spec frees a variable to move (picker is check-only: its page shows)
MOVABLE = sorted(k for k in STUDIO_SPECS if k != "picker")
ROUNDS = {"coarse": 40, "fine": 10}

#: one input on the first free slider, to ``value``; resolves with the ms until the page drew the answer
ONE_INPUT = """async ([name, value, event]) => {
  const range = document.getElementById(`range-${name}`);
  const before = Number(document.body.dataset.evaluations);
  const drawn = new Promise((resolve) => {
    const watch = new MutationObserver(() => {
      if (Number(document.body.dataset.evaluations) > before) { watch.disconnect(); resolve(); }
    });
    watch.observe(document.body, {attributes: true, attributeFilter: ["data-evaluations"]});
  });
  const began = performance.now();
  range.value = value;
  range.dispatchEvent(new Event(event));
  await drawn;
  return [performance.now() - began, Number(document.body.dataset.drawMs), state.current.ms];
}"""


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(q * (len(ordered) - 1))))]


@pytest.mark.parametrize("grid", ["coarse", "fine"])
@pytest.mark.parametrize("kind", MOVABLE)
def test_input_to_table_latency(kind, grid, tmp_path, sync_playwright, benchmark):
    with running_studio(STUDIO_SPECS[kind], tmp_path / "studio") as studio, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=LAUNCH_FLAGS)
        page = browser.new_page()
        page.goto(studio.url)
        page.wait_for_selector("body[data-ready='1']", timeout=60_000)
        page.uncheck("#animate")
        # the first free slider (guide_way: the control point the studio tests move, one with an effect)
        var = next(v for v in studio.session.free if v.name in MOVED.get(kind, (v.name,)))
        lo, hi = var.bounds
        # values sweeping a tenth of the range either side of the given one, never the same twice running
        span = 0.1 * (hi - lo)
        values = [min(hi, max(lo, var.value + span * ((k % 9) - 4) / 4)) for k in range(ROUNDS[grid] + 1)]
        event = "input" if grid == "coarse" else "change"
        page.evaluate(ONE_INPUT, [var.name, values[0], event])        # warm-up
        timings: list[float] = []
        drawing: list[float] = []
        evaluation: list[float] = []
        rounds = iter(values[1:])

        def one_input():
            total, drawn, evaluated = page.evaluate(ONE_INPUT, [var.name, next(rounds), event])
            timings.append(total)
            drawing.append(drawn)
            evaluation.append(evaluated)

        if benchmark.disabled:          # --benchmark-disable (the default addopts): the rounds all the same
            for _ in range(ROUNDS[grid]):
                one_input()
        else:
            benchmark.pedantic(one_input, rounds=ROUNDS[grid], iterations=1)
        browser.close()
    median, p95 = statistics.median(timings), percentile(timings, 0.95)
    draw, evaluate = statistics.median(drawing), statistics.median(evaluation)
    benchmark.extra_info.update(kind=kind, grid=grid, median_ms=round(median, 1), p95_ms=round(p95, 1),
                                evaluation_median_ms=round(evaluate, 1), draw_median_ms=round(draw, 1),
                                samples=len(timings))
    print(f"\nstudio latency {kind} {grid}: median {median:.1f} ms, p95 {p95:.1f} ms; medians of its parts: "
          f"evaluation (server) {evaluate:.1f} ms, drawing {draw:.1f} ms ({len(timings)} inputs)")
    assert len(timings) == ROUNDS[grid] and all(t > 0 for t in timings)

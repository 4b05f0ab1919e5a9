"""Terminal tables adapt to the terminal's width by folding a long cell onto the next lines of
that cell, never by cutting it ("opening_cam_optimised_l..." or a number losing its digits)."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from synthesis.cli import terminal
from synthesis.cli.views import bench_table, comparison_table, rule_table
from synthesis.report.tables import DesignRow

NAME = "opening_cam_redesign_modified_sine_return"
RULE = {"name": "transmission_angle_minimum", "value": 40.123456, "limit": [40.0, None], "unit": "deg",
        "satisfied": True, "margin": 0.123456, "where": "over a turn, at theta2 = 180 deg"}
BENCH = [{"rows": [{"problem": NAME, "method": "ipopt_exact", "objective": 1.2345678, "objective_gap": 0.0,
                    "worst_violation": 0.0, "median_s": 6.38555, "details": {"median_iterations": 12},
                    "time_to_target_text": "2.5", "time_ratio_text": "1.0x"}]}]
DESIGN = [DesignRow("base_radius_of_the_cam", [52.345678], [False], "mm", [10.0, 150.0], True, ["upper"], 50.0)]


def body_cells(text: str) -> list[str]:
    """The cells of a one-row rich table as printed: each column's fragments over the row's lines, joined,
    without spaces (a cell may wrap at one)."""
    lines = [ln for ln in text.splitlines() if ln.startswith("│")]
    columns = [ln.strip("│").split("│") for ln in lines]
    return ["".join(parts[i] for parts in columns).replace(" ", "") for i in range(len(columns[0]))]


def printed(table, width: int) -> str:
    buf = io.StringIO()
    Console(file=buf, width=width, highlight=False).print(table)
    return buf.getvalue()


@pytest.mark.parametrize("width", [60, 100, 10_000])
@pytest.mark.parametrize("name, table, cells", [
    ("rules", lambda: rule_table([RULE], "t"), ["transmission_angle_minimum", "40.12", ">=40", "deg", "0.1235",
                                                  "pass", "overaturn,attheta2=180deg"]),
    ("given vs solved", lambda: comparison_table([RULE], [RULE], "t"),
     ["transmission_angle_minimum", ">=40", "40.12", "pass", "40.12", "pass", "deg"]),
    ("bench", lambda: bench_table(BENCH, 3), [NAME, "ipopt_exact", "1.235", "0", "0", "6.386", "2.5", "12", "1.0x"]),
    ("design", lambda: terminal.design_table(DESIGN, "t"),
     ["base_radius_of_the_cam", "50", "52.3457", "mm", "[10,150]", "atupperbound"]),
])
def test_no_cell_is_cut_at_any_width(name, table, cells, width):
    text = printed(table(), width)
    assert "…" not in text
    assert body_cells(text) == cells
    assert max(len(ln) for ln in text.splitlines()) <= width


class _Pipe(io.StringIO):
    def isatty(self) -> bool:
        return False


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_piped_table_is_folded_to_a_readable_width(monkeypatch):
    """Piped, a rule table with a long note was as wide as its longest cell (300 characters and more): it is folded
    to $COLUMNS, else 120, and still no cell is cut; on a terminal rich measures the terminal itself."""
    note = "where the coupler curve leaves the furrow, " * 8
    rule = {**RULE, "where": note}
    monkeypatch.delenv("COLUMNS", raising=False)
    assert terminal.table_width(_Pipe()) == 120 and terminal.table_width(_Terminal()) is None
    for columns, width in (("", 120), ("90", 90), ("wide", 120), ("0", 120)):
        monkeypatch.setenv("COLUMNS", columns)
        out = _Pipe()
        terminal.print_table(Console(file=out, width=terminal.PIPED_WIDTH, highlight=False), rule_table([rule], "t"))
        text = out.getvalue()
        assert max(len(ln) for ln in text.splitlines()) == width, columns
        assert "…" not in text and body_cells(text)[-1] == note.replace(" ", "")


def test_the_design_table_has_a_marks_column_only_when_a_variable_is_at_a_bound():
    inside = DesignRow("crank", [20.0], [False], "mm", [10.0, 150.0], True, [], 25.0)
    for rows, columns in (([inside], 5), (DESIGN + [inside], 6)):
        text = printed(terminal.design_table(rows, "t"), 200)
        header = next(ln for ln in text.splitlines() if ln.startswith("┃"))
        assert header.count("┃") - 1 == columns, header


def test_the_solve_line_says_how_many_starts_ran_as_result_json_does():
    """[solver] stop_at_objective ended a run after 4 of 8 starts: the terminal said "best of 8 starts", result.json
    (starts_run 4, stopped_early) and report.html "4 of 8 run"."""
    from synthesis.cli.views import _starts_said

    assert _starts_said({"starts": 8, "starts_run": 8, "stopped_early": False}) == "8 starts"
    assert _starts_said({"starts": 8, "starts_run": 4, "stopped_early": True}) == (
        "the 4 starts run of 8 (stopped early: [solver] stop_at_objective was reached)")
    assert _starts_said({"starts": 8, "starts_run": 9}) == "8 starts and one from the elastic re-solve"


def test_the_bench_table_says_a_gap_no_run_measured_as_bench_md_does():
    """No run met every rule, so there is no best known: bench.json wrote null, bench.md "–", the terminal "-inf"."""
    from rich.console import Console

    from synthesis.cli.views import bench_table

    row = {"problem": "steer_tight", "method": "ipopt_multistart", "objective": 9.165,
           "objective_gap": float("-inf"), "worst_violation": 4.02, "median_s": 0.292, "time_to_target_text": None,
           "time_ratio_text": "n/a", "details": {}}
    console = Console(width=200, record=True)
    console.print(bench_table([{"rows": [row, {**row, "objective_gap": None}]}], 1))
    text = console.export_text()
    assert "inf" not in text and text.count("–") >= 4

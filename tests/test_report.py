"""Reports and `agrisynth compare`: the tables the pages are built from, and bad result files."""

from __future__ import annotations

import dataclasses
import html
import json
import re

import pytest

from conftest import LIBRARY, PLANTING
from report_fixtures import checked_run
from synthesis.report.compare import load_candidates, write_comparison
from synthesis.errors import ResultError
from synthesis import kinds
from synthesis.report.tables import candidates, design_rows, headlines, rule_rows, worst_margins
from synthesis.result import SCHEMA_VERSION, load_result
from solving import agrisynth

#: most tests here read the same two checked runs (``runs``, seconds of figures): one test process draws them once
pytestmark = pytest.mark.xdist_group("report-runs")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs")
    return [checked_run(PLANTING / f"taiwan_example{k}.toml", out) for k in (1, 3)]


def test_rule_table_marks_exactly_the_violated_rules(runs):
    cands = candidates([r for _, r in runs])
    rows = rule_rows(cands)
    red = {(row.name, cands[i].label) for row in rows for i, bad in enumerate(row.violated) if bad}
    # seed 000 example 1 as we read it: collinearity at P2, entry angle and transmission angle fail
    assert {n for n, c in red if c == "taiwan_example1"} == {"p1p2p3_collinearity", "entry_angle",
                                                             "transmission_angle_min"}
    expected = {(r["name"], c.label) for c in cands for r in c.result.rules if not r["satisfied"]}
    assert red == expected
    # one row per rule, in the baseline's order
    assert [row.name for row in rows] == [r["name"] for r in cands[0].result.rules]


def test_worst_margin_is_the_smallest_normalised_margin(runs):
    cands = candidates([r for _, r in runs])
    for c, w in zip(cands, worst_margins(cands)):
        margins = {r["name"]: r["normalised_margin"] for r in c.result.rules if r["normalised_margin"] is not None}
        assert w.rule == min(margins, key=margins.get)
        assert w.normalised_margin == pytest.approx(min(margins.values()))
        assert w.violated == len(c.result.violated())


def test_design_table_highlights_what_differs_from_the_baseline(runs):
    cands = candidates([r for _, r in runs])
    rows = {row.name: row for row in design_rows(cands)}
    # Table 1: examples 1 and 3 share nothing but the branch
    assert rows["l1"].values == [75, 74] and rows["l1"].differs == [False, True]
    assert rows["branch"].differs == [False, False]
    same = candidates([runs[0][1], runs[0][1]])
    assert not any(any(row.differs) for row in design_rows(same))
    assert [c.label for c in same] == ["taiwan_example1 (1)", "taiwan_example1 (2)"]


@pytest.mark.slow
def test_compare_page_has_one_red_cell_per_violation_and_every_figure(runs, tmp_path):
    cands = load_candidates([runs[0][0], runs[1][0] / "result.json"])
    page = write_comparison(cands, tmp_path / "cmp")
    text = page.read_text()
    n_red_rules = sum(len(c.result.violated()) for c in cands)
    n_red_summary = sum(1 for c in cands if c.result.violated())
    assert len(re.findall(r"<td class='(?:num )?fail'", text)) == n_red_rules + n_red_summary
    images = re.findall(r"<img src='([^']+)'", text)
    assert images == ["paths.png", "kinematics.png", "linkage.png", "animation.gif"]
    assert all((page.parent / f).stat().st_size > 1000 for f in images)
    assert "http" not in text.replace("http-equiv", "")        # nothing fetched from a network
    assert not list(page.parent.glob(".compare.*"))             # no staging folder left behind


def test_single_run_report_shows_the_runs_own_figures_not_the_overlays(runs):
    """One design's drawings: its trajectory, speeds, linkage and animation; not the comparison
    overlay of the same paths (paths.png), which belongs to `agrisynth compare`."""
    folder, _ = runs[0]
    text = (folder / "report.html").read_text()
    for f in ("trajectory.png", "kinematics.png", "linkage.png", "animation.gif"):
        assert f"src='{f}'" in text and (folder / f).exists()
    assert "paths.png" not in text and not (folder / "paths.png").exists()
    assert "(baseline)" not in text


def test_figure_that_cannot_be_drawn_is_a_note_not_a_crash(runs, tmp_path):
    data = json.loads((runs[0][0] / "result.json").read_text())
    del data["design"]["l5"]               # a hand-edited or partial result
    (tmp_path / "partial.json").write_text(json.dumps(data))
    page = write_comparison(load_candidates([tmp_path / "partial.json"]), tmp_path / "cmp")
    text = page.read_text()
    assert "class='missing'" in text and "comparison figures not drawn" in text and "l5" in text


def _write(path, text):
    path.write_text(text)
    return path


def test_bad_result_files_are_named_with_what_is_wrong(runs, tmp_path):
    good = (runs[0][0] / "result.json").read_text()
    with pytest.raises(ResultError, match=r"cut\.json: truncated"):
        load_result(_write(tmp_path / "cut.json", good[: len(good) // 2]))
    future = json.loads(good)
    future["schema_version"] = SCHEMA_VERSION + 1
    with pytest.raises(ResultError, match=rf"future\.json: schema_version {SCHEMA_VERSION + 1} is newer"):
        load_result(_write(tmp_path / "future.json", json.dumps(future)))
    with pytest.raises(ResultError, match=r"other\.json: missing required key\(s\) kind, spec_sha256"):
        load_result(_write(tmp_path / "other.json", json.dumps({"name": "x", "status": "optimal",
                                                                "design": {}, "rules": []})))
    with pytest.raises(ResultError, match="no such result file"):
        load_result(tmp_path / "nowhere")


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_compare_cli_exit_codes(runs, tmp_path):
    good = json.loads((runs[0][0] / "result.json").read_text())
    other = dict(good, kind="clamp_cam", name="a-cam")
    mixed = _write(tmp_path / "cam.json", json.dumps(other))
    cut = _write(tmp_path / "cut.json", json.dumps(good)[:500])

    def run(*args):
        return agrisynth("compare", *map(str, args), "--out", str(tmp_path / "out"))

    p = run(runs[0][0], mixed)
    assert p.returncode == 2 and "one kind" in p.stderr and "clamp_cam" in p.stderr and "Traceback" not in p.stderr
    p = run(runs[0][0], cut)
    assert p.returncode == 2 and "cut.json: truncated" in p.stderr
    p = run(runs[0][0], runs[1][0])
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "out" / "compare.html").exists()
    assert "taiwan_example1: evaluated, 3 rule(s) violated" in p.stdout


def test_objective_text_says_when_a_value_could_not_be_measured():
    from synthesis.report.tables import objective_text

    assert objective_text({"name": "sum_of_distances", "value": 0.0978123, "unit": "mm"}) == "sum_of_distances = 0.0978123 mm"
    assert objective_text({"name": "sum_of_distances", "value": None, "unit": "mm"}) == "sum_of_distances = not measured"
    assert objective_text(None) is None
    # a pure number (guide_way's smoothness, unit "-") reads without a trailing "-"
    assert objective_text({"name": "smoothness", "value": 0.98728, "unit": "-"}) == "smoothness = 0.98728"


@pytest.mark.parametrize("edit, complaint", [
    (lambda d: d.update(name=None), "name must be a string"),
    (lambda d: d.update(versions=None), "versions must be an object"),
    (lambda d: d.update(rules=None), "rules must be a list"),
    (lambda d: d["rules"][0].pop("satisfied"), r"rules\[0\] needs a string name and a true/false satisfied"),
    (lambda d: d["rules"][0].update(limit=None), r"rules\[0\] \(p1p3_distance\): limit must be"),
    (lambda d: d.update(status="great"), "status 'great' is not one of"),
])
def test_result_json_with_wrong_types_is_refused_naming_the_file(runs, tmp_path, edit, complaint):
    data = json.loads((runs[0][0] / "result.json").read_text())
    edit(data)
    with pytest.raises(ResultError, match=rf"edited\.json: {complaint}"):
        load_result(_write(tmp_path / "edited.json", json.dumps(data)))


def test_unknown_kind_and_broken_bench_are_refused(runs, tmp_path):
    data = json.loads((runs[0][0] / "result.json").read_text())
    with pytest.raises(ResultError, match="kind 'steam_engine' is not one this agrisynth knows"):
        load_candidates([_write(tmp_path / "odd.json", json.dumps(dict(data, kind="steam_engine")))])
    from synthesis.report.compare import load_bench

    bench = _write(tmp_path / "bench.json", json.dumps({"problems": [{"problem": "p", "best_known": 0}],
                                                        "rows": [{"problem": "p", "method": "m"}]}))
    with pytest.raises(ResultError, match=r"bench\.json: not a readable agrisynth bench.json \(KeyError: .*objective"):
        load_bench(bench)


@pytest.mark.slow
def test_a_figure_that_fails_costs_the_run_nothing(tmp_path, monkeypatch):
    from synthesis.kinds.planting import plots

    def broken(result, path):
        raise RuntimeError("out of ink")

    from synthesis.kinds.planting import parts

    monkeypatch.setattr(plots, "trajectory_figure", broken)
    monkeypatch.setattr(parts, "trajectory_figure", broken)     # the Kind class hands out its parts' binding
    folder, _ = checked_run(PLANTING / "taiwan_example1.toml", tmp_path)
    page = (folder / "report.html").read_text()
    assert (folder / "result.json").exists() and not (folder / "trajectory.png").exists()
    assert "trajectory.png not written: RuntimeError: out of ink" in page and "src='trajectory.png'" not in page


@pytest.mark.slow
def test_picker_comparison_overlays_the_clamp_trajectories(tmp_path):
    folder, result = checked_run(PLANTING.parent / "picker" / "cai2020_picker.toml", tmp_path / "runs")
    page = write_comparison(load_candidates([folder, folder / "result.json"]), tmp_path / "cmp")
    assert "src='trajectories.png'" in page.read_text()
    assert (page.parent / "trajectories.png").stat().st_size > 10_000
    # the figure is drawn from the trajectory the result carries: one cycle at 60 r/min
    assert result.trajectory["t"][-1] == pytest.approx(1.0)


def test_the_design_table_names_a_crank_rockers_assembly_from_its_facts():
    """crank_rocker holds its assembly (+1 / -1) in facts.branch, not in the design: two designs of the same
    dimensions on the two assemblies differ only there, and the table's "branch (assembly)" row shows it."""
    import dataclasses

    from conftest import LIBRARY
    from synthesis.kinds.crank_rocker.check import run_check
    from synthesis.report.tables import candidates, design_rows
    from synthesis.spec import load_spec

    first = run_check(load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml"))
    assert "branch" not in first.design and first.extra["branch"] in (1, -1)
    other = dataclasses.replace(first, name="other", extra={**first.extra, "branch": -first.extra["branch"]})
    rows = {row.name: row for row in design_rows(candidates([first, other]))}
    assert rows["branch (assembly)"].values == [first.extra["branch"], -first.extra["branch"]]
    assert rows["branch (assembly)"].differs == [False, True]
    assert not any(d for name, row in rows.items() if name != "branch (assembly)" for d in row.differs)


@pytest.mark.slow
def test_the_design_tables_bounds_are_each_designs_own_where_the_specs_disagree(runs, tmp_path):
    """A published design (every variable fixed) beside a redesign of it (free within bounds): the bounds column
    once showed the first design's "fixed" for both, beside the redesign's "at lower bound"."""
    from synthesis.report.compare import write_comparison
    from synthesis.spec import load_spec

    folder, redesign = checked_run(PLANTING / "redesign_from_example1.toml", tmp_path / "runs")
    published = runs[0][1]
    rows = {row.name: row for row in design_rows(candidates([published, redesign]))}
    bounds = list(load_spec(PLANTING / "redesign_from_example1.toml").model.arm.l2.bounds)
    assert rows["l2"].per_candidate == [(False, None), (True, bounds)]
    assert rows["l2"].free is None and rows["l2"].bounds is None
    assert rows["l1"].per_candidate is None and rows["l1"].free is False          # fixed in both
    same = {row.name: row for row in design_rows(candidates([redesign, redesign]))}
    assert same["l2"].per_candidate is None and same["l2"].free is True and list(same["l2"].bounds) == bounds
    page = write_comparison(load_candidates([runs[0][0], folder]), tmp_path / "cmp").read_text()
    row = next(line for line in page.splitlines() if line.startswith("<tr><td>l2</td>"))
    assert "taiwan_example1: fixed<br>redesign_from_example1: [" in row


def test_run_facts_say_the_workers_and_how_many_starts_ran(runs):
    import dataclasses

    from synthesis.report.tables import run_facts

    base = runs[0][1]
    solver = {"name": "ipopt", "return_status": "Solve_Succeeded", "iterations": 9, "wall_s": 1.5, "starts": 40,
              "seed": 0, "best_start": 3, "workers": 2}
    ran = [dataclasses.replace(base, name=f"r{k}", solver=dict(solver, starts_run=n)) for k, n in enumerate((40, 37, 41))]
    facts = dict(run_facts(candidates(ran)))
    assert facts["starts"] == [40, "37 of 40 run", "40 + 1 from the elastic re-solve"]
    assert facts["workers"] == [2, 2, 2] and facts["wall time (build and starts), s"] == [1.5] * 3


def test_a_bench_of_another_kind_is_refused_and_a_bench_of_every_kind_gives_this_kinds_rows(tmp_path):
    from synthesis.report.compare import bench_of_kind

    crank = [{"problem": "a", "kind": "crank_rocker"}, {"problem": "b", "kind": "crank_rocker"}]
    with pytest.raises(ResultError, match="a bench of crank_rocker problems, not of planting_fourbar"):
        bench_of_kind(tmp_path / "bench.json", crank, "planting_fourbar")
    mixed = crank + [{"problem": "c", "kind": "planting_fourbar"}, {"problem": "d"}]
    assert [p["problem"] for p in bench_of_kind(tmp_path, mixed, "planting_fourbar")] == ["c", "d"]


def test_operating_conditions_show_the_range_a_design_was_solved_over(runs):
    """An envelope design (facts.envelope: forward speed 0.5-0.75 m/s) was listed at its nominal 0.6 m/s alone."""
    import dataclasses

    from synthesis.report.tables import operating_conditions

    base = runs[0][1]
    envelope = {"conditions": {"forward_speed": {"range": [0.5, 0.75], "nominal": 0.6, "section": "operation"}}}
    ranged = dataclasses.replace(base, name="ranged", extra={**base.extra, "envelope": envelope})
    rows = {(label, unit): values for label, unit, values in operating_conditions(candidates([base, ranged]))}
    speed = base.extra["operation"]["forward_speed_m_s"]
    assert rows[("forward speed", "m/s")] == [speed, f"{speed:g} (nominal; over 0.5-0.75)"]
    assert rows[("crank speed", "r/min")][0] == rows[("crank speed", "r/min")][1]      # not a range: as it was


def test_a_not_evaluated_cell_says_its_own_limit_where_it_differs_from_the_rows():
    """A trial: a compare of two planting results whose collinearity limits differ (5 and 0.5 deg), the second not
    evaluated there: its cell read only "not evaluated", under the row's limit (the first candidate's, <= 5)."""
    from synthesis.report.page import _rule_cell
    from synthesis.report.tables import RuleCell

    own = RuleCell(None, [None, 0.5], None, None, False, "P1 never found")
    assert "(limit &le; 0.5)" in _rule_cell(own, [None, 5.0])
    assert "(limit" not in _rule_cell(own, [None, 0.5])


def test_steering_lock_ranges_and_comb_finger_operation_are_operating_conditions():
    """Steering designs evaluated over inside locks 0-27 and 0-40 deg were compared side by side with no word of
    it, and a comb_finger page had no operating conditions (its machine speed and row spacing are top-level facts)."""
    from conftest import LIBRARY
    from synthesis import kinds
    from synthesis.report.tables import candidates, operating_conditions
    from synthesis.spec import load_spec

    def checked(path):
        loaded = load_spec(LIBRARY / path)
        return kinds.checker(loaded.kind)(loaded)

    steering = [checked(f"steering/steering_redesign_{lock}.toml") for lock in (27, 40)]
    rows = {(label, unit): values for label, unit, values in operating_conditions(candidates(steering))}
    assert rows[("inside locks evaluated, 0 to", "deg")] == [27.0, 40.0]
    finger = checked("comb_finger/peanut_baseline.toml")
    rows = {(label, unit): values for label, unit, values in operating_conditions(candidates([finger]))}
    spec = load_spec(LIBRARY / "comb_finger/peanut_baseline.toml").model
    assert rows[("machine speed", "m/s")] == [spec.operation.machine_speed]
    assert rows[("row spacing", "mm")] == [spec.operation.row_spacing]


def test_a_bench_is_found_in_the_folder_bench_was_given(tmp_path):
    """`agrisynth bench --out OUT` writes OUT/bench/bench.json; `compare RESULT OUT` said "OUT/result.json: no such
    result file".  OUT, OUT/bench and the file all name the bench; a run folder is never one."""
    from synthesis.report.compare import bench_file, is_bench

    (tmp_path / "out" / "bench").mkdir(parents=True)
    file = tmp_path / "out" / "bench" / "bench.json"
    file.write_text("{}")
    for given in (tmp_path / "out", tmp_path / "out" / "bench", file):
        assert bench_file(given) == file
    run = tmp_path / "run"
    run.mkdir()
    (run / "result.json").write_text("{}")
    (run / "bench.json").write_text("{}")
    assert not is_bench(run) and not is_bench(tmp_path / "elsewhere")


def test_candidates_tracing_different_targets_are_said_not_to_compare():
    """A trial: fourbar_path results of 14 and 16 target points side by side, objectives included, no word."""
    from synthesis.report.compare import _different_targets
    from synthesis.report.tables import Candidate
    from synthesis.result import Result

    def cand(label, targets):
        result = Result("fourbar_path", label, "0" * 64, "evaluated", {}, [], extra={"targets": targets})
        return Candidate(label=label, result=result)

    a, b = [[0.0, 0.0], [1.0, 1.0]], [[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]]
    assert _different_targets([cand("a", a), cand("b", a)]) == []
    assert _different_targets([cand("a", a), cand("b", b)]) == [
        "the candidates trace different target points (a: 2, b: 3 points): each objective measures the distance to "
        "its own targets, so they do not compare"]


def test_a_check_beside_a_solve_says_it_has_no_objective():
    """Two trials: compare of a published design's check beside a redesign showed "-" for its objective, read as a
    number gone missing.  It says a check evaluates the rules only; checks alone show no objective row."""
    from synthesis.report.tables import candidates, run_facts
    from synthesis.result import Result

    check = Result("crank_rocker", "published", "0" * 64, "evaluated", {"l7": 1.0}, [])
    solve = Result("crank_rocker", "redesign", "1" * 64, "optimal", {"l7": 1.0}, [],
                   objective={"name": "min_total_length", "value": 435.13, "unit": "mm"}, solver={"starts": 1})
    facts = dict(run_facts(candidates([check, solve])))
    assert facts["objective"] == ["none: a check evaluates the rules only", "min_total_length = 435.13 mm"]
    assert "objective" not in dict(run_facts(candidates([check, check])))


def test_each_candidates_headline_opens_its_verdict_box(runs):
    """The report's first screen: each candidate's headline (Kind.headline) in its verdict box, before the rules."""
    folder, result = runs[0]
    page = (folder / "report.html").read_text()
    lines = kinds.get(result.kind).headline(result)
    assert lines[0] == "entry angle 79.3 deg, planting depth 25 mm, hole P4-P6 28.6 mm"
    box = page[page.index("<div class='verdicts'>"):page.index("<h2>Rules</h2>")]
    assert "<ul class='headline'>" + "".join(f"<li>{html.escape(line)}</li>" for line in lines) + "</ul>" in box
    (head,) = headlines(candidates([result]))
    assert head.lines == lines and head.tables == []


def test_a_path_synthesis_report_tables_its_error_per_target(tmp_path):
    folder, result = checked_run(LIBRARY / "fourbar_path" / "picking_arc.toml", tmp_path)
    page = (folder / "report.html").read_text()
    assert "path error over 10 targets: rms 234 mm, max 238 mm at target 3" in page
    table = page[page.index("<h2>Path error per target</h2>"):page.index("<h2>Rules</h2>")]
    cells = re.findall(r"<tr><td class='num'>(\d+)</td><td class='num'>([^<]+)</td><td class='num'>([^<]+)</td>"
                       r"<td class='num'>([^<]+)</td></tr>", table)
    assert [int(c[0]) for c in cells] == list(range(1, 11))
    errors = result.extra["target_errors_mm"]
    assert [float(c[3]) for c in cells] == pytest.approx(errors, rel=5e-4)       # shown to 4 digits
    assert float(cells[2][3]) == pytest.approx(238.2, abs=0.05)                  # target 3, the largest


def test_a_result_its_kind_cannot_read_has_no_headline_and_keeps_its_page(runs):
    _, result = runs[0]
    odd = dataclasses.replace(result, extra={**result.extra, "precision_points": ["not", "a", "table"]})
    (head,) = headlines(candidates([odd]))
    assert head.lines == [] and head.tables == []


def test_a_bounds_cell_names_each_text_once_with_the_candidates_that_have_it():
    """Where the specs disagree, the candidates that share bounds share one line (the cell listed every candidate's
    name with the same bounds)."""
    from types import SimpleNamespace

    from synthesis.report.page import _bounds_cell

    cands = [SimpleNamespace(label=label) for label in ("published", "redesign", "redesign_4", "wider")]
    row = SimpleNamespace(per_candidate=[(False, None), (True, [28.0, 42.0]), (True, [28.0, 42.0]),
                                         (True, [20.0, 50.0])], free=None, bounds=None)
    assert _bounds_cell(row, cands) == ("<td class='note'>published: fixed<br>redesign, redesign_4: [28, 42]<br>"
                                        "wider: [20, 50]</td>")

"""What the comparison page and a run's report say of a candidate, against its result.json: the findings of an audit
of the compare page (each was reproduced before the fix)."""

from __future__ import annotations

import json

import pytest

from conftest import PLANTING
from report_fixtures import checked_run
from synthesis.errors import ResultError
from synthesis.report import compare as compare_module
from synthesis.report.page import rule_table, tolerance_section
from synthesis.report.tables import candidates, worst_margin
from synthesis.result import Result, load_result


def _check_file(tmp_path):
    folder, _ = checked_run(PLANTING / "taiwan_example1.toml", tmp_path)
    return folder / "result.json"


def test_a_violated_rule_without_a_normalised_margin_is_the_tightest_not_a_passing_one():
    """A tolerance analysis' verdict rows (``@monte_carlo``, ``@linear_worst_corner``) have no normalised margin: the
    "worst margin" line named a passing rule (normalised margin 1e-7) as the tightest, beside "2 violated"."""
    rules = [
        {"name": "steering_arm_length", "satisfied": True, "value": 1.0, "margin": 1e-7, "normalised_margin": 1.02e-7,
         "unit": "mm"},
        {"name": "steering_arm_length@monte_carlo", "satisfied": False, "value": 0.565, "margin": -0.435,
         "normalised_margin": None, "unit": "-"},
        {"name": "steering_arm_length@linear_worst_corner", "satisfied": False, "value": 0.5, "margin": -0.5,
         "normalised_margin": None, "unit": "mm"},
    ]
    w = worst_margin(rules)
    assert (w.rule, w.normalised_margin, w.margin, w.unit, w.violated) == (
        "steering_arm_length@monte_carlo", None, -0.435, "-", 2)
    # a violated rule with a normalised margin stays first
    rules[0] = {**rules[0], "satisfied": False, "margin": -1.0, "normalised_margin": -0.5}
    assert worst_margin(rules).rule == "steering_arm_length"
    # nothing violated: the smallest normalised margin, as before
    assert worst_margin([{**r, "satisfied": True} for r in rules[:1]]).rule == "steering_arm_length"


def test_a_result_without_versions_says_they_are_not_recorded(tmp_path):
    """The reader's own versions (agrisynth, casadi, Python) were shown as the file's."""
    path = _check_file(tmp_path)
    data = json.loads(path.read_text())
    del data["versions"]
    path.write_text(json.dumps(data))
    old = load_result(path)
    assert old.versions == {}
    new = Result.from_json(json.loads(json.dumps(load_result(_check_file(tmp_path / "b")).to_json())))
    notes = compare_module.different_versions(candidates([old, new]))
    assert any("not recorded" in n for n in notes)


def test_null_units_are_shown_and_hand_edited_solver_numbers_are_refused_in_one_line(tmp_path):
    """A rule's or a design variable's unit null (the loader accepts both) crashed the page (AttributeError);
    ``solver.starts: "8"`` or a probability as text crashed it later (TypeError, ValueError)."""
    path = _check_file(tmp_path)
    data = json.loads(path.read_text())
    data["rules"][0]["unit"] = None
    next(iter(data["design_variables"].values()))["unit"] = None
    path.write_text(json.dumps(data))
    page = rule_table(candidates([load_result(path)]))
    assert data["rules"][0]["name"] in page
    for edit, said in (({"starts": "8"}, "solver.starts must be a whole number or null, got '8'"),
                       ({"confidence": {"probability_best_is_global": "0.9"}},
                        "solver.confidence.probability_best_is_global must be a number or null, got '0.9'")):
        path.write_text(json.dumps({**data, "solver": edit}))
        with pytest.raises(ResultError) as err:
            load_result(path)
        assert said in str(err.value)


def test_a_tolerance_analysis_without_samples_says_no_monte_carlo_ran(tmp_path):
    """``tolerance --samples 0``: the page said "Monte-Carlo check of the answer: 0 samples ... - pass every rule"
    over an empty table; and the analysis' objective read "none: a check evaluates the rules only"."""
    from synthesis.report.tables import run_facts

    path = _check_file(tmp_path)
    data = json.loads(path.read_text())
    data["facts"]["tolerance"] = {"stack_up": {}, "monte_carlo": {"samples": 0, "seed": 0, "rules": {}}}
    path.write_text(json.dumps(data))
    analysis = load_result(path)
    text = tolerance_section(candidates([analysis]))
    assert "no Monte-Carlo check (0 samples)" in text and "pass every rule" not in text
    solved = Result.from_json({**data, "name": "solved", "status": "optimal",
                               "objective": {"name": "nearest", "value": 0.5, "unit": "-"},
                               "facts": {k: v for k, v in data["facts"].items() if k != "tolerance"}})
    objectives = dict(run_facts(candidates([solved, analysis])))
    assert objectives["objective"] == ["nearest = 0.5", "none: a tolerance analysis evaluates the rules only"]


def test_a_long_candidate_name_is_wrapped_inside_the_figure():
    """A 95-character name clipped the steering overlay's legend on both sides; one of 195 characters left no room
    for it (matplotlib: "Tight layout not applied")."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from synthesis.report.legends import legend_below

    fig, ax = plt.subplots(figsize=(8, 4.6))
    for name in ("a" * 195, "steering_redesign_40_" + "x" * 74):
        ax.plot([0, 1], [0, 1], label=f"{name} (max 0.523 deg)")
    legend = legend_below(ax, ncol=2, fontsize=8)
    fig.tight_layout()
    fig.canvas.draw()
    box, frame = legend.get_window_extent(), fig.bbox
    assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0
    assert all(len(line) <= 48 for t in legend.get_texts() for line in t.get_text().splitlines())
    plt.close(fig)


def test_the_auto_line_says_the_starts_that_ran_and_whose_batch_the_answer_is():
    """The kind's early stop (stop_at_objective) after 1 of a 16-start batch read "16 starts"; an answer kept from an
    earlier batch says so, with every batch run."""
    from synthesis.report.tables import auto_said

    early = {"starts": 16, "starts_run": 1, "auto": {"stopped_by": "stop_at_objective", "batches": [16]}}
    assert auto_said(early) == "; --starts auto: 1 of 16 starts, stopped by stop_at_objective"
    kept = {"starts": 16, "starts_run": 16,
            "auto": {"stopped_by": "max_starts", "batches": [16, 32, 64], "answer_batch": 16}}
    assert auto_said(kept) == ("; --starts auto: batches of 16, 32, 64 starts, stopped by max_starts; the answer and "
                               "this statement are the 16-start batch's (no later batch found as good a design)")
    assert auto_said({"starts": 8}) == ""


def test_objectives_that_do_not_compare_are_said_so(tmp_path):
    """redesign_from_example1's nearest = 0.561 beside redesign_from_example2's 0.938, each its distance from its own
    given design: set side by side without a word (the page warns of a path's different targets the same way)."""
    def solved(name: str, given: dict, objective: dict) -> Result:
        return Result.from_json({"kind": "planting_fourbar", "name": name, "spec_sha256": "0" * 64, "status": "optimal",
                                 "design": {"l2": 35.0}, "rules": [], "objective": objective,
                                 "baseline_design": given, "schema_version": 5})

    nearest = {"name": "nearest", "value": 0.5, "unit": "-"}
    one, two = solved("a", {"l2": 35.0}, nearest), solved("b", {"l2": 36.0}, {**nearest, "value": 0.9})
    notes = compare_module._different_objectives(candidates([one, two]))
    assert notes == ["each candidate's nearest objective is its design's distance from its own spec's given design "
                     "(and bounds), and those differ: the values do not compare"]
    assert compare_module._different_objectives(candidates([one, solved("c", {"l2": 35.0}, nearest)])) == []
    smooth = solved("d", {"l2": 35.0}, {"name": "smooth", "value": 3.0, "unit": "mm/s^2"})
    assert compare_module._different_objectives(candidates([one, smooth])) == [
        "the candidates minimise different objectives (a: nearest, d: smooth): their values do not compare"]


def test_a_probability_near_one_is_not_rounded_to_a_certainty():
    """P(best is global) 0.998 printed as "~ 1.00"."""
    from synthesis.report.tables import said

    line = said({"starts_counted": 500, "distinct_optima": 1, "starts_at_best": 500,
                 "probability_best_is_global": 0.99799})
    assert "P(best is global) ~ 0.997 " in line and "1.00" not in line
    assert "~ 0.95 " in said({"starts_counted": 20, "distinct_optima": 1, "starts_at_best": 20,
                              "probability_best_is_global": 18 / 19})

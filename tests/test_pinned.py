"""A rule no design variable moves (synthesis.core.pinned): found from the problem's exact Jacobians before any start,
and when violated at the spec's values refused at once (exit 2) naming the rule, its value, its limit and the spec
field that fixes it (docs/ARCHITECTURE.md, "Exit codes")."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from conftest import LIBRARY
from synthesis.constraints.base import Rule
from solving import agrisynth
from synthesis import kinds
from synthesis.core import pinned
from synthesis.core.kind import Setting
from synthesis.core.problem import ObjectiveParts, Problem
from synthesis.core.solve import run_solve
from synthesis.errors import SpecError
from synthesis.spec import load_spec


def edited(tmp_path: Path, source: str, replacements: list[tuple[str, str]]) -> Path:
    text = (LIBRARY / source).read_text()
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / Path(source).name
    path.write_text(text)
    return path


#: the measured case: a 35 mm analysis depth asked to plant 45-50 mm deep (before: exit 3 after 39 s of 16 starts and
#: an elastic diagnosis blaming "the variable bounds or the mechanism")
DEEP = [("analysis_depth = 25.0", "analysis_depth = 35"), ("[solver]", "[rules]\ndepth = [45, 50]\n\n[solver]")]


def built(path: Path):
    loaded = load_spec(path)
    kind = kinds.get(loaded.kind)
    solving = kind.solving()
    setting = Setting(loaded.model, 0, solving.prepare(loaded.model))
    return kind, loaded, solving.build(setting, False)


def test_a_rule_equal_to_an_input_on_the_equality_rows_is_pinned_and_its_value_read_off_them():
    """x = (a, b), the structural row b - a = 3: the rule b - a is 3 wherever the row holds (its Jacobian is the
    row's), a + b moves with a; a rule of a fixed variable c alone is pinned too, and names it."""
    x = ca.SX.sym("x", 3)
    a, b, c = x[0], x[1], x[2]
    rules = [Rule("gap", b - a, 5.0, None, "mm", 1.0), Rule("sum", a + b, 0.0, None, "mm", 1.0),
             Rule("fixed", 2 * c, None, 10.0, "mm", 1.0)]
    problem = Problem("toy", x, np.array([0.0, 0.0, 7.0]), np.array([10.0, 20.0, 7.0]), [(b - a - 3.0, 0.0, 0.0)],
                      rules, ObjectiveParts(f=a ** 2))
    found = {r.name: r for r in pinned.pinned_rules(problem, {2: ("[toy] c",)})}
    assert set(found) == {"gap", "fixed"}
    assert found["gap"].value == pytest.approx(3.0, abs=1e-12) and found["gap"].violated
    assert found["gap"].fixed_variables == ()
    assert found["fixed"].value == pytest.approx(14.0, abs=1e-12) and found["fixed"].violated
    assert found["fixed"].fixed_variables == ("[toy] c",)


def test_the_planting_depth_of_an_analysis_depth_is_refused_before_any_start(tmp_path):
    loaded = load_spec(edited(tmp_path, "planting_arm/redesign_from_example1.toml", DEEP))
    ran: list = []
    with pytest.raises(SpecError) as caught:
        run_solve(kinds.get(loaded.kind), loaded, workers=1, on_start=lambda report, best: ran.append(report),
                  record=ran.append)
    assert ran == []                  # no start was solved, none recorded
    assert caught.value.exit_code == 2
    assert ("planting_depth = 35 mm is fixed by [soil] analysis_depth (no design variable moves it); the rule asks "
            "45..50 mm: change [soil] analysis_depth or [rules] depth") in str(caught.value)


def test_the_refusal_is_one_line_with_exit_2_and_writes_nothing_cli(tmp_path):
    spec = edited(tmp_path, "planting_arm/redesign_from_example1.toml", DEEP)
    proc = agrisynth("solve", str(spec), "--out", str(tmp_path / "out"), "--workers", "1", cwd=tmp_path)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert "planting_depth = 35 mm is fixed by [soil] analysis_depth" in proc.stderr
    assert not (tmp_path / "out" / "redesign_from_example1").exists()


def test_a_depth_at_its_limit_is_pinned_but_no_violation(tmp_path):
    """The soil 30 mm above the lowest point against [20, 30]: the depth is read back as 30 to round-off, which is
    no violation (the solve goes on: tests/test_solve.py's margin-of-zero case)."""
    kind, loaded, nlp = built(edited(tmp_path, "planting_arm/redesign_from_example1.toml",
                                     [("analysis_depth = 25.0", "analysis_depth = 30.0")]))
    depth = {r.name: r for r in pinned.of_nlp(kind, loaded.model, nlp)}["planting_depth"]
    assert depth.value == pytest.approx(30.0, abs=1e-9) and not depth.violated
    assert pinned.refuse_violated(kind, loaded.model, nlp)      # pinned rules returned, nothing raised


def test_a_soil_level_frees_the_depth(tmp_path):
    """With the soil at a free level instead of the analysis convention, the depth moves with the design."""
    kind, loaded, nlp = built(edited(tmp_path, "planting_arm/redesign_from_example1.toml",
                                     [("analysis_depth = 25.0", "level = { init = -53.3, bounds = [-80, -30] }")]))
    assert "planting_depth" not in {r.name for r in pinned.of_nlp(kind, loaded.model, nlp)}


def test_a_tube_given_as_numbers_fixes_its_own_rules(tmp_path):
    """guide_tube: tube I given whole (angle 45 deg) keeps its free fall of 245 mm whatever tube II does."""
    spec = edited(tmp_path, "guide_tube/cai2020_delta2.toml", [("min_free_fall = 0 ", "min_free_fall = 300 ")])
    loaded = load_spec(spec)
    with pytest.raises(SpecError) as caught:
        run_solve(kinds.get(loaded.kind), loaded, workers=1)
    message = str(caught.value)
    assert ("free_fall_height_I = 245 mm is fixed by tube I's angle, l3, h5 and h6 in [[tubes]] (no design variable "
            "moves it); the rule asks >= 300 mm: change tube I's angle, l3, h5 and h6 in [[tubes]] or [rules] "
            "min_free_fall") in message
    assert "free_fall_height_II" not in message          # tube II's angle is free: its rule is the solver's


def test_a_fixed_design_variable_is_named_with_its_spec_path(tmp_path):
    """picker_double_crank's retrofit keeps the pivot A at x_a = 25 mm: a frame-point rule asking x_a >= 40 is that
    number's, and the message says to free it."""
    loaded = load_spec(edited(tmp_path, "picker/picker_double_crank_retrofit.toml",
                              [("x_a_min = 0.0", "x_a_min = 40.0")]))
    with pytest.raises(SpecError) as caught:
        run_solve(kinds.get(loaded.kind), loaded, workers=1)
    assert ("frame_point_x_a = 25 mm is fixed by [linkage] x_a, given as a number (no design variable moves it); "
            "the rule asks >= 40 mm: give [linkage] x_a bounds, or change the rule's limits") in str(caught.value)


def test_a_row_with_a_nonzero_target_is_read_as_expression_minus_target():
    """Four angles summing to 360 (written with its target, as clamp_cam writes its timing row), three fixed: the
    fourth is 100 wherever the row holds, so 'fourth >= 90' holds and 'fourth >= 120' is pinned and violated at 100."""
    x = ca.SX.sym("x", 4)
    rules = [Rule("fourth_min_90", x[3], 90.0, None, "deg", 1.0), Rule("fourth_min_120", x[3], 120.0, None, "deg", 1.0)]
    problem = Problem("angles", x, np.array([100.0, 80.0, 80.0, 0.0]), np.array([100.0, 80.0, 80.0, 300.0]),
                      [(ca.sum1(x), 360.0, 360.0)], rules, ObjectiveParts(f=x[3] ** 2))
    found = {r.name: r for r in pinned.pinned_rules(problem)}
    assert found["fourth_min_90"].value == pytest.approx(100.0, abs=1e-9) and not found["fourth_min_90"].violated
    assert found["fourth_min_120"].value == pytest.approx(100.0, abs=1e-9) and found["fourth_min_120"].violated


def test_a_rule_with_a_branch_that_moves_elsewhere_in_the_bounds_is_not_pinned():
    """b - a = 0 and the rule fmax(b, 5) >= 8: below b = 5 its Jacobian is 0 (explained by no row), above it b moves it;
    the rule's value differs between the points drawn, so it is left to the solve (b in [8, 9] meets it)."""
    x = ca.SX.sym("x", 2)
    rules = [Rule("branch", ca.fmax(x[1], 5.0), 8.0, None, "mm", 1.0)]
    problem = Problem("branch", x, np.zeros(2), np.full(2, 9.0), [(x[1] - x[0], 0.0, 0.0)], rules,
                      ObjectiveParts(f=x[0] ** 2))
    assert pinned.pinned_rules(problem) == []


def test_a_clamp_cam_with_a_free_dwell_is_solved_not_refused(tmp_path):
    """opening_cam_redesign with its far dwell free: the timing row (rise + far dwell + return + near dwell = 360)
    has a target of 360; the hold rules it fixes are met, so no rule is refused before the starts."""
    path = edited(tmp_path, "clamp_cam/opening_cam_redesign.toml", [])
    text = path.read_text()
    import re
    text, n = re.subn(r"far_dwell = [0-9.]+", "far_dwell = {init = 160, bounds = [100, 200]}", text, count=1)
    if n == 0:
        pytest.skip("the library spec gives no plain far_dwell number to free")
    path.write_text(text)
    kind, loaded, nlp = built(path)
    violated = [r for r in pinned.pinned_rules(nlp.compiled.problem) if r.violated]
    assert violated == []

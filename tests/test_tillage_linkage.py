"""tillage_linkage (seed 002 §四.2, eq 3-11): the printed relations against the constructed geometry and
against CasADi's AD, the baseline's rules, the redesign re-checked independently on a much finer grid,
bad input.

Tolerances: identities hold to round-off, so 1e-9 (relative to the bar length c where they are
lengths) is 10^6 times the round-off seen and far below any modelling choice; pinned figures of our
own runs carry 1e-6 relative (IPOPT at tight tolerances, deterministic starts).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import LIBRARY
from solving import agrisynth, modules_after_runs, run_solve, spec_with, strict_json
from synthesis.kinds.tillage_linkage.kinematics import bar_angle, joints, path_function, tool_point
from synthesis.spec import load_spec
from synthesis.kinds.tillage_linkage import printed as pr
from synthesis.kinds.tillage_linkage.check import evaluate, motion, printed_relations, run_check

TILLAGE = LIBRARY / "tillage"
BASELINE = TILLAGE / "hwang_tillage_baseline.toml"
REDESIGN = TILLAGE / "tillage_redesign.toml"
DEG = math.pi / 180.0
#: geometries (a, b, c, theta deg) the identities are checked on: the baseline, the redesign, others
GEOMETRIES = [(120.0, 250.0, 500.0, 20.0), (107.68670621538232, 215.37341568749238, 373.06012290551644, 28.67),
              (60.0, 300.0, 700.0, 45.0), (140.0, 160.0, 400.0, -10.0), (30.0, 400.0, 450.0, 80.0)]
OMEGA = np.linspace(0.0, 2 * math.pi, 721)[:-1]


# --- eq 3-8: the geometry as we derive it, against the printed relations ----------------------------------

@pytest.mark.parametrize("a, b, c, theta_deg", GEOMETRIES)
def test_printed_eq3_to_eq8_against_the_constructed_linkage(a, b, c, theta_deg):
    th = theta_deg * DEG
    for w in OMEGA:
        j = joints(w, a, b, c, th)
        (ax, ay), (bx, by), (dx, dy) = j["A"], j["B"], j["D"]
        # the construction itself: |AB| = a, |AC| = b, |BD| = c, D on the line B C beyond C
        assert math.hypot(bx - ax, by - ay) == pytest.approx(a, rel=1e-12)
        assert math.hypot(ax, ay) == pytest.approx(b, rel=1e-12)
        assert math.hypot(dx - bx, dy - by) == pytest.approx(c, rel=1e-12)
        assert abs(bx * dy - by * dx) / (c * c) < 1e-12 and bx * dx + by * dy < 0.0
        phi = math.atan2(ax * by - ay * bx, ax * bx + ay * by)            # angle ACB, + with B above AC
        assert math.tan(phi) == pytest.approx(pr.eq3_tan(w, a, b, th), rel=1e-9, abs=1e-12)
        assert pr.eq3_tan_expanded(w, a, b, th) == pytest.approx(pr.eq3_tan(w, a, b, th), rel=1e-9, abs=1e-12)
        assert pr.eq3_denominator_squared(w, a, b, th) == pytest.approx(bx * bx + by * by, rel=1e-12)
        assert pr.eq3_sin(w, a, b, th) == pytest.approx(math.sin(phi), abs=1e-12)
        assert pr.eq4_cos(w, a, b, th) == pytest.approx(math.cos(phi), abs=1e-12)
        assert float(bar_angle(w, a, b, th)) == pytest.approx(phi, abs=1e-12)
        for x in (pr.eq5_first_line(w, a, b, c, th), pr.eq5(w, a, b, c, th), pr.eq7(w, a, b, c, th)[0]):
            assert abs(x - dx) / c < 1e-12
        for y in (pr.eq6_first_line(w, a, b, c, th), pr.eq6(w, a, b, c, th), pr.eq7(w, a, b, c, th)[1]):
            assert abs(y - dy) / c < 1e-12
        x, y = (float(v) for v in tool_point(w, a, b, c, th))
        assert math.hypot(x - dx, y - dy) / c < 1e-12
        assert abs(pr.eq8(w, a, b, c, th)) / (c * c) < 1e-12


def test_eq8_expanded_as_printed_does_not_hold_and_equals_2UV_1_minus_W():
    """The printed expansion (a sin w + b sin th) x + (a cos w + b cos th) y = 0 has '+' where eq 8's own
    first form V x - U y = 0 has '-': it is 2 U V (1 - W), zero only where CB is horizontal or vertical."""
    a, b, c, theta_deg = GEOMETRIES[0]
    th = theta_deg * DEG
    worst = 0.0
    for w in OMEGA:
        u, v = a * math.cos(w) + b * math.cos(th), a * math.sin(w) + b * math.sin(th)
        big_w = c / math.hypot(u, v)
        value = pr.eq8_expanded_as_printed(w, a, b, c, th)
        assert value == pytest.approx(2 * u * v * (1 - big_w), rel=1e-9, abs=1e-9)
        worst = max(worst, abs(value) / (c * c))
    assert worst == pytest.approx(0.248976, abs=1e-6)        # mm^2 / c^2: not round-off
    # it vanishes where U V = 0, e.g. where B is level with C (V = a sin w + b sin th = 0)
    w0 = -math.asin(b * math.sin(th) / a)
    assert abs(a * math.sin(w0) + b * math.sin(th)) < 1e-12
    assert abs(pr.eq8_expanded_as_printed(w0, a, b, c, th)) / (c * c) < 1e-12


@pytest.mark.parametrize("a, b, c, theta_deg", GEOMETRIES)
def test_eq9_to_eq11_by_ad_equal_the_hand_derived_derivatives(a, b, c, theta_deg):
    th = theta_deg * DEG
    f = path_function()
    out = [np.asarray(v, float).ravel() for v in f.map(OMEGA.size)(OMEGA.reshape(1, -1), [a, b, c, th])]
    _, _, dx, dy, ddx, ddy = out
    for k, w in enumerate(OMEGA):
        x1, y1, x2, y2 = pr.derivatives(w, a, b, c, th)
        assert abs(dx[k] - x1) / c < 1e-9 and abs(dy[k] - y1) / c < 1e-9
        assert abs(ddx[k] - x2) / c < 1e-9 and abs(ddy[k] - y2) / c < 1e-9
        assert abs(pr.eq9(x1, y1) - math.hypot(dx[k], dy[k])) / c < 1e-9                  # eq 9
        assert abs(math.remainder(pr.eq10(x1, y1) - math.atan2(dy[k], dx[k]), 2 * math.pi)) < 1e-9   # eq 10
        assert abs(pr.eq11(x2, y2) - math.hypot(ddx[k], ddy[k])) / c < 1e-9                 # eq 11


def test_the_result_carries_every_printed_relation_and_only_eq8_expanded_fails():
    design = load_spec(BASELINE).model.design_values()
    rel = printed_relations(design)
    failing = [k for k, ok in rel["holds_to_1e-9"].items() if not ok]
    assert failing == ["eq8 expanded as printed ('+')"]
    assert len(rel["max_residual"]) == 17


def test_a_crank_a_hair_shorter_than_b_is_checked_not_crashed(tmp_path):
    """An independent trial: a = 249.9999999, b = 250 (the a >= b refusal is exact) crashed `check` with a
    ZeroDivisionError in eq 3's sin(phi): at omega = theta + 180 deg the crank pin B lies 1e-7 mm from the rollers C
    and a^2 + b^2 - 2ab rounds to 0.  The printed relations skip that crank angle and say so; the rules are
    evaluated on the constructed geometry, which divides by |CB| = 1e-7 and not by the rounded square."""
    design = {**load_spec(BASELINE).model.design_values(), "a": 249.9999999, "b": 250.0}
    rel = printed_relations(design)
    theta = design["theta"]
    assert rel["not_evaluated_at_crank_deg"] == [pytest.approx(theta + 180.0)]
    assert len(rel["max_residual"]) == 17
    text = BASELINE.read_text()
    assert "\na = 120.0" in text
    path = tmp_path / "hair.toml"
    path.write_text(text.replace("\na = 120.0", "\na = 249.9999999", 1))
    proc = agrisynth("check", str(path), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr
    data = strict_json(tmp_path / f"{load_spec(path).model.name}-check" / "result.json")
    assert data["facts"]["printed_relations"]["not_evaluated_at_crank_deg"] == [pytest.approx(theta + 180.0)]


def test_the_tool_tip_runs_clockwise_and_moves_backwards_at_the_bottom():
    a, b, c, theta_deg = GEOMETRIES[0]
    x, y = (np.asarray(v, float).ravel() for v in tool_point(OMEGA, a, b, c, theta_deg * DEG))
    signed_area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    assert signed_area < 0.0                                    # clockwise
    k = int(np.argmin(y))
    assert x[(k + 1) % x.size] < x[k - 1]                       # at the bottom D moves towards -x


# --- the baseline -----------------------------------------------------------------------------------------

def test_baseline_rules_and_closed_form_values():
    spec = load_spec(BASELINE).model
    result = run_check(load_spec(BASELINE))
    rules = {r["name"]: r for r in result.rules}
    assert result.all_satisfied
    assert rules["bar_slot_angle"]["value"] == pytest.approx(math.degrees(math.asin(120 / 250)), abs=1e-12)
    assert rules["bar_engagement"]["value"] == 130.0
    assert rules["working_depth"]["value"] == pytest.approx(103.58818, abs=1e-4)
    assert rules["lift_height"]["value"] == pytest.approx(173.35846, abs=1e-4)
    assert rules["rearward_in_soil"]["value"] == pytest.approx(-0.0897854, abs=1e-6)
    # the extremes are root-found: a dense grid of eq 7 alone (printed.py) never goes beyond them
    d = spec.design_values()
    dense = np.array([pr.eq7(w, d["a"], d["b"], d["c"], d["theta"] * DEG)[1]
                      for w in np.linspace(0, 2 * math.pi, 200001)])
    low, top = result.extra["lowest_point"]["y_mm"], result.extra["highest_point"]["y_mm"]
    assert dense.min() >= low - 1e-9 and dense.min() - low < 1e-6
    assert dense.max() <= top + 1e-9 and top - dense.max() < 1e-6
    assert result.trajectory["frame"] == "ground"


# --- the redesign -----------------------------------------------------------------------------------------

def independent_recheck(spec, design: dict, turn_points: int = 360001) -> dict:
    """The rules of ``design`` from eq 7 and the hand-derived derivatives alone (no AD, no root-finding): the
    in-soil samples are every point of a dense grid below the ground."""
    a, b, c, th = design["a"], design["b"], design["c"], design["theta"] * DEG
    w = np.linspace(0.0, 2 * math.pi, turn_points)
    y = np.array([pr.eq7(x, a, b, c, th)[1] for x in w])
    ground = -design["height_c"]
    soil = y < ground
    rate = spec.operation.crank_speed * 2 * math.pi / 60.0
    vx = np.array([rate * pr.derivatives(x, a, b, c, th)[0] / 1000.0 for x in w[soil]]) + spec.operation.forward_speed
    return {"depth": ground - y.min(), "lift": y.max() - ground, "vx_max": vx.max(),
            "slot": math.degrees(math.asin(a / b)), "engagement": c - a - b}


@pytest.mark.slow
def test_redesign_meets_every_rule_on_an_independent_finer_grid():
    loaded = load_spec(REDESIGN)
    result, reports, _ = run_solve(loaded, workers=1)
    assert result.status == "optimal"
    assert result.objective["value"] == pytest.approx(373.06012, rel=1e-6)
    assert result.fine_grid_worst_violation == 0.0
    d, req = result.design, loaded.model.requirements
    # the active rules of the shortest bar: engagement, slot angle, depth, rearward speed; C on its bound
    assert d["c"] - d["a"] - d["b"] == pytest.approx(50.0, abs=1e-5)
    assert d["a"] / d["b"] == pytest.approx(0.5, abs=1e-8)
    assert d["height_c"] == pytest.approx(100.0, abs=1e-6)
    ind = independent_recheck(loaded.model, d, 360001)         # 500x the solver's 72 crank angles per turn
    assert req.depth[0] <= ind["depth"] <= req.depth[1] and ind["depth"] == pytest.approx(90.0, abs=1e-5)
    assert ind["lift"] >= req.lift
    assert ind["vx_max"] <= -req.min_rearward_speed
    assert ind["slot"] <= req.max_slot_angle + 1e-9 and ind["engagement"] >= req.min_engagement - 1e-6
    # much shorter than the plausible baseline's 500 mm bar
    assert d["c"] < 0.75 * 500.0


@pytest.mark.slow
def test_max_margin_reaches_the_depth_band_s_half_width(tmp_path):
    """max_margin: the smallest normalised margin cannot exceed the depth band's half-width over its scale,
    (120 - 90) / 2 / 10 = 1.5; the solve reaches that bound with the depth at 105 mm."""
    text = REDESIGN.read_text().replace('name = "min_bar_length"', 'name = "max_margin"')
    spec = tmp_path / "max_margin.toml"
    spec.write_text(text)
    result, _, _ = run_solve(load_spec(spec), workers=1)
    assert result.status == "optimal"
    assert result.objective["value"] == pytest.approx(1.5, abs=1e-6)
    depth = next(r for r in result.rules if r["name"] == "working_depth")
    assert depth["value"] == pytest.approx(105.0, abs=1e-4)


# --- CLI: bad input, isolation -----------------------------------------------------------------------------



@pytest.mark.slow
def test_check_cli_writes_result_trajectory_and_figure(tmp_path):
    proc = agrisynth("check", str(BASELINE), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    folder = tmp_path / "out" / "hwang_tillage_baseline-check"
    data = strict_json(folder / "result.json")
    assert set(data["trajectory"]) >= {"t", "crank_deg", "x", "y", "vx", "vy", "ax", "ay", "frame"}
    assert (folder / "tillage.png").stat().st_size > 10_000


def test_a_bar_that_leaves_the_roller_pair_is_a_rule_failure(tmp_path):
    """c = 300 < a + b = 370: at omega = theta the bar's end has passed the rollers (D between B and C)."""
    path = spec_with(tmp_path, BASELINE, [("c = 500.0 ", "c = 300.0 ")])
    proc = agrisynth("check", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    data = strict_json(tmp_path / "out" / "hwang_tillage_baseline-check" / "result.json")
    rule = next(r for r in data["rules"] if r["name"] == "bar_engagement")
    assert rule["value"] == -70.0 and not rule["satisfied"]


def test_a_tool_that_never_reaches_the_soil_names_why(tmp_path):
    path = spec_with(tmp_path, BASELINE, [("height_c = 130.0 ", "height_c = 400.0 ")])
    proc = agrisynth("check", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    data = strict_json(tmp_path / "out" / "hwang_tillage_baseline-check" / "result.json")
    rules = {r["name"]: r for r in data["rules"]}
    assert rules["rearward_in_soil"]["value"] is None
    assert "never enters the soil" in rules["rearward_in_soil"]["note"]
    assert rules["working_depth"]["value"] == pytest.approx(-166.41182, abs=1e-4)


@pytest.mark.parametrize("old, new, message", [
    ("a = 120.0 ", "a = 260.0 ",
     "tillage_linkage.linkage: a = 260 mm >= b = 250 mm (largest a, smallest b): the crank circle reaches the "
     "roller C, where |CB| = 0 and D cannot be placed (W = c / |CB| of eq 7 is undefined)"),
    ("a = 120.0 ", "a = 250.0 ", "D cannot be placed"),
    ("theta = 20.0 ", "theta = 95.0 ", "tillage_linkage.linkage: theta: expected -30 <= theta <= 89 deg, got 95"),
    ("c = 500.0 ", "c = -1.0 ", "tillage_linkage.linkage: c: expected > 0, got -1"),
    ("depth = [90.0, 120.0]", "depth = [120.0, 90.0]",
     "tillage_linkage.requirements: depth: expected 0 < lo <= hi, got [120, 90]"),
    ("crank_speed = 60.0 ", "crank_speed = 0.0 ", "tillage_linkage.operation.crank_speed: expected > 0, got 0"),
    ("height_c = 130.0", "heigth_c = 130.0", "tillage_linkage.linkage.heigth_c: unknown field; did you mean 'height_c'?"),
])
def test_bad_input_exits_2_naming_the_field(tmp_path, old, new, message):
    path = spec_with(tmp_path, BASELINE, [(old, new)])
    for command in ("check", "solve"):
        proc = agrisynth(command, str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
        assert proc.returncode == 2, proc.stdout + proc.stderr
        assert message in " ".join(proc.stderr.split()), proc.stderr
        assert "Traceback" not in proc.stderr


def test_free_bounds_that_let_the_crank_reach_the_rollers_are_bad_input(tmp_path):
    path = spec_with(tmp_path, REDESIGN, [("a = { init = 120.0, bounds = [40.0, 150.0] }",
                                            "a = { init = 120.0, bounds = [40.0, 170.0] }")])
    proc = agrisynth("solve", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2 and "a = 170 mm >= b = 160 mm" in " ".join(proc.stderr.split()), proc.stderr


FORBIDDEN = ("synthesis.kinds.steering_linkage", "synthesis.kinds.steering_linkage.kinematics", "synthesis.kinds.steering_linkage.rules",
             "synthesis.kinds.planting", "synthesis.kinds.picker", "synthesis.kinds.fourbar_path", "synthesis.kinds.crank_rocker",
             "synthesis.kinds.clamp_cam", "synthesis.kinds.guide_tube", "synthesis.kinds.planting.kinematics",
             "synthesis.kinematics.fourbar", "synthesis.kinematics.rocker_drive", "synthesis.kinds.combing_chain",
             "synthesis.kinds.comb_finger", "synthesis.kinds.guide_way", "cvxpy")    # ezdxf: the run writes linkage.dxf


@pytest.mark.slow
def test_a_tillage_run_imports_no_other_kind(tmp_path):
    out = str(tmp_path / "out")
    modules = modules_after_runs(tmp_path, [["check", str(BASELINE), "--out", out],
                                            ["solve", str(REDESIGN), "--workers", "1", "--starts", "2", "--out", out]])
    assert "synthesis.kinds.tillage_linkage.solve" in modules
    assert [m for m in modules if m.startswith(FORBIDDEN)] == []
    assert [m for m in modules if m.startswith("synthesis.constraints.")] == ["synthesis.constraints.base"]
    assert "synthesis.kinds.tillage_linkage.rules" in modules
    assert (tmp_path / "out" / "tillage_redesign" / "result.json").exists()


def test_motion_windows_bracket_the_lowest_point():
    spec = load_spec(BASELINE).model
    m = motion(spec, spec.design_values(), 720, 240)
    (w0, w1), = m.windows
    assert w0 < m.omega_low < w1
    rules, _ = evaluate(spec, spec.design_values(), 720, 240)
    assert [r.name for r in rules] == ["working_depth", "lift_height", "rearward_in_soil", "bar_slot_angle",
                                       "bar_engagement"]

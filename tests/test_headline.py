"""Each kind's headline (Kind.headline): the figures an engineer looks at first, read from result.json alone, each
checked against the same figure recomputed from the result (its coordinates, its curves, its rule table)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from conftest import LIBRARY
from synthesis import kinds
from synthesis.core.kind import figure_text
from synthesis.kinds.fourbar_path.kinematics import BRANCHES, coupler_function, design_parameters
from synthesis.result import Result
from synthesis.spec import load_spec

#: a library spec of every kind whose check is quick, the kind's figures read off its result
CHECKED = {
    "clamp_cam": "clamp_cam/opening_cam.toml",
    "comb_finger": "comb_finger/peanut_baseline.toml",
    "combing_chain": "combing_chain/kubota_hc500.toml",
    "crank_rocker": "picker/cai2020_crank_rocker.toml",
    "fourbar_path": "fourbar_path/picking_arc.toml",
    "guide_tube": "guide_tube/cai2020_tubes.toml",
    "guide_way": "guide_way/liang_2z.toml",
    "picker": "picker/cai2020_picker.toml",
    "picker_double_crank": "picker/cai2020_double_crank.toml",
    "planting_fourbar": "planting_arm/taiwan_example1.toml",
    "steering_linkage": "steering/hwang_model3_steering.toml",
    "tillage_linkage": "tillage/hwang_tillage_baseline.toml",
}


@pytest.fixture(scope="module")
def checked() -> dict[str, Result]:
    return {kind: kinds.get(kind).check(load_spec(LIBRARY / spec)) for kind, spec in CHECKED.items()}


def test_every_kind_of_the_problem_library_has_a_headline(checked):
    assert len(CHECKED) == 12 and set(CHECKED) <= set(kinds.names())
    for kind, result in checked.items():
        lines = kinds.get(kind).headline(result)
        assert lines and all(isinstance(line, str) and line for line in lines), kind
        # every figure named is measured: a "-" stands for a figure the result lacks
        assert not any(" - " in f" {line} " or line.endswith(" -") for line in lines), (kind, lines)


def _fourbar_errors(result: Result) -> np.ndarray:
    """Each target's distance to the coupler point at its crank angle, from the result's design and targets."""
    point = coupler_function(BRANCHES[result.extra["branch"]])
    p = design_parameters(result.design)
    at = [np.array(point(math.radians(a), p)[0]).ravel() for a in result.design["crank_deg"]]
    return np.array([np.hypot(*(q - np.array(t))) for q, t in zip(at, result.extra["targets"])])


def test_fourbar_path_headline_is_its_path_error_recomputed_from_the_coordinates(checked):
    result = checked["fourbar_path"]
    errors = _fourbar_errors(result)
    rms, worst = float(np.sqrt(np.mean(errors ** 2))), int(np.argmax(errors))
    assert result.extra["path_error"]["rms_mm"] == pytest.approx(rms, rel=1e-9)
    assert errors[worst] == pytest.approx(238.2025, abs=1e-3) and worst == 2          # target 3
    lines = kinds.get("fourbar_path").headline(result)
    assert lines[0] == (f"path error over 10 targets: rms {rms:.3g} mm, max {errors[worst]:.3g} mm at target "
                        f"{worst + 1}") == "path error over 10 targets: rms 234 mm, max 238 mm at target 3"
    assert len(lines) == 1 + 10
    assert lines[1] == f"target 1 (376, 123.7) mm: error {errors[0]:.3g} mm"
    (table,) = kinds.get("fourbar_path").result_tables(result)
    assert table.columns == ("target", "x, mm", "y, mm", "error, mm")
    assert [row[0] for row in table.rows] == list(range(1, 11))
    assert np.allclose([row[3] for row in table.rows], errors, rtol=1e-9)


def test_fourbar_path_headline_of_many_targets_is_its_summary_and_of_an_open_loop_says_where(checked):
    result = checked["fourbar_path"]
    many = dataclasses.replace(result, extra={**result.extra, "targets": [[float(i), 0.0] for i in range(13)],
                                              "target_errors_mm": [1.0] * 12 + [2.0],
                                              "path_error": {"rms_mm": 1.08, "max_mm": 2.0}})
    assert kinds.get("fourbar_path").headline(many) == [
        "path error over 13 targets: rms 1.08 mm, max 2 mm at target 13"]
    open_loop = dataclasses.replace(result, extra={**result.extra, "target_errors_mm": [1.0, None] + [1.0] * 8,
                                                   "path_error": {"rms_mm": None, "max_mm": None}})
    lines = kinds.get("fourbar_path").headline(open_loop)
    assert lines[0] == "path error: the loop does not close at target(s) 2"
    assert lines[2] == "target 2 (363.3, 145.1) mm: error -"


def test_planting_headline_is_its_rule_table_with_the_misses(checked):
    result = checked["planting_fourbar"]
    rules = {r["name"]: r for r in result.rules}
    lines = kinds.get("planting_fourbar").headline(result)
    assert lines[0] == (f"entry angle {rules['entry_angle']['value']:.3g} deg, planting depth 25 mm, hole P4-P6 "
                        f"{rules['p4p6_distance']['value']:.3g} mm") == \
        "entry angle 79.3 deg, planting depth 25 mm, hole P4-P6 28.6 mm"
    # seed 000's example 1: P1, P2, P3 not on a line by 13.4 deg, 8.44 past its 5 deg; the entry angle 0.736 deg short
    missed = {n: -r["margin"] for n, r in rules.items() if not r["satisfied"]}
    assert lines[-1] == (f"P1-P6 misses: p1p2p3_collinearity by {missed['p1p2p3_collinearity']:.3g} deg; entry_angle "
                         f"by {missed['entry_angle']:.3g} deg") == \
        "P1-P6 misses: p1p2p3_collinearity by 8.44 deg; entry_angle by 0.736 deg"
    # a point rule that could not be evaluated (P1 not found: no value, no margin) is a miss too, never "holds"
    unevaluated = [{**r, "value": None, "margin": None, "satisfied": False} if r["name"] == "p1p3_distance" else r
                   for r in result.rules]
    lines = kinds.get("planting_fourbar").headline(dataclasses.replace(result, rules=unevaluated))
    assert lines[-1] == ("P1-P6 misses: p1p3_distance not evaluated; p1p2p3_collinearity by 8.44 deg; entry_angle by "
                         "0.736 deg")


def test_crank_rocker_headline_is_its_stroke_time_ratio_and_transmission_angle(checked):
    result = checked["crank_rocker"]
    rules = {r["name"]: r["value"] for r in result.rules}
    curve = result.extra["motion"]["curve"]
    # the smallest transmission angle over the facts' curve (1 deg steps) is the rule's (root-found) minimum
    assert min(curve["transmission_deg"]) == pytest.approx(rules["min_transmission_angle"], abs=1e-6)
    line = kinds.get("crank_rocker").headline(result)[0]
    assert line == (f"rocker stroke {rules['rocker_swing']:.4g} deg, time ratio {rules['time_ratio']:.4g}, transmission "
                    f"angle min {rules['min_transmission_angle']:.4g} deg at crank 0 deg")
    assert line.startswith("rocker stroke 49.95 deg, time ratio 1.25, transmission angle min 40.01 deg")


def test_steering_headline_is_the_largest_ackermann_error_of_its_curve(checked):
    result = checked["steering_linkage"]
    curve = result.extra["curve"]
    error = np.abs(np.array(curve["error_deg"]))
    worst = int(np.argmax(error))
    lines = kinds.get("steering_linkage").headline(result)
    assert lines[0] == (f"Ackermann error max {error[worst]:.3g} deg at inside {curve['inside_deg'][worst]:.3g} deg"
                        ) == "Ackermann error max 0.744 deg at inside 26.5 deg"


def test_guide_tube_headline_is_each_tubes_landing_time_and_their_spread(checked):
    result = checked["guide_tube"]
    times = {t["name"]: t["t_z"] for t in result.extra["tubes"]}
    spread = max(times.values()) - min(times.values())
    lines = kinds.get("guide_tube").headline(result)
    assert lines[0] == "landing times: I 0.445 s (delta 45 deg), II 0.4237 s (delta 41 deg)"
    assert lines[1].startswith(f"spread {1000 * spread:.3g} ms") and lines[1].startswith("spread 21.3 ms")


def test_figure_text_says_a_missing_figure_as_a_dash():
    assert figure_text(1.5871, "mm") == "1.59 mm" and figure_text(2.0) == "2"
    assert figure_text(None, "mm") == "-" and figure_text(float("nan"), "deg") == "-" and figure_text(True) == "-"

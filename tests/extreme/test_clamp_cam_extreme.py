"""Degenerate and stiff clamp cams: very short returns (undercut), huge rollers, zero dwells, an
oscillating follower, a clockwise cam, the smallest B-spline, a solve where the undercut binds."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from cam_reference import sampled_roller_envelope, translating_pitch
from synthesis.kinds.clamp_cam.check import cam_facts, profile, run_check
from synthesis.kinds.clamp_cam.scene import CamScene, evaluate
from solving import run_solve
from synthesis.spec import LoadedSpec, load_spec

CAMS = Path(__file__).resolve().parents[2] / "problems" / "clamp_cam"
OPENING = (CAMS / "opening_cam.toml").read_text()


def spec_text(tmp_path: Path, text: str, *edits: tuple[str, str]) -> LoadedSpec:
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return load_spec(path)


def opening_with_return(tmp_path: Path, ret: float) -> LoadedSpec:
    return spec_text(tmp_path, OPENING, ("return = 14.0", f"return = {ret!r}"),
                     ("near_dwell = 146.0", f"near_dwell = {160.0 - ret!r}"),
                     ("hold_near = [[0.0, 146.0]]", f"hold_near = [[0.0, {160.0 - ret!r}]]"))


def test_the_published_return_is_1_7_deg_from_undercut(tmp_path, record_property):
    """Shortest cycloidal return of 10 mm on the 50 mm / 3.5 mm cam before the roller envelope cusps
    (threshold 12.301 deg within 1e-3 deg; working-radius margin at the published 14 deg within 1e-5 mm)."""
    def margin(ret):
        return cam_facts(CamScene.from_spec(opening_with_return(tmp_path, ret).model))["min_working_radius_mm"]
    threshold = brentq(margin, 6.0, 14.0, xtol=1e-9)
    assert threshold == pytest.approx(12.301, abs=1e-3)
    assert margin(14.0) == pytest.approx(0.77187, abs=1e-5)
    record_property("figure", f"undercut threshold: return {threshold:.3f} deg; the published 14 deg keeps "
                              f"{margin(14.0):.4f} mm of working radius")


@pytest.mark.parametrize("ret", [8.0, 3.0, 1.0])
def test_very_short_return_undercuts_and_the_cutter_envelope_departs(tmp_path, ret, record_property):
    """A return shorter than the 12.3 deg undercut threshold: check reports no_undercut violated, every
    pressure angle finite, and the cam a cutter leaves departs from the looping analytic envelope by
    more than 0.05 mm (sampled roller envelope, 36000 angles)."""
    loaded = opening_with_return(tmp_path, ret)
    result = run_check(loaded)
    rule = {r["name"]: r for r in result.rules}["no_undercut"]
    assert not rule["satisfied"] and "undercut" in rule["where"]
    assert result.extra["cam"]["undercut"] is True
    assert result.extra["cam"]["segments"]["return"]["max_pressure_angle_deg"] > 65.0
    assert np.all(np.isfinite(result.extra["follower"]["pressure_angle_deg"]))
    # the analytic inner envelope loops (swallowtail); the cam a cutter leaves is smaller there
    w = np.column_stack([result.extra["profile"]["working"]["x"], result.extra["profile"]["working"]["y"]])
    phi = np.linspace(0.0, 2 * np.pi, 36000, endpoint=False)
    scene = CamScene.from_spec(loaded.model)
    centres = translating_pitch(scene.motion.at(146.0 + np.degrees(phi)).s, phi, 50.0)
    cut = sampled_roller_envelope(centres, 3.5, np.arctan2(w[:, 1], w[:, 0]))
    departs = np.max(np.hypot(w[:, 0], w[:, 1]) - cut)
    assert departs > 0.05
    record_property("figure", f"return {ret:g} deg: undercut reported, min working radius "
                              f"{result.extra['cam']['min_working_radius_mm']:.3f} mm, max return pressure angle "
                              f"{result.extra['cam']['segments']['return']['max_pressure_angle_deg']:.1f} deg, "
                              f"cutter envelope {departs:.3f} mm inside the analytic one")


def test_roller_almost_as_big_as_the_base_circle(tmp_path, record_property):
    """A 49.9 mm roller on the rotating cam (50 mm base circle): check reports no_undercut violated with the
    working radius pitch radius - roller within 1e-4 mm, no NaN."""
    loaded = spec_text(tmp_path, (CAMS / "rotating_cam.toml").read_text(), ("roller_radius = 3.5", "roller_radius = 49.9"))
    result = run_check(loaded)
    names = [r["name"] for r in result.violated()]
    assert "no_undercut" in names                     # 26.5 mm pitch radius < 49.9 mm roller
    assert result.extra["cam"]["min_working_radius_mm"] == pytest.approx(26.51296 - 49.9, abs=1e-4)
    record_property("figure", f"roller 49.9 mm: no_undercut violated, min working radius "
                              f"{result.extra['cam']['min_working_radius_mm']:.4f} mm (= 26.513 - 49.9)")


def test_zero_dwells_rise_straight_into_return(tmp_path, record_property):
    """No far dwell: the rise runs straight into the return; the follower still reaches the 25 mm stroke
    (1e-6 mm) and comes back to 0 (1e-12 mm), the near hold is met."""
    loaded = spec_text(tmp_path, (CAMS / "rotating_cam.toml").read_text(),
                       ("far_dwell = 160.0", "far_dwell = 0.0"), ("near_dwell = 80.0", "near_dwell = 240.0"),
                       ("hold_far = [[140.0, 300.0]]", "hold_far = []"),
                       ("hold_near = [[0.0, 80.0]]", "hold_near = [[200.0, 440.0]]"))
    result = run_check(loaded)
    f = result.extra["follower"]
    assert max(f["s"]) == pytest.approx(25.0, abs=1e-6) and min(f["s"]) == pytest.approx(0.0, abs=1e-12)
    assert {r["name"]: r["satisfied"] for r in result.rules}["timing_hold_near[0]"] is True
    record_property("figure", f"far dwell 0: stroke {max(f['s']):.6f} mm, lowest {min(f['s']):.1e} mm, every pressure "
                              f"angle finite: {bool(np.all(np.isfinite(f['pressure_angle_deg'])))}")


OSCILLATING = """
kind = "clamp_cam"
name = "oscillating"
[cam]
base_radius = 40.0
roller_radius = 5.0
[follower]
type = "oscillating"
pivot_distance = 100.0
arm_length = 75.0
side = -1
[motion]
law = "modified_sine"
stroke = 18.0
rise_start = 0.0
rise = 80.0
far_dwell = 60.0
return = 70.0
near_dwell = 150.0
[operation]
crank_speed = 60.0
"""


def test_oscillating_follower_profile_is_the_sampled_roller_envelope(tmp_path):
    loaded = spec_text(tmp_path, OSCILLATING)
    scene = CamScene.from_spec(loaded.model)
    prof = profile(scene)
    w = np.column_stack([prof["working"]["x"], prof["working"]["y"]])
    phi = np.linspace(0.0, 2 * np.pi, 36000, endpoint=False)
    psi = scene.motion.at(np.degrees(phi)).s
    psi0 = math.acos((100.0**2 + 75.0**2 - 40.0**2) / (2 * 100.0 * 75.0))
    gx, gy = 100.0 - 75.0 * np.cos(psi0 + psi), -75.0 * np.sin(psi0 + psi)
    centres = np.column_stack([np.cos(phi) * gx + np.sin(phi) * gy, -np.sin(phi) * gx + np.cos(phi) * gy])
    cut = sampled_roller_envelope(centres, 5.0, np.arctan2(w[:, 1], w[:, 0]))
    assert np.max(np.abs(np.hypot(w[:, 0], w[:, 1]) - cut)) < 1e-3
    facts = cam_facts(scene)
    assert facts["stroke_unit"] == "deg"
    # peak arm acceleration, deg/s^2: C_a (modified sine) h omega^2 / beta^2
    expected = 5.527957 * 18.0 * (2 * math.pi) ** 2 / math.radians(80.0) ** 2
    assert facts["segments"]["rise"]["peak_acceleration"] == pytest.approx(expected, rel=1e-5)


def test_oscillating_follower_smallest_cam(tmp_path):
    loaded = spec_text(tmp_path, OSCILLATING, ("base_radius = 40.0", "base_radius = { init = 40.0, bounds = [15, 80] }"),
                       ("pivot_distance = 100.0", "pivot_distance = { init = 100.0, bounds = [60, 140] }"))
    result, _, _ = run_solve(loaded, starts=2, workers=1)
    assert result.status == "optimal"
    rules, _ = evaluate(CamScene.from_spec(loaded.model, result.design), 5000)
    assert [r.name for r in rules if not r.record().satisfied] == []
    assert result.design["base_radius"] < 40.0


def test_clockwise_cam_is_the_mirror_image(tmp_path):
    ccw = CamScene.from_spec(load_spec(CAMS / "opening_cam.toml").model)
    cw = CamScene.from_spec(spec_text(tmp_path, OPENING, ("roller_radius = 3.5", 'roller_radius = 3.5\nrotation = "clockwise"')).model)
    a, b = profile(ccw)["working"], profile(cw)["working"]
    assert a["x"] == b["x"] and a["y"] == pytest.approx([-y for y in b["y"]], abs=1e-12)


def test_rotation_is_spelled_with_an_underscore_and_result_json_keeps_its_name(tmp_path):
    """Names are written with underscores in every kind; the hyphenated spelling is refused
    naming the new one, and result.json's facts.profile.rotation is spelled as before (schema 2)."""
    from synthesis.errors import SpecError

    with pytest.raises(SpecError) as err:
        spec_text(tmp_path, OPENING, ("roller_radius = 3.5", 'roller_radius = 3.5\nrotation = "counter-clockwise"'))
    assert str(err.value).endswith('clamp_cam.cam.rotation: "counter-clockwise" is no longer read; write rotation = '
                                   '"counter_clockwise"')
    ccw = CamScene.from_spec(spec_text(tmp_path, OPENING, ("roller_radius = 3.5",
                                                           'roller_radius = 3.5\nrotation = "counter_clockwise"')).model)
    assert profile(ccw)["rotation"] == "counter-clockwise"
    assert profile(ccw)["working"] == profile(CamScene.from_spec(load_spec(CAMS / "opening_cam.toml").model))["working"]


def test_smallest_bspline_is_still_c2(tmp_path):
    loaded = spec_text(tmp_path, (CAMS / "opening_cam_optimised_law.toml").read_text(),
                       ("spans = 32", "spans = 4"), ("degree = 5", "degree = 3"))
    scene = CamScene.from_spec(loaded.model)
    for spl in (scene.optimised.rise, scene.optimised.return_):
        assert [spl.s(0.0), spl.v(0.0), spl.a(0.0)] == [0.0, 0.0, 0.0]
        assert [spl.v(1.0), spl.a(1.0)] == pytest.approx([0.0, 0.0], abs=1e-12)
    # with 4 spans of a cubic the law is nearly all ramps: worse than the cycloid's peak
    assert scene.optimised.ratio_to_cycloidal["rise"] > 1.0


def test_solve_where_the_undercut_binds(tmp_path, record_property):
    """A textbook working-radius floor (3 mm) with the pressure-angle limits relaxed: the smallest cam
    is set by the curvature of the 14 deg return."""
    loaded = spec_text(tmp_path, OPENING, ("base_radius = 50.0", "base_radius = { init = 50.0, bounds = [10, 150] }"),
                       ("[operation]", "[rules]\npressure_angle_rise = 89.0\npressure_angle_return = 89.0\n"
                                       "min_working_radius = 3.0\n\n[operation]"))
    result, _, _ = run_solve(loaded, starts=1, workers=1)
    assert result.status == "optimal"
    rule = {r["name"]: r for r in result.rules}["no_undercut"]
    assert rule["satisfied"] and rule["value"] == pytest.approx(3.0, rel=0.03)      # working radius, active up to the backoff
    rules, _ = evaluate(CamScene.from_spec(loaded.model, result.design), 5000)
    assert [r.name for r in rules if not r.record().satisfied] == []
    assert json.dumps(result.to_json(), allow_nan=False)
    record_property("figure", f"base radius {result.design['base_radius']:.3f} mm, working radius "
                              f"{rule['value']:.4f} mm against the 3 mm floor (within 3 %)")

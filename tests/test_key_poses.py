"""Key poses of the planting arm ([key_poses], rules from synthesis/constraints/poses.py, shared with rotary_planetary).

* The claw attitude on floats (synthesis.kinds.planting.kinematics.claw_attitudes) is the direction of C - A from the
  joint positions the figures draw the linkage with, computed here with numpy's arctan2.
* The pose rows the NLP holds (at a precision point, at a free pose's own crank angle, at a prescribed one) have AD
  derivatives equal to central differences, and at the check's crank angles the values of the check's rules.
* The check of the published example 1 reports the claw's attitude at P1-P6, and a pose asking an attitude off by
  more than its tolerance is a violated rule (by that much); within it, a satisfied one.
* The library redesign (key_pose_redesign_from_example1) meets every pose on the fine grid, re-checked apart from the
  solver, and its attitudes read from the joint positions at the re-found points are within the tolerances.
* A pose that cannot mean anything (an unknown point, an attitude out of range, ...) is refused: exit 2 naming the
  field.
"""

from __future__ import annotations

import json
import math

import casadi as ca
import numpy as np
import pytest

from conftest import LIBRARY
from solving import agrisynth, recheck_rules, spec_with
from synthesis import kinds
from synthesis.kinds import solve_spec
from synthesis.kinds.planting.check import evaluate
from synthesis.kinds.planting.kinematics import claw_attitudes, joint_positions
from synthesis.kinds.planting.nlp import PlantingProblem
from synthesis.kinds.planting.scene import PlantingScene, find_precision_points, locate_poses
from synthesis.result import result_text
from synthesis.spec import load_spec

EXAMPLE1 = LIBRARY / "planting_arm" / "taiwan_example1.toml"
REDESIGN = LIBRARY / "planting_arm" / "key_pose_redesign_from_example1.toml"
#: example 1's claw attitude at soil entry P4, deg (GEOMETRY.md, "Claw attitude and key poses")
EXAMPLE1_P4_ATTITUDE = -156.91


def wrapped(deg):
    """Angles (deg) wrapped into (-180, 180]."""
    return -((-np.asarray(deg, float) + 180.0) % 360.0 - 180.0)


def independent_attitude(design, theta) -> np.ndarray:
    """The direction of C - A (deg) from the joint positions, with numpy."""
    joints = joint_positions(design, theta)
    return np.degrees(np.arctan2(joints["C"][1] - joints["A"][1], joints["C"][0] - joints["A"][0]))


def checked(path) -> dict:
    loaded = load_spec(path)
    return json.loads(result_text(kinds.get(loaded.kind).check(loaded)))


@pytest.mark.parametrize("example", [1, 2, 3, 4])
def test_the_attitude_on_floats_is_the_direction_of_c_minus_a(example):
    spec = load_spec(LIBRARY / "planting_arm" / f"taiwan_example{example}.toml").model
    design = PlantingScene.from_spec(spec).design
    theta = np.linspace(0.0, 2.0 * math.pi, 360, endpoint=False)
    ours = np.degrees(claw_attitudes(design, theta))
    assert np.all(np.abs(ours) <= 180.0)
    assert np.abs(wrapped(ours - independent_attitude(design, theta))).max() < 1e-9
    # it turns with the coupler: phi rotates it clockwise by as much at every crank angle
    turned = PlantingScene.from_spec(spec, {**spec.design_values(), "phi": spec.design_values()["phi"] + 10.0}).design
    assert np.abs(wrapped(np.degrees(claw_attitudes(turned, theta)) - ours + 10.0)).max() < 1e-9


def poses_spec(tmp_path):
    """The library redesign with, besides its poses at P4 and P3, a free pose (tip and attitude) near example 1's
    path and a pose at a prescribed crank angle."""
    extra = ("\n[key_poses.carrying]\nx = -150.0\ny = 60.0\ntolerance = 2.0\nattitude = 160.0\n"
             "\n[key_poses.at_100]\ncrank_angle = 100.0\nx = -160.0\ny = 70.0\nattitude = 170.0\n")
    path = tmp_path / "poses.toml"
    path.write_text(REDESIGN.read_text() + extra)
    return load_spec(path).model


def test_pose_rows_ad_derivatives_equal_central_differences_and_the_checks_values(tmp_path):
    spec = poses_spec(tmp_path)
    problem = PlantingProblem(spec)
    pose_rules = [r for r in problem.problem.rules if r.name.startswith("pose_")]
    assert [r.name for r in pose_rules] == ["pose_soil_entry_attitude", "pose_seedling_pick_attitude",
                                            "pose_carrying", "pose_carrying_attitude", "pose_at_100",
                                            "pose_at_100_attitude"]
    rows = ca.vertcat(*[row[0] for r in pose_rules for row in r.rows()])
    x = problem.problem.x
    f = ca.Function("pose_rows", [x], [rows, ca.jacobian(rows, x)])
    # at the given design and the check's crank angles: P1-P6 root-found, the free pose where the tip comes nearest
    scene = PlantingScene.from_spec(spec)
    pts = locate_poses(scene, find_precision_points(scene))
    n = len(problem.names)
    x0 = np.concatenate([problem.init, problem.theta_guess(spec.design_values())])
    x0[n:n + 6] = [pts.theta[p] for p in ("P1", "P2", "P3", "P4", "P5", "P6")]
    x0[n + problem.pose_offset] = pts.poses["carrying"]
    values, jac = (np.asarray(v) for v in f(x0))
    # the rows' values are the check's rules' (the tip rule's row is its squared distance)
    check = {r.name: r.record().value for r in evaluate(scene, spec.rules)[0] if r.name.startswith("pose_")}
    expected = [check["pose_soil_entry_attitude"], check["pose_seedling_pick_attitude"], check["pose_carrying"] ** 2,
                check["pose_carrying_attitude"], check["pose_at_100"] ** 2, check["pose_at_100_attitude"]]
    np.testing.assert_allclose(values.ravel(), expected, rtol=1e-9, atol=1e-9)
    h = 1e-5
    for i in range(x.numel()):
        step = np.zeros(x.numel())
        step[i] = h
        central = (np.asarray(f(x0 + step)[0]) - np.asarray(f(x0 - step)[0])) / (2 * h)
        np.testing.assert_allclose(jac[:, i:i + 1], central, rtol=1e-5, atol=1e-6 * max(1.0, np.abs(jac).max()))
    # every pose row moves with the design and with its own crank angle alone: P4's moves the entry attitude, the
    # free pose's the carrying attitude but not its squared distance, stationary where the tip is nearest its target
    assert np.abs(jac[:, :n]).max(axis=1).min() > 1e-3
    assert abs(jac[0, n + 3]) > 1e-3 and abs(jac[3, n + problem.pose_offset]) > 1e-3
    assert abs(jac[2, n + problem.pose_offset]) < 1e-9 * np.abs(jac[2, :n]).max()
    assert jac[2, n + 3] == 0.0 and jac[0, n + problem.pose_offset] == 0.0 and np.all(jac[4:, n:] == 0.0)


def test_check_of_example1_reports_the_attitudes_and_a_pose_missed_by_more_than_its_tolerance(tmp_path):
    plain = checked(EXAMPLE1)
    assert "key_poses" not in plain["facts"] and not any(r["name"].startswith("pose_") for r in plain["rules"])
    spec = load_spec(EXAMPLE1).model
    design = PlantingScene.from_spec(spec).design
    for off, held in ((2.5, False), (1.5, True)):
        path = spec_with(tmp_path, EXAMPLE1, [("[soil]", f"[key_poses.entry]\nat = \"P4\"\nattitude = "
                                                        f"{EXAMPLE1_P4_ATTITUDE + off}\nattitude_tolerance = 2.0\n\n"
                                                        f"[soil]")], name=f"off_{off}.toml")
        data = checked(path)
        facts = data["facts"]["key_poses"]
        points = data["facts"]["precision_points"]
        theta = np.radians([points[p]["crank_deg"] for p in ("P1", "P2", "P3", "P4", "P5", "P6")])
        reported = [facts["claw_attitude_at_points_deg"][p] for p in ("P1", "P2", "P3", "P4", "P5", "P6")]
        assert np.abs(wrapped(np.subtract(reported, independent_attitude(design, theta)))).max() < 1e-9
        assert facts["claw_attitude_at_points_deg"]["P4"] == pytest.approx(EXAMPLE1_P4_ATTITUDE, abs=0.01)
        rule = {r["name"]: r for r in data["rules"]}["pose_entry_attitude"]
        assert rule["limit"] == [-2.0, 2.0] and rule["unit"] == "deg" and rule["where"] == "key pose entry, at P4"
        assert rule["satisfied"] is held
        assert rule["value"] == pytest.approx(facts["claw_attitude_at_points_deg"]["P4"] - EXAMPLE1_P4_ATTITUDE - off,
                                              abs=1e-12)
        assert facts["poses"]["entry"]["attitude_miss_deg"] == pytest.approx(rule["value"], abs=1e-12)
        # the other rules are example 1's, in its order, the pose's last
        assert [r["name"] for r in data["rules"]] == [r["name"] for r in plain["rules"]] + ["pose_entry_attitude"]
        assert [r["value"] for r in data["rules"][:-1]] == [r["value"] for r in plain["rules"]]


def test_the_attitude_miss_wraps_across_the_backward_direction(tmp_path):
    """Example 1's claw arm points backwards (about 180 deg) at P2: a target of -179 deg is 1.4 deg away, not 359."""
    path = spec_with(tmp_path, EXAMPLE1, [("[soil]", "[key_poses.pick]\nat = \"P2\"\nattitude = -179.0\n\n[soil]")])
    data = checked(path)
    at_p2 = data["facts"]["key_poses"]["claw_attitude_at_points_deg"]["P2"]
    rule = {r["name"]: r for r in data["rules"]}["pose_pick_attitude"]
    assert 179.0 < at_p2 < 180.0
    assert rule["value"] == pytest.approx(at_p2 - 181.0, abs=1e-12) and rule["satisfied"]


def test_the_headline_names_each_poses_miss(tmp_path):
    path = spec_with(tmp_path, EXAMPLE1, [("[soil]", "[key_poses.entry]\nat = \"P4\"\nattitude = -150.0\n\n"
                                                     "[key_poses.near]\nx = -200.0\ny = -60.0\ntolerance = 50.0\n\n"
                                                     "[soil]")])
    loaded = load_spec(path)
    kind = kinds.get("planting_fourbar")
    result = kind.check(loaded)
    rules = {r["name"]: r for r in result.rules}
    lines = kind.headline(result)
    assert lines[-2] == (f"pose entry at P4: attitude {-150.0 + rules['pose_entry_attitude']['value']:.1f} deg, "
                         f"{rules['pose_entry_attitude']['value']:+.2f} deg from -150 (within 2) -- MISSED "
                         f"(pose_entry_attitude)")
    assert lines[-1].startswith(f"pose near: tip {rules['pose_near']['value']:.2f} mm from (-200, -60) (within 50)")
    assert "MISSED" not in lines[-1]
    table, = kind.result_tables(result)
    assert [row[0] for row in table.rows] == ["entry", "near"]
    assert not kind.result_tables(kind.check(load_spec(EXAMPLE1)))


@pytest.mark.slow         # about 3 s: the library solve (16 starts)
def test_the_solved_redesign_meets_every_pose_on_the_fine_grid():
    loaded = load_spec(REDESIGN)
    spec = loaded.model
    result, _, _ = solve_spec(loaded, workers=1)
    assert result.status == "optimal"
    design = {k: v for k, v in result.design.items() if k != "branch"}
    # the kind's fine-grid re-check of the returned design, apart from the solver: every rule holds, the poses too
    rules = {r.name: r.record() for r in recheck_rules(spec, design)}
    assert all(r.satisfied for r in rules.values()), [r for r in rules.values() if not r.satisfied]
    assert {"pose_soil_entry_attitude", "pose_seedling_pick_attitude"} <= set(rules)
    # the attitudes read from the joint positions at the precision points found anew
    scene = PlantingScene.from_spec(spec, design)
    pts = find_precision_points(scene)
    for name, pose in spec.key_poses.items():
        attitude = independent_attitude(scene.design, [pts.theta[pose.at]])[0]
        assert abs(wrapped(attitude - pose.attitude)) <= pose.attitude_tolerance
        assert rules[f"pose_{name}_attitude"].value == pytest.approx(wrapped(attitude - pose.attitude), abs=1e-9)
    # the plain redesign trails at entry (-166.8 deg): the poses moved the design
    assert independent_attitude(scene.design, [pts.theta["P4"]])[0] > -165.0 - 1e-6


@pytest.mark.slow         # about 3 s: four starts
def test_a_free_pose_is_solved_at_its_own_crank_angle(tmp_path):
    """The library redesign with a free pose (tip and attitude) its answer passes near on the way up (the tip
    at (-140.44, 70.61) mm, the claw at 157.6 deg at crank angle 100 deg): solved with the pose held on the fine
    grid, the solver's crank angle of the pose where the check finds the tip nearest its target."""
    path = tmp_path / "free.toml"
    path.write_text(REDESIGN.read_text() + "\n[key_poses.carrying]\nx = -140.0\ny = 70.0\nattitude = 158.0\n")
    loaded = load_spec(path)
    spec = loaded.model.model_copy(update={"solver": loaded.model.solver.model_copy(update={"starts": 4})})
    result, _, _ = solve_spec(type(loaded)(**{**loaded.__dict__, "model": spec}), workers=1)
    assert result.status == "optimal"
    data = json.loads(result_text(result))
    rules = {r["name"]: r for r in data["rules"]}
    assert all(r["satisfied"] for r in rules.values())
    assert rules["pose_carrying"]["value"] <= 1.0 and abs(rules["pose_carrying_attitude"]["value"]) <= 2.0
    pose = data["facts"]["key_poses"]["poses"]["carrying"]
    solver = data["facts"]["solver_crank_deg"]["key pose carrying"]
    assert wrapped(solver - pose["crank_deg"]) == pytest.approx(0.0, abs=1e-3)


@pytest.mark.parametrize("pose, field", [
    ('at = "P7"\nattitude = -100.0', "key_poses.entry.at"),
    ('at = "P4"\nattitude = 200.0', "key_poses.entry.attitude"),
    ('at = "P4"\nattitude = -100.0\nattitude_tolerance = 0.0', "key_poses.entry.attitude_tolerance"),
    ('at = "P4"', "key_poses.entry"),
    ('attitude = -100.0', "key_poses.entry"),
    ('at = "P4"\ncrank_angle = 30.0\nattitude = -100.0', "crank_angle"),
    ('x = -200.0\nattitude = -100.0', "key_poses.entry"),
])
def test_a_bad_pose_is_refused_naming_the_field(tmp_path, pose, field):
    path = spec_with(tmp_path, EXAMPLE1, [("[soil]", f"[key_poses.entry]\n{pose}\n\n[soil]")])
    proc = agrisynth("check", path, "--out", tmp_path / "out")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert field in proc.stderr and "Traceback" not in proc.stderr


def test_a_pose_name_that_would_clash_is_refused(tmp_path):
    path = spec_with(tmp_path, EXAMPLE1, [("[soil]", "[key_poses.entry_attitude]\nat = \"P4\"\nattitude = -100.0\n\n"
                                                     "[soil]")])
    proc = agrisynth("check", path, "--out", tmp_path / "out")
    assert proc.returncode == 2 and "may not end in _attitude" in proc.stderr

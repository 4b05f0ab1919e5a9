"""result.json schema 2: the kind's facts under "facts", one run tail for every kind; version-1
files (facts and tail flattened at the top level) are still read, and compare shows them."""

from __future__ import annotations

import json

from synthesis.result import SCHEMA_VERSION, Result, load_result
from solving import agrisynth

V1 = {
    "kind": "crank_rocker", "name": "old_run", "spec_sha256": "0" * 64, "status": "optimal",
    "design": {"l7": 54.04, "l8": 107.63, "l9": 133.47, "l10": 140.0},
    "rules": [{"name": "grashof_crank_rocker", "value": 45.2, "limit": [0.0, None], "unit": "mm", "satisfied": True,
               "margin": 45.2}],
    "objective": {"name": "min_total_length", "value": 435.134, "unit": "mm"},
    "solver": {"name": "ipopt", "return_status": "Solve_Succeeded", "iterations": 8, "wall_s": 0.4, "starts": 8,
               "seed": 0, "best_start": 0},
    "versions": {"agrisynth": "0.1.0", "casadi": "3.6", "python": "3.11"},
    # version 1: the kind's facts and the run tail side by side at the top level
    "source": "seed 001", "motion": {"crank_turns": True}, "closed_form": None,
    "starts": [{"start": 0, "return_status": "Solve_Succeeded", "objective": 435.134}],
    "elastic": None, "baseline_design": {"l7": 50.0}, "fine_grid_worst_violation": 0.0,
}


def test_a_version_1_file_is_read_into_the_version_2_shape(tmp_path):
    path = tmp_path / "result.json"
    path.write_text(json.dumps(V1))
    r = load_result(path)
    assert r.extra == {"source": "seed 001", "motion": {"crank_turns": True}, "closed_form": None}
    assert r.starts == V1["starts"] and r.elastic is None and r.baseline_design == {"l7": 50.0}
    assert r.fine_grid_worst_violation == 0.0
    again = r.to_json()
    assert again["schema_version"] == SCHEMA_VERSION == 5
    assert again["facts"] == r.extra and "motion" not in again
    assert Result.from_json(json.loads(json.dumps(again))) == r


def test_compare_reads_a_version_1_file_beside_a_version_2_one(tmp_path):

    from conftest import ROOT

    old = tmp_path / "old"
    old.mkdir()
    (old / "result.json").write_text(json.dumps(V1))
    new = Result.from_json({**{k: v for k, v in V1.items() if k in ("kind", "spec_sha256", "status", "design", "rules",
                                                                    "objective", "solver", "versions")},
                            "name": "new_run", "schema_version": 2, "facts": {"source": "seed 001"}, "starts": [],
                            "elastic": None, "baseline_design": {}, "fine_grid_worst_violation": 0.0})
    (tmp_path / "new").mkdir()
    (tmp_path / "new" / "result.json").write_text(json.dumps(new.to_json()))
    proc = agrisynth("compare", str(old), str(tmp_path / "new"), "--out", str(tmp_path / "cmp"), cwd=ROOT, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    page = (tmp_path / "cmp" / "compare.html").read_text()
    assert "old_run" in page and "new_run" in page


def test_a_version_2_fourbar_path_file_keeps_its_branch_as_a_fact(tmp_path):
    """Version 2 wrote fourbar_path's assembly name in the design too; version 3 keeps only numbers there (design
    values in mm / deg).  A version-2 file is read with the name moved to facts.branch, so its figures draw the
    assembly it was solved on, and written back as the current version."""
    crossed = {"kind": "fourbar_path", "name": "old_path", "spec_sha256": "0" * 64, "status": "evaluated",
               "schema_version": 2, "rules": [], "facts": {"source": "test"},
               "design": {"r1": 60.0, "r2": 20.0, "r3": 70.0, "r4": 50.0, "rcx": 10.0, "rcy": 5.0, "x0": 0.0,
                          "y0": 0.0, "theta0": 0.0, "crank_deg": [0.0, 90.0, 180.0], "branch": "crossed"}}
    path = tmp_path / "result.json"
    path.write_text(json.dumps(crossed))
    r = load_result(path)
    assert "branch" not in r.design and r.extra["branch"] == "crossed" and r.design["crank_deg"] == [0.0, 90.0, 180.0]
    again = r.to_json()
    assert again["schema_version"] == 5 and again["facts"]["branch"] == "crossed" and "branch" not in again["design"]
    # a version-2 file whose facts already hold the branch keeps the facts' value
    both = {**crossed, "facts": {"branch": "open"}}
    assert Result.from_json(both).extra["branch"] == "open" and "branch" not in Result.from_json(both).design
    # a version-3 file is read as it is
    assert Result.from_json({**crossed, "schema_version": 3}).design["branch"] == "crossed"

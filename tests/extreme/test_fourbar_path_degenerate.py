"""fourbar_path on degenerate inputs: a change-point linkage, collinear targets, repeated targets."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fourbar_path_support import cli, write_spec
from synthesis.fourbar_path.synthetic import truth_data


def test_change_point_linkage_is_diagnosed_not_crashed(tmp_path):
    """r1 = r2 fixed: the only crank-rockers are change-point linkages (r3 = r4), where O'A shrinks to
    zero at theta2 = 0 and the transmission angle to 0 deg, so [30, 150] cannot hold: exit 3 naming it."""
    data = truth_data(0, 6, timed=False, solver={"starts": 8})
    data["linkage"].update(r1=30.0, r2=30.0)
    proc = cli("solve", str(write_spec(tmp_path, data)), "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "transmission_angle_min" in proc.stderr and "Traceback" not in proc.stderr


def test_collinear_targets_are_approximated_within_the_rules(tmp_path):
    """Seven points on a 60 mm straight line: a four-bar coupler curve is algebraic of degree 6, so it
    meets a line in at most 6 points (Bezout) and no coupler curve passes all 7; the fit obeys every rule."""
    data = truth_data(0, 7, timed=False, solver={"starts": 16})
    data["targets"]["points"] = [[10.0 * i, 5.0] for i in range(7)]
    proc = cli("solve", str(write_spec(tmp_path, data)), "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = json.loads((tmp_path / data["name"] / "result.json").read_text())
    assert all(r["satisfied"] for r in out["rules"])
    assert out["objective"]["value"] > 1e-12
    assert out["facts"]["path_error"]["max_mm"] < 1.0                               # a usable straight-line mechanism


def test_repeated_targets_share_one_crank_angle(tmp_path):
    data = truth_data(0, 6, timed=False, solver={"starts": 8})
    pts = data["targets"]["points"]
    pts[1] = pts[2] = pts[0]
    proc = cli("solve", str(write_spec(tmp_path, data)), "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = json.loads((tmp_path / data["name"] / "result.json").read_text())
    crank = out["design"]["crank_deg"]
    assert np.ptp(crank[:3]) < 1e-3 and out["objective"]["value"] < 1e-8


def test_check_of_a_linkage_that_never_closes_reports_it_without_nan(tmp_path):
    """r3 = 500 mm against links of about 30 mm: the loop closes at no crank angle, so there is no
    coupler curve and no crank angle to give the targets.  check exits 1 with every such rule failed
    and says why; result.json holds no NaN (crank angles not found are null)."""
    data = truth_data(0, 6, timed=False)
    data["linkage"]["r3"] = 500.0
    proc = cli("check", str(write_spec(tmp_path, data)), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    out = json.loads((tmp_path / data["name"] / "result.json").read_text(),
                     parse_constant=lambda c: pytest.fail(f"result.json holds {c}"))
    rules = {r["name"]: r for r in out["rules"]}
    assert rules["assembly"]["value"] < -400 and not rules["assembly"]["satisfied"]
    assert not rules["grashof"]["satisfied"]                  # r3 is far longer than the other three together
    assert rules["sequence"]["value"] is None and "closes at no crank angle" in rules["sequence"]["note"]
    assert out["design"]["crank_deg"] == [None] * 6

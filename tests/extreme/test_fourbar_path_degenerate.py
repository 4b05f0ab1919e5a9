"""fourbar_path on degenerate inputs: a change-point linkage, collinear targets, repeated (coincident)
targets, 200 targets, a linkage that never closes.  Every run is a subprocess with a timeout (a hang fails
the test; the time is not a pass/fail figure)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fourbar_path_support import cli, write_spec
from synthesis.kinds.fourbar_path.synthetic import truth_data


@pytest.mark.slow
def test_change_point_linkage_is_diagnosed_not_crashed(tmp_path, record_property):
    """r1 = r2 fixed: the only crank-rockers are change-point linkages (r3 = r4), where O'A shrinks to
    zero at theta2 = 0 and the transmission angle to 0 deg, so [30, 150] cannot hold: exit 3 naming it."""
    data = truth_data(0, 6, timed=False, solver={"starts": 8})
    data["linkage"].update(r1=30.0, r2=30.0)
    proc = cli("solve", str(write_spec(tmp_path, data)), "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "transmission_angle_min" in proc.stderr and "Traceback" not in proc.stderr
    record_property("figure", "exit 3 naming transmission_angle_min (the rule a change-point linkage cannot meet)")


@pytest.mark.slow
def test_collinear_targets_are_approximated_within_the_rules(tmp_path, record_property):
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
    record_property("figure", f"exit 0, every rule met, largest distance to a target "
                              f"{out['facts']['path_error']['max_mm']:.3f} mm (< 1 mm; exactly 0 is impossible)")


@pytest.mark.slow
def test_repeated_targets_share_one_crank_angle(tmp_path, record_property):
    """Three of six targets coincident: a valid design with one crank angle for them (spread < 1e-3 deg) and a
    zero-error fit (objective < 1e-8 mm^2)."""
    data = truth_data(0, 6, timed=False, solver={"starts": 8})
    pts = data["targets"]["points"]
    pts[1] = pts[2] = pts[0]
    proc = cli("solve", str(write_spec(tmp_path, data)), "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    out = json.loads((tmp_path / data["name"] / "result.json").read_text())
    crank = out["design"]["crank_deg"]
    assert np.ptp(crank[:3]) < 1e-3 and out["objective"]["value"] < 1e-8
    record_property("figure", f"exit 0, crank angles of the coincident targets within {np.ptp(crank[:3]):.1e} deg, "
                              f"objective {out['objective']['value']:.1e} mm^2")


def test_1001_targets_are_refused_with_the_allowed_count(tmp_path, record_property):
    """1,001 coupler points of a known crank-rocker: more than the spec allows (1,000, each adds a crank-angle
    variable and its rows); solve exits 2 at once naming the field, the count and the range."""
    data = truth_data(0, 1001, timed=False, solver={"starts": 2})
    proc = cli("solve", str(write_spec(tmp_path, data)), "--workers", "1", "--out", str(tmp_path), cwd=tmp_path,
               timeout=60)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    message = " ".join(proc.stderr.split())
    assert "targets.points" in message and "expected 3 to 1000 points, got 1001" in message
    assert "Traceback" not in proc.stderr
    record_property("figure", "exit 2: 'targets.points: expected 3 to 1000 points, got 1001'")


def test_check_of_a_linkage_that_never_closes_reports_it_without_nan(tmp_path, record_property):
    """r3 = 500 mm against links of about 30 mm: the loop closes at no crank angle, so there is no
    coupler curve and no crank angle to give the targets.  check exits 1 with every such rule failed
    and says why; result.json holds no NaN (crank angles not found are null)."""
    data = truth_data(0, 6, timed=False)
    data["linkage"]["r3"] = 500.0
    proc = cli("check", str(write_spec(tmp_path, data)), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    out = json.loads((tmp_path / f"{data['name']}-check" / "result.json").read_text(),
                     parse_constant=lambda c: pytest.fail(f"result.json holds {c}"))
    rules = {r["name"]: r for r in out["rules"]}
    assert rules["assembly"]["value"] < -400 and not rules["assembly"]["satisfied"]
    assert not rules["grashof"]["satisfied"]                  # r3 is far longer than the other three together
    assert rules["sequence"]["value"] is None and "closes at no crank angle" in rules["sequence"]["note"]
    assert out["design"]["crank_deg"] == [None] * 6
    record_property("figure", f"exit 1, assembly {rules['assembly']['value']:.1f} mm, crank angles null, no NaN")

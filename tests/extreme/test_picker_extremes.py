"""Degenerate and impossible crank-rocker requests: no quick return (K = 1), a vanishing swing, and
transmission angles no crank-rocker with the given K and swing can have."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest

from synthesis.kinds.crank_rocker.check import mechanism
from solving import agrisynth, recheck_rules, run_solve
from synthesis.kinematics.rocker_drive import acute, quick_return, transmission_angles_deg
from synthesis.core.solve import starts_table
from synthesis.core.verdict import measured, report_of
from synthesis.spec import load_spec

ROOT = Path(__file__).resolve().parents[2]
SYNTHESIS = ROOT / "problems" / "picker" / "cai2020_crank_rocker_synthesis.toml"


def spec_file(tmp_path: Path, time_ratio: str, swing: str, gamma: str, lower: str = "5.0") -> Path:
    text = SYNTHESIS.read_text()
    for old, new in (("time_ratio = 1.25", f"time_ratio = {time_ratio}"), ("rocker_swing = 50.0", f"rocker_swing = {swing}"),
                     ("min_transmission_angle = 40.0", f"min_transmission_angle = {gamma}"),
                     ("bounds = [5.0,", f"bounds = [{lower},")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "extreme.toml"
    path.write_text(text)
    return path


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return agrisynth(*args, cwd=cwd)


def simulated(loaded, design):
    cr = mechanism(loaded.model, design)
    q = quick_return(cr)
    return q, float(acute(transmission_angles_deg(cr, 3600)).min())


@pytest.mark.parametrize("time_ratio", ["1.0", "1.0001"])
def test_no_quick_return(tmp_path, time_ratio, record_property):
    """K = 1 (and 1 + 1e-4): the simulated design has K and the 50 deg swing within 1e-6, gamma_min >= 40 deg."""
    loaded = load_spec(spec_file(tmp_path, time_ratio, "50.0", "40.0"))
    result, _, _ = run_solve(loaded, starts=2, workers=1)
    assert result.status == "optimal"
    q, gmin = simulated(loaded, result.design)
    assert q.time_ratio == pytest.approx(float(time_ratio), abs=1e-6)
    assert math.degrees(q.swing) == pytest.approx(50.0, abs=1e-6)
    assert gmin >= 40.0
    if time_ratio == "1.0":   # no quick return: the two extremes lie exactly half a crank turn apart
        assert math.degrees(q.stroke_fold_to_ext) == pytest.approx(180.0, abs=1e-6)
    record_property("figure", f"K = {time_ratio}: {result.status}, simulated K {q.time_ratio:.7f}, swing "
                              f"{math.degrees(q.swing):.6f} deg, gamma_min {gmin:.3f} deg")


@pytest.mark.parametrize("swing", ["0.5", "0.05"])
def test_vanishing_swing(tmp_path, swing, record_property):
    """Swing 0.5 and 0.05 deg: the swing within 1e-6 relative, K within 1e-6, every rule re-checked."""
    loaded = load_spec(spec_file(tmp_path, "1.25", swing, "40.0", lower="0.01"))
    result, _, _ = run_solve(loaded, starts=2, workers=1)
    # a crank of a few hundredths of a mm: IPOPT may stop at its acceptable (looser) tolerances, which
    # the result must then call feasible, not optimal; the requirements are re-checked below either way
    expected = {"Solve_Succeeded": "optimal", "Solved_To_Acceptable_Level": "feasible"}
    assert result.status == expected[result.solver["return_status"]]
    q, gmin = simulated(loaded, result.design)
    assert math.degrees(q.swing) == pytest.approx(float(swing), rel=1e-6)
    assert q.time_ratio == pytest.approx(1.25, abs=1e-6)
    assert gmin >= 40.0
    assert result.design["l7"] < 0.02 * float(swing) * 140.0          # the crank shrinks with the swing
    rules = recheck_rules(loaded.model, result.design)
    assert all(r.record().satisfied for r in rules)
    record_property("figure", f"swing {swing} deg: {result.status}, crank {result.design['l7']:.4f} mm, simulated "
                              f"swing {math.degrees(q.swing):.6f} deg, K {q.time_ratio:.7f}")


def test_zero_swing_is_bad_input(tmp_path):
    proc = cli("solve", str(spec_file(tmp_path, "1.25", "0.0", "40.0")), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2
    assert "crank_rocker.requirements.rocker_swing: expected > 0, got 0.0" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_time_ratio_below_one_is_bad_input(tmp_path):
    proc = cli("check", str(spec_file(tmp_path, "0.8", "50.0", "40.0")), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2
    assert "crank_rocker.requirements.time_ratio: expected >= 1, got 0.8" in proc.stderr


@pytest.mark.parametrize("time_ratio, swing, gamma", [("1.25", "50.0", "45.0"), ("1.25", "50.0", "60.0"),
                                                      ("2.0", "120.0", "40.0")])
@pytest.mark.slow
def test_impossible_transmission_angle_exits_3_naming_the_rules(tmp_path, time_ratio, swing, gamma,
                                                              record_property):
    """No crank-rocker with this K and swing has this gamma_min: exit 3 naming the conflicting rules."""
    path = spec_file(tmp_path, time_ratio, swing, gamma)
    proc = cli("solve", str(path), "--out", str(tmp_path / "out"), "--starts", "3", "--workers", "1", cwd=tmp_path)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    err = " ".join(proc.stderr.split())
    assert "min_transmission_angle (misses its limit by" in err
    assert "time_ratio" in err and "rocker_swing" in err
    assert "IPOPT said" in err and "Traceback" not in proc.stderr
    assert (tmp_path / "out" / "cai2020_crank_rocker_synthesis" / "result.json").exists()   # written first
    record_property("figure", "exit 3: " + err[err.index("min_transmission_angle (misses"):][:90])


@pytest.mark.slow
def test_swing_near_180_deg_exits_3_with_a_result_file(tmp_path):
    """psi = 179 deg: no crank-rocker swings that far with gamma_min = 40 deg, and some starts end on designs
    the re-check cannot evaluate.  Their violation cannot be measured: result.json says null, not inf."""
    path = spec_file(tmp_path, "1.25", "179.0", "40.0")
    proc = cli("solve", str(path), "--out", str(tmp_path / "out"), "--starts", "3", "--workers", "1", cwd=tmp_path)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr and "IPOPT said" in proc.stderr
    data = json.loads((tmp_path / "out" / "cai2020_crank_rocker_synthesis" / "result.json").read_text())
    # the elastic re-solve converges (no NaN near psi = 180 deg): the transmission angle gives way
    assert data["status"] == "infeasible" and data["elastic"]["converged"]
    assert data["elastic"]["relaxed"] == ["min_transmission_angle"]
    assert "min_transmission_angle (misses its limit by" in " ".join(proc.stderr.split())
    assert not all(r["satisfied"] for r in data["rules"])
    for start in data["starts"]:
        assert start["worst_violation"] is None or start["worst_violation"] >= 0.0
        assert start["return_status"] != "Invalid_Number_Detected"


def test_a_start_that_cannot_be_evaluated_is_written_as_null():
    """The shared multistart table: an unmeasurable violation is null in JSON (allow_nan=False passes)."""
    outcome = SimpleNamespace(start=0, return_status="Invalid_Number_Detected", success=False, iterations=3,
                              wall_s=0.1, objective=math.inf, design={"l7": 1.0}, details={})

    def cannot_evaluate(outcome):
        raise ValueError("the crank does not turn")

    report = report_of(outcome, cannot_evaluate)
    assert not report.satisfied and report.worst_violation == math.inf
    row = json.loads(json.dumps(starts_table([report]), allow_nan=False))[0]
    assert row["worst_violation"] is None and row["objective"] is None
    assert measured(2.5) == 2.5


def test_a_given_design_that_is_no_crank_rocker_still_solves(tmp_path):
    """Crank 150 mm > frame 140 mm and rocker 30 mm: the given design does not assemble over a turn.  The
    float check says so (Grashof violated, the rest not evaluated); the NLP's Grashof coordinates keep
    every iterate a crank-rocker, so no start meets NaN kinematics and the published lengths come out."""
    text = spec_file(tmp_path, "1.25", "50.0", "40.0").read_text()
    text = text.replace("l7 = { init = 50.0", "l7 = { init = 150.0").replace("l9 = { init = 120.0", "l9 = { init = 30.0")
    path = tmp_path / "outside.toml"
    path.write_text(text)
    loaded = load_spec(path)
    from synthesis.kinds.crank_rocker.check import run_check
    checked = {r["name"]: r for r in run_check(loaded).rules}
    assert checked["grashof_crank_rocker"]["value"] < 0 and checked["time_ratio"]["value"] is None
    result, reports, _ = run_solve(loaded, starts=3, workers=1)
    assert [r.outcome.return_status for r in reports].count("Invalid_Number_Detected") == 0
    assert result.status == "optimal"
    for name, value in {"l7": 54.0, "l8": 107.6, "l9": 133.5}.items():
        assert result.design[name] == pytest.approx(value, abs=0.1)

"""Status of a solve where no start satisfies every rule (DESIGN.md): "infeasible" only when something
says the rules conflict, "failed" when IPOPT simply converged from no start; both exit 3 with a message
saying what IPOPT said and what to try.  One case per kind that solves through the shared rule_solve
diagnosis (crank_rocker, picker_double_crank, clamp_cam, guide_tube)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from conftest import LIBRARY, ROOT
from synthesis import kinds
from synthesis.rule_solve import ElasticDiagnosis, StartReport, status_of, unsatisfied_error
from synthesis.spec import load_spec

#: spec, text replacements, starts: feasible rule sets whose given design misses a rule, capped at one
#: IPOPT iteration, so that no start converges and no returned design meets the rules
CAPPED = {
    "crank_rocker": ("picker/cai2020_crank_rocker_synthesis.toml",
                     [("l7 = { init = 50.0", "l7 = { init = 150.0"), ("l9 = { init = 120.0", "l9 = { init = 30.0"),
                      ("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "picker_double_crank": ("picker/picker_double_crank_redesign.toml",
                            [("min_transmission_angle = 40.0", "min_transmission_angle = 80.0"),
                             ("max_iter = 1500", "max_iter = 1")], 2),
    "clamp_cam": ("clamp_cam/opening_cam_redesign.toml", [("[solver]\n", "[solver]\nmax_iter = 1\n")], 2),
    "guide_tube": ("guide_tube/cai2020_delta2.toml",
                   [("angle = { init = 41,", "angle = { init = 65,"), ("[solver]\n", "[solver]\nmax_iter = 1\n")], 3),
}


def capped_spec(tmp_path: Path, kind: str) -> tuple[Path, int]:
    source, replacements, starts = CAPPED[kind]
    text = (LIBRARY / source).read_text()
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    if "max_iter = 1\n" not in text:
        text = re.sub(r"max_iter = \d+\n", "max_iter = 1\n", text)
    path = tmp_path / Path(source).name
    path.write_text(text)
    return path, starts


@pytest.mark.parametrize("kind", sorted(CAPPED))
def test_no_start_converged_is_failed_not_infeasible(tmp_path, kind):
    path, starts = capped_spec(tmp_path, kind)
    loaded = load_spec(path)
    assert loaded.kind == kind
    solve = kinds.solver(kind)
    result, reports, _ = solve.run_solve(loaded, starts=starts, workers=1)
    assert not any(r.outcome.success for r in reports)
    assert not any(r.satisfied for r in reports)
    assert result.status == "failed"
    assert result.extra["elastic"]["relaxed"] == []
    message = str(solve.diagnose_infeasible(loaded, result, reports))
    assert message.startswith(f"IPOPT found no solution: it converged from none of the {starts} starts")
    assert re.search(r"IPOPT said: (Maximum_Iterations_Exceeded|Invalid_Number_Detected)", message)
    assert "not an infeasible rule set" in message and "[solver] max_iter" in message
    assert "Rules that conflict" not in message


def test_failed_run_exits_3_with_result_and_message(tmp_path):
    path, starts = capped_spec(tmp_path, "guide_tube")
    proc = subprocess.run([sys.executable, "-m", "synthesis.cli", "solve", str(path), "--out", str(tmp_path / "out"),
                           "--starts", str(starts), "--workers", "1"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    err = " ".join(proc.stderr.split())
    assert "IPOPT found no solution" in err and "Maximum_Iterations_Exceeded" in err
    data = json.loads((tmp_path / "out" / "cai2020_delta2" / "result.json").read_text())
    assert data["status"] == "failed" and data["elastic"]["relaxed"] == []


def _report(start: int, status: str, success: bool) -> StartReport:
    return StartReport(SimpleNamespace(start=start, return_status=status, success=success), False, 0.3)


def test_status_and_message_follow_the_elastic_verdict():
    """The three verdicts on one set of unconverged starts: the elastic re-solve relaxes a rule
    (infeasible), converges without slack (failed: the rules are compatible), or does not converge (failed)."""
    reports = [_report(0, "Maximum_Iterations_Exceeded", False), _report(1, "Invalid_Number_Detected", False),
               _report(2, "Maximum_Iterations_Exceeded", False)]
    units, scales = {"gap": "mm", "angle": "deg"}, {"gap": 1.0, "angle": 10.0}
    conflict = ElasticDiagnosis("Solve_Succeeded", True, {"gap": 2.5, "angle": 1e-9}, units, scales, ["angle"])
    compatible = ElasticDiagnosis("Solve_Succeeded", True, {"gap": 1e-9, "angle": 1e-8}, units, scales)
    stuck = ElasticDiagnosis("Restoration_Failed", False, {"gap": 7.0, "angle": 0.0}, units, scales)
    assert status_of(reports[0], reports, conflict) == "infeasible"
    assert status_of(reports[0], reports, compatible) == "failed"
    assert status_of(reports[0], reports, stuck) == "failed"
    converged_once = reports[:2] + [_report(2, "Solve_Succeeded", True)]     # a converged design between samples
    assert status_of(reports[0], converged_once, compatible) == "infeasible"

    def message(elastic, status, reps=reports):
        result = SimpleNamespace(status=status, rules=[{"name": "gap", "satisfied": False}])
        return str(unsatisfied_error(result, reps, elastic, samples_hint="[solver] samples"))

    m = message(conflict, "infeasible")
    assert "Rules that conflict" in m and "gap (misses its limit by 2.5 mm)" in m
    assert "they conflict with angle (binding there)" in m
    assert "IPOPT said: Maximum_Iterations_Exceeded x2, Invalid_Number_Detected" in m
    m = message(compatible, "failed")
    assert m.startswith("IPOPT found no solution") and "an elastic re-solve needs no slack" in m
    assert "not an infeasible rule set" in m and "Violated at the best start: gap" in m
    m = message(stuck, "failed")
    assert "did not converge either (Restoration_Failed)" in m and "Rules that conflict" not in m
    m = message(compatible, "infeasible", converged_once)
    assert "Violated between samples: gap" in m and "Raise [solver] samples" in m

"""`agrisynth solve` for planting_fourbar: redesigns hold every rule, determinism, AD gradients,
infeasible rule sets and bad options."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from conftest import PLANTING
from synthesis.planting.check import evaluate
from synthesis.planting.nlp import PlantingNLP
from synthesis.planting.scene import PlantingScene
from synthesis.planting.solve import run_solve
from synthesis.spec import load_spec


@pytest.mark.parametrize("example", [1, 2, 3, 4])
def test_redesign_satisfies_every_rule_when_rechecked_independently(example):
    loaded = load_spec(PLANTING / f"redesign_from_example{example}.toml")
    result, reports, _ = run_solve(loaded, workers=1)
    assert result.status == "optimal"
    # re-evaluate the returned design from scratch: root-found points, the check's own fine grids
    design = {k: v for k, v in result.design.items() if k != "branch"}
    rules, _ = evaluate(PlantingScene.from_spec(loaded.model, design), loaded.model.rules)
    failed = [(r.name, r.record().value) for r in rules if not r.record().satisfied]
    assert failed == []
    # and the published design it started from did not satisfy them all
    base_rules, _ = evaluate(PlantingScene.from_spec(loaded.model), loaded.model.rules)
    assert not all(r.record().satisfied for r in base_rules)


def test_same_spec_and_seed_give_the_same_design():
    loaded = load_spec(PLANTING / "redesign_from_example1.toml")
    a, _, _ = run_solve(loaded, starts=4, seed=3, workers=1)
    b, _, _ = run_solve(loaded, starts=4, seed=3, workers=2)
    assert a.solver["best_start"] == b.solver["best_start"]
    for k, v in a.design.items():
        assert b.design[k] == pytest.approx(v, abs=1e-8)


def test_constraint_jacobian_matches_central_differences():
    spec = load_spec(PLANTING / "redesign_from_example1.toml").model
    nlp = PlantingNLP(spec)
    x = np.concatenate([nlp.init, nlp.theta_guess(dict(zip(nlp.names, nlp.init))), np.zeros(nlp.n_extra)])
    jac = ca.Function("J", [nlp.decision], [ca.jacobian(nlp.g, nlp.decision)])
    J = np.asarray(jac(x))
    g = lambda z: np.asarray(nlp.g_function(z)).ravel()  # noqa: E731
    fd = np.zeros_like(J)
    for j in range(x.size):
        h = 1e-6 * max(1.0, abs(x[j]))
        e = np.zeros_like(x)
        e[j] = h
        fd[:, j] = (g(x + e) - g(x - e)) / (2 * h)
    scale = np.maximum(np.abs(J), 1.0)
    # transmission-angle rows use fabs (non-smooth only at 0 and 180 deg, far from here)
    assert np.max(np.abs(J - fd) / scale) < 1e-6


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "synthesis.cli", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300)


def test_infeasible_rule_set_exits_3_naming_the_conflict(tmp_path):
    proc = cli("solve", str(PLANTING / "infeasible_deep_planting.toml"), "--out", str(tmp_path), "--workers", "1",
               cwd=tmp_path)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "Rules that conflict" in proc.stderr and "planting_depth" in proc.stderr
    data = json.loads((tmp_path / "infeasible_deep_planting" / "result.json").read_text())
    assert data["status"] == "infeasible"          # the run's result is kept, not lost


def test_no_start_converging_is_a_failed_run_not_a_conflict(tmp_path):
    text = (PLANTING / "redesign_from_example1.toml").read_text()
    assert "max_iter" not in text
    spec = tmp_path / "spec.toml"
    spec.write_text(text.replace("[solver]", "[solver]\nmax_iter = 2"))
    proc = cli("solve", str(spec), "--starts", "2", "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    assert "IPOPT converged from none of the 2 starts" in proc.stderr and "Maximum_Iterations_Exceeded" in proc.stderr
    assert "Rules that conflict" not in proc.stderr
    assert "a larger [solver] max_iter" in proc.stderr       # brackets in messages are text, not markup
    data = json.loads((tmp_path / "redesign_from_example1" / "result.json").read_text())
    assert data["status"] == "failed"


def test_solve_cli_writes_the_contract(tmp_path):
    proc = cli("solve", str(PLANTING / "redesign_from_example4.toml"), "--starts", "2", "--seed", "0",
               "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    data = json.loads((tmp_path / "redesign_from_example4" / "result.json").read_text())
    assert set(data["solver"]) >= {"name", "return_status", "iterations", "wall_s", "starts", "seed", "best_start"}
    assert data["objective"]["name"] == "nearest" and data["solver"]["starts"] == 2
    assert "EXIT: Optimal Solution Found" in (tmp_path / "redesign_from_example4" / "ipopt.log").read_text()
    assert "<a href='ipopt.log'>ipopt.log</a>" in (tmp_path / "redesign_from_example4" / "report.html").read_text()
    assert "baseline" in proc.stdout and "solution" in proc.stdout


BASE = (PLANTING / "redesign_from_example1.toml").read_text()


@pytest.mark.parametrize("old, new, message", [
    ("l2 = { init = 35, bounds = [28, 42] }", "l2 = { init = 35, bounds = [42, 28] }",
     "planting_fourbar.arm.l2: bounds [42, 28] have lo > hi"),
    ("l2 = { init = 35, bounds = [28, 42] }", "l2 = { init = 50, bounds = [28, 42] }",
     "planting_fourbar.arm.l2: init 50 lies outside its bounds [28, 42]"),
    ('name = "nearest"', 'name = "fastest"', "planting_fourbar.objective.name: expected 'nearest', 'robust' or 'smooth'"),
])
def test_bad_solve_specs(tmp_path, old, new, message):
    assert old in BASE
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace(old, new))
    proc = cli("solve", str(path), cwd=tmp_path)
    assert proc.returncode == 2
    assert message in proc.stderr.replace("\n", " ")


@pytest.mark.parametrize("option, value", [("--starts", "0"), ("--seed", "-1")])
def test_bad_solve_options(tmp_path, option, value):
    proc = cli("solve", str(PLANTING / "redesign_from_example1.toml"), option, value, cwd=tmp_path)
    assert proc.returncode == 2
    assert option in proc.stderr


def _with_objective(name: str):
    loaded = load_spec(PLANTING / "redesign_from_example4.toml")
    spec = loaded.model.model_copy(update={"objective": loaded.model.objective.model_copy(update={"name": name})})
    return type(loaded)(spec, loaded.path, loaded.sha256)


def _peak_acc(result) -> float:
    tr = result.trajectory
    return max(float(np.hypot(ax, ay)) for ax, ay in zip(tr["ax"], tr["ay"]))


def test_robust_objective_is_the_smallest_normalised_margin():
    result, _, _ = run_solve(_with_objective("robust"), starts=2, seed=0, workers=1)
    assert result.status == "optimal" and result.objective["value"] > 0.1
    smallest = min(r["normalised_margin"] for r in result.rules)
    # the NLP's margin is measured at its samples and after the backoff: the fine grid can only
    # differ by what lies between samples, a few hundredths here
    assert smallest == pytest.approx(result.objective["value"] + 0.02, abs=0.05)


def test_smooth_objective_lowers_the_peak_acceleration():
    smooth, _, _ = run_solve(_with_objective("smooth"), starts=2, seed=0, workers=1)
    nearest, _, _ = run_solve(_with_objective("nearest"), starts=2, seed=0, workers=1)
    assert smooth.status == "optimal"
    assert smooth.objective["value"] == pytest.approx(_peak_acc(smooth), rel=0.02)
    assert _peak_acc(smooth) < 0.95 * _peak_acc(nearest)

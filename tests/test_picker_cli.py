"""The picker kinds through the CLI: baselines check, exit codes, bad input naming the field, and the
rule that a run imports no other mechanism's modules."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import LIBRARY, ROOT
from solving import agrisynth

PICKER = LIBRARY / "picker"


def run(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return agrisynth(*args, cwd=cwd, timeout=300)


@pytest.mark.parametrize("spec, files", [
    ("cai2020_crank_rocker", ["extremes.png"]),
    ("cai2020_double_crank", ["path.png"]),
    pytest.param("cai2020_picker", ["trajectory.png", "animation.gif"], marks=pytest.mark.slow),
])
def test_published_designs_check_clean(tmp_path, spec, files):
    proc = run("check", str(PICKER / f"{spec}.toml"), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    folder = tmp_path / f"{spec}-check"
    data = json.loads((folder / "result.json").read_text())
    assert data["status"] == "evaluated" and "objective" not in data
    for rule in data["rules"]:
        assert set(rule) >= {"name", "value", "limit", "unit", "satisfied", "margin"}
    for name in files:
        assert (folder / name).stat().st_size > 10_000
    if spec == "cai2020_picker":
        assert data["trajectory"]["frame"] == "machine"
        assert data["facts"]["instants"]["dropping"]["published_t"] == 0.44
        _parts_described(tmp_path, data)


def _parts_described(tmp_path: Path, data: dict):
    """The combined picker's design_variables: every design name, each part's variable as that part's own check
    describes it (unit, path, fixed), with the part's file; the installation angles in deg at their own path."""
    described = data["design_variables"]
    assert set(described) == set(data["design"])
    for part, source in (("crank_rocker", "cai2020_crank_rocker"), ("double_crank", "cai2020_double_crank")):
        proc = run("check", str(PICKER / f"{source}.toml"), "--out", str(tmp_path / "parts"), cwd=tmp_path)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        own = json.loads((tmp_path / "parts" / f"{source}-check" / "result.json").read_text())["design_variables"]
        for name, entry in own.items():
            assert described[f"{part}.{name}"] == {**entry, "file": str(PICKER / f"{source}.toml")}
    for angle in ("theta1", "theta2"):
        assert described[angle] == {"path": f"installation.{angle}", "unit": "deg", "bounds": None, "free": False}


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_solve_of_the_combined_picker_is_bad_input(tmp_path):
    proc = run("solve", str(PICKER / "cai2020_picker.toml"), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 2
    assert "kind 'picker' has nothing to optimise" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("spec, message", [
    ("cai2020_crank_rocker", "crank_rocker: solve needs at least one free design variable"),
    ("cai2020_double_crank", "picker_double_crank: solve needs at least one free design variable"),
])
def test_solve_with_nothing_free_is_bad_input(tmp_path, spec, message):
    proc = run("solve", str(PICKER / f"{spec}.toml"), "--out", str(tmp_path), "--workers", "1", cwd=tmp_path)
    assert proc.returncode == 2
    assert message in proc.stderr and "agrisynth check" in proc.stderr and "Traceback" not in proc.stderr


def _variant(tmp_path: Path, source: str, old: str, new: str, name: str = "bad.toml") -> Path:
    text = (PICKER / source).read_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize("source, old, new, message", [
    ("cai2020_double_crank.toml", "l2 = 78.5 ", "l2 = -3 ", "picker_double_crank.linkage: l2: expected > 0, got -3"),
    ("cai2020_double_crank.toml", "points = 10", "points = 1", "picker_double_crank.target.points: expected >= 2, got 1"),
    ("cai2020_double_crank.toml", "swing = 50.0", "swng = 50.0", "picker_double_crank.drive.swng: unknown field; did you mean 'swing'?"),
    ("cai2020_crank_rocker.toml", "l9 = 133.5", "l9 = 0", "crank_rocker.links: l9: expected > 0, got 0"),
    ("cai2020_picker.toml", "crank_speed = 60.0", "crank_speed = -60", "picker.operation.crank_speed: expected > 0, got -60"),
    ("cai2020_picker.toml", 'picking_extreme = "folded"', 'picking_extreme = "open"', "picker.installation.picking_extreme"),
])
def test_bad_input_names_the_field(tmp_path, source, old, new, message):
    proc = run("check", str(_variant(tmp_path, source, old, new)), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2
    assert message in proc.stderr
    assert "Traceback" not in proc.stderr


def test_picker_parts_must_exist_and_have_the_right_kind(tmp_path):
    missing = _variant(tmp_path, "cai2020_picker.toml", '"cai2020_crank_rocker.toml"', '"nowhere.toml"', "a.toml")
    proc = run("check", str(missing), cwd=tmp_path)
    assert proc.returncode == 2 and "picker.crank_rocker:" in proc.stderr and "no such spec file" in proc.stderr
    (tmp_path / "cai2020_double_crank.toml").write_text((PICKER / "cai2020_double_crank.toml").read_text())
    (tmp_path / "cai2020_crank_rocker.toml").write_text((PICKER / "cai2020_crank_rocker.toml").read_text())
    swapped = _variant(tmp_path, "cai2020_picker.toml", '"cai2020_crank_rocker.toml"', '"cai2020_double_crank.toml"', "b.toml")
    proc = run("check", str(swapped), cwd=tmp_path)
    assert proc.returncode == 2
    assert "is a 'picker_double_crank' spec, expected kind 'crank_rocker'" in proc.stderr


def test_double_crank_that_cannot_assemble_exits_2(tmp_path):
    bad = _variant(tmp_path, "cai2020_double_crank.toml", "l2 = 78.5 ", "l2 = 8.5 ")
    proc = run("check", str(bad), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    message = " ".join(proc.stderr.split())
    assert f"{bad}: picker_double_crank.linkage: the double crank cannot assemble" in message
    assert "l2 = 8.5" in message


FORBIDDEN_PROBE = """
import json, sys
from synthesis.cli import cli
runs = [["check", "{p}/cai2020_picker.toml"], ["check", "{p}/cai2020_double_crank.toml"],
        ["solve", "{p}/cai2020_crank_rocker_synthesis.toml", "--starts", "1", "--workers", "1"],
        ["solve", "{p}/picker_double_crank_retrofit.toml", "--starts", "1", "--workers", "1"]]
for args in runs:
    try:
        cli.main(args + ["--out", "{out}"], standalone_mode=False)
    except SystemExit:
        pass
words = ("planting", "cam", "guide_tube", "guide_way", "tillage", "combing", "steering")
bad = [m for m in sys.modules if m.startswith(("synthesis.", "synthesis.constraints.")) and any(w in m for w in words)]
bad += [m for m in sys.modules if m.split(".")[0] == "cvxpy"]
print(json.dumps(bad))
"""


@pytest.mark.slow
def test_runs_import_no_other_mechanism(tmp_path):
    code = FORBIDDEN_PROBE.format(p=PICKER, out=tmp_path)
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout.strip().splitlines()[-1]) == []


@pytest.mark.slow
def test_compare_figures_overlay_baseline_and_solution(tmp_path):
    from synthesis import kinds
    from synthesis.kinds.crank_rocker.check import run_check as check_crank_rocker
    from synthesis.kinds.picker.check import run_check as check_double_crank
    from synthesis.kinds import solve_spec
    from synthesis.result import Result
    from synthesis.spec import load_spec

    def roundtrip(result):              # figures are drawn from result.json alone
        return Result.from_json(json.loads(json.dumps(result.to_json())))

    base = roundtrip(check_crank_rocker(load_spec(PICKER / "cai2020_crank_rocker.toml")))
    best = roundtrip(solve_spec(load_spec(PICKER / "crank_rocker_max_transmission.toml"), starts=1)[0])
    written = kinds.compare_figures("crank_rocker")([base, best], tmp_path)
    base = roundtrip(check_double_crank(load_spec(PICKER / "cai2020_double_crank.toml")))
    best = roundtrip(solve_spec(load_spec(PICKER / "picker_double_crank_retrofit.toml"), starts=1)[0])
    written += kinds.compare_figures("picker_double_crank")([base, best], tmp_path)
    assert written == ["compare_crank_rocker.png", "compare_picker_double_crank.png"]
    for name in written:
        assert (tmp_path / name).stat().st_size > 10_000


def test_combined_picker_names_the_part_that_cannot_assemble(tmp_path):
    for part in ("cai2020_crank_rocker.toml", "cai2020_picker.toml"):
        (tmp_path / part).write_text((PICKER / part).read_text())
    broken = _variant(tmp_path, "cai2020_double_crank.toml", "l2 = 78.5 ", "l2 = 8.5 ", "cai2020_double_crank.toml")
    proc = run("check", str(tmp_path / "cai2020_picker.toml"), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    message = " ".join(proc.stderr.split())
    assert f"picker.double_crank: {broken}: picker_double_crank.linkage: the double crank cannot assemble" in message

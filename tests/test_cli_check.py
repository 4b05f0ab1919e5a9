"""`agrisynth check` end to end: rule table, result.json contract, plot, exit codes, bad input."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import pytest

from conftest import PLANTING
from solving import agrisynth

BASE = (PLANTING / "taiwan_example1.toml").read_text()


def run(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return agrisynth(*args, cwd=cwd, timeout=120)


def spec_with(tmp_path: Path, old: str, new: str, name: str = "bad.toml") -> Path:
    assert old in BASE, old
    path = tmp_path / name
    path.write_text(BASE.replace(old, new, 1))
    return path


def test_check_writes_result_json_report_and_plot(tmp_path):
    proc = run("check", str(PLANTING / "taiwan_example1.toml"), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr        # example 1 violates some rules (see the closing note)
    assert "entry_angle" in proc.stdout and "FAIL" in proc.stdout
    folder = tmp_path / "taiwan_example1-check"
    data = json.loads((folder / "result.json").read_text())
    for key in ("kind", "name", "spec_sha256", "status", "design", "rules", "trajectory", "versions"):
        assert key in data
    assert data["status"] == "evaluated" and "objective" not in data
    assert set(data["design"]) >= {"l1", "l2", "l3", "l4", "l5", "zeta", "phi"}
    for rule in data["rules"]:
        assert set(rule) >= {"name", "value", "limit", "unit", "satisfied", "margin"}
    assert len(data["rules"]) == 13
    tr = data["trajectory"]
    assert tr["frame"] == "ground"
    assert {len(tr[k]) for k in ("t", "crank_deg", "x", "y", "vx", "vy", "ax", "ay")} == {361}
    # the file says the units of its keys (mm, mm/s, mm/s^2): the ground frame's vx is the machine
    # frame's plus the forward speed, 0.6 m/s = 600 mm/s
    assert [g - m for g, m in zip(tr["vx"], tr["machine"]["vx"])] == pytest.approx([600.0] * 361, abs=1e-9)
    assert tr["units"] == {"t": "s", "crank_deg": "deg", "x": "mm", "y": "mm", "vx": "mm/s", "vy": "mm/s",
                           "ax": "mm/s^2", "ay": "mm/s^2"}
    assert data["design_variables"]["l2"] == {"path": "arm.l2", "unit": "mm", "bounds": None, "free": False}
    # every design value is described, the assembly branch beside the variables too
    assert data["design"]["branch"] == -1 and set(data["design_variables"]) == set(data["design"])
    assert data["design_variables"]["branch"] == {"path": "arm.branch", "unit": "-", "bounds": None, "free": False}
    assert (folder / "trajectory.png").stat().st_size > 10_000
    assert "<table class='rules'>" in (folder / "report.html").read_text()
    # a second run keeps the first (exit 2 before any work) unless --force, which replaces it and says so
    again = run("check", str(PLANTING / "taiwan_example1.toml"), "--out", str(tmp_path), cwd=tmp_path)
    assert again.returncode == 2 and "holds an earlier agrisynth run; give --force" in again.stderr
    forced = run("check", str(PLANTING / "taiwan_example1.toml"), "--out", str(tmp_path), "--force", cwd=tmp_path)
    assert forced.returncode == 1 and "replaced the previous run" in forced.stdout
    assert [p.name for p in tmp_path.iterdir()] == ["taiwan_example1-check"]


def test_missing_field(tmp_path):
    proc = run("check", str(spec_with(tmp_path, "l3 = 75 ", "")), cwd=tmp_path)
    assert proc.returncode == 2
    assert "planting_fourbar.arm.l3: missing required field" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_unknown_field_suggests_the_right_name(tmp_path):
    proc = run("check", str(spec_with(tmp_path, "l3 = 75 ", "l33 = 75 ")), cwd=tmp_path)
    assert proc.returncode == 2
    assert "planting_fourbar.arm.l33: unknown field; did you mean 'l3'?" in proc.stderr


@pytest.mark.parametrize("value", ["-3", "0"])
def test_non_positive_length(tmp_path, value):
    proc = run("check", str(spec_with(tmp_path, "l2 = 35 ", f"l2 = {value} ")), cwd=tmp_path)
    assert proc.returncode == 2
    assert f"planting_fourbar.arm: l2: expected > 0, got {value}" in proc.stderr


def test_linkage_that_cannot_assemble_names_angle_and_triangle(tmp_path):
    path = spec_with(tmp_path, "l3 = 75 ", "l3 = 10 ")
    path.write_text(path.read_text().replace("l4 = 80 ", "l4 = 12 "))
    proc = run("check", str(path), cwd=tmp_path)
    assert proc.returncode == 2
    assert ("linkage cannot assemble at any crank angle: at crank angle 0 deg |O'A| = l1 - l2 = 40 mm "
            "> l3 + l4 = 22 mm (triangle O'AB cannot close)") in proc.stderr.replace("\n", " ")
    assert not (tmp_path / "results").exists()


def test_non_grashof_design_is_a_violated_rule(tmp_path):
    path = spec_with(tmp_path, "l3 = 75 ", "l3 = 40 ")
    path.write_text(path.read_text().replace("l4 = 80 ", "l4 = 45 "))
    proc = run("check", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr
    data = json.loads((tmp_path / "out" / "taiwan_example1-check" / "result.json").read_text())
    rules = {r["name"]: r for r in data["rules"]}
    assert rules["grashof_crank_rocker"]["satisfied"] is False
    assert rules["grashof_crank_rocker"]["value"] == pytest.approx(-25.0)   # l3 + l4 - l2 - l1
    assert "crank cannot complete a turn" in rules["entry_angle"]["note"]
    assert "grashof_crank_rocker" in proc.stdout


def test_spec_that_is_not_toml_reports_line_and_column(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text('kind = "planting_fourbar"\nname = \n')
    proc = run("check", str(path), cwd=tmp_path)
    assert proc.returncode == 2
    assert "not valid TOML" in proc.stderr and "line 2, column 8" in proc.stderr


def test_missing_file_and_unknown_kind(tmp_path):
    assert run("check", str(tmp_path / "nope.toml"), cwd=tmp_path).returncode == 2
    path = tmp_path / "k.toml"
    path.write_text('kind = "planting_forbar"\nname = "x"\n')
    proc = run("check", str(path), cwd=tmp_path)
    assert proc.returncode == 2 and "did you mean 'planting_fourbar'?" in proc.stderr


@pytest.mark.parametrize("args, said", [
    (("solve", "{spec}", "--starts", "0"), "error: Invalid value for '--starts': 0 is not in the range"),
    (("solve", "{spec}", "--seed", str(2**53 + 1)), "error: Invalid value for '--seed'"),    # as [solver] seed
    # click's IntRange said "'1e9' is not a valid integer range", as if a range were asked for
    (("solve", "{spec}", "--starts", "1e9"),
     "error: Invalid value for '--starts': '1e9' is neither a whole number (1<=x<=10000) nor auto"),
    (("solve",), "error: Missing argument 'SPEC'. (see `agrisynth solve --help`)"),
    (("frob",), "error: No such command 'frob'. (see `agrisynth --help`)"),
])
def test_a_usage_error_is_one_line_like_every_other_bad_input(tmp_path, args, said):
    """click writes its usage errors in three lines (Usage, Try, Error); agrisynth says them in one, exit 2."""
    spec = str(PLANTING / "redesign_from_example1.toml")
    proc = run(*(a.format(spec=spec) for a in args), cwd=tmp_path)
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1 and proc.stderr.startswith(said), proc.stderr


def test_compare_of_a_file_that_is_not_json_says_so(tmp_path):
    """A report.html given to compare instead of its folder: "not JSON", not "truncated, re-run the check"."""
    page = tmp_path / "report.html"
    page.write_text("<!doctype html>\n<html><head><title>taiwan_example1</title></head><body></body></html>\n")
    proc = run("compare", str(page), "--out", str(tmp_path / "cmp"), cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"error: {page}: not JSON, so not a result.json (give a run folder or its result.json)"


def test_problems_lists_the_library(tmp_path):
    proc = run("problems", cwd=tmp_path)
    assert proc.returncode == 0
    for k in (1, 2, 3, 4):
        assert f"taiwan_example{k}" in proc.stdout


def test_problems_refuses_a_missing_folder_and_lists_past_a_bad_file(tmp_path):
    """--dir naming no folder is bad input (exit 2: it listed an empty library, exit 0); in a library, a folder named
    x.toml is no spec and an unreadable spec is a row saying why, not the end of the listing (it exited 2)."""
    proc = run("problems", "--dir", str(tmp_path / "nowhere"), cwd=tmp_path)
    assert proc.returncode == 2 and "does not exist" in proc.stderr and "Traceback" not in proc.stderr
    library = tmp_path / "lib"
    (library / "x.toml").mkdir(parents=True)
    (library / "bad.toml").write_text('kind = "planting_fourbar"\nname = [1\n')
    (library / "good.toml").write_text((PLANTING / "taiwan_example1.toml").read_text())
    proc = run("problems", "--dir", str(library), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "taiwan_example1" in proc.stdout and "bad.toml" in proc.stdout and "not read: not valid TOML" in proc.stdout
    # a spec is found by its listed name in the built-in library only: another folder's are named by their path
    said = " ".join(proc.stdout.split())
    assert f"check or solve one by its path (agrisynth check {library / 'FILE'})" in said
    assert f"agrisynth problems --dir {library} --copy FILE" in said
    assert "check or solve one by its file as listed" in " ".join(run("problems", cwd=tmp_path).stdout.split())


def test_help_teaches_every_command_and_every_kind_that_solves(tmp_path):
    from synthesis import kinds

    top = run("--help", cwd=tmp_path).stdout
    for command in ("check", "solve", "compare", "bench", "problems", "Exit codes"):
        assert command in top
    solve_help = run("solve", "--help", cwd=tmp_path).stdout
    for kind in kinds.all_kinds():
        listed = re.search(rf"^\s+{kind.name}:", solve_help, re.MULTILINE) is not None
        assert listed == kind.solves, kind.name
        for objective in kind.objectives:          # every objective of a solving kind, with its meaning
            assert re.search(rf"^\s+{objective}\s+\S", solve_help, re.MULTILINE), (kind.name, objective)
    compare_help = run("compare", "--help", cwd=tmp_path).stdout
    for phrase in ("first RESULT is the baseline", "offline", "bench", "Example"):
        assert phrase in compare_help


@pytest.mark.parametrize("command", [("check", str(PLANTING / "taiwan_example1.toml")),
                                     ("solve", str(PLANTING / "taiwan_example1.toml")),
                                     ("compare", str(PLANTING / "taiwan_example1.toml"))])
def test_an_empty_out_is_refused_not_read_as_the_working_folder(tmp_path, command):
    proc = agrisynth(*command, "--out", "", cwd=tmp_path)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "Invalid value for '--out': an empty path" in proc.stderr and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_run_folder_or_its_result_given_as_spec_is_refused_naming_its_solved_toml(tmp_path):
    """check RESULT said "not valid TOML: Invalid statement" of a result.json and "is a directory" of a run folder."""
    run = tmp_path / "results" / "my_arm"
    run.mkdir(parents=True)
    (run / "result.json").write_text("{}")
    (run / "solved.toml").write_text("")
    for given, what in ((run, "a folder"), (run / "result.json", "a JSON file (a run's result?)")):
        proc = agrisynth("check", str(given), cwd=tmp_path)
        assert proc.returncode == 2, proc.stdout + proc.stderr
        assert " ".join(proc.stderr.split()) == (f"error: {given}: {what}, not a spec file: a solve's design is its "
                                                 f"solved.toml, `agrisynth check {run / 'solved.toml'}`")


def test_a_misspelt_command_is_told_the_nearest_one(tmp_path):
    proc = agrisynth("chek", "x.toml", cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.startswith("error: No such command 'chek'; did you mean 'check'?")
    proc = agrisynth("xyzzy", cwd=tmp_path)
    assert proc.returncode == 2 and "did you mean" not in proc.stderr


def test_agrisynth_alone_prints_its_help_not_an_error():
    """`agrisynth` with no command printed its help as "error: Usage: ..." and exited 2 (click >= 8.2 raises the help
    as a usage error); a mistyped command stays an error in one line."""
    bare = agrisynth()
    assert bare.returncode == 0 and bare.stdout.startswith("Usage: agrisynth [OPTIONS] COMMAND")
    assert "error" not in bare.stderr and "solve" in bare.stdout
    typo = agrisynth("solv")
    assert typo.returncode == 2 and typo.stderr.strip() == ("error: No such command 'solv'; did you mean 'solve'? "
                                                            "(see `agrisynth --help`)")


@pytest.mark.parametrize("relative", ["picker/cai2020_picker.toml", "fourbar_path/picking_arc.toml",
                                      "planting_arm/taiwan_example1.toml", "comb_finger/peanut_baseline.toml",
                                      "rotary_planetary/smooth_loop_redesign.toml", "clamp_cam/opening_cam_redesign.toml"])
def test_every_number_of_a_trajectory_has_its_unit(relative):
    """trajectory.units named the eight common keys only: the combined picker's crank_ab_deg and speed_m_s and
    fourbar_path's crank_speed_rpm had none."""
    from synthesis import kinds
    from synthesis.result import with_units
    from synthesis.spec import load_spec

    loaded = load_spec(PLANTING.parent / relative)
    trajectory = with_units(kinds.get(loaded.kind).check(loaded).trajectory)
    units = trajectory["units"]
    frames = [trajectory, *([trajectory["machine"]] if "machine" in trajectory else [])]
    for frame in frames:
        numeric = [k for k, v in frame.items() if k != "units" and isinstance(v, (int, float, list))]
        assert numeric and all(k in units for k in numeric), [k for k in numeric if k not in units]

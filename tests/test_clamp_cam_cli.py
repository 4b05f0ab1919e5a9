"""`agrisynth check` / `solve` for clamp_cam end to end: run folder (result.json, plots, CSV, DXF),
what a cam run imports, and bad input (exit 2 naming the field, exit 3 naming the rule)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import LIBRARY, ROOT
from synthesis.errors import SpecError
from synthesis.spec import load_spec
from solving import agrisynth

CAMS = LIBRARY / "clamp_cam"
OPENING = (CAMS / "opening_cam.toml").read_text()


def run(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return agrisynth(*args, cwd=cwd, timeout=180)


def spec_with(tmp_path: Path, *edits: tuple[str, str], base: str = OPENING) -> Path:
    text = base
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


@pytest.mark.slow
def test_check_writes_result_plots_and_workshop_files(tmp_path):
    import ezdxf

    proc = run("check", str(CAMS / "opening_cam.toml"), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr               # the return's pressure angle (see the baselines)
    assert "pressure_angle_return" in proc.stdout and "FAIL" in proc.stdout
    folder = tmp_path / "opening_cam-check"
    data = json.loads((folder / "result.json").read_text())
    for key in ("kind", "name", "spec_sha256", "status", "design", "rules", "trajectory", "versions", "facts"):
        assert key in data
    assert {"cam", "follower", "profile"} <= set(data["facts"])
    assert data["kind"] == "clamp_cam" and data["status"] == "evaluated"
    assert {r["name"] for r in data["rules"]} == {"pressure_angle_rise", "pressure_angle_return", "no_undercut",
                                                  "timing_hold_near[0]", "timing_hold_far[0]"}
    tr = data["trajectory"]
    assert {len(tr[k]) for k in ("t", "crank_deg", "x", "y", "vx", "vy", "ax", "ay")} == {len(tr["t"])}
    assert tr["t"][-1] == pytest.approx(1.0)                # one turn at 60 r/min
    for name in ("motion.png", "profile.png"):
        assert (folder / name).stat().st_size > 20_000
    html = (folder / "report.html").read_text()
    assert "<img src='motion.png'" in html and "<a href='profile.dxf'>" in html
    # CSV: header, closed (last row = first but for the cam angle 360), the working profile of result.json
    # (the other columns: tests/test_exports.py)
    rows = np.genfromtxt(folder / "profile.csv", delimiter=",", skip_header=1)[:, 2:4]
    assert rows.shape == (3601, 2) and np.array_equal(rows[0], rows[-1])
    assert rows[:-1] == pytest.approx(np.column_stack([data["facts"]["profile"]["working"]["x"],
                                                       data["facts"]["profile"]["working"]["y"]]), abs=1e-6)
    # DXF: a closed polyline in mm with the same points
    doc = ezdxf.readfile(folder / "profile.dxf")
    assert doc.header["$INSUNITS"] == 4
    (poly,) = [e for e in doc.modelspace().query("LWPOLYLINE") if e.dxf.layer == "PROFILE"]
    assert poly.closed
    pts = np.array([(x, y) for x, y, *_ in poly.get_points()])
    assert pts == pytest.approx(rows[:-1], abs=1e-6)


SCENE_CHECK = """
import os
import sys
# one core: the figures are drawn in this process, not side by side in forked ones, so what drawing them imports
# (ezdxf for the DXF) is among this process's modules
os.sched_setaffinity(0, {{min(os.sched_getaffinity(0))}})
from synthesis.cli import main
sys.argv = ["agrisynth", "{command}", "{spec}", "--out", "{out}"] + {extra}
try:
    main()
except SystemExit:
    pass
loaded = sorted(m for m in sys.modules if m.startswith(("synthesis", "constraints", "cvxpy", "ezdxf")))
print("MODULES", " ".join(loaded))
"""

FORBIDDEN = ("synthesis.kinds.planting", "synthesis.kinds.picker", "synthesis.kinds.guide_tube", "synthesis.kinematics.fourbar",
             "synthesis.kinds.planting.kinematics", "synthesis.kinds.picker.kinematics.arc", "synthesis.constraints.grashof",
             "synthesis.constraints.transmission", "synthesis.kinds.planting.rules.precision_points")


def _modules(tmp_path, command: str, spec: Path, extra: list[str] = ()) -> set[str]:
    code = SCENE_CHECK.format(command=command, spec=spec, out=tmp_path / "out", extra=list(extra))
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=180,
                          env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("MODULES")]
    assert line, proc.stdout + proc.stderr
    return set(line[0].split()[1:])


@pytest.mark.slow
def test_a_cam_run_imports_no_linkage_no_drop_model_and_cvxpy_only_for_the_optimised_law(tmp_path):
    checked = _modules(tmp_path, "check", CAMS / "opening_cam.toml")
    assert "synthesis.kinds.clamp_cam.check" in checked and "ezdxf" in checked       # the DXF was written
    assert not [m for m in checked if m.startswith(FORBIDDEN)]
    assert not [m for m in checked if m.startswith("cvxpy")]
    solved = _modules(tmp_path, "solve", CAMS / "opening_cam_redesign.toml", ["--workers", "1", "--starts", "1"])
    assert "synthesis.kinds.clamp_cam.nlp" in solved
    assert not [m for m in solved if m.startswith(FORBIDDEN) or m.startswith("cvxpy")]
    optimised = _modules(tmp_path, "check", CAMS / "opening_cam_optimised_law.toml")
    assert "cvxpy" in optimised and "synthesis.kinds.clamp_cam.bspline_law" in optimised
    assert not [m for m in optimised if m.startswith(FORBIDDEN)]


@pytest.mark.parametrize("edits, message", [
    ((("near_dwell = 146.0", "near_dwell = 136.0"),),
     "clamp_cam.motion: rise + far_dwell + return + near_dwell = 40 + 160 + 14 + 136 = 350 deg, expected 360"),
    ((("stroke = 10.0", "stroke = -3"),), "clamp_cam.motion.stroke: expected > 0, got -3"),
    ((("stroke = 10.0", "stroke = 0"),), "clamp_cam.motion.stroke: expected > 0, got 0"),
    ((("roller_radius = 3.5", "roller_radius = 50"),),
     "clamp_cam.cam.roller_radius: expected below base_radius, 50 mm, got 50 mm: the roller must be smaller"),
    ((("roller_radius = 3.5", "roller_radius = 60"),),
     "clamp_cam.cam.roller_radius: expected below base_radius, 50 mm, got 60 mm"),
    # a negative base radius is named itself (it was reported as the roller's fault); bounds are read as bounds
    ((("base_radius = 50.0", "base_radius = -50.0"),), "clamp_cam.cam.base_radius: expected > 0, got -50 mm"),
    ((("base_radius = 50.0", "base_radius = { init = 50.0, bounds = [1, 150] }"),),
     "clamp_cam.cam.roller_radius: expected below the smallest base_radius its bounds allow, 1 mm, got 3.5 mm"),
    ((("base_radius = 50.0", "base_radius = { init = 50.0, bounds = [20, 150] }"),
      ("roller_radius = 3.5", "roller_radius = { init = 3.5, bounds = [0.5, 60] }")),
     "clamp_cam.cam.roller_radius: expected below the smallest base_radius its bounds allow, 20 mm, got 3.5 (free in "
     "[0.5, 60]) mm (its upper bound 60 mm)"),
    ((("return = 14.0", "return = 0.0"),), "clamp_cam.motion: return: expected > 0, got 0"),
    # an operating range (the follower's contact over a speed range) with a law fitted at one speed says so
    ((("crank_speed = 60.0", "crank_speed = { range = [50, 90], samples = 3 }"),
      ("law = \"cycloidal\"", "law = \"optimised\"")),
     "clamp_cam.operation.crank_speed: a range needs a closed-form motion law (the optimised law is fitted once, at "
     "one speed)"),
    ((("hold_far = [[186.0, 346.0]]", "hold_far = [[140.0, 346.0]]"),),
     "clamp_cam.timing: hold_near[0] [0, 146] overlaps hold_far[0] [140, 346] deg"),
    ((("offset = 0.0", "offset = 0.0\narm_length = 60"),),
     "clamp_cam.follower: arm_length: only for type = \"oscillating\""),
    ((("law = \"cycloidal\"", "law = \"cycloid\""),), "clamp_cam.motion.law: expected 'cycloidal'"),
    ((("return = 14.0", "retrun = 14.0"),), "clamp_cam.motion.retrun: unknown field; did you mean 'return'?"),
    ((("law = \"cycloidal\"", "law = \"optimised\""), ("rise = 40.0", "rise = { init = 40.0, bounds = [30, 50] }")),
     "clamp_cam.motion: rise: the optimised law is fitted once for fixed segments"),
    ((("type = \"translating\"", "type = \"oscillating\"\npivot_distance = 90"), ("offset = 0.0", "")),
     "clamp_cam.follower: arm_length: missing required field for type = \"oscillating\""),
    ((("rise_start = 146.0", "rise_start = 146.0\nstroke = 5"),), "not valid TOML: Cannot overwrite a value (at line 20, column 11)"),
    # the fuzz campaign's find: a cubic has no 4th derivative for the jerk fit's tie-break (a scipy traceback)
    ((("law = \"cycloidal\"", "law = \"optimised\""), ("[motion]", "[bspline]\nminimise = \"jerk\"\ndegree = 3\n\n[motion]")),
     "clamp_cam.bspline: minimise = 'jerk' needs degree >= 4 (a degree-3 spline's jerk is piecewise constant"),
])
def test_bad_specs_name_the_field(tmp_path, edits, message):
    with pytest.raises(SpecError) as err:
        load_spec(spec_with(tmp_path, *edits))
    assert err.value.exit_code == 2
    assert message in " ".join(str(err.value).split())


def test_bad_spec_exits_2_without_traceback(tmp_path):
    proc = run("check", str(spec_with(tmp_path, ("stroke = 10.0", "stroke = -3"))), cwd=tmp_path)
    assert proc.returncode == 2
    assert "clamp_cam.motion.stroke: expected > 0, got -3" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_timing_window_the_cam_misses_is_a_violated_rule_in_check(tmp_path):
    """Fig. 8c of seed 001: the clamp stays closed until the drop at 0.44 s; Table 1's dwells open it
    12.4 deg (0.034 s) earlier when the return ends at the pick."""
    path = spec_with(tmp_path, ('clock = "deg"', 'clock = "s"'), ("hold_near = [[0.0, 146.0]]",
                                                                 "hold_near = [[0.0, 0.44]]"),
                     ("hold_far = [[186.0, 346.0]]", "hold_far = []"))
    proc = run("check", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 1
    data = json.loads((tmp_path / "out" / "opening_cam-check" / "result.json").read_text())
    rule = {r["name"]: r for r in data["rules"]}["timing_hold_near[0]"]
    assert not rule["satisfied"] and rule["value"] == pytest.approx(-12.4, abs=1e-9)


@pytest.mark.slow
def test_rules_the_free_timing_cannot_move_are_refused_before_a_start_naming_their_fields(tmp_path):
    """Only rise_start free: the published cam's return pressure angle (-56.19 deg against +-45) and its undercut are
    fixed by numbers the spec gives, so solve refuses at once (exit 2) naming those fields, instead of a multistart
    that can only end infeasible (it exited 3 naming them as conflicting)."""
    path = spec_with(tmp_path, ("rise_start = 146.0", "rise_start = { init = 146.0, bounds = [140.0, 150.0] }"),
                     ("hold_near = [[0.0, 146.0]]", "hold_near = [[0.0, 160.0]]"),
                     ("[operation]", "[solver]\nstarts = 2\n\n[operation]"))
    proc = run("solve", str(path), "--out", str(tmp_path / "out"), "--workers", "1", cwd=tmp_path)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    text = " ".join(proc.stderr.split())
    assert "pressure_angle_return = -56.19 deg is fixed by [cam] base_radius, [follower] offset and [motion] return" in text
    assert "no start was solved" in text and not (tmp_path / "out" / "opening_cam").exists()


def test_optimised_law_that_cannot_meet_an_acceleration_cap_exits_3(tmp_path):
    base = (CAMS / "opening_cam_optimised_law.toml").read_text()
    path = spec_with(tmp_path, ("[operation]", "[rules]\nmax_acceleration = 20000.0\n\n[operation]"), base=base)
    proc = run("check", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    text = " ".join(proc.stderr.split())
    assert "rules.max_acceleration: the optimised law cannot meet the timing: the return window of 14 deg" in text
    assert "27379.7" in text               # the least peak any C2 B-spline of this size reaches, mm/s^2


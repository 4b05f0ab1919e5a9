"""Reports and figures: a solve report puts the given design's rule values beside the solution's,
the operating conditions are a table, a run's report holds its own figures only (no comparison overlay, no
legend calling the one design "baseline"), SVG beside the main PNG, joint letters and link lengths on the
linkage drawings, readable animations with a frame counter; library warnings go to the run's log."""

from __future__ import annotations

import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from synthesis import kinds
from synthesis.core.solve import baseline_rules
from synthesis.kinds import solve_spec
from synthesis.report import run_artifacts, write_report
from synthesis.report.tables import candidates, operating_conditions
from synthesis.result import Result
from synthesis.spec import load_spec
from solving import agrisynth

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def _checked(spec: str) -> Result:
    loaded = load_spec(PROBLEMS / spec)
    return kinds.checker(loaded.model.kind)(loaded)


def _rule_table(html: str) -> str:
    return re.search(r"<table class='rules'>.*?</table>", html, re.S).group(0)


def test_a_solve_report_shows_the_given_designs_rules_beside_the_solution(tmp_path):
    loaded = load_spec(PROBLEMS / "picker/cai2020_crank_rocker_synthesis.toml")
    result, _, _ = solve_spec(loaded, starts=1)
    given = baseline_rules(kinds.get("crank_rocker"), loaded)
    assert [r["name"] for r in given] == [r["name"] for r in result.rules]
    write_report(result, tmp_path / "report.html", [], given_rules=given)
    table = _rule_table((tmp_path / "report.html").read_text())
    head = re.findall(r"<th>([^<]*)</th>", table)
    assert head == ["rule", "limit", "unit", "given (start 0)", "solved"]      # the question, the answer
    rows = re.findall(r"<tr><td>([^<]+)</td><td class='limit'>.*?</td><td>[^<]*</td>(<td.*?</td>)(<td.*?</td>)</tr>",
                      table, re.S)
    assert [name for name, _, _ in rows] == [r["name"] for r in result.rules]
    for (name, start, solved), g, s in zip(rows, given, result.rules):
        assert ("FAIL" in start) is (not g["satisfied"]) and ("FAIL" in solved) is (not s["satisfied"])
        assert f"{g['value']:.4g}" in start and f"{s['value']:.4g}" in solved
    assert any(not g["satisfied"] for g in given) and result.all_satisfied    # the question and the answer
    # a check (no solve) has no such column
    write_report(_checked("picker/cai2020_crank_rocker.toml"), tmp_path / "check.html", [])
    checked = _rule_table((tmp_path / "check.html").read_text())
    assert "given (start 0)" not in checked and "solved" not in checked and "<th>cai2020_crank_rocker</th>" in checked


def test_operating_conditions_are_a_table(tmp_path):
    planting = _checked("planting_arm/taiwan_example1.toml")
    rows = {(name, unit): values for name, unit, values in operating_conditions(candidates([planting]))}
    assert rows == {("forward speed", "m/s"): [0.6], ("crank speed", "r/min"): [250.0],
                    ("plant spacing", "mm"): [144.0]}
    tillage = _checked("tillage/hwang_tillage_baseline.toml")
    rows = {(name, unit): values for name, unit, values in operating_conditions(candidates([planting, tillage]))}
    assert rows[("crank speed", "r/min")] == [250.0, 60.0] and rows[("forward speed", "m/s")] == [0.6, 0.15]
    assert rows[("plant spacing", "mm")] == [144.0, None]
    cam = _checked("clamp_cam/opening_cam.toml")
    assert operating_conditions(candidates([cam])) == [("crank speed", "r/min", [60.0])]
    write_report(planting, tmp_path / "report.html", [])
    html = (tmp_path / "report.html").read_text()
    table = re.search(r"<h2>Operating conditions</h2>.*?</table>", html, re.S).group(0)
    assert "<td>forward speed</td><td>m/s</td><td class='num'>0.6</td>" in table
    assert "<td>crank speed</td><td>r/min</td><td class='num'>250</td>" in table


def test_a_runs_report_holds_its_own_figures_an_svg_copy_and_the_exports(tmp_path):
    result = _checked("picker/cai2020_crank_rocker.toml")
    artifacts = run_artifacts(result)
    for name, write in artifacts.items():
        write(tmp_path / name)
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written == ["extremes.png", "extremes.svg", "linkage.dxf", "paths.csv", "report.html"]
    html = (tmp_path / "report.html").read_text()
    assert re.findall(r"<img src='([^']+)'", html) == ["extremes.png"]      # the SVG is linked, not shown twice
    assert "<a href='extremes.svg'>" in html and "<a href='linkage.dxf'>" in html
    assert "baseline" not in html.lower()
    svg = (tmp_path / "extremes.svg").read_text()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg and len(svg) > 20_000


def test_linkage_drawings_carry_joint_letters_and_link_lengths():
    import matplotlib.pyplot as plt

    from synthesis.kinds.fourbar_path import plots as path_plots
    from synthesis.kinds.fourbar_path.construction import joint_positions
    from synthesis.kinds.planting.kinematics import ArmDesign
    from synthesis.kinds.planting.kinematics import joint_positions as arm_joints
    from synthesis.kinds.planting.compare_plots import annotate_linkage

    d = _checked("planting_arm/taiwan_example1.toml").design
    joints = arm_joints(ArmDesign(*(d[k] for k in ("l1", "l2", "l3", "l4", "l5", "zeta", "phi")), branch=d["branch"]),
                        np.radians([53.66]))
    fig, ax = plt.subplots()
    texts = [a.get_text() for a in annotate_linkage(ax, joints)]
    assert texts[:5] == ["O", "O'", "A", "B", "C"]
    # frame O-O' = l1, crank O-A = l2, coupler A-B = l3, rocker O'-B = l4 (Table 1, example 1)
    assert texts[5:9] == [f"{d['l1']:.1f}", f"{d['l2']:.1f}", f"{d['l3']:.1f}", f"{d['l4']:.1f}"]
    plt.close(fig)

    path = _checked("fourbar_path/picking_arc.toml")
    design = {n: path.design[n] for n in ("r1", "r2", "r3", "r4", "rcx", "rcy", "x0", "y0", "theta0")}
    j = joint_positions(design, np.radians([path.design["crank_deg"][0]]), 1)
    fig, ax = plt.subplots()
    path_plots._annotate(ax, j)
    texts = [t.get_text() for t in ax.texts]
    assert texts[:5] == list(j)                                   # O, A, B, O', P in the construction's order
    assert texts[5:9] == [f"{path.design[k]:.1f}" for k in ("r1", "r2", "r3", "r4")]
    plt.close(fig)


@pytest.mark.slow
def test_the_animation_is_large_enough_and_counts_its_frames(tmp_path):
    from PIL import Image

    from synthesis.kinds.fourbar_path import plots as path_plots

    result = _checked("fourbar_path/picking_arc.toml")
    seen = []
    orig = path_plots.save_gif

    def spy(fig, draw, frames, path, **kw):          # the text drawn on each frame
        def wrapped(k):
            artists = draw(k)
            seen.append([a.get_text() for a in artists if hasattr(a, "get_text")])
            return artists
        return orig(fig, wrapped, frames, path, **kw)

    path_plots.save_gif = spy
    try:
        path_plots.linkage_animation(result, tmp_path / "linkage.gif")
    finally:
        path_plots.save_gif = orig
    gif = Image.open(tmp_path / "linkage.gif")
    assert gif.size[0] >= 600 and gif.size[1] >= 500 and gif.n_frames == path_plots.GIF_FRAMES
    counters = [t for texts in seen for t in texts if t.startswith("frame ")]
    assert f"frame 1/{path_plots.GIF_FRAMES}, crank" in counters[0] or counters[0].startswith("frame 1/")
    assert any(t.startswith(f"frame {path_plots.GIF_FRAMES}/{path_plots.GIF_FRAMES}") for t in counters)


def test_library_warnings_go_to_the_log_not_the_terminal(capfd):
    import casadi as ca

    from synthesis.core.ipopt_log import captured_stdout
    from synthesis.core.library_log import captured_warnings

    x = ca.MX.sym("x")
    solver = ca.nlpsol("s", "ipopt", {"x": x, "f": x**2, "g": ca.sqrt(x)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.max_iter": 2})
    with captured_stdout() as log:            # what every IPOPT run of a solve goes through
        solver(x0=-1.0, lbg=0.0, ubg=1.0)     # NaN in sqrt: CasADi warns
        warnings.warn("delta_grad == 0.0", UserWarning)
    text = log()
    assert "WARNING(" in text and "NaN detected" in text
    assert "warning: UserWarning: delta_grad == 0.0" in text
    with captured_warnings() as said:
        np.log(np.array([-1.0]))              # numpy RuntimeWarning
        print("CasADi - WARNING(\"x\")", file=sys.stderr)
    assert "RuntimeWarning" in said() and 'CasADi - WARNING("x")' in said()
    out, err = capfd.readouterr()
    assert "WARNING" not in out + err and "delta_grad" not in out + err and "RuntimeWarning" not in out + err


@pytest.mark.slow
def test_warnings_while_drawing_go_to_the_runs_log_not_the_terminal(tmp_path, monkeypatch):
    """A planting arm whose links cannot close (l4 = 2 mm) has no trajectory, and its trajectory figure warns as it
    is drawn (a UserWarning added here, from the axes styling it calls: the figures no longer ask matplotlib for an empty legend, the warning this
    test used to hear).  `check` prints none of it: the run's warnings.log has it and the report links it."""
    import warnings

    from synthesis.kinds.planting import plots

    styled = plots.style_plane          # called by the figure as it draws (the figure writers may be cached)

    def warning(ax):
        warnings.warn("No artists with labels found to put in legend", UserWarning)
        styled(ax)

    monkeypatch.setattr(plots, "style_plane", warning)

    text = (PROBLEMS / "planting_arm" / "redesign_from_example1.toml").read_text()
    old = "l4 = { init = 80, bounds = [64, 96] }"
    assert old in text
    spec = tmp_path / "open_arm.toml"
    spec.write_text(text.replace(old, "l4 = 2"))
    proc = agrisynth("check", str(spec), "--out", str(tmp_path), timeout=300)
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr == "" and "Warning" not in proc.stdout
    run = tmp_path / "redesign_from_example1-check"
    log = (run / "warnings.log").read_text()
    assert "warning: UserWarning: No artists with labels found to put in legend" in log
    assert "<a href='warnings.log'>warnings.log</a>" in (run / "report.html").read_text()

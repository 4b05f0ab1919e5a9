"""`agrisynth tolerance` and the tolerance-robust `solve` as a user meets them: the report with its tornado,
--tol, a run folder as input, the Monte-Carlo pass rates of a robust solve, and the exit 3 of a box no design holds."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from types import SimpleNamespace

import pytest

from solving import agrisynth, strict_json

ROOT = Path(__file__).resolve().parents[1]
LIBRARY = ROOT / "problems"
STEERING = LIBRARY / "steering" / "steering_redesign_27.toml"


def test_tolerance_report_embeds_a_tornado_and_tol_sets_one_variable(tmp_path):
    """report.md embeds and links tornado.png (written, a PNG); --tol arm_length=0.5 overrides --length for that
    variable only; every stack-up row's signed contributions add up (in absolute value) to its linear loss, which
    is what the tornado's bars show, and the tornado draws the worst rules first."""
    from synthesis.tolerance.output import tornado_rules

    run = agrisynth("tolerance", str(STEERING), "--length", "0.2", "--angle", "0.3", "--tol", "arm_length=0.5",
                    "--samples", "10", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    folder = tmp_path / "steering_redesign_27-tolerance"
    assert (folder / "tornado.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (folder / "report.md").read_text()
    assert "](tornado.png)" in report and "[tornado.png](tornado.png)" in report
    facts = strict_json(folder / "result.json")["facts"]["tolerance"]
    assert facts["tolerance"] == {"arm_length": {"half_width": 0.5, "unit": "mm"},
                                  "base_angle": {"half_width": 0.3, "unit": "deg"}}
    rows = facts["stack_up"]
    for row in rows:
        if row["linear_loss"] is not None:
            assert sum(abs(c) for c in row["contributions"].values()) == pytest.approx(row["linear_loss"], rel=1e-9)
    arm = next(r for r in rows if r["name"] == "steering_arm_length")
    assert abs(arm["contributions"]["arm_length"]) == pytest.approx(0.5, rel=1e-9)     # d(arm)/d(arm) = 1, tol 0.5
    shown = tornado_rules(facts)
    assert shown and [r["name"] for r in shown] == [r["name"] for r in sorted(
        shown, key=lambda r: r["linear_worst_margin"] / r["scale"])]


@pytest.mark.parametrize("options, widths", [
    # --length over the spec's own entries of lengths (its [tolerance] variables: 0.2, 0.05, 0.2 mm)
    (("--length", "3"), {"base_radius": 3.0, "roller_radius": 3.0, "offset": 3.0}),
    # --tol over --length; the angles keep no width
    (("--length", "5", "--tol", "roller_radius=0.1"), {"base_radius": 5.0, "roller_radius": 0.1, "offset": 5.0}),
    # --angle leaves the spec's lengths standing; the near dwell closes the turn: it moves by the other three
    # segments' widths together (ClampCam.follows)
    (("--angle", "1"), {"base_radius": 0.2, "roller_radius": 0.05, "offset": 0.2, "rise_start": 1.0, "rise": 1.0,
                        "far_dwell": 1.0, "return": 1.0, "near_dwell": 3.0}),
])
def test_the_command_lines_widths_are_over_the_specs(tmp_path, options, widths):
    """`agrisynth tolerance` takes its tolerances "from --length/--angle ... else the spec's [tolerance] table": a
    spec listing its lengths one by one kept them, and --length 5 was dropped without a word."""
    spec = LIBRARY / "clamp_cam" / "opening_cam_robust_redesign.toml"
    run = agrisynth("tolerance", str(spec), *options, "--samples", "0", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    box = strict_json(tmp_path / "opening_cam_robust_redesign-tolerance" / "result.json")["facts"]["tolerance"]
    assert {name: v["half_width"] for name, v in box["tolerance"].items() if v["half_width"]} == widths


@pytest.mark.parametrize("option, said", [
    ("arm_len=0.2", "--tol: unknown design variable arm_len (known: arm_length, base_angle)"),
    ("arm_length=0", "--tol arm_length=0: the half-width must be a finite number > 0"),
    ("base_angle=inf", "--tol base_angle=inf: the half-width must be a finite number > 0"),
    # beyond what --angle and --length take for a variable of that unit (--angle 91 was refused, --tol 100 not)
    ("base_angle=100", "--tol base_angle=100: a half-width in deg is at most 90 (as --angle takes it)"),
    ("arm_length=1001", "--tol arm_length=1001: a half-width in mm is at most 1000 (as --length takes it)"),
    (("--length", "0", "--angle", "0"), "tolerance: every half-width given is 0 (--length 0, --angle 0): give one "
                                        "above 0, or --samples 0 for the sensitivities alone"),
])
def test_tol_refuses_an_unknown_variable_or_a_non_positive_value(tmp_path, option, said):
    options = ("--tol", option) if isinstance(option, str) else option
    run = agrisynth("tolerance", str(STEERING), *options, "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2, run.stdout + run.stderr
    assert run.stderr.strip() == f"error: {said}"
    assert not (tmp_path / "steering_redesign_27-tolerance").exists()


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_half_width_that_reaches_no_design_variable_is_refused(tmp_path):
    """guide_tube's design variables are its two wall angles: `--length 1` toleranced nothing and the report
    showed an empty box's zero losses without a word.  Refused (exit 2), naming the variables and their units;
    with --angle the same spec is analysed (a box of 0.5 deg on each wall)."""
    spec = LIBRARY / "guide_tube" / "cai2020_tubes.toml"
    run = agrisynth("tolerance", str(spec), "--length", "1", "--samples", "0", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2, run.stdout + run.stderr
    assert run.stderr.strip() == ("error: tolerance: the half-width (length 1 mm) applies to no design variable, so "
                                  "the tolerance box is empty; the design variables: delta_I (deg), delta_II (deg)")
    assert not (tmp_path / "cai2020_tubes-tolerance").exists()
    run = agrisynth("tolerance", str(spec), "--length", "1", "--angle", "0.5", "--samples", "0", "--out",
                    str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    facts = strict_json(tmp_path / "cai2020_tubes-tolerance" / "result.json")["facts"]["tolerance"]
    assert facts["tolerance"] == {"delta_I": {"half_width": 0.5, "unit": "deg"},
                                  "delta_II": {"half_width": 0.5, "unit": "deg"}}


@pytest.mark.parametrize("option, value", [("--length", "nan"), ("--length", "inf"), ("--angle", "nan"),
                                           ("--angle", "-0.1"), ("--length", "1e300"), ("--angle", "91")])
def test_length_and_angle_refuse_a_value_that_is_not_a_finite_half_width(tmp_path, option, value):
    """click's FloatRange(min=0) lets nan and inf through: the analysis then wrote nan margins and exited 1; and
    the options take what a spec's [tolerance] may say (length <= 1000 mm, angle <= 90 deg), not 1e300."""
    run = agrisynth("tolerance", str(STEERING), option, value, "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2, run.stdout + run.stderr
    assert run.stderr.strip().startswith(f"error: Invalid value for '{option}'") and "\n" not in run.stderr.strip()
    assert not (tmp_path / "steering_redesign_27-tolerance").exists()


@pytest.mark.slow
def test_a_box_reaching_zero_for_a_length_is_refused_in_one_line(tmp_path):
    """+-1000 mm on a planting arm's 35-191 mm links: its samples had links of -1865 mm, and its rules were counted
    (the depth held in 5 % of them).  A half-width reaching zero for a variable the kind holds > 0 is refused."""
    spec = LIBRARY / "planting_arm" / "taiwan_example1.toml"
    run = agrisynth("tolerance", str(spec), "--length", "1000", "--samples", "5", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2, run.stdout + run.stderr
    assert run.stderr.strip() == ("error: tolerance: the box reaches -925 mm for l1 (75 mm +- 1000), which must be > 0: "
                                  "give it a half-width below 75 mm")
    assert not (tmp_path / "taiwan_example1-tolerance").exists()
    # the same box with l1 and l2 held tighter passes that check (l2 = 35 mm: the next to reach zero)
    run = agrisynth("tolerance", str(spec), "--length", "30", "--tol", "l1=1", "--samples", "0", "--out",
                    str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr


def test_samples_0_without_a_box_gives_the_sensitivities_and_the_design_s_verdict(tmp_path):
    """--samples 0 with no half-width is "the sensitivities alone": the exit is the design's rules' verdict (the
    library design passes every rule: 0).  It said "every linear worst case in the box holds" of an empty box, its
    report.md that no rule moved with the design and held no derivative w.r.t. the design variables (only
    result.json did); now the verdict is the design's, no row claims a box, and report.md tables every derivative."""
    run = agrisynth("tolerance", str(STEERING), "--samples", "0", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    folder = tmp_path / "steering_redesign_27-tolerance"
    result = strict_json(folder / "result.json")
    facts = result["facts"]["tolerance"]
    assert facts["monte_carlo"]["samples"] == 0 and facts["monte_carlo"]["pass_rate"] is None
    assert all(r["satisfied"] for r in facts["nominal_rules"])
    assert [r["name"] for r in result["rules"]] == [r["name"] for r in facts["nominal_rules"]]     # no @tolerance
    assert run.stdout.startswith("Verdict: holds at the design: it passes every rule (no tolerance box")
    assert "in the box" not in run.stdout and "0.00 %" not in run.stdout
    report = (folder / "report.md").read_text()
    assert report.startswith("Verdict: holds at the design: it passes every rule; no tolerance box, every half-width 0")
    assert report.rstrip().endswith("with no tolerance box there is no stack-up to draw; the tables above are the "
                                    "derivatives")
    assert "does not move with the design" not in report and "linear worst" not in report
    # every derivative result.json holds is in report.md's table, to its 4 digits
    lines = report.splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("| rule | unit | d/d "))
    header, table = lines[at], lines[at + 2:at + 2 + len(facts["stack_up"])]
    rows = {line.split(" | ")[0].lstrip("| "): line for line in table}
    keys = list(facts["tolerance"])
    assert header.split(" | ")[2:] == [f"d/d {k} (per {facts['tolerance'][k]['unit']})" for k in keys[:-1]] + \
        [f"d/d {keys[-1]} (per {facts['tolerance'][keys[-1]]['unit']}) |"]
    for row in facts["stack_up"]:
        cells = [c.strip() for c in rows[row["name"]].strip("| ").split(" | ")][2:]
        assert cells == [f"{row['sensitivity'][k]:.4g}" for k in keys], row["name"]
        assert any(row["sensitivity"].values())


@pytest.mark.slow
def test_the_monte_carlo_counts_per_rule_the_samples_where_the_rule_could_not_be_evaluated(tmp_path):
    """A sample whose design assembles but misses a precision point (P3 not found) has rules without a margin: their
    worst_margin is null, and "unevaluable" (the samples the re-check could not evaluate at all) stayed 0, so the
    file contradicted itself.  Each rule now counts its own; a null worst margin comes with a positive count."""
    run = agrisynth("tolerance", str(LIBRARY / "planting_arm" / "taiwan_example1.toml"), "--length", "4", "--angle",
                    "3", "--samples", "40", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 1, run.stdout + run.stderr
    mc = strict_json(tmp_path / "taiwan_example1-tolerance" / "result.json")["facts"]["tolerance"]["monte_carlo"]
    assert mc["samples"] == 40 and mc["unevaluable"] == 0
    counted = {name: r["unevaluable"] for name, r in mc["rules"].items() if r["unevaluable"]}
    assert counted, "this box should hold samples that miss P3"
    for name, r in mc["rules"].items():
        assert (r["worst_margin"] is None) == (r["unevaluable"] > 0), name
        assert round(r["pass_rate"] * 40) <= 40 - r["unevaluable"], name     # an unevaluated rule never passes
    report = (tmp_path / "taiwan_example1-tolerance" / "report.md").read_text()
    for name, n in counted.items():
        line = next(line for line in report.splitlines() if line.startswith(f"| {name} |"))
        assert f"(not evaluable in {n} of 40 samples: counted as failing)" in line
    # why, counted by reason: in result.json, in report.md and (the top reasons) in the terminal summary
    reasons = mc["unevaluable_reasons"]
    assert reasons[0]["reason"].startswith("P1 not found: the claw does not cross the line 110 mm above the seedbed "
                                           "bottom on its way down between soil exit and entry")
    assert reasons[0]["samples"] == max(counted.values()) and set(reasons[0]["rules"]) <= set(counted)
    assert sum(r["samples"] for r in reasons) >= mc["samples_not_fully_evaluable"] == max(counted.values())
    assert f"| {reasons[0]['samples']} | {reasons[0]['reason']} |" in report
    assert f"{reasons[0]['samples']:>7}  P1 not found: the claw does not cross the line 110 mm" in run.stdout


def test_tol_refuses_a_variable_given_twice(tmp_path):
    run = agrisynth("tolerance", str(STEERING), "--tol", "arm_length=0.2", "--tol", "arm_length=0.3",
                    "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2
    assert run.stderr.strip() == "error: --tol arm_length: given twice (0.2 and 0.3); give each variable once"


@pytest.mark.slow
def test_tolerance_of_a_run_folder_analyses_the_solved_design(tmp_path):
    solve = agrisynth("solve", str(STEERING), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "runs"),
                      cwd=tmp_path)
    assert solve.returncode == 0, solve.stderr
    run_dir = tmp_path / "runs" / "steering_redesign_27"
    solved = json.loads((run_dir / "result.json").read_text())["design"]
    run = agrisynth("tolerance", str(run_dir), "--length", "0.2", "--angle", "0.3", "--samples", "10",
                    "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    data = strict_json(tmp_path / "steering_redesign_27-tolerance" / "result.json")
    assert data["name"] == "steering_redesign_27-tolerance"
    assert data["design"] == pytest.approx({k: solved[k] for k in data["design"]}, rel=1e-12)
    assert data["design"]["arm_length"] != pytest.approx(150.0)       # the solved design, not the spec's start
    assert data["facts"]["tolerance"]["monte_carlo"]["samples"] == 10
    # its result.json names the same run (an independent trial: it was parsed as TOML, "not valid TOML")
    again = agrisynth("tolerance", str(run_dir / "result.json"), "--length", "0.2", "--angle", "0.3", "--samples", "10",
                      "--out", str(tmp_path / "again"), cwd=tmp_path)
    assert again.returncode == run.returncode, again.stderr
    assert strict_json(tmp_path / "again" / "steering_redesign_27-tolerance" / "result.json")["design"] == data["design"]


@pytest.mark.parametrize("status, said", [
    ("interrupted", "an interrupted run, with no solved design (solved.toml) yet: finish it with `agrisynth solve "
                    "SPEC --resume"),
    ("evaluated", "a check's folder, with no solved design: give the spec file it checked"),
    # a tolerance analysis' own folder was called a check's
    ("evaluated+tolerance", "a tolerance analysis' folder, with no solved design: give the run folder or the spec "
                            "file it analysed"),
    ("failed", "no solved.toml in this folder (give a solve's run folder or a spec file)")])
def test_a_folder_without_a_solved_design_says_why_in_one_line(tmp_path, status, said):
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    status, _, facts = status.partition("+")
    (run_dir / "result.json").write_text(json.dumps({"status": status, **({"facts": {facts: {}}} if facts else {})}))
    for target in (run_dir, run_dir / "result.json"):
        run = agrisynth("tolerance", str(target), "--length", "0.2", "--out", str(tmp_path), cwd=tmp_path)
        assert run.returncode == 2 and "Traceback" not in run.stderr
        assert said in " ".join(run.stderr.split())


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_the_tolerance_result_json_holds_the_rows_its_exit_code_reads(tmp_path):
    """`agrisynth tolerance` exits 1 when a Monte-Carlo sample misses a rule (--samples 0: when a linearised worst case
    misses); its result.json said every rule held (only the design's own rules), so `compare` showed the analysis as
    passing.  Now it holds <rule>@monte_carlo rows (the pass rate, satisfied only at 100 %) or, with --samples 0,
    <rule>@tolerance rows (the linear worst margin), and the exit code is 1 exactly when one of its rows fails."""
    solve = agrisynth("solve", str(STEERING), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "runs"),
                      cwd=tmp_path)
    assert solve.returncode == 0, solve.stderr
    run_dir = tmp_path / "runs" / "steering_redesign_27"      # its arm length at the rule's limit
    for samples, suffix in (("100", "@monte_carlo"), ("0", "@tolerance")):
        run = agrisynth("tolerance", str(run_dir), "--length", "0.1", "--samples", samples, "--out",
                        str(tmp_path / samples), cwd=tmp_path)
        data = strict_json(tmp_path / samples / "steering_redesign_27-tolerance" / "result.json")
        rows = {r["name"]: r for r in data["rules"]}
        assert "versions" in data and f"steering_arm_length{suffix}" in rows
        failing = [n for n, r in rows.items() if not r["satisfied"]]
        assert run.returncode == (1 if failing else 0) and failing, (samples, run.stderr, failing)
        mc = data["facts"]["tolerance"]["monte_carlo"]
        if mc["samples"]:
            assert rows["steering_arm_length@monte_carlo"]["value"] == mc["rules"]["steering_arm_length"]["pass_rate"]
            assert mc["pass_rate"] < 1.0
        page = agrisynth("compare", str(run_dir), str(tmp_path / samples / "steering_redesign_27-tolerance"),
                         "--out", str(tmp_path / f"cmp{samples}"), cwd=tmp_path)
        assert page.returncode == 0 and f"{len(failing)} rule(s) violated" in page.stdout, page.stdout + page.stderr


def test_robust_solve_states_the_monte_carlo_pass_rates_in_the_terminal_and_the_report(tmp_path):
    spec = tmp_path / "robust.toml"
    spec.write_text(STEERING.read_text() + "\n[tolerance]\nlength = 0.2\nangle = 0.3\nsamples = 40\nseed = 3\n")
    run = agrisynth("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    mc = json.loads((tmp_path / "out" / "steering_redesign_27" / "result.json").read_text())["facts"]["tolerance"][
        "monte_carlo"]
    assert mc["samples"] == 40 and mc["seed"] == 3 and len(mc["rules"]) == 2
    out = " ".join(run.stdout.split())
    assert f"Monte-Carlo check: 40 samples (seed 3, uniform in the tolerance box): {100 * mc['pass_rate']:.2f} % pass " \
           f"every rule" in out
    page = (tmp_path / "out" / "steering_redesign_27" / "report.html").read_text()
    section = page[page.index("<h2>Tolerance</h2>"):page.index("<h2>Figures</h2>")]
    assert "40 samples (seed 3" in section and f"<b>{100 * mc['pass_rate']:.2f} %</b> pass every rule" in section
    for name, r in mc["rules"].items():
        assert f"{name}: {100 * r['pass_rate']:.2f} % pass" in out
        assert f"<td>{name}</td><td class='num'>{100 * r['pass_rate']:.2f} %</td>" in section


def test_a_robust_answer_whose_monte_carlo_finds_misses_says_so(tmp_path, monkeypatch):
    """The robust solve promises every rule at its linearised worst case; its Monte-Carlo check may still find sampled
    designs that miss a rule (the model is not linear), and then the answer carries a note saying how many and which
    rules, in result.json (solver.status_note) and on the terminal, while the status stays what the rules say.  Here
    the check samples a box 30x the held one, so real samples miss: steering_arm_length's margin is 0.0006 mm at
    the held box's worst corner."""
    from click.testing import CliRunner

    from synthesis.cli import cli
    from synthesis.tolerance import analysis, robust

    real = analysis.monte_carlo
    # the robust solve's own name of it (robust imports it at module level)
    monkeypatch.setattr(robust, "monte_carlo", lambda kind, spec, design, dmap, box, samples, seed, **kw:
                        real(kind, spec, design, dmap, 30.0 * box, samples, seed, **kw))
    spec = tmp_path / "robust.toml"
    spec.write_text(STEERING.read_text() + "\n[tolerance]\nlength = 0.2\nangle = 0.3\nsamples = 40\nseed = 3\n")
    run = CliRunner().invoke(cli, ["solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path)])
    assert run.exit_code == 0, run.output
    data = strict_json(tmp_path / "steering_redesign_27" / "result.json")
    mc = data["facts"]["tolerance"]["monte_carlo"]
    missed = [name for name, r in mc["rules"].items() if r["pass_rate"] < 1.0]
    failing = round(40 * (1.0 - mc["pass_rate"]))
    assert data["status"] == "optimal" and 0 < failing < 40 and "steering_arm_length" in missed
    note = (f"{failing} of 40 Monte-Carlo samples in the tolerance box miss a rule ({', '.join(missed)}). The solve "
            f"holds every rule at its linearised worst case in the box, which does not cover every sampled design")
    assert data["solver"]["status_note"].startswith(note)
    assert "note: " + note in " ".join(run.output.split())


@pytest.mark.slow
def test_a_robust_run_that_fails_its_linearised_worst_case_carries_no_monte_carlo_note(tmp_path):
    """The library's robust clamp cam with an oscillating follower and every angle +-0.3 deg: the fixed timing rows
    cannot hold at their worst case, so the run fails (exit 3) and its note says which rows miss; the Monte-Carlo's
    misses are no news there, and a note saying the worst case holds would contradict it."""
    text = (LIBRARY / "clamp_cam" / "opening_cam_robust_redesign.toml").read_text()
    for old, new in (('type = "translating"\noffset = { init = 0.0, bounds = [-20.0, 20.0] }',
                      'type = "oscillating"\npivot_distance = { init = 120.0, bounds = [80.0, 200.0] }\n'
                      'arm_length = { init = 100.0, bounds = [60.0, 160.0] }'),
                     ("stroke = 10.0", "stroke = 15.0"),
                     ("variables = { base_radius = 0.2, roller_radius = 0.05, offset = 0.2 }\nsamples = 2000",
                      "length = 0.2\nangle = 0.3\nsamples = 50")):
        assert old in text, old
        text = text.replace(old, new, 1)
    spec = tmp_path / "oscillating.toml"
    spec.write_text(text)
    run = agrisynth("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 3, run.stdout + run.stderr
    data = strict_json(tmp_path / "opening_cam_robust_redesign" / "result.json")
    note = data["solver"]["status_note"]
    assert data["status"] == "failed" and "@tolerance" in note and "does not keep its promise" in note
    assert data["facts"]["tolerance"]["monte_carlo"]["pass_rate"] < 1.0 and "Monte-Carlo" not in note


def test_the_monte_carlo_note_names_the_rules_missed_in_evaluated_samples_and_the_unevaluable_apart():
    """A rule's pass rate counts a sample the re-check could not evaluate at all as a miss of every rule: the note
    names only the rules missed where a sample was evaluated, says the unevaluable ones apart, and over an operating
    range says where the samples are re-checked.  No note when every sample passed or none was drawn."""
    from synthesis.tolerance.robust import _sampled_misses

    # 10 samples: 1 unevaluable, 1 more missing rule a only -> a 0.8, b 0.9, all 0.8
    mc = {"samples": 10, "pass_rate": 0.8, "unevaluable": 1,
          "rules": {"a": {"pass_rate": 0.8}, "b": {"pass_rate": 0.9}}}
    assert _sampled_misses(mc).startswith("2 of 10 Monte-Carlo samples in the tolerance box miss a rule (a); 1 of "
                                          "them could not be evaluated at all. The solve holds")
    only = {"samples": 4, "pass_rate": 0.75, "unevaluable": 1, "rules": {}}
    assert _sampled_misses(only).startswith("1 of 4 Monte-Carlo samples in the tolerance box miss a rule: 1 of them "
                                            "could not be evaluated at all.")
    over = {**mc, "envelope": {"points": 26}}
    assert ("miss a rule at the nominal operating point or at a point of the operating range's re-check grid (a)"
            in _sampled_misses(over) and "in the box, at the operating points the NLP samples," in _sampled_misses(over))
    assert _sampled_misses({**mc, "pass_rate": 1.0}) is None and _sampled_misses({"samples": 0, "pass_rate": None}) is None


@pytest.mark.slow
def test_a_tolerance_box_no_design_can_hold_names_the_rule_and_the_tolerance_that_breaks_it(tmp_path):
    """cai2020's crank-rocker at +-5 mm: exit 3; the message names min_transmission_angle@tolerance, by how much its
    linear worst case misses at the elastic re-solve's design (the elastic slack itself), the largest
    contributions (variable and tolerance) and the labelled linear estimate of the box scale that can be met."""
    spec = tmp_path / "impossible.toml"
    spec.write_text((LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").read_text()
                    + "\n[tolerance]\nlength = 5\nangle = 2\nsamples = 20\n")
    run = agrisynth("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert run.returncode == 3, run.stdout + run.stderr
    err = " ".join(run.stderr.split())
    assert "Traceback" not in err
    data = json.loads((tmp_path / "out" / "cai2020_crank_rocker_synthesis" / "result.json").read_text())
    assert "min_transmission_angle" in data["elastic"]["relaxed"] and data["elastic"]["design"]
    m = re.search(r"min_transmission_angle@tolerance: its worst case misses by ([0-9.]+) deg \(nominal margin "
                  r"[-0-9.e]+ deg, lost to the tolerances ([0-9.]+) deg\); largest contributions: (\w+) ±5 mm "
                  r"\(([0-9.]+) deg\)", err)
    assert m, err
    assert float(m[1]) == pytest.approx(data["elastic"]["slacks"]["min_transmission_angle"], rel=0.02)
    assert m[3] in ("l7", "l8", "l9", "l10") and 0 < float(m[4]) <= float(m[2])
    assert "at the elastic re-solve's design" in err
    scale = re.search(r"Linear estimate \(at this design, not a solve\): the box scaled by ([0-9.e-]+) "
                      r"\(lengths ±([0-9.e-]+) mm\)", err)
    assert scale, err
    assert 0 < float(scale[1]) < 1 and float(scale[2]) == pytest.approx(5 * float(scale[1]), rel=0.05)
    assert "angles ±" not in err          # no angle variable: the angle tolerance breaks nothing


def test_a_gap_at_an_unevaluable_corner_says_so_and_is_never_called_second_order():
    """The planting case of "P3 not found" at the linear worst corner: the gap is against the Monte-Carlo samples
    only, and the explanation must say that (not classify it as second order or a kink)."""
    from synthesis.tolerance.analysis import explain_gaps

    kind = SimpleNamespace(solving=lambda: None)          # never re-checked: nothing to evaluate at a corner
    row = {"name": "p2p3_distance", "unit": "mm", "scale": 1.0, "recheck_margin": 0.6, "nominal_margin": 0.6,
           "linear_worst_margin": 0.5, "linear_loss": 0.1, "same_terms": True, "linear_vs_sampled_gap": 0.6,
           "mc_worst_margin": 0.5625, "sampled_worst_margin": 0.5625, "corner": [0.2, -0.3], "corner_margin": None,
           "corner_note": "at the linear worst corner: not evaluated: P3 not found: the claw does not cross the line"}
    explain_gaps(kind, None, {}, None, [row])
    why = row["gap_explanation"]
    assert "not evaluable (not evaluated: P3 not found" in why and "only the Monte-Carlo samples were compared" in why
    assert "second order" not in why and "kink" not in why
    assert "0.0625 mm" in why and "below the worst sample" in why
    assert math.isclose(row["linear_vs_sampled_gap"], 0.6)


def test_a_rule_the_nlp_writes_in_other_terms_shows_the_re_checks_unit_and_no_loss_ratio(tmp_path):
    """opening_cam_redesign's no_undercut: the NLP holds a curvature (unit 1), the re-check reports the radius
    margin in mm (an independent trial: the row read unit "1" above mm numbers, and a loss ratio of the two).  The
    unit column is the re-check's, the linear worst margin's cell names the NLP's terms, no ratio is formed."""
    run = agrisynth("tolerance", str(LIBRARY / "clamp_cam" / "opening_cam_redesign.toml"), "--length", "0.2",
                    "--samples", "20", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    facts = strict_json(tmp_path / "opening_cam_redesign-tolerance" / "result.json")["facts"]["tolerance"]
    row = next(r for r in facts["stack_up"] if r["name"] == "no_undercut")
    assert row["unit"] == "1" and row["recheck_unit"] == "mm" and not row["same_terms"]
    assert row["linear_over_sampled"] is None
    report = (tmp_path / "opening_cam_redesign-tolerance" / "report.md").read_text()
    line = next(l for l in report.splitlines() if l.startswith("| no_undercut | mm |"))
    assert f"{row['linear_worst_margin']:.4g} (NLP's terms, 1)" in line


def test_samples_outside_the_cams_domain_are_unevaluable_not_read_as_designs(tmp_path):
    """opening_cam with base_radius +-49.9 mm: the box keeps r0 > 0 (a box reaching 0 is refused: the radius must be
    > 0), but a sample below the roller's 3.5 mm is no cam; with offset +-60 mm, |offset| >= r0 = 50 mm took a sqrt
    of a negative number (a RuntimeWarning on the terminal, an infinite corner margin in report.md).  Such samples
    are unevaluable, each counted, and the count equals the samples drawn outside the domain (the same default_rng
    draws, recomputed here)."""
    import numpy as np

    for option, width, outside, samples in (("base_radius=49.9", 49.9, lambda d: 50.0 + d <= 3.5, 200),
                                            ("offset=60", 60.0, lambda d: abs(0.0 + d) >= 50.0, 50)):
        out = tmp_path / option.split("=")[0]
        run = agrisynth("tolerance", str(LIBRARY / "clamp_cam" / "opening_cam.toml"), "--tol", option, "--samples",
                        str(samples), "--out", str(out), cwd=tmp_path)
        assert run.returncode == 1 and "RuntimeWarning" not in run.stderr + run.stdout, run.stderr
        facts = strict_json(out / "opening_cam-tolerance" / "result.json")["facts"]["tolerance"]
        keys = list(facts["tolerance"])
        j = keys.index(option.split("=")[0])
        draws = np.random.default_rng(0).uniform(-1.0, 1.0, size=(samples, len(keys)))[:, j] * width
        assert facts["monte_carlo"]["unevaluable"] == sum(bool(outside(d)) for d in draws) > 0
        cells = [c.strip() for c in (out / "opening_cam-tolerance" / "report.md").read_text().split("|")]
        assert "inf" not in cells and "-inf" not in cells and "nan" not in cells


@pytest.mark.slow
def test_guide_tube_equal_times_in_a_tolerance_box_hold_the_spread_limit_at_every_corner(tmp_path):
    """With objective nearest or fastest the NLP pins equal landing times (t_k = t_0), an equality no tolerance box
    can hold at its corners: the robust solve kept it as it was, so the spread limit was never held in the box and
    the solve ended "failed", exit 3, with no box-scale estimate (trial: nearest, +-0.2 deg, 1 ms).  In a box the
    rule's own limit is held at its linearised worst case (Rule.box_rows).  Checked without the linearisation: the
    solved angles at the box's four corners, each evaluated by check, keep the spread within max_time_spread."""
    from itertools import product

    from synthesis import kinds
    from synthesis.spec import load_spec
    from solving import spec_with

    spec = spec_with(tmp_path, LIBRARY / "guide_tube" / "fastest_equal_time.toml",
                     [('name = "fastest"', 'name = "nearest"'),
                      ("[solver]", "[tolerance]\nangle = 0.2\nsamples = 50\n\n[solver]")])
    run = agrisynth("solve", str(spec), "--starts", "2", "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    result = strict_json(tmp_path / "fastest_equal_time" / "result.json")
    assert result["status"] == "optimal"
    rows = {r["name"]: r for r in result["rules"]}
    assert rows["landing_time_spread@tolerance"]["satisfied"]
    solved = (tmp_path / "fastest_equal_time" / "solved.toml").read_text()
    delta = result["design"]
    spreads = []
    for s1, s2 in product((-1, 1), repeat=2):
        corner = {"delta_I": delta["delta_I"] + 0.2 * s1, "delta_II": delta["delta_II"] + 0.2 * s2}
        text = solved
        for name, value in zip(("I", "II"), corner.values()):
            text = re.sub(rf'(name = "{name}"\n(?:[^\[]*?\n)*?angle = )[^\n]+', rf"\g<1>{value!r}", text, count=1)
        path = tmp_path / f"corner_{s1}_{s2}.toml"
        path.write_text(text)
        checked = kinds.checker("guide_tube")(load_spec(path))
        assert checked.design == pytest.approx(corner, abs=1e-12)
        spreads.append(next(r for r in checked.rules if r["name"] == "landing_time_spread")["value"])
    assert max(spreads) <= 0.001
    assert max(spreads) > 0.0005         # the box moves the times: the limit is what holds the corners


LOOP_TOL = """kind = "fourbar_path"
name = "loop_tol"

[targets]
points = [[160.0, 150.0], [157.67, 171.65], [150.45, 179.43], [137.12, 183.64], [100.0, 185.0], [62.88, 183.64],
          [49.55, 179.43], [42.33, 171.65], [40.0, 150.0], [42.33, 128.35], [49.55, 120.57], [62.88, 116.36],
          [100.0, 115.0], [137.12, 116.36], [150.45, 120.57], [157.67, 128.35]]

[linkage]
r1 = 125.03952502879295
r2 = 53.165064514960584
r3 = 95.07636315595138
r4 = 95.38712860553508
rcx = 10.733852264397997
rcy = 43.28018865251051
x0 = 70.61847979236988
y0 = 124.09422657494432
theta0 = -76.36942581854638
branch = 1

[design]
crank_deg = [87.080414654136, 113.92300860711048, 125.52504029038143, 140.13408794791758, 179.8803978529792,
             219.67028380883747, 234.30980651853142, 245.9357262160097, 272.82992424311857, 305.128717627224,
             317.6320468522306, 331.5096831253782, 359.9836281270053, 388.42410126073617, 402.27834115549064,
             414.76977283423474]

[rules]
grashof = "crank_rocker"
transmission_angle = [40, 140]
order = true
"""


def test_samples_0_fails_a_rule_its_linear_worst_corner_breaks(tmp_path):
    """A trial's solved loop (a crank-rocker, transmission angle within [40, 140] deg), box +-0.2 mm / +-0.2 deg:
    the linear stack-up leaves transmission_angle_max +0.0179 deg, the rule re-checked at that corner misses by
    0.0058 deg, and --samples 0 said pass, exit 0.  A corner is a design in the box: now the row fails (exit 1)
    and says why.  Independently of the analysis: a crank-rocker's largest transmission angle is at the crank
    along the frame, cos mu = (r3^2 + r4^2 - (r1 + r2)^2) / (2 r3 r4): 140.0058 deg at r1, r2 + 0.2 and r3, r4 - 0.2."""
    spec = tmp_path / "loop_tol.toml"
    spec.write_text(LOOP_TOL)
    run = agrisynth("tolerance", str(spec), "--length", "0.2", "--angle", "0.2", "--samples", "0", "--out",
                    str(tmp_path), cwd=tmp_path)
    assert run.returncode == 1, run.stdout + run.stderr
    result = strict_json(tmp_path / "loop_tol-tolerance" / "result.json")
    rows = {r["name"]: r for r in result["rules"]}
    assert all(rows[n]["satisfied"] for n in rows if "@" not in n)           # the design itself passes
    row = rows["transmission_angle_max@tolerance"]
    assert row["margin"] == pytest.approx(0.01787, abs=2e-4) and not row["satisfied"]
    r1, r2, r3, r4 = 125.03952502879295, 53.165064514960584, 95.07636315595138, 95.38712860553508
    a, b, diagonal = r3 - 0.2, r4 - 0.2, r1 + r2 + 0.4
    corner = math.degrees(math.acos((a ** 2 + b ** 2 - diagonal ** 2) / (2 * a * b)))
    assert corner - 140.0 == pytest.approx(0.005813, abs=2e-5)
    assert row["note"] == f"re-checked at that corner of the box the rule misses by {corner - 140.0:.4g} deg: a design " \
                          "in the box breaks it"
    assert [n for n, r in rows.items() if not r["satisfied"]] == ["transmission_angle_max@tolerance"]


def test_a_robust_answer_missing_a_rule_at_its_linear_worst_corner_says_so():
    """A trial: combing chain redesign_window_80_100 with chain_speed +-0.01 m/s: window_top held at its linear worst
    case (+1e-7 deg), status optimal, while at that corner (one variable: the box's end) the top of the window is
    100.0029 deg > 100.  The promise stays the linear one; the row and the run's note now say the corner misses."""
    from synthesis.tolerance.robust import _row_note, _sampled_misses

    row = {"name": "window_top", "unit": "deg", "corner_margin": -0.002875}
    note = _row_note(row, "deg", holds=True)
    assert note == ("re-checked at that corner of the box the rule misses by 0.002875 deg: the linear worst case "
                    "holds, the rule curves beyond it")
    assert _row_note(row, "deg", holds=False) is None              # a failed row: the failure says it
    assert _row_note({**row, "corner_margin": 0.001}, "deg", holds=True) is None
    worst = [{"name": "window_top@tolerance", "note": note}, {"name": "window_bottom@tolerance", "note": None}]
    mc = {"samples": 300, "pass_rate": 298 / 300, "rules": {"window_top": {"pass_rate": 298 / 300}}}
    said = _sampled_misses(mc, worst)
    assert said.startswith("2 of 300 Monte-Carlo samples in the tolerance box miss a rule (window_top).")
    assert said.endswith("Re-checked at its linear worst corner of the box, window_top misses (the rows say by how "
                         "much): the linear worst case is what the solve holds, and the rule curves beyond it.")
    # every sample passing (or none drawn), the corner alone is news
    assert _sampled_misses({"samples": 0, "pass_rate": None}, worst).startswith("Re-checked at its linear worst")


def test_a_rule_with_no_linear_driver_is_explained_as_such(tmp_path):
    """The loop's sequence rule (free timing): its NLP rows move with the crank angles only, which the analysis holds
    and the re-check finds anew per sample.  It read "in other terms (11.62 in the NLP's, 11.62 deg in the
    re-check's)", the same numbers; now it says there is no linear driver and what the samples lose."""
    spec = tmp_path / "loop_tol.toml"
    spec.write_text(LOOP_TOL)
    run = agrisynth("tolerance", str(spec), "--length", "0.2", "--angle", "0.2", "--samples", "40", "--out",
                    str(tmp_path), cwd=tmp_path)
    result = strict_json(tmp_path / "loop_tol-tolerance" / "result.json")
    rows = {r["name"]: r for r in result["facts"]["tolerance"]["stack_up"]}
    row = rows["sequence"]
    assert row["linear_loss"] == 0
    lost = row["recheck_margin"] - row["sampled_worst_margin"]
    assert lost > 0
    assert row["gap_explanation"] == (
        "not compared: no linear driver (the rule's first derivatives in the design variables are 0: its NLP rows "
        "move only with the NLP's own variables, e.g. free crank angles, which the re-check finds anew for each "
        f"design, or the design sits at the rule's extremum); the samples lose {lost:.3g} deg")
    # the review: with samples, transmission_angle_max's linear worst corner (140.0058 deg, a design in the box)
    # was ignored and the run exited 0 on the samples' pass rates alone; it fails either way
    verdict = {r["name"]: r for r in result["rules"]}
    corner = verdict["transmission_angle_max@linear_worst_corner"]
    assert not corner["satisfied"] and corner["margin"] == pytest.approx(-0.005813, abs=2e-5)
    assert verdict["transmission_angle_max@monte_carlo"]["satisfied"]       # no sample came near that corner
    assert run.returncode == 1, run.stdout + run.stderr
    # and it says why (a table of 100 % passes exited 1 without a word: the second review)
    assert "failed: transmission_angle_max@linear_worst_corner (misses by 0.005813 deg)" in " ".join(run.stdout.split())


@pytest.mark.parametrize("entry, said", [
    ("l7 = -0.1", "crank_rocker.tolerance.variables.l7: expected > 0, got -0.1"),
    ("l7 = 2000", "crank_rocker.tolerance.variables.l7: expected <= 1000, got 2000"),
    ("l99 = 0.1", "tolerance.variables: unknown design variable l99 (known: l7, l8, l9, l10)"),
])
def test_a_spec_s_per_variable_half_width_is_checked_as_the_option_is(tmp_path, entry, said):
    """A trial: [tolerance] variables = {l7 = -0.1} passed check, crashed solve (ValueError, exit 1) and gave
    tolerance a linear worst case better than the nominal; {l99 = 0.1} passed check while solve refused it.  Each is
    bad input in every command (exit 2), named with the file, as --tol NAME=VALUE is."""
    spec = tmp_path / "cr.toml"
    spec.write_text((LIBRARY / "picker" / "crank_rocker_max_transmission.toml").read_text()
                    + f"\n[tolerance]\nvariables = {{{entry}}}\n")
    for command in (["check", str(spec)], ["solve", str(spec), "--starts", "1", "--workers", "1"],
                    ["tolerance", str(spec), "--samples", "0"]):
        run = agrisynth(*command, "--out", str(tmp_path / "out"), cwd=tmp_path)
        assert run.returncode == 2, (command, run.stdout + run.stderr)
        line = run.stderr.strip()
        assert line.startswith(f"error: {spec}") and said in line and "\n" not in line, (command, line)
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_equal_times_in_a_tolerance_box_over_a_friction_range_are_held_at_each_scenario(tmp_path):
    """The review of Rule.box_rows: an operating range fills its scenarios' values into a rule's rows, and the box
    form was left with the symbol mu in it: IPOPT refused to start ("variables [mu] are free"), a traceback and exit
    1.  Now each scenario's box rows are its own: the run ends with the verdict on its answer (here the box at the
    range's high friction breaks the spread, exit 3, with the box scale that would hold)."""
    from solving import spec_with

    spec = spec_with(tmp_path, LIBRARY / "guide_tube" / "uniform_spacing_mu_envelope.toml",
                     [('name = "uniform"', 'name = "nearest"'),
                      ("[solver]", "[tolerance]\nangle = 0.2\nsamples = 0\n\n[solver]")])
    run = agrisynth("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 3 and "Traceback" not in run.stderr, run.stdout + run.stderr
    result = strict_json(tmp_path / "uniform_spacing_mu_envelope" / "result.json")
    rows = {r["name"]: r for r in result["rules"]}
    assert {"landing_time_spread@mu=0.4848@tolerance", "landing_time_spread@mu=0.7271@tolerance"} <= set(rows)
    assert "the largest uniform scale these rules can be held at" in " ".join(run.stderr.split())


@pytest.mark.parametrize("command", ["check", "tolerance"])
def test_a_spec_tolerance_wider_than_the_options_take_is_refused_by_every_command(tmp_path, command):
    """[tolerance] variables = { base_angle = 100 } passed check and failed tolerance (which --tol now limits as
    --angle): every command reads the spec alike."""
    spec = tmp_path / "wide.toml"
    spec.write_text(STEERING.read_text() + "\n[tolerance]\nvariables = { base_angle = 100.0 }\n")
    run = agrisynth(command, str(spec), "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2, run.stdout + run.stderr
    assert run.stderr.strip().endswith("tolerance.variables.base_angle = 100: a half-width in deg is at most 90 (as "
                                       "--angle takes it)"), run.stderr


def _with_tolerance(tmp_path, table: str, name: str) -> Path:
    """A copy of guide_tube's uniform_spacing with the [tolerance] table ``table``, named ``name``."""
    text = (LIBRARY / "guide_tube" / "uniform_spacing.toml").read_text()
    assert "[tolerance]" not in text
    text = re.sub(r'(?m)^name = ".*"$', f'name = "{name}"', text, count=1)
    path = tmp_path / f"{name}.toml"
    path.write_text(text + f"\n[tolerance]\n{table}\n")
    return path


def test_a_tolerance_table_naming_a_suffix_of_a_design_variable_is_refused_alike_by_every_command(tmp_path):
    """guide_tube's NLP names its angles I and II, its spec delta_I and delta_II: `variables = { I = 0.1 }` was taken
    by check, analysed by tolerance and refused by solve.  Every command now takes the result.json names alone."""
    path = _with_tolerance(tmp_path, "variables = { I = 0.1, II = 0.1 }", "suffix")
    said = f"error: {path}: tolerance.variables: unknown design variable I, II (known: delta_I, delta_II)"
    for command in (["check"], ["tolerance", "--samples", "5"], ["solve", "--starts", "1", "--workers", "1"]):
        run = agrisynth(command[0], str(path), *command[1:], "--out", str(tmp_path / command[0]), cwd=tmp_path)
        assert run.returncode == 2 and run.stderr.strip() == said, (command, run.stderr)
    on_the_line = agrisynth("tolerance", str(LIBRARY / "guide_tube" / "uniform_spacing.toml"), "--tol", "I=0.1",
                            "--out", str(tmp_path / "line"), cwd=tmp_path)
    assert on_the_line.returncode == 2
    assert on_the_line.stderr.strip() == "error: --tol: unknown design variable I (known: delta_I, delta_II)"


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_tolerance_table_of_zero_half_widths_is_named_by_tolerance_and_refused_by_solve(tmp_path):
    """length = 0, angle = 0: tolerance said "give --length and/or --angle (or a [tolerance] table in the spec)" of a
    spec holding one, and solve ran a tolerance-robust solve of an empty box (the nominal one, called robust)."""
    path = _with_tolerance(tmp_path, "length = 0\nangle = 0", "zeros")
    tol = agrisynth("tolerance", str(path), "--out", str(tmp_path / "t"), cwd=tmp_path)
    assert tol.returncode == 2 and tol.stderr.strip() == (
        f"error: {path}: [tolerance] gives no half-width above 0 (tolerance.length = 0, tolerance.angle = 0): give one "
        f"there or with --length, --angle or --tol NAME=VALUE, or --samples 0 for the sensitivities alone")
    solve = agrisynth("solve", str(path), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "s"), cwd=tmp_path)
    assert solve.returncode == 2 and "a tolerance-robust solve needs one" in solve.stderr
    assert not (tmp_path / "s").exists()
    # the command line gives the box: the spec's zeros stand aside, as for any spec without widths
    wide = agrisynth("tolerance", str(path), "--angle", "0.1", "--samples", "5", "--out", str(tmp_path / "w"),
                     cwd=tmp_path)
    assert wide.returncode in (0, 1), wide.stderr


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_tolerance_of_a_guide_way_of_published_conics_says_why_in_the_kinds_words(tmp_path):
    """liang_2z's guide way is the paper's conics: the analysis said "the kind's NLP made no solve call to take its
    start from"; now the kind's own reason.  A spline path left to the convex fit is analysed (its check names the
    fit's control points: it said "the design has no value for P0_x, ...")."""
    conics = agrisynth("tolerance", str(LIBRARY / "guide_way" / "liang_2z.toml"), "--length", "0.1", "--samples", "5",
                       "--out", str(tmp_path), cwd=tmp_path)
    assert conics.returncode == 2 and conics.stderr.strip() == (
        "error: tolerance: guide_way: a guide way of published conics has no NLP to solve or linearise (a [spline] "
        "path has; `agrisynth check` evaluates the conics)")
    spline = agrisynth("tolerance", str(LIBRARY / "guide_way" / "smooth_redesign.toml"), "--length", "0.1",
                       "--samples", "5", "--out", str(tmp_path), cwd=tmp_path)
    assert spline.returncode in (0, 1), spline.stderr
    facts = strict_json(tmp_path / "smooth_redesign-tolerance" / "result.json")["facts"]["tolerance"]
    assert {f"P{j}_{c}" for j in range(24) for c in "xy"} <= set(facts["tolerance"])


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_a_box_reaching_a_non_physical_cam_or_chain_is_refused_as_every_kinds_is(tmp_path):
    """opening_cam's base radius +-100 mm reached -50 mm and the combing chain's speed +-1.5 m/s reached -0.5 m/s:
    both were sampled, evaluated and counted in the pass rates (the fields were not marked > 0, so the planting
    arm's and the comb finger's refusal never fired for them)."""
    for spec, option, said in (
            (LIBRARY / "clamp_cam" / "opening_cam.toml", "base_radius=100",
             "the box reaches -50 mm for base_radius (50 mm +- 100), which must be > 0: give it a half-width below 50 mm"),
            (LIBRARY / "combing_chain" / "redesign_window_80_100.toml", "chain_speed=1.5",
             "the box reaches -0.5 m/s for chain_speed (1 m/s +- 1.5), which must be > 0: give it a half-width below "
             "1 m/s")):
        run = agrisynth("tolerance", str(spec), "--tol", option, "--samples", "5", "--out", str(tmp_path), cwd=tmp_path)
        assert run.returncode == 2 and run.stderr.strip() == f"error: tolerance: {said}", run.stderr


def test_an_acute_angles_box_is_advised_the_half_width_both_ends_allow(tmp_path):
    """steering's base angle 72.4 deg +- 80 was advised "below 72.4 deg"; +- 70 then reached 142.4 deg."""
    run = agrisynth("tolerance", str(LIBRARY / "steering" / "steering_redesign_27.toml"), "--tol", "base_angle=80",
                    "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2 and run.stderr.strip().endswith("must be > 0: give it a half-width below 17.6 deg")
    fine = agrisynth("tolerance", str(LIBRARY / "steering" / "steering_redesign_27.toml"), "--tol", "base_angle=17",
                     "--samples", "5", "--out", str(tmp_path), cwd=tmp_path)
    assert fine.returncode in (0, 1), fine.stderr


def test_a_robust_answer_whose_box_leaves_the_acute_range_is_not_monte_carlo_checked(tmp_path):
    """steering_redesign_27 with [tolerance] angle = 30: the solve ended "optimal" at base_angle 86.7 deg and its
    Monte-Carlo check said 100 % of 50 samples pass, counting designs up to 116.7 deg that the spec refuses
    (`agrisynth tolerance` of that answer refused the same box).  The check is now not run, and says why; a box no
    design in the bounds can hold inside (0, 90) is refused before any start."""
    text = re.sub(r'(?m)^name = ".*"$', 'name = "st_rob"', (LIBRARY / "steering" / "steering_redesign_27.toml").read_text(),
                  count=1)
    spec = tmp_path / "st_rob.toml"
    spec.write_text(text + "\n[tolerance]\nangle = 30.0\nsamples = 50\n")
    run = agrisynth("solve", str(spec), "--starts", "2", "--workers", "1", "--out", str(tmp_path / "s"), cwd=tmp_path)
    assert run.returncode in (0, 1, 3), run.stderr
    mc = strict_json(tmp_path / "s" / "st_rob" / "result.json")["facts"]["tolerance"]["monte_carlo"]
    assert mc["samples"] == 0 and mc["pass_rate"] is None
    assert mc["distribution"].startswith("not run: the box reaches") and "which must be < 90" in mc["distribution"]
    spec.write_text(text + "\n[tolerance]\nangle = 50.0\nsamples = 50\n")
    none = agrisynth("solve", str(spec), "--starts", "2", "--workers", "1", "--out", str(tmp_path / "n"), cwd=tmp_path)
    assert none.returncode == 2 and none.stderr.strip() == (
        f"error: {spec}: [tolerance] +-50 deg on base_angle: no design in its bounds [55, 89] deg keeps the box inside "
        f"(0, 90) (the value must lie between 50 and 40): give base_angle a smaller half-width (tolerance.variables) "
        f"or bounds further from the limit")
    assert not (tmp_path / "n").exists()


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_guide_ways_control_points_are_named_alike_by_every_command(tmp_path):
    """smooth_redesign leaves its control points to the convex fit: `--tol P0_x=0.1` was "unknown" (the check of
    names read the arm's five variables) and `--tol R=0.1` passed that check to be refused by the analysis, naming
    the control points as the known ones.  The names are result.json's (the fit's points written out), and a design
    variable the analysis does not vary is said so."""
    smooth = LIBRARY / "guide_way" / "smooth_redesign.toml"
    point = agrisynth("tolerance", str(smooth), "--tol", "P0_x=0.1", "--samples", "3", "--out", str(tmp_path / "p"),
                      cwd=tmp_path)
    assert point.returncode in (0, 1), point.stderr
    arm = agrisynth("tolerance", str(smooth), "--tol", "R=0.1", "--samples", "3", "--out", str(tmp_path / "r"),
                    cwd=tmp_path)
    assert arm.returncode == 2 and arm.stderr.startswith("error: tolerance: R: no variable this kind's analysis "
                                                         "varies (it varies P0_x, P1_x")
    spec = tmp_path / "points.toml"
    spec.write_text(re.sub(r'(?m)^name = ".*"$', 'name = "points"', smooth.read_text(), count=1)
                    + "\n[tolerance]\nvariables = { P3_x = 0.1 }\n")
    check = agrisynth("check", str(spec), "--out", str(tmp_path / "c"), cwd=tmp_path)
    assert check.returncode in (0, 1) and "unknown design variable" not in check.stderr, check.stderr


@pytest.mark.slow         # seconds: with the slow tests (the quick suite stays under 3 min)
def test_length_on_the_command_line_replaces_a_fitted_control_points_width_from_the_spec(tmp_path):
    """--length replaces the spec's [tolerance] width of every length: a guide way's control point (named as
    result.json names the fit's points) kept its 0.1 mm under --length 0.5."""
    smooth = LIBRARY / "guide_way" / "smooth_redesign.toml"
    spec = tmp_path / "gwp3.toml"
    spec.write_text(re.sub(r'(?m)^name = ".*"$', 'name = "gwp3"', smooth.read_text(), count=1)
                    + "\n[tolerance]\nvariables = { P3_x = 0.1 }\n")
    run = agrisynth("tolerance", str(spec), "--length", "0.5", "--samples", "0", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    box = strict_json(tmp_path / "gwp3-tolerance" / "result.json")["facts"]["tolerance"]["tolerance"]
    assert box["P3_x"]["half_width"] == box["P4_x"]["half_width"] == 0.5


def test_a_combined_picker_with_a_tolerance_table_is_refused_as_a_kind_that_does_not_solve(tmp_path):
    """The robust box's domain check read the spec's variables(), which the combined picker has none of: a traceback
    where solve said the kind has nothing to optimise."""
    for name in ("cai2020_picker.toml", "cai2020_crank_rocker.toml", "cai2020_double_crank.toml"):
        (tmp_path / name).write_text((LIBRARY / "picker" / name).read_text())
    spec = tmp_path / "cai2020_picker.toml"
    spec.write_text(spec.read_text() + "\n[tolerance]\nlength = 0.1\n")
    run = agrisynth("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert run.stderr.startswith("error: kind 'picker' has nothing to optimise")


def test_a_fixed_length_whose_robust_box_reaches_zero_is_refused_naming_its_value(tmp_path):
    """The fixed-value side of the robust box's range check: l2 = 28.5 mm with a +-30 mm box can only sample links
    of -1.5 mm and below."""
    from synthesis.errors import SpecError
    from synthesis.runs.specs import refuse_robust_box_outside
    from synthesis.spec import load_spec

    text = (LIBRARY / "planting_arm" / "robust_redesign_from_example1.toml").read_text()
    spec = tmp_path / "fixed.toml"
    spec.write_text(re.sub(r"(?m)^l2 = .*$", "l2 = 28.5", text, count=1).replace("length = 0.2", "length = 30.0"))
    with pytest.raises(SpecError) as raised:
        refuse_robust_box_outside(load_spec(spec))
    assert str(raised.value) == (f"{spec}: [tolerance] +-30 mm on l2: its value 28.5 mm does not keep the box inside "
                                 f"> 0 (the value must lie above 30): give l2 a smaller half-width (tolerance.variables) "
                                 f"or a value further from the limit")


@pytest.mark.slow         # 6 s: five commands and a solve
def test_a_half_width_of_the_near_dwell_is_refused_by_every_command_and_a_solves_box_sees_it_follow(tmp_path):
    """The near dwell closes the cam's turn: tolerance.variables or --tol giving it a half-width of its own is bad
    input in check, solve and tolerance alike (check ran on, solve refused); a [tolerance] angle that would carry a
    2 deg near dwell below 0 is refused before the solve, naming the segments that move it."""
    robust = (LIBRARY / "clamp_cam" / "opening_cam_robust_redesign.toml").read_text()
    own = tmp_path / "own.toml"
    own.write_text(robust.replace("variables = { base_radius = 0.2,", "variables = { near_dwell = 0.5, base_radius = 0.2,"))
    said = "tolerance.variables: near_dwell follows rise, far_dwell, return (the kind holds it to them)"
    for command in ("check", "solve"):
        run = agrisynth(command, str(own), "--out", str(tmp_path / command), cwd=tmp_path)
        assert run.returncode == 2 and said in run.stderr and "Traceback" not in run.stderr, run.stderr
    run = agrisynth("tolerance", str(LIBRARY / "clamp_cam" / "opening_cam_redesign.toml"), "--tol", "near_dwell=0.5",
                    "--out", str(tmp_path / "t"), cwd=tmp_path)
    assert run.returncode == 2 and "--tol: near_dwell follows rise, far_dwell, return" in run.stderr, run.stderr
    narrow = tmp_path / "narrow.toml"
    narrow.write_text(robust.replace("far_dwell = 160.0", "far_dwell = 304.0").replace("near_dwell = 146.0",
                                                                                      "near_dwell = 2.0")
                      .replace("hold_far = [[186.0, 346.0]]", "hold_far = [[186.0, 300.0]]")
                      .replace("hold_near = [[0.0, 146.0]]", "hold_near = [[0.0, 1.0]]")
                      .replace("variables = {", "angle = 1.0\nvariables = {"))
    run = agrisynth("solve", str(narrow), "--out", str(tmp_path / "n"), cwd=tmp_path)
    assert run.returncode == 2, run.stderr
    assert ("[tolerance] +-3 deg on near_dwell: its value 2 deg does not keep the box inside >= 0 (the value must lie "
            "at or above 3): give rise, far_dwell, return (which near_dwell follows) smaller half-widths") in run.stderr
    # the library's robust cam: a box of lengths alone moves no segment, and nothing says the near dwell follows
    run = agrisynth("solve", str(LIBRARY / "clamp_cam" / "opening_cam_robust_redesign.toml"), "--starts", "1",
                    "--out", str(tmp_path / "r"), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    facts = strict_json(tmp_path / "r" / "opening_cam_robust_redesign" / "result.json")["facts"]["tolerance"]
    assert "follows" not in facts and facts["box"]["near_dwell"] == 0.0
    assert "put it" not in facts["monte_carlo"]["distribution"]


@pytest.mark.parametrize("follows", [5, ["near_dwell"], "near_dwell", {"near_dwell": 5}, None,
                                     {"near_dwell": {"rise": -1.0, "far_dwell": -1.0, "return": -1.0}}])
@pytest.mark.parametrize("box", [5, {"base_radius": "x", "near_dwell": 3.0}, {"base_radius": 0.2, "near_dwell": 3.0}])
def test_a_hand_edited_tolerance_box_or_follows_never_breaks_the_page(follows, box):
    """`compare` takes hand-edited results: a box or follows that is not a table of numbers is left out of the
    tolerance section (a TypeError traceback before), a well-formed one is shown."""
    from synthesis.report.page import tolerance_section
    from synthesis.report.tables import Candidate

    tolerance = {"box": box, "monte_carlo": {"samples": 10, "seed": 0, "distribution": "uniform", "pass_rate": 1.0,
                                             "rules": {"no_undercut": {"pass_rate": 0.5, "worst_margin": -1.0},
                                                       "bad": 5, "worse": {"pass_rate": "x"}}}}
    if follows is not None:
        tolerance["follows"] = follows
    result = SimpleNamespace(extra={"tolerance": tolerance}, design_variables={})
    text = tolerance_section([Candidate("a", result)])
    assert "pass every rule" in text and "<td>no_undercut</td><td class='num'>50.00 %</td>" in text
    assert "<td>bad</td>" not in text and "<td>worse</td><td class='num'>&ndash;</td>" in text
    # the rest of the check hand-edited too: a list of rules, a pass rate of text, unescaped counts
    tolerance["monte_carlo"].update(rules=["no_undercut"], pass_rate="x", samples="<b>", unevaluable="<i>")
    text = tolerance_section([Candidate("a", result)])
    assert "<b>&ndash;</b> pass every rule" in text and "&lt;b&gt; samples" in text and "&lt;i&gt; sample(s)" in text
    if isinstance(box, dict) and box.get("base_radius") == 0.2:
        assert "base_radius ±0.2" in text and "near_dwell ±3" in text
    shown = isinstance(follows, dict) and isinstance(follows.get("near_dwell"), dict) and isinstance(box, dict)
    assert ("(follows rise, far_dwell, return)" in text) == shown and ("(follows" in text) == shown

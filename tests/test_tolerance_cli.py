"""`agrisynth tolerance` and the tolerance-robust `solve` as a user meets them (issue 20): the report with its tornado,
--tol, a run folder as input, the Monte-Carlo pass rates of a robust solve, and the exit 3 of a box no design holds."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from types import SimpleNamespace

import pytest

from solving import cli_run, strict_json

ROOT = Path(__file__).resolve().parents[1]
LIBRARY = ROOT / "problems"
STEERING = LIBRARY / "steering" / "steering_redesign_27.toml"


def test_tolerance_report_embeds_a_tornado_and_tol_sets_one_variable(tmp_path):
    """report.md embeds and links tornado.png (written, a PNG); --tol arm_length=0.5 overrides --length for that
    variable only; every stack-up row's signed contributions add up (in absolute value) to its linear loss, which
    is what the tornado's bars show, and the tornado draws the worst rules first."""
    from synthesis.tolerance.output import tornado_rules

    run = cli_run("tolerance", str(STEERING), "--length", "0.2", "--angle", "0.3", "--tol", "arm_length=0.5",
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


@pytest.mark.parametrize("option, said", [
    ("arm_len=0.2", "--tol: unknown design variable arm_len (known: arm_length, base_angle)"),
    ("arm_length=0", "--tol arm_length=0: the half-width must be a finite number > 0"),
    ("base_angle=inf", "--tol base_angle=inf: the half-width must be a finite number > 0"),
])
def test_tol_refuses_an_unknown_variable_or_a_non_positive_value(tmp_path, option, said):
    run = cli_run("tolerance", str(STEERING), "--tol", option, "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2, run.stdout + run.stderr
    assert run.stderr.strip() == f"error: {said}"
    assert not (tmp_path / "steering_redesign_27-tolerance").exists()


@pytest.mark.parametrize("option, value", [("--length", "nan"), ("--length", "inf"), ("--angle", "nan"),
                                           ("--angle", "-0.1"), ("--length", "1e300"), ("--angle", "91")])
def test_length_and_angle_refuse_a_value_that_is_not_a_finite_half_width(tmp_path, option, value):
    """click's FloatRange(min=0) lets nan and inf through: the analysis then wrote nan margins and exited 1; and
    the options take what a spec's [tolerance] may say (length <= 1000 mm, angle <= 90 deg), not 1e300."""
    run = cli_run("tolerance", str(STEERING), option, value, "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2, run.stdout + run.stderr
    assert run.stderr.strip().startswith(f"error: Invalid value for '{option}'") and "\n" not in run.stderr.strip()
    assert not (tmp_path / "steering_redesign_27-tolerance").exists()


def test_samples_0_exits_on_the_design_and_its_linear_worst_cases(tmp_path):
    """--samples 0 runs no Monte-Carlo: the exit is the nominal rules' and the linear worst cases' verdict (the
    library design passes every rule with nothing toleranced: 0), and the report says no sample was drawn rather
    than "0.00 % pass"."""
    run = cli_run("tolerance", str(STEERING), "--samples", "0", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    facts = strict_json(tmp_path / "steering_redesign_27-tolerance" / "result.json")["facts"]["tolerance"]
    assert facts["monte_carlo"]["samples"] == 0 and facts["monte_carlo"]["pass_rate"] is None
    assert all(r["satisfied"] for r in facts["nominal_rules"])
    assert all(row["linear_worst_margin"] >= 0 for row in facts["stack_up"])
    assert "Monte-Carlo: none (--samples 0)" in run.stdout and "0.00 %" not in run.stdout


def test_the_monte_carlo_counts_per_rule_the_samples_where_the_rule_could_not_be_evaluated(tmp_path):
    """A sample whose design assembles but misses a precision point (P3 not found) has rules without a margin: their
    worst_margin is null, and "unevaluable" (the samples the re-check could not evaluate at all) stayed 0, so the
    file contradicted itself.  Each rule now counts its own; a null worst margin comes with a positive count."""
    run = cli_run("tolerance", str(LIBRARY / "planting_arm" / "taiwan_example1.toml"), "--length", "4", "--angle", "3",
                  "--samples", "40", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 1, run.stdout + run.stderr
    mc = strict_json(tmp_path / "taiwan_example1-tolerance" / "result.json")["facts"]["tolerance"]["monte_carlo"]
    assert mc["samples"] == 40 and mc["unevaluable"] == 0
    counted = {name: r["unevaluable"] for name, r in mc["rules"].items() if r["unevaluable"]}
    assert counted, "this box should hold samples that miss P3"
    for name, r in mc["rules"].items():
        assert (r["worst_margin"] is None) == (r["unevaluable"] > 0), name
        assert round(r["pass_rate"] * 40) <= 40 - r["unevaluable"], name     # an unevaluated rule never passes
    for name, n in counted.items():
        assert f"| {name} |" in run.stdout and f"(not evaluable in {n} of 40 samples: counted as failing)" in run.stdout


def test_tol_refuses_a_variable_given_twice(tmp_path):
    run = cli_run("tolerance", str(STEERING), "--tol", "arm_length=0.2", "--tol", "arm_length=0.3",
                  "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode == 2
    assert run.stderr.strip() == "error: --tol arm_length: given twice (0.2 and 0.3); give each variable once"


def test_tolerance_of_a_run_folder_analyses_the_solved_design(tmp_path):
    solve = cli_run("solve", str(STEERING), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "runs"),
                    cwd=tmp_path)
    assert solve.returncode == 0, solve.stderr
    run_dir = tmp_path / "runs" / "steering_redesign_27"
    solved = json.loads((run_dir / "result.json").read_text())["design"]
    run = cli_run("tolerance", str(run_dir), "--length", "0.2", "--angle", "0.3", "--samples", "10",
                  "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    data = strict_json(tmp_path / "steering_redesign_27-tolerance" / "result.json")
    assert data["name"] == "steering_redesign_27-tolerance"
    assert data["design"] == pytest.approx({k: solved[k] for k in data["design"]}, rel=1e-12)
    assert data["design"]["arm_length"] != pytest.approx(150.0)       # the solved design, not the spec's start
    assert data["facts"]["tolerance"]["monte_carlo"]["samples"] == 10
    # its result.json names the same run (an independent trial: it was parsed as TOML, "not valid TOML")
    again = cli_run("tolerance", str(run_dir / "result.json"), "--length", "0.2", "--angle", "0.3", "--samples", "10",
                    "--out", str(tmp_path / "again"), cwd=tmp_path)
    assert again.returncode == run.returncode, again.stderr
    assert strict_json(tmp_path / "again" / "steering_redesign_27-tolerance" / "result.json")["design"] == data["design"]


@pytest.mark.parametrize("status, said", [
    ("interrupted", "an interrupted run, with no solved design (solved.toml) yet: finish it with `agrisynth solve "
                    "SPEC --resume"),
    ("evaluated", "a check's folder, with no solved design: give the spec file it checked"),
    ("failed", "no solved.toml in this folder (give a solve's run folder or a spec file)")])
def test_a_folder_without_a_solved_design_says_why_in_one_line(tmp_path, status, said):
    run_dir = tmp_path / "run"
    run_dir.mkdir()
    (run_dir / "result.json").write_text(json.dumps({"status": status}))
    for target in (run_dir, run_dir / "result.json"):
        run = cli_run("tolerance", str(target), "--length", "0.2", "--out", str(tmp_path), cwd=tmp_path)
        assert run.returncode == 2 and "Traceback" not in run.stderr
        assert said in " ".join(run.stderr.split())


def test_the_tolerance_result_json_holds_the_rows_its_exit_code_reads(tmp_path):
    """`agrisynth tolerance` exits 1 when a Monte-Carlo sample misses a rule (--samples 0: when a linearised worst case
    misses); its result.json said every rule held (only the design's own rules), so `compare` showed the analysis as
    passing.  Now it holds <rule>@monte_carlo rows (the pass rate, satisfied only at 100 %) or, with --samples 0,
    <rule>@tolerance rows (the linear worst margin), and the exit code is 1 exactly when one of its rows fails."""
    solve = cli_run("solve", str(STEERING), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "runs"),
                    cwd=tmp_path)
    assert solve.returncode == 0, solve.stderr
    run_dir = tmp_path / "runs" / "steering_redesign_27"      # its arm length at the rule's limit
    for samples, suffix in (("100", "@monte_carlo"), ("0", "@tolerance")):
        run = cli_run("tolerance", str(run_dir), "--length", "0.1", "--samples", samples, "--out",
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
        page = cli_run("compare", str(run_dir), str(tmp_path / samples / "steering_redesign_27-tolerance"),
                       "--out", str(tmp_path / f"cmp{samples}"), cwd=tmp_path)
        assert page.returncode == 0 and f"{len(failing)} rule(s) violated" in page.stdout, page.stdout + page.stderr


def test_robust_solve_states_the_monte_carlo_pass_rates_in_the_terminal_and_the_report(tmp_path):
    spec = tmp_path / "robust.toml"
    spec.write_text(STEERING.read_text() + "\n[tolerance]\nlength = 0.2\nangle = 0.3\nsamples = 40\nseed = 3\n")
    run = cli_run("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "out"), cwd=tmp_path)
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
    from synthesis.tolerance import analysis

    real = analysis.monte_carlo
    monkeypatch.setattr(analysis, "monte_carlo", lambda kind, spec, design, dmap, box, samples, seed, **kw:
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
    run = cli_run("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path), cwd=tmp_path)
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


def test_a_tolerance_box_no_design_can_hold_names_the_rule_and_the_tolerance_that_breaks_it(tmp_path):
    """cai2020's crank-rocker at +-5 mm: exit 3; the message names min_transmission_angle@tolerance, by how much its
    linear worst case misses at the elastic re-solve's design (the elastic slack itself), the largest
    contributions (variable and tolerance) and the labelled linear estimate of the box scale that can be met."""
    spec = tmp_path / "impossible.toml"
    spec.write_text((LIBRARY / "picker" / "cai2020_crank_rocker_synthesis.toml").read_text()
                    + "\n[tolerance]\nlength = 5\nangle = 2\nsamples = 20\n")
    run = cli_run("solve", str(spec), "--starts", "1", "--workers", "1", "--out", str(tmp_path / "out"), cwd=tmp_path)
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

    kind = SimpleNamespace(solver_side=lambda: None)          # never re-checked: nothing to evaluate at a corner
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
    run = cli_run("tolerance", str(LIBRARY / "clamp_cam" / "opening_cam_redesign.toml"), "--length", "0.2",
                  "--samples", "20", "--out", str(tmp_path), cwd=tmp_path)
    assert run.returncode in (0, 1), run.stderr
    facts = strict_json(tmp_path / "opening_cam_redesign-tolerance" / "result.json")["facts"]["tolerance"]
    row = next(r for r in facts["stack_up"] if r["name"] == "no_undercut")
    assert row["unit"] == "1" and row["recheck_unit"] == "mm" and not row["same_terms"]
    assert row["linear_over_sampled"] is None
    line = next(l for l in run.stdout.splitlines() if l.startswith("| no_undercut | mm |"))
    assert f"{row['linear_worst_margin']:.4g} (NLP's terms, 1)" in line


def test_samples_outside_the_cams_domain_are_unevaluable_not_read_as_designs(tmp_path):
    """opening_cam with base_radius +-100 mm: the box reaches radii below 0, which the formulas read as |r0| (an
    independent trial: counted as evaluated, 0 unevaluable); with offset +-60 mm, |offset| >= r0 = 50 mm took a
    sqrt of a negative number (a RuntimeWarning on the terminal, an infinite corner margin in report.md).  Such
    samples are unevaluable, each counted, and the count equals the samples drawn outside the domain (the same
    default_rng draws, recomputed here)."""
    import numpy as np

    for option, width, outside in (("base_radius=100", 100.0, lambda d: 50.0 + d <= 3.5),
                                   ("offset=60", 60.0, lambda d: abs(0.0 + d) >= 50.0)):
        out = tmp_path / option.split("=")[0]
        run = cli_run("tolerance", str(LIBRARY / "clamp_cam" / "opening_cam.toml"), "--tol", option, "--samples", "50",
                      "--out", str(out), cwd=tmp_path)
        assert run.returncode == 1 and "RuntimeWarning" not in run.stderr + run.stdout, run.stderr
        facts = strict_json(out / "opening_cam-tolerance" / "result.json")["facts"]["tolerance"]
        keys = list(facts["tolerance"])
        j = keys.index(option.split("=")[0])
        draws = np.random.default_rng(0).uniform(-1.0, 1.0, size=(50, len(keys)))[:, j] * width
        assert facts["monte_carlo"]["unevaluable"] == sum(bool(outside(d)) for d in draws) > 0
        cells = [c.strip() for c in (out / "opening_cam-tolerance" / "report.md").read_text().split("|")]
        assert "inf" not in cells and "-inf" not in cells and "nan" not in cells

"""`agrisynth tolerance` in a user's terms: the Monte-Carlo on the core's process pool gives every sample the verdict
the kind's own re-check gives it alone, the terminal summary fits one screen, and a sample that cannot be evaluated
says why in words (counted by reason)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from synthesis import kinds
from synthesis.core.kind import Setting
from synthesis.core.outcome import StartOutcome
from synthesis.errors import AgrisynthError
from synthesis.kinds.planting.scene import PlantingScene, find_precision_points
from synthesis.spec import load_spec
from synthesis.tolerance.analysis import Sample, analyse, check_samples, linearise, monte_carlo, unevaluable_reasons
from synthesis.tolerance.design import box_of
from synthesis.tolerance.output import WIDTH, full_table, table

LIBRARY = Path(__file__).resolve().parents[1] / "problems"


def _one_by_one(kind, spec, design, keys, offsets):
    """The per-sample path: each sample re-checked alone by the kind, in this process (the analysis before the pool)."""
    solving = kind.solving()
    setting = Setting(spec, 0, solving.prepare(spec))
    verdicts = []
    for i, row in enumerate(offsets):
        trial = {**design, **{k: design[k] + float(o) for k, o in zip(keys, row)}}
        try:
            records = [r.record() for r in solving.recheck(setting, StartOutcome(i, trial, 0.0, "", True, 0, 0.0,
                                                                                 "")).rules]
        except (AgrisynthError, ValueError, ArithmeticError) as exc:
            verdicts.append(" ".join(str(exc).split()))
            continue
        verdicts.append({r.name: (r.margin, bool(r.satisfied)) for r in records})
    return verdicts


@pytest.mark.parametrize("spec, length, angle, samples", [
    # a box as wide as the arm length's margin: about half the samples miss a rule
    ("steering/steering_redesign_40.toml", 60.0, 3.0, 40),
    # a box where some samples miss P1 (rules not evaluable), the design itself failing two rules
    pytest.param("planting_arm/taiwan_example1.toml", 4.0, 3.0, 24, marks=pytest.mark.slow),
])
def test_the_pooled_monte_carlo_gives_every_sample_its_own_re_check_s_verdict(spec, length, angle, samples):
    """Two workers, one worker and the kind's re-check of each sample alone: the same margin and verdict of every
    rule in every sample, so the same result.json numbers (everything but the wall time)."""
    loaded = load_spec(LIBRARY / spec)
    kind = kinds.get(loaded.kind)
    lin = linearise(kind, loaded.model, kind.check(loaded).design)
    box = box_of(lin.dmap, length, angle, {})
    offsets = np.random.default_rng(0).uniform(-1.0, 1.0, size=(samples, lin.dmap.n)) * box
    solving = kind.solving()
    setting = Setting(loaded.model, 0, solving.prepare(loaded.model))
    pooled = check_samples(solving, setting, lin.design, lin.dmap.keys, offsets, workers=2)
    alone = check_samples(solving, setting, lin.design, lin.dmap.keys, offsets, workers=1)
    assert pooled == alone and len(pooled) == samples
    reference = _one_by_one(kind, loaded.model, lin.design, lin.dmap.keys, offsets)
    assert [s.raised if s.rules is None else {n: (m, ok) for n, m, ok, _ in s.rules} for s in pooled] == reference
    verdicts = [s.rules is not None and all(ok for _, _, ok, _ in s.rules) for s in pooled]
    # samples that differ in which rules they hold: the comparison means something
    assert len({tuple(ok for _, _, ok, _ in s.rules) for s in pooled}) > 1
    two, one = (monte_carlo(kind, loaded.model, lin.design, lin.dmap, box, samples, 0, workers=w) for w in (2, 1))
    two.pop("wall_s"), one.pop("wall_s")
    assert two == one and two["pass_rate"] == sum(verdicts) / samples


def test_a_sample_that_raises_is_counted_with_its_reason():
    """A sample the re-check cannot evaluate at all is counted as such, with the kind's message as its reason, in
    the same place whatever the number of workers (the fourbar_path linkage that cannot assemble)."""
    checked = [Sample(None, "linkage cannot assemble at any crank angle: l1 - l2 = 80 mm > l3 + l4 = 70 mm"),
               Sample([("a", 1.0, True, None)]),
               Sample(None, "linkage cannot assemble at any crank angle: l1 - l2 = 82.5 mm > l3 + l4 = 70 mm")]
    assert unevaluable_reasons(checked) == [
        {"reason": "linkage cannot assemble at any crank angle: l1 - l2 = 80 to 82.5 mm > l3 + l4 = 70 mm",
         "samples": 2, "rules": ["(every rule)"]}]


def test_reasons_are_counted_by_their_cause_with_the_figures_as_ranges():
    """A rule whose note ends in another rule's note ("P2 not searched: P3 not found: ...") is counted under that
    cause; reasons that differ only in their figures are one, the figures shown as their range; most frequent
    first; P3 and P2 are names, not figures."""
    p3 = "P3 not found: the claw never reaches the seedbed bottom between soil exit and entry: its tip stays {} mm above it"
    p1 = ("P1 not found: the claw does not cross the line 110 mm above the seedbed bottom on its way down between soil "
          "exit and entry")

    def sample(lowest):
        why = p3.format(lowest)
        return Sample([("p2_speed", None, False, f"P2 not searched: {why}"), ("accel_hold", None, False, why),
                       ("planting_depth", 5.0, True, None)])

    checked = [sample(4.1), Sample([("p1p3_distance", None, False, p1)]), sample(0.3), sample(2.0)]
    assert unevaluable_reasons(checked) == [
        {"reason": p3.format("0.3 to 4.1"), "samples": 3, "rules": ["p2_speed", "accel_hold"]},
        {"reason": p1, "samples": 1, "rules": ["p1p3_distance"]}]


@pytest.mark.parametrize("moved, said", [
    ({"zeta": -98.9}, "P3 not found: the claw enters the soil (crank angle 205.7 deg) before it comes down to the "
                      "seedbed bottom (207.0 deg)"),
    ({"seedbed_y": -30.0}, "P3 not found: the claw never reaches the seedbed bottom between soil exit and entry: its "
                           "tip stays 6.4 mm above it"),
])
def test_a_missing_p3_says_what_the_claw_does(moved, said):
    """"the claw does not cross the line 0 mm above the seedbed bottom" was all a user read of 7 % of the samples of a
    planting redesign at +-1 mm / +-1 deg: now the reason says what the tip does (example 1's redesign, rounded)."""
    spec = load_spec(LIBRARY / "planting_arm" / "redesign_from_example1.toml").model
    design = {"l1": 75.0, "l2": 28.5, "l3": 65.3, "l4": 69.5, "l5": 181.6, "zeta": -96.9, "phi": 34.3,
              "seedbed_x": -191.1, "seedbed_y": -5.5, "seedbed_tilt": -34.4}
    assert find_precision_points(PlantingScene.from_spec(spec, design)).theta["P3"] is not None
    points = find_precision_points(PlantingScene.from_spec(spec, {**design, **moved}))
    assert points.theta["P3"] is None and points.problems["P3"] == said
    assert points.problems["P2"] == f"P2 not searched: {said}"


def _facts_with(rows: int, failing: int, reasons: int) -> dict:
    """Facts of a design with ``rows`` rules, the first ``failing`` missed in some samples, and ``reasons`` long
    reasons for unevaluable samples."""
    def row(k):
        return {"name": f"a_rather_long_rule_name_{k:02d}", "unit": "mm/s^2", "scale": 1.0, "recheck_margin": 1234.5,
                "linear_worst_margin": -12.5 + k, "mc_pass_rate": 0.5 + 0.01 * k if k < failing else 1.0,
                "mc_worst_margin": -3.25, "drivers": [{"variable": f"seedbed_tilt_{j}", "contribution": 1.5 - j}
                                                      for j in range(3)],
                "contributions": {f"seedbed_tilt_{j}": 1.5 - j for j in range(3)}, "corner_margin": 1.0,
                "linear_over_sampled": 1.25, "linear_vs_sampled_gap": 0.05, "mc_unevaluable": 0}
    mc = {"samples": 1000, "seed": 0, "distribution": "uniform in the tolerance box", "pass_rate": 0.3,
          "unevaluable": 3 if reasons else 0, "samples_not_fully_evaluable": 70 if reasons else 0,
          "rules": {f"a_rather_long_rule_name_{k:02d}": {"pass_rate": 0.5 + 0.01 * k if k < failing else 1.0,
                                                        "worst_margin": -3.25, "unevaluable": 0} for k in range(rows)},
          "unevaluable_reasons": [{"reason": "P3 not found: the claw enters the soil (crank angle 203.1 to 207.2 deg) "
                                             "before it comes down to the seedbed bottom (203.5 to 212 deg) " * 2,
                                   "samples": 40 - k, "rules": ["p2_speed"]} for k in range(reasons)]}
    return {"design": {}, "nominal_rules": [], "tolerance": {f"v{k}": {"half_width": 0.5, "unit": "mm"}
                                                             for k in range(12)},
            "stack_up": [row(k) for k in range(rows)], "monte_carlo": mc}


@pytest.mark.parametrize("rows, failing, reasons", [(13, 3, 0), (40, 20, 9), (5, 0, 0)])
def test_the_summary_fits_one_screen_and_the_full_table_is_in_the_report(rows, failing, reasons):
    """At most 100 columns and about 25 lines however many rules fail or reasons there are: the verdict, the
    rules that decide it, the top reasons; report.md's table has every rule and every reason."""
    facts = _facts_with(rows, failing, reasons)
    text = table(facts)
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= WIDTH
    assert len(lines) <= 30 if reasons else len(lines) <= 25
    assert lines[0] == (f"Verdict: FAILS in the tolerance box: {failing} rule(s) break" if failing else
                        "Verdict: holds: the design and all 1000 samples pass every rule; no linear worst corner "
                        "breaks one") + ("; some samples cannot be evaluated" if reasons else "")
    assert ("Monte-Carlo: 1000 samples (seed 0): 30.00 % pass every rule"
            + ("; 70 (7.0%) not fully evaluable (failing)" if reasons else "\n")) in text
    assert f"({rows - max(3, min(failing, 6))} more rule(s) in report.md)" in text
    if reasons:
        assert "     40  P3 not found: the claw enters the soil (crank angle 203.1 to 207.2 deg) before it" in text
        assert f"({reasons - 3} more reason(s) in report.md)" in text
    report = full_table(facts)
    assert all(f"| a_rather_long_rule_name_{k:02d} |" in report for k in range(rows))
    assert report.count("| p2_speed |") == reasons


def test_the_summary_of_a_real_analysis_names_its_failing_rule_and_what_to_tighten():
    """steering_redesign_40 in a box as wide as its arm length's margin (+-60 mm, +-3 deg): the rules its samples miss
    are named with the share of samples, marked in the table, and the largest driver is the first to tighten."""
    loaded = load_spec(LIBRARY / "steering/steering_redesign_40.toml")
    kind = kinds.get(loaded.kind)
    facts = analyse(kind, loaded.model, kind.check(loaded).design, length=60.0, angle=3.0, samples=40, seed=0)
    text = table(facts)
    lines = text.splitlines()
    assert max(len(line) for line in lines) <= WIDTH and len(lines) <= 25
    missed = {n: r for n, r in facts["monte_carlo"]["rules"].items() if r["pass_rate"] < 1.0}
    assert missed
    for name, r in missed.items():
        assert f"  {name}: in {100 * (1 - r['pass_rate']):.1f} % of the samples" in text
        assert any(line.startswith(name) and " FAIL " in line and f"{r['pass_rate']:.1%}" in line for line in lines)
    assert "report.md" in lines[-1] + lines[-2]
    first = next(x for x in facts["stack_up"] if x["name"] in missed)
    assert first["drivers"][0]["variable"] in text.split("Tighten first")[1].split("\n")[0]


def test_a_linear_worst_margin_in_the_nlps_terms_is_marked_in_the_terminal_as_in_the_report():
    """A cam's no_undercut: its re-check in mm, its stack-up in the NLP's ratio (unit 1).  The terminal showed
    "mm  margin -2.228  lin. worst -0.546" -- a worst case that read better than the nominal -- where report.md says
    "(NLP's terms, 1)"."""
    facts = _facts_with(3, 1, 0)
    facts["stack_up"][0].update(name="no_undercut", unit="1", recheck_unit="mm", same_terms=False,
                                recheck_margin=-2.228, linear_worst_margin=-0.546)
    lines = table(facts).splitlines()
    row = next(line for line in lines if line.startswith("no_undercut"))
    assert " mm " in row and "-2.228" in row and "-0.546*" in row
    assert "* lin. worst in the NLP's terms of the rule, not the unit shown: no_undercut (1)" in lines
    assert "| no_undercut | mm | -2.228 | -0.546 (NLP's terms, 1) |" in full_table(facts)
    assert max(len(line) for line in lines) <= WIDTH
    others = [line for line in lines if line.startswith("a_rather_long_rule_name")]
    assert others and not any("*" in line for line in others)

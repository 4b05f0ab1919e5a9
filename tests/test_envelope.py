"""Operating envelopes: the core's multi-scenario NLP on a problem with a closed-form answer,
the range spec, and the planting envelope redesign re-checked at every 0.01 m/s, independently of the solver
(the kind's float ``check`` of the spec at each forward speed: root-found precision points, no NLP)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from synthesis.constraints.base import Rule
from synthesis import kinds
from synthesis.core.ipopt import CompiledNLP
from synthesis.core.problem import Envelope, ObjectiveParts, Operating, Problem
from synthesis.kinds import solve_spec
from synthesis.spec import LoadedSpec, load_spec
from synthesis.spec.operating import at_operating, ranges_of

LIBRARY = Path(__file__).resolve().parents[1] / "problems"


def _toy(envelope, structural_on_v: bool = False):
    """min x s.t. x >= v^2 (rule 'floor', reads the operating condition v) and x <= 10 ('cap', does not)."""
    x, v = ca.SX.sym("x"), ca.SX.sym("v")
    structural = [(x - v, None, 100.0)] if structural_on_v else []
    return Problem("toy", x, [0.0], [20.0], structural,
                   [Rule("floor", x - v * v, 0.0, None, "-", 1.0), Rule("cap", x, None, 10.0, "-", 1.0)],
                   ObjectiveParts(f=x), operating=[Operating("v", v, 1.5)], envelope=envelope)


def test_envelope_replicates_only_the_rules_that_read_a_sampled_condition():
    nominal = CompiledNLP(_toy(None))
    assert [r.name for r in nominal.rules] == ["floor", "cap"]
    assert nominal.solve(0, [5.0]).x[0] == pytest.approx(1.5**2, abs=1e-6)     # x = v_nominal^2
    env = CompiledNLP(_toy(Envelope({"v": (1.0, 1.5, 2.0)})))
    assert [r.name for r in env.rules] == ["floor@v=1", "floor@v=1.5", "floor@v=2", "cap"]
    out = env.solve(0, [5.0])
    assert out.success and out.x[0] == pytest.approx(4.0, abs=1e-6)            # the worst scenario, v = 2
    assert env.active_rules(out) == ["floor@v=2"]
    # the elastic form names the scenario that conflicts: cap 10 against x >= v^2 at v = 4
    elastic = CompiledNLP(_toy(Envelope({"v": (1.0, 4.0)})), elastic=True)
    slacks = elastic.slack_values(elastic.solve(0, [5.0]).x)
    assert slacks["floor@v=1"] == pytest.approx(0.0, abs=1e-6)
    assert slacks["floor@v=4"] + slacks["cap"] == pytest.approx(6.0, abs=1e-5)


def test_an_epigraph_objective_is_the_worst_over_the_envelope():
    """min tau s.t. tau >= (x - v)^2 (objective rows): v in {1, 3} -> x = 2, tau = 1; the nominal v = 1.5 alone:
    x = 1.5, tau = 0."""
    def problem(envelope):
        x, tau, v = ca.SX.sym("x"), ca.SX.sym("tau"), ca.SX.sym("v")
        objective = ObjectiveParts(f=tau, extra=tau, extra_lb=[0.0], extra_ub=[np.inf], extra_init=[10.0],
                                   rows=[(tau - (x - v) ** 2, 0.0, None)])
        return Problem("minmax", x, [-10.0], [10.0], [], [Rule("cap", x, None, 5.0, "-", 1.0)], objective,
                       operating=[Operating("v", v, 1.5)], envelope=envelope)

    out = CompiledNLP(problem(Envelope({"v": (1.0, 3.0)}))).solve(0, [0.0])
    assert out.success and out.x[0] == pytest.approx(2.0, abs=1e-6) and out.objective == pytest.approx(1.0, abs=1e-6)
    out = CompiledNLP(problem(None)).solve(0, [0.0])
    assert out.x[0] == pytest.approx(1.5, abs=1e-5) and out.objective == pytest.approx(0.0, abs=1e-8)


def test_structural_rows_may_not_read_a_sampled_condition():
    with pytest.raises(ValueError, match=r"structural rows \[0\] depend on a condition the envelope samples \(v\)"):
        _toy(Envelope({"v": (1.0, 2.0)}), structural_on_v=True)
    with pytest.raises(ValueError, match="the envelope samples w, which the problem does not depend on"):
        _toy(Envelope({"w": (1.0, 2.0)}))


def test_range_spec_grids():
    loaded = load_spec(LIBRARY / "planting_arm/envelope_redesign_from_example1.toml")
    spec = loaded.model
    assert spec.operation.forward_speed == 0.6                    # check, figures and objective read the nominal
    (field, rng), = ranges_of(spec).values()
    assert field == "operation"
    assert rng.solver_values() == pytest.approx((0.5, 0.5 + 0.25 / 3, 0.5 + 0.5 / 3, 0.75), abs=1e-15)
    grid = rng.recheck_values()
    assert len(grid) == 26 and grid[0] == 0.5 and grid[-1] == 0.75
    assert np.allclose(np.diff(grid), 0.01, atol=1e-12)
    at = at_operating(spec, {"forward_speed": 0.71})
    assert at.operation.forward_speed == 0.71 and ranges_of(at) == {} and ranges_of(spec) != {}


def _check_at(loaded, design: dict, **operating: float) -> dict:
    """The kind's float check (no NLP) of ``design`` at the operating values given (forward_speed=0.6,
    crank_speed=250): name -> record."""
    spec = at_operating(loaded.model, operating)
    arm = {k: design[k] for k in ("l1", "l2", "l3", "l4", "l5", "zeta", "phi")}
    seedbed = {k: design[f"seedbed_{k}"] for k in ("x", "y", "tilt")}
    spec = spec.model_copy(update={"arm": spec.arm.model_copy(update=arm),
                                   "seedbed": spec.seedbed.model_copy(update=seedbed)})
    result = kinds.get("planting_fourbar").check(LoadedSpec(spec, loaded.path, loaded.sha256))
    return {r["name"]: r for r in result.rules}


@pytest.fixture(scope="module")
def example1_solved():
    """(nominal spec, its one-start redesign, envelope spec, its one-start envelope redesign) of example 1."""
    nominal_loaded = load_spec(LIBRARY / "planting_arm/redesign_from_example1.toml")
    env_loaded = load_spec(LIBRARY / "planting_arm/envelope_redesign_from_example1.toml")
    nominal, _, _ = solve_spec(nominal_loaded, starts=1, workers=1)
    envelope, _, _ = solve_spec(env_loaded, starts=1, workers=1)
    return nominal_loaded, nominal, env_loaded, envelope


@pytest.mark.slow
def test_planting_envelope_design_holds_at_every_speed_where_the_nominal_redesign_does_not(example1_solved):
    speeds = [round(0.50 + 0.01 * k, 2) for k in range(26)]
    nominal_loaded, nominal, env_loaded, envelope = example1_solved
    assert nominal.status == envelope.status == "optimal"
    # the envelope's NLP held entry angle and P4P6 at 4 speeds; the result's re-check at 26
    names = [r["name"] for r in envelope.rules]
    assert {"entry_angle@envelope", "p4p6_distance@envelope"} <= set(names)
    assert not any(n.endswith("@envelope") for n in names if n.split("@")[0] not in ("entry_angle", "p4p6_distance"))
    table = envelope.extra["envelope"]["rules"]
    assert len(table["entry_angle"]["values"]) == 26 and envelope.extra["envelope"]["all_satisfied"]

    nominal_fails, entry, p4p6 = [], [], []
    for v in speeds:
        n = _check_at(nominal_loaded, nominal.design, forward_speed=v)
        if not (n["entry_angle"]["satisfied"] and n["p4p6_distance"]["satisfied"]):
            nominal_fails.append(v)
        e = _check_at(env_loaded, envelope.design, forward_speed=v)
        assert all(r["satisfied"] for r in e.values()), (v, [r["name"] for r in e.values() if not r["satisfied"]])
        entry.append(e["entry_angle"]["value"])
        p4p6.append(e["p4p6_distance"]["value"])
    # the nominal redesign (designed at 0.6 m/s) enters too flat above 0.70 m/s: 77.4 deg at 0.75
    assert nominal_fails == [0.71, 0.72, 0.73, 0.74, 0.75]
    at_end = _check_at(nominal_loaded, nominal.design, forward_speed=0.75)
    assert at_end["entry_angle"]["value"] == pytest.approx(77.40, abs=0.01)
    # the envelope design: entry angle >= 80 deg and P4P6 >= 20 mm at every 0.01 m/s; the binding end is the
    # fast one for the entry angle (kept 0.2 deg = the back-off inside), the slow one for P4P6
    assert min(entry) >= 80.0 and min(p4p6) >= 20.0
    assert int(np.argmin(entry)) == 25 and min(entry) == pytest.approx(80.2, abs=1e-3)
    assert int(np.argmin(p4p6)) == 0
    # the result's own table agrees with the independent check
    assert np.allclose(table["entry_angle"]["values"], entry, atol=1e-9)
    assert np.allclose(table["p4p6_distance"]["values"], p4p6, atol=1e-9)
    # and the price of the envelope in the objective
    assert envelope.objective["value"] > nominal.objective["value"]



@pytest.mark.parametrize("example, first_fail, entry_at_075, p4p6_min", [(3, 0.69, 76.591, 29.421), (4, 0.66, 75.272, 26.359)])
@pytest.mark.slow
def test_planting_envelope_redesigns_of_examples_3_and_4(example, first_fail, entry_at_075, p4p6_min):
    """The nominal redesign enters too flat from ``first_fail`` m/s on; the envelope design
    passes every rule at every 0.01 m/s (start 0 is the best of the spec's 16 starts for both)."""
    speeds = [round(0.50 + 0.01 * k, 2) for k in range(26)]
    nominal_loaded = load_spec(LIBRARY / f"planting_arm/redesign_from_example{example}.toml")
    env_loaded = load_spec(LIBRARY / f"planting_arm/envelope_redesign_from_example{example}.toml")
    nominal, _, _ = solve_spec(nominal_loaded, starts=1, workers=1)
    envelope, _, _ = solve_spec(env_loaded, starts=1, workers=1)
    assert nominal.status == envelope.status == "optimal"
    nominal_fails, entry, p4p6 = [], [], []
    for v in speeds:
        n = _check_at(nominal_loaded, nominal.design, forward_speed=v)
        failed = [name for name, r in n.items() if not r["satisfied"]]
        assert failed in ([], ["entry_angle"]), (v, failed)
        if failed:
            nominal_fails.append(v)
        e = _check_at(env_loaded, envelope.design, forward_speed=v)
        assert all(r["satisfied"] for r in e.values()), (v, [r["name"] for r in e.values() if not r["satisfied"]])
        entry.append(e["entry_angle"]["value"])
        p4p6.append(e["p4p6_distance"]["value"])
    assert nominal_fails == [v for v in speeds if v >= first_fail]
    at_end = _check_at(nominal_loaded, nominal.design, forward_speed=0.75)
    assert at_end["entry_angle"]["value"] == pytest.approx(entry_at_075, abs=0.01)
    assert int(np.argmin(entry)) == 25 and min(entry) == pytest.approx(80.2, abs=1e-3)
    assert int(np.argmin(p4p6)) == 0 and min(p4p6) == pytest.approx(p4p6_min, abs=0.01)
    assert envelope.objective["value"] > nominal.objective["value"]


def _ode_spread_mm(design: dict, mu: float, spacing: float) -> float:
    """Plant-position error (0.5 m/s x landing-time spread of tubes I and II) by the ODE twin of the drop
    (scipy integration of the printed equations of motion, not the closed form the NLP and check use)."""
    from synthesis.kinds.guide_tube.drop import Physics, Tube
    from synthesis.kinds.guide_tube.ode import simulate

    physics = Physics(0.6, 9.8, 17.5, mu)
    scale = (300.0 - spacing) / 70.0                 # l3 shifts with the row spacing (GUIDE_TUBE.md)
    times = [simulate(design[f"delta_{name}"], Tube(name, l3 * scale * 1e-3, 0.04, 0.21), physics).landing_time
             for name, l3 in (("I", 105.0), ("II", 35.0))]
    return 500.0 * abs(times[0] - times[1])


@pytest.mark.slow
def test_guide_tube_envelope_keeps_the_stated_error_at_every_mu_where_the_nominal_design_does_not(tmp_path):
    from solving import spec_with

    source = LIBRARY / "guide_tube/uniform_spacing_mu_envelope.toml"
    envelope, _, _ = solve_spec(load_spec(source), starts=1, workers=1)
    fixed = spec_with(tmp_path, source, [("mu = { range = [0.48476005, 0.72714007], samples = 3, nominal = 0.60595006 }",
                                          "mu = 0.60595006")])
    nominal, _, _ = solve_spec(load_spec(fixed), starts=1, workers=1)
    assert envelope.status == nominal.status == "optimal"
    # min-max over 3 mu x 8 spacings: 5.681 mm; designed at the nominal mu only: 4.999 mm there
    assert envelope.objective["value"] == pytest.approx(5.68133, abs=1e-4)
    assert nominal.objective["value"] == pytest.approx(4.99898, abs=1e-4)
    mus = np.linspace(0.48476005, 0.72714007, 21)
    spacings = [230.0, 240.0, 250.0, 260.0, 270.0, 280.0, 290.0, 300.0 - 1e-6]
    env = np.array([[_ode_spread_mm(envelope.design, m, w) for w in spacings] for m in mus])
    nom = np.array([[_ode_spread_mm(nominal.design, m, w) for w in spacings] for m in mus])
    assert env.max() <= 6.0 and env.max() == pytest.approx(5.6813, abs=2e-3)
    assert nom.max() > 6.0 and nom.max() == pytest.approx(6.5266, abs=2e-3)
    assert nom[-1].max() == nom.max()                    # the nominal design misses at mu + 20 %
    assert nom[10].max() == pytest.approx(4.999, abs=2e-3)
    # the result's own re-check over 21 mu agrees
    table = envelope.extra["envelope"]["rules"]["spacing_error"]
    assert len(table["values"]) == 21 and max(table["values"]) == pytest.approx(env.max(), abs=2e-3)


@pytest.mark.slow
def test_envelope_run_folder_through_the_cli(tmp_path):
    """`agrisynth solve` of an envelope spec: exit 0, result.json with facts.envelope (every re-check point of mu)
    and the @envelope rows for the solution and the given design, envelope.png beside the report."""
    import os
    import subprocess
    import sys

    from solving import strict_json

    # a process of its own: what the terminal shows is read as a user sees it, whatever earlier in-process runs left
    run = subprocess.run([sys.executable, "-m", "synthesis.cli", "solve",
                          str(LIBRARY / "guide_tube/uniform_spacing_mu_envelope.toml"), "--out", str(tmp_path),
                          "--starts", "1"], cwd=tmp_path, capture_output=True, text=True, timeout=600,
                         env={k: v for k, v in os.environ.items() if k != "COLUMNS"})   # piped: 120 wide
    assert run.returncode == 0, run.stderr
    folder = tmp_path / "uniform_spacing_mu_envelope"
    assert (folder / "envelope.png").stat().st_size > 0 and "envelope.png" in (folder / "report.html").read_text()
    result = strict_json(folder / "result.json")
    assert result["schema_version"] == 5 and result["status"] == "optimal"
    env = result["facts"]["envelope"]
    mus = env["conditions"]["mu"]["recheck_values"]
    assert len(mus) == 21 and mus[0] == 0.48476005 and mus[-1] == 0.72714007 and len(env["grid"]) == 21
    assert env["conditions"]["mu"]["solver_values"] == pytest.approx([0.48476005, 0.60595006, 0.72714007])
    rows = {r["name"]: r for r in result["rules"]}
    assert rows["spacing_error@envelope"]["satisfied"] and rows["spacing_error@envelope"]["value"] <= 6.0
    assert max(env["rules"]["spacing_error"]["values"]) == pytest.approx(rows["spacing_error@envelope"]["value"])
    # the given angles (45 / 41 deg) miss the stated error over the envelope: 12.4 mm, in the terminal's table
    assert "spacing_error@envelope" in run.stdout and "12.36" in run.stdout


@pytest.mark.slow
def test_planting_crank_speed_envelope_holds_at_every_2_rpm_where_the_nominal_redesign_does_not():
    """200-300 r/min at 0.6 m/s, re-checked every 2 r/min by the float check; the 2 mm seedling clearance keeps P1 a
    crossing (without it one start ends on a loop that only touches the seedling-top line: no P1 in the re-check)."""
    rpms = [200.0 + 2.0 * k for k in range(51)]
    nominal_loaded = load_spec(LIBRARY / "planting_arm/redesign_from_example1.toml")
    env_loaded = load_spec(LIBRARY / "planting_arm/crank_speed_envelope_redesign_from_example1.toml")
    nominal, _, _ = solve_spec(nominal_loaded, starts=1, workers=1)
    envelope, _, _ = solve_spec(env_loaded, starts=1, workers=1)
    assert nominal.status == envelope.status == "optimal"
    assert envelope.extra["envelope"]["all_satisfied"]
    nominal_fails, entry, p4p6 = [], [], []
    for rpm in rpms:
        n = _check_at(nominal_loaded, nominal.design, crank_speed=rpm)
        nominal_fails += [rpm] if not all(r["satisfied"] for r in n.values()) else []
        e = _check_at(env_loaded, envelope.design, crank_speed=rpm)
        assert all(r["satisfied"] for r in e.values()), (rpm, [r["name"] for r in e.values() if not r["satisfied"]])
        entry.append(e["entry_angle"]["value"])
        p4p6.append(e["p4p6_distance"]["value"])
    # the nominal redesign (250 r/min only) enters too flat below 220 r/min: 77.4 deg at 200
    assert nominal_fails and max(nominal_fails) < 220.0
    at_end = _check_at(nominal_loaded, nominal.design, crank_speed=200.0)
    assert at_end["entry_angle"]["value"] == pytest.approx(77.4, abs=0.05)
    assert min(entry) >= 80.0 and min(p4p6) >= 20.0 and int(np.argmin(entry)) == 0
    table = envelope.extra["envelope"]["rules"]
    assert np.allclose(table["entry_angle"]["values"], entry, atol=1e-9)
    assert envelope.objective["value"] > nominal.objective["value"]
    # the ground-frame path depends on the forward speed only through v / omega (the plant spacing): 200-300 r/min
    # at 0.6 m/s spans the spacings of 0.50-0.75 m/s at 250 r/min (120-180 mm), and the rules that read omega alone
    # (P2 speed >= 1.137 m/s, the accelerations) do not bind, so both envelopes give the same design
    assert envelope.objective["value"] == pytest.approx(0.5695780708252276, rel=1e-6)
    assert min(entry) == pytest.approx(80.2, abs=1e-3)


@pytest.mark.slow
def test_seedling_clearance_keeps_p1_a_crossing(tmp_path):
    """The crank-speed envelope from start 0 of a 230-270 r/min range without a clearance ends with the loop's top
    on the seedling-top line (P1 a tangency: P1 not found by the float check); with 2 mm start 0 finds it.  (Without
    the clearance the run is no longer 'failed': the elastic re-solve needs no slack, and the start solved from its
    design crosses the line.)"""
    from solving import spec_with
    source = LIBRARY / "planting_arm/crank_speed_envelope_redesign_from_example1.toml"
    narrow = "crank_speed = { range = [230, 270], samples = 4, nominal = 250, step = 4 }"
    old = "crank_speed = { range = [200, 300], samples = 4, nominal = 250, step = 2 }"
    touching = spec_with(tmp_path, source, [(old, narrow), ("seedling_clearance = 2", "seedling_clearance = 0")])
    clear = spec_with(tmp_path, source, [(old, narrow)], name="clear.toml")
    bad, bad_starts, _ = solve_spec(load_spec(touching), starts=1, workers=1)
    good, _, _ = solve_spec(load_spec(clear), starts=1, workers=1)
    p1 = next(r for r in bad_starts[0].records if r.name == "p1p3_distance")
    assert not bad_starts[0].satisfied and p1.value is None and "P1 not found" in (p1.note or "")
    assert bad.status == "optimal" and bad.solver["best_start"] == 1
    assert bad_starts[1].outcome.details["start_from"] == "elastic re-solve"
    assert good.status == "optimal" and good.solver["best_start"] == 0


ENVELOPE_SPEC = LIBRARY / "planting_arm/envelope_redesign_from_example1.toml"
FORWARD_RANGE = "forward_speed = { range = [0.50, 0.75], samples = 4, nominal = 0.6, step = 0.01 }"


@pytest.mark.slow
def test_check_of_a_range_spec_says_it_evaluated_the_nominal_point_only(tmp_path):
    """check reads a range's nominal value: it says so, and its verdict names the nominal point, instead of
    "every rule satisfied" for a design that may fail inside the range."""
    from solving import agrisynth
    run = agrisynth("check", str(ENVELOPE_SPEC), "--out", str(tmp_path), cwd=tmp_path)
    out = " ".join(run.stdout.split())
    assert "forward_speed given as a range: check evaluates the nominal value only" in out
    assert "violated at the nominal operating point" in out or "every rule satisfied at the nominal operating point" in out
    plain = agrisynth("check", str(LIBRARY / "planting_arm/redesign_from_example1.toml"), "--out", str(tmp_path),
                      cwd=tmp_path)
    assert "nominal operating point" not in plain.stdout and "given as a range" not in plain.stdout


@pytest.mark.parametrize("replacement, message", [
    # two ranges of 50 samples: 2,500 scenarios and ~2.6e5 re-check points
    (("crank_speed = 250", "crank_speed = { range = [200, 300], samples = 50, step = 0.01 }"),
     "forward_speed, crank_speed: 200 scenarios and 260026 re-check points together (at most 200 and 20000)"),
    # samples closer than the 4 significant digits that name a scenario's rules
    ((FORWARD_RANGE, "forward_speed = { range = [0.6, 0.60001], samples = 4 }"),
     "forward_speed: samples = 4 over [0.6, 0.60001] are not distinct to 4 significant digits"),
])
def test_range_sizes_that_would_blow_up_or_merge_scenarios_are_refused(tmp_path, replacement, message):
    from solving import agrisynth, spec_with
    run = agrisynth("check", str(spec_with(tmp_path, ENVELOPE_SPEC, [replacement])), "--out", str(tmp_path),
                    cwd=tmp_path)
    assert run.returncode == 2 and message in " ".join(run.stderr.split()), run.stderr
    assert "Traceback" not in run.stderr and len(run.stderr.strip().splitlines()) == 1


def test_a_malformed_range_of_a_field_that_takes_ranges_is_not_called_one_value(tmp_path):
    """forward_speed takes a range: a range of one number is named as that, never "takes one value" (which a
    clamp_cam crank_speed range is told: test_clamp_cam_cli)."""
    from solving import agrisynth, spec_with
    bad = (FORWARD_RANGE, "forward_speed = { range = [0.5], samples = 3 }")
    run = agrisynth("check", str(spec_with(tmp_path, ENVELOPE_SPEC, [bad])), "--out", str(tmp_path), cwd=tmp_path)
    err = " ".join(run.stderr.split())
    assert run.returncode == 2 and "forward_speed.range: expected [lo, hi] (two numbers), got [0.5]" in err, err
    assert "takes one value" not in err


@pytest.mark.slow
def test_monte_carlo_of_an_envelope_design_checks_every_operating_point(example1_solved, tmp_path):
    """The Monte-Carlo of a spec with an operating range re-checks each sampled design (uniform in the
    tolerance box) at the nominal point and at every point of the re-check grid; a sample passes when every rule
    holds at all of them.  Re-done independently: the same samples (default_rng(seed)) through the kind's float
    check at each forward speed of the grid.  The nominal redesign (entry angle too flat above 0.70 m/s) passes at
    0.6 m/s as often as the envelope redesign but never over 0.50-0.75 m/s; the envelope redesign does.  The grid is
    coarsened to 0.05 m/s (6 points) to keep the test short."""
    from solving import spec_with
    from synthesis.spec.design_info import describe
    from synthesis.tolerance.analysis import monte_carlo
    from synthesis.tolerance.design import DesignMap, box_of

    nominal_loaded, nominal, env_loaded, envelope = example1_solved
    coarse = load_spec(spec_with(tmp_path, LIBRARY / "planting_arm/envelope_redesign_from_example1.toml",
                                 [("step = 0.01", "step = 0.05")]))
    speeds = [0.5, 0.55, 0.6, 0.65, 0.7, 0.75]
    info = describe(coarse.model)
    keys = list(info)
    dmap = DesignMap(keys, keys, [info[k]["unit"] for k in keys], np.zeros(len(keys)), np.eye(len(keys)))
    box = box_of(dmap, 0.2, 0.3, {})
    samples, seed = 12, 3
    offsets = np.random.default_rng(seed).uniform(-1.0, 1.0, size=(samples, len(keys))) * box
    kind = kinds.solving_kind("planting_fourbar")
    rates = {}
    for label, result in (("nominal", nominal), ("envelope", envelope)):
        design = {k: float(result.design[k]) for k in keys}
        mc = monte_carlo(kind, coarse.model, design, dmap, box, samples, seed)
        assert mc["envelope"]["points"] == 6 and mc["envelope"]["conditions"] == {"forward_speed": [0.5, 0.75]}
        assert "every one of the 6 points" in mc["distribution"]
        over, at_nominal = 0, 0
        for row in offsets:
            trial = {k: design[k] + float(o) for k, o in zip(keys, row)}
            checks = [_check_at(coarse, trial, forward_speed=v) for v in speeds]
            over += all(r["satisfied"] for c in checks for r in c.values())
            at_nominal += all(r["satisfied"] for r in checks[2].values())
        assert mc["pass_rate"] == over / samples, label
        assert mc["envelope"]["pass_rate_at_nominal"] == at_nominal / samples, label
        rates[label] = (mc["pass_rate"], mc["envelope"]["pass_rate_at_nominal"], mc["rules"]["entry_angle@envelope"])
    # measured (seeded): 6 of the 12 samples pass at 0.6 m/s for either design (the box is wider than either
    # design's margins on the collinearity and transmission-angle rules); over the range the nominal redesign keeps
    # none (its entry angle is below 80 deg at the fast end in every sample, worst -2.91 deg), the envelope one 6
    # (its entry angle holds over the range in 10 of 12; the misses lose the 0.2 deg back-off and more: -0.126 deg)
    assert rates["nominal"][:2] == (0.0, 0.5) and rates["nominal"][2]["pass_rate"] == 0.0
    assert rates["nominal"][2]["worst_margin"] == pytest.approx(-2.907, abs=2e-3)
    assert rates["envelope"][:2] == (0.5, 0.5) and rates["envelope"][2]["pass_rate"] == 10 / 12
    assert rates["envelope"][2]["worst_margin"] == pytest.approx(-0.1257, abs=2e-4)


def test_the_given_design_of_a_spec_whose_variable_has_a_toml_alias_is_read():
    """clamp_cam's return angle is written ``motion.return`` (attribute ``return_``): the envelope's baseline read the
    given design by walking the TOML path, an AttributeError after every start of
    opening_cam_redesign_spring_dynamics had finished (exit 1, a traceback, no result)."""
    from synthesis.tolerance.envelope import given_design

    loaded = load_spec(LIBRARY / "clamp_cam" / "opening_cam_redesign_spring_dynamics.toml")
    design = given_design(loaded.model)
    assert design["return"] == 14.0 == loaded.model.motion.return_
    assert set(design) == set(loaded.model.variables())

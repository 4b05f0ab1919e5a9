"""fourbar_path: kinematics identities, exact transmission extremes, the rules against the independent
oracle, AD derivatives, spec errors, the picking-arc baseline's points."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from fourbar_path_support import PATH_LIBRARY, cli, independent_check, toml_text, transmission_deg
from synthesis.errors import SpecError
from synthesis.kinds.fourbar_path.check import evaluate
from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.kinds.fourbar_path.nlp import PathNLP
from synthesis.kinds.fourbar_path.synthetic import random_crank_rocker, truth_data, truth_spec
from synthesis.kinds.picker.kinematics.arc import picking_arc
from synthesis.kinds.fourbar_path.kinematics import (BRANCHES, coupler_function, cos_transmission, design_parameters,
                                                joints as symbolic_joints)
from synthesis.spec import load_spec
from synthesis.spec.common import FreeVariable, validate
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

THETA = np.linspace(0.0, 2 * math.pi, 37)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("branch", [1, -1])
def test_closed_form_coupler_point_equals_the_complex_number_construction(seed, branch):
    design, _ = random_crank_rocker(seed)
    p = np.array(design_parameters(design), dtype=float)
    closed = np.asarray(coupler_function(branch)(THETA.reshape(1, -1), p)[0])
    z = joint_positions(design, THETA, branch)
    assert np.max(np.abs(closed[0] - z["P"].real)) < 1e-10
    assert np.max(np.abs(closed[1] - z["P"].imag)) < 1e-10
    # loop closure of the construction itself: |AB| = r3, |O'B| = r4, |OA| = r2, |OO'| = r1
    for (a, b), length in ((("A", "B"), "r3"), (("O'", "B"), "r4"), (("O", "A"), "r2"), (("O", "O'"), "r1")):
        assert np.max(np.abs(np.abs(z[a] - z[b]) - design[length])) < 1e-10


def test_open_branch_keeps_the_links_uncrossed_at_90_degrees():
    design, _ = random_crank_rocker(3)
    j = symbolic_joints(math.pi / 2, design_parameters(design), 1)
    a, b, o, o2 = (np.array(j[k], dtype=float) for k in ("A", "B", "O", "O'"))

    def side(p):
        u, w = o2 - a, p - a
        return np.sign(u[0] * w[1] - u[1] * w[0])

    assert side(b) == -side(o) != 0          # B and O on opposite sides of the diagonal A O'


@pytest.mark.parametrize("seed", range(4))
def test_transmission_extremes_over_a_turn_are_at_0_and_180_degrees(seed):
    design, _ = random_crank_rocker(seed)
    r = [design[k] for k in ("r1", "r2", "r3", "r4")]
    grid = np.linspace(0.0, 2 * math.pi, 7200, endpoint=False)
    mu = transmission_deg(joint_positions(design, grid, 1))
    assert mu.min() == pytest.approx(math.degrees(math.acos(cos_transmission(0.0, *r))), abs=1e-9)
    assert mu.max() == pytest.approx(math.degrees(math.acos(cos_transmission(math.pi, *r))), abs=1e-9)
    assert np.argmin(mu) == 0 and grid[np.argmax(mu)] == pytest.approx(math.pi)


@pytest.mark.parametrize("seed", range(12))
def test_the_rules_on_floats_agree_with_the_independent_oracle(seed):
    """check and the re-check evaluate rules.path_rules (closed forms) on floats; the oracle measures the
    same things on the textbook construction.  Even seeds: the synthetic crank-rockers at their own crank
    angles; odd seeds: random lengths (often no crank-rocker, the loop open somewhere)."""
    spec = truth_spec(seed, 6, timed=False).model
    design, phase = random_crank_rocker(seed)
    if seed % 2:
        rng = np.random.default_rng(seed)
        design.update(zip(("r1", "r2", "r3", "r4"), (float(r) for r in rng.uniform(5.0, 60.0, 4))))
    crank = list(phase + 60.0 * np.arange(6))
    rules = {r.name: r.record() for r in evaluate(spec, design, crank, timing="solved").rules}
    oracle = independent_check(spec, design, crank)
    assert rules["grashof"].satisfied == (oracle["textbook_grashof"] >= 0.0)
    assert rules["sequence"].value == pytest.approx(oracle["written_out_order"], abs=1e-9) == 60.0
    error = evaluate(spec, design, crank, timing="solved").sum_sq
    if math.isfinite(oracle["path_error_mm2"]):
        assert error == pytest.approx(oracle["path_error_mm2"], rel=1e-9, abs=1e-12)
    else:
        assert not rules["assembly"].satisfied
    if rules["grashof"].satisfied:
        # a crank-rocker: closure everywhere, the exact extremes are the measured extremes (0 and 180 on the grid)
        assert rules["assembly"].satisfied and oracle["measured_closure"] >= 0.0
        assert rules["transmission_angle_min"].value == pytest.approx(30.0 + oracle["measured_transmission_min"],
                                                                      abs=1e-9)
        assert rules["transmission_angle_max"].value == pytest.approx(150.0 - oracle["measured_transmission_max"],
                                                                      abs=1e-9)
    else:
        assert oracle["measured_closure"] < 0.0         # a crank that cannot turn: the loop opens somewhere
    if seed % 2 == 0:
        assert error < 1e-20 and all(r.satisfied for r in rules.values())


@pytest.mark.parametrize("timed", [True, False])
def test_nlp_derivatives_match_central_differences(timed):
    nlp = PathNLP(truth_spec(2, 6, timed).model)
    t = nlp.compiled.t                    # the transcribed NLP IPOPT sees: w = (design, crank angles)
    sign = nlp.problem.parameters
    rng = np.random.default_rng(0)
    lo, hi = nlp.bounds[:, 0], nlp.bounds[:, 1]
    design = lo + (0.3 + 0.4 * rng.random(9)) * (hi - lo)
    design[:4] = [40.0, 12.0, 45.0, 35.0]        # a crank-rocker: every row is defined
    x = np.concatenate([design, np.sort(rng.uniform(0, 6, nlp.n_theta))])
    assert t.w.numel() == x.size == 9 + (0 if timed else 6)
    grad = ca.Function("J", [t.w, sign], [ca.jacobian(ca.vertcat(t.f, t.g), t.w)])
    J = np.asarray(grad(x, 1.0))
    fg_function = ca.Function("fg", [t.w, sign], [ca.vertcat(t.f, t.g)])

    def fg(z):
        return np.ravel(np.asarray(fg_function(z, 1.0)))

    fd = np.zeros_like(J)
    for k in range(x.size):
        h = 1e-6 * max(1.0, abs(x[k]))
        e = np.zeros_like(x)
        e[k] = h
        fd[:, k] = (fg(x + e) - fg(x - e)) / (2 * h)
    assert np.max(np.abs(J - fd) / np.maximum(np.abs(J), 1.0)) < 1e-6


def test_transmission_rows_are_degrees_at_the_limit():
    """The NLP rows of the transmission rules are cos mu scaled to degrees at the limit, so a row's margin,
    its back-off and an elastic slack are in the rule's unit: one degree inside the limit is a row of 1
    (to first order: 1.0103 at 40 deg)."""
    from synthesis.kinds.fourbar_path.rules.transmission_turn import transmission_turn_rules

    lo, hi = 40.0, 140.0
    rmin, rmax = transmission_turn_rules(math.cos(math.radians(41.0)), math.cos(math.radians(139.0)), (lo, hi))
    (row_min, lb_min, _), = rmin.rows()
    (row_max, lb_max, _), = rmax.rows()
    assert lb_min == lb_max == 0.0
    assert row_min == pytest.approx(1.0103, abs=1e-4) and row_max == pytest.approx(1.0103, abs=1e-4)
    assert rmin.record().value == pytest.approx(41.0) and rmax.record().margin == pytest.approx(1.0)


@pytest.mark.parametrize("open_somewhere", [False, True])
def test_the_vectorised_numeric_rules_equal_the_per_sample_ones(open_somewhere):
    """The re-check evaluates thousands of samples of closure and transmission as numpy vectors (rules.path_rules on
    numbers); the per-sample form (a list, one expression per sample, as the NLP builds them) must give the same
    records to the bit and the same row values, including a motion where the loop opens (transmission not
    evaluated, closure violated)."""
    from synthesis.kinds.fourbar_path.rules.assembly import assembly_rule
    from synthesis.kinds.fourbar_path.rules.transmission_turn import transmission_sampled_rules

    rng = np.random.default_rng(7)
    r = (30.0, 12.0, 35.0, 10.0) if open_somewhere else (30.0, 8.0, 14.0, 31.0)     # r3 < r4, |r3 - r4| binds
    angles = rng.uniform(-2.0 * math.pi, 4.0 * math.pi, 500)
    d2 = [r[0] ** 2 + r[1] ** 2 - 2.0 * r[0] * r[1] * math.cos(a) for a in angles]
    cs = [cos_transmission(a, *r) for a in angles]
    pairs = [(assembly_rule(d2, r[2], r[3], "w"), assembly_rule(np.array(d2), r[2], r[3], "w"))]
    pairs += zip(transmission_sampled_rules(cs, (35.0, 145.0)), transmission_sampled_rules(np.array(cs), (35.0, 145.0)))
    def row_values(rule, interleaved=False):     # the list form has the two closure rows of a sample side by side
        rows = [np.ravel(np.asarray(e, float)) for e, _, _ in rule.rows()]
        return np.column_stack(rows).ravel() if interleaved else np.concatenate(rows)

    for listed, vector in pairs:
        assert listed.record() == vector.record()
        assert [(lb, ub) for _, lb, ub in listed.rows()][:1] == [(lb, ub) for _, lb, ub in vector.rows()][:1]
        assert np.array_equal(row_values(listed), row_values(vector, interleaved=listed.name == "assembly"),
                              equal_nan=True)
    closure = pairs[0][1].record()
    assert (closure.margin < 0) == open_somewhere and (pairs[1][1].missing is not None) == open_somewhere

def test_picking_arc_spec_holds_the_ten_arc_points():
    spec = load_spec(PATH_LIBRARY / "picking_arc.toml").model
    assert np.array(spec.targets.points) == pytest.approx(picking_arc(10), abs=1e-12)
    assert spec.targets.crank_deg is None and spec.rules.order


# ---------------------------------------------------------------------------- bad input

def _with(tmp_path, edit) -> str:
    data = truth_data(0, 6, timed=True)
    edit(data)
    path = tmp_path / "bad.toml"
    path.write_text(toml_text(data))
    with pytest.raises(SpecError) as err:
        load_spec(path)
    return str(err.value)


@pytest.mark.parametrize("edit, message", [
    (lambda d: d["targets"].update(points=d["targets"]["points"][:2], crank_deg=[0.0, 60.0]),
     "fourbar_path.targets.points: expected 3 to 1000 points, got 2"),
    (lambda d: d["targets"].update(crank_deg=d["targets"]["crank_deg"][:5]),
     "fourbar_path.targets.crank_deg: expected one angle per point (6), got 5"),
    (lambda d: d["targets"]["points"].__setitem__(3, [float("nan"), 1.0]),
     "targets.points[3][0]: nan is not a finite number"),         # the loader, before any model
    (lambda d: d["targets"]["points"].__setitem__(1, [2.0, float("inf")]),
     "targets.points[1][1]: inf is not a finite number"),
    (lambda d: d["linkage"].update(r3={"init": 30, "bounds": [60, 5]}),
     "fourbar_path.linkage.r3: bounds [60, 5] have lo > hi; write them as [5, 60]"),
    (lambda d: d["linkage"].update(rc_x={"init": 30, "bounds": [5, 60]}),
     "fourbar_path.linkage.rc_x: unknown field; did you mean 'rcx'?"),
    (lambda d: d["linkage"].update(theta_0={"init": 0, "bounds": [0, 360]}),
     "fourbar_path.linkage.theta_0: unknown field; did you mean 'theta0'?"),
    (lambda d: d["linkage"].update(r2={"init": 30, "bounds": [-1, 60]}),
     "fourbar_path.linkage: r2: expected > 0, got -1 (lower bound)"),
    (lambda d: d["linkage"].update(branch=0), "fourbar_path.linkage.branch: expected -1 or 1, got 0"),
    (lambda d: d["rules"].update(grashof="crank rocker"),
     "fourbar_path.rules.grashof: expected 'crank_rocker', 'double_crank' or 'any', got 'crank rocker'"),
    (lambda d: d["solver"].update(mu_strategy="fast"),
     "fourbar_path.solver.mu_strategy: expected 'monotone' or 'adaptive', got 'fast'"),
    # magnitudes whose squares overflow a float: named, not a traceback from the kinematics
    (lambda d: d["targets"]["points"].__setitem__(0, [1e300, 0.0]),
     "targets.points[0][0]: 1e+300 is beyond the largest magnitude a spec value may have (1e+12)"),
    (lambda d: d["linkage"].update(r3={"init": 30, "bounds": [5, 1e200]}),
     "linkage.r3.bounds[1]: 1e+200 is beyond the largest magnitude a spec value may have (1e+12)"),
    # within what any spec may hold, beyond what a four-bar in mm can mean: the kind's own cap
    (lambda d: d["targets"]["points"].__setitem__(0, [1e8, 0.0]),
     "fourbar_path.targets.points.0: x: expected a magnitude of at most 1e+06 (mm or deg), got 1e+08"),
    (lambda d: d["linkage"].update(r3={"init": 30, "bounds": [5, 1e9]}),
     "fourbar_path.linkage: r3.bounds: expected a magnitude of at most 1e+06 (mm or deg), got 1e+09"),
    (lambda d: d["linkage"].update(x0=-2e6),
     "fourbar_path.linkage: x0: expected a magnitude of at most 1e+06 (mm or deg), got -2e+06"),
    # timed targets give every crank angle: a free-timing rule asking otherwise was dropped without a word
    (lambda d: d.setdefault("rules", {}).update(order=False),
     "fourbar_path.rules.order = false: only read with free timing; targets.crank_deg gives every target's crank "
     "angle"),
    (lambda d: d.setdefault("rules", {}).update(direction="clockwise"),
     "fourbar_path.rules.direction = \"clockwise\": only read with free timing"),
])
def test_bad_input_names_the_field_and_value(tmp_path, edit, message):
    assert message in _with(tmp_path, edit)


def test_too_many_points(tmp_path):
    """Above MAX_POINTS (1,000) targets a spec is refused on one line naming the field, the range and the count."""
    def edit(d):
        d["targets"] = {"points": [[float(i), float(i * i % 7)] for i in range(1001)]}
    message = _with(tmp_path, edit)
    assert "fourbar_path.targets.points: expected 3 to 1000 points, got 1001" in message
    assert len([line for line in message.splitlines() if "points" in line]) == 1


@pytest.mark.parametrize("edit, message", [
    (lambda d: d["targets"]["points"].__setitem__(2, [float("nan"), 0.0]),
     "targets.points[2][0]: nan is not a finite number"),
    pytest.param(lambda d: d["targets"]["points"].__setitem__(0, [1e300, 0.0]),
                 "targets.points[0][0]: 1e+300 is beyond the largest magnitude a spec value may have (1e+12)",
                 marks=pytest.mark.slow),
    pytest.param(lambda d: d["linkage"].update(r3={"init": 30, "bounds": [5, 1e200]}),
                 "linkage.r3.bounds[1]: 1e+200 is beyond the largest magnitude a spec value may have (1e+12)",
                 marks=pytest.mark.slow),
], ids=["nan", "huge-point", "huge-bound"])
def test_bad_input_exits_2_without_a_traceback(tmp_path, edit, message):
    data = truth_data(0, 6, timed=False)
    edit(data)
    path = tmp_path / "bad.toml"
    path.write_text(toml_text(data))
    for command in ("check", "solve"):
        proc = cli(command, str(path), "--out", str(tmp_path), cwd=tmp_path)
        assert proc.returncode == 2, proc.stdout + proc.stderr
        assert message in " ".join(proc.stderr.split())
        assert "Traceback" not in proc.stderr


# ---------------------------------------------------------------------------- the first spec forms, refused

OLD_PICKING_ARC = """kind = "fourbar_path"
name = "old_form"
branch = "crossed"

[targets]
points = [[376.0, 123.7], [332.3, 183.9], [205.0, 258.0]]

[bounds]
r1 = [20, 200]
r2 = 35
x0 = [0, 150]

[design]
x0 = 40

[rules]
grashof = "double-crank"
direction = "cw"
"""


def test_the_old_forms_are_refused_with_the_new_spelling_of_the_users_values(tmp_path):
    """[bounds] (with its [design] value as the init), branch "open"/"crossed" at the top and the hyphenated
    Grashof classes: one line each, exit 2, the values of the file spelled the new way."""
    path = tmp_path / "old.toml"
    path.write_text(OLD_PICKING_ARC)
    proc = cli("check", str(path), "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.splitlines() == [
        f"error: {path}: fourbar_path.bounds: [bounds] is no longer read; write each variable under [linkage], a "
        "number fixes it, {init, bounds} frees it: r1 = {init = 110, bounds = [20, 200]}; r2 = 35; "
        "x0 = {init = 40, bounds = [0, 150]}",
        "fourbar_path.branch: \"crossed\" is no longer read at the top; write branch = -1 under [linkage] "
        "(+1: B left of A -> O', the open assembly; -1: the crossed one)",
        "fourbar_path.rules.grashof: \"double-crank\" is no longer read; write grashof = \"double_crank\"",
        "fourbar_path.rules.direction: \"cw\" is no longer read; write direction = \"clockwise\""]


def test_an_old_branch_name_under_linkage_is_refused_with_its_number():
    data = truth_data(0, 6, timed=False)
    data["linkage"]["branch"] = "open"
    with pytest.raises(SpecError) as err:
        validate(FourbarPathSpec, data, prefix="fourbar_path")
    assert str(err.value) == ("fourbar_path.linkage.branch: \"open\" is no longer read; write branch = 1 (+1: B left "
                              "of A -> O', the open assembly; -1: the crossed one)")


def test_design_values_outside_the_linkage_are_refused_with_the_init_form():
    data = truth_data(0, 6, timed=False)
    data["design"] = {"r3": 31.5}
    with pytest.raises(SpecError) as err:
        validate(FourbarPathSpec, data, prefix="fourbar_path")
    assert str(err.value) == ("fourbar_path.design.r3: [design] holds only crank_deg now; write the given value as "
                              "the init of the variable under [linkage]: r3 = {init = 31.5, bounds = [lo, hi]}")


def test_the_new_spelling_reaches_the_kinematics_and_result_names():
    """branch = -1 is the crossed assembly, grashof = "double_crank" the double-crank rows; result.json keeps
    the assembly's name (in facts.branch since schema version 3) and the class's hyphenated name."""
    data = truth_data(0, 6, timed=False)
    data["linkage"]["branch"] = -1
    data["rules"]["grashof"] = "double_crank"
    spec = validate(FourbarPathSpec, data, prefix="fourbar_path")
    assert (spec.linkage.branch, spec.branch, BRANCHES[spec.branch]) == (-1, "crossed", -1)
    assert spec.rules.grashof_class == "double_crank" and spec.rules.grashof == "double-crank"
    for spelled, short in (("counter_clockwise", "ccw"), ("clockwise", "cw"), ("either", "either")):
        data["rules"]["direction"] = spelled
        assert validate(FourbarPathSpec, data, prefix="fourbar_path").rules.direction == short
    assert spec.design_values()["r1"] == 32.5 and spec.bounds_array()[0] == (5.0, 60.0)
    default = validate(FourbarPathSpec, {**data, "linkage": {k: v for k, v in data["linkage"].items()
                                                              if k != "theta0"}}, prefix="fourbar_path")
    assert default.linkage.theta0 == FreeVariable(init=180.0, bounds=(0.0, 360.0))


def test_crank_angles_are_free_in_design_variables_only_where_a_solve_moves_them():
    """picking_arc_dynamics fixes every linkage variable: solve refuses it ("every one is fixed"), yet its
    design_variables called the free-timing crank angles free.  picking_arc, whose linkage is free, solves them."""
    from synthesis import kinds
    from synthesis.spec import load_spec
    from synthesis.spec.design_info import attach

    fixed = load_spec(PATH_LIBRARY / "picking_arc_dynamics.toml")
    free = load_spec(PATH_LIBRARY / "picking_arc.toml")
    for loaded, expected in ((fixed, False), (free, True)):
        result = attach(kinds.checker("fourbar_path")(loaded), loaded.model)
        assert result.design_variables["crank_deg"] == {"path": "design.crank_deg", "unit": "deg", "bounds": None,
                                                        "free": expected}

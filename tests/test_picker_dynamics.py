"""Inverse dynamics of the picker double crank (seed 001's ABCD on the shared four-bar, over its working swing).

* The kind's mapping is its own kinematics: the links' centres of mass and angles the dynamics moves are those of the
  joints A, B, C, D and the clamp point M the kind's kinematics gives.
* The shared formulation with the kind's mass properties (the coupler BC with its clamp arm CM and a clamp mass at M:
  a centre of mass off the link line) against the independent sympy.physics.mechanics one of tests/test_dynamics.py.
* Energy balance from result.json alone: over each sample interval of the working swing the input work (the power
  integrated by a 6-point interpolating rule: the swing is not a period, so no spectral sum) equals the change of
  kinetic plus potential energy.
* The rules are the same functions on floats (check) and CasADi symbols (the NLP): equal values and rows, and AD
  derivatives equal to central differences.
* min_peak_torque lowers the peak against the given design with every rule held.
"""

from __future__ import annotations

import json
import math
import re
import tomllib

import casadi as ca
import numpy as np
import pytest

from conftest import LIBRARY
from dynamics_support import swing_energy_residuals
from synthesis import kinds
from synthesis.kinds import solve_spec
from synthesis.kinds.picker.check import (linkage, rules_of, swing_angles, target_angles, target_points)
from synthesis.kinds.picker.dynamics import double_crank_dynamics
from synthesis.kinds.picker.kinematics.linkage import clamp_function, clamp_states, joint_positions
from synthesis.result import result_text
from synthesis.spec import load_spec
from synthesis.spec.dynamics import DynamicsLimits, PointMass
from test_dynamics import assert_sample_agrees, sympy_newton_euler

PICKER = LIBRARY / "picker"
PUBLISHED = PICKER / "cai2020_double_crank_dynamics.toml"
OMEGA = 60 * 2 * math.pi / 60


def published():
    """The published double crank with its [dynamics] table: (spec, DoubleCrank, parameters as floats)."""
    spec = load_spec(PUBLISHED).model
    dc = linkage(spec)
    return spec, dc, tuple(float(v) for v in dc.parameters())


def with_clamp(spec, mass: float = 0.12):
    """The spec with a clamp of ``mass`` kg at the clamp point M (a point mass at the coupler's tip)."""
    table = spec.dynamics.model_copy(update={"point_masses": [PointMass(link="coupler", mass=mass, at="tip")]})
    return spec.model_copy(update={"dynamics": table})


def test_the_dynamics_moves_the_kinds_own_joints():
    """Bars only: AB's centre of mass is the middle of A and B, CD's of C and D, the coupler's the length-weighted
    middle of its bars BC and CM (machine frame, from facts.dynamics); each link's angle is its joints' direction."""
    spec, dc, _ = published()
    data = json.loads(result_text(kinds.get("picker_double_crank").check(load_spec(PUBLISHED))))
    dyn = data["facts"]["dynamics"]
    assert dyn["span"] == "working swing" and dyn["joint_roles"] == {
        "A": "crank_pivot", "B": "crank_pin", "C": "coupler_rocker", "D": "rocker_pivot"}
    crank = np.array(dyn["crank_deg"])
    assert crank[0] == 50.0 and crank[-1] == 100.0 and crank.size == spec.dynamics.samples
    links = {link["role"]: link for link in dyn["links"]}
    for i in (0, 97, 211, crank.size - 1):
        j = {k: np.array(v) for k, v in joint_positions(dc, float(crank[i])).items()}
        bc, cm = np.hypot(*(j["C"] - j["B"])), np.hypot(*(j["M"] - j["C"]))
        expected = {"crank": (j["A"] + j["B"]) / 2, "rocker": (j["D"] + j["C"]) / 2,
                    "coupler": (bc * (j["B"] + j["C"]) / 2 + cm * (j["C"] + j["M"]) / 2) / (bc + cm)}
        for role, centre in expected.items():
            np.testing.assert_allclose(links[role]["com_mm"][i], centre, rtol=0, atol=1e-9)
        for role, (p, q) in {"crank": ("A", "B"), "coupler": ("B", "C"), "rocker": ("D", "C")}.items():
            direction = math.degrees(math.atan2(*(j[q] - j[p])[::-1]))
            assert (links[role]["angle_deg"][i] - direction + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=1e-9)


@pytest.mark.slow         # seconds: sympy solves a 9 x 9 system per angle
def test_double_crank_inverse_dynamics_equals_an_independent_multibody_formulation():
    """The published double crank with steel bars and a 0.12 kg clamp at M, gravity with an x part so every term
    counts, across the working swing and beyond it."""
    spec, dc, p = published()
    dyn = double_crank_dynamics(with_clamp(spec).dynamics, p, dc.branch)
    gravity = (0.3, -9.81)
    thetas = np.radians([50.0, 62.5, 75.0, 87.5, 100.0, 250.0])
    ours = type(dyn)(dyn.branch, dyn.geometry, dyn.mass, dyn.loads, dyn.omega, gravity).over_turn(thetas)
    assert dyn.geometry == (dc.l4, dc.l1, dc.l2, dc.l3, -math.radians(dc.phi3))
    for i, theta in enumerate(thetas):
        independent = sympy_newton_euler(dyn.geometry, list(dyn.mass), OMEGA, gravity, theta,
                                         [float(ours["angle"][1, i]), float(ours["angle"][2, i])])
        assert_sample_agrees(ours, i, independent, 1e-12, 1e-13)     # measured: 2e-14 relative at most
    assert np.abs(ours["reactions"]).max() > 1.0 and np.abs(ours["torque"]).max() > 0.1


def test_energy_balance_of_the_published_double_crank_result():
    data = json.loads(result_text(kinds.get("picker_double_crank").check(load_spec(PUBLISHED))))
    work, change = swing_energy_residuals(data["facts"]["dynamics"])
    peak = np.abs(work).max()
    assert peak > 1e-3
    assert np.abs(work - change).max() <= 1e-10 * peak          # measured: 4e-13
    # not a turn: the swing lifts the clamp arm, and the motor puts that energy in
    assert work.sum() > 100 * peak


def test_energy_balance_with_a_clamp_and_an_external_load():
    """A clamp mass at M and a constant force on the follower: the input and the load's work together change the
    energy over every interval of the swing."""
    from synthesis.spec.dynamics import ExternalLoad

    loaded = load_spec(PUBLISHED)
    spec = with_clamp(loaded.model)
    table = spec.dynamics.model_copy(update={"external_loads": [
        ExternalLoad(link="rocker", force=(-3.0, 1.2), at=(150.0, 10.0), note="test load")]})
    spec = spec.model_copy(update={"dynamics": table})
    result = kinds.get("picker_double_crank").check(type(loaded)(**{**loaded.__dict__, "model": spec}))
    dyn = json.loads(result_text(result))["facts"]["dynamics"]
    work, change = swing_energy_residuals(dyn)
    assert np.abs(work - change).max() <= 1e-10 * np.abs(work).max()
    assert np.abs(dyn["external_loads"]["external_power_W"]).max() > 0.01


def symbolic_and_float_rules(spec, samples: int) -> tuple[list, list, ca.Function]:
    """The spec's rules on CasADi symbols as the NLP builds them (parameters p in mm and rad) and on floats as check
    does at the published design, on the same grid; and p -> (every rule's value, every row) as a Function."""
    _, dc, p0 = published()
    p = ca.SX.sym("p", 9)
    f = clamp_function(spec.linkage.branch)
    angles = np.radians(target_angles(spec))
    r = f.map(angles.size)(angles.reshape(1, -1), p)[0] - ca.DM(target_points(spec).T)
    crank = np.radians(swing_angles(spec, samples))
    mu = ca.vec(f.map(samples)(crank.reshape(1, -1), p)[3]) * (180.0 / math.pi)
    symbolic = rules_of(spec, p[0], p[2], p[3], p[4], p[5], mu, p, r)
    values = ca.vertcat(*[ca.vec(rule.expr) for rule in symbolic])
    rows = ca.vertcat(*[ca.vec(row[0]) for rule in symbolic for row in rule.rows()])
    mu0 = clamp_states(dc, swing_angles(spec, samples))["mu"]
    misses = clamp_states(dc, target_angles(spec))["M"] - target_points(spec).T
    floats = rules_of(spec, dc.x_a, dc.l1, dc.l2, dc.l3, dc.l4, mu0, p0, misses)
    return symbolic, floats, ca.Function("rules", [p], [values, rows, ca.jacobian(rows, p)])


def limited(spec):
    """The spec with every dynamics limit and an arc limit, so every rule the kind can add is built."""
    table = spec.dynamics.model_copy(update={"limits": DynamicsLimits(peak_input_torque=1.0, peak_shaking_force=20.0,
                                                                      peak_shaking_moment=1.0)})
    return spec.model_copy(update={"dynamics": table,
                                   "rules": spec.rules.model_copy(update={"max_arc_error": 10.0})})


def test_rules_are_the_same_on_floats_and_symbols():
    spec = limited(with_clamp(published()[0]))
    symbolic, floats, f = symbolic_and_float_rules(spec, 26)
    names = [r.name for r in floats]
    assert names == [r.name for r in symbolic] == [
        "grashof_double_crank", "frame_point_x_a", "min_transmission_angle", "max_arc_error", "peak_input_torque",
        "peak_shaking_force", "peak_shaking_moment"]
    values, rows, _ = (np.asarray(v).ravel() for v in f(np.array(published()[2])))
    float_values = np.concatenate([np.atleast_1d(np.asarray(r.expr, float)).ravel() for r in floats])
    float_rows = np.concatenate([np.atleast_1d(np.asarray(row[0], float)).ravel() for r in floats for row in r.rows()])
    np.testing.assert_allclose(values, float_values, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rows, float_rows, rtol=1e-12, atol=1e-12)
    assert all(r.where.startswith("over the working swing") for r in floats if r.name.startswith("peak_"))


def test_rule_derivatives_equal_central_differences():
    """d(rows)/dp by CasADi AD against central differences of the same rows (lengths, phi3, phi4: every one moves a
    bar, the clamp arm or the frame's direction)."""
    spec = limited(with_clamp(published()[0]))
    _, _, f = symbolic_and_float_rules(spec, 12)
    p0 = np.array(published()[2])
    jac = np.asarray(f(p0)[2])
    for i, h in enumerate([1e-4] * 7 + [1e-6] * 2):
        step = np.zeros(9)
        step[i] = h
        central = (np.asarray(f(p0 + step)[1]) - np.asarray(f(p0 - step)[1])) / (2 * h)
        np.testing.assert_allclose(jac[:, i:i + 1], central, rtol=1e-6, atol=1e-6 * max(np.abs(jac[:, i]).max(), 1e-9))
    assert np.abs(jac[:, 6]).max() > 1e-3        # the clamp arm's length moves the rows


def test_the_check_rule_reads_the_facts_peak():
    """Evaluated on the facts' own grid, the check's peak_input_torque is facts.dynamics' peak (same functions)."""
    spec = limited(published()[0])
    table = spec.dynamics.model_copy(update={"samples": 2001})
    spec = spec.model_copy(update={"dynamics": table})
    loaded = load_spec(PUBLISHED)
    data = json.loads(result_text(kinds.get("picker_double_crank").check(type(loaded)(**{**loaded.__dict__,
                                                                                         "model": spec}))))
    rules = {r["name"]: r for r in data["rules"]}
    summary = data["facts"]["dynamics"]["summary"]
    assert rules["peak_input_torque"]["value"] == pytest.approx(summary["input_torque_Nm"]["peak"], rel=1e-14)
    assert rules["peak_shaking_force"]["value"] == pytest.approx(summary["shaking_force_N"]["peak"], rel=1e-14)
    assert rules["peak_shaking_moment"]["value"] == pytest.approx(summary["shaking_moment_Nm"]["peak"], rel=1e-14)
    assert rules["max_arc_error"]["value"] == pytest.approx(data["facts"]["arc_error"]["max_mm"], rel=1e-14)


def test_a_spec_without_dynamics_has_no_dynamics_rules_or_facts():
    data = json.loads(result_text(kinds.get("picker_double_crank").check(load_spec(PICKER / "cai2020_double_crank.toml"))))
    assert "dynamics" not in data["facts"]
    assert [r["name"] for r in data["rules"]] == ["grashof_double_crank", "frame_point_x_a", "min_transmission_angle"]


@pytest.mark.slow         # about 5 s: two starts of both stages
def test_min_peak_torque_lowers_the_peak_of_the_given_design_with_every_rule_held():
    loaded = load_spec(PICKER / "picker_double_crank_min_peak_torque.toml")
    spec = loaded.model.model_copy(update={"solver": loaded.model.solver.model_copy(update={"starts": 2})})
    given = kinds.get("picker_double_crank").check(loaded)
    result, _, _ = solve_spec(type(loaded)(**{**loaded.__dict__, "model": spec}), workers=1)
    assert result.status == "optimal"
    data = json.loads(result_text(result))
    before = json.loads(result_text(given))["facts"]["dynamics"]["summary"]["input_torque_Nm"]["peak"]
    assert result.objective["unit"] == "N m" and result.objective["value"] < 0.5 * before
    # every rule of the re-check holds, the arc among them
    assert all(r["satisfied"] for r in data["rules"]), data["rules"]
    assert {r["name"] for r in data["rules"]} >= {"max_arc_error", "min_transmission_angle", "grashof_double_crank"}
    assert data["facts"]["arc_error"]["max_mm"] <= 5.5
    # the objective is the design's own peak on the check's grid: facts.dynamics' coarser grid cannot exceed it
    assert data["facts"]["dynamics"]["summary"]["input_torque_Nm"]["peak"] <= result.objective["value"] * (1 + 1e-12)


@pytest.mark.parametrize("change, message", [
    ({"objective": {"name": "min_peak_torque"}, "rules": {"max_arc_error": 5.0}, "dynamics": None},
     "needs a [dynamics] table"),
    ({"objective": {"name": "min_peak_shaking_force"}}, "needs rules.max_arc_error"),
    ({"dynamics": {"crank_speed": None}}, "has no crank speed of its own"),
    ({"dynamics": {"point_masses": [{"link": "rocker", "mass": 0.1, "at": "tip"}]}}, "the clamp point M, on the coupler"),
    ({"dynamics": {"counterweight": {"mass": {"init": 0.1, "bounds": [0.0, 1.0]}, "radius": 30.0}}},
     "frees only its linkage"),
])
def test_dynamics_tables_that_cannot_hold_are_refused(change, message):
    from pydantic import ValidationError

    data = tomllib.loads(PUBLISHED.read_text())
    for key, value in change.items():
        if value is None:
            data.pop(key)
            continue
        data[key] = {k: v for k, v in {**data.get(key, {}), **value}.items() if v is not None}
    with pytest.raises(ValidationError, match=re.escape(message)):
        kinds.get("picker_double_crank").spec_model().model_validate(data)


def test_every_peak_objective_is_listed_in_its_unit():
    from synthesis.dynamics.linkage import PEAK_OBJECTIVES
    from synthesis.kinds.picker.solve import OBJECTIVE_UNITS

    assert set(PEAK_OBJECTIVES) <= set(kinds.get("picker_double_crank").objectives)
    assert all(OBJECTIVE_UNITS[name] == unit for name, (unit, _) in PEAK_OBJECTIVES.items())


@pytest.mark.slow         # about 4 s each: two starts of both stages
@pytest.mark.parametrize("objective, summary", [("min_peak_shaking_force", "shaking_force_N"),
                                                ("min_peak_shaking_moment", "shaking_moment_Nm")])
def test_the_shaking_objectives_lower_the_given_designs_peak_with_every_rule_held(objective, summary):
    loaded = load_spec(PICKER / "picker_double_crank_min_peak_torque.toml")
    model = loaded.model
    spec = model.model_copy(update={"objective": model.objective.model_copy(update={"name": objective}),
                                    "solver": model.solver.model_copy(update={"starts": 2})})
    loaded = type(loaded)(**{**loaded.__dict__, "model": spec})
    before = json.loads(result_text(kinds.get("picker_double_crank").check(loaded)))["facts"]["dynamics"]["summary"]
    result, _, _ = solve_spec(loaded, workers=1)
    assert result.status == "optimal" and result.objective["name"] == objective
    data = json.loads(result_text(result))
    assert result.objective["value"] < before[summary]["peak"]
    assert all(r["satisfied"] for r in data["rules"]), [r for r in data["rules"] if not r["satisfied"]]
    assert data["facts"]["dynamics"]["summary"][summary]["peak"] == pytest.approx(result.objective["value"], rel=1e-3)

"""Inverse dynamics of one comb-finger unit (synthesis/kinds/comb_finger/dynamics.py, problems/comb_finger/FINGER.md
"Dynamics").

* An independent formulation: the drive torque by the energy method (sympy: the bodies' centres of mass written out
  again from the front view of FINGER.md, differentiated symbolically; torque omega = d(kinetic + potential)/dt - load
  power, the combing turn taken as 90 deg + alpha, eq 20) equals the Newton-Euler torque to 1e-9 relative, in and out
  of the combing turn; the shaking force and moment the model reports equal the bodies' momentum balance written with
  sympy's accelerations.
* Energy balance from result.json alone: over each sample interval the input and load work equals the change of
  kinetic plus potential energy, and over a turn the net work is zero (1e-9).
* The rules' values on symbols equal the check's on floats, their AD derivatives equal central differences; the NLP
  carries them (a torque limit binds r at limit / (2 f) in closed form, slow).
* A spec without [dynamics] has neither dynamics rules nor facts (its library answers are unchanged: measured with
  studies/library_answers.py); tables that cannot hold are refused with exit 2 naming the field.
"""

from __future__ import annotations

import json
import math

import casadi as ca
import numpy as np
import pytest
import sympy as sp
from conftest import LIBRARY
from dynamics_support import energy_residuals

from synthesis import kinds
from synthesis.errors import SpecError
from synthesis.kinds.comb_finger.check import RPM, evaluate, finger_dynamics
from synthesis.kinds.comb_finger.dynamics import FingerDynamics, inverse_dynamics, turn
from synthesis.result import result_text
from synthesis.spec import load_spec

DYNAMICS_SPEC = LIBRARY / "comb_finger" / "peanut_baseline_dynamics.toml"
#: a design off the tangent construction (b != r + e sin alpha): r, e, alpha (rad), b (mm)
GEOMETRY = (130.0, 45.0, math.radians(35.0), 170.0)
#: lumped mass vectors (kg, m, m, kg m^2), centres off the bodies' axes so every term counts
ROTOR = (2.7, 0.006, -0.003, 0.014)
FINGER = (0.11, 0.07, 0.004, 2.1e-4)
FINGERS = 3
OMEGA = 70.0 * RPM
GRAVITY = (0.4, -9.81)
LOAD = 6.5
#: turn angles (deg) of the first finger: in and out of its combing turn (0 to 125 deg here), the others' too
ANGLES = (3.0, 47.0, 110.0, 124.0, 131.0, 200.0, 250.0, 301.0, 355.0)


def sympy_bodies(geometry, rotor, finger, fingers):
    """The turn angle q and, as sympy expressions of it (m): the rotor's centre of mass, each finger's and its tip,
    written from FINGER.md's front view alone."""
    r, e, alpha, b = (sp.Float(v, 40) for v in geometry)
    q = sp.Symbol("q", real=True)
    s = sp.Matrix([-(r + e) * sp.cos(alpha), b]) / 1000
    hub = sp.Matrix([-r * sp.cos(alpha), b - e * sp.sin(alpha)]) / 1000

    def at(origin, angle, x, y):
        u = sp.Matrix([sp.sin(angle), -sp.cos(angle)])
        v = sp.Matrix([sp.cos(angle), sp.sin(angle)])
        return origin + sp.Float(x, 40) * u + sp.Float(y, 40) * v

    phases = [q + 2 * sp.pi * k / fingers for k in range(fingers)]
    coms = [at(s, q, rotor[1], rotor[2])] + [at(hub, p, finger[1], finger[2]) for p in phases]
    tips = [at(hub, p, r / 1000, 0.0) for p in phases]
    return q, s, hub, coms, tips, phases


def sympy_torque(geometry, rotor, finger, fingers, load, omega, gravity, angle):
    """The drive torque by the energy method at the turn angle ``angle`` (rad)."""
    q, _, _, coms, tips, phases = sympy_bodies(geometry, rotor, finger, fingers)
    masses = [rotor[0]] + [finger[0]] * fingers
    inertia = [rotor[3]] + [finger[3]] * fingers
    g = sp.Matrix(gravity)
    energy = sum(sp.Rational(1, 2) * m * omega ** 2 * (c.diff(q).T * c.diff(q))[0] + sp.Rational(1, 2) * i * omega ** 2
                 - m * (g.T * c)[0] for m, i, c in zip(masses, inertia, coms))
    zone_end = math.pi / 2 + geometry[2]                      # eq 20: the combing turn is 90 deg + alpha
    load_power = 0.0
    for tip, phase in zip(tips, phases):
        if float(phase.subs(q, angle)) % (2 * math.pi) <= zone_end:
            speed = omega * sp.sqrt((tip.diff(q).T * tip.diff(q))[0])
            load_power -= load * float(speed.subs(q, angle))   # a force of size `load` against the velocity
    return float((energy.diff(q) * omega).subs(q, angle)) / omega - load_power / omega


def test_torque_equals_the_energy_method():
    out = FingerDynamics(FINGERS, GEOMETRY, ROTOR, FINGER, LOAD, OMEGA, GRAVITY).over(np.radians(ANGLES))
    for k, angle in enumerate(ANGLES):
        expected = sympy_torque(GEOMETRY, ROTOR, FINGER, FINGERS, LOAD, OMEGA, GRAVITY, math.radians(angle))
        assert out["torque"][k] == pytest.approx(expected, rel=1e-9, abs=1e-12), angle
    # the load acts where the energy method says: 1 or 2 of the three tips in the combing turn at these angles
    assert set(np.asarray(out["in_zone"]).sum(axis=0).astype(int)) == {1, 2}


def cross(u, v) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


def test_shaking_force_and_moment_are_the_momentum_balance():
    """What the moving bodies put on the frame: sum m (g - a) + loads, and its moment about S, sympy accelerations."""
    q, s, _, coms, tips, _ = sympy_bodies(GEOMETRY, ROTOR, FINGER, FINGERS)
    masses = [ROTOR[0]] + [FINGER[0]] * FINGERS
    g = np.array(GRAVITY)
    out = FingerDynamics(FINGERS, GEOMETRY, ROTOR, FINGER, LOAD, OMEGA, GRAVITY).over(np.radians(ANGLES))
    for k, angle in enumerate(ANGLES):
        at = {q: math.radians(angle)}
        sv = np.array(s.subs(at), float).ravel()
        force, moment = np.zeros(2), 0.0
        for m, c in zip(masses, coms):
            pos = np.array(c.subs(at), float).ravel()
            acc = np.array(c.diff(q, 2).subs(at), float).ravel() * OMEGA ** 2
            f = m * (g - acc)
            force += f
            moment += cross(pos - sv, f)
        for j, tip in enumerate(tips):
            load = out["load_force"][:, j, k]
            force += load
            moment += cross(np.array(tip.subs(at), float).ravel() - sv, load)
        np.testing.assert_allclose(out["shaking_force"][:, k], force, rtol=1e-10, atol=1e-10)
        assert out["shaking_moment"][k] == pytest.approx(moment, rel=1e-10, abs=1e-10)
        # the frame's forces at S and R with the bodies' weights and loads balance their momentum
        assert np.allclose(-out["reactions"][:, :, k].sum(axis=1), out["shaking_force"][:, k], atol=1e-12)


def test_evenly_spaced_equal_fingers_on_a_balanced_drum_need_no_torque_but_the_load():
    """Four equal fingers evenly spaced put their common centre of mass on R: without a load the torque vanishes;
    with one, it is the load's moment f r times the tips in the combing turn."""
    rotor, finger = (3.0, 0.0, 0.0, 0.015), (0.1, 0.06, 0.0, 1.2e-4)
    angles = turn(72)
    free = FingerDynamics(4, GEOMETRY, rotor, finger, 0.0, OMEGA, (0.0, -9.81)).over(angles)
    assert np.abs(free["torque"]).max() < 1e-12
    loaded = FingerDynamics(4, GEOMETRY, rotor, finger, LOAD, OMEGA, (0.0, -9.81)).over(angles)
    tips = np.asarray(loaded["in_zone"]).sum(axis=0)
    np.testing.assert_allclose(loaded["torque"], LOAD * GEOMETRY[0] / 1000.0 * tips, rtol=1e-12, atol=1e-12)


def checked_json(spec_text: str | None = None, tmp_path=None) -> dict:
    """result.json's data of ``check`` (the library spec, or ``spec_text`` written to ``tmp_path``), as written
    (strict JSON) and read back."""
    path = DYNAMICS_SPEC
    if spec_text is not None:
        path = tmp_path / "spec.toml"
        path.write_text(spec_text)
    loaded = load_spec(path)
    return json.loads(result_text(kinds.get(loaded.model.kind).check(loaded)))


@pytest.mark.slow            # two checks on the 3600-angle grid, about 1.4 s
def test_energy_balance_from_the_result_alone(tmp_path):
    """The library spec, and the same with three fingers of a lumped, off-axis mass under a tilted gravity (the
    fingers' weight then does work over the turn): every interval's work of the input and the load equals its change
    of energy, over a turn their net work is zero, and the input's mean power is what the load takes."""
    text = DYNAMICS_SPEC.read_text()
    lumped = (text.replace("fingers = 4", "fingers = 3")
              .replace("finger = { density = 7850, area = 50.3 }",
                       "finger = { mass = 0.12, com = [70.0, 5.0], inertia = 2.0e-4 }")
              .replace("gravity = [0.0, -9.81]", "gravity = [0.5, -9.81]")
              .replace("rotor = { mass = 3.0, com = [0.0, 0.0]", "rotor = { mass = 3.0, com = [4.0, -2.0]"))
    change = np.zeros(0)
    for spec_text in (None, lumped):
        dyn = checked_json(spec_text, tmp_path)["facts"]["dynamics"]
        work, change, net = energy_residuals(dyn)
        # the input's work over one interval sets the scale (the library spec's energy is constant: work ~ 0)
        peak = np.abs(dyn["power_W"]).max() * 2 * math.pi / len(work) / (dyn["crank_speed_rpm"] * RPM)
        assert peak > 0.01
        assert np.abs(work - change).max() <= 1e-9 * peak
        assert abs(net) <= 1e-9 * peak
        input_net = np.mean(dyn["power_W"])
        load_net = np.mean(dyn["external_loads"]["external_power_W"])
        assert input_net > 1.0 and load_net < -1.0
        assert input_net == pytest.approx(-load_net, rel=1e-9)
    assert np.ptp(np.array(change)) > 1e-4                  # the lumped case's energy does change over the turn


def test_the_library_spec_figures():
    """peanut_baseline_dynamics (FINGER.md "Dynamics"): four 120 mm fingers 90 deg apart over a 120 deg combing turn,
    one or two tips combing at 5 N: the drive torque is 0.6 or 1.2 N m (the fingers' weights cancel about R)."""
    dyn = checked_json()["facts"]["dynamics"]
    s = dyn["summary"]
    assert s["input_torque_Nm"]["peak"] == pytest.approx(1.2, abs=1e-9)
    assert set(np.round(dyn["input_torque_Nm"], 9)) == {0.6, 1.2}
    assert s["mean_power_W"] == pytest.approx(-s["mean_load_power_W"], rel=1e-9)
    assert set(dyn["joints"]) == {"S", "R"} and dyn["joint_roles"] == {"S": "crank_pivot", "R": "eccentric"}
    assert [link["role"] for link in dyn["links"]] == ["crank"] + ["finger"] * 4
    finger = dyn["links"][1]
    # a bar of 7850 kg/m^3 x 50.3 mm^2 x 120 mm with its 0.05 kg collar at R
    bar = 7850 * 50.3e-6 * 0.120
    assert finger["mass_kg"] == pytest.approx(bar + 0.05, rel=1e-12)
    centre = bar * 0.060 / (bar + 0.05)
    assert finger["inertia_kgm2"] == pytest.approx(bar * 0.12 ** 2 / 12 + bar * (0.06 - centre) ** 2
                                                   + 0.05 * centre ** 2, rel=1e-12)
    assert dyn["crank_speed_rpm"] == 60.0 and len(dyn["crank_deg"]) == 360
    assert dyn["external_loads"]["loads"][0]["source"].startswith("assumption")
    assert s["shaking_force_N"]["peak"] == pytest.approx(40.12, abs=0.01)


def test_rules_on_symbols_equal_the_check_and_their_derivatives_central_differences():
    spec = load_spec(DYNAMICS_SPEC).model
    z = ca.SX.sym("z", 5)                                  # r, e, alpha (rad), b, omega (rad/s)
    angles = turn(36)
    symbolic = finger_dynamics(spec, z[0], z[1], z[2], z[3], z[4]).over(angles)
    f = ca.Function("f", [z], [ca.vertcat(ca.vec(symbolic["torque"]), ca.vec(symbolic["shaking_force"]),
                                          ca.vec(symbolic["shaking_moment"]))])
    # alpha off the 10-degree grid: no sample sits on the combing turn's end (90 deg + alpha)
    x0 = np.array([120.0, 40.0, math.radians(31.3), 140.0, 60.0 * RPM])
    on_floats = finger_dynamics(spec, *x0).over(angles)
    expected = np.concatenate([on_floats["torque"], on_floats["shaking_force"].T.ravel(),
                               on_floats["shaking_moment"]])
    np.testing.assert_allclose(np.asarray(f(x0), float).ravel(), expected, rtol=1e-13, atol=1e-12)
    jac = np.asarray(ca.Function("j", [z], [ca.jacobian(f(z), z)])(x0), float)
    steps = np.array([1e-4, 1e-4, 1e-7, 1e-4, 1e-6])       # none moves a sample across the combing turn's ends
    for i, h in enumerate(steps):
        dx = np.zeros(5)
        dx[i] = h
        central = (np.asarray(f(x0 + dx), float) - np.asarray(f(x0 - dx), float)).ravel() / (2 * h)
        np.testing.assert_allclose(jac[:, i], central, rtol=1e-6, atol=1e-7)
    # the check's rule table reads the same model on its turn grid
    rules, _ = evaluate(spec, spec.design_values())
    by_name = {r.name: r for r in rules}
    assert by_name["peak_input_torque"].record().value == pytest.approx(1.2, abs=1e-9)


def declared_rules(path) -> list[str]:
    from synthesis.core.kind import Setting
    from synthesis.kinds.comb_finger.nlp import problem

    spec = load_spec(path).model
    return [r.name for r in problem(Setting(spec)).problem.rules]


def test_the_nlp_carries_the_rules(tmp_path):
    text = (LIBRARY / "comb_finger" / "redesign_max_combing.toml").read_text()
    table = DYNAMICS_SPEC.read_text()
    path = tmp_path / "spec.toml"
    path.write_text(text + table[table.index("\n[dynamics]"):])
    assert declared_rules(path)[-2:] == ["peak_input_torque", "peak_shaking_force"]
    assert "peak_input_torque" not in declared_rules(LIBRARY / "comb_finger" / "redesign_max_combing.toml")


@pytest.mark.slow            # a multistart solve, about 3 s
def test_a_torque_limit_binds_the_finger_length(tmp_path):
    """Two tips combing at 5 N need 10 N x r of torque: a 1 N m limit holds r at 100 mm (a shorter finger combs
    less), and the solved design meets it on the check's grid."""
    text = (LIBRARY / "comb_finger" / "redesign_max_combing.toml").read_text()
    table = DYNAMICS_SPEC.read_text().replace("peak_input_torque = 5.0", "peak_input_torque = 1.0")
    path = tmp_path / "spec.toml"
    path.write_text(text + table[table.index("\n[dynamics]"):])
    from synthesis.kinds import solve_spec

    result = solve_spec(load_spec(path), workers=1)[0]
    assert result.status == "optimal"
    assert result.design["r"] == pytest.approx(100.0, abs=1e-4)     # IPOPT's interior: 1e-5 mm inside
    peak = next(r for r in result.rules if r["name"] == "peak_input_torque")
    assert peak["value"] == pytest.approx(1.0, abs=1e-6) and peak["satisfied"]


def test_a_spec_without_the_table_has_no_dynamics():
    names = ["root_clearance", "units_gap", "finger_clear_of_other_unit", "unit_within_row", "finger_hides_in_drum",
             "finger_protrudes", "tip_reaches_ground", "drum_above_ground"]
    for name, speed in (("peanut_baseline.toml", ["tip_speed"]), ("redesign_max_combing.toml", [])):
        loaded = load_spec(LIBRARY / "comb_finger" / name)
        result = json.loads(result_text(kinds.get("comb_finger").check(loaded)))
        assert "dynamics" not in result["facts"]
        assert [r["name"] for r in result["rules"]] == names + speed


@pytest.mark.slow            # two fresh processes, about 5 s
def test_a_run_without_the_table_imports_no_dynamics(tmp_path):
    from solving import modules_after_runs

    plain = modules_after_runs(tmp_path, [["check", str(LIBRARY / "comb_finger" / "peanut_baseline.toml"), "--out",
                                           str(tmp_path)]])
    assert not [m for m in plain if m.startswith(("synthesis.dynamics", "synthesis.constraints.dynamics",
                                                  "synthesis.kinds.comb_finger.dynamics"))]
    with_table = modules_after_runs(tmp_path, [["check", str(DYNAMICS_SPEC), "--out", str(tmp_path)]])
    assert "synthesis.kinds.comb_finger.dynamics" in with_table
    assert not [m for m in with_table if m.startswith(("synthesis.kinematics", "synthesis.dynamics.fourbar"))]


def test_a_table_without_limits_reports_the_facts_and_adds_no_rule(tmp_path):
    text = DYNAMICS_SPEC.read_text()
    text = text[:text.index("\n[dynamics.limits]")]
    result = checked_json(text, tmp_path)
    assert "dynamics" in result["facts"]
    assert not any(r["name"].startswith("peak_") for r in result["rules"])


@pytest.mark.parametrize("old, new, field", [
    ("rotor = { mass = 3.0, com = [0.0, 0.0], inertia = 0.015 }", "rotor = { density = 7850, area = 50.3 }",
     "dynamics.rotor"),
    ("fingers = 4", "fingers = 0", "dynamics.fingers"),
    ('{ link = "finger", mass = 0.05, at = [0.0, 0.0]', '{ link = "rotor", mass = 0.05, at = "tip"',
     "dynamics: point_masses"),
    ('{ link = "finger", mass = 0.05', '{ link = "crank", mass = 0.05', "dynamics.point_masses.0.link"),
    ("combing_load = { force = 5.0,", "combing_load = { force = -5.0,", "dynamics.combing_load.force"),
    ("combing_load = { force = 5.0, source =", "combing_load = { force = 5.0, note =", "dynamics.combing_load"),
    ("samples = 360", "samples = 360\ncrank_speed = 60.0", "dynamics.crank_speed"),
    ("finger = { density = 7850, area = 50.3 }", "finger = { density = 0.0, area = 50.3 }", "dynamics.finger"),
    ("peak_input_torque = 5.0", "peak_input_torque = -5.0", "dynamics.limits.peak_input_torque"),
])
def test_tables_that_cannot_hold_are_refused_naming_the_field(tmp_path, old, new, field):
    text = DYNAMICS_SPEC.read_text()
    assert old in text
    path = tmp_path / "spec.toml"
    path.write_text(text.replace(old, new))
    with pytest.raises(SpecError) as err:
        load_spec(path)
    assert err.value.exit_code == 2
    assert field in str(err.value), str(err.value)


def test_one_function_per_finger_count():
    assert inverse_dynamics(3) is inverse_dynamics(3)
    assert inverse_dynamics(3).name() != inverse_dynamics(4).name()

"""Inverse dynamics of the tillage linkage (synthesis/kinds/tillage_linkage/dynamics.py, problems/tillage/TILLAGE.md
"Dynamics").

* An independent formulation: the input torque by the energy method (sympy: the links' positions written out again
  from the geometry, differentiated symbolically; torque Omega = d(kinetic + potential)/dt - soil power) equals the
  Newton-Euler torque to 1e-9 relative at crank angles in and out of the soil; and every reaction the model reports
  satisfies each link's Newton-Euler equations, written with sympy's accelerations, with roller friction on.
* Energy balance from result.json alone: over each sample interval the input, soil and friction work equals the
  change of kinetic plus potential energy, and over a turn the net work is zero (1e-9).
* The dynamics rules' AD derivatives equal central differences; their values on symbols equal the check's on floats.
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
from synthesis.kinds.tillage_linkage.check import (
    DEG,
    dynamics_rules_of,
    linkage_dynamics,
)
from synthesis.kinds.tillage_linkage.dynamics import (
    V_SLIP,
    TillageDynamics,
    inverse_dynamics,
    turn,
)
from synthesis.result import result_text
from synthesis.spec import load_spec

DYNAMICS_SPEC = LIBRARY / "tillage" / "hwang_tillage_dynamics.toml"
#: the baseline's geometry: a, b, c (mm), theta (rad), height of C (mm)
GEOMETRY = (120.0, 250.0, 500.0, math.radians(20.0), 130.0)
#: lumped mass properties per link (kg, m, m, kg m^2), centres off the link lines so every term counts
MASS = (5.9, 0.012, -0.004, 0.066, 3.1, 0.21, 0.006, 0.081)
OMEGA = 2 * math.pi                  # 60 r/min
GRAVITY = (0.4, -9.81)
#: f0 (N), k (N/mm), forward speed (m/s): a jump at entry and exit too, so the model's if_else is exercised whole
SOIL = (25.0, 5.88, 0.15)
#: crank angles (deg): above the ground, near entry (93.7 deg), deep, near the lowest point, near exit (199.4)
ANGLES = (10.0, 60.0, 95.0, 130.0, 157.0, 185.0, 198.0, 250.0, 320.0)


def sympy_model(geometry, mass, gravity, soil, omega):
    """Positions of the moving points as sympy expressions of the crank angle q (m), written from the geometry alone:
    the crank pin on its circle, the bar along B -> C through the rollers at the origin, the tool at its end."""
    a, b, c, theta, height = (sp.Float(v, 40) for v in geometry)
    q = sp.Symbol("q", real=True)
    pivot = sp.Matrix([b * sp.cos(theta), b * sp.sin(theta)]) / 1000
    pin = pivot + a / 1000 * sp.Matrix([sp.cos(q), sp.sin(q)])
    length = sp.sqrt(pin.dot(pin))
    e = -pin / length
    normal = sp.Matrix([-e[1], e[0]])
    tool = pin + c / 1000 * e
    m1, cx1, cy1, i1, m2, cx2, cy2, i2 = (sp.Float(v, 40) for v in mass)
    com1 = pivot + cx1 * sp.Matrix([sp.cos(q), sp.sin(q)]) + cy1 * sp.Matrix([-sp.sin(q), sp.cos(q)])
    com2 = pin + cx2 * e + cy2 * normal
    psi = sp.atan2(e[1], e[0])
    return {"q": q, "pivot": pivot, "pin": pin, "length": length, "e": e, "normal": normal, "tool": tool,
            "com": (com1, com2), "psi": psi, "m": (m1, m2), "I": (i1, i2), "omega": sp.Float(omega, 40),
            "g": sp.Matrix([sp.Float(v, 40) for v in gravity]), "height": height, "soil": soil}


def _at(expr, q, value):
    return expr.subs(q, sp.Float(value, 40)).evalf(30)


def _soil_force(model, q_value):
    """The soil force (N) at crank angle q: magnitude f0 + k d while the tool is below the ground, opposing its
    velocity relative to the soil (the machine travels towards +x at v)."""
    q, omega = model["q"], model["omega"]
    f0, k, forward = model["soil"]
    tool = _at(model["tool"], q, q_value)
    depth = -model["height"] - 1000 * tool[1]
    if depth <= 0:
        return sp.Matrix([0, 0]), float(depth)
    relative = _at(sp.diff(model["tool"], q), q, q_value) * omega + sp.Matrix([forward, 0])
    return -(f0 + k * depth) * relative / sp.sqrt(relative.dot(relative)), float(depth)


def energy_torque(model, q_value) -> float:
    """Torque (N m) by the energy method: torque Omega = d(kinetic + potential)/dt - soil power, frictionless."""
    q, omega = model["q"], model["omega"]
    kinetic = sum(m * omega ** 2 * sp.diff(g, q).dot(sp.diff(g, q)) / 2 for m, g in zip(model["m"], model["com"]))
    kinetic += model["I"][0] * omega ** 2 / 2 + model["I"][1] * (omega * sp.diff(model["psi"], q)) ** 2 / 2
    potential = -sum(m * model["g"].dot(g) for m, g in zip(model["m"], model["com"]))
    rate = omega * _at(sp.diff(kinetic + potential, q), q, q_value)
    force, _ = _soil_force(model, q_value)
    soil_power = force.dot(_at(sp.diff(model["tool"], q), q, q_value) * omega)
    return float((rate - soil_power) / omega)


def model_at(q_deg, mu=0.0) -> dict:
    f = inverse_dynamics()
    out = f(math.radians(q_deg), list(GEOMETRY), list(MASS), [SOIL[0], SOIL[1], SOIL[2], mu], OMEGA, list(GRAVITY))
    arrays = {name: np.asarray(v, float) for name, v in zip(f.name_out(), out)}
    return {name: a.reshape(()) if a.size == 1 else a for name, a in arrays.items()}


def test_torque_equals_the_energy_method():
    model = sympy_model(GEOMETRY, MASS, GRAVITY, SOIL, OMEGA)
    torques = {q: float(model_at(q)["torque"]) for q in ANGLES}
    peak = max(abs(t) for t in torques.values())
    in_soil = 0
    for q_deg, torque in torques.items():
        expected = energy_torque(model, math.radians(q_deg))
        assert torque == pytest.approx(expected, rel=1e-9, abs=1e-9 * peak), q_deg
        in_soil += _soil_force(model, math.radians(q_deg))[1] > 0
    assert in_soil >= 4 and peak > 10.0


def _cross(u, v) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


@pytest.mark.slow          # about 3.5 s of symbolic differentiation
def test_reactions_satisfy_each_links_newton_euler_equations_with_roller_friction():
    """Each link's force and moment balance about its own centre of mass, with the accelerations differentiated by
    sympy, holds for the reported pivot, pin and roller forces and torque; the roller force's component along the
    bar is the friction mu |N| tanh(S'/V_SLIP); the shaking force and moment are what the frame receives."""
    mu = 0.2
    model = sympy_model(GEOMETRY, MASS, GRAVITY, SOIL, OMEGA)
    q = model["q"]
    g = np.array(GRAVITY)
    for q_deg in ANGLES:
        w = math.radians(q_deg)
        out = model_at(q_deg, mu)
        f_a, f_b, f_c = (out["reactions"][:, j] for j in range(3))
        point = {k: np.array(_at(model[k], q, w), float).ravel() for k in ("pivot", "pin", "tool", "e", "normal")}
        coms = [np.array(_at(c, q, w), float).ravel() for c in model["com"]]
        accs = [np.array(_at(sp.diff(c, q, 2), q, w), float).ravel() * OMEGA ** 2 for c in model["com"]]
        alpha = float(_at(sp.diff(model["psi"], q, 2), q, w)) * OMEGA ** 2
        sliding = float(_at(sp.diff(model["length"], q), q, w)) * OMEGA
        soil, _ = _soil_force(model, w)
        soil = np.array(soil, float).ravel()
        m1, m2, i2 = MASS[0], MASS[4], MASS[7]
        scale = max(np.abs(out["reactions"]).max(), 1.0)
        residuals = [
            f_b + f_c + soil + m2 * g - m2 * accs[1],                                      # bar, forces
            _cross(point["pin"] - coms[1], f_b) + _cross(-coms[1], f_c) + _cross(point["tool"] - coms[1], soil)
            - i2 * alpha,                                                                  # bar, moments about G2
            f_a - f_b + m1 * g - m1 * accs[0],                                             # crank, forces
            float(out["torque"]) + _cross(point["pivot"] - coms[0], f_a) - _cross(point["pin"] - coms[0], f_b),
            f_c @ point["e"] - mu * abs(f_c @ point["normal"]) * math.tanh(sliding / V_SLIP),   # friction law
            f_c @ point["normal"] - float(out["roller_normal"]),
            out["shaking_force"].ravel() + f_a + f_c,
            float(out["shaking_moment"]) + float(out["torque"]) + _cross(-point["pivot"], f_c),
        ]
        for k, r in enumerate(residuals):
            assert np.abs(r).max() <= 1e-9 * scale, (q_deg, k, r)
        assert float(out["sliding_speed"]) == pytest.approx(sliding, rel=1e-9, abs=1e-12)
        assert float(out["friction_power"]) == pytest.approx(-(f_c @ point["e"]) * sliding, rel=1e-9, abs=1e-9)


def test_mass_properties_follow_the_table():
    """A bar {density, area} of length c, a point mass at B and the tool at the tip D combine by the parallel-axis
    theorem in the bar frame (origin B, x towards D); a lumped flywheel is taken as given."""
    spec = load_spec(DYNAMICS_SPEC).model
    dyn = linkage_dynamics(spec, 120.0, 250.0, 500.0, math.radians(20.0), 130.0)
    bar = 7850 * 400e-6 * 0.5
    total = bar + 0.3 + 1.5
    centre = (bar * 0.25 + 1.5 * 0.5) / total
    inertia = bar * 0.5 ** 2 / 12 + bar * (0.25 - centre) ** 2 + 0.3 * centre ** 2 + 1.5 * (0.5 - centre) ** 2
    assert dyn.mass[:4] == (5.55, 0.0, 0.0, 0.0624)
    assert dyn.mass[4] == pytest.approx(total, rel=1e-12)
    assert (dyn.mass[5], dyn.mass[6]) == pytest.approx((centre, 0.0), rel=1e-12, abs=1e-15)
    assert dyn.mass[7] == pytest.approx(inertia, rel=1e-12)
    assert dyn.soil == (0.0, 5.88, 0.15, 0.0) and dyn.omega == pytest.approx(2 * math.pi)


def checked_json(spec_text: str | None = None, tmp_path=None) -> dict:
    """result.json's data of ``check`` (the library spec, or ``spec_text`` written to ``tmp_path``), as written
    (strict JSON) and read back."""
    path = DYNAMICS_SPEC
    if spec_text is not None:
        path = tmp_path / "spec.toml"
        path.write_text(spec_text)
    loaded = load_spec(path)
    return json.loads(result_text(kinds.get(loaded.model.kind).check(loaded)))


def test_energy_balance_from_the_result_alone(tmp_path):
    """The library baseline, and the same with roller friction 0.1: every interval's work of the input, the soil and
    the friction equals its change of energy, and over a turn their net work is zero; the input's mean power is what
    the soil and the friction take."""
    text = DYNAMICS_SPEC.read_text()
    for friction in (0.0, 0.1):
        dyn = checked_json(None if friction == 0.0 else text.replace(
            "samples = 360", f"samples = 360\nroller_friction = {friction}"), tmp_path)["facts"]["dynamics"]
        assert ("friction_power_W" in dyn) == (friction > 0.0)
        work, change, net = energy_residuals(dyn)
        peak = np.abs(work).max()
        assert peak > 0.1
        assert np.abs(work - change).max() <= 1e-9 * peak
        assert abs(net) <= 1e-9 * peak
        input_net = np.mean(dyn["power_W"])
        soil_net = np.mean(dyn["external_loads"]["external_power_W"])
        friction_net = np.mean(dyn.get("friction_power_W", [0.0]))
        assert input_net > 50.0 and soil_net < -50.0 and friction_net <= (-1.0 if friction else 0.0)
        assert input_net == pytest.approx(-(soil_net + friction_net), rel=1e-9)


def test_the_library_baseline_figures():
    """hwang_tillage_dynamics (problems/tillage/TILLAGE.md "Dynamics"): peak input torque, power, shaking force,
    roller force and soil force, and where."""
    dyn = checked_json()["facts"]["dynamics"]
    s = dyn["summary"]
    assert s["input_torque_Nm"]["peak"] == pytest.approx(130.93, abs=0.01)
    assert s["input_torque_Nm"]["peak_at_crank_deg"] == 180.0
    assert s["mean_power_W"] == pytest.approx(112.24, abs=0.01)
    assert s["shaking_force_N"]["peak"] == pytest.approx(655.54, abs=0.01)
    assert s["joints_N"]["C"]["peak"] == pytest.approx(1921.85, abs=0.01)
    assert s["soil_force_N"]["peak"] == pytest.approx(609.08, abs=0.01)
    assert set(dyn["joints"]) == {"A", "B", "C"} and len(dyn["joints"]["C"]) == 360
    assert dyn["external_loads"]["loads"][0]["source"].startswith("assumption")
    assert [link["role"] for link in dyn["links"]] == ["crank", "bar"]
    # the roller force is normal to the bar (frictionless): along e turned +90 deg, of the signed size reported
    e = np.array([[np.cos(np.radians(a)), np.sin(np.radians(a))] for a in dyn["links"][1]["angle_deg"]])
    roller = np.array(dyn["joints"]["C"])
    assert np.abs((roller * e).sum(1)).max() <= 1e-9 * np.abs(roller).max()
    assert np.allclose(roller[:, 1] * e[:, 0] - roller[:, 0] * e[:, 1], dyn["roller_normal_N"], rtol=1e-12,
                       atol=1e-9)


def _design_rules(spec, samples):
    z = ca.SX.sym("z", 5)
    rules = dynamics_rules_of(spec, z[0], z[1], z[2], z[3] * DEG, z[4], samples)
    rows = ca.vertcat(*[row for rule in rules for row, _, _ in rule.rows()])
    return z, rules, ca.Function("rows", [z], [rows, ca.jacobian(rows, z)])


def test_rule_derivatives_equal_central_differences(tmp_path):
    """d(rule rows)/d(a, b, c, theta, height_c) by CasADi AD against central differences of the same rows, with
    roller friction and a soil force that jumps at entry (no sample within the step of the ground line); the rows'
    values on floats are the check's rules' (the same functions)."""
    text = DYNAMICS_SPEC.read_text().replace("samples = 360", "samples = 360\nroller_friction = 0.15").replace(
        "f0 = 0.0", "f0 = 20.0") + ("\n[dynamics.limits]\npeak_input_torque = 100.0\npeak_shaking_force = 500.0\n"
                                    "peak_shaking_moment = 200.0\n")
    path = tmp_path / "spec.toml"
    path.write_text(text)
    spec = load_spec(path).model
    x0 = np.array([120.0, 250.0, 500.0, 20.0, 130.0])
    _, rules, f = _design_rules(spec, 72)
    assert [r.name for r in rules] == ["peak_input_torque", "peak_shaking_force", "peak_shaking_moment"]
    depth = linkage_dynamics(spec, *x0[:3], x0[3] * DEG, x0[4]).over(turn(72))["depth"]
    assert np.abs(depth).min() > 0.1                 # no sample on the ground line, where the force jumps
    values, jac = (np.asarray(v) for v in f(x0))
    h = 1e-5
    for i in range(5):
        step = np.zeros(5)
        step[i] = h
        central = (np.asarray(f(x0 + step)[0]) - np.asarray(f(x0 - step)[0])) / (2 * h)
        scale = np.abs(jac[:, i]).max()
        np.testing.assert_allclose(jac[:, i:i + 1], central, rtol=1e-6, atol=1e-6 * scale)
        assert scale > 1e-3, i
    floats = dynamics_rules_of(spec, *x0[:3], x0[3] * DEG, x0[4], 72)
    on_floats = np.concatenate([np.ravel(row) for rule in floats for row, _, _ in rule.rows()])
    np.testing.assert_allclose(values.ravel(), on_floats, rtol=1e-12, atol=1e-9)


def test_the_nlp_carries_the_rules_and_the_objective():
    """tillage_torque_limited's NLP holds the peak-torque rule at the solver's samples; tillage_min_peak_torque's
    objective is an epigraph over them, scaled by the given design's peak; tillage_redesign's NLP has no dynamics."""
    from synthesis.core.kind import Setting
    from synthesis.kinds.tillage_linkage.nlp import problem

    def declared(name):
        loaded = load_spec(LIBRARY / "tillage" / name)
        return problem(Setting(loaded.model)).problem

    limited = declared("tillage_torque_limited.toml")
    assert [r.name for r in limited.rules][-1] == "peak_input_torque"
    assert limited.rules[-1].rows()[0][0].shape == (72, 1)
    peak = declared("tillage_min_peak_torque.toml")
    assert peak.objective.extra.shape == (1, 1) and len(peak.objective.rows) == 2
    assert peak.objective.extra_init[0] == pytest.approx(130.93, abs=0.01)        # the baseline's peak, 72 samples
    plain = declared("tillage_redesign.toml")
    assert [r.name for r in plain.rules] == ["working_depth", "lift_height", "rearward_in_soil", "bar_slot_angle",
                                             "bar_engagement"]


def test_a_spec_without_the_table_has_no_dynamics():
    for name in ("hwang_tillage_baseline.toml", "tillage_redesign.toml"):
        loaded = load_spec(LIBRARY / "tillage" / name)
        result = json.loads(result_text(kinds.get("tillage_linkage").check(loaded)))
        assert "dynamics" not in result["facts"]
        assert [r["name"] for r in result["rules"]] == ["working_depth", "lift_height", "rearward_in_soil",
                                                        "bar_slot_angle", "bar_engagement"]


@pytest.mark.parametrize("old, new, field", [
    ('{ link = "bar", mass = 1.5, at = "tip"', '{ link = "crank", mass = 1.5, at = "tip"', "dynamics: point_masses"),
    ('{ link = "bar", mass = 1.5', '{ link = "rocker", mass = 1.5', "dynamics.point_masses.1.link"),
    ("k = 5.88 ", "k = -1.0 ", "dynamics.soil.k"),
    ("source = \"assumption: k", "note = \"assumption: k", "dynamics.soil"),
    ("samples = 360", "samples = 360\ncrank_speed = 60.0", "dynamics.crank_speed"),
    ("samples = 360", "samples = 360\nroller_friction = 1.5", "dynamics.roller_friction"),
    ("bar = { density = 7850, area = 400 }", "bar = { density = 0.0, area = 400 }", "dynamics.bar"),
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


def test_the_peak_torque_objective_needs_the_table(tmp_path):
    text = DYNAMICS_SPEC.read_text()
    path = tmp_path / "spec.toml"
    path.write_text(text[:text.index("\n[dynamics]")] + "\n[objective]\nname = \"min_peak_torque\"\n")
    with pytest.raises(SpecError) as err:
        load_spec(path)
    assert err.value.exit_code == 2
    assert "objective.name = 'min_peak_torque' needs a [dynamics] table" in str(err.value)


def test_a_dynamics_table_built_from_numbers_and_symbols_is_one_model():
    """TillageDynamics on symbols (the NLP) and on floats (check) evaluate to the same torque."""
    spec = load_spec(DYNAMICS_SPEC).model
    z = ca.SX.sym("z", 5)
    symbolic = linkage_dynamics(spec, z[0], z[1], z[2], z[3], z[4]).over(turn(36))["torque"]
    x0 = [120.0, 250.0, 500.0, math.radians(20.0), 130.0]
    on_symbols = np.asarray(ca.Function("t", [z], [symbolic])(x0), float).ravel()
    on_floats = linkage_dynamics(spec, *x0).over(turn(36))["torque"]
    assert isinstance(linkage_dynamics(spec, *x0), TillageDynamics)
    np.testing.assert_allclose(on_symbols, on_floats, rtol=1e-13, atol=1e-12)

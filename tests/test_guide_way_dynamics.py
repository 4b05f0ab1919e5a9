"""Inverse dynamics of the rotary-arm slide guide way (synthesis/kinds/guide_way/dynamics.py).

* An independent formulation: the Lagrangian of the arm and the claw body as a free two-link chain (theta, alpha),
  written out again in sympy from the paper's eq (5)-(7) on the conic written out again from its centre and axes,
  the arm at constant speed and alpha(theta) the path's (sympy's exact derivatives), every part of each body its own
  (bars with their own centres and inertias, the point masses): its two equations give the drive torque and the
  groove force, equal to the Newton-Euler model's at samples of every published stretch (both elbows).
* Energy balance from result.json alone: over each stretch of the controlled path the work of the drive torque is
  the change of kinetic plus potential energy, the energy rebuilt from the links' masses, inertias, centres and
  velocities in the file.
* The wall changes are where the groove force changes sign; the NLP's dynamics columns on symbols are the floats'.
* A spec without [dynamics] has neither dynamics rules nor facts (its library answers are unchanged: measured with
  studies/library_answers.py); tables that cannot hold are refused with exit 2 naming the field.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import sympy as sp
from conftest import LIBRARY

from synthesis import kinds
from synthesis.errors import SpecError
from synthesis.kinds.guide_way import path as pth
from synthesis.kinds.guide_way import spline as spl
from synthesis.kinds.guide_way.check import given_control
from synthesis.kinds.guide_way.dynamics import along, mass_vector
from synthesis.kinds.guide_way.scene import arm_of, spline_path
from synthesis.result import result_text
from synthesis.spec import load_spec

DYNAMICS_SPEC = LIBRARY / "guide_way" / "liang_2z_dynamics.toml"


def checked(text: str | None, tmp_path) -> dict:
    path = DYNAMICS_SPEC
    if text is not None:
        path = tmp_path / "spec.toml"
        path.write_text(text)
    return json.loads(result_text(kinds.get("guide_way").check(load_spec(path))))


def _lagrangian(spec):
    """(T, A, Td, Ad, Add) -> (the theta equation's left side, the alpha equation's, dN/dT, dN/dA) as numpy functions:
    the chain's kinetic and potential energy written part by part in SI units."""
    a, table = spec.arm, spec.dynamics
    R, d, r, beta = a.radius / 1e3, a.claw / 1e3, a.crank / 1e3, math.radians(a.beta)
    T, A, Td, Ad, Add = sp.symbols("T A Td Ad Add")
    P = sp.Matrix([-R * sp.sin(T), -R * sp.cos(T)])
    M = P + d * sp.Matrix([sp.sin(A), -sp.cos(A)])
    N = P - r * sp.Matrix([sp.sin(beta - A), sp.cos(beta - A)])
    assert table.arm.density == 7850.0 and table.claw.density == 7850.0      # the spec's bars, read below
    arm_mass = table.arm.density * table.arm.area * 1e-6 * R
    claw_mass, crank_mass = (table.claw.density * table.claw.area * 1e-6 * length for length in (d, r))
    points = {"roller": N, "tip": M}
    parts = [(arm_mass, P / 2, arm_mass * R * R / 12, -Td), (claw_mass, (P + M) / 2, claw_mass * d * d / 12, Ad),
             (crank_mass, (P + N) / 2, crank_mass * r * r / 12, Ad)]
    parts += [(pm.mass, points[pm.at], 0.0, Ad) for pm in table.point_masses]

    def velocity(q):
        return q.diff(T) * Td + q.diff(A) * Ad

    kinetic = sum(m * velocity(q).dot(velocity(q)) / 2 + inertia * w * w / 2 for m, q, inertia, w in parts)
    gx, gy = table.gravity
    potential = -sum(m * (gx * q[0] + gy * q[1]) for m, q, _, _ in parts)

    def rate(e):          # d/dt along a motion with theta'' = 0
        return e.diff(T) * Td + e.diff(A) * Ad + e.diff(Ad) * Add

    eq_theta = rate(kinetic.diff(Td)) - kinetic.diff(T) + potential.diff(T)
    eq_alpha = rate(kinetic.diff(Ad)) - kinetic.diff(A) + potential.diff(A)
    args = (T, A, Td, Ad, Add)
    return (sp.lambdify(args, eq_theta), sp.lambdify(args, eq_alpha), sp.lambdify(args, list(N.diff(T))),
            sp.lambdify(args, list(N.diff(A))))


def _conic_tip(piece):
    """(s, x(s), y(s)) of a conic piece, mm, written from its centre, axes and semi-axes."""
    s = sp.symbols("s")
    c = piece.conic
    t = piece.t0 + s * (piece.t1 - piece.t0)
    u, v = (c.p * c.branch * sp.cosh(t), c.q * sp.sinh(t)) if c.hyperbola else (c.p * sp.cos(t), c.q * sp.sin(t))
    (e1x, e1y), (e2x, e2y) = c.axes
    return s, c.centre[0] + e1x * u + e2x * v, c.centre[1] + e1y * u + e2y * v


def _spline_tip(path, u0: float):
    """(h, x(h), y(h)) of a spline path near u0, mm: the cubic through four of its points on u0's knot span (the
    spline is one cubic there), in h = u - u0."""
    n = path.n
    j = min(math.floor(u0 * n), n - 1)
    hs = (j + np.array([0.1, 0.4, 0.6, 0.9])) / n - u0
    points = spl.basis(n, u0 + hs) @ np.asarray(path.control, float)
    h = sp.symbols("h")
    coefficients = [np.polyfit(hs, points[:, axis], 3) for axis in (0, 1)]
    return h, *(sum(float(c) * h ** (3 - k) for k, c in enumerate(cs)) for cs in coefficients)


def _path_angles(s, x_mm, y_mm, branch: float, R: float, d: float):
    """s -> (theta, theta', theta'', alpha, alpha', alpha'') along a claw-tip curve (x(s), y(s)) in mm: sympy's exact
    derivatives of the inverse kinematics (eq 7) written out again (m)."""
    x, y = x_mm / 1e3, y_mm / 1e3
    rho = sp.sqrt(x * x + y * y)
    theta = sp.atan2(-x, -y) + branch * sp.acos((R * R + rho * rho - d * d) / (2 * R * rho))
    alpha = sp.atan2(x + R * sp.sin(theta), -(y + R * sp.cos(theta)))
    return sp.lambdify(s, [theta, theta.diff(s), theta.diff(s, 2), alpha, alpha.diff(s), alpha.diff(s, 2)])


def _lagrange_forces(equations, angles, s: float, omega: float) -> tuple[float, float, np.ndarray]:
    """(drive torque, groove force, groove normal) from both Lagrange equations of the free chain at the path's
    parameter ``s``, with the drive torque on theta and the groove force's generalised forces n . dN/dtheta and
    n . dN/dalpha."""
    eq_theta, eq_alpha, n_theta, n_alpha = equations
    th, th1, th2, al, al1, al2 = (float(v) for v in angles(s))
    a_t = al1 / th1
    a_tt = (al2 * th1 - al1 * th2) / th1 ** 3
    args = (th, al, omega, a_t * omega, a_tt * omega ** 2)
    tangent = np.array(n_theta(*args)) * th1 + np.array(n_alpha(*args)) * al1
    normal = np.array([-tangent[1], tangent[0]]) / np.hypot(*tangent)
    force = eq_alpha(*args) / (normal @ np.array(n_alpha(*args)))
    torque = eq_theta(*args) - force * (normal @ np.array(n_theta(*args)))
    return torque, force, normal


@pytest.mark.slow
def test_torque_and_groove_force_equal_the_lagrangian():
    """The published conics (both elbows) at 7 samples of every stretch: the model's drive torque and groove force
    equal the Lagrangian's to 1e-9 (of the larger of 1 and the value: N m, N), its normal to 1e-12."""
    spec = load_spec(DYNAMICS_SPEC).model
    table = spec.dynamics
    omega = table.arm_speed * 2.0 * math.pi / 60.0
    equations = _lagrangian(spec)
    for piece in pth.conic_pieces(spec):
        angles = _path_angles(*_conic_tip(piece), piece.branch, spec.arm.radius / 1e3, spec.arm.claw / 1e3)
        st = piece.stretch(9)
        out = along(st, arm_of(spec), mass_vector(spec), omega, table.gravity)
        for k, s in enumerate(st.u[1:-1], 1):
            torque, force, normal = _lagrange_forces(equations, angles, s, omega)
            assert out["torque"][k] == pytest.approx(torque, abs=1e-9 * max(1.0, abs(torque)))
            assert out["groove_force"][k] == pytest.approx(force, abs=1e-9 * max(1.0, abs(force)))
            assert np.allclose(out["normal"][:, k], normal, atol=1e-12)


@pytest.mark.slow
def test_the_spline_path_equals_the_lagrangian():
    """The solved smooth redesign (a spline: the claw tip a cubic on each knot span, refitted here from four of its
    points) at 3 samples of every stretch, the one before the fold on the plus elbow: drive torque and groove force
    as the Lagrangian's to 1e-7 (the refit's rounding)."""
    spec = load_spec(LIBRARY / "guide_way" / "smooth_redesign_dynamics.toml").model
    table = spec.dynamics
    omega = table.arm_speed * 2.0 * math.pi / 60.0
    equations = _lagrangian(spec)
    path = spline_path(spec, given_control(spec))
    for st in path.stretches(5):
        out = along(st, arm_of(spec), mass_vector(spec), omega, table.gravity)
        for k, u in enumerate(st.u[1:-1], 1):
            angles = _path_angles(*_spline_tip(path, float(u)), st.branch, spec.arm.radius / 1e3, spec.arm.claw / 1e3)
            torque, force, _ = _lagrange_forces(equations, angles, 0.0, omega)
            assert out["torque"][k] == pytest.approx(torque, abs=1e-7 * max(1.0, abs(torque))), st.name
            assert out["groove_force"][k] == pytest.approx(force, abs=1e-7 * max(1.0, abs(force))), st.name


def energy_from_file(dyn: dict) -> np.ndarray:
    """Kinetic plus potential energy (J) at every sample, from the links' entries of facts.dynamics alone."""
    g = np.array(dyn["gravity_mps2"])
    energy = np.zeros(len(dyn["crank_deg"]))
    for link in dyn["links"]:
        v, w = np.array(link["com_velocity_mps"]), np.array(link["angular_velocity_radps"])
        c = np.array(link["com_mm"]) / 1000.0
        energy += (0.5 * link["mass_kg"] * (v ** 2).sum(axis=1) + 0.5 * link["inertia_kgm2"] * w ** 2
                   - link["mass_kg"] * (c @ g))
    return energy


@pytest.mark.slow
def test_energy_balance_from_the_result_alone(tmp_path):
    """At 1440 samples: over each stretch the drive's work (trapezoid of the power over time) equals the change of
    energy to 5e-4 of its |work|; the energy rebuilt from the links equals the file's kinetic + potential."""
    text = DYNAMICS_SPEC.read_text().replace("samples = 360", "samples = 1440")
    dyn = checked(text, tmp_path)["facts"]["dynamics"]
    energy = energy_from_file(dyn)
    assert np.allclose(energy, np.add(dyn["kinetic_energy_J"], dyn["potential_energy_J"]), rtol=0, atol=1e-12)
    omega = dyn["crank_speed_rpm"] * math.pi / 30.0
    time = np.radians(dyn["crank_deg"]) / omega
    power, stretch = np.array(dyn["power_W"]), np.array(dyn["stretch"])
    assert np.allclose(power, np.array(dyn["input_torque_Nm"]) * omega, rtol=1e-15)
    for name in ("DE", "CD", "BC", "AB"):
        i = stretch == name
        work = np.trapezoid(power[i], time[i])
        assert abs(work - (energy[i][-1] - energy[i][0])) <= 5e-4 * np.trapezoid(np.abs(power[i]), time[i]), name


def test_the_library_check_facts_and_rules(tmp_path):
    """The published guide way at 60 r/min (every mass ours): the drive torque peaks at B, the groove force near the
    fold's dead point (D, 337 N) and 16.4 N outside the fold window (at C); the roller changes wall six times;
    the torque rule reads the same samples; keys and shapes as the four-bar kinds'."""
    result = checked(None, tmp_path)
    dyn = result["facts"]["dynamics"]
    n = len(dyn["crank_deg"])
    assert n == 360
    for key in ("input_torque_Nm", "power_W", "shaking_moment_Nm", "groove_force_N", "stretch"):
        assert len(dyn[key]) == n
    assert np.shape(dyn["shaking_force_N"]) == (n, 2)
    assert set(dyn["joints"]) == {"O", "P", "N"} and all(np.shape(v) == (n, 2) for v in dyn["joints"].values())
    assert [link["name"] for link in dyn["links"]] == ["arm", "claw"]
    summary = dyn["summary"]
    assert summary["input_torque_Nm"]["peak"] == pytest.approx(0.5455898, rel=1e-6)
    assert summary["input_torque_Nm"]["stretch"] == "AB"
    assert summary["groove_force_N"]["peak"] == pytest.approx(337.10, rel=1e-4)
    assert summary["groove_force_outside_fold_window_N"]["peak"] == pytest.approx(16.374, rel=1e-4)
    rule = next(r for r in result["rules"] if r["name"] == "peak_input_torque")
    assert rule["value"] == pytest.approx(summary["input_torque_Nm"]["peak"], rel=1e-12)
    force = np.array(dyn["groove_force_N"])
    changes = int(np.sum(np.sign(force[:-1]) * np.sign(force[1:]) < 0))
    assert changes == summary["wall_changes"] == len(dyn["wall_changes"]) == 6
    walls = dyn["groove_wall"]
    assert all(w == ("right" if f > 0 else "left") for w, f in zip(walls, force))
    # the groove force is the joint N's reaction, along the normal
    assert np.allclose(np.array(dyn["joints"]["N"]), force[:, None] * np.array(dyn["groove_normal"]), atol=1e-9)


def test_a_spec_without_the_table_has_no_dynamics():
    for name in ("liang_2z.toml",):
        loaded = load_spec(LIBRARY / "guide_way" / name)
        result = json.loads(result_text(kinds.get("guide_way").check(loaded)))
        assert "dynamics" not in result["facts"]
        assert not any(r["name"].startswith("peak_") for r in result["rules"])


def test_the_nlp_rules_are_the_check_model_on_symbols():
    """The NLP's dynamics columns on the spline's control points as symbols, evaluated at the solved redesign's, equal
    the float model's at the same samples (torque, shaking force, shaking moment) to 1e-10 of the peak (the samples next to the fold: 8e-12); and a limit makes rules
    of both, the NLP's with rows at every sample."""
    import casadi as ca

    from synthesis.kinds.guide_way.dynamics import along, limit_rules, symbolic_samples

    spec = load_spec(LIBRARY / "guide_way" / "smooth_redesign_dynamics.toml").model
    control = given_control(spec)
    x = ca.SX.sym("x", control.size)
    symbolic = ca.reshape(x, control.shape[1], control.shape[0]).T
    columns = ca.Function("columns", [x], list(symbolic_samples(spec, symbolic, 7)))
    values = [np.ravel(v) for v in columns(control.ravel())]
    omega = spec.dynamics.arm_speed * 2.0 * math.pi / 60.0
    parts = [along(st, arm_of(spec), mass_vector(spec), omega, spec.dynamics.gravity)
             for st in spline_path(spec, control).stretches(7)]
    torque = np.concatenate([p["torque"] for p in parts])
    force = np.concatenate([p["shaking_force"] for p in parts], axis=1)
    moment = np.concatenate([p["shaking_moment"] for p in parts])
    for got, want in zip(values, (torque, force[0], force[1], moment)):
        assert np.abs(got - want).max() <= 1e-10 * np.abs(want).max(), np.abs(got - want).max()
    limits = spec.dynamics.limits.model_copy(update={"peak_input_torque": 1.0})
    limited = spec.model_copy(update={"dynamics": spec.dynamics.model_copy(update={"limits": limits})})
    rules = limit_rules(limited, *symbolic_samples(limited, symbolic, 7))
    assert [r.name for r in rules] == ["peak_input_torque"]
    assert rules[0].nlp_rows[0][0].shape[0] == torque.size


@pytest.mark.parametrize("old, new, field", [
    ("arm_speed = 60.0", "arm_speed = -1.0", "dynamics.arm_speed"),
    ("arm_speed = 60.0", "", "dynamics.arm_speed"),
    ('link = "claw"\nmass = 0.06\nat = "roller"', 'link = "arm"\nmass = 0.06\nat = "roller"',
     "dynamics.point_masses.0"),
    ('link = "claw"\nmass = 0.06', 'link = "coupler"\nmass = 0.06', "dynamics.point_masses.0.link"),
    ("arm = { density = 7850.0, area = 200.0 }", "arm = { density = 0.0, area = 200.0 }", "dynamics.arm"),
    ("samples = 360", "samples = 4", "dynamics.samples"),
    ("peak_input_torque = 5.0", "peak_input_torque = 0.0", "dynamics.limits.peak_input_torque"),
    ("gravity = [0.0, -9.81]", "gravity = [0.0, nan]", "dynamics"),
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


def test_check_and_the_solve_s_re_check_read_the_dynamics_rules_on_one_grid():
    """check read the peak torque on [dynamics] samples, the solve's re-check on its finer grid: 0.4964 against
    0.4966 N m for one design.  Both read it on check.dynamics_samples: the same value, to the bit."""
    from types import SimpleNamespace

    from synthesis import kinds
    from synthesis.core.kind import Setting
    from synthesis.kinds.guide_way.solve import recheck
    from synthesis.spec import load_spec

    loaded = load_spec(LIBRARY / "guide_way" / "smooth_torque_limited.toml")
    checked = kinds.checker("guide_way")(loaded)
    rules = recheck(Setting(loaded.model), SimpleNamespace(design=checked.design)).rules
    torque = next(r for r in rules if r.name == "peak_input_torque").record().value
    assert torque == next(r["value"] for r in checked.rules if r["name"] == "peak_input_torque")

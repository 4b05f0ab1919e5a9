"""The planting arm's soil force on the claw and its counterweights on the crank and the rocker.

* The soil force in result.json equals the law f0 + k d, opposing C's velocity relative to the soil, evaluated here
  from the planting kinematics (C's position and velocity from synthesis.kinds.planting.kinematics, the surface from
  the lowest point found here by a bounded minimisation), at every sample, in and out of the soil.
* The energy balance closes from result.json alone with the soil's power in ``external_power_W`` (and does not
  without it), and over a turn the motor supplies what the soil takes.
* The dynamics rules with the soil: AD derivatives against central differences, away from the surface crossing.
* A counterweight on the rocker: the mass vector against a hand parallel-axis sum; and its effect on the shaking
  force and the input torque against the counterweight's own motion, computed here from the joints B and O'.
* The two-counterweight redesign of example 1 holds every kinematic rule on the fine grid and lowers the peak
  shaking force below the crank-only counterweight redesign's (problems/planting_arm/DYNAMICS.md).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from conftest import LIBRARY
from dynamics_support import energy_residuals
from synthesis import kinds
from synthesis.dynamics import mass as mass_properties
from synthesis.dynamics.fourbar import LINKS, SOIL_SPEED_EPS
from synthesis.errors import SpecError
from synthesis.kinds import solve_spec
from synthesis.kinds.planting.dynamics import SoilContact, arm_dynamics, arm_dynamics_rules, arm_linkage
from synthesis.kinds.planting.kinematics import ArmDesign, Motion, joint_positions, tip_state
from synthesis.result import result_text
from synthesis.spec import load_spec
from synthesis.spec.dynamics import Counterweight, DynamicsLimits

SOIL_SPEC = LIBRARY / "planting_arm" / "taiwan_example1_soil.toml"
#: the crank-only counterweight redesign's peak shaking force, N (tests/test_library.py's record of its solve)
CRANK_ONLY_PEAK = 10.213169268527457


@pytest.fixture(scope="module")
def soil_result() -> dict:
    """result.json's data of ``check`` on the soil spec, as written (strict JSON) and read back."""
    loaded = load_spec(SOIL_SPEC)
    return json.loads(result_text(kinds.get(loaded.kind).check(loaded)))


def lowest_y(design: ArmDesign) -> float:
    """The lowest Y of the claw tip over a turn (mm): a grid of 3600 angles, then a bounded minimisation."""
    grid = np.linspace(0.0, 2 * math.pi, 3600, endpoint=False)
    motion = Motion(1.0, 0.0)
    k = int(np.argmin(tip_state(design, motion, grid).pos[1]))
    found = minimize_scalar(lambda t: float(tip_state(design, motion, t).pos[1, 0]),
                            bounds=(grid[k] - grid[1], grid[k] + grid[1]), method="bounded",
                            options={"xatol": 1e-12})
    return float(found.fun)


@pytest.mark.slow         # the first check of a soil spec builds its dynamics Functions (about 2 s)
def test_soil_force_equals_the_law_from_the_claw_kinematics(soil_result):
    spec = load_spec(SOIL_SPEC).model
    dyn = soil_result["facts"]["dynamics"]
    soil = dyn["external_loads"]
    law = spec.dynamics.soil
    design = ArmDesign(*(spec.design_values()[k] for k in ("l1", "l2", "l3", "l4", "l5", "zeta", "phi")),
                       branch=spec.arm.branch)
    omega = spec.operation.crank_speed * 2 * math.pi / 60
    forward = spec.operation.forward_speed
    surface = lowest_y(design) + spec.soil.analysis_depth
    assert soil["loads"][-1]["surface_y_mm"] == pytest.approx(surface, abs=1e-7)
    state = tip_state(design, Motion(omega, 0.0), np.radians(dyn["crank_deg"]))
    depth = surface - state.pos[1]
    relative = state.vel / 1000.0 + np.array([[forward], [0.0]])         # C relative to the soil, m/s
    magnitude = np.where(depth > 0.0, law.f0 + law.k * depth, 0.0)
    expected = -magnitude * relative / np.sqrt((relative ** 2).sum(0) + SOIL_SPEED_EPS ** 2)
    force = np.array(soil["force_N"]).T
    inside = depth > 0.0
    assert inside.sum() >= 60 and (~inside).sum() >= 200          # about 90 deg of the turn in the soil
    np.testing.assert_allclose(np.array(soil["depth_mm"]), depth, atol=1e-7)
    np.testing.assert_allclose(force, expected, rtol=0, atol=1e-9 * law.k * spec.soil.analysis_depth)
    assert np.all(force[:, ~inside] == 0.0)
    # the deepest sample: 25 mm below the surface, k x 25 mm = 73.5 N against C's motion through the soil
    assert np.hypot(*force).max() == pytest.approx(law.k * spec.soil.analysis_depth, rel=1e-4)
    assert np.all((force * relative).sum(0)[inside] < 0.0)


@pytest.mark.slow         # shares the check of the test above
def test_energy_balance_with_the_soil_from_result_json(soil_result):
    dyn = soil_result["facts"]["dynamics"]
    work, change, net = energy_residuals(dyn)
    peak = np.abs(change).max()
    assert peak > 1e-2
    assert np.abs(work - change).max() <= 1e-9 * peak
    assert abs(net) <= 1e-9 * peak
    # the soil's power is in the file: without it the balance misses by a sizeable fraction of the energy swing
    without = {**dyn, "external_loads": False}
    assert np.abs(energy_residuals(without)[0] - change).max() > 0.3 * peak
    # over a turn the motor supplies what the soil takes
    soil_power = dyn["summary"]["mean_soil_power_W"]
    assert soil_power < -1.0
    assert np.mean(dyn["power_W"]) == pytest.approx(-soil_power, rel=1e-9)


@pytest.mark.slow         # shares the check of the tests above
def test_peak_torque_with_and_without_soil(soil_result):
    """The published example 1 (DYNAMICS.md): 2.524 N m at crank 340 deg without soil, 2.714 N m at 313 deg with
    k = 2.94 N/mm; the soil force peaks at 73.5 N, the deepest point."""
    summary = soil_result["facts"]["dynamics"]["summary"]
    assert summary["input_torque_Nm"]["peak"] == pytest.approx(2.7137, abs=5e-5)
    assert summary["input_torque_Nm"]["peak_at_crank_deg"] == pytest.approx(313.0)
    assert summary["soil_force_N"]["peak"] == pytest.approx(73.498, abs=5e-4)
    loaded = load_spec(LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml")
    plain = kinds.get(loaded.kind).check(loaded).extra["dynamics"]["summary"]
    assert plain["input_torque_Nm"]["peak"] == pytest.approx(2.5242, abs=5e-5)
    assert "soil_force_N" not in plain


def test_soil_rule_derivatives_equal_central_differences():
    """The dynamics rules' rows with the soil law, by AD in the arm parameters, the soil surface and the forward speed
    against central differences, at a design where no sample lies within 0.5 mm of the surface (the law has a kink
    there)."""
    table = load_spec(SOIL_SPEC).model.dynamics
    table = table.model_copy(update={"limits": DynamicsLimits(peak_input_torque=1.0, peak_shaking_force=20.0,
                                                              peak_shaking_moment=5.0)})
    omega, samples = 250 * 2 * math.pi / 60, 36
    x = ca.SX.sym("x", 9)                # l1..l5 mm, zeta, phi rad, surface mm, forward speed m/s
    dyn = arm_dynamics(table, x[:7], -1, omega, contact=SoilContact(x[7], x[8]))
    rules = {r.name: r for r in arm_dynamics_rules(dyn, samples)}
    rows = ca.vertcat(*[rules[n].rows()[0][0] for n in ("peak_input_torque", "peak_shaking_force",
                                                        "peak_shaking_moment")])
    f = ca.Function("rows", [x], [rows, ca.jacobian(rows, x)])
    x0 = np.array([75.0, 35.0, 75.0, 80.0, 191.0, math.radians(-90.0), math.radians(31.0), -53.0, 0.6])
    depth = np.asarray(arm_linkage(table, x0[:7], -1, omega, contact=SoilContact(x0[7], x0[8])).over_turn(
        np.linspace(0.0, 2 * math.pi, samples, endpoint=False))["soil_depth"])
    assert (depth > 0.0).sum() >= 6 and np.abs(depth).min() > 0.5
    jac = np.asarray(f(x0)[1])
    for i, h in enumerate([1e-4] * 5 + [1e-6] * 2 + [1e-4, 1e-6]):
        step = np.zeros(9)
        step[i] = h
        central = (np.asarray(f(x0 + step)[0]) - np.asarray(f(x0 - step)[0])) / (2 * h)
        np.testing.assert_allclose(jac[:, i:i + 1], central, rtol=1e-6, atol=1e-6 * np.abs(jac[:, i]).max())
    assert np.abs(jac[:, 7]).max() > 1e-2 and np.abs(jac[:, 8]).max() > 1e-2     # the surface and speed count


def test_rocker_counterweight_by_the_parallel_axis_sum():
    """A steel bar rocker (7850 kg/m^3, 100 mm^2, 80 mm) with 0.2 kg at 50 mm opposite B, by hand:
    bar 0.0628 kg at x = 40 mm, inertia 0.0628 x 0.08^2 / 12 = 3.349333e-5 kg m^2; together 0.2628 kg at
    x = (0.0628 x 40 - 0.2 x 50) / 0.2628 = -28.493151 mm; inertia about it 3.349333e-5
    + 0.0628 x (40 + 28.493151)^2 e-6 + 0.2 x (50 - 28.493151)^2 e-6 = 3.349333e-5 + 2.946144e-4 + 9.250891e-5
    = 4.206166e-4 kg m^2.  The crank and the coupler stay as they were."""
    table = load_spec(LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml").model.dynamics
    bars = {"crank": [((0.0, 0.0), (35.0, 0.0))], "coupler": [((0.0, 0.0), (75.0, 0.0))],
            "rocker": [((0.0, 0.0), (80.0, 0.0))]}
    plain = [float(v) for v in mass_properties.mass_vector(table, bars, LINKS, {"coupler": (150.0, -90.0)})]
    weighted = [float(v) for v in mass_properties.mass_vector(table, bars, LINKS, {"coupler": (150.0, -90.0)},
                                                               rocker_counterweight=(0.2, 50.0))]
    assert weighted[:8] == plain[:8]
    assert weighted[8:] == pytest.approx([0.2628, -0.028493151, 0.0, 4.206166e-4], rel=2e-7, abs=1e-12)


def test_rocker_counterweight_moves_the_shaking_force_and_torque_by_its_own_motion():
    """Adding m at -r along the rocker adds -m (a - g) to the shaking force and m (a - g) . v / omega to the input
    torque, a and v the counterweight's, from the joints O' and B (planting kinematics) by a five-point difference in
    the crank angle, at 24 crank angles."""
    spec = load_spec(LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml").model
    table = spec.dynamics
    design = ArmDesign(75.0, 35.0, 75.0, 80.0, 191.0, -90.0, 31.0, -1)
    omega, mass, radius = 250 * 2 * math.pi / 60, 0.3, 45.0
    crank = np.linspace(0.0, 2 * math.pi, 24, endpoint=False)
    base = arm_linkage(table, design.parameters(), -1, omega).over_turn(crank)
    weighted = arm_linkage(table, design.parameters(), -1, omega, rocker_counterweight=(mass, radius)).over_turn(crank)

    def position(theta):                    # m, machine frame
        joints = joint_positions(design, theta)
        pivot, b = joints["O'"], joints["B"]
        return (pivot - radius * (b - pivot) / design.l4) / 1000.0

    h = 1e-3
    p = [position(crank + k * h) for k in (-2, -1, 0, 1, 2)]
    velocity = (p[0] - 8 * p[1] + 8 * p[3] - p[4]) / (12 * h) * omega
    acceleration = (-p[0] + 16 * p[1] - 30 * p[2] + 16 * p[3] - p[4]) / (12 * h * h) * omega ** 2
    need = mass * (acceleration - np.array(table.gravity).reshape(2, 1))
    scale = np.abs(need).max()
    assert scale > 1.0
    np.testing.assert_allclose(weighted["shaking_force"] - base["shaking_force"], -need, atol=2e-6 * scale)
    power = (need * velocity).sum(0)
    np.testing.assert_allclose(weighted["torque"] - base["torque"], power / omega,
                               atol=2e-6 * np.abs(power / omega).max())


def test_a_kind_that_does_not_read_the_rocker_counterweight_refuses_it():
    """picker_double_crank builds its dynamics without a rocker counterweight: the field is refused by name."""
    loaded = load_spec(LIBRARY / "picker" / "cai2020_double_crank_dynamics.toml")
    table = loaded.model.dynamics.model_copy(update={"rocker_counterweight": Counterweight(mass=0.2, radius=40.0)})
    spec = loaded.model.model_copy(update={"dynamics": table})
    with pytest.raises(SpecError, match=r"^dynamics\.rocker_counterweight: "):
        kinds.get(spec.kind).check(replace(loaded, model=spec))


@pytest.mark.slow       # the redesign's solve: 16 starts, 20-70 s on one worker
@pytest.mark.long
def test_two_counterweight_redesign_beats_the_crank_only_one():
    loaded = load_spec(LIBRARY / "planting_arm" / "two_counterweights_min_shaking_from_example1.toml")
    solved, _, _ = solve_spec(loaded, workers=1)
    assert solved.status == "optimal"
    # every rule, kinematic and dynamic, on the fine grid of the re-check
    assert solved.rules and all(r["satisfied"] for r in solved.rules)
    kinematic = {r["name"] for r in solved.rules}
    assert {"planting_depth", "entry_angle", "p1p3_distance", "transmission_angle_min"} <= kinematic
    design = solved.design
    assert design["rocker_counterweight_mass"] > 0.1
    peak = solved.objective["value"]
    assert peak < 0.8 * CRANK_ONLY_PEAK               # 7.872 N against 10.213 N: 22.9 % lower
    assert peak == pytest.approx(7.8720, abs=5e-4)
    # the design's own check (360 samples of result.json) agrees with the solve's 3600-angle peak
    summary = solved.extra["dynamics"]["summary"]["shaking_force_N"]
    assert summary["peak"] <= peak + 1e-9 and summary["peak"] == pytest.approx(peak, rel=1e-3)

"""The planting arm's soil force on the claw and its counterweights on the crank and the rocker.

* The soil force in result.json equals the law f0 + k d, opposing C's velocity relative to the soil, evaluated here
  from the planting kinematics (C's position and velocity from synthesis.kinds.planting.kinematics, the surface from
  the lowest point found here by a bounded minimisation), at every sample, in and out of the soil.
* The energy balance closes from result.json alone with the soil's power in ``external_power_W`` (and does not
  without it), and over a turn the motor supplies what the soil takes.
* The dynamics rules with the soil: AD derivatives against central differences, away from the surface crossing.
* A counterweight on the rocker: the mass vector against a hand parallel-axis sum; and its effect on the shaking
  force and the input torque against the counterweight's own motion, computed here from the joints B and O'.
* The counterweight clearance rules: each counterweight's lowest point over a turn above the soil surface, against
  the joints of the planting kinematics and the lowest claw point found here, on the designs an independent review
  found underground; in the NLP, one row per sample of the turn equal to the same heights; no rule without a
  counterweight or with a zero mass; the caveat on a radius longer than its link.
* The crank-only counterweight redesign holds every rule on the fine grid with its counterweight clear of the soil;
  the two-counterweight one is infeasible: its rocker counterweight would sit below the rocker pivot O', which lies
  below the soil surface (problems/planting_arm/DYNAMICS.md).
* crank_rocker's rocker counterweight, fourbar_path's and picker_double_crank's refusal of it at load.
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
from synthesis.kinematics.rocker_drive import CrankRocker, rocker_curve
from synthesis.kinds.planting.dynamics import SoilContact, arm_dynamics, arm_dynamics_rules, arm_linkage
from synthesis.kinds.planting.check import evaluate
from synthesis.kinds.planting.kinematics import ArmDesign, Motion, joint_positions, tip_state
from synthesis.kinds.planting.nlp import PlantingProblem
from synthesis.kinds.planting.scene import PlantingScene
from synthesis.result import result_text
from synthesis.spec import load_spec
from synthesis.spec.dynamics import Counterweight, DynamicsLimits

SOIL_SPEC = LIBRARY / "planting_arm" / "taiwan_example1_soil.toml"
#: the crank-only counterweight redesign's peak shaking force with its counterweight clear of the soil, N
#: (tests/test_library.py's record of its solve)
CRANK_ONLY_PEAK = 12.396999267196685
#: the designs an independent review found with a counterweight underground (the two redesigns solved before the
#: clearance rule), to 4 decimals: the crank-only one, 0.163 kg at 60 mm on the crank; the two-counterweight one,
#: 0.291 kg at 60 mm on the rocker (its crank counterweight 0 kg)
CRANK_ONLY_UNDERGROUND = {"l1": 75.0, "l2": 29.0356, "l3": 61.5169, "l4": 64.0, "l5": 152.8, "zeta": -85.6525,
                          "phi": 42.5969, "seedbed_x": -195.4528, "seedbed_y": -12.6289, "seedbed_tilt": -26.7676,
                          "counterweight_mass": 0.1628, "counterweight_radius": 60.0}
TWO_UNDERGROUND = {"l1": 75.0, "l2": 31.6948, "l3": 61.8785, "l4": 64.0, "l5": 152.8, "zeta": -90.093, "phi": 30.5987,
                   "seedbed_x": -220.6, "seedbed_y": -30.1, "seedbed_tilt": -18.0555, "counterweight_mass": 0.0,
                   "counterweight_radius": 2.3117, "rocker_counterweight_mass": 0.2906,
                   "rocker_counterweight_radius": 60.0}


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
    # the claw moves forward through the soil (ground speed +0.22 to +0.92 m/s), so the soil pushes it backwards
    assert relative[0, inside].min() == pytest.approx(0.2197, abs=1e-4)
    assert relative[0, inside].max() == pytest.approx(0.9248, abs=1e-4)
    assert np.all(force[0, inside] < 0.0)
    # the soil dissipates -F . v_rel (ground frame): 10.16 W, the crank's 5.49 W and the drawbar's -F_x v_f 4.68 W
    summary = dyn["summary"]
    dissipated = float(np.mean(-(force * relative).sum(0)))
    assert summary["mean_soil_dissipation_W"] == pytest.approx(dissipated, rel=1e-9)
    assert dissipated == pytest.approx(10.162, abs=1e-3)
    through_crank = float(np.mean((force * state.vel / 1000.0).sum(0)))
    assert summary["mean_soil_power_W"] == pytest.approx(through_crank, rel=1e-9)
    assert through_crank == pytest.approx(-5.486, abs=1e-3)
    assert float(np.mean(-force[0] * forward)) == pytest.approx(4.676, abs=1e-3)


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


def point_mass_load(position, crank, omega: float, mass: float, gravity) -> tuple[np.ndarray, np.ndarray]:
    """(m (a - g) N, velocity m/s) of a point mass whose position (m) is ``position(crank angle)``, the crank turning
    at ``omega``: its motion by five-point differences in the crank angle, independent of the dynamics' AD."""
    h = 1e-3
    p = [position(crank + k * h) for k in (-2, -1, 0, 1, 2)]
    velocity = (p[0] - 8 * p[1] + 8 * p[3] - p[4]) / (12 * h) * omega
    acceleration = (-p[0] + 16 * p[1] - 30 * p[2] + 16 * p[3] - p[4]) / (12 * h * h) * omega ** 2
    return mass * (acceleration - np.array(gravity).reshape(2, 1)), velocity


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

    need, velocity = point_mass_load(position, crank, omega, mass, table.gravity)
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


def clearance_rules(spec_name: str, values: dict) -> tuple[dict, PlantingScene]:
    """The check's rules (name -> record) of a design of a library spec, and its scene."""
    spec = load_spec(LIBRARY / "planting_arm" / f"{spec_name}.toml").model
    scene = PlantingScene.from_spec(spec, values)
    rules, _ = evaluate(scene, spec.rules)
    return {r.name: r.record() for r in rules}, scene


def rocker_counterweight_lowest(design: ArmDesign, radius: float) -> float:
    """The lowest Y (mm) of a counterweight at -radius along the rocker O'B, from the joints on 200,001 crank angles
    (the sampling error, about r psi'' h^2 / 8, is below 1e-8 mm)."""
    theta = np.linspace(0.0, 2 * math.pi, 200001)
    joints = joint_positions(design, theta)
    pivot, b = joints["O'"], joints["B"]
    return float((pivot - radius * (b - pivot) / design.l4)[1].min())


def arm_of(values: dict) -> ArmDesign:
    return ArmDesign(*(values[k] for k in ("l1", "l2", "l3", "l4", "l5", "zeta", "phi")), branch=-1)


def test_the_review_s_rocker_counterweight_is_underground():
    """The two-counterweight design solved before the rule: 0.291 kg at 60 mm opposite B, its lowest point Y =
    -130.1 mm against the surface 25 mm above the lowest claw point, Y = -55.6 mm: 74.5 mm underground, the rule
    missed by 84.5 mm.  The crank's counterweight of 0 kg takes no rule."""
    rules, _ = clearance_rules("two_counterweights_min_shaking_from_example1", TWO_UNDERGROUND)
    design = arm_of(TWO_UNDERGROUND)
    surface = lowest_y(design) + 25.0
    lowest = rocker_counterweight_lowest(design, 60.0)
    assert surface == pytest.approx(-55.64, abs=0.01) and lowest == pytest.approx(-130.10, abs=0.01)
    rule = rules["rocker_counterweight_clearance"]
    assert rule.value == pytest.approx(lowest - surface, abs=1e-7)
    assert rule.limit == [10.0, None] and rule.unit == "mm" and not rule.satisfied
    assert rule.margin == pytest.approx(lowest - surface - 10.0, abs=1e-7)
    assert rule.note is None                                # 60 mm on a 64 mm rocker
    assert "counterweight_clearance" not in rules


def test_the_review_s_crank_counterweight_is_underground_and_longer_than_the_crank():
    """The crank-only design solved before the rule: 0.163 kg at 60 mm circles the crank pivot O (the origin), so
    its lowest point is Y = -60 mm exactly, 26.7 mm below the surface (25 mm above its lowest claw point, Y =
    -33.26 mm); 60 mm is longer than its 29.0 mm crank, which the rule's note says."""
    rules, _ = clearance_rules("counterweight_min_shaking_from_example1", CRANK_ONLY_UNDERGROUND)
    surface = lowest_y(arm_of(CRANK_ONLY_UNDERGROUND)) + 25.0
    assert surface == pytest.approx(-33.26, abs=0.01)
    rule = rules["counterweight_clearance"]
    assert rule.value == pytest.approx(-60.0 - surface, abs=1e-7) and not rule.satisfied
    assert "longer than the crank itself (29.04 mm)" in rule.note
    assert "rocker_counterweight_clearance" not in rules


def test_no_counterweight_no_clearance_rule():
    """Without a counterweight, or with one of a given zero mass, no clearance rule; with a given mass, the rule
    with the spec's clearance."""
    loaded = load_spec(LIBRARY / "planting_arm" / "taiwan_example1_dynamics.toml")
    spec = loaded.model
    plain = [r["name"] for r in kinds.get(spec.kind).check(loaded).rules]
    assert not [n for n in plain if "counterweight" in n]
    for mass, clearance, expected in ((0.0, 10.0, None), (0.2, 10.0, 10.0), (0.2, 4.0, 4.0)):
        table = spec.dynamics.model_copy(update={"counterweight": Counterweight(mass=mass, radius=20.0),
                                                 "counterweight_clearance": clearance})
        rules, _ = evaluate(PlantingScene.from_spec(spec.model_copy(update={"dynamics": table})), spec.rules)
        limits = [r.lower for r in rules if r.name == "counterweight_clearance"]
        assert limits == ([] if expected is None else [expected])


@pytest.mark.slow         # builds the planting NLP (about 1.5 s)
def test_nlp_rows_are_the_counterweights_heights_at_the_turn_samples():
    """The NLP's clearance rows at the review's two-counterweight design, P5 at its root-found crank angle: the
    crank's one row -radius - surface, the rocker's one per sample of the turn, its counterweight's Y from the joints
    minus the surface (25 mm above the lowest claw point found here)."""
    spec = load_spec(LIBRARY / "planting_arm" / "two_counterweights_min_shaking_from_example1.toml").model
    problem = PlantingProblem(spec)
    x0 = np.concatenate([[TWO_UNDERGROUND[n] for n in problem.names], problem.theta_guess(TWO_UNDERGROUND)])
    rules = {r.name: r for r in problem.problem.rules}
    rows = {n: np.asarray(ca.Function("rows", [problem.problem.x], [rules[n].rows()[0][0]])(x0), float).ravel()
            for n in ("counterweight_clearance", "rocker_counterweight_clearance")}
    design = arm_of(TWO_UNDERGROUND)
    surface = lowest_y(design) + 25.0
    assert rows["counterweight_clearance"] == pytest.approx([-2.3117 - surface], abs=1e-7)
    turn = np.linspace(0.0, 2 * math.pi, spec.solver.samples_per_turn, endpoint=False)
    joints = joint_positions(design, turn)
    expected = (joints["O'"] - 60.0 * (joints["B"] - joints["O'"]) / design.l4)[1] - surface
    np.testing.assert_allclose(rows["rocker_counterweight_clearance"], expected, atol=1e-7)
    assert rules["rocker_counterweight_clearance"].lower == 10.0


@pytest.mark.slow       # the redesign's solve: 16 starts, about 16 s on one worker
def test_crank_only_redesign_with_its_counterweight_clear_of_the_soil():
    loaded = load_spec(LIBRARY / "planting_arm" / "counterweight_min_shaking_from_example1.toml")
    solved, _, _ = solve_spec(loaded, workers=1)
    assert solved.status == "optimal"
    assert solved.rules and all(r["satisfied"] for r in solved.rules)
    rules = {r["name"]: r for r in solved.rules}
    design = solved.design
    # the clearance binds (to the back-off, 0.02 x 10 mm): the radius is the surface's depth below O less 10 mm
    assert rules["counterweight_clearance"]["value"] == pytest.approx(10.2, abs=1e-5)
    surface = lowest_y(arm_of(design)) + 25.0
    assert design["counterweight_radius"] == pytest.approx(-surface - 10.2, abs=1e-5)
    peak = solved.objective["value"]
    assert peak == pytest.approx(CRANK_ONLY_PEAK, abs=5e-4)
    assert peak > 10.2132                # above the underground answer's 10.213 N: the clearance costs 2.18 N
    summary = solved.extra["dynamics"]["summary"]["shaking_force_N"]
    assert summary["peak"] <= peak + 1e-9 and summary["peak"] == pytest.approx(peak, rel=1e-3)


@pytest.mark.slow       # the redesign's solve: 16 starts, about 30 s on one worker
@pytest.mark.long
def test_two_counterweight_redesign_is_infeasible_with_the_rocker_counterweight_clear_of_the_soil():
    """The rocker's counterweight sits at O' - r (B - O') / l4 with B above O' all turn, so it is never above O',
    which is 19 to 22 mm below the surface in these bounds: even at radius 0 the clearance conflicts with the
    transmission angle, the entry angle and the hole length (the elastic diagnosis)."""
    loaded = load_spec(LIBRARY / "planting_arm" / "two_counterweights_min_shaking_from_example1.toml")
    solved, _, _ = solve_spec(loaded, workers=1)
    assert solved.status == "infeasible"
    elastic = solved.to_json()["elastic"]
    assert "rocker_counterweight_clearance" in elastic["conflicting"]
    assert "transmission_angle_min" in elastic["conflicting"]
    assert elastic["design"]["rocker_counterweight_radius"] == pytest.approx(0.0, abs=1e-6)


def test_crank_rocker_rocker_counterweight_by_its_own_motion():
    """crank_rocker's check reads ``[dynamics] rocker_counterweight`` (numbers): m at -r along the rocker AE adds
    -m (a - g) to result.json's shaking force and m (a - g) . v / omega to its input torque, a and v the
    counterweight's, from the rocker tip E of synthesis.kinematics.rocker_drive by a five-point difference in the
    crank angle, at the check's 360 samples."""
    loaded = load_spec(LIBRARY / "picker" / "cai2020_crank_rocker_dynamics.toml")
    table = loaded.model.dynamics
    mass, radius = 0.25, 40.0
    weighted_table = table.model_copy(update={"rocker_counterweight": Counterweight(mass=mass, radius=radius)})
    weighted_spec = replace(loaded, model=loaded.model.model_copy(update={"dynamics": weighted_table}))
    kind = kinds.get(loaded.kind)
    base = json.loads(result_text(kind.check(loaded)))["facts"]["dynamics"]
    weighted = json.loads(result_text(kind.check(weighted_spec)))["facts"]["dynamics"]
    cr = CrankRocker(*(loaded.model.design_values()[k] for k in ("l7", "l8", "l9", "l10")), loaded.model.branch)
    omega = table.crank_speed * 2 * math.pi / 60
    crank = np.radians(base["crank_deg"])
    pivot = np.array([[cr.l10], [0.0]])

    def position(phi):                      # m, the mechanism's frame
        return (pivot - radius * (rocker_curve(cr, phi)["tip"] - pivot) / cr.l9) / 1000.0

    need, velocity = point_mass_load(position, crank, omega, mass, table.gravity)
    scale = np.abs(need).max()
    assert scale > 1.0
    shaking = np.array(weighted["shaking_force_N"]).T - np.array(base["shaking_force_N"]).T
    np.testing.assert_allclose(shaking, -need, atol=2e-6 * scale)
    torque = np.array(weighted["input_torque_Nm"]) - np.array(base["input_torque_Nm"])
    power = (need * velocity).sum(0)
    np.testing.assert_allclose(torque, power / omega, atol=2e-6 * np.abs(power / omega).max())


@pytest.mark.parametrize("spec_path, message", [
    ("picker/cai2020_double_crank_dynamics.toml", "a picker_double_crank reads a counterweight on its input crank AB only"),
    ("fourbar_path/picking_arc_dynamics.toml", "a fourbar_path reads a counterweight on its crank only")])
def test_kinds_without_a_rocker_counterweight_refuse_it_at_load(tmp_path, spec_path, message):
    """The spec validator refuses the field by name, before any dynamics are built."""
    text = (LIBRARY / spec_path).read_text() + "\n[dynamics.rocker_counterweight]\nmass = 0.2\nradius = 40.0\n"
    path = tmp_path / "spec.toml"
    path.write_text(text)
    with pytest.raises(SpecError, match=r"dynamics\.rocker_counterweight: " + message):
        load_spec(path)
    path.write_text((LIBRARY / spec_path).read_text())
    load_spec(path)                      # the spec itself loads


@pytest.mark.parametrize("name", ["counterweight", "rocker_counterweight"])
def test_a_free_counterweight_mass_allowed_down_to_zero_is_refused_naming_it(tmp_path, name):
    """The clearance rows hold a counterweight that exists: a free mass down to 0 kg would let the NLP call
    infeasible what a 0 kg counterweight (none) satisfies, so the spec asks for a lower bound above 0."""
    text = (LIBRARY / "planting_arm" / "two_counterweights_min_shaking_from_example1.toml").read_text()
    line = f"{name} = {{ mass = {{ init = 0.05, bounds = [0.01, 0.5] }}"
    assert line in text
    path = tmp_path / "zero.toml"
    path.write_text(text.replace(line, f"{name} = {{ mass = {{ init = 0.05, bounds = [0.0, 0.5] }}"))
    with pytest.raises(SpecError) as refused:
        load_spec(path)
    message = str(refused.value)
    assert f"{name}.mass" in message and "above 0 kg" in message and "\n" not in message.strip()


def test_clearance_rows_derivatives_equal_central_differences():
    """The two clearance rules' NLP rows, by AD in every NLP variable (the arm, the seedbed, both counterweights and
    the precision points' crank angles), against central differences at the review's two-counterweight design."""
    spec = load_spec(LIBRARY / "planting_arm" / "two_counterweights_min_shaking_from_example1.toml").model
    problem = PlantingProblem(spec)
    x = problem.problem.x
    rules = {r.name: r for r in problem.problem.rules}
    rows = ca.vertcat(*[ca.vec(ca.SX(rules[n].rows()[0][0]))
                        for n in ("counterweight_clearance", "rocker_counterweight_clearance")])
    f = ca.Function("rows", [x], [rows, ca.jacobian(rows, x)])
    x0 = np.concatenate([[TWO_UNDERGROUND[n] for n in problem.names], problem.theta_guess(TWO_UNDERGROUND)])
    x0[problem.names.index("counterweight_mass")] = 0.1             # the review's 0 kg moved inside the bounds
    jac = np.asarray(f(x0)[1])
    for i in range(x0.size):
        h = 1e-6 * max(1.0, abs(x0[i]))
        step = np.zeros(x0.size)
        step[i] = h
        central = (np.asarray(f(x0 + step)[0]) - np.asarray(f(x0 - step)[0])) / (2 * h)
        np.testing.assert_allclose(jac[:, i:i + 1], central, rtol=1e-6, atol=1e-6 * max(np.abs(jac).max(), 1.0),
                                   err_msg=f"variable {i}")
    assert np.count_nonzero(np.abs(jac).max(axis=0)) >= 6      # the rows move with the arm and both counterweights

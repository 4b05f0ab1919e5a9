"""The planting kind's float re-check (every Monte-Carlo sample of `agrisynth tolerance`, every start of the
multistart) gives the numbers it gave before it was made faster, to the bit.

The digests below were recorded at commit 835ab78, before the grids were evaluated by expanded SX functions
called through CasADi's buffer interface (synthesis.kinds.planting.kinematics._expanded, Evaluator): per library
spec, 50 designs near its given design (25 within +-0.5, 25 within +-4 in every design variable's unit; the
counterweight's mass +-0.01 kg), re-checked through the kind's ``Solving.recheck`` as the Monte-Carlo and the
multistart call it; every precision point's crank angle and every rule's value, margin, verdict and note, floats
as hex, hashed.  Many designs miss P1 or more, so the notes of the points not found are compared too.
"""

from __future__ import annotations

import hashlib
import json
import time

import numpy as np
import pytest
from conftest import PLANTING

from synthesis import kinds
from synthesis.core.kind import Setting
from synthesis.core.outcome import StartOutcome
from synthesis.errors import AgrisynthError
from synthesis.kinds.planting import kinematics
from synthesis.kinds.planting.scene import PlantingScene
from synthesis.spec import load_spec

DESIGNS_PER_SPEC = 50

#: sha256 (first 20 hex digits) of the re-check of each spec's 50 designs at commit 835ab78
RECORDED = {
    "counterweight_min_shaking_from_example1": "88ae9722bca5740252f6",
    "crank_speed_envelope_redesign_from_example1": "7b19cf49b5896cf1fc2d",
    "envelope_redesign_from_example1": "7b19cf49b5896cf1fc2d",
    "envelope_redesign_from_example2": "9fb287731622489df43a",
    "envelope_redesign_from_example3": "577ebf2e593b042f5b69",
    "envelope_redesign_from_example4": "bf31f8cfc42f665b2f7c",
    "infeasible_deep_planting": "0afeccf4a6066836b8ae",
    "min_peak_torque_from_example1": "7b19cf49b5896cf1fc2d",
    "redesign_from_example1": "7b19cf49b5896cf1fc2d",
    "redesign_from_example2": "9fb287731622489df43a",
    "redesign_from_example3": "577ebf2e593b042f5b69",
    "redesign_from_example4": "bf31f8cfc42f665b2f7c",
    "robust_envelope_redesign_from_example1": "7b19cf49b5896cf1fc2d",
    "robust_redesign_from_example1": "7b19cf49b5896cf1fc2d",
    "robust_redesign_from_example2": "9fb287731622489df43a",
    "robust_redesign_from_example3": "577ebf2e593b042f5b69",
    "robust_redesign_from_example4": "bf31f8cfc42f665b2f7c",
    "taiwan_example1": "7b19cf49b5896cf1fc2d",
    "taiwan_example1_dynamics": "7b19cf49b5896cf1fc2d",
    "taiwan_example2": "9fb287731622489df43a",
    "taiwan_example2_zeta_minus41": "69a2d386ac0746d4808d",
    "taiwan_example3": "577ebf2e593b042f5b69",
    "taiwan_example4": "bf31f8cfc42f665b2f7c",
    "torque_redesign_from_example1": "db0a5e82bdb33333b2cf",
}
#: rules added after the recording (a counterweight's clearance above the soil): left out of the digest, which so
#: proves every recorded rule unchanged (their values: tests/test_planting_soil_and_counterweights.py)
ADDED_SINCE = ("counterweight_clearance", "rocker_counterweight_clearance")
#: run by default: the Monte-Carlo's subject and the spec with a counterweight and dynamics rules; the rest: -m slow
QUICK = ("redesign_from_example1", "counterweight_min_shaking_from_example1")


def designs_near(design: dict, n: int, seed: int = 12345) -> list[dict]:
    rng = np.random.default_rng(seed)
    keys = sorted(k for k, v in design.items() if isinstance(v, (int, float)))
    out = []
    for i in range(n):
        half = 0.5 if i < n // 2 else 4.0
        out.append({**design, **{k: design[k] + float(rng.uniform(-(0.01 if k == "counterweight_mass" else half),
                                                                  0.01 if k == "counterweight_mass" else half))
                                 for k in keys}})
    return out


def _recheck(name: str):
    loaded = load_spec(PLANTING / f"{name}.toml")
    solving = kinds.get(loaded.kind).solving()
    setting = Setting(loaded.model, 0, solving.prepare(loaded.model))
    return loaded, lambda i, design: solving.recheck(setting, StartOutcome(i, design, 0.0, "", True, 0, 0.0, ""))


def _hex(x) -> str | None:
    return None if x is None else float(x).hex()


def _row(recheck) -> dict:
    _, pts = recheck.context
    return {"theta": None if pts is None else {k: _hex(v) for k, v in pts.theta.items()},
            "problems": None if pts is None else pts.problems,
            "rules": [[r.name, _hex(r.value), _hex(r.margin), bool(r.satisfied), getattr(r, "note", None)]
                      for r in (q.record() for q in recheck.rules) if r.name not in ADDED_SINCE]}


@pytest.mark.parametrize("name", [n if n in QUICK else pytest.param(n, marks=pytest.mark.slow) for n in RECORDED])
def test_recheck_of_designs_near_each_library_spec_is_what_it_was_to_the_bit(name):
    loaded, recheck = _recheck(name)
    rows, added = [], set()
    for i, design in enumerate(designs_near(loaded.model.design_values(), DESIGNS_PER_SPEC)):
        try:
            checked = recheck(i, design)
            added |= {r.name for r in checked.rules if r.name in ADDED_SINCE}
            rows.append(_row(checked))
        except (AgrisynthError, ValueError, ArithmeticError) as exc:   # as the Monte-Carlo counts a sample's raise
            rows.append({"raised": f"{type(exc).__name__}: {exc}"})
    assert any(rule[4] for r in rows for rule in r.get("rules", []))   # notes (of points not found) compared too
    assert added == ({"counterweight_clearance"} if "counterweight" in name else set())
    assert hashlib.sha256(json.dumps(rows, sort_keys=True).encode()).hexdigest()[:20] == RECORDED[name]


def test_one_recheck_in_plain_numbers():
    """Design 0 near example 1 as recorded at 835ab78 (P1 is not found there: the seedbed rules say why)."""
    loaded, recheck = _recheck("redesign_from_example1")
    rc = recheck(0, designs_near(loaded.model.design_values(), DESIGNS_PER_SPEC)[0])
    values = {r.name: r.value for r in (q.record() for q in rc.rules)}
    assert values["entry_angle"] == 78.50239766215908
    assert values["planting_depth"] == 25.000000000000064
    assert values["p4p6_distance"] == 28.871665220874718
    assert values["p2_speed"] == 1.828502759676001
    assert values["accel_hold"] == 5228.648510236027
    assert values["accel_throw"] == 16185.573327591439
    assert values["accel_release"] == 59710.48491641673
    assert values["transmission_angle_min"] == 29.535728342271543
    assert values["transmission_angle_max"] == 89.53487378024164
    assert values["p1p3_distance"] is None
    assert rc.context[1].theta["P2"] == float.fromhex("0x1.1a8344dac3d7bp+3")
    assert rc.context[1].theta["P5"] == float.fromhex("0x1.3edf4f9a027d5p+2")


def test_grid_functions_equal_the_full_functions_to_the_bit():
    """The expanded grid functions (only the rows read, repeated operations merged) against the full functions' map."""
    scene = PlantingScene.from_spec(load_spec(PLANTING / "redesign_from_example1.toml").model)
    d, m = scene.design, scene.motion
    theta = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False)
    state = kinematics.tip_state(d, m, theta)
    y, mu = kinematics.tip_heights_and_transmission(d, theta)
    assert np.array_equal(y, state.pos[1])
    assert np.array_equal(mu, kinematics.link_angles(d, theta)["mu"])
    assert np.array_equal(kinematics.tip_positions(d, theta), state.pos)
    assert np.array_equal(kinematics.tip_accelerations_y(d, m, theta), state.acc[1])
    # a grid larger than EXPANDED_MAX goes through the map: the same numbers
    big = np.linspace(0.0, 2 * np.pi, kinematics.EXPANDED_MAX + 1)
    assert np.array_equal(kinematics.tip_positions(d, big), kinematics.tip_state(d, m, big).pos)


@pytest.mark.slow
def test_recheck_cpu_per_sample():
    """CPU per Monte-Carlo sample of redesign_from_example1 (+-0.5): 13.5 ms before (one process, a loaded 2-core
    machine), 2.2 ms after; bounded at 6 ms (the goal), so the per-angle map calls or the DM conversions coming back
    fail it."""
    loaded, recheck = _recheck("redesign_from_example1")
    designs = designs_near(loaded.model.design_values(), 100)[:50]
    recheck(0, designs[0])       # build the grid functions once, as a worker does
    start = time.process_time()
    for i, design in enumerate(designs):
        recheck(i, design)
    assert (time.process_time() - start) / len(designs) < 0.006

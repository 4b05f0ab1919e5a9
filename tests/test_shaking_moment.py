"""The min_peak_shaking_moment objective (synthesis.dynamics.linkage.PEAK_OBJECTIVES) offered by both four-bar kinds.

* Each kind lists it with its unit, N m (the moment is reported like the torque, not squared).
* A solve with it lowers the peak |shaking moment| about the crank pivot below the given design's, with every rule of
  the fine-grid re-check held, and reports the design's own peak on the check's grid.
"""

from __future__ import annotations

import json

import pytest

from conftest import LIBRARY
from synthesis import kinds
from synthesis.dynamics.linkage import PEAK_OBJECTIVES
from synthesis.kinds import solve_spec
from synthesis.result import result_text
from synthesis.spec import load_spec


def with_objective(relative: str, name: str, starts: int):
    """The library spec ``relative`` with objective ``name`` and ``starts`` starts."""
    loaded = load_spec(LIBRARY / relative)
    model = loaded.model
    spec = model.model_copy(update={"objective": model.objective.model_copy(update={"name": name}),
                                    "solver": model.solver.model_copy(update={"starts": starts})})
    return type(loaded)(**{**loaded.__dict__, "model": spec})


def peak_moment(result) -> float:
    return json.loads(result_text(result))["facts"]["dynamics"]["summary"]["shaking_moment_Nm"]["peak"]


@pytest.mark.parametrize("kind", ["planting_fourbar", "crank_rocker"])
def test_both_four_bar_kinds_offer_every_peak_objective_in_its_unit(kind):
    from synthesis.kinds.crank_rocker.solve import OBJECTIVE_UNITS as CRANK_ROCKER_UNITS
    from synthesis.kinds.planting.solve import OBJECTIVE_UNITS as PLANTING_UNITS

    units = {"planting_fourbar": PLANTING_UNITS, "crank_rocker": CRANK_ROCKER_UNITS}[kind]
    assert set(PEAK_OBJECTIVES) <= set(kinds.get(kind).objectives)
    assert units["min_peak_shaking_moment"] == "N m"
    assert all(units[name] == unit for name, (unit, _) in PEAK_OBJECTIVES.items())


@pytest.mark.slow         # about 6 s each: two starts
@pytest.mark.parametrize("relative", ["planting_arm/min_peak_torque_from_example1.toml",
                                      "picker/crank_rocker_min_peak_torque.toml"])
def test_min_peak_shaking_moment_lowers_the_given_designs_peak_with_every_rule_held(relative):
    """The redesign of example 1 with taiwan_example1_dynamics.toml's mass properties (min_peak_torque_from_example1
    with the moment as its objective), and the crank-rocker's counterpart."""
    loaded = with_objective(relative, "min_peak_shaking_moment", starts=2)
    kind = kinds.get(loaded.model.kind)
    before = peak_moment(kind.check(loaded))
    result, _, _ = solve_spec(loaded, workers=1)
    assert result.status == "optimal"
    data = json.loads(result_text(result))
    assert result.objective["name"] == "min_peak_shaking_moment" and result.objective["unit"] == "N m"
    assert result.objective["value"] < before
    assert all(r["satisfied"] for r in data["rules"]), [r for r in data["rules"] if not r["satisfied"]]
    # the objective is the design's own peak on the check's grid: facts.dynamics' grid agrees to its sampling
    assert peak_moment(result) == pytest.approx(result.objective["value"], rel=1e-3)
    assert peak_moment(result) < before

"""A toy kind on the public contract alone (docs/ARCHITECTURE.md, "Adding a kind"): a point (x, y) in mm in a disc of
radius r about the origin, y >= y_min, nearest a target (optimum: the target if inside, else the nearest feasible point)."""

import math
from typing import Literal

import casadi as ca
from pydantic import Field

from synthesis.constraints.base import Rule
from synthesis.core.declared import Declared, evaluated, named, rules_solving
from synthesis.core.kind import Kind
from synthesis.core.problem import ObjectiveParts, Problem
from synthesis.spec.common import MultistartSettings, ProblemSpec, Variable, design_box, value_of


class ToySpec(ProblemSpec):
    kind: Literal["toy_disc"]
    x: Variable = Field(description="x, mm")
    y: Variable = Field(description="y, mm")
    radius: float = Field(gt=0, description="disc radius, mm")
    y_min: float = Field(description="lowest y, mm")
    target: tuple[float, float] = Field(description="target point, mm")
    solver: MultistartSettings = MultistartSettings()

    def design_values(self) -> dict[str, float]:
        return {"x": value_of(self.x), "y": value_of(self.y)}


def rules_of(spec: ToySpec, d: dict) -> list[Rule]:
    """The rules on floats or symbols: one function for the check, the problem and the re-check."""
    return [Rule("inside_disc", d["x"]**2 + d["y"]**2, None, spec.radius**2, "mm^2", spec.radius**2),
            Rule("above_line", d["y"], spec.y_min, None, "mm", 1.0)]


def problem(setting) -> Declared:
    spec, z = setting.spec, ca.SX.sym("z", 2)
    bounds, init = design_box({"x": spec.x, "y": spec.y}, ["x", "y"])
    toy = Problem("toy", z, bounds[:, 0], bounds[:, 1], [], rules_of(spec, {"x": z[0], "y": z[1]}),
                  ObjectiveParts(f=(z[0] - spec.target[0]) ** 2 + (z[1] - spec.target[1]) ** 2), max_iter=spec.solver.max_iter)
    return Declared(toy, ["x", "y"], bounds, init, design=named(["x", "y"]))


class ToyDisc(Kind):
    name = "toy_disc"
    summary = "a point in a disc nearest a target (test kind)"
    objectives = {"nearest_target": "squared distance to the target, mm^2"}

    def spec_model(self):
        return ToySpec

    def check(self, loaded):
        return evaluated(loaded, rules_of(loaded.model, loaded.model.design_values()))

    def solving(self):
        return rules_solving(problem, rules_of, "nearest_target", "mm^2", lambda spec, d: {
            "distance_to_target_mm": math.hypot(d["x"] - spec.target[0], d["y"] - spec.target[1])})


KIND = ToyDisc()

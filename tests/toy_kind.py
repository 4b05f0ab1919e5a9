"""A toy kind written against the public kind contract only (tests/test_kind_contract.py).

A point (x, y) in mm must stay inside a disc of radius r about the origin and above the line
y >= y_min; the objective is the squared distance to a target point.  Known optimum: the target
when it is inside; otherwise the nearest point of the feasible set (for a target outside the disc
and above the line, the disc point on the ray to it).
"""

from __future__ import annotations

import math
from typing import Literal

import casadi as ca
import numpy as np
from pydantic import Field

from constraints.base import Rule
from synthesis.core.ipopt import CompiledNLP
from synthesis.core.kind import Finished, Kind, KindNLP, Setting, Solving
from synthesis.core.outcome import StartOutcome
from synthesis.core.problem import ObjectiveParts, Problem
from synthesis.core.verdict import Recheck
from synthesis.result import Result
from synthesis.spec.common import MultistartSettings, ProblemSpec, StrictModel, Variable, bounds_of, value_of


class Point(StrictModel):
    x: Variable = Field(description="x, mm")
    y: Variable = Field(description="y, mm")


class Limits(StrictModel):
    radius: float = Field(gt=0, description="disc radius, mm")
    y_min: float = Field(description="lowest y, mm")


class Objective(StrictModel):
    name: Literal["nearest_target"] = "nearest_target"
    target: tuple[float, float] = Field(description="target point, mm")


class ToySpec(ProblemSpec):
    kind: Literal["toy_disc"]
    point: Point
    rules: Limits
    objective: Objective
    solver: MultistartSettings = MultistartSettings()

    def design_values(self) -> dict[str, float]:
        return {"x": value_of(self.point.x), "y": value_of(self.point.y)}


def rules_of(spec: ToySpec, x, y) -> list[Rule]:
    """The toy's rules on floats or symbols: one function for check, the NLP and the re-check."""
    return [Rule("inside_disc", x**2 + y**2, None, spec.rules.radius**2, "mm^2", spec.rules.radius**2),
            Rule("above_line", y, spec.rules.y_min, None, "mm", 1.0)]


def run_check(loaded) -> Result:
    spec = loaded.model
    d = spec.design_values()
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated", design=d,
                  rules=[r.record().to_json() for r in rules_of(spec, d["x"], d["y"])], extra={"source": spec.source})


class ToyNLP(KindNLP):
    def __init__(self, spec: ToySpec, elastic: bool):
        self.names = ["x", "y"]
        self.bounds = np.array([bounds_of(spec.point.x), bounds_of(spec.point.y)], dtype=float)
        self.init = np.array([value_of(spec.point.x), value_of(spec.point.y)])
        z = ca.SX.sym("z", 2)
        tx, ty = spec.objective.target
        problem = Problem("toy", z, self.bounds[:, 0], self.bounds[:, 1], [], rules_of(spec, z[0], z[1]),
                          ObjectiveParts(f=(z[0] - tx) ** 2 + (z[1] - ty) ** 2), max_iter=spec.solver.max_iter)
        self.compiled = CompiledNLP(problem, elastic)

    def solve(self, start: int, x0) -> StartOutcome:
        out = self.compiled.solve(start, x0)
        return StartOutcome.of(out, {"x": float(out.x[0]), "y": float(out.x[1])}, out.objective)


def build(setting: Setting, elastic: bool = False) -> ToyNLP:
    return ToyNLP(setting.spec, elastic)


def recheck(setting: Setting, outcome) -> Recheck:
    d = outcome.design
    return Recheck(rules_of(setting.spec, d["x"], d["y"]))


def finish(setting: Setting, best) -> Finished:
    tx, ty = setting.spec.objective.target
    d = best.outcome.design
    return Finished(design=dict(d), objective={"name": "nearest_target", "value": best.outcome.objective,
                                               "unit": "mm^2"},
                    facts={"distance_to_target_mm": math.hypot(d["x"] - tx, d["y"] - ty)})


def baseline_rules(setting: Setting):
    d = setting.spec.design_values()
    return [r.record().to_json() for r in rules_of(setting.spec, d["x"], d["y"])]


SOLVING = Solving(build=build, recheck=recheck, finish=finish, baseline_rules=baseline_rules)

class ToyDisc(Kind):
    name = "toy_disc"
    summary = "a point in a disc nearest a target (test kind)"
    objectives = {"nearest_target": "squared distance to the target, mm^2"}

    def spec_model(self) -> type[ToySpec]:
        return ToySpec

    def check(self, loaded) -> Result:
        return run_check(loaded)

    def solving(self) -> Solving:
        return SOLVING


KIND = ToyDisc()

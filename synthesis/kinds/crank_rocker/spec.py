"""Spec model of kind ``crank_rocker``: a crank-rocker from its time ratio K, rocker swing and minimum
transmission angle (seed 001 §2.1.3, eq 8-10).

Links (seed 001 symbols): crank GF = l7, coupler FE = l8, rocker AE = l9, frame AG = l10, in mm.
``check`` evaluates the given lengths; ``solve`` frees those written as ``{init, bounds}``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.dynamics import DynamicsSection
from synthesis.spec.common import (Starts,
    POSITIVE, Sign, MultistartSettings, ProblemSpec, StrictModel, Variable, max_iter_field, require_positive_fields,
    starts_field, value_of,
)

KIND = "crank_rocker"


class Requirements(StrictModel):
    """What the rocker must do (seed 001: K = 1.25, psi = 50 deg, gamma_min = 40 deg)."""

    time_ratio: float = Field(ge=1.0, le=3.0, description="time ratio K = slow stroke / quick stroke, dimensionless (1 = no quick return)")
    rocker_swing: float = Field(gt=0.0, lt=180.0, description="rocker swing psi between its extreme positions, deg")
    min_transmission_angle: float = Field(gt=0.0, lt=90.0, description="smallest transmission angle over a turn, deg")


class Tolerances(StrictModel):
    """How far a *given* design may miss K and psi in ``check`` (solve imposes them exactly)."""

    time_ratio: float = Field(0.005, ge=0.0, description="|K - K_required| allowed, dimensionless")
    rocker_swing: float = Field(0.1, ge=0.0, description="|psi - psi_required| allowed, deg")


class LinkSection(StrictModel):
    """Link lengths, mm. A number fixes a length, ``{init, bounds}`` frees it."""

    l7: Variable = Field(json_schema_extra=POSITIVE, description="crank GF, mm")
    l8: Variable = Field(json_schema_extra=POSITIVE, description="coupler FE, mm")
    l9: Variable = Field(json_schema_extra=POSITIVE, description="rocker AE, mm")
    l10: Variable = Field(json_schema_extra=POSITIVE, description="frame AG (crank pivot G to rocker pivot A), mm")

    @model_validator(mode="after")
    def _lengths_positive(self) -> "LinkSection":
        require_positive_fields(self)
        return self


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the designs that satisfy every requirement."""

    name: Literal["min_total_length", "max_transmission_angle", "min_peak_torque", "min_peak_shaking_force",
                  "min_peak_shaking_moment"] = Field(
        "min_total_length",
        description="min_total_length: shortest l7 + l8 + l9 + l10 meeting every requirement (the published "
                    "design at l10 = 140 mm); max_transmission_angle: largest minimum transmission angle for "
                    "the given K and psi; min_peak_torque, min_peak_shaking_force, min_peak_shaking_moment: "
                    "smallest peak input torque (N m), shaking force (N) or shaking moment about the crank pivot "
                    "(N m) over a turn (a [dynamics] table needed)")


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(8)
    samples_per_turn: int = Field(72, ge=8, le=3600, multiple_of=2,
                                  description="crank angles sampled for the transmission angle (even: includes "
                                              "the crank along and against the frame, where its extremes lie)")
    max_iter: int = max_iter_field(500)


class CrankRockerSpec(ProblemSpec):
    kind: Literal["crank_rocker"] = Field(description="the problem kind (crank_rocker)")
    requirements: Requirements
    tolerances: Tolerances = Field(default_factory=Tolerances)
    links: LinkSection
    branch: Sign = Field(1, description="assembly: E left (+1) or right (-1) of the line F -> A "
                                                  "(mirror images: same K, swing and transmission angles)")
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    dynamics: DynamicsSection | None = Field(
        None, description="mass properties, crank speed and limits for the inverse dynamics at constant crank speed "
                          "(docs/ARCHITECTURE.md \"Dynamics\"); left out: no dynamics, no dynamics rules")

    @model_validator(mode="after")
    def _dynamics_has_a_speed(self) -> "CrankRockerSpec":
        if self.objective.name.startswith("min_peak") and self.dynamics is None:
            raise ValueError(f"objective.name = {self.objective.name!r} needs a [dynamics] table (mass properties and "
                             f"crank speed)")
        if self.dynamics is not None and self.dynamics.crank_speed is None:
            raise ValueError("dynamics.crank_speed: a crank_rocker has no crank speed of its own; give it in r/min")
        for field in ("counterweight", "rocker_counterweight"):
            weight = getattr(self.dynamics, field) if self.dynamics is not None else None
            if weight is not None and not all(isinstance(v, (int, float)) for v in (weight.mass, weight.radius)):
                raise ValueError(f"dynamics.{field}: a crank_rocker's solve frees only its lengths; give the "
                                 f"counterweight's mass (kg) and radius (mm) as numbers")
        if self.dynamics is not None and any(pm.at == "tip" for pm in self.dynamics.point_masses):
            raise ValueError("dynamics.point_masses: at = \"tip\" names a traced point, which a crank_rocker has "
                             "not; give the position in the link frame, mm")
        return self

    def variables(self) -> dict[str, Variable]:
        return {n: getattr(self.links, n) for n in ("l7", "l8", "l9", "l10")}

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

"""Spec model of kind ``comb_finger``: the eccentric rotating comb fingers of seed 002 §四.3 (eq 14-22, Fig. 26-28).

Two conical divider drums turn about their axes S; each comb finger of effective length r turns about its
hub R, offset from S by e at the depression angle alpha.  Design variables: r, e, alpha, the finger speed
omega, the drum-axis height b and the drum radius rho at the fingers' station.  Units: mm, deg, r/min, m/s.
Our reading of the paper: problems/comb_finger/FINGER.md.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.common import (
    ACUTE, POSITIVE, MultistartSettings, ProblemSpec, StrictModel, Variable, bounds_of, max_iter_field,
    require_positive_fields, starts_field, value_of,
)

KIND = "comb_finger"
NAMES = ("r", "e", "alpha", "omega", "b", "rho")


class FingerSection(StrictModel):
    """A number fixes a value, ``{init, bounds}`` frees it for solve."""

    r: Variable = Field(json_schema_extra=POSITIVE, description="effective finger length r (hub R to tip), mm")
    e: Variable = Field(json_schema_extra=POSITIVE, description="eccentricity e of the finger hub R from the drum axis S, mm")
    alpha: Variable = Field(json_schema_extra=ACUTE, description="depression angle alpha of S -> R toward the row, deg (0 < alpha < 90)")
    omega: Variable = Field(json_schema_extra=POSITIVE, description="finger (drum) speed omega, r/min")
    b: Variable = Field(json_schema_extra=POSITIVE, description="height of the drum axis S above the ground line, mm (eq 15's b)")
    rho: Variable = Field(json_schema_extra=POSITIVE, description="drum (cone) radius at the fingers' station, mm")

    @model_validator(mode="after")
    def _valid(self) -> "FingerSection":
        require_positive_fields(self)
        lo, hi = bounds_of(self.alpha)
        if not (0.0 < lo and hi < 90.0):
            raise ValueError(f"alpha: expected 0 < alpha < 90 deg (the hub below the drum axis, toward the row), "
                             f"got {lo:g}" + (f"-{hi:g}" if hi != lo else ""))
        return self


class OperationSection(StrictModel):
    """Operating condition: machine speed and row spacing."""

    machine_speed: float = Field(gt=0, le=5, description="machine (travel) speed V_s, m/s (the fastest it works: "
                                                         "theta falls with V_s)")
    row_spacing: float = Field(gt=0, description="row spacing, mm: each unit stays within half of it of its row")


class Requirements(StrictModel):
    """Clearances and reaches the comb fingers must keep (seed 002 eq 14-22)."""

    root_clearance: float = Field(ge=0, description="PD >= this: the fingers keep clear of the root zone where the "
                                                    "pegs enter the soil (eq 17), mm")
    units_gap: float = Field(ge=0, description="clear width between the left and right drums, where the combed "
                                               "row passes (the space the text says limits alpha), mm")
    finger_clearance: float = Field(ge=0, description="a finger tip keeps at least this off the other unit's drum "
                                                      "over its whole turn, mm")
    protrusion: float = Field(gt=0, description="a finger at full extension (at E) reaches at least this beyond its "
                                                "drum, mm")
    hub_inset: float = Field(20.0, ge=0, description="the finger hub R stays at least this far inside its drum's wall "
                                                     "(e <= rho - hub_inset), mm (our addition)")
    ground_reach: float = Field(ge=0, description="the tip's lowest point is at most this above the ground line "
                                                  "(and never below it), mm")
    max_tip_speed: float | None = Field(None, gt=0, description="optional: finger tip speed r omega at most this, "
                                                                "m/s (our addition; the paper gives none)")


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the designs that satisfy every rule."""

    name: Literal["max_combing_angle"] = Field("max_combing_angle",
                                               description="largest combing angle theta at the machine speed (eq 21)")


class SolverSection(MultistartSettings):
    starts: int = starts_field(8)
    turn_samples: int = Field(72, ge=8, le=36000, description="finger turn angles sampled for the clearance to "
                                                              "the other unit over a turn")
    max_iter: int = max_iter_field(500)


class CombFingerSpec(ProblemSpec):
    kind: Literal["comb_finger"] = Field(description="the problem kind (comb_finger)")
    finger: FingerSection
    operation: OperationSection
    requirements: Requirements
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)

    def variables(self) -> dict[str, Variable]:
        return {n: getattr(self.finger, n) for n in NAMES}

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

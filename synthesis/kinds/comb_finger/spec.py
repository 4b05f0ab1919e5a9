"""Spec model of kind ``comb_finger``: the eccentric rotating comb fingers of seed 002 §四.3 (eq 14-22, Fig. 26-28).

Two conical divider drums turn about their axes S; each comb finger of effective length r turns about its
hub R, offset from S by e at the depression angle alpha.  Design variables: r, e, alpha, the finger speed
omega, the drum-axis height b and the drum radius rho at the fingers' station.  Units: mm, deg, r/min, m/s.
Our reading of the paper: problems/comb_finger/FINGER.md.

An optional ``[dynamics]`` table (:class:`CombFingerDynamicsSection`) gives the rotor's and the fingers' mass
properties, gravity, a combing load on the finger tips and limits for the inverse dynamics of one unit at the
constant speed omega (synthesis/kinds/comb_finger/dynamics.py).  Frames: the rotor's origin at the drum axis S, the
finger's at its hub R; both x along the first finger (R -> tip), y 90 deg counter-clockwise from x.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.common import (Starts,
    ACUTE, POSITIVE, MultistartSettings, ProblemSpec, StrictModel, Variable, bounds_of, max_iter_field,
    require_positive_fields, starts_field, value_of,
)
from synthesis.spec.dynamics import BarLink, DynamicsLimits, LumpedLink

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
    starts: Starts = starts_field(8)
    turn_samples: int = Field(72, ge=8, le=36000, description="finger turn angles sampled for the clearance to "
                                                              "the other unit over a turn")
    max_iter: int = max_iter_field(500)


class FingerPointMass(StrictModel):
    """A mass carried by the rotor or by every finger (a hub collar, a tip), its own inertia neglected."""

    link: Literal["rotor", "finger"] = Field(description="what carries it: the rotor, or each finger")
    mass: float = Field(gt=0.0, le=100.0, description="mass, kg (on each finger when link = \"finger\")")
    at: tuple[float, float] | Literal["tip"] = Field(
        description="position in the carrier's frame, mm; or \"tip\": the finger tip (at r along the finger, moves "
                    "with r)")
    note: str = Field("", description="what it is and where its value comes from")


class CombingLoad(StrictModel):
    """The crop's resistance on each finger tip while it combs: from its lowest point (turn 0) to F (turn 90 deg +
    alpha), a force of constant magnitude opposing the tip's velocity in the front view (machine frame); none
    elsewhere on the turn."""

    force: float = Field(ge=0.0, le=1.0e4, description="its magnitude on one finger tip, N")
    source: str = Field(min_length=1, description="where the value comes from: a cited figure, or say that it is an "
                                                  "assumption and how it was estimated")


class CombFingerDynamicsSection(StrictModel):
    """Mass properties, combing load and limits for the inverse dynamics of one unit (the left; the right is its
    mirror image) at the constant speed ``[finger] omega`` (synthesis/kinds/comb_finger/dynamics.py)."""

    rotor: LumpedLink = Field(
        description="the drum (cone) with its shaft, turning about S: {mass, com, inertia} in the rotor frame (origin "
                    "S, x along the first finger; a balanced drum: com = [0, 0]); inertia about its centre of mass")
    finger: BarLink | LumpedLink = Field(
        description="one finger shaft: a bar {density, area} from the hub R to the tip (length r: mass and inertia "
                    "follow r), or {mass, com, inertia} in the finger frame (origin R, x towards the tip)")
    fingers: int = Field(1, ge=1, le=36, description="fingers on the unit, all turning about R, evenly spaced over "
                                                     "a turn (the first at the turn angle of the rotor), count")
    point_masses: list[FingerPointMass] = Field(default_factory=list,
                                                description="masses carried by the rotor or by every finger")
    gravity: tuple[float, float] = Field((0.0, -9.81), description="gravity in the machine frame (front view), m/s^2 "
                                                                   "(0 allowed)")
    combing_load: CombingLoad | None = Field(None, description="the crop's resistance on each finger tip while it "
                                                               "combs; left out: none")
    samples: int = Field(360, ge=8, le=3600, description="turn angles of result.json's facts.dynamics over a turn")
    limits: DynamicsLimits = Field(default_factory=DynamicsLimits)
    assumption: str = Field("", description="which values are ours, not a paper's")

    def has_rules(self) -> bool:
        return self.limits.any_given()

    @model_validator(mode="after")
    def _tip_on_a_finger(self) -> CombFingerDynamicsSection:
        if any(pm.at == "tip" and pm.link != "finger" for pm in self.point_masses):
            raise ValueError("point_masses: at = \"tip\" is the finger tip, on a finger; on the rotor give the "
                             "position in the rotor frame, mm")
        return self


class CombFingerSpec(ProblemSpec):
    kind: Literal["comb_finger"] = Field(description="the problem kind (comb_finger)")
    finger: FingerSection
    operation: OperationSection
    requirements: Requirements
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    dynamics: CombFingerDynamicsSection | None = Field(
        None, description="mass properties, the combing load and limits for the inverse dynamics of one unit at the "
                          "constant speed omega (drive torque on the drum, eccentric (hub R) and drum-bearing "
                          "reactions, shaking force and moment, power).  Seed 002 prints no masses or loads: say "
                          "which values are assumptions in `assumption` and `combing_load.source`.  Left out: no "
                          "dynamics, no dynamics rules")

    def variables(self) -> dict[str, Variable]:
        return {n: getattr(self.finger, n) for n in NAMES}

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

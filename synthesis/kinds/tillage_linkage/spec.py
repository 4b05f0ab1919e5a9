"""Spec model of kind ``tillage_linkage``: the distorted rotary tillage linkage of seed 002 (Hwang, §四.2,
eq 3-11, Figs. 18-20).

Linkage (mm, deg): crank radius a = AB, b = AC (flywheel centre A to roller pair C), bar length c = BD,
depression angle theta of C seen from A, and the height of C above the ground.  Operation: flywheel
speed (r/min, counter-clockwise) and forward speed (m/s).  ``check`` evaluates the given linkage over a
crank turn; ``solve`` frees the variables written as ``{init, bounds}``.

An optional ``[dynamics]`` table (:class:`TillageDynamicsSection`) gives the moving links' mass properties, gravity,
the soil force on the tool and limits for the inverse dynamics at the constant flywheel speed of ``[operation]``
(synthesis/kinds/tillage_linkage/dynamics.py).  Link frames: the crank's origin at the flywheel centre A, x towards
the crank pin B; the bar's origin at B, x towards the tool D (along the bar, through the rollers C).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.common import (Starts,
    POSITIVE, FreeVariable, documented_range, MultistartSettings, ProblemSpec, StrictModel, Variable, max_iter_field,
    require_positive_fields, starts_field, value_of,
)
from synthesis.spec.dynamics import BarLink, DynamicsLimits, LumpedLink, SoilForce

KIND = "tillage_linkage"
NAMES = ("a", "b", "c", "theta", "height_c")


def _range(v: Variable) -> tuple[float, float]:
    return v.bounds if isinstance(v, FreeVariable) else (float(v), float(v))


class Linkage(StrictModel):
    """The linkage (seed 002 eq 3-11). A number fixes a value, ``{init, bounds}`` frees it."""

    a: Variable = Field(json_schema_extra=POSITIVE, description="crank radius AB on the flywheel, mm")
    b: Variable = Field(json_schema_extra=POSITIVE, description="distance AC from the flywheel centre A to the roller pair C, mm")
    c: Variable = Field(json_schema_extra=POSITIVE, description="tillage bar length BD, mm")
    theta: Variable = Field(json_schema_extra=documented_range(">= -30, <= 89"),
                            description="depression angle of C seen from A, deg (A lies up and ahead of C)")
    height_c: Variable = Field(json_schema_extra=POSITIVE, description="height of the roller pair C above the ground, mm")

    @model_validator(mode="after")
    def _ranges(self) -> "Linkage":
        require_positive_fields(self)
        lo, hi = _range(self.theta)
        if not (-30.0 <= lo and hi <= 89.0):
            raise ValueError(f"theta: expected -30 <= theta <= 89 deg, got {lo:g}" + ("" if lo == hi else f" .. {hi:g}"))
        a_hi, b_lo = _range(self.a)[1], _range(self.b)[0]
        if a_hi >= b_lo:
            raise ValueError(f"a = {a_hi:g} mm >= b = {b_lo:g} mm (largest a, smallest b): the crank circle reaches "
                             f"the roller C, where |CB| = 0 and D cannot be placed (W = c / |CB| of eq 7 is "
                             f"undefined); keep a below b")
        return self


class Operation(StrictModel):
    """Operating condition: flywheel speed and forward speed."""

    crank_speed: float = Field(gt=0.0, le=2000.0, description="flywheel speed, r/min (counter-clockwise)")
    forward_speed: float = Field(ge=0.0, le=5.0, description="machine travel speed towards +x, m/s")


class Requirements(StrictModel):
    """What the tool tip must do in the soil, and the bar and slot limits."""

    depth: tuple[float, float] = Field(description="[lo, hi] depth of the tool tip's lowest point below the "
                                                   "ground, mm (text: pods 5-8 cm deep; slip grows past 12 cm)")
    lift: float = Field(ge=0.0, description="least height of the tool tip's highest point above the ground, mm")
    min_rearward_speed: float = Field(0.0, ge=0.0, description="least speed (m/s) at which the tip moves "
                                                               "backwards relative to the soil while in it")
    max_slot_angle: float = Field(gt=0.0, lt=90.0, description="largest angle of the bar to the roller slot "
                                                               "(aligned with AC), deg")
    min_engagement: float = Field(ge=0.0, description="least length of bar beyond the rollers when B is "
                                                      "farthest from C: c - (a + b) >= this, mm")

    @model_validator(mode="after")
    def _ordered(self) -> "Requirements":
        lo, hi = self.depth
        if not 0.0 < lo <= hi:
            raise ValueError(f"depth: expected 0 < lo <= hi, got [{lo:g}, {hi:g}]")
        return self


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the linkages that satisfy every rule."""

    name: Literal["min_bar_length", "max_margin", "min_peak_torque"] = Field(
        "min_bar_length", description="min_bar_length: the shortest bar c meeting every rule (a compact, light "
                                      "tool); max_margin: the largest smallest normalised rule margin; "
                                      "min_peak_torque: the smallest peak |input torque| on the flywheel over a turn, "
                                      "N m (a [dynamics] table needed)")


class TillagePointMass(StrictModel):
    """A mass carried by a moving link (the tool, a crank pin, a counterweight), its own inertia neglected."""

    link: Literal["crank", "bar"] = Field(description="the link that carries it: the crank (flywheel) or the bar")
    mass: float = Field(gt=0.0, le=1000.0, description="mass, kg")
    at: tuple[float, float] | Literal["tip"] = Field(
        description="position in the link frame, mm; or \"tip\": the tool tip D at the bar's end (moves with c)")
    note: str = Field("", description="what it is and where its value comes from")


class TillageDynamicsSection(StrictModel):
    """Mass properties, soil force and limits for the inverse dynamics at the constant flywheel speed of
    ``[operation] crank_speed`` (synthesis/kinds/tillage_linkage/dynamics.py)."""

    crank: BarLink | LumpedLink = Field(
        description="the flywheel with its crank AB: a bar {density, area} from A to B, or {mass, com, inertia} in the "
                    "crank frame (origin A, x towards B; a balanced flywheel: com = [0, 0])")
    bar: BarLink | LumpedLink = Field(
        description="the tillage bar BD: a bar {density, area} of length c (mass and inertia follow c), or {mass, com, "
                    "inertia} in the bar frame (origin B, x towards D)")
    point_masses: list[TillagePointMass] = Field(default_factory=list,
                                                 description="masses carried by the links (the tool: at = \"tip\")")
    gravity: tuple[float, float] = Field((0.0, -9.81), description="gravity in the machine frame, m/s^2 (0 allowed)")
    soil: SoilForce | None = Field(None, description="the soil force on the tool D while D is below the ground (depth "
                                                     "d = -height_c - y_D > 0, mm), opposing D's velocity relative to "
                                                     "the soil; left out: none")
    roller_friction: float = Field(0.0, ge=0.0, le=1.0,
                                   description="Coulomb friction coefficient of the bar in the roller pair C "
                                               "(dimensionless; 0: the roller force is normal to the bar)")
    samples: int = Field(360, ge=8, le=3600, description="crank angles of result.json's facts.dynamics over a turn")
    limits: DynamicsLimits = Field(default_factory=DynamicsLimits)
    assumption: str = Field("", description="which values are ours, not a paper's")

    def has_rules(self) -> bool:
        return self.limits.any_given()

    @model_validator(mode="after")
    def _tip_on_the_bar(self) -> "TillageDynamicsSection":
        if any(pm.at == "tip" and pm.link != "bar" for pm in self.point_masses):
            raise ValueError("point_masses: at = \"tip\" is the tool tip D, on the bar; on the crank give the "
                             "position in the crank frame, mm")
        return self


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(8)
    samples: int = Field(72, ge=12, le=3600, description="crank angles over a turn on which the lowest and "
                                                        "highest points are checked global (re-check: 10x)")
    soil_samples: int = Field(24, ge=3, le=2000, description="crank angles sampled over the in-soil phase for "
                                                            "the rearward-motion rule (re-check: 10x)")
    backoff: float = Field(0.02, ge=0.0, le=1.0, description="the NLP tightens the sampled rearward-motion limit "
                                                            "by backoff x 0.1 m/s, so it holds between samples (dimensionless)")
    max_iter: int = max_iter_field(1000)


class TillageSpec(ProblemSpec):
    kind: Literal["tillage_linkage"] = Field(description="the problem kind (tillage_linkage)")
    linkage: Linkage
    operation: Operation
    requirements: Requirements
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    dynamics: TillageDynamicsSection | None = Field(
        None, description="mass properties, the soil force on the tool and limits for the inverse dynamics at the "
                          "constant flywheel speed (input torque, pin reaction at B, roller reaction at C, shaking "
                          "force and moment, power).  Seed 002 prints no masses or soil forces: say which values are "
                          "assumptions in `assumption` and `soil.source`.  Left out: no dynamics, no dynamics rules")

    @model_validator(mode="after")
    def _dynamics_for_the_objective(self) -> "TillageSpec":
        if self.objective.name == "min_peak_torque" and self.dynamics is None:
            raise ValueError("objective.name = 'min_peak_torque' needs a [dynamics] table (mass properties and the "
                             "soil force)")
        return self

    def variables(self) -> dict[str, Variable]:
        return {n: getattr(self.linkage, n) for n in NAMES}

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

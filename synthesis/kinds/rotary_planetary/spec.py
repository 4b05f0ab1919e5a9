"""Spec model of kind ``rotary_planetary``: the rotary transplanting mechanism whose planting arms ride on
non-circular planetary gear trains (problems/rotary_planetary/NOTES.md).

A design is the two pairs' centre distances, the Fourier laws of the idler and the planet (deg per harmonic),
and the arm (tip distance and direction on the planet, the claw's direction relative to it).  A number fixes a
design variable, ``{init, bounds}`` frees it for ``solve``.  Key poses are what a designer writes: the claw tip's
position and, optionally, the claw's attitude at picking, carrying, pushing out and leaving the soil (the
``[key_poses]`` table shared with the planting arm: :mod:`synthesis.spec.poses`).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_validator

from synthesis.spec.common import (Starts,
    POSITIVE, MultistartSettings, ProblemSpec, StrictModel, Variable, max_iter_field, require_positive_fields,
    starts_field, value_of, within_a_turn,
)
from synthesis.spec.poses import MAX_POSES, ClawPose, attitude_field, pose_names

KIND = "rotary_planetary"
#: harmonics a law may have (a law's shape beyond a dozen harmonics is a tooth-scale ripple, not a design)
MAX_HARMONICS = 12


class GearSection(StrictModel):
    """The train of one arm: sun (fixed) -> compound idler -> planet, centres on one line of the carrier.

    Laws (NOTES.md): idler rotation relative to the carrier phi + G(phi), planet rotation relative to the carrier
    -phi + F(phi); G and F are Fourier series of the carrier angle phi with the coefficients below (harmonic
    k = 1, 2, ... in order).  F is also the arm's absolute swing about its mean direction."""

    centre_distance_1: Variable = Field(json_schema_extra=POSITIVE, description="sun to idler centre distance a1, mm")
    centre_distance_2: Variable = Field(json_schema_extra=POSITIVE,
                                        description="idler to planet centre distance a2, mm")
    planet_cos: list[Variable] = Field(default_factory=list, max_length=MAX_HARMONICS,
                                       description="cosine coefficients of F, harmonic 1, 2, ..., deg")
    planet_sin: list[Variable] = Field(default_factory=list, max_length=MAX_HARMONICS,
                                       description="sine coefficients of F, harmonic 1, 2, ..., deg")
    idler_cos: list[Variable] = Field(default_factory=list, max_length=MAX_HARMONICS,
                                      description="cosine coefficients of G, harmonic 1, 2, ..., deg")
    idler_sin: list[Variable] = Field(default_factory=list, max_length=MAX_HARMONICS,
                                      description="sine coefficients of G, harmonic 1, 2, ..., deg")

    @model_validator(mode="after")
    def _shape(self) -> "GearSection":
        require_positive_fields(self)
        for law in ("planet", "idler"):
            c, s = getattr(self, f"{law}_cos"), getattr(self, f"{law}_sin")
            if len(c) != len(s):
                raise ValueError(f"{law}_cos has {len(c)} harmonics and {law}_sin {len(s)}: give both the same "
                                 f"number (0 for a harmonic the law lacks)")
        return self


class ArmSection(StrictModel):
    """The planting arm, fixed on the planet."""

    length: Variable = Field(json_schema_extra=POSITIVE, description="planet centre to claw tip, mm")
    angle: Variable = Field(description="direction of the tip from the planet centre where F = 0, from +x "
                                        "(rearwards) counter-clockwise, deg")
    claw_angle: Variable = Field(0.0, description="the claw's direction (root to tip) relative to the arm line "
                                                  "planet centre -> tip, counter-clockwise, deg")
    _turn = field_validator("angle", "claw_angle")(within_a_turn)

    @model_validator(mode="after")
    def _positive(self) -> "ArmSection":
        require_positive_fields(self)
        return self


class Operation(StrictModel):
    """How the machine runs: the gearbox's speed, the forward speed and where the soil is."""

    carrier_speed: float = Field(gt=0, le=2000, description="carrier (gearbox) speed, r/min")
    forward_speed: float = Field(gt=0, le=10, description="machine forward speed, m/s")
    axis_height: float = Field(gt=0, description="carrier axis above the soil surface, mm")


class KeyPose(ClawPose):
    """A pose the claw must pass through: its tip within ``tolerance`` of (x, y) and, if given, its attitude
    within ``attitude_tolerance`` of ``attitude``, at a carrier angle the solver finds (or ``carrier_angle``)."""

    x: float = Field(description="tip x (rearwards), machine frame, mm")
    y: float = Field(description="tip y (up), machine frame, mm")
    attitude: float | None = attitude_field("claw attitude, from +x counter-clockwise (pointing down: -90), deg")
    carrier_angle: float | None = Field(None, ge=-360, le=360,
                                        description="carrier angle of the pose, deg (absent: the solver's choice)")


class Rules(StrictModel):
    """Gear and transplanting rules (sources and assumptions: NOTES.md, "Rules")."""

    ratio_min: float = Field(0.5, gt=0, description="smallest pair ratio i = r_driver / r_driven, dimensionless")
    ratio_max: float = Field(2.0, gt=0, description="largest pair ratio, dimensionless")
    min_concave_radius: float = Field(20.0, gt=0,
                                      description="smallest radius of curvature where a pitch curve is concave, mm")
    max_normal_angle: float = Field(30.0, gt=0, lt=90, description="largest angle between a pitch curve's "
                                    "normal at the contact and the line of centres, deg")
    trajectory_height_min: float = Field(0.0, ge=0, description="smallest height of the tip's loop, mm")
    planting_depth: tuple[float, float] = Field(description="[min, max] depth of the lowest tip point below the "
                                                            "soil surface, mm")
    entry_angle_min: float = Field(80.0, gt=0, lt=90, description="min angle of the ground-frame tip velocity to "
                                                                   "the horizontal at soil entry, deg")
    hole_width_max: float = Field(gt=0, description="largest ground-frame distance between the tip's soil entry "
                                                    "and exit, mm")
    in_soil_forward_speed_max: float = Field(0.0, description="largest forward tip speed relative to the ground "
                                                              "while in the soil, mm/s (0: never pushes forward)")
    plant_spacing: tuple[float, float] = Field(description="[min, max] plant spacing (two plants per carrier "
                                                           "turn), mm")
    single_idler: bool = Field(False, description="true: the idler is one gear meshing with both sun and planet (the "
                                                  "common three-gear train), its two pitch curves one curve; false: a "
                                                  "compound idler (two gears on one shaft)")
    single_idler_tolerance: float = Field(0.01, gt=0, description="with single_idler: largest difference of the "
                                                                  "idler's two pitch radii at one polar angle, mm")

    @model_validator(mode="after")
    def _ordered(self) -> "Rules":
        for name in ("planting_depth", "plant_spacing"):
            lo, hi = getattr(self, name)
            if lo > hi:
                raise ValueError(f"{name} [{lo:g}, {hi:g}] has min > max")
        if self.planting_depth[0] <= 0:
            # the soil rules read a stroke below the surface: a lowest point at or above it has none
            raise ValueError(f"planting_depth [{self.planting_depth[0]:g}, {self.planting_depth[1]:g}]: the min must "
                             f"be above 0 mm (the tip's lowest point below the soil surface)")
        if self.ratio_min >= self.ratio_max:
            raise ValueError(f"ratio_min {self.ratio_min:g} must be below ratio_max {self.ratio_max:g}")
        return self


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the designs that hold every rule."""

    name: Literal["key_pose_miss", "smooth_law"] = Field(
        "key_pose_miss", description="key_pose_miss: smallest sum of squared key-pose misses (mm^2 and deg^2); "
                                     "smooth_law: smallest mean squared second derivative of the laws F and G "
                                     "(deg^2/rad^4), every rule held")


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(8)
    samples_per_turn: int = Field(72, ge=12, le=3600, description="carrier angles sampled over a turn for the "
                                                                   "gear and trajectory rules")
    in_soil_samples: int = Field(12, ge=3, le=1000, description="samples of the in-soil stroke for its speed rule")
    backoff: float = Field(0.01, ge=0, le=1, description="the NLP holds each rule it reads on samples (pair ratio, "
                                                         "concavity, normal angle, largest depth, in-soil speed, "
                                                         "out of the soil) "
                                                         "backoff x the rule's scale inside its limits, so it holds "
                                                         "between samples too (dimensionless)")
    max_iter: int = max_iter_field(1000)


class RotaryPlanetarySpec(ProblemSpec):
    kind: Literal["rotary_planetary"] = Field(description="the problem kind (rotary_planetary)")
    gears: GearSection
    arm: ArmSection
    operation: Operation
    key_poses: dict[str, KeyPose] = Field(default_factory=dict, max_length=MAX_POSES,
                                          description="named poses, e.g. [key_poses.picking]")
    rules: Rules
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)

    _pose_names = field_validator("key_poses")(pose_names)

    @property
    def harmonics(self) -> tuple[int, int]:
        """(harmonics of F, harmonics of G)."""
        return len(self.gears.planet_cos), len(self.gears.idler_cos)

    def variables(self) -> dict[str, Variable]:
        g, a = self.gears, self.arm
        out: dict[str, Variable] = {"centre_distance_1": g.centre_distance_1, "centre_distance_2": g.centre_distance_2}
        for law in ("planet", "idler"):
            for part in ("cos", "sin"):
                for k, v in enumerate(getattr(g, f"{law}_{part}"), start=1):
                    out[f"{law}_{part}_{k}"] = v
        out.update(arm_length=a.length, arm_angle=a.angle, claw_angle=a.claw_angle)
        return out

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

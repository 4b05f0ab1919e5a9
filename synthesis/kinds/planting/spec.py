"""Spec model of kind ``planting_fourbar``: the four-bar planting arm of seed 000.

Units: lengths mm, angles deg, forward speed m/s, crank speed r/min (docs/ARCHITECTURE.md, "Units").

Operating condition: we take the **crank speed** (r/min) as the input and derive the plant
spacing (= forward speed x crank period).  Seed 000 varies the forward speed at a fixed crank speed
in its sensitivity study (Table 2 lists RPM and V_m as separate factors) and finds that P4P6
changes with forward speed; at a fixed plant spacing the ground-frame path would be the same
curve at every speed, so that finding needs the crank speed held fixed.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, PrivateAttr, field_validator, model_validator

from synthesis.spec.dynamics import DynamicsSection, SoilForce
from synthesis.spec.poses import MAX_POSES, ClawPose, attitude_field, pose_names
from synthesis.spec.operating import OperatingRange, resolve_ranges
from synthesis.spec.common import (Starts,
    POSITIVE, WITHIN_A_TURN, Interval, documented_range, is_free, MultistartSettings, ProblemSpec, Sign, StrictModel, Variable,
    max_iter_field, require_positive_fields, starts_field, value_of, within_a_turn,
)

KIND = "planting_fourbar"


class ArmSection(StrictModel):
    """Linkage (seed 000 Table 1 symbols). A number fixes a variable, {init, bounds} frees it."""

    l1: Variable = Field(json_schema_extra=POSITIVE, description="frame O'O, mm")
    l2: Variable = Field(json_schema_extra=POSITIVE, description="crank OA, mm")
    l3: Variable = Field(json_schema_extra=POSITIVE, description="coupler AB, mm")
    l4: Variable = Field(json_schema_extra=POSITIVE, description="rocker O'B, mm")
    l5: Variable = Field(json_schema_extra=POSITIVE, description="claw arm AC (A to claw tip C), mm")
    zeta: Variable = Field(json_schema_extra=documented_range(">= -360, <= 360"), description="frame angle: direction of O -> O' from the +X axis, deg (-360 to 360)")
    phi: Variable = Field(json_schema_extra=documented_range(">= -360, <= 360"), description="claw angle: AC is AB turned clockwise by phi, deg (-360 to 360)")
    _angles_within_a_turn = field_validator("zeta", "phi")(within_a_turn)
    branch: Sign = Field(-1, description="assembly: B right (-1) or left (+1) of the line A -> O'")
    tray_tilt: Literal["backward", "forward"] | None = Field(
        None, description="seedling-tray tilt of the machine (seed 000 Table 1, informational)")

    @model_validator(mode="after")
    def _lengths_positive(self) -> "ArmSection":
        require_positive_fields(self)
        return self


class SeedbedSection(StrictModel):
    """Seedling mat on the tray: a straight seedbed-bottom line fixed in the machine frame."""

    x: Variable = Field(description="X of a point on the seedbed bottom (tray surface), mm from the crank pivot O")
    y: Variable = Field(description="Y of that point, mm")
    tilt: Variable = Field(json_schema_extra=WITHIN_A_TURN, description="direction of the tray surface from the +X axis, deg; "
                                       "the seedlings stand on its upper side")
    thickness: float = Field(22.0, gt=0, description="seedbed (mat) thickness P2-P3 level, mm (seed 000: 22)")
    seedling_height: float = Field(110.0, gt=0, description="seedling top above the seedbed bottom, mm (seed 000: 110)")

    _tilt_within_a_turn = field_validator("tilt")(within_a_turn)


class OperationSection(StrictModel):
    """Operating condition: forward speed and crank speed (the plant spacing follows).  Either may be given
    as a range ``{range = [lo, hi], samples = N}``: the solve then holds every rule at each sampled value
    (an operating envelope, one shared design) and re-checks the answer on a finer grid of the range."""

    forward_speed: Annotated[float, Field(ge=0, le=2.0)] | OperatingRange = Field(
        description="machine forward speed, m/s (seed 000 analyses 0.50-0.75); or a range "
                    "{range = [lo, hi], samples = 4, nominal = (lo+hi)/2, step = re-check spacing}")
    crank_speed: Annotated[float, Field(gt=0, le=2000)] | OperatingRange = Field(
        description="crank (driving shaft) speed, r/min; or a range as for forward_speed")
    _operating_ranges: dict = PrivateAttr(default_factory=dict)

    @model_validator(mode="after")
    def _nominal(self) -> "OperationSection":
        resolve_ranges(self, {"forward_speed": ">= 0, <= 2", "crank_speed": "> 0, <= 2000"})
        return self


class SoilSection(StrictModel):
    """Either the soil surface Y in the machine frame, or the paper's analysis convention."""

    level: Variable | None = Field(None, description="Y of the soil surface in the machine frame, mm")
    analysis_depth: float | None = Field(
        None, gt=0, description="soil surface this far above the lowest claw point, mm (seed 000 uses 25)")

    @model_validator(mode="after")
    def _one_of(self) -> "SoilSection":
        if (self.level is None) == (self.analysis_depth is None):
            raise ValueError("give exactly one of soil.level (mm) or soil.analysis_depth (mm)")
        return self


class AccelerationSigns(StrictModel):
    """Sign of the claw's Y acceleration required on each phase (+1 up, -1 down).

    Printed rules (seed 000 §6.2 (4)-(6)): hold +, throw -, release +.  The printed throw sign is
    unattainable by any smooth path (see GEOMETRY.md); the default is the physical reading, +.
    """

    hold: Sign = Field(1, description="P3 (seedling taken) -> P4 (soil entry)")
    throw: Sign = Field(1, description="P4 (soil entry) -> P5 (lowest point)")
    release: Sign = Field(1, description="P5 (lowest point) -> P6 (soil exit)")


class RulesSection(StrictModel):
    """Limits of the design rules (seed 000 §6.2); defaults are the paper's values."""

    p1p3: Interval | None = Field(None, description="distance P1-P3, mm; default: follows the seedling height h, "
                                                    "[105/110, 115/110] x h (seed 000: [105, 115] mm for 110 mm)")
    p2p3: Interval | None = Field(None, description="distance P2-P3, mm; default: follows the seedbed thickness t, "
                                                    "[21/22, 23/22] x t (seed 000: about 22 mm; [21, 23] mm)")
    collinearity: float = Field(5.0, gt=0, le=90, description="max turn of the claw path at P2 between "
                                                             "P1->P2 and P2->P3, deg (0 = collinear)")
    # below 90: the angle to the horizontal is at most 90, so a minimum of 90 asks for an exactly vertical entry, which
    # no computed velocity meets to the last digit
    entry_angle_min: float = Field(80.0, gt=0, lt=90, description="min angle of the ground-frame velocity "
                                                                  "at P4 to the horizontal, deg")
    depth: Interval = Field((20.0, 30.0), description="planting depth Y(P4) - Y(P5), mm")
    p4p6_min: float = Field(20.0, ge=0, description="min ground-frame distance P4-P6, mm")
    p2_speed_min: float = Field(1.0, ge=0, description="min claw speed at P2 relative to the seedbed, m/s")
    transmission_angle: Interval = Field((40.0, 140.0), description="transmission angle range over a turn, deg")
    acceleration: AccelerationSigns = Field(default_factory=AccelerationSigns)

    @model_validator(mode="after")
    def _ordered(self) -> "RulesSection":
        for name in ("p1p3", "p2p3", "depth", "transmission_angle"):
            if getattr(self, name) is None:
                continue
            lo, hi = getattr(self, name)
            if lo > hi:
                raise ValueError(f"{name}: [{lo:g}, {hi:g}] has lo > hi")
            if lo == hi:        # an equality no computed value meets to the last digit: every check would fail it
                raise ValueError(f"{name}: [{lo:g}, {hi:g}] is one value; give a range lo < hi (a computed value "
                                 f"meets a single number only to rounding, so the rule would never hold)")
        return self


class KeyPose(ClawPose):
    """A pose the claw must pass through: its attitude and/or its tip's position, read at a precision point
    (``at``) or, for a free pose, where the tip comes nearest (x, y) (or at ``crank_angle``)."""

    at: Literal["P1", "P2", "P3", "P4", "P5", "P6"] | None = Field(
        None, description="the precision point the pose is read at (P1 seedling top, P2 seedbed top, P3 seedbed "
                          "bottom, P4 soil entry, P5 lowest point, P6 soil exit): the claw's attitude there and, if "
                          "x and y are given, the tip within tolerance of them; absent: a free pose at x, y")
    x: float | None = Field(None, description="tip X (forward), machine frame, mm")
    y: float | None = Field(None, description="tip Y (up), machine frame, mm")
    attitude: float | None = attitude_field(
        "claw attitude: the direction of the claw arm A -> C (crank pin A to the claw tip C, rigid on the coupler) "
        "from +X (forward) counter-clockwise, deg (pointing straight down: -90, backwards: 180)")
    crank_angle: float | None = Field(
        None, ge=-360, le=360, description="crank angle of a free pose, deg from the frame line O -> O' "
                                           "(absent: where the tip comes nearest (x, y), the solver's choice)")

    @model_validator(mode="after")
    def _where(self) -> "KeyPose":
        if self.at is not None and self.crank_angle is not None:
            raise ValueError(f"crank_angle: a pose at {self.at} is read at that point's crank angle; give at or "
                             f"crank_angle, not both")
        if self.at is None and self.crank_angle is None and self.tip is None:
            raise ValueError("a free pose (no at, no crank_angle) is read where the tip comes nearest its target: "
                             "give x and y (mm)")
        return self


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the designs that satisfy every rule."""

    name: Literal["nearest", "robust", "smooth", "min_peak_torque", "min_peak_shaking_force",
                  "min_peak_shaking_moment"] = Field(
        "nearest", description="nearest: smallest change from the given design (default); robust: maximise the "
                               "smallest normalised rule margin; smooth: minimise the peak claw acceleration; "
                               "min_peak_torque, min_peak_shaking_force, min_peak_shaking_moment: minimise the peak "
                               "input torque (N m), shaking force (N) or shaking moment about the crank pivot (N m) "
                               "over a turn (a [dynamics] table needed)")


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(16)
    samples_per_phase: int = Field(16, ge=3, le=500, description="samples of each acceleration phase")
    samples_per_turn: int = Field(72, ge=12, le=3600, description="samples of a crank turn (transmission, lowest)")
    max_iter: int = max_iter_field(500)
    backoff: float = Field(0.02, ge=0, le=1, description="the NLP tightens every rule limit by backoff x the "
                                                         "rule's scale, so rules hold between the samples too "
                                                         "(dimensionless)")
    point_gap: float = Field(
        1.0, gt=0, le=30, description="smallest crank angle (deg) the NLP keeps between consecutive precision points "
                                      "(P5, P6, P1, P2, P3, P4); with a [tolerance] table held at the linearised "
                                      "worst case of the box, as the rules are; more keeps them further apart")
    seedling_clearance: float = Field(
        0.0, ge=0, le=100, description="the NLP makes the claw tip rise at least this far (mm) above the seedling-top "
                                       "line before it comes down through it at P1 (one more crank angle, the loop's "
                                       "top between P6 and P1); 0 admits a path that only touches the line at the "
                                       "top of its loop, which the float check (a sign change) does not count as a "
                                       "crossing, so such an answer fails its re-check; with a [tolerance] table the "
                                       "clearance is held at its linearised worst case in the box, as the rules are")


class PlantingDynamicsSection(DynamicsSection):
    """The four-bar's ``[dynamics]`` table with the planting arm's own load: the soil on the claw tip C."""

    soil: SoilForce | None = Field(
        None, description="the soil's resistance on the claw tip C while C is below the [soil] surface (depth d, mm): "
                          "magnitude f0 + k d opposing C's velocity relative to the soil (the machine travelling "
                          "forward at [operation] forward_speed; the direction blended to zero below 1 mm/s, "
                          "synthesis/dynamics/fourbar.py); left out: no soil force")
    counterweight_clearance: float = Field(
        10.0, ge=0, description="mm: the lowest point of each counterweight (crank's, rocker's) over a turn at least "
                                "this far above the [soil] surface (rules counterweight_clearance, "
                                "rocker_counterweight_clearance, when the counterweight's mass is free or not zero); "
                                "10 mm: the planting-depth band (20-30 mm about the 25 mm analysis depth) admits a "
                                "surface 5 mm above the analysis one, and the counterweight, a point mass here, "
                                "reaches about 5 mm below its centre as a plate 10 mm deep")

    @model_validator(mode="after")
    def _a_free_counterweight_exists(self) -> "PlantingDynamicsSection":
        # The clearance rows hold a counterweight that exists; "no counterweight unless one clears" is not a smooth
        # row, so a free mass allowed down to 0 would let the NLP call infeasible what a 0 kg counterweight (none)
        # satisfies, a false verdict.
        for name in ("counterweight", "rocker_counterweight"):
            weight = getattr(self, name)
            if weight is not None and is_free(weight.mass) and weight.mass.bounds[0] <= 0.0:
                raise ValueError(f"{name}.mass: a free counterweight mass needs a lower bound above 0 kg (the "
                                 f"clearance rule holds a counterweight that exists); leave the counterweight out "
                                 f"for none")
        return self


class PlantingFourbarSpec(ProblemSpec):
    kind: Literal["planting_fourbar"] = Field(description="the problem kind (planting_fourbar)")
    arm: ArmSection
    seedbed: SeedbedSection
    operation: OperationSection
    soil: SoilSection
    rules: RulesSection = Field(default_factory=RulesSection)
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    dynamics: PlantingDynamicsSection | None = Field(
        None, description="mass properties, the soil on the claw and limits for the inverse dynamics at the "
                          "[operation] crank speed (docs/ARCHITECTURE.md \"Dynamics\"); left out: no dynamics, no "
                          "dynamics rules")
    key_poses: dict[str, KeyPose] = Field(
        default_factory=dict, max_length=MAX_POSES,
        description="named poses, e.g. [key_poses.entry] at = \"P4\", attitude = -100: the claw's attitude (and "
                    "optionally the tip's position) at a precision point, or a free pose at x, y; each adds the "
                    "rules pose_<name> (tip) and pose_<name>_attitude")
    _pose_names = field_validator("key_poses")(pose_names)
    _derived: tuple[str, ...] = PrivateAttr(default=())          # rule limits filled in from the inputs

    @model_validator(mode="after")
    def _one_crank_speed(self) -> "PlantingFourbarSpec":
        if self.objective.name.startswith("min_peak") and self.dynamics is None:
            raise ValueError(f"objective.name = {self.objective.name!r} needs a [dynamics] table (mass properties)")
        if self.dynamics is not None and self.dynamics.crank_speed is not None:
            raise ValueError("dynamics.crank_speed: a planting arm turns at [operation] crank_speed; leave it out here")
        if self.dynamics is not None and any(pm.at == "tip" and pm.link != "coupler"
                                             for pm in self.dynamics.point_masses):
            raise ValueError("dynamics.point_masses: at = \"tip\" is the claw tip C, on the coupler")
        return self

    @model_validator(mode="after")
    def _limits_follow_the_inputs(self) -> "PlantingFourbarSpec":
        """P1P3 and P2P3 not given: the paper's limits scaled with the seedling height and the mat thickness
        they stand for (seed 000: [105, 115] mm for a 110 mm seedling, about 22 mm for a 22 mm mat)."""
        derived = {}
        h, t = self.seedbed.seedling_height, self.seedbed.thickness
        if self.rules.p1p3 is None:
            derived["p1p3"] = (105.0 / 110.0 * h, 115.0 / 110.0 * h)
        if self.rules.p2p3 is None:
            derived["p2p3"] = (21.0 / 22.0 * t, 23.0 / 22.0 * t)
        if derived:
            # the model is frozen once validated; this is its own validation, before anyone reads it
            object.__setattr__(self, "rules", self.rules.model_copy(update=derived))
            self._derived = tuple(derived)
        return self

    def derived_limits(self) -> dict[str, str]:
        """How each limit that was not written in the spec follows from the inputs (for the report)."""
        out = {}
        # a derived limit is one _limits_follow_the_inputs filled in
        if "p1p3" in self._derived:
            assert self.rules.p1p3 is not None
            lo, hi = self.rules.p1p3
            out["p1p3"] = (f"[{lo:.4g}, {hi:.4g}] mm = [105/110, 115/110] x seedling height "
                           f"{self.seedbed.seedling_height:g} mm (seed 000: [105, 115] mm for 110 mm)")
        if "p2p3" in self._derived:
            assert self.rules.p2p3 is not None
            lo, hi = self.rules.p2p3
            out["p2p3"] = (f"[{lo:.4g}, {hi:.4g}] mm = [21/22, 23/22] x seedbed thickness "
                           f"{self.seedbed.thickness:g} mm (seed 000: about 22 mm for a 22 mm mat)")
        return out

    def choice_variables(self) -> dict[str, str]:
        """result.json's design holds the assembly branch beside the variables: its TOML path."""
        return {"branch": "arm.branch"}

    def variables(self) -> dict[str, Variable]:
        """Every design variable (spec units) by its result.json name."""
        out = {n: getattr(self.arm, n) for n in ("l1", "l2", "l3", "l4", "l5", "zeta", "phi")}
        out.update({f"seedbed_{n}": getattr(self.seedbed, n) for n in ("x", "y", "tilt")})
        if self.soil.level is not None:
            out["soil_level"] = self.soil.level
        if self.dynamics is not None and self.dynamics.counterweight is not None:
            out["counterweight_mass"] = self.dynamics.counterweight.mass
            out["counterweight_radius"] = self.dynamics.counterweight.radius
        if self.dynamics is not None and self.dynamics.rocker_counterweight is not None:
            out["rocker_counterweight_mass"] = self.dynamics.rocker_counterweight.mass
            out["rocker_counterweight_radius"] = self.dynamics.rocker_counterweight.radius
        return out

    def design_values(self) -> dict[str, float]:
        """Every design variable at its given (or start) value, spec units."""
        return {n: value_of(v) for n, v in self.variables().items()}

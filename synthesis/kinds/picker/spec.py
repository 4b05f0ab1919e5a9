"""Spec models of the seed-001 picker: ``picker_double_crank`` (§2.1.2) and ``picker`` (the combined drive).

Units: mm, deg, r/min.  Our reading of the paper's symbols is in problems/picker/PICKER.md; in short:
l1 = crank AB, l2 = coupler BC, l3 = follower CD, l4 = frame AD (the shortest link, eq 5-6), l5 = CM,
phi3 = frame AD below the +x axis, phi4 = CM turned counter-clockwise from BC.  The clamp's attitude (a key pose's)
is the direction of the clamp arm C -> M, from +x counter-clockwise.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from synthesis.spec.docmeta import SPEC_FILE
from synthesis.spec.dynamics import BarLink, DynamicsLimits, DynamicsSection, LumpedLink, PointMass
from synthesis.spec.poses import MAX_POSES, ClawPose, attitude_field, pose_names
from synthesis.spec.common import (Starts,
    POSITIVE, WITHIN_A_TURN, MultistartSettings, ProblemSpec, Sign, StrictModel, Variable, require_positive_fields,
    starts_field, value_of, within_a_turn,
)


class TargetArc(StrictModel):
    """The picking arc M1 -> M2 with its tangent at M1 (seed 001 §2.1.1, Fig. 3)."""

    m1: tuple[float, float] = Field(description="picking point M1 (x, y), mm from the power-output bar, y up")
    m2: tuple[float, float] = Field(description="drop point M2 (x, y), mm")
    tangent_from_vertical: float = Field(gt=0.0, lt=90.0, description="theta5: tangent at M1 to the vertical, deg")
    points: int = Field(10, ge=2, le=1000, description="target points evenly by arc length, M1 and M2 included")

    @model_validator(mode="after")
    def _distinct(self) -> "TargetArc":
        if self.m1 == self.m2:
            raise ValueError(f"m1 and m2 are the same point {self.m1}")
        return self


class DriveSection(StrictModel):
    """Crank AB's working swing: it starts at phi10 and turns by psi, the target points at evenly
    spaced crank angles (seed 001: 50 and 50 deg)."""

    start: float = Field(ge=-360.0, le=360.0, description="phi10: crank angle AB from AD at M1, deg")
    swing: float = Field(gt=0.0, lt=360.0, description="psi: crank swing from M1 to M2, deg")


class LinkageSection(StrictModel):
    """The double crank and clamp point. A number fixes a variable, ``{init, bounds}`` frees it."""

    x_a: Variable = Field(description="x of the crank pivot A, mm")
    y_a: Variable = Field(description="y of the crank pivot A, mm")
    l1: Variable = Field(json_schema_extra=POSITIVE, description="crank AB, mm")
    l2: Variable = Field(json_schema_extra=POSITIVE, description="coupler BC, mm")
    l3: Variable = Field(json_schema_extra=POSITIVE, description="follower CD, mm (printed as l4 = 186.7 in the paper's result list)")
    l4: Variable = Field(json_schema_extra=POSITIVE, description="frame AD, the shortest link, mm (printed as l3 = 45.9)")
    l5: Variable = Field(json_schema_extra=POSITIVE, description="clamp arm CM, mm")
    phi3: Variable = Field(json_schema_extra=WITHIN_A_TURN, description="frame AD direction below the +x axis, deg (-360 to 360)")
    phi4: Variable = Field(json_schema_extra=WITHIN_A_TURN, description="CM turned counter-clockwise from BC, deg (-360 to 360)")
    _angles_within_a_turn = field_validator("phi3", "phi4")(within_a_turn)
    branch: Sign = Field(1, description="assembly: C left (+1) or right (-1) of the line B -> D")

    @model_validator(mode="after")
    def _lengths_positive(self) -> "LinkageSection":
        require_positive_fields(self)
        return self


class PickerRules(StrictModel):
    """Limits of the design rules (seed 001 §2.1.2)."""

    min_transmission_angle: float = Field(40.0, gt=0.0, lt=90.0,
                                          description="smallest transmission angle at C over the working swing, deg")
    x_a_min: float = Field(0.0, description="eq (7): the pivot A lies between the frame and the tray, x_A > x_a_min, mm")
    max_arc_error: float | None = Field(
        None, gt=0.0, description="largest distance allowed between a target point and the clamp point at its crank "
                                  "angle, mm (ours, not the paper's); left out: no rule.  Needed by the min-peak "
                                  "objectives, which would otherwise let the clamp leave the arc")


class PickerObjective(StrictModel):
    """What `solve` minimises: how far the clamp point misses the target points."""

    name: Literal["sum_of_distances", "sum_of_squares", "min_peak_torque", "min_peak_shaking_force",
                  "min_peak_shaking_moment"] = Field(
        "sum_of_distances", description="sum_of_distances: seed 001 eq (4), sum of |M_i - target_i| (mm); "
                                        "sum_of_squares: sum of |M_i - target_i|^2 (mm^2); min_peak_torque, "
                                        "min_peak_shaking_force, min_peak_shaking_moment: smallest peak input torque "
                                        "on AB (N m), shaking force (N) or shaking moment about A (N m) over the "
                                        "working swing (a [dynamics] table and [rules] max_arc_error needed)")


class PickerSolver(MultistartSettings):
    starts: Starts = starts_field(8)
    samples: int = Field(26, ge=2, le=2000, description="crank angles over the working swing for the transmission angle")
    max_iter: int = Field(3000, ge=1, description="IPOPT iteration limit per start and stage")
    backoff: float = Field(0.01, ge=0.0, le=1.0, description="the NLP tightens the sampled transmission limit by "
                                                             "backoff x 10 deg, so it holds between samples too (dimensionless)")


#: what the clamp's attitude is (the spec's [key_poses] attitude, result.json's facts.key_poses)
CLAMP_ATTITUDE = ("clamp attitude: the direction of the clamp arm C -> M (fixed on the coupler BC, turned from it "
                  "counter-clockwise by phi4; the clamp and its seedling turn with it), from +x (towards the tray) "
                  "counter-clockwise, deg (up: 90)")


def _where(pose: ClawPose, at, crank_angle) -> None:
    """A pose is read at a named point, at a prescribed crank angle or, free, where the clamp point comes nearest
    its target: not two of them, and a free pose needs the target."""
    if at is not None and crank_angle is not None:
        raise ValueError(f"crank_angle: a pose at {at} is read at that point's crank angle; give at or crank_angle, "
                         f"not both")
    if at is None and crank_angle is None and pose.tip is None:
        raise ValueError("a free pose (no at, no crank_angle) is read where the clamp point comes nearest its "
                         "target: give x and y (mm)")


class ClampPose(ClawPose):
    """A pose the double crank's clamp must pass through: its attitude and/or the clamp point's position, read at the
    picking point M1 or the drop point M2 (``at``) or, for a free pose, where the clamp point comes nearest (x, y)
    over the working swing (or at ``crank_angle``)."""

    at: Literal["M1", "M2"] | None = Field(
        None, description="the named point the pose is read at: M1, the picking point (crank angle phi10, the first "
                          "target point), or M2, the drop point (phi10 + psi, the last): the clamp's attitude there "
                          "and, if x and y are given, the clamp point within tolerance of them; absent: a free pose")
    x: float | None = Field(None, description="clamp point M x (towards the tray), machine frame, mm")
    y: float | None = Field(None, description="clamp point M y (up), machine frame, mm")
    attitude: float | None = attitude_field(CLAMP_ATTITUDE)
    crank_angle: float | None = Field(
        None, ge=-360, le=360, description="crank angle phi1 of a free pose, deg from AD, within the working swing "
                                           "(absent: where the clamp point comes nearest (x, y) over the swing, the "
                                           "solver's choice)")

    @model_validator(mode="after")
    def _read_somewhere(self) -> ClampPose:
        _where(self, self.at, self.crank_angle)
        return self


class PickerDoubleCrankSpec(ProblemSpec):
    kind: Literal["picker_double_crank"] = Field(description="the problem kind (picker_double_crank)")
    target: TargetArc
    drive: DriveSection
    linkage: LinkageSection
    rules: PickerRules = Field(default_factory=PickerRules)
    objective: PickerObjective = Field(default_factory=PickerObjective)
    solver: PickerSolver = Field(default_factory=PickerSolver)
    # seed 001 prints no section, mass or clamp weight: every number of this table is an assumption of the spec's
    # author, to be said in its `assumption` (the library's picker specs: steel flat bars, the paper's 60 r/min)
    dynamics: DynamicsSection | None = Field(
        None, description="mass properties, crank speed and limits for the inverse dynamics of the double crank "
                          "(docs/ARCHITECTURE.md \"Dynamics\"): crank AB, coupler BC (a bar is BC and the clamp arm "
                          "CM of the same section; a point mass at = \"tip\" sits at the clamp point M), follower CD; "
                          "AB turns at the constant crank_speed over the working swing (phi10 to phi10 + psi, ends "
                          "included; samples spread there, not over a turn), though in the picker the crank-rocker "
                          "drives it at a varying speed.  Seed 001 gives no masses: every value is an assumption, "
                          "say which in `assumption`.  Left out: no dynamics, no dynamics rules")
    key_poses: dict[str, ClampPose] = Field(
        default_factory=dict, max_length=MAX_POSES,
        description="named poses, e.g. [key_poses.pick] at = \"M1\", attitude = 40: the clamp's attitude (and "
                    "optionally the clamp point's position) at the picking point M1 or the drop point M2, or a free "
                    "pose at x, y over the working swing; each adds the rules pose_<name> (clamp point) and "
                    "pose_<name>_attitude")
    _pose_names = field_validator("key_poses")(pose_names)

    @model_validator(mode="after")
    def _poses_within_the_swing(self) -> PickerDoubleCrankSpec:
        lo, hi = self.drive.start, self.drive.start + self.drive.swing
        for name, pose in self.key_poses.items():
            # a turn is 360 deg: a swing past 360 (330 to 380) holds 10 deg as well as 370
            if pose.crank_angle is not None and not (pose.crank_angle - lo) % 360.0 <= hi - lo:
                raise ValueError(f"key_poses.{name}.crank_angle = {pose.crank_angle:g} deg: the clamp moves only over "
                                 f"the working swing, crank angles {lo:g} to {hi:g} deg")
        return self

    @model_validator(mode="after")
    def _dynamics_can_be_evaluated(self) -> "PickerDoubleCrankSpec":
        objective = self.objective.name
        if objective.startswith("min_peak") and self.dynamics is None:
            raise ValueError(f"objective.name = {objective!r} needs a [dynamics] table (mass properties and crank "
                             f"speed)")
        if objective.startswith("min_peak") and self.rules.max_arc_error is None:
            raise ValueError(f"objective.name = {objective!r} needs rules.max_arc_error (mm): without it the clamp "
                             f"need not follow the picking arc at all")
        if self.dynamics is None:
            return self
        if self.dynamics.crank_speed is None:
            raise ValueError("dynamics.crank_speed: a picker_double_crank has no crank speed of its own; give AB's "
                             "in r/min")
        if self.dynamics.drive is not None:
            raise ValueError("dynamics.drive: a picker_double_crank's dynamics cover its working swing, not a full "
                             "turn, so it has no steady speed fluctuation; leave the field out")
        weight = self.dynamics.counterweight
        if weight is not None and not all(isinstance(v, (int, float)) for v in (weight.mass, weight.radius)):
            raise ValueError("dynamics.counterweight: a picker_double_crank's solve frees only its linkage; give the "
                             "counterweight's mass (kg) and radius (mm) as numbers")
        if self.dynamics.rocker_counterweight is not None:
            raise ValueError("dynamics.rocker_counterweight: a picker_double_crank reads a counterweight on its input "
                             "crank AB only; leave the field out")
        if any(pm.at == "tip" and pm.link != "coupler" for pm in self.dynamics.point_masses):
            raise ValueError("dynamics.point_masses: at = \"tip\" is the clamp point M, on the coupler; on the crank "
                             "or the follower give the position in the link frame, mm")
        return self

    def choice_variables(self) -> dict[str, str]:
        """result.json's design holds the assembly branch beside the variables: its TOML path."""
        return {"branch": "linkage.branch"}

    def variables(self) -> dict[str, Variable]:
        return {n: getattr(self.linkage, n) for n in ("x_a", "y_a", "l1", "l2", "l3", "l4", "l5", "phi3", "phi4")}

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}


class Installation(StrictModel):
    """How the crank-rocker AEFG drives crank AB (seed 001 §2.1.3; our reading in PICKER.md)."""

    theta1: float = Field(gt=0.0, lt=180.0, description="published angle G-A-E between the frame AG and the rocker AE "
                                                       "at the picking extreme, deg (checked against the mechanism's)")
    theta1_tolerance: float = Field(0.5, ge=0.0, description="|theta1 - computed| allowed, deg (printed to 1 deg)")
    theta2: float = Field(ge=-180.0, le=180.0, description="direction of the frame A -> G above the +x axis, deg")
    picking_extreme: Literal["folded", "extended"] = Field(
        "folded", description="rocker extreme at which the clamp is at M1 (folded: crank and coupler overlap)")
    holding_stroke: Literal["quick", "slow"] = Field(
        "quick", description="the stroke M1 -> M2 that holds the seedling: the quick one shortens the holding time")
    swing_tolerance: float = Field(0.1, ge=0.0, description="|rocker swing - crank AB swing| allowed, deg")


class Operation(StrictModel):
    """Operating condition of the combined picker."""

    crank_speed: float = Field(gt=0.0, le=2000.0, description="crank GF speed, r/min (seed 001: 60)")


class Published(StrictModel):
    """Numbers the paper reports for the combined picker, shown beside ours."""

    instants: tuple[float, float, float] | None = Field(None, description="picking, dropping, picking again, s")

    @model_validator(mode="after")
    def _in_order(self) -> "Published":
        if self.instants is not None:
            pick, drop, again = self.instants
            if not 0.0 <= pick < drop < again:
                raise ValueError(f"instants: [{pick:g}, {drop:g}, {again:g}] s must be picking, dropping, picking "
                                 f"again in that order (0 <= picking < dropping < picking again)")
        return self


class PickerPose(ClawPose):
    """A pose the combined picker's clamp must pass through: its attitude and/or the clamp point's position, read at
    the picking or the dropping instant (``at``) or, for a free pose, where the clamp point comes nearest (x, y)
    over a turn of the crank GF (or at ``crank_angle``)."""

    at: Literal["picking", "dropping"] | None = Field(
        None, description="the instant the pose is read at: picking (t = 0, the rocker at its picking extreme, the "
                          "clamp at M1) or dropping (the other extreme, the clamp near M2): the clamp's attitude "
                          "there and, if x and y are given, the clamp point within tolerance of them; absent: a free "
                          "pose")
    x: float | None = Field(None, description="clamp point M x (towards the tray), machine frame, mm")
    y: float | None = Field(None, description="clamp point M y (up), machine frame, mm")
    attitude: float | None = attitude_field(CLAMP_ATTITUDE)
    crank_angle: float | None = Field(
        None, ge=0, lt=360, description="angle turned by the crank GF since picking, deg, of a free pose (absent: "
                                        "where the clamp point comes nearest (x, y) over a turn; the clamp passes "
                                        "each point of its path twice, holding and returning, in the same pose: the "
                                        "first is taken)")

    @model_validator(mode="after")
    def _read_somewhere(self) -> PickerPose:
        _where(self, self.at, self.crank_angle)
        return self


class PartMasses(StrictModel):
    """One linkage's moving links in the combined picker's ``[dynamics]``: each a bar {density, area} along its joints
    or lumped {mass, com, inertia} in its link frame (origin at its first joint, x towards its second), with the
    masses it carries."""

    crank: BarLink | LumpedLink = Field(description="the crank: a bar or {mass, com, inertia}")
    coupler: BarLink | LumpedLink = Field(description="the coupler: a bar or {mass, com, inertia}")
    rocker: BarLink | LumpedLink = Field(description="the rocker (the double crank's: the follower CD, origin D, x "
                                                     "towards C): a bar or {mass, com, inertia}")
    point_masses: list[PointMass] = Field(default_factory=list, description="masses carried by these links")


class PickerDynamicsSection(StrictModel):
    """Mass properties, gravity and limits for the inverse dynamics of the combined picker over a turn of the crank GF
    at ``[operation] crank_speed`` (synthesis/kinds/picker/combined_dynamics.py).  The rocker AE and the crank AB are
    one rigid body turning about A: its mass is given in two halves, AE as the crank-rocker's rocker and AB as the
    double crank's crank, each in its own link frame."""

    crank_rocker: PartMasses = Field(description="the drive AEFG: crank GF (origin G, x towards F), coupler FE (origin "
                                                 "F, x towards E), rocker AE (origin A, x towards E: the rigid body's "
                                                 "part on the drive's side)")
    double_crank: PartMasses = Field(description="the double crank ABCD: crank AB (origin A, x towards B: the rigid "
                                                 "body's other part), coupler BC (a bar is BC and the clamp arm CM of "
                                                 "the same section; a point mass at = \"tip\" sits at the clamp "
                                                 "point M), rocker = the follower CD (origin D, x towards C)")
    gravity: tuple[float, float] = Field((0.0, -9.81), description="gravity in the machine frame, m/s^2 (0 allowed)")
    samples: int = Field(360, ge=8, le=3600, description="instants of result.json's facts.dynamics over a turn of the "
                                                         "crank GF, evenly from picking")
    limits: DynamicsLimits = Field(default_factory=DynamicsLimits,
                                   description="peak_input_torque: the motor's on GF; peak_shaking_force: the sum "
                                               "over the frame pivots G, A and D; peak_shaking_moment: about G")
    assumption: str = Field("", description="which values are ours, not a paper's")

    @model_validator(mode="after")
    def _tip_is_the_clamp(self) -> PickerDynamicsSection:
        if any(pm.at == "tip" for pm in self.crank_rocker.point_masses):
            raise ValueError("crank_rocker.point_masses: at = \"tip\" is the clamp point M, on the double crank's "
                             "coupler; on the drive give the position in the link frame, mm")
        if any(pm.at == "tip" and pm.link != "coupler" for pm in self.double_crank.point_masses):
            raise ValueError("double_crank.point_masses: at = \"tip\" is the clamp point M, on the coupler; on the "
                             "crank or the follower give the position in the link frame, mm")
        return self


class PickerSpec(ProblemSpec):
    kind: Literal["picker"] = Field(description="the problem kind (picker)")
    crank_rocker: Annotated[str, SPEC_FILE] = Field(description="crank_rocker spec file of the drive, relative to "
                                                                "this file")
    double_crank: Annotated[str, SPEC_FILE] = Field(description="picker_double_crank spec file of the linkage, "
                                                                "relative to this file")
    installation: Installation
    operation: Operation
    published: Published = Field(default_factory=Published)

    @field_validator("crank_rocker", "double_crank")
    @classmethod
    def _a_file_name(cls, value: str) -> str:
        # a NUL or an empty name is no file: said here, not as the operating system's error when the part is read
        if not value.strip() or "\x00" in value:
            raise ValueError(f"expected the name of a spec file, got {value!r}")
        return value
    key_poses: dict[str, PickerPose] = Field(
        default_factory=dict, max_length=MAX_POSES,
        description="named poses of the combined motion, e.g. [key_poses.drop] at = \"dropping\", attitude = 60: "
                    "the clamp's attitude (and optionally the clamp point's position) at the picking or dropping "
                    "instant, or a free pose at x, y; each adds the rules pose_<name> (clamp point) and "
                    "pose_<name>_attitude.  The double crank's own [key_poses] (at M1, M2) are its part's rules")
    _pose_names = field_validator("key_poses")(pose_names)
    # seed 001 prints no section or mass: every number of this table is an assumption of the spec's author
    dynamics: PickerDynamicsSection | None = Field(
        None, description="mass properties, gravity and limits for the inverse dynamics of the whole picker over a "
                          "turn of the crank GF at [operation] crank_speed: the drive at constant speed, the double "
                          "crank driven through the rigid body AE + AB at the speed the rocker gives it "
                          "(docs/ARCHITECTURE.md \"Dynamics\").  Left out: no dynamics, no dynamics rules")

    def part_path(self, spec_path: Path, field: str) -> Path:
        return (spec_path.parent / getattr(self, field)).resolve()

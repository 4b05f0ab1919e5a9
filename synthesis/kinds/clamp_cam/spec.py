"""Spec model of kind ``clamp_cam``: a disc cam with a roller follower (seed 001 §2.2, Table 1).

A cam spec builds no linkage and no drop model: the timing comes in as numbers (crank angles on
the picker's clock, or times at the crank speed), copied from a picker result or typed.

Units: lengths mm, angles deg, crank speed r/min.  The stroke is in mm for a translating
follower and in degrees (arm swing) for an oscillating one.
"""

from __future__ import annotations

from typing import Annotated, Literal, get_args

from pydantic import Field, PrivateAttr, ValidationInfo, field_validator, model_validator

from synthesis.spec.common import (NON_NEGATIVE, POSITIVE, Starts,
    WITHIN_A_TURN, FreeVariable, Interval, MultistartSettings, ProblemSpec, StrictModel, Variable, bounds_of, is_free,
    max_iter_field, Sign, starts_field, value_of, within_a_turn,
)
from synthesis.spec.operating import OperatingRange, resolve_ranges

KIND = "clamp_cam"
SEGMENTS = ("rise", "far_dwell", "return", "near_dwell")
#: closed-form motion law families, plus the B-spline law fitted by cvxpy
Law = Literal["cycloidal", "poly345", "modified_trapezoid", "modified_sine", "optimised"]
LAWS = get_args(Law)


def _lo(v: Variable) -> float:
    return bounds_of(v)[0]


def _hi(v: Variable) -> float:
    return bounds_of(v)[1]


def _fmt(v: Variable) -> str:
    if isinstance(v, FreeVariable):
        return f"{v.init:g} (free in [{v.bounds[0]:g}, {v.bounds[1]:g}])"
    return f"{float(v):g}"


class CamSection(StrictModel):
    """The cam disc and the roller."""

    base_radius: Variable = Field(json_schema_extra=POSITIVE, description="pitch base circle: smallest distance of the roller centre "
                                              "from the cam centre, mm (seed 001 Table 1: 50)")
    roller_radius: Variable = Field(json_schema_extra=POSITIVE, description="roller radius, mm (seed 001 Table 1: 3.5)")
    rotation: Literal["counter_clockwise", "clockwise"] = Field(
        "counter_clockwise", description="turning sense of the cam seen from the side the profile is drawn on; "
                                         "clockwise mirrors the exported profile (seed 001 eq 12 is counter-clockwise)")

    @field_validator("base_radius")
    @classmethod
    def _base_positive(cls, base: Variable) -> Variable:
        if _lo(base) <= 0:
            raise ValueError(f"expected > 0, got {_fmt(base)} mm" + (" (its lower bound)" if is_free(base) else ""))
        return base

    @field_validator("roller_radius")
    @classmethod
    def _roller_inside_base(cls, roller: Variable, info: ValidationInfo) -> Variable:
        if _lo(roller) <= 0:
            raise ValueError(f"expected > 0, got {_fmt(roller)} mm" + (" (its lower bound)" if is_free(roller) else ""))
        base = info.data.get("base_radius")
        if base is not None and _hi(roller) >= _lo(base):
            largest = f" (its upper bound {_hi(roller):g} mm)" if is_free(roller) else ""
            smallest = (f"the smallest base_radius its bounds allow, {_lo(base):g} mm" if is_free(base)
                        else f"base_radius, {_lo(base):g} mm")
            raise ValueError(f"expected below {smallest}, got {_fmt(roller)} mm{largest}: the roller must be "
                             "smaller than the base circle at every design the bounds allow")
        return roller


class FollowerSection(StrictModel):
    """Roller follower: translating (offset allowed) or oscillating (arm on a pivot)."""

    type: Literal["translating", "oscillating"] = Field(
        "translating", description="translating: the roller centre moves on a line (offset); oscillating: it swings "
                                   "on an arm about a pivot (pivot_distance, arm_length)")
    offset: Variable | None = Field(None, description="translating: offset of the follower line, mm; > 0 on the "
                                                      "side that lowers the rise pressure angle (Table 1: 0)")
    pivot_distance: Variable | None = Field(None, description="oscillating: cam centre to arm pivot, mm")
    arm_length: Variable | None = Field(None, description="oscillating: arm pivot to roller centre, mm")
    side: Sign = Field(1, description="oscillating: +1 roller on the +Y side of the line cam centre -> "
                                                "pivot (follower along +X as in seed 001 eq 12), -1 the other")

    @model_validator(mode="after")
    def _fields_of_type(self) -> "FollowerSection":
        if self.type == "translating":
            for name in ("pivot_distance", "arm_length"):
                if getattr(self, name) is not None:
                    raise ValueError(f"{name}: only for type = \"oscillating\" (this follower translates)")
        else:
            if self.offset is not None:
                raise ValueError("offset: only for type = \"translating\" (an oscillating follower has "
                                 "pivot_distance and arm_length)")
            for name in ("pivot_distance", "arm_length"):
                v = getattr(self, name)
                if v is None:
                    raise ValueError(f"{name}: missing required field for type = \"oscillating\"")
                if _lo(v) <= 0:
                    raise ValueError(f"{name}: expected > 0, got {_lo(v):g}")
        return self


class MotionSection(StrictModel):
    """Motion law and timing of one turn: rise, far dwell, return, near dwell (seed 001 Table 1)."""

    law: Law = Field("cycloidal", description="motion law of the rise and the return: " + ", ".join(LAWS))
    stroke: float = Field(gt=0, description="follower stroke: mm (translating) or deg of arm swing (oscillating)")
    rise_start: Variable = Field(0.0, json_schema_extra=WITHIN_A_TURN, description="crank angle at which the rise begins, deg on the picker's "
                                                  "clock (0 = the pick; -360 to 360)")
    _angles_within_a_turn = field_validator("rise_start")(within_a_turn)
    rise: Variable = Field(json_schema_extra=POSITIVE, description="rise angle, deg")
    far_dwell: Variable = Field(json_schema_extra=NON_NEGATIVE, description="far dwell angle, deg (follower held at the full stroke)")
    return_: Variable = Field(alias="return", json_schema_extra=POSITIVE, description="return angle, deg")
    near_dwell: Variable = Field(json_schema_extra=NON_NEGATIVE, description="near dwell angle, deg (follower held at rest)")

    def segments(self) -> dict[str, Variable]:
        return {"rise": self.rise, "far_dwell": self.far_dwell, "return": self.return_,
                "near_dwell": self.near_dwell}

    @model_validator(mode="after")
    def _segments(self) -> "MotionSection":
        seg = self.segments()
        for name in ("rise", "return"):
            if _lo(seg[name]) <= 0:
                raise ValueError(f"{name}: expected > 0, got {_lo(seg[name]):g}")
        for name in ("far_dwell", "near_dwell"):
            if _lo(seg[name]) < 0:
                raise ValueError(f"{name}: expected >= 0, got {_lo(seg[name]):g}")
        total = sum(value_of(v) for v in seg.values())
        if abs(total - 360.0) > 1e-6:
            terms = " + ".join(f"{value_of(v):g}" for v in seg.values())
            raise ValueError(f"rise + far_dwell + return + near_dwell = {terms} = {total:g} deg, expected 360 "
                             "(one turn of the cam)")
        if sum(_lo(v) for v in seg.values()) > 360.0 or sum(_hi(v) for v in seg.values()) < 360.0:
            raise ValueError("the segment bounds cannot sum to 360 deg: widen them")
        if self.law == "optimised" and any(is_free(v) for v in seg.values()):
            free = [n for n, v in seg.items() if is_free(v)]
            raise ValueError(f"{free[0]}: the optimised law is fitted once for fixed segments, before the geometry "
                             "NLP; give a number (or pick a closed-form law to optimise the timing)")
        return self


class BSplineSection(StrictModel):
    """The optimised law (motion.law = "optimised"): B-spline displacement fitted by one convex problem."""

    minimise: Literal["acceleration", "jerk", "spring_force"] = Field(
        "acceleration", description="peak follower acceleration, peak jerk, or spring_force: the least spring "
                                    "force at full stroke (preload + stiffness x stroke) that holds the "
                                    "[dynamics.limits] jump speed and contact force, the law fitted with the spring "
                                    "(a translating follower on a given cam; the stiffness at its value or its lower "
                                    "bound; the NLP then sizes the spring for the law)")
    spans: int = Field(32, ge=4, le=400, description="uniform knot spans in each of the rise and the return")
    degree: int = Field(5, ge=3, le=7, description="spline degree (>= 3: continuity to the acceleration, C2)")
    samples_per_span: int = Field(8, ge=2, le=50, description="points per span where the peak is bounded")

    @model_validator(mode="after")
    def _degree_above_the_minimised_derivative(self) -> "BSplineSection":
        # the fit's tie-break smooths the derivative after the minimised one (the 4th for jerk), which a cubic
        # does not have: refused here, once, instead of a traceback out of the fit
        if self.minimise == "jerk" and self.degree < 4:
            raise ValueError(f"minimise = 'jerk' needs degree >= 4 (a degree-{self.degree} spline's jerk is "
                             "piecewise constant, with no derivative to smooth); give degree = 4 or more")
        return self


class TimingSection(StrictModel):
    """Windows the follower must dwell through, on the picker's clock (0 = the pick)."""

    clock: Literal["deg", "s"] = Field("deg", description="windows in crank degrees or in seconds at the crank speed")
    hold_near: list[Interval] = Field(default_factory=list,
                                      description="windows where the follower must rest at the near dwell "
                                                  "(opening cam: clamp closed), [lo, hi] deg or s (timing.clock)")
    hold_far: list[Interval] = Field(default_factory=list,
                                     description="windows where the follower must stay at full stroke "
                                                 "(opening cam: clamp open), [lo, hi] deg or s (timing.clock)")

    @model_validator(mode="after")
    def _windows(self) -> "TimingSection":
        for name in ("hold_near", "hold_far"):
            for i, (lo, hi) in enumerate(getattr(self, name)):
                if lo > hi:
                    raise ValueError(f"{name}[{i}]: [{lo:g}, {hi:g}] has lo > hi")
        return self


class OperationSection(StrictModel):
    """Operating condition: the cam speed (turns the timing in seconds into crank degrees).  It may be given as a
    range ``{range = [lo, hi], samples = N}``: the solve then holds every rule that reads it (the follower's
    acceleration and dynamics, windows timed in seconds) at each sampled speed (an operating envelope, one shared
    design) and re-checks the answer on a finer grid of the range."""

    crank_speed: Annotated[float, Field(gt=0, le=2000)] | OperatingRange = Field(
        description="cam speed, r/min: the cams turn once per picker crank turn (seed 001: 60); or a range "
                    "{range = [lo, hi], samples = 4, nominal = (lo+hi)/2, step = re-check spacing}")
    _operating_ranges: dict = PrivateAttr(default_factory=dict)

    @model_validator(mode="after")
    def _nominal(self) -> "OperationSection":
        resolve_ranges(self, {"crank_speed": "> 0, <= 2000"})
        return self

    @property
    def speed(self) -> float:
        """The cam speed, r/min (a range's nominal value once validated)."""
        assert not isinstance(self.crank_speed, OperatingRange), "validation leaves a range's nominal value"
        return self.crank_speed


class RulesSection(StrictModel):
    """Limits of the design rules."""

    pressure_angle_rise: float = Field(30.0, gt=0, lt=90, description="max |pressure angle| on the rise, deg")
    pressure_angle_return: float = Field(45.0, gt=0, lt=90, description="max |pressure angle| on the return, deg")
    min_working_radius: float = Field(3.0, ge=0, description="smallest radius of curvature of the working profile "
                                                             "a cutter can make and a roller can run on, mm "
                                                             "(default 3: machine-design texts ask 3-5 mm; "
                                                             "0 only forbids the undercut cusp)")
    groove: bool = Field(False, description="the roller runs in a groove: also forbid the undercut of the outer "
                                            "flank (concave pitch radius < roller radius)")
    max_acceleration: float | None = Field(None, gt=0, description="max |follower acceleration| at the crank speed: "
                                                                   "mm/s^2 (translating) or deg/s^2 (oscillating)")


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the cams that satisfy every rule."""

    name: Literal["base_radius", "pressure_angle", "nearest", "spring_force"] = Field(
        "base_radius", description="base_radius: smallest pitch base circle (compact cam); pressure_angle: "
                                   "smallest peak |pressure angle| on rise and return; nearest: smallest change "
                                   "of the free variables from the given design; spring_force: smallest peak "
                                   "spring load on the follower, preload + stiffness x stroke (needs [dynamics])")


class DynamicsLimits(StrictModel):
    """Rules on the follower dynamics; a limit left out is no rule."""

    min_contact_force: float | None = Field(
        None, ge=0, le=1.0e5, description="smallest contact force between roller and cam over a turn at the crank "
                                          "speed (at every speed of an operating range), N")
    max_hertz_stress: float | None = Field(
        None, gt=0, le=1.0e5, description="largest Hertz contact stress between roller and cam over a turn at the "
                                          "crank speed, MPa (needs roller_width)")
    min_jump_speed: float | None = Field(
        None, gt=0, le=20000, description="the follower must stay on the cam up to this cam speed: the jump speed "
                                          "(the speed at which the contact force first reaches zero) at least this, "
                                          "r/min")


#: the fields of each follower type (the others are refused)
_BODY_FIELDS = {"translating": ("mass", "spring_preload", "spring_stiffness"),
                "oscillating": ("inertia", "spring_preload_torque", "spring_torsional_stiffness")}


class DynamicsSection(StrictModel):
    """The follower's mass and spring and the roller's contact with the cam: the contact force over a turn at the
    crank speed, the jump speed and the Hertz stress (synthesis/kinds/clamp_cam/kinematics/follower_dynamics.py).
    Friction and the roller's spin inertia are left out."""

    mass: float | None = Field(None, gt=0, le=1000, description="translating: mass of everything that moves with "
                                                                "the follower (slider, roller, and the pull wire's "
                                                                "and clamp's mass reflected to it), kg")
    spring_preload: Variable | None = Field(None, description="translating: spring force pressing the follower "
                                                              "onto the cam at rest (s = 0, the near dwell), N")
    spring_stiffness: Variable | None = Field(None, description="translating: spring rate along the follower, N/mm")
    inertia: float | None = Field(None, gt=0, le=1000, description="oscillating: moment of inertia of the arm and "
                                                                   "roller about the arm pivot, kg m^2")
    spring_preload_torque: Variable | None = Field(None, description="oscillating: torque of the torsional spring "
                                                                     "about the pivot pressing the roller onto the "
                                                                     "cam at rest (psi = 0), N m")
    spring_torsional_stiffness: Variable | None = Field(None, description="oscillating: rate of the torsional "
                                                                          "spring about the pivot, N m/rad")
    arm_mass: float = Field(0.0, ge=0, le=1000, description="oscillating: mass of the arm and roller, for gravity "
                                                            "only (inertia gives the dynamics), kg")
    com_distance: float = Field(0.0, ge=0, le=1.0e4, description="oscillating: pivot to the arm's centre of mass, "
                                                                 "on the line to the roller centre, mm (gravity only)")
    gravity: tuple[float, float] = Field((0.0, 0.0), description="gravity in the cam's ground frame (cam centre at "
                                                                 "the origin, the follower along +X), m/s^2; "
                                                                 "default none: the mounting is not given")
    roller_width: float | None = Field(None, gt=0, le=1000, description="length of the line contact: the roller's "
                                                                        "width (the cam's thickness if narrower), mm")
    roller_modulus: float = Field(206000.0, gt=0, le=2.0e6, description="roller's elastic modulus, MPa "
                                                                        "(default steel, 206000)")
    roller_poisson: float = Field(0.3, ge=0, lt=0.5, description="roller's Poisson ratio (dimensionless; default "
                                                                 "steel, 0.3)")
    cam_modulus: float = Field(206000.0, gt=0, le=2.0e6, description="cam's elastic modulus, MPa (default steel, "
                                                                     "206000)")
    cam_poisson: float = Field(0.3, ge=0, lt=0.5, description="cam's Poisson ratio (dimensionless; default steel, "
                                                              "0.3)")
    limits: DynamicsLimits = Field(default_factory=DynamicsLimits)
    assumption: str = Field("", description="which values are ours, not a paper's")

    @model_validator(mode="after")
    def _springs_not_negative(self) -> "DynamicsSection":
        for name in ("spring_preload", "spring_stiffness", "spring_preload_torque", "spring_torsional_stiffness"):
            v = getattr(self, name)
            if v is not None and _lo(v) < 0:
                raise ValueError(f"{name}: expected >= 0, got {_fmt(v)}"
                                 + (" (its lower bound)" if is_free(v) else ""))
        if self.limits.max_hertz_stress is not None and self.roller_width is None:
            raise ValueError("limits.max_hertz_stress: the Hertz stress needs roller_width (the contact length, mm)")
        return self

    def body_fields(self, follower_type: str) -> tuple[str, str, str]:
        """(inertia, preload, stiffness) field names of a follower type."""
        a, b, c = _BODY_FIELDS[follower_type]
        return a, b, c


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(4)
    samples_per_segment: int = Field(100, ge=5, le=2000, description="samples of the rise and of the return in the "
                                                                    "NLP (the re-check uses 10x more)")
    max_iter: int = max_iter_field(500)
    backoff: float = Field(0.01, ge=0, le=1, description="the NLP tightens every sampled rule by backoff x its "
                                                         "scale, so it holds between the samples too (dimensionless)")


class ClampCamSpec(ProblemSpec):
    kind: Literal["clamp_cam"] = Field(description="the problem kind (clamp_cam)")

    @classmethod
    def old_forms(cls, data: dict) -> str:
        """The hyphenated turning sense ("counter-clockwise"), with its new spelling (see spec.common.validate)."""
        cam = data.get("cam")
        rotation = cam.get("rotation") if isinstance(cam, dict) else None
        if rotation != "counter-clockwise":
            return ""
        return 'cam.rotation: "counter-clockwise" is no longer read; write rotation = "counter_clockwise"'
    cam: CamSection
    follower: FollowerSection = Field(default_factory=FollowerSection)
    motion: MotionSection
    bspline: BSplineSection = Field(default_factory=BSplineSection)
    timing: TimingSection = Field(default_factory=TimingSection)
    operation: OperationSection
    rules: RulesSection = Field(default_factory=RulesSection)
    dynamics: DynamicsSection | None = Field(None, description="the follower's mass and spring, the roller's "
                                                               "contact: contact force, jump speed, Hertz stress")
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)

    @model_validator(mode="after")
    def _geometry(self) -> "ClampCamSpec":
        r0 = value_of(self.cam.base_radius)
        f = self.follower
        if f.type == "translating":
            e = 0.0 if f.offset is None else value_of(f.offset)
            if abs(e) >= 0.9 * r0:
                raise ValueError(f"follower.offset: expected |offset| < 0.9 x base_radius ({0.9 * r0:g} mm), "
                                 f"got {e:g}")
        else:
            assert f.pivot_distance is not None and f.arm_length is not None, "an oscillating follower has both"
            a, l = value_of(f.pivot_distance), value_of(f.arm_length)
            if not abs(a - l) < r0 < a + l:
                raise ValueError(f"follower: the arm cannot reach the base circle: need |pivot_distance - "
                                 f"arm_length| < base_radius < pivot_distance + arm_length, got |{a:g} - {l:g}| "
                                 f"and {r0:g} mm")
            if self.motion.stroke >= 90.0:
                raise ValueError(f"motion.stroke: expected < 90 deg of arm swing, got {self.motion.stroke:g}")
        return self

    @model_validator(mode="after")
    def _one_law_over_a_speed_range(self) -> "ClampCamSpec":
        if self.operation._operating_ranges and self.motion.law == "optimised":
            raise ValueError("operation.crank_speed: a range needs a closed-form motion law (the optimised law is "
                             "fitted once, at one speed)")
        return self

    @model_validator(mode="after")
    def _spring_shaped_law(self) -> "ClampCamSpec":
        if self.motion.law != "optimised" or self.bspline.minimise != "spring_force":
            return self
        why = "bspline.minimise = \"spring_force\" fits the law with a translating follower's spring on a given cam"
        if self.follower.type != "translating":
            raise ValueError(f"follower.type: {why}; an oscillating follower is not supported (give minimise = "
                             "\"acceleration\" or \"jerk\")")
        for field, value in (("cam.base_radius", self.cam.base_radius), ("follower.offset", self.follower.offset)):
            if value is not None and is_free(value):
                raise ValueError(f"{field}: {why}, whose pressure angle it holds: give a number")
        if self.dynamics is None:
            raise ValueError("bspline.minimise: \"spring_force\" needs a [dynamics] table (the follower's mass "
                             "and spring)")
        limits = self.dynamics.limits
        if limits.min_jump_speed is None and limits.min_contact_force is None:
            raise ValueError("bspline.minimise: \"spring_force\" needs dynamics.limits.min_jump_speed or "
                             "min_contact_force (what the spring must hold the follower against)")
        preload, stiffness = self.dynamics.spring_preload, self.dynamics.spring_stiffness
        if preload is not None and stiffness is not None and not is_free(preload) and is_free(stiffness):
            # the fit holds the stiffness at its lower bound, which loses nothing only if the preload may rise
            raise ValueError("dynamics.spring_preload: bspline.minimise = \"spring_force\" fits the preload with the "
                             "stiffness at its lower bound; free the preload too ({init, bounds}) or give the "
                             "stiffness as a number")
        return self

    @model_validator(mode="after")
    def _dynamics_of_the_follower(self) -> "ClampCamSpec":
        d, kind = self.dynamics, self.follower.type
        if d is None:
            if self.objective.name == "spring_force":
                raise ValueError("objective.name = \"spring_force\" needs a [dynamics] table (the follower's spring)")
            return self
        other = "oscillating" if kind == "translating" else "translating"
        for name in _BODY_FIELDS[other]:
            if getattr(d, name) is not None:
                raise ValueError(f"dynamics.{name}: only for a follower of type = \"{other}\" (this one is {kind}; "
                                 f"give {', '.join(_BODY_FIELDS[kind])})")
        for name in _BODY_FIELDS[kind]:
            if getattr(d, name) is None:
                raise ValueError(f"dynamics.{name}: missing required field for a {kind} follower")
        if kind == "translating" and (d.arm_mass or d.com_distance):
            raise ValueError("dynamics.arm_mass, com_distance: only for an oscillating follower (a translating "
                             "follower's mass is dynamics.mass)")
        return self

    @model_validator(mode="after")
    def _windows_apart(self) -> "ClampCamSpec":
        turn = 360.0 if self.timing.clock == "deg" else 60.0 / self.operation.speed
        unit = "deg" if self.timing.clock == "deg" else "s"
        windows = {k: getattr(self.timing, k) for k in ("hold_near", "hold_far")}
        for kind, ws in windows.items():
            for i, (lo, hi) in enumerate(ws):
                if hi - lo > turn:
                    raise ValueError(f"timing.{kind}[{i}]: [{lo:g}, {hi:g}] is longer than one turn ({turn:g} {unit})")
        for i, (a0, a1) in enumerate(windows["hold_near"]):
            for j, (b0, b1) in enumerate(windows["hold_far"]):
                if any(max(a0, b0 + k * turn) < min(a1, b1 + k * turn) for k in (-2, -1, 0, 1, 2)):
                    raise ValueError(f"timing: hold_near[{i}] [{a0:g}, {a1:g}] overlaps hold_far[{j}] [{b0:g}, {b1:g}] "
                                     f"{unit}: the follower cannot rest and stay at full stroke at once")
        return self

    def variables(self) -> dict[str, Variable]:
        """Every design variable (spec units) by its result.json name."""
        out: dict[str, Variable] = {"base_radius": self.cam.base_radius, "roller_radius": self.cam.roller_radius}
        f = self.follower
        if f.type == "translating":
            out["offset"] = 0.0 if f.offset is None else f.offset
        else:
            assert f.pivot_distance is not None and f.arm_length is not None, "an oscillating follower has both"
            out["pivot_distance"] = f.pivot_distance
            out["arm_length"] = f.arm_length
        out["rise_start"] = self.motion.rise_start
        out.update(self.motion.segments())
        if self.dynamics is not None:
            _, preload, stiffness = self.dynamics.body_fields(f.type)
            for name in (preload, stiffness):
                value = getattr(self.dynamics, name)
                assert value is not None, "validation requires the follower type's spring"
                out[name] = value
        return out

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

    def free_names(self) -> list[str]:
        return [n for n, v in self.variables().items() if isinstance(v, FreeVariable)]

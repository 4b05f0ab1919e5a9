"""Spec model of kind ``guide_way``: the rotary-arm slide guide way of seed 003 (Liang et al.).

The arm OP turns uniformly; the claw PM and the crank arm PN are one rigid body pivoting at P; the
roller at N runs in a fixed guide way.  A spec gives the arm geometry, the claw-tip path relative
to the frame (in time order, from where the guide takes the claw over to where it lets go) and
the rule limits.  The path is either the paper's conic segments (``[[conic]]``, check only) or a
periodic cubic B-spline through key points with tangents (``[spline]``), fitted once by cvxpy and
then held to the rules by IPOPT (``solve``).

Units: mm and deg.  Frame and angles of the paper's eq (5)-(7) (problems/guide_way/GUIDE_WAY.md).
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.common import (FreeVariable, MultistartSettings, ProblemSpec, Sign, Starts, StrictModel, Variable,
                                   value_of)
from synthesis.spec.dynamics import BarLink, DynamicsLimits, LumpedLink

KIND = "guide_way"
Point = tuple[float, float]


class ArmSection(StrictModel):
    """The rotary arm, the claw and the roller (seed 003 §3(1))."""

    radius: float = Field(gt=0, description="arm OP, R, mm (seed 003: 140, the 280 mm planting wheel)")
    claw: float = Field(gt=0, description="claw PM, d, mm (seed 003: 119.6829)")
    crank: float = Field(gt=0, description="crank arm PN, r, mm (seed 003: 70)")
    beta: float = Field(gt=0, lt=360, description="angle NPM, deg (seed 003: 179.6)")
    roller_radius: float = Field(gt=0, description="roller radius, mm (seed 003: 15)")

    @model_validator(mode="after")
    def _claw_shorter(self) -> "ArmSection":
        if self.claw >= self.radius:
            raise ValueError(f"claw: expected < radius ({self.radius:g} mm), got {self.claw:g} mm: the claw must "
                             "fold onto the arm inside the wheel")
        return self


#: the branch's earlier spelling -> its sign (result.json's facts keep the words: ``ik_branch``)
OLD_BRANCHES = {"minus": -1, "plus": 1}


class ConicSegment(StrictModel):
    """One conic x^2 + a1 xy + a2 y^2 + a3 x + a4 y + a5 = 0 (eq 1) between two key points, in time order."""

    name: str = Field(description="segment name, e.g. 'CD'")
    start: str = Field(alias="from", description="key point where the claw enters the segment")
    end: str = Field(alias="to", description="key point where it leaves it")
    coefficients: tuple[float, float, float, float, float] = Field(description="a1..a5 as printed (a1, a2 dimensionless; a3, a4 mm; a5 mm^2)")
    branch: Sign = Field(description="inverse kinematics: theta = gamma + branch * phi, i.e. -1: "
                                               "gamma - phi (the paper's eq 7), +1: gamma + phi")
    form: Literal["y+", "y-", "x+", "x-"] | None = Field(
        None, description="the paper's explicit form (§3(2)): y(x) or x(y) with the + or - root; checked")
    via: Point | None = Field(None, description="a point of the segment choosing the arc of an ellipse, mm "
                                                "(default: the shorter arc)")


class SplineSection(StrictModel):
    """A periodic uniform cubic B-spline claw path through key points with tangents (the redesign)."""

    control_points: int = Field(24, ge=8, le=200, description="control points of the closed curve")
    keys: list[str] = Field(min_length=3, description="key points in time order, first = the guide takes the claw "
                                                      "over, last = it lets go (the rest of the loop is uncontrolled)")
    tangents: dict[str, float] = Field(default_factory=dict,
                                       description="direction of motion at a key point, deg from +x, counter-clockwise")
    fold: str = Field(description="the key point where the claw folds onto the arm: moved along OM onto "
                                  "|OM| = R - d, tangent perpendicular to OM, and the inverse kinematics "
                                  "changes branch there (minus before it in the paper's eq 7 ... see GUIDE_WAY.md)")
    min_speed: float = Field(0.2, gt=0, description="|dM/du| at a key tangent, at least this x the loop length (dimensionless)")
    move: float = Field(40.0, gt=0, description="IPOPT stage, when `control` is not given (refused with it): each "
                                                "control point stays within this of the convex fit, mm")
    control: list[tuple[Variable, Variable]] | None = Field(
        None, description="the control points (x, y) round the loop, mm, one pair per control point (default: the "
                          "convex fit, each coordinate free within `move` of it); a number fixes a coordinate, "
                          "{init, bounds} frees it (init: what `check` evaluates and start 0 of `solve`)")

    @model_validator(mode="after")
    def _control(self) -> "SplineSection":
        if self.control is None:
            return self
        if "move" in self.model_fields_set:
            raise ValueError(f"move: {self.move:g} is not read when `control` is given (each free coordinate has its "
                             "own bounds there); leave it out")
        if len(self.control) != self.control_points:
            raise ValueError(f"control: expected {self.control_points} control points (control_points), got "
                             f"{len(self.control)}")
        for j, point in enumerate(self.control):
            for axis, v in zip("xy", point):
                numbers = (v.init, *v.bounds) if isinstance(v, FreeVariable) else (v,)
                if not all(math.isfinite(n) for n in numbers):
                    raise ValueError(f"control[{j}].{axis}: expected finite numbers, got {_shown(v)}")
        return self


def _shown(v) -> str:
    if isinstance(v, FreeVariable):
        return f"{{init = {v.init}, bounds = [{v.bounds[0]}, {v.bounds[1]}]}}"
    return str(v)


class RulesSection(StrictModel):
    """Limits of the design rules and the tolerances of the joints and the fold."""

    roller_margin: float = Field(0.0, ge=0, description="smallest centre-line radius of curvature = roller radius + "
                                                        "this, mm (0: just no undercut)")
    max_pressure_angle: float = Field(45.0, gt=0, lt=90, description="max pressure angle, deg")
    fold_window: float = Field(0.0, ge=0, lt=90, description="the pressure-angle rule is not held within this many "
                                                             "deg of arm angle either side of the fold, where it "
                                                             "is 90 deg by geometry (the dead point, GUIDE_WAY.md)")
    joint_position: float = Field(0.01, gt=0, description="largest roller-centre position jump at a joint, mm")
    joint_tangent: float = Field(0.01, gt=0, description="largest tangent-direction jump at a joint, deg")
    joint_curvature: float = Field(1e-4, gt=0, description="largest curvature jump at a joint, 1/mm")
    fold_distance: float = Field(0.01, gt=0, description="| |OD| - (R - d) | at the fold point, at most, mm")
    fold_angle: float = Field(0.01, gt=0, description="| angle(OD, tangent) - 90 | at the fold point, at most, deg")
    key_point: float = Field(0.01, gt=0, description="spline path: largest distance from a key point to the path "
                                                     "at the key's parameter, mm")
    key_tangent: float = Field(0.01, gt=0, description="spline path: largest angle between the path's direction at a "
                                                       "key point and its given tangent, deg")
    joint_gap: float = Field(0.05, gt=0, description="bad input: a key point farther than this from its conic, mm")


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the paths that satisfy every rule."""

    name: Literal["smoothness"] = Field("smoothness", description="smoothness: the claw path's squared third "
                                                                   "derivative, relative to the convex fit's")


class SolverSection(MultistartSettings):
    samples_per_segment: int = Field(60, ge=5, le=5000, description="samples per conic segment or per key-to-key "
                                                                    "stretch of the spline (check: 10x)")
    starts: Starts = Field(2, ge=1, le=10000, description='multistart starts (start 0 = the convex fit), or "auto": '
                                                        'batches until the confidence rule holds (`--starts auto`)')


class GuideWayPointMass(StrictModel):
    """A mass carried by the arm or the claw body (a seedling, the roller, a counterweight), its own inertia
    neglected."""

    link: Literal["arm", "claw"] = Field(description="the body that carries it: the arm OP or the claw body (claw "
                                                     "PM and crank arm PN)")
    mass: float = Field(gt=0.0, le=1000.0, description="mass, kg")
    at: tuple[float, float] | Literal["tip", "roller"] = Field(
        description="position in the body's frame, mm (arm: origin O, x towards P; claw: origin P, x towards M); "
                    "or \"tip\" (the claw tip M) or \"roller\" (the roller centre N) on the claw")
    note: str = Field("", description="what it is and where its value comes from")

    @model_validator(mode="after")
    def _named_point_on_claw(self) -> "GuideWayPointMass":
        if isinstance(self.at, str) and self.link != "claw":
            raise ValueError(f"at: {self.at!r} is a point of the claw body; on the arm give [x, y] in mm")
        if not isinstance(self.at, str) and not all(math.isfinite(v) for v in self.at):
            raise ValueError(f"at: expected finite coordinates, got {list(self.at)}")
        return self


class GuideWayDynamics(StrictModel):
    """Mass properties for the inverse dynamics at constant arm speed over the controlled path (GUIDE_WAY.md
    "Dynamics")."""

    arm: BarLink | LumpedLink = Field(description="the arm OP: a bar {density, area} along OP or {mass, com, "
                                                  "inertia} (frame: origin O, x towards P)")
    claw: BarLink | LumpedLink = Field(description="the claw body: bars PM and PN of one section {density, area} or "
                                                   "{mass, com, inertia} (frame: origin P, x towards M)")
    point_masses: list[GuideWayPointMass] = Field(default_factory=list, description="masses carried by the bodies")
    gravity: tuple[float, float] = Field((0.0, -9.81), description="gravity in the machine frame, m/s^2 (0 allowed)")
    arm_speed: float = Field(gt=0.0, le=5000.0, description="constant arm speed, r/min (theta growing)")
    samples: int = Field(360, ge=8, le=3600, description="samples of the controlled path in result.json's "
                                                         "facts.dynamics, spread evenly over its stretches")
    limits: DynamicsLimits = Field(default_factory=DynamicsLimits,
                                   description="rules on the dynamics over the controlled path (check, re-check "
                                               "and, on a spline path, the NLP)")
    assumption: str = Field("", description="which values are ours, not a paper's")

    @model_validator(mode="after")
    def _finite(self) -> "GuideWayDynamics":
        if not all(math.isfinite(v) for v in self.gravity):
            raise ValueError(f"gravity: expected finite numbers, got {list(self.gravity)}")
        return self

    def has_rules(self) -> bool:
        return self.limits.any_given()


class GuideWaySpec(ProblemSpec):
    kind: Literal["guide_way"] = Field(description="the problem kind (guide_way)")
    arm: ArmSection
    points: dict[str, Point] = Field(description="key points of the claw-tip path, mm")
    fold: str | None = Field(None, description="conic path: the key point where the claw folds onto the arm (D)")
    conic: list[ConicSegment] | None = Field(None, description="the paper's conic segments, in time order")
    spline: SplineSection | None = None
    rules: RulesSection = Field(default_factory=RulesSection)
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    dynamics: GuideWayDynamics | None = Field(None, description="mass properties, gravity and arm speed for the "
                                                                "inverse dynamics (optional; none: no dynamics)")

    @classmethod
    def old_forms(cls, data: dict) -> str:
        """Earlier spellings of a conic's branch ("minus" / "plus"), each with its new one (see spec.common.validate)."""
        conics = data.get("conic")
        if not isinstance(conics, list):
            return ""
        return "\n".join(f"conic.{k}.branch: \"{seg['branch']}\" is no longer read; write branch = "
                         f"{OLD_BRANCHES[seg['branch']]} (theta = gamma {'+' if OLD_BRANCHES[seg['branch']] > 0 else '-'} phi)"
                         for k, seg in enumerate(conics)
                         if isinstance(seg, dict) and isinstance(seg.get("branch"), str) and seg["branch"] in OLD_BRANCHES)

    @model_validator(mode="after")
    def _path(self) -> "GuideWaySpec":
        if (self.conic is None) == (self.spline is None):
            raise ValueError("give the claw path either as [[conic]] segments or as a [spline], exactly one")
        names = set(self.points)
        if self.conic is not None:
            if not self.conic:
                raise ValueError("conic: expected at least one segment")
            for k, seg in enumerate(self.conic):
                for end in (seg.start, seg.end):
                    if end not in names:
                        raise ValueError(f"conic[{k}] ({seg.name}): point {end!r} is not in [points] "
                                         f"({', '.join(sorted(names))})")
                if k and seg.start != self.conic[k - 1].end:
                    raise ValueError(f"conic[{k}] ({seg.name}) starts at {seg.start!r} but the segment before "
                                     f"ends at {self.conic[k - 1].end!r}: list the segments in time order")
            if self.fold is not None and self.fold not in [s.end for s in self.conic[:-1]]:
                raise ValueError(f"fold: {self.fold!r} is not a joint between two segments")
        else:
            sp = self.spline
            assert sp is not None       # the first check above: exactly one of conic and spline
            named = [(f"keys[{i}]", k) for i, k in enumerate(sp.keys)] + [(f"tangents.{k}", k) for k in sp.tangents]
            for field, key in named + [("fold", sp.fold)]:
                if key not in names:
                    raise ValueError(f"spline.{field}: point {key!r} is not in [points] ({', '.join(sorted(names))})")
            if len(set(sp.keys)) != len(sp.keys):
                raise ValueError("spline.keys: a key point is listed twice")
            if sp.fold not in sp.keys[1:-1]:
                raise ValueError(f"spline.fold: {sp.fold!r} must be a key point strictly inside the controlled stretch")
        for name, (x, y) in self.points.items():
            if not (math.isfinite(x) and math.isfinite(y)):
                raise ValueError(f"points.{name}: expected finite coordinates, got [{x}, {y}]")
        return self

    def variables(self) -> dict[str, Variable]:
        """Every design variable by its result.json name: the arm geometry (fixed) and, when the spec gives them,
        the spline's control points, x coordinates first (``P<j>_x``, then ``P<j>_y``: the NLP's order)."""
        a = self.arm
        out: dict[str, Variable] = {"R": a.radius, "d": a.claw, "r": a.crank, "beta": a.beta,
                                    "roller_radius": a.roller_radius}
        control = self.spline.control if self.spline is not None else None
        if control is not None:
            for k, axis in enumerate("xy"):
                out.update({f"P{j}_{axis}": point[k] for j, point in enumerate(control)})
        return out

    def design_values(self) -> dict[str, float]:
        """The published (or given) path's numbers: the arm geometry and the given control points (the conics,
        and the convex fit a spline spec without control points starts from, are in ``facts``)."""
        return {n: value_of(v) for n, v in self.variables().items()}

"""Spec model of kind ``fourbar_path``: a four-bar whose coupler point passes through target points.

The table and variable names are fixed by the problem statement (issue 5), since other tools write
specs in this form::

    [targets]  points = [[x, y], ...]  (mm, 3 to 100)   crank_deg = [...]  (optional: timing)
    [bounds]   r1 r2 r3 r4 rcx rcy x0 y0 theta0: [lo, hi] frees a variable, a number fixes it
    [rules]    grashof = "crank-rocker" | "double-crank" | "any";  transmission_angle = [lo, hi];
               order = true | false
    [solver]   starts = 64, seed = 0

Our additions, all optional: ``branch`` ("open" | "crossed"), ``[rules] direction`` (which way the
crank turns through the targets when the timing is free), ``[design]`` (the design ``check``
evaluates and the first multistart start; a free variable without a value there starts from the
midpoint of its bounds), ``[solver] stop_at_objective`` (end the multistart early), and
``crank_speed`` (r/min, only sets the time scale of the reported trajectory).

Angles: theta0 and crank_deg in degrees; crank_deg is the crank angle measured from the frame line
O -> O', counter-clockwise (see synthesis.kinematics.coupler_point).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, ValidationInfo, field_validator

from synthesis.kinematics.coupler_point import VARIABLES
from synthesis.spec.common import MultistartSettings, ProblemSpec, StrictModel, max_iter_field, starts_field
from synthesis.spec.docmeta import TomlType

KIND = "fourbar_path"
LENGTHS = ("r1", "r2", "r3", "r4")
MAX_POINTS = 100
#: largest |coordinate|, |bound|, |design value| (mm or deg): beyond it the squared errors and closure
#: polynomials overflow a float (1e300^2), and no machine of the field is a kilometre long
MAX_MAGNITUDE = 1e6


def _number(v: Any, what: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{what}: expected a number, got {v!r}")
    if not math.isfinite(v):
        raise ValueError(f"{what}: expected a finite number, got {v}")
    if abs(v) > MAX_MAGNITUDE:
        raise ValueError(f"{what}: expected a magnitude of at most {MAX_MAGNITUDE:g} (mm or deg), got {v:g}")
    return float(v)


def _bound(v: Any) -> tuple[float, float]:
    """A number fixes the variable (lo = hi); [lo, hi] frees it within those bounds."""
    if isinstance(v, (list, tuple)):
        if len(v) != 2:
            raise ValueError(f"expected a number (fixes it) or [lo, hi] (frees it), got a list of {len(v)}")
        lo, hi = _number(v[0], "lo"), _number(v[1], "hi")
        if lo > hi:
            raise ValueError(f"[{lo:g}, {hi:g}] has lo > hi; write it as [{hi:g}, {lo:g}]")
        return lo, hi
    if isinstance(v, dict):
        raise ValueError(f"expected a number (fixes it) or [lo, hi] (frees it), got a table {v!r}")
    x = _number(v, "value")
    return x, x


def _point(v: Any) -> tuple[float, float]:
    if not isinstance(v, (list, tuple)) or len(v) != 2:
        raise ValueError(f"expected a point [x, y] in mm, got {v!r}")
    return _number(v[0], "x"), _number(v[1], "y")


def _angle(v: Any) -> float:
    return _number(v, "angle")


Bound = Annotated[tuple[float, float], BeforeValidator(_bound), TomlType("number (fixes it) or [lo, hi] (frees it)")]
Point = Annotated[tuple[float, float], BeforeValidator(_point)]
Angle = Annotated[float, BeforeValidator(_angle)]
Finite = Annotated[float, BeforeValidator(lambda v: _number(v, "value"))]


class TargetsSection(StrictModel):
    """The points the coupler point must pass through, and optionally when (the crank angles)."""

    points: list[Point] = Field(description="target points [[x, y], ...], mm; 3 to 100")
    crank_deg: list[Angle] | None = Field(
        None, description="prescribed crank angle of each point (deg, from the frame line O -> O', "
                          "counter-clockwise); omit to leave the timing free")

    @field_validator("points", mode="after")
    @classmethod
    def _count(cls, points: list) -> list:
        if not 3 <= len(points) <= MAX_POINTS:
            raise ValueError(f"expected 3 to {MAX_POINTS} points, got {len(points)}")
        return points

    @field_validator("crank_deg", mode="after")
    @classmethod
    def _one_per_point(cls, angles: list | None, info: ValidationInfo) -> list | None:
        points = info.data.get("points")
        if angles is not None and points is not None and len(angles) != len(points):
            raise ValueError(f"expected one angle per point ({len(points)}), got {len(angles)}")
        return angles


class BoundsSection(StrictModel):
    """[lo, hi] frees a design variable within those bounds, a number fixes it. mm and deg."""

    r1: Bound = Field(description="frame O -> O', mm")
    r2: Bound = Field(description="input crank O -> A, mm")
    r3: Bound = Field(description="coupler A -> B, mm")
    r4: Bound = Field(description="output link O' -> B, mm")
    rcx: Bound = Field(description="coupler point along A -> B, mm")
    rcy: Bound = Field(description="coupler point normal to A -> B (90 deg counter-clockwise), mm")
    x0: Bound = Field(description="input pivot O, x, mm")
    y0: Bound = Field(description="input pivot O, y, mm")
    theta0: Bound = Field((0.0, 360.0), description="frame angle, direction of O -> O' from +x, deg")

    @field_validator(*LENGTHS, mode="after")
    @classmethod
    def _positive_length(cls, v: tuple[float, float]) -> tuple[float, float]:
        if v[0] <= 0:
            raise ValueError(f"a link length must be > 0, got {'lower bound ' if v[0] < v[1] else ''}{v[0]:g}")
        return v


class DesignSection(StrictModel):
    """A given design: what ``check`` evaluates and the first start of ``solve`` (result.json names)."""

    r1: Finite | None = Field(None, description="frame O -> O', mm (default: the midpoint of bounds.r1)")
    r2: Finite | None = Field(None, description="input crank O -> A, mm (default: the midpoint of its bounds)")
    r3: Finite | None = Field(None, description="coupler A -> B, mm (default: the midpoint of its bounds)")
    r4: Finite | None = Field(None, description="output link O' -> B, mm (default: the midpoint of its bounds)")
    rcx: Finite | None = Field(None, description="coupler point along A -> B, mm (default: the midpoint of its bounds)")
    rcy: Finite | None = Field(None, description="coupler point normal to A -> B, mm (default: the midpoint of its "
                                                 "bounds)")
    x0: Finite | None = Field(None, description="input pivot O, x, mm (default: the midpoint of its bounds)")
    y0: Finite | None = Field(None, description="input pivot O, y, mm (default: the midpoint of its bounds)")
    theta0: Finite | None = Field(None, description="frame angle, deg (default: the midpoint of its bounds)")
    crank_deg: list[Angle] | None = Field(None, description="crank angle of each target, deg (free timing only)")


class RulesSection(StrictModel):
    """The design rules besides passing through the targets: Grashof class, transmission angle, order."""

    grashof: Literal["crank-rocker", "double-crank", "any"] = Field(
        "crank-rocker", description="crank-rocker: r2 shortest and s + l <= p + q (the crank turns fully); "
                                    "double-crank: r1 shortest and s + l <= p + q; any: no Grashof rule, "
                                    "the loop must close at every target and between them")
    transmission_angle: tuple[Finite, Finite] | None = Field(
        None, description="[lo, hi] deg: the transmission angle over the crank's motion")
    order: bool = Field(True, description="free timing: the crank meets the targets in the given order "
                                          "within one turn (the `sequence` rule)")
    direction: Literal["either", "ccw", "cw"] = Field(
        "either", description="free timing: the crank turns counter-clockwise, clockwise, or either way "
                              "(chosen per start) through the targets")

    @field_validator("transmission_angle", mode="after")
    @classmethod
    def _angle_range(cls, v):
        if v is not None:
            lo, hi = v
            if not 0.0 <= lo <= hi <= 180.0:
                raise ValueError(f"expected 0 <= lo <= hi <= 180 deg, got [{lo:g}, {hi:g}]")
        return v


class SolverSection(MultistartSettings):
    starts: int = starts_field(64)
    stop_at_objective: float | None = Field(
        None, ge=0, description="end the multistart at the first start (in start order) whose objective "
                                "is at most this many mm^2 and that satisfies every rule; reported as "
                                "starts needed")
    max_iter: int = max_iter_field(1000)
    mu_strategy: Literal["monotone", "adaptive"] = Field(
        "monotone", description="IPOPT's barrier update: monotone (default: more starts reach the optimum "
                                "when the targets go round the whole coupler curve) or adaptive (with "
                                "max_iter = 3000, recovers targets on a 120 deg arc that monotone misses)")
    samples: int = Field(36, ge=4, le=3600, description="samples of the crank motion for sampled rules "
                                                         "(grashof = \"any\"); the re-check is 10x finer")


class FourbarPathSpec(ProblemSpec):
    kind: Literal["fourbar_path"] = Field(description="the problem kind (fourbar_path)")
    branch: Literal["open", "crossed"] = Field("open", description="assembly branch (kinematics.coupler_point)")
    crank_speed: float = Field(60.0, gt=0, le=10000, description="r/min; only the time scale of the trajectory")
    targets: TargetsSection
    bounds: BoundsSection
    design: DesignSection = Field(default_factory=DesignSection)
    rules: RulesSection = Field(default_factory=RulesSection)
    solver: SolverSection = Field(default_factory=SolverSection)

    @field_validator("design", mode="after")
    @classmethod
    def _design_fits(cls, design: DesignSection, info: ValidationInfo) -> DesignSection:
        bounds, targets = info.data.get("bounds"), info.data.get("targets")
        if bounds is not None:
            for name in VARIABLES:
                v = getattr(design, name)
                lo, hi = getattr(bounds, name)
                if v is not None and not lo <= v <= hi:
                    raise ValueError(f"{name} = {v:g} lies outside bounds.{name} [{lo:g}, {hi:g}]")
        if design.crank_deg is not None and targets is not None:
            if targets.crank_deg is not None:
                raise ValueError("crank_deg: the timing is already prescribed by targets.crank_deg; remove one")
            if len(design.crank_deg) != len(targets.points):
                raise ValueError(f"crank_deg: expected one angle per target ({len(targets.points)}), "
                                 f"got {len(design.crank_deg)}")
        return design

    @property
    def timed(self) -> bool:
        """True when targets.crank_deg prescribes the crank angle of every point."""
        return self.targets.crank_deg is not None

    def bounds_array(self) -> list[tuple[float, float]]:
        return [getattr(self.bounds, n) for n in VARIABLES]

    def design_values(self) -> dict[str, float]:
        """The given design: [design] value, else the fixed number, else the midpoint of [lo, hi]."""
        out = {}
        for name in VARIABLES:
            v = getattr(self.design, name)
            lo, hi = getattr(self.bounds, name)
            out[name] = v if v is not None else 0.5 * (lo + hi)
        return out

    def midpoint_variables(self) -> list[str]:
        """Free variables whose given value is the midpoint convention (no [design] value)."""
        return [n for n in VARIABLES
                if getattr(self.design, n) is None and getattr(self.bounds, n)[0] < getattr(self.bounds, n)[1]]

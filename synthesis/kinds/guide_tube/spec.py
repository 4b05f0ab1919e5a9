"""Spec model of kind ``guide_tube``: wall angles of the guide tubes of seed 001 §2.4.

Units: lengths mm, angles deg, times s, speeds m/s (docs/ARCHITECTURE.md, "Units"); converted to SI in the scene.

Each ``[[tubes]]`` entry is one tube, or a symmetric pair sharing geometry and wall angle
(seed 001: tubes I and IV, II and III, delta1 = delta4, delta2 = delta3): name the twin in ``mirror``.
``l3`` is the horizontal distance from the drop point to the tube centre at ``rows.design_spacing``;
at another row spacing w it scales with the tube's shift, l3 (tray_pitch - w) / (tray_pitch - design_spacing)
(the tubes slide sideways to change the row spacing, seed 001 Fig. 2; at w = tray_pitch no tube moves).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, PrivateAttr, model_validator

from synthesis.spec.operating import OperatingRange, resolve_ranges
from synthesis.spec.common import (Starts,
    ACUTE, Interval, MultistartSettings, ProblemSpec, StrictModel, Variable, bounds_of, is_free,
    max_iter_field, starts_field, value_of,
)

KIND = "guide_tube"
_NAME = r"^[A-Za-z0-9]+$"


class DropSection(StrictModel):
    """Where the pot seedling is dropped and how air slows it (seed 001 §2.4)."""

    height: float = Field(600.0, gt=0, le=10000, description="drop point N1 above the paddy, mm (seed 001 §2.1.1: 600)")
    gravity: float = Field(9.8, gt=0, le=100, description="gravitational acceleration, m/s^2 (seed 001: 9.8)")
    terminal_speed: float = Field(17.5, gt=0, description="float (terminal) speed v_L of a pot seedling in air, "
                                                          "m/s (seed 001: 17.5); no air drag: a large value such as 1e6 "
                                                          "(inf is refused: results hold finite numbers only)")


class CalibrationSection(StrictModel):
    """Find mu from a measured landing time of one tube at its (fixed) wall angle."""

    tube: str = Field(description="name of the tube whose landing time was measured")
    landing_time: float = Field(gt=0, le=60, description="measured drop time t_z, s (seed 001: tube I, 0.445)")
    mu_range: Interval = Field((0.0, 1.5), description="friction coefficients searched, [lo, hi], dimensionless")

    @model_validator(mode="after")
    def _range(self) -> "CalibrationSection":
        lo, hi = self.mu_range
        if not 0 <= lo < hi:
            raise ValueError(f"mu_range: expected 0 <= lo < hi, got [{lo:g}, {hi:g}]")
        return self


class FrictionSection(StrictModel):
    """Coulomb friction between pot seedling and wall: give mu, or calibrate it (not printed in seed 001).
    mu may be given as a range ``{range = [lo, hi], samples = N}``: solve then holds every rule at each
    sampled mu (an operating envelope, one shared design) and re-checks the answer on a finer grid of it."""

    mu: Annotated[float, Field(ge=0, le=10)] | OperatingRange | None = Field(
        None, description="friction coefficient, dimensionless; or a range {range = [lo, hi], samples = 4, "
                          "nominal = (lo+hi)/2, step = re-check spacing}")
    calibrate: CalibrationSection | None = None
    _operating_ranges: dict = PrivateAttr(default_factory=dict)

    @model_validator(mode="after")
    def _one_of(self) -> "FrictionSection":
        if (self.mu is None) == (self.calibrate is None):
            raise ValueError("give exactly one of friction.mu or friction.calibrate")
        resolve_ranges(self, {"mu": ">= 0, <= 10"})
        return self


class RowsSection(StrictModel):
    """Row spacings the tubes serve, and the forward speed turning time into position."""

    tray_pitch: float = Field(300.0, gt=0, description="pitch of the seedlings picked from the tray, mm (seed 001: 300)")
    design_spacing: float = Field(230.0, gt=0, description="row spacing at which the tubes' l3 are given and the "
                                                           "landing times are equalised, mm (seed 001: 230)")
    spacings: Interval = Field((230.0, 300.0), description="row spacings the design is evaluated over, mm "
                                                         "(seed 001: 230-300)")
    forward_speed: float = Field(gt=0, le=5, description="machine forward speed, m/s, turning landing-time "
                                                        "differences into plant-position errors (not printed in seed 001)")

    @model_validator(mode="after")
    def _ordered(self) -> "RowsSection":
        lo, hi = self.spacings
        if not self.design_spacing < self.tray_pitch:
            raise ValueError(f"design_spacing: expected < tray_pitch = {self.tray_pitch:g}, got {self.design_spacing:g}")
        if not 0 < lo <= hi <= self.tray_pitch:
            raise ValueError(f"spacings: expected 0 < lo <= hi <= tray_pitch = {self.tray_pitch:g}, "
                             f"got [{lo:g}, {hi:g}]")
        return self

    def l3_scale(self, spacing: float) -> float:
        """l3 at ``spacing`` / l3 at the design spacing."""
        return (self.tray_pitch - spacing) / (self.tray_pitch - self.design_spacing)


class TubeSection(StrictModel):
    """One guide tube (or a symmetric pair, see mirror): geometry and wall angle."""

    name: str = Field(pattern=_NAME, description="tube name, e.g. I")
    mirror: str | None = Field(None, pattern=_NAME, description="its symmetric twin sharing geometry and angle, e.g. IV")
    l3: float = Field(gt=0, description="drop point - tube centre horizontal distance at rows.design_spacing, mm")
    h5: float = Field(ge=0, description="straight section length, mm")
    h6: float = Field(ge=0, description="tube outlet above the paddy, mm")
    angle: Variable = Field(json_schema_extra=ACUTE, description="wall inclination delta to the horizontal, deg; a number fixes it, "
                                        "{init, bounds} frees it for solve")
    wall_gap: float | None = Field(None, gt=0, description="horizontal distance from the wall end to the vertical "
                                                          "wall, mm (ODE only; does not change the drop time)")

    @model_validator(mode="after")
    def _angle_range(self) -> "TubeSection":
        lo, hi = bounds_of(self.angle)
        if not 0 < lo <= hi < 90:
            what = "bounds" if is_free(self.angle) else "value"
            got = f"[{lo:g}, {hi:g}]" if is_free(self.angle) else f"{lo:g}"
            raise ValueError(f"angle: expected 0 < angle < 90 deg, got {what} {got}")
        return self


class RulesSection(StrictModel):
    """Limits of the design rules."""

    max_time_spread: float = Field(0.001, gt=0, description="largest landing-time difference between tubes at "
                                                          "the design row spacing, s")
    max_spacing_error: float | None = Field(None, gt=0, description="largest plant-position error (forward speed x "
                                                                   "landing-time spread) over rows.spacings, mm; "
                                                                   "unset: reported, not a rule")
    min_exit_speed: float = Field(0.05, ge=0, description="smallest speed at the wall end (no sticking), m/s")
    min_free_fall: float = Field(0.0, ge=0, description="smallest free fall h1 before the wall, mm")


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the wall angles that satisfy every rule."""

    name: Literal["nearest", "fastest", "uniform"] = Field(
        "nearest", description="nearest: smallest change of the free angles (default); fastest: shortest common "
                               "landing time; uniform: smallest worst plant-position error over rows.spacings "
                               "(landing times at the design row spacing within rules.max_time_spread instead of equal)")


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(4)
    samples: int = Field(8, ge=2, le=200, description="row spacings sampled over rows.spacings in the NLP "
                                                      "(the check uses 10x as many)")
    max_iter: int = max_iter_field(200)
    backoff: float = Field(0.02, ge=0, le=1, description="inequality limits tightened by backoff x the rule's "
                                                         "scale, so rules hold between the sampled row spacings "
                                                         "(dimensionless)")


class GuideTubeSpec(ProblemSpec):
    kind: Literal["guide_tube"] = Field(description="the problem kind (guide_tube)")
    drop: DropSection = Field(default_factory=DropSection)
    friction: FrictionSection
    rows: RowsSection
    tubes: list[TubeSection] = Field(min_length=1)
    rules: RulesSection = Field(default_factory=RulesSection)
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)

    @model_validator(mode="after")
    def _consistent(self) -> "GuideTubeSpec":
        names = [t.name for t in self.tubes] + [t.mirror for t in self.tubes if t.mirror]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ValueError(f"tubes: names must be unique, {', '.join(twice)} given twice")
        cal = self.friction.calibrate
        if cal is not None:
            index = next((i for i, t in enumerate(self.tubes) if cal.tube in (t.name, t.mirror)), None)
            if index is None:
                raise ValueError(f"friction.calibrate.tube: no tube named {cal.tube!r} "
                                 f"(tubes: {', '.join(t.name for t in self.tubes)})")
            if is_free(self.tubes[index].angle):
                raise ValueError(f"friction.calibrate.tube: tube {cal.tube}'s angle must be a fixed number (the "
                                 f"angle at which the landing time was measured), got {{init, bounds}}")
        widest = self.rows.l3_scale(min(self.rows.design_spacing, self.rows.spacings[0]))
        for i, t in enumerate(self.tubes):
            room = self.drop.height - t.h5 - t.h6         # height of the drop point above the wall's lower end
            if room <= 0:
                raise ValueError(f"tubes.{i}.h5, h6: h5 + h6 = {t.h5 + t.h6:g} mm reaches the drop point "
                                 f"(drop.height = {self.drop.height:g} mm)")
            steepest = math.degrees(math.atan(room / (t.l3 * widest)))
            hi = bounds_of(t.angle)[1]
            if hi >= steepest:
                what = "upper bound" if is_free(t.angle) else "value"
                raise ValueError(f"tubes.{i}.angle: {what} {hi:g} deg puts the wall top (l3 tan delta = "
                                 f"{t.l3 * widest * math.tan(math.radians(hi)):.0f} mm above its lower end, at "
                                 f"row spacing {min(self.rows.design_spacing, self.rows.spacings[0]):g} mm) above "
                                 f"the drop point ({room:g} mm above it); keep it below {steepest:.2f} deg")
        return self

    def variables(self) -> dict[str, Variable]:
        """Every design variable (spec units) by its result.json name: the wall angle of each tube."""
        return {f"delta_{t.name}": t.angle for t in self.tubes}

    def design_values(self) -> dict[str, float]:
        """Every design variable's given value (deg) by its result.json name (the studio's sliders read them)."""
        return {name: value_of(v) for name, v in self.variables().items()}

    def given_angles(self) -> dict[str, float]:
        """tube name -> the wall angle `check` evaluates (deg)."""
        return {t.name: value_of(t.angle) for t in self.tubes}

"""Spec model of kind ``steering_linkage``: the Ackermann steering trapezoid of seed 002 (Hwang, Model-3
small peanut combine, Table 12).

Vehicle (mm): wheelbase L, track, kingpin spacing w.  Trapezoid: steering-arm length r (mm) and base
angle gamma (deg, between the arm and the axle line); the tie rod follows (l = w - 2 r cos gamma).
``check`` evaluates the given trapezoid; ``solve`` frees arm length and base angle written as
``{init, bounds}`` and minimises the largest steering error over 0 .. the maximum inside lock.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.common import (Starts,
    ACUTE, POSITIVE, FreeVariable, MultistartSettings, ProblemSpec, StrictModel, Variable, max_iter_field,
    require_positive_fields, starts_field, value_of,
)

KIND = "steering_linkage"


class Vehicle(StrictModel):
    """The machine: Model-3 has L = 1400 mm and a 1100 mm track (seed 002 §四.1)."""

    wheelbase: float = Field(gt=0.0, description="wheelbase L, mm")
    track: float = Field(gt=0.0, description="track (wheel contact centres), mm")
    kingpin_spacing: float = Field(gt=0.0, description="kingpin spacing w, mm (the w of the Ackermann "
                                                       "condition cot(alpha) - cot(beta) = w / L)")

    @model_validator(mode="after")
    def _spacing_within_track(self) -> "Vehicle":
        if self.kingpin_spacing > self.track:
            raise ValueError(f"kingpin_spacing: expected <= track = {self.track:g} mm, got {self.kingpin_spacing:g}")
        return self


class Trapezoid(StrictModel):
    """The steering arms; a number fixes a value, ``{init, bounds}`` frees it."""

    arm_length: Variable = Field(json_schema_extra=POSITIVE, description="steering-arm length r (kingpin to tie-rod joint), mm")
    base_angle: Variable = Field(json_schema_extra=ACUTE, description="base angle gamma between arm and axle line, deg, 0 < gamma < 90 (arms "
                                             "point rearward and inward; towards 90 the arms grow parallel and the "
                                             "Ackermann effect vanishes)")

    @model_validator(mode="after")
    def _ranges(self) -> "Trapezoid":
        require_positive_fields(self)
        for lo, hi in (_range(self.base_angle),):
            if not (0.0 < lo and hi < 90.0):
                raise ValueError(f"base_angle: expected 0 < base_angle < 90 deg, got {_text(self.base_angle)}")
        return self


def _range(v: Variable) -> tuple[float, float]:
    return v.bounds if isinstance(v, FreeVariable) else (float(v), float(v))


def _text(v: Variable) -> str:
    return f"bounds [{v.bounds[0]:g}, {v.bounds[1]:g}]" if isinstance(v, FreeVariable) else f"{float(v):g}"


class Requirements(StrictModel):
    """What the trapezoid must do: reach the lock, keep the transmission angle, arm length range."""

    max_inside_lock: float = Field(gt=0.0, lt=60.0, description="largest inside lock beta the linkage must reach, "
                                                               "deg (Model-3: 27; Table 12 runs to 40)")
    min_transmission_angle: float = Field(gt=0.0, lt=90.0, description="smallest angle between tie rod and either "
                                                                      "steering arm over 0 .. max_inside_lock, deg")
    arm_length: tuple[float, float] = Field(description="[lo, hi] allowed steering-arm length, mm")

    @model_validator(mode="after")
    def _ordered(self) -> "Requirements":
        lo, hi = self.arm_length
        if not 0.0 < lo <= hi:
            raise ValueError(f"arm_length: expected 0 < lo <= hi, got [{lo:g}, {hi:g}]")
        return self


class MaxLockRow(StrictModel):
    """The printed row at the maximum lock."""

    inside: float = Field(gt=0.0, lt=90.0, description="inside lock, deg")
    accurate: float = Field(gt=0.0, lt=90.0, description="'accurate' (Ackermann) outside lock, deg")
    actual: float = Field(gt=0.0, lt=90.0, description="actual outside lock, deg")


class Published(StrictModel):
    """Seed 002 Table 12 and the text beside it, as printed (deg; radius mm)."""

    inside_lock: list[float] = Field(min_length=1, description="inside lock beta, deg")
    accurate_outside: list[float] = Field(description="'accurate' outside lock alpha, deg")
    actual_outside: list[float] = Field(description="actual outside lock alpha0, deg")
    error: list[float] = Field(description="printed error alpha - alpha0, deg")
    max_lock: MaxLockRow
    min_turning_radius: float = Field(gt=0.0, description="printed minimum turning radius, mm (3.1 m)")
    resolution: float = Field(0.05, gt=0.0, description="half the last printed digit of an angle, deg")

    @model_validator(mode="after")
    def _same_length(self) -> "Published":
        n = len(self.inside_lock)
        for name in ("accurate_outside", "actual_outside", "error"):
            if len(getattr(self, name)) != n:
                raise ValueError(f"{name}: expected {n} values (one per inside_lock), got {len(getattr(self, name))}")
        for name in ("inside_lock", "accurate_outside", "actual_outside"):      # a lock is an angle in (0, 90) deg
            for i, v in enumerate(getattr(self, name)):
                if not 0.0 < v < 90.0:
                    raise ValueError(f"{name}[{i}] = {v:g}: a lock must lie in (0, 90) deg")
        # one row per lock: the table's concavity reads each row against the chord of its neighbours (a lock given
        # twice divided by zero)
        seen: dict[float, int] = {}
        for i, v in enumerate(self.inside_lock):
            if v in seen:
                raise ValueError(f"inside_lock[{i}] = {v:g}: the same lock as inside_lock[{seen[v]}]; give each "
                                 f"printed row once")
            seen[v] = i
        for i, v in enumerate([*self.accurate_outside, self.max_lock.accurate]):   # Table 12 explained: alpha +- resolution
            if not 0.0 < v - self.resolution and v + self.resolution < 90.0:
                raise ValueError(f"resolution = {self.resolution:g}: the 'accurate' lock {v:g} deg +- resolution "
                                 f"must stay in (0, 90) deg")
        return self


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the trapezoids that satisfy every requirement."""

    name: Literal["min_max_error"] = Field(
        "min_max_error", description="min_max_error: smallest largest |alpha - alpha_Ackermann| over 0 .. "
                                     "max_inside_lock (a smooth epigraph over the sampled locks)")


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(8)
    samples: int = Field(40, ge=4, le=2000, description="inside locks sampled over 0 .. max_inside_lock (the "
                                                        "re-check uses 10x as many)")
    backoff: float = Field(0.01, ge=0.0, le=1.0, description="the NLP tightens the sampled transmission-angle "
                                                            "limits by backoff x 10 deg, so they hold between samples (dimensionless)")
    max_iter: int = max_iter_field(500)


class SteeringSpec(ProblemSpec):
    kind: Literal["steering_linkage"] = Field(description="the problem kind (steering_linkage)")
    vehicle: Vehicle
    trapezoid: Trapezoid
    requirements: Requirements
    published: Published | None = None
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)

    @model_validator(mode="after")
    def _tie_rod_positive(self) -> "SteeringSpec":
        """l = w - 2 r cos(gamma) > 0 for every arm length and base angle the spec allows."""
        w = self.vehicle.kingpin_spacing
        r_hi = _range(self.trapezoid.arm_length)[1]
        g_lo = _range(self.trapezoid.base_angle)[0]
        l = w - 2.0 * r_hi * math.cos(math.radians(g_lo))
        if l <= 0.0:
            raise ValueError(f"trapezoid: the arms cross: tie rod w - 2 r cos(gamma) = {l:.4g} mm <= 0 at arm_length "
                             f"{r_hi:g} mm, base_angle {g_lo:g} deg (kingpin_spacing {w:g} mm); shorten the arms "
                             f"or raise the base angle")
        return self

    def variables(self) -> dict[str, Variable]:
        return {"arm_length": self.trapezoid.arm_length, "base_angle": self.trapezoid.base_angle}

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

"""Operating conditions given as a range (operating envelopes).

An operating field of a spec (``forward_speed``, ``crank_speed``, a row spacing, a friction factor) takes a
number or a table ``{range = [lo, hi], samples = 4}``: the solve holds every rule that depends on it at
``samples`` evenly spaced values of the range (one shared design), and the re-check evaluates the answer on
a finer grid of the range (``step``).  Everything else (check, figures, the objective) reads the nominal
value, which the section's field then holds as a plain number; the range stays available through
:func:`ranges_of`.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, Field, ValidationInfo, field_validator

from synthesis.spec.common import StrictModel

#: the re-check's grid is this much finer than the solver's samples when no ``step`` is given
FINE = 10
#: at most this many scenarios (products of the ranges' samples) in one NLP and points in one re-check grid:
#: each scenario repeats every rule that reads it, each re-check point costs a float check per start
MAX_SCENARIOS, MAX_RECHECK_POINTS = 200, 20_000


class OperatingRange(StrictModel):
    """``{range = [lo, hi], samples = N}``: an operating condition the design must work over."""

    range: tuple[float, float] = Field(description="[lo, hi] of the condition, in the field's unit")
    samples: int = Field(4, ge=2, le=50, description="values of the range the solve holds every rule at "
                                                     "(evenly spaced, both ends included)")
    nominal: float | None = Field(None, description="value for check, figures and the objective "
                                                    "(default: the middle of the range)")
    step: float | None = Field(None, gt=0, description="spacing of the re-check's grid over the range "
                                                       "(default: 10x finer than the solve's samples)")

    @field_validator("range")
    @classmethod
    def _ordered(cls, value: tuple[float, float]) -> tuple[float, float]:
        lo, hi = value
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo >= hi:
            raise ValueError(f"[{lo:g}, {hi:g}]: expected finite lo < hi")
        return value

    @field_validator("nominal")
    @classmethod
    def _inside(cls, value: float | None, info: ValidationInfo) -> float | None:
        rng = info.data.get("range")
        if value is not None and rng is not None and not rng[0] <= value <= rng[1]:
            raise ValueError(f"{value:g} lies outside the range [{rng[0]:g}, {rng[1]:g}]")
        return value

    @field_validator("step")
    @classmethod
    def _fits(cls, value: float | None, info: ValidationInfo) -> float | None:
        rng = info.data.get("range")
        if value is None or rng is None:
            return value
        if value > rng[1] - rng[0]:
            raise ValueError(f"{value:g} is wider than the range [{rng[0]:g}, {rng[1]:g}]")
        if (rng[1] - rng[0]) / value > 10_000:
            raise ValueError(f"{value:g}: more than 10000 re-check points over [{rng[0]:g}, {rng[1]:g}]")
        return value

    @property
    def centre(self) -> float:
        lo, hi = self.range
        return 0.5 * (lo + hi) if self.nominal is None else float(self.nominal)

    def solver_values(self) -> tuple[float, ...]:
        lo, hi = self.range
        return tuple(float(v) for v in np.linspace(lo, hi, self.samples))

    def recheck_values(self) -> tuple[float, ...]:
        """The re-check's grid: ``step`` apart from lo, hi included (the solver's samples 10x finer by default)."""
        lo, hi = self.range
        step = self.step if self.step is not None else (hi - lo) / (FINE * (self.samples - 1))
        n = int(math.floor((hi - lo) / step + 1e-9))
        values = [lo + k * step for k in range(n + 1)]
        if hi - values[-1] > 1e-9 * max(1.0, abs(hi)):
            values.append(hi)
        return tuple(round(v, 12) for v in values)


def resolve_ranges(section: BaseModel, limits: dict[str, str]) -> None:
    """In a section's after-validator: each field of ``limits`` given as a range has both ends checked
    against the field's allowed values (``limits[name]``, e.g. ``"> 0, <= 2000"``), is kept in the section's
    ``_operating_ranges`` and replaced by its nominal value."""
    ranges = {}
    for name, allowed in limits.items():
        value = getattr(section, name)
        if not isinstance(value, OperatingRange):
            continue
        for v in value.range:
            if not all(_holds(v, part.split()) for part in allowed.split(",")):
                raise ValueError(f"{name}: range value {v:g}: expected {allowed}")
        # a scenario's rules are named by the value to 4 significant digits (entry_angle@forward_speed=0.5833):
        # samples closer than that would share a name and one of them would be dropped
        labels = [f"{v:.4g}" for v in value.solver_values()]
        if len(set(labels)) < len(labels):
            raise ValueError(f"{name}: samples = {value.samples} over [{value.range[0]:g}, {value.range[1]:g}] are not "
                             f"distinct to 4 significant digits: widen the range or take fewer samples")
        ranges[name] = value
        object.__setattr__(section, name, value.centre)     # frozen once validated; this is its own validation
    scenarios = math.prod(r.samples for r in ranges.values())
    points = math.prod(len(r.recheck_values()) for r in ranges.values())
    if scenarios > MAX_SCENARIOS or points > MAX_RECHECK_POINTS:
        raise ValueError(f"{', '.join(ranges)}: {scenarios} scenarios and {points} re-check points together "
                         f"(at most {MAX_SCENARIOS} and {MAX_RECHECK_POINTS}): fewer samples or a coarser step")
    section._operating_ranges = ranges   # declared as ``_operating_ranges: dict = PrivateAttr(default_factory=dict)``


def _holds(v: float, test: list[str]) -> bool:
    op, limit = test[0], float(test[1])
    return {">": v > limit, ">=": v >= limit, "<": v < limit, "<=": v <= limit}[op]


def ranges_of(spec: BaseModel) -> dict[str, tuple[str, OperatingRange]]:
    """Every operating condition of a spec given as a range: name -> (section field, range)."""
    out = {}
    for field in type(spec).model_fields:
        section = getattr(spec, field)
        for name, rng in (getattr(section, "_operating_ranges", None) or {}).items():
            out[name] = (field, rng)
    return out


def at_operating(spec: BaseModel, values: dict[str, float]) -> BaseModel:
    """The spec with operating conditions set to ``values`` (numbers; the ranges dropped): for a float re-check
    at one operating point."""
    ranges = ranges_of(spec)
    update: dict[str, dict] = {}
    top = {}
    for name, v in values.items():
        if name not in ranges and name in type(spec).model_fields:
            top[name] = float(v)            # a condition the spec holds outside any section (a crank_speed)
            continue
        field = ranges[name][0] if name in ranges else _section_of(spec, name)
        update.setdefault(field, {})[name] = float(v)
    sections = {}
    for field, changes in update.items():
        section = getattr(spec, field).model_copy(update=changes)
        ranged = getattr(section, "_operating_ranges", None)     # None: a section that takes no range (a number)
        if ranged is not None:
            section._operating_ranges = {k: r for k, r in ranged.items() if k not in changes}
        sections[field] = section
    return spec.model_copy(update={**sections, **top})


def _section_of(spec: BaseModel, name: str) -> str:
    for field in type(spec).model_fields:
        if name in type(getattr(spec, field)).model_fields if isinstance(getattr(spec, field), BaseModel) else False:
            return field
    raise KeyError(name)

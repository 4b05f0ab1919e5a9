"""Spec model of kind ``combing_chain``: the stem-combing chain of seed 002 §四.3 (Shimamoto; eq 12-13,
Fig. 22-23, Table 13).

A tine on a chain leaning back at ``theta`` to the ground meets a plant of initial angle beta at height
``h``, a distance ``e`` ahead of the cut, and combs it to delta before the cut (eq 12).  The design
variables are the chain speeds V_r: one, or two gears with the machine speed at which gear 2 takes over.
Units: mm, deg, m/s.  Our reading of the paper: problems/combing_chain/CHAIN.md.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from synthesis.spec.common import (POSITIVE, Starts,
    Interval, MultistartSettings, ProblemSpec, StrictModel, Variable, bounds_of, is_free, max_iter_field, starts_field,
    value_of,
)

KIND = "combing_chain"


def _beta_limit(h: float, e: float) -> float:
    """Largest beta whose root is still ahead of the cut when the tine meets the plant, deg."""
    return 180.0 - math.degrees(math.atan2(h, e))


class ChainSection(StrictModel):
    """The combing unit (Table 13 rows h, theta, e) and its chain speed(s)."""

    h: float = Field(gt=0, description="height above the ground at which the tine meets the plant (h), mm")
    theta: float = Field(description="inclination of the chain to the ground (theta), deg, 0 < theta < 90")
    e: float = Field(gt=0, description="distance of that contact point ahead of the cut point (e), mm")
    speeds: list[Variable] = Field(min_length=1, max_length=2, json_schema_extra=POSITIVE,
                                   description="chain (tine) speed V_r of each gear, m/s: one gear, or two "
                                               "(gear 1 below switch_speed, gear 2 above)")
    switch_speed: Variable | None = Field(None, description="two gears: the machine speed at which gear 2 takes "
                                                            "over, m/s; without it every gear must serve the whole "
                                                            "machine-speed range (check only)")

    @model_validator(mode="after")
    def _valid(self) -> "ChainSection":
        if not 0.0 < self.theta < 90.0:
            raise ValueError(f"theta: expected 0 < theta < 90 deg (the chain leans back over the cut point), "
                             f"got {self.theta:g}")
        for i, v in enumerate(self.speeds):
            lo = bounds_of(v)[0]
            if lo <= 0:
                raise ValueError(f"speeds.{i}: expected > 0 m/s, got {lo:g}")
        if self.switch_speed is not None and len(self.speeds) != 2:
            raise ValueError("switch_speed: only with two chain gears (speeds = [gear 1, gear 2])")
        return self


class OperationSection(StrictModel):
    """Where the machine works: its speed range and the initial plant angles it must comb."""

    machine_speed: Interval = Field(description="machine (travel) speed range V_s, [lo, hi] m/s")
    plant_angle: Interval = Field(description="initial plant angles beta to comb, [lo, hi] deg, measured from "
                                              "the backward direction (beta < 90: leaning toward the machine, "
                                              "face cut; beta > 90: leaning away, back cut)")

    @model_validator(mode="after")
    def _ordered(self) -> "OperationSection":
        lo, hi = self.machine_speed
        if not 0.0 < lo <= hi:
            raise ValueError(f"machine_speed: expected 0 < lo <= hi m/s, got [{lo:g}, {hi:g}]")
        lo, hi = self.plant_angle
        if not 0.0 < lo <= hi < 180.0:
            raise ValueError(f"plant_angle: expected 0 < lo <= hi < 180 deg (a plant lying flat has no height h "
                             f"for the tine to meet), got [{lo:g}, {hi:g}]")
        return self


class Requirements(StrictModel):
    """What the combing must achieve: the window of plant angles before the cut."""

    window: Interval | None = Field(None, description="acceptable plant angle delta before the cut, [lo, hi] deg "
                                                      "(e.g. [80, 100]); required by solve")

    @model_validator(mode="after")
    def _window(self) -> "Requirements":
        if self.window is not None:
            lo, hi = self.window
            if not 0.0 < lo < hi < 180.0:
                raise ValueError(f"window: expected 0 < lo < hi < 180 deg, got [{lo:g}, {hi:g}]")
        return self


class PublishedEntry(StrictModel):
    """One printed figure of the paper and the operating point we read it at (the reading is data)."""

    quantity: Literal["delta", "time"] = Field(description="delta: angle before the cut (deg); time: from the "
                                                           "tine meeting the plant to the cut (s)")
    beta: float = Field(gt=0, lt=180, description="initial plant angle of the printed row, deg")
    machine_speed: float = Field(gt=0, description="V_s we read the printed value at, m/s")
    chain_speed: float | None = Field(None, gt=0, description="V_r we read it at, m/s (delta only)")
    value: float = Field(gt=0, description="the printed value (deg or s; > 0: an angle before the cut, a time)")
    label: str = Field("", description="where it is printed, e.g. 'Table 13, delta (beta = 90), first'")

    @model_validator(mode="after")
    def _speed(self) -> "PublishedEntry":
        if self.quantity == "delta" and self.chain_speed is None:
            raise ValueError("chain_speed: a printed delta needs the chain speed it is read at")
        return self


class ObjectiveSection(StrictModel):
    """What `solve` optimises among the chain speeds that satisfy every rule."""

    name: Literal["max_window_margin", "min_chain_speed"] = Field(
        "max_window_margin",
        description="max_window_margin: the chain speed(s) keeping every plant farthest inside the window "
                    "(largest smallest margin, deg); min_chain_speed: the slowest chain(s) that still comb every "
                    "plant into the window (smallest sum of the gears' speeds, m/s)")


class SolverSection(MultistartSettings):
    starts: Starts = starts_field(4)
    beta_samples: int = Field(13, ge=2, le=2000, description="initial plant angles sampled over plant_angle "
                                                             "(the ends included)")
    speed_samples: int = Field(5, ge=2, le=2000, description="machine speeds sampled over each gear's range "
                                                             "(the ends included); beta_samples x speed_samples "
                                                             "at most 10,000")
    max_iter: int = max_iter_field(200)

    @model_validator(mode="after")
    def _grid_size(self) -> "SolverSection":
        # the NLP holds a row per sample and gear, the re-check 100x as many (10x each way): 300 x 300 took 3 min and
        # 2 GB for one start, 2000 x 2000 ran out of memory
        if self.beta_samples * self.speed_samples > MAX_GRID:
            raise ValueError(f"beta_samples x speed_samples = {self.beta_samples} x {self.speed_samples} = "
                             f"{self.beta_samples * self.speed_samples} exceeds {MAX_GRID} (a row per sample and "
                             f"gear in the NLP, 100x as many in the re-check)")
        return self


#: the largest beta_samples x speed_samples grid of a solve (the default is 13 x 5)
MAX_GRID = 10_000


class CombingChainSpec(ProblemSpec):
    kind: Literal["combing_chain"] = Field(description="the problem kind (combing_chain)")
    chain: ChainSection
    operation: OperationSection
    requirements: Requirements = Field(default_factory=Requirements)
    published: list[PublishedEntry] = Field(default_factory=list,
                                            description="printed figures to reproduce (baselines)")
    objective: ObjectiveSection = Field(default_factory=ObjectiveSection)
    solver: SolverSection = Field(default_factory=SolverSection)

    @model_validator(mode="after")
    def _geometry(self) -> "CombingChainSpec":
        c, op = self.chain, self.operation
        limit = _beta_limit(c.h, c.e)
        hi = op.plant_angle[1]
        if hi >= limit:
            lead = c.e + c.h / math.tan(math.radians(hi))
            raise ValueError(
                f"operation.plant_angle: beta = {hi:g} deg leaves the root behind the cut point when the tine meets "
                f"the plant (e + h cot beta = {lead:.4g} mm <= 0), so the tine never combs it before the cut; with "
                f"h = {c.h:g} mm and e = {c.e:g} mm beta must stay below {limit:.4g} deg")
        vlo, vhi = op.machine_speed
        if c.switch_speed is not None:
            slo, shi = bounds_of(c.switch_speed)
            if not (vlo <= slo and shi <= vhi):
                raise ValueError(f"chain.switch_speed: expected within operation.machine_speed [{vlo:g}, {vhi:g}] "
                                 f"m/s, got {slo:g}" + (f"-{shi:g}" if shi != slo else ""))
        cos_t = math.cos(math.radians(c.theta))
        for i, v in enumerate(c.speeds):
            top = self.gear_range_bounds(i)[1]
            lo = bounds_of(v)[0]
            if lo <= top * cos_t:
                what = "the lower bound" if is_free(v) else "V_r ="
                raise ValueError(
                    f"chain.speeds.{i}: {what} {lo:g} m/s is too slow: at V_s = {top:g} m/s, K = V_r/V_s = "
                    f"{lo / top:.4g} <= cos(theta) = {cos_t:.4g}, so the tine slides back down the chain relative "
                    f"to the crop and never reaches the plant; V_r must exceed V_s cos(theta) = {top * cos_t:.4g} m/s")
        return self

    def gear_range_bounds(self, gear: int) -> tuple[float, float]:
        """The widest machine-speed range gear ``gear`` may serve (with a free switch speed: its bounds)."""
        vlo, vhi = self.operation.machine_speed
        sw = self.chain.switch_speed
        if sw is None:
            return vlo, vhi
        slo, shi = bounds_of(sw)
        return (vlo, shi) if gear == 0 else (slo, vhi)

    @property
    def gears(self) -> int:
        return len(self.chain.speeds)

    def speed_names(self) -> list[str]:
        return ["chain_speed"] if self.gears == 1 else [f"chain_speed_{i + 1}" for i in range(self.gears)]

    def variables(self) -> dict[str, Variable]:
        out = dict(zip(self.speed_names(), self.chain.speeds))
        if self.chain.switch_speed is not None:
            out["switch_speed"] = self.chain.switch_speed
        return out

    def design_values(self) -> dict[str, float]:
        return {n: value_of(v) for n, v in self.variables().items()}

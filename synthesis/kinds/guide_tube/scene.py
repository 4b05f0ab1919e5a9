"""A guide_tube spec turned into SI physics and tube geometry, with mu resolved (given or calibrated)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from synthesis.errors import SpecError
from synthesis.kinds.guide_tube.calibrate import MuCalibration, calibrate_mu
from synthesis.kinds.guide_tube.drop import Physics, Tube
from synthesis.spec.common import value_of
from synthesis.spec.operating import OperatingRange
from synthesis.kinds.guide_tube.spec import GuideTubeSpec, RowsSection, TubeSection

MM = 1e-3
#: the row-spacing range is evaluated up to this close below the tray pitch.  At the tray pitch
#: itself no tube is shifted and the seedlings miss the walls (a free fall, zero spread); just
#: below it they still hit the wall's lower end and lose its normal velocity there (plastic
#: impact, eq 15), so the spread jumps at the tray pitch.  Sampling the left limit keeps the worst
#: case of the range at a sample instead of between the last sample and the jump.
CONTACT_MARGIN_MM = 1e-6


@dataclass(frozen=True)
class GuideTubeScene:
    physics: Physics
    tubes: tuple[TubeSection, ...]
    rows: RowsSection
    calibration: MuCalibration | None
    #: the forward speed (m/s) as a CasADi symbol when the NLP declares it an operating condition; None: rows'
    forward_speed: Any = None

    @classmethod
    def from_spec(cls, spec: GuideTubeSpec) -> "GuideTubeScene":
        mu = spec.friction.mu
        assert not isinstance(mu, OperatingRange), "validation keeps a range aside and leaves its nominal value"
        physics = Physics(spec.drop.height * MM, spec.drop.gravity, spec.drop.terminal_speed,
                          mu if mu is not None else 0.0)
        scene = cls(physics, tuple(spec.tubes), spec.rows, None)
        cal = spec.friction.calibrate
        if cal is None:
            return scene
        index = next(i for i, t in enumerate(spec.tubes) if cal.tube in (t.name, t.mirror))
        tube = spec.tubes[index]
        result = calibrate_mu(cal.landing_time, value_of(tube.angle), scene.tube(index, spec.rows.design_spacing),
                              physics, cal.mu_range)
        if len(result.roots) != 1:
            raise SpecError(calibration_failure(result))
        return cls(physics.with_(mu=result.roots[0]), scene.tubes, scene.rows, result)

    def tube(self, index: int, spacing: float) -> Tube:
        """Tube ``index`` at row spacing ``spacing`` (mm), in SI."""
        t = self.tubes[index]
        return Tube(t.name, t.l3 * self.rows.l3_scale(spacing) * MM, t.h5 * MM, t.h6 * MM)

    def spacing_grid(self, samples: int) -> list[float]:
        """``samples`` row spacings (mm) spread evenly over rows.spacings (one if the range is a point),
        the tray pitch taken as its left limit (CONTACT_MARGIN_MM)."""
        lo, hi = self.rows.spacings
        hi = min(hi, self.rows.tray_pitch - CONTACT_MARGIN_MM)
        lo = min(lo, hi)
        return [float(lo)] if lo == hi else np.linspace(lo, hi, samples).tolist()

    @property
    def forward_mm_per_s(self) -> float:
        return (self.rows.forward_speed if self.forward_speed is None else self.forward_speed) * 1000.0


def calibration_failure(c: MuCalibration) -> str:
    """The spec error of a calibration that found no mu, or several."""
    lo, hi = c.mu_range
    if c.roots:
        return (f"guide_tube.friction.calibrate: several friction coefficients make tube {c.tube} (wall angle "
                f"{c.delta_deg:g} deg) land after {c.target:g} s: mu = {', '.join(f'{m:.6g}' for m in c.roots)}; "
                f"give friction.mu, or narrow guide_tube.friction.calibrate.mu_range to one of them")
    span = ("the seedling sticks on the wall for every mu there" if c.landing_time_range is None else
            f"its landing time spans {c.landing_time_range[0]:.4f}-{c.landing_time_range[1]:.4f} s there")
    sticks = "" if c.sticks_above is None or c.landing_time_range is None else \
        f", and the seedling sticks on the wall from mu = {c.sticks_above:.4g}"
    return (f"guide_tube.friction.calibrate.landing_time: no mu in [{lo:g}, {hi:g}] makes tube {c.tube} (wall angle "
            f"{c.delta_deg:g} deg) land after {c.target:g} s: {span}{sticks}")

"""The drop of a pot seedling through one guide tube (seed 001 §2.4, eq 13-23), in closed form.

Heights are measured down from the drop point N1, ``height`` above the paddy (600 mm):

1. free fall from rest over h1 (eq 13/14);
2. plastic impact on the inclined wall at N2: only the speed along the wall survives,
   v2a = v1a sin d (eq 15);
3. slide down the wall over s1 = L3 / cos d, dropping h2 = L3 tan d, with Coulomb friction mu and
   drag (eq 16/17), driving acceleration g (sin d - mu cos d): negative when tan d < mu, the
   decelerating slide; the seedling sticks if it stops before the wall end N3;
4. projectile from N3 with vertical speed v3a sin d; eq 18 drags the vertical speed alone;
5. plastic impact on the vertical wall at N4 keeps the vertical speed (eq 20);
6. fall with drag to the paddy (eq 21).

Eq 23 closes the geometry: h1 + h2 + h3 + h4 = height and h3 + h4 = h5 + h6, so
h1 = height - h5 - h6 - L3 tan d.  Since eq 18 and eq 20 leave the vertical motion untouched by
the horizontal one, phases 4-6 are one vertical fall of h5 + h6 starting at v3a sin d: the split
h3 / h4 (where the seedling meets the vertical wall, not published) does not change the drop time.
A tube with L3 = 0 (row spacing equal to the tray pitch) has no wall contact: a free fall.

``drop_phases`` runs on floats and CasADi symbols alike (angle in radians, SI units);
``landing`` is its checked float front end (degrees in, errors that name the tube).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import casadi as ca

from synthesis.errors import AssemblyError, SolverError
from synthesis.kinds.guide_tube.drag import exit_speed_sq, stopping_distance, traverse


@dataclass(frozen=True)
class Physics:
    """Drop point and pot-seedling properties (SI)."""

    height: float             # m, drop point N1 above the paddy
    gravity: float            # m/s^2
    terminal_speed: float     # m/s, v_L (math.inf: no drag)
    mu: float                 # Coulomb friction coefficient seedling-wall

    @property
    def kappa(self) -> float:
        """Drag per unit speed squared, g / v_L^2 (1/m): dv/dt = a - kappa v^2."""
        return 0.0 if math.isinf(self.terminal_speed) else self.gravity / self.terminal_speed ** 2

    def with_(self, **changes) -> "Physics":
        return Physics(**{**{f.name: getattr(self, f.name) for f in fields(self)}, **changes})


@dataclass(frozen=True)
class Tube:
    """One guide tube at one row spacing (SI)."""

    name: str
    l3: float                 # m, horizontal distance drop point - tube centre (the wall's horizontal run)
    h5: float                 # m, straight section length
    h6: float                 # m, tube outlet above the paddy

    @property
    def below_wall(self) -> float:
        """h3 + h4 = h5 + h6: height of the wall's lower end N3 above the paddy."""
        return self.h5 + self.h6


@dataclass(frozen=True)
class DropPhases:
    """Heights (m), phase times (s) and speeds (m/s) of one drop; floats or CasADi expressions."""

    h1: Any                   # free-fall height N1 -> N2
    h2: Any                   # height of the slide, L3 tan d
    s1: Any                   # slide length, L3 / cos d
    t_fall: Any               # t1
    t_slide: Any              # t2
    t_after: Any              # t3 + t4: wall end N3 -> paddy
    v_impact: Any             # v1a, vertical speed reaching the wall
    v_wall: Any               # v2a, speed along the wall after the impact
    v_exit: Any               # v3a, speed along the wall at its end
    v_land: Any               # vertical speed reaching the paddy
    exit_speed_sq: Any        # v3a^2 from the energy balance; <= 0: the seedling stops on the wall
    slide_accel: Any          # g (sin d - mu cos d), driving acceleration of the slide

    @property
    def landing_time(self):
        """t_z = t1 + t2 + t3 + t4 (eq 22)."""
        return self.t_fall + self.t_slide + self.t_after


def drop_phases(delta, tube: Tube, physics: Physics) -> DropPhases:
    """The closed-form drop through ``tube`` whose wall is inclined ``delta`` (rad) to the horizontal."""
    g, kappa = physics.gravity, physics.kappa
    if tube.l3 == 0:       # no wall contact
        h1 = physics.height - tube.below_wall
        t1, v1 = traverse(0.0, g, kappa, h1)
        t_after, v_land = traverse(v1, g, kappa, tube.below_wall)
        return DropPhases(h1, 0.0, 0.0, t1, 0.0, t_after, v1, v1, v1, v_land, v1 * v1, g)
    sin, cos = ca.sin(delta), ca.cos(delta)
    h2 = tube.l3 * sin / cos
    s1 = tube.l3 / cos
    h1 = physics.height - tube.below_wall - h2
    t1, v1 = traverse(0.0, g, kappa, h1)
    v2 = v1 * sin                                   # eq 15
    accel = g * (sin - physics.mu * cos)            # eq 16 without drag: g A^2
    t2, v3 = traverse(v2, accel, kappa, s1)
    t_after, v_land = traverse(v3 * sin, g, kappa, tube.below_wall)
    return DropPhases(h1, h2, s1, t1, t2, t_after, v1, v2, v3, v_land,
                      exit_speed_sq(v2, accel, kappa, s1), accel)


class SeedlingSticks(SolverError):
    """The seedling stops on a wall flatter than the friction angle before reaching its end (exit 3)."""

    def __init__(self, tube: str, delta_deg: float, mu: float, stops_after_mm: float, wall_mm: float):
        self.tube, self.delta_deg, self.mu = tube, delta_deg, mu
        self.stops_after_mm, self.wall_mm = stops_after_mm, wall_mm
        super().__init__(
            f"the seedling sticks on the wall of tube {tube}: at wall angle {delta_deg:.4g} deg with friction "
            f"coefficient mu = {mu:.4g} (tan {delta_deg:.4g} deg = {math.tan(math.radians(delta_deg)):.4g} < mu) "
            f"it stops {stops_after_mm:.1f} mm down the {wall_mm:.1f} mm wall. Steepen that wall (above "
            f"atan(mu) = {math.degrees(math.atan(mu)):.2f} deg it always slides) or lower mu.")


class WallAboveDropPoint(AssemblyError):
    """The inclined wall reaches above the drop point: no free fall before the impact (exit 2)."""


def slide(delta_deg: float, tube: Tube, physics: Physics) -> tuple[DropPhases, SeedlingSticks | None]:
    """Float drop through ``tube`` at wall angle ``delta_deg``, and whether the seedling sticks on the wall:
    its phases up to the wall end (heights, impact and exit speeds, exit_speed_sq <= 0) are given either way,
    its landing times mean nothing if it sticks.  Raises if the wall reaches above the drop point
    (WallAboveDropPoint, exit 2)."""
    phases = drop_phases(math.radians(delta_deg), tube, physics)
    if phases.h1 <= 0:
        raise WallAboveDropPoint(
            f"tube {tube.name}: at wall angle {delta_deg:.4g} deg the inclined wall rises L3 tan d = "
            f"{1000 * phases.h2:.1f} mm above its lower end, {1000 * tube.below_wall:.0f} mm (h5 + h6) above the "
            f"paddy: it reaches {-1000 * phases.h1:.1f} mm above the drop point ({1000 * physics.height:.0f} mm); "
            f"flatten the wall or lower h5 + h6")
    sticks = None
    if phases.exit_speed_sq <= 0:
        stop = stopping_distance(float(phases.v_wall), float(phases.slide_accel), physics.kappa)
        sticks = SeedlingSticks(tube.name, delta_deg, physics.mu, 1000 * stop, 1000 * float(phases.s1))
    return DropPhases(*(float(getattr(phases, f.name)) for f in fields(DropPhases))), sticks


def landing(delta_deg: float, tube: Tube, physics: Physics) -> DropPhases:
    """Float drop through ``tube`` at wall angle ``delta_deg``; raises if the wall reaches above the
    drop point (WallAboveDropPoint, exit 2) or the seedling sticks on it (SeedlingSticks, exit 3)."""
    phases, sticks = slide(delta_deg, tube, physics)
    if sticks is not None:
        raise sticks
    return phases

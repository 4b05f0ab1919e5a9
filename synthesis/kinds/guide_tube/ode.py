"""The drop through one guide tube integrated with scipy ``solve_ivp``; phase switches are events.

This is the second, independent implementation of seed 001 eq 13-22 (the first is the closed
form in drop.py).  Each phase integrates the printed differential equation from the state the
previous phase ended in, and stops at its event:

    fall        y'' = g - kappa y'|y'|                      until y = h1 (the wall)
    impact      v := v_y sin d                              (eq 15)
    slide       s'' = g (sin d - mu cos d) - kappa s'|s'|    until s = s1 (wall end)  or s' = 0 (sticks)
    projectile  x'' = -kappa x'|x'|,  y'' = g - kappa y'|y'|  until y = h5 + h6 (paddy) or x = wall gap
    impact      x' := 0                                     (eq 20, only when a wall gap is given)
    fall        y'' = g - kappa y'|y'|                      until y = h5 + h6

The projectile drags each velocity component with its own speed, as eq 18 does for Y (the paper
gives no X equation); with that reading the vertical-wall impact never changes the drop time.
DOP853 at rtol = atol = 1e-12 puts event times within ~1e-12 s of the exact switch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from synthesis.errors import SolverError
from synthesis.kinds.guide_tube.drop import Physics, SeedlingSticks, Tube, WallAboveDropPoint

#: no phase of a drop of a few metres lasts this long; reaching it means an event was missed
HORIZON_S = 1000.0
RTOL = ATOL = 1e-12


@dataclass
class OdeDrop:
    """Phase end times (s, cumulative), speeds (m/s) and a sampled height-time profile."""

    t_fall: float
    t_slide: float
    t_after: float
    v_impact: float
    v_exit: float
    v_land: float
    hit_vertical_wall: bool
    samples_t: list = field(default_factory=list)         # s
    samples_height: list = field(default_factory=list)    # m above the paddy

    @property
    def landing_time(self) -> float:
        return self.t_fall + self.t_slide + self.t_after


def _event(fun, direction: float):
    fun.terminal = True
    fun.direction = direction
    return fun


def _run(rhs, y0, events, what: str):
    sol = solve_ivp(rhs, (0.0, HORIZON_S), y0, method="DOP853", rtol=RTOL, atol=ATOL, events=events,
                    dense_output=True)
    if sol.status != 1:
        raise SolverError(f"ODE of the {what} ended without its event ({sol.message})")
    for i, times in enumerate(sol.t_events):
        if times.size:
            return i, float(times[0]), sol.y_events[i][0], sol.sol
    raise SolverError(f"ODE of the {what}: no event recorded")  # pragma: no cover - status 1 implies one


def _falling(g: float, kappa: float):
    return lambda t, y: [y[1], g - kappa * y[1] * abs(y[1])]


def simulate(delta_deg: float, tube: Tube, physics: Physics, wall_gap: float | None = None,
             samples_per_phase: int = 40) -> OdeDrop:
    """Integrate one drop; ``wall_gap`` (m) is the horizontal distance from the wall end N3 to the
    vertical wall (None: not modelled, the projectile flies to the paddy)."""
    g, kappa, mu = physics.gravity, physics.kappa, physics.mu
    d = math.radians(delta_deg)
    sin, cos = math.sin(d), math.cos(d)
    below = tube.below_wall
    h2 = tube.l3 * math.tan(d) if tube.l3 > 0 else 0.0
    h1 = physics.height - below - h2
    if h1 <= 0:
        raise WallAboveDropPoint(f"tube {tube.name}: the wall reaches above the drop point")
    ts: list[float] = []
    hs: list[float] = []

    def record(sol, t_end: float, t0: float, height_of) -> None:
        tt = np.linspace(0.0, t_end, samples_per_phase)
        ys = sol(tt)
        ts.extend((t0 + tt).tolist())
        hs.extend(height_of(ys).tolist())

    # 1. free fall from rest to the wall (or, without a wall, to the straight section's top)
    _, t1, y1, sol = _run(_falling(g, kappa), [0.0, 0.0], [_event(lambda t, y: y[0] - h1, 1.0)], "free fall")
    record(sol, t1, 0.0, lambda ys: physics.height - ys[0])
    v1 = y1[1]
    if tube.l3 == 0:
        _, t34, y4, sol = _run(_falling(g, kappa), [0.0, v1], [_event(lambda t, y: y[0] - below, 1.0)],
                               "fall to the paddy")
        record(sol, t34, t1, lambda ys: below - ys[0])
        return OdeDrop(t1, 0.0, t34, v1, v1, float(y4[1]), False, ts, hs)

    # 2. plastic impact (eq 15) and slide (eq 16)
    s1 = tube.l3 / cos
    accel = g * (sin - mu * cos)
    slide_events = [_event(lambda t, y: y[0] - s1, 1.0), _event(lambda t, y: y[1], -1.0)]
    which, t2, y2, sol = _run(lambda t, y: [y[1], accel - kappa * y[1] * abs(y[1])], [0.0, v1 * sin],
                              slide_events, "slide")
    if which == 1:
        raise SeedlingSticks(tube.name, delta_deg, mu, 1000 * y2[0], 1000 * s1)
    record(sol, t2, t1, lambda ys: below + h2 - ys[0] * sin)
    v3 = y2[1]

    # 3. projectile from the wall end (eq 18), per-component drag
    def projectile(t, y):
        return [y[2], y[3], -kappa * y[2] * abs(y[2]), g - kappa * y[3] * abs(y[3])]

    events = [_event(lambda t, y: y[1] - below, 1.0)]
    if wall_gap is not None:
        events.append(_event(lambda t, y: y[0] - wall_gap, 1.0))
    which, t3, y3, sol = _run(projectile, [0.0, 0.0, v3 * cos, v3 * sin], events, "projectile")
    record(sol, t3, t1 + t2, lambda ys: below - ys[1])
    if which == 0:
        return OdeDrop(t1, t2, t3, v1, v3, float(y3[3]), False, ts, hs)

    # 4. plastic impact on the vertical wall keeps the vertical speed (eq 20); fall (eq 21)
    rest = below - y3[1]
    _, t4, y4, sol = _run(_falling(g, kappa), [0.0, y3[3]], [_event(lambda t, y: y[0] - rest, 1.0)],
                          "fall after the vertical wall")
    record(sol, t4, t1 + t2 + t3, lambda ys: rest - ys[0])
    return OdeDrop(t1, t2, t3 + t4, v1, v3, float(y4[1]), True, ts, hs)

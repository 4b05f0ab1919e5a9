"""Claw tip of the four-bar planting arm (seed 000, Fig. 2) and its derivatives by CasADi AD.

The coupler AB is rigidly extended to the claw tip C: |AC| = l5 and the direction AC is the
direction AB turned clockwise by the fixed angle phi.  With the frame angle zeta and the crank
angle theta of :mod:`synthesis.kinematics.fourbar`::

    C(theta) = A + l5 * R(-phi) (B - A) / l3

Machine frame: X forward (direction of travel), Y up, origin at the crank pivot O; the crank turns
counter-clockwise (theta increasing) at the constant speed omega.  Ground frame: X_g = X + v t.
The reading of the garbled OCR formulas behind these choices is in
``problems/planting_arm/GEOMETRY.md``.

Velocities and accelerations are exact: d/dtheta by AD, times omega (and omega^2) because omega is
constant.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np
from scipy.optimize import minimize_scalar

from synthesis.kinematics import fourbar

#: order of the parameter vector p of :func:`claw_tip` (mm, mm, mm, mm, mm, rad, rad)
PARAMETERS = ("l1", "l2", "l3", "l4", "l5", "zeta", "phi")


def claw_arm(theta, p, branch: int) -> tuple[fourbar.Point, fourbar.Point]:
    """(A, u): the crank pin A (mm) and the unit vector u along the claw arm A -> C, the direction AB turned
    clockwise by phi, for the parameter vector p = (l1, l2, l3, l4, l5, zeta, phi) (mm, rad)."""
    l1, l2, l3, l4, _, zeta, phi = (p[i] for i in range(7))
    (ax, ay), (bx, by) = fourbar.coupler_joint(theta, l1, l2, l3, l4, zeta, branch)
    return (ax, ay), fourbar.rotate(((bx - ax) / l3, (by - ay) / l3), -phi)


def claw_tip(theta, p, branch: int) -> fourbar.Point:
    """C(theta) for the parameter vector p = (l1, l2, l3, l4, l5, zeta, phi) (mm, rad)."""
    (ax, ay), (ux, uy) = claw_arm(theta, p, branch)
    l5 = p[4]
    return (ax + l5 * ux, ay + l5 * uy)


def claw_attitude(theta, p, branch: int):
    """The claw's attitude: the direction of the claw arm A -> C (crank pin A to the claw tip C, rigid on the
    coupler), rad from +X counter-clockwise in (-pi, pi] (pointing straight down: -pi/2).  One expression for floats
    and CasADi symbols: the check reads it through :func:`attitude_function`, the NLP on its own symbols."""
    _, (ux, uy) = claw_arm(theta, p, branch)
    return ca.atan2(uy, ux)


@lru_cache(maxsize=4)
def tip_derivatives(branch: int) -> ca.Function:
    """CasADi Function (theta, p) -> (C, dC/dtheta, d2C/dtheta2), each 2x1, in mm, mm/rad, mm/rad^2.

    Built once per assembly branch and reused: calling it on floats evaluates numerically, calling
    it on symbols embeds it in an NLP, and ``.map(N)`` vectorises it over crank angles.
    """
    theta = ca.SX.sym("theta")
    p = ca.SX.sym("p", len(PARAMETERS))
    c = ca.vertcat(*claw_tip(theta, p, branch))
    dc = ca.jacobian(c, theta)
    ddc = ca.jacobian(dc, theta)
    return ca.Function(
        f"claw_tip_branch{'p' if branch > 0 else 'm'}",
        [theta, p],
        [c, dc, ddc],
        ["theta", "p"],
        ["pos", "dpos", "ddpos"],
    )


@dataclass(frozen=True)
class ArmDesign:
    """Geometry of one planting arm in spec units: lengths mm, angles deg."""

    l1: float
    l2: float
    l3: float
    l4: float
    l5: float
    zeta: float
    phi: float
    branch: int = -1

    @classmethod
    def of_result(cls, design: Mapping[str, Any]) -> ArmDesign:
        """The arm of a result.json design: its seven values and its assembly branch."""
        l1, l2, l3, l4, l5, zeta, phi = (float(design[k]) for k in ("l1", "l2", "l3", "l4", "l5", "zeta", "phi"))
        return cls(l1, l2, l3, l4, l5, zeta, phi, branch=int(design["branch"]))

    def parameters(self) -> np.ndarray:
        """p for :func:`claw_tip`: lengths in mm, angles in rad."""
        return np.array([self.l1, self.l2, self.l3, self.l4, self.l5,
                         np.radians(self.zeta), np.radians(self.phi)])


@dataclass(frozen=True)
class Motion:
    """Operating condition: crank speed omega (rad/s) and forward speed v (mm/s)."""

    omega: float
    forward: float

    @property
    def period(self) -> float:
        return 2.0 * np.pi / self.omega


@dataclass(frozen=True)
class TipState:
    """Claw tip at one or several crank angles; machine-frame vectors, shape (2,) or (2, N)."""

    theta: np.ndarray   # rad
    pos: np.ndarray     # mm
    vel: np.ndarray     # mm/s
    acc: np.ndarray     # mm/s^2

    def time(self, motion: Motion) -> np.ndarray:
        """t = theta / omega: time zero when the crank lies on the frame line OO'."""
        return np.asarray(self.theta) / motion.omega

    def ground_pos(self, motion: Motion) -> np.ndarray:
        pos = np.array(self.pos, dtype=float)
        pos[0] = pos[0] + motion.forward * self.time(motion)
        return pos

    def ground_vel(self, motion: Motion) -> np.ndarray:
        vel = np.array(self.vel, dtype=float)
        vel[0] = vel[0] + motion.forward
        return vel


def tip_state(design: ArmDesign, motion: Motion, theta) -> TipState:
    """Exact position, velocity and acceleration of C at crank angle(s) theta (rad)."""
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    f = _mapped(tip_derivatives, design.branch, theta.size) if theta.size > 1 else tip_derivatives(design.branch)
    pos, dpos, ddpos = f(theta.reshape(1, -1), design.parameters())
    pos, dpos, ddpos = (np.asarray(v).reshape(2, -1) for v in (pos, dpos, ddpos))
    return TipState(theta, pos, dpos * motion.omega, ddpos * motion.omega**2)


@lru_cache(maxsize=4)
def attitude_function(branch: int) -> ca.Function:
    """CasADi Function (theta, p) -> the claw's attitude (rad, :func:`claw_attitude`)."""
    theta = ca.SX.sym("theta")
    p = ca.SX.sym("p", len(PARAMETERS))
    return ca.Function(f"claw_attitude_branch{'p' if branch > 0 else 'm'}", [theta, p],
                       [claw_attitude(theta, p, branch)], ["theta", "p"], ["attitude"])


def claw_attitudes(design: ArmDesign, theta) -> np.ndarray:
    """The claw's attitude (N,) at the crank angles theta (rad), rad (:func:`claw_attitude`).  Through the mapped
    function: a few angles (the precision points, the key poses), for which no expanded grid is worth building."""
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    return np.asarray(_mapped(attitude_function, design.branch, theta.size)(theta.reshape(1, -1),
                                                                             design.parameters())).ravel()


def path_positions(design: ArmDesign, theta) -> np.ndarray:
    """Positions (2, N) of C at the crank angles theta (rad), mm, through the mapped function (no expanded grid
    built): a key pose's search for where the tip comes nearest its target."""
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    return np.asarray(_mapped(tip_position, design.branch, theta.size)(theta.reshape(1, -1), design.parameters()))


@lru_cache(maxsize=4)
def tip_position(branch: int) -> ca.Function:
    """CasADi Function (theta, p) -> C alone (2x1, mm): the same expression as :func:`tip_derivatives`' first output,
    so the same numbers to the bit, without its derivatives (a precision-point search scans 3,600 positions)."""
    theta = ca.SX.sym("theta")
    p = ca.SX.sym("p", len(PARAMETERS))
    return ca.Function(f"claw_tip_position_branch{'p' if branch > 0 else 'm'}", [theta, p],
                       [ca.vertcat(*claw_tip(theta, p, branch))], ["theta", "p"], ["pos"])


def tip_positions(design: ArmDesign, theta: np.ndarray) -> np.ndarray:
    """Positions (2, N) of C at the crank angles theta (rad), mm: :func:`tip_state`'s ``pos``, bit for bit."""
    return _on_grid(((tip_position, 0, (0, 1)),), design, theta)


def tip_heights_and_transmission(design: ArmDesign, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Y (N,) of C, mm, and the transmission angle mu (N,), rad, at the crank angles theta (rad): :func:`tip_positions`'
    second row and :func:`transmission_angles`, bit for bit, in one pass sharing the four-bar's closure (a re-check
    scans the claw's Y for P5 on the very turn grid its transmission rule samples)."""
    y, mu = _on_grid(((tip_position, 0, (1,)), (link_function, 0, (0,))), design, theta)
    return y, mu


def tip_accelerations_y(design: ArmDesign, motion: Motion, theta: np.ndarray) -> np.ndarray:
    """a_y (N,) of C at the crank angles theta (rad), mm/s^2: :func:`tip_state`'s ``acc[1]``, bit for bit, without
    the position, velocity and a_x it also computes (a re-check reads a_y alone over each acceleration phase)."""
    return _on_grid(((tip_derivatives, 2, (1,)),), design, theta)[0] * motion.omega**2


#: the largest grid evaluated through :func:`_expanded`: the check's turn (3,600 angles, 3,601 from P5) and phases;
#: its SX function holds every angle's operations (some 50 MB and 0.2 s to build for a_y on 3,600 angles), so a
#: finer grid (a spec's samples_per_turn above 400 re-checked 10x finer, a plot) goes through ``.map``
EXPANDED_MAX = 4000

#: what :func:`_expanded` evaluates: (function of a branch, its output's index, the rows of that output) per part
Parts = tuple[tuple[Callable[[int], ca.Function], int, tuple[int, ...]], ...]


def _on_grid(parts: Parts, design: ArmDesign, theta) -> np.ndarray:
    """The rows of ``parts`` stacked, at crank angles theta: (rows, N)."""
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    p = design.parameters()
    if theta.size > EXPANDED_MAX:
        return np.vstack([np.asarray(_mapped(function, design.branch, theta.size).call([theta.reshape(1, -1), p])[
            output])[list(rows)] for function, output, rows in parts])
    return _expanded(parts, design.branch, theta.size).values(theta, p)


class Evaluator:
    """A CasADi Function (theta, p) -> values, called through its buffer interface: numpy arrays in and out, with
    no DM built or converted (a root finder's call 0.3 us instead of 12, 3,600 angles 0.3 ms instead of 0.8: the
    conversions were most of a re-check's CasADi time).  The same function evaluated, so the same numbers.  One
    buffer per function, so a call holds a lock (the studio may serve two pages at once)."""

    def __init__(self, function: ca.Function):
        self.function = function
        self._theta, self._p = np.zeros(function.nnz_in(0)), np.zeros(function.nnz_in(1))
        self._out = np.zeros(function.nnz_out(0))
        self._rows = function.size1_out(0)
        self._buffer, self._evaluate = function.buffer()
        # stub gaps: casadi's stubs ask for a size the binding reads off the buffer itself, and numpy's give
        # ndarray no __buffer__ before Python 3.12
        self._buffer.set_arg(0, memoryview(self._theta))  # type: ignore[call-arg, arg-type]
        self._buffer.set_arg(1, memoryview(self._p))  # type: ignore[call-arg, arg-type]
        self._buffer.set_res(0, memoryview(self._out))  # type: ignore[call-arg, arg-type]
        self._lock = threading.Lock()

    def values(self, theta, p) -> np.ndarray:
        """(rows, N) at the N crank angles theta (rad) for parameters p (:func:`claw_tip`'s order)."""
        with self._lock:
            self._theta[:] = theta
            self._p[:] = p
            self._evaluate()
            # CasADi stores column by column: angle after angle
            return self._out.reshape(-1, self._rows).T.copy()

    def scalar(self, theta: float, p) -> float:
        """The first value at one crank angle (rad)."""
        with self._lock:
            self._theta[0] = theta
            self._p[:] = p
            self._evaluate()
            return float(self._out[0])


@lru_cache(maxsize=16)
def _expanded(parts: Parts, branch: int, n: int) -> Evaluator:
    """The rows of ``parts`` (stacked) at n crank angles as one SX Function (theta (1, n), p) -> (rows, n), built once
    per process, called as an :class:`Evaluator`.

    Per angle, the chosen rows' operations alone, once each: common subexpressions merged (``ca.cse``: the
    claw's Y and the transmission angle share the four-bar's closure, a_y repeats terms of its AD), then the map
    over the grid expanded into SX, so CasADi's virtual machine runs the whole grid in one call instead of one call
    per angle (2.5x faster on 3,600 angles).  Merging a repeated operation and running it once per angle leave
    every operation and its inputs as they were, so the numbers are the full functions' to the bit (compared over
    designs near the library in tests/test_planting_recheck_speed.py).
    """
    theta = ca.SX.sym("theta")
    p = ca.SX.sym("p", len(PARAMETERS))
    rows = ca.vertcat(*[function(branch).call([theta, p])[output][list(picked), :]
                        for function, output, picked in parts])
    name = "_".join(f"{function.__name__}{output}r{''.join(map(str, picked))}" for function, output, picked in parts)
    one = ca.Function(f"{name}_branch{'p' if branch > 0 else 'm'}", [theta, p], [ca.cse(rows)], ["theta", "p"],
                      ["values"])
    if n == 1:
        return Evaluator(one)
    grid = ca.SX.sym("theta", 1, n)
    return Evaluator(ca.Function(f"{one.name()}_on_{n}", [grid, p], [one.map(n).call([grid, p])[0]], ["theta", "p"],
                                 ["values"]))


def scalar_function(function, branch: int, output: int, rows: tuple[int, ...]) -> Evaluator:
    """Rows ``rows`` of output ``output`` of ``function(branch)`` alone, (theta, p) -> (len(rows), 1): a root
    finder's function (the full function's operations, so its numbers to the bit, with only those it needs)."""
    return _expanded(((function, output, rows),), branch, 1)


@lru_cache(maxsize=64)
def _mapped(function, branch: int, n: int) -> ca.Function:
    """``function(branch).map(n)``, built once: a check or a Monte-Carlo sample evaluates the same few grids
    (3,600 crank angles, 400 per phase) thousands of times, and building the map was a fifth of a re-check."""
    return function(branch).map(n)


@lru_cache(maxsize=4)
def link_function(branch: int) -> ca.Function:
    """CasADi Function (theta, p) -> (mu, h2): transmission angle (rad) and assembly height^2 (mm^2)."""
    theta = ca.SX.sym("theta")
    p = ca.SX.sym("p", len(PARAMETERS))
    l1, l2, l3, l4, _, zeta, _ = (p[i] for i in range(7))
    mu = fourbar.transmission_angle(theta, l1, l2, l3, l4, zeta, branch)
    h2 = fourbar.assembly_height_sq(theta, l1, l2, l3, l4)
    return ca.Function("links", [theta, p], [mu, h2], ["theta", "p"], ["mu", "h2"])


def link_angles(design: ArmDesign, theta) -> dict[str, np.ndarray]:
    """Transmission angle mu (rad) and assembly margin h2 (mm^2) at crank angles theta (rad)."""
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    f = _mapped(link_function, design.branch, theta.size)
    mu, h2 = f(theta.reshape(1, -1), design.parameters())
    return {"mu": np.asarray(mu).ravel(), "h2": np.asarray(h2).ravel()}


def transmission_angles(design: ArmDesign, theta) -> np.ndarray:
    """Transmission angle mu (N,) at crank angles theta (rad), rad: :func:`link_angles`' ``mu``, bit for bit, without
    the assembly margin."""
    return _on_grid(((link_function, 0, (0,)),), design, theta)[0]


def joint_positions(design: ArmDesign, theta) -> dict[str, np.ndarray]:
    """Ground pivots O, O' and moving joints A, B, C at crank angles theta (rad): name -> (2, N) mm.

    For drawing the linkage; the same closed form as :func:`claw_tip`, evaluated on arrays.
    """
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    l1, l2, l3, l4, l5, zeta, phi = design.parameters()
    (ax, ay), (bx, by) = fourbar.coupler_joint(theta, l1, l2, l3, l4, zeta, design.branch)
    a = np.vstack([np.asarray(ax, float).ravel(), np.asarray(ay, float).ravel()])
    b = np.vstack([np.asarray(bx, float).ravel(), np.asarray(by, float).ravel()])
    c = np.array([tuple(np.asarray(v, float).ravel()) for v in claw_tip(theta, design.parameters(), design.branch)])
    pivot = np.array(fourbar.rocker_pivot(l1, zeta), float).reshape(2, 1)
    n = theta.size
    return {"O": np.zeros((2, n)), "O'": np.repeat(pivot, n, axis=1), "A": a, "B": b, "C": c.reshape(2, n)}


def rocker_counterweight_y(theta, p, radius, branch: int):
    """Y (mm, machine frame) of the rocker's counterweight at crank angle theta, for the arm parameters
    p = (l1, l2, l3, l4, l5, zeta, phi) (mm, rad) and its radius (mm): O' - radius (B - O') / l4; floats, arrays or
    CasADi symbols."""
    l1, l2, l3, l4, zeta = p[0], p[1], p[2], p[3], p[5]
    _, (_, by) = fourbar.coupler_joint(theta, l1, l2, l3, l4, zeta, branch)
    _, oy = fourbar.rocker_pivot(l1, zeta)
    return oy - radius * (by - oy) / l4


@lru_cache(maxsize=4)
def rocker_counterweight_y_function(branch: int) -> ca.Function:
    """CasADi Function (theta, p, radius) -> Y of the rocker's counterweight (mm)."""
    theta, p, radius = ca.SX.sym("theta"), ca.SX.sym("p", 7), ca.SX.sym("radius")
    return ca.Function("rocker_counterweight_y", [theta, p, radius],
                       [rocker_counterweight_y(theta, p, radius, branch)])


def lowest_rocker_counterweight_y(p, radius: float, branch: int, samples: int) -> float:
    """The lowest Y (mm) of the rocker's counterweight over a turn: ``samples`` crank angles, then a bounded
    minimisation between the neighbours of the lowest (to 1e-10 rad), for a crank that completes a turn."""
    f = rocker_counterweight_y_function(branch)
    grid = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    ys = np.asarray(_mapped(rocker_counterweight_y_function, branch, samples)(grid.reshape(1, -1), p, radius),
                    float).ravel()
    k, step = int(np.argmin(ys)), grid[1]
    found = minimize_scalar(lambda t: float(f(t, p, radius)), bounds=(grid[k] - step, grid[k] + step),
                            method="bounded", options={"xatol": 1e-10})
    return float(min(found.fun, ys[k]))

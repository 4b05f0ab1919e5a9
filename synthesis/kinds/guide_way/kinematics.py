"""Rotary arm with a claw steered by a roller in a fixed slide guide way (seed 003, Liang et al., Fig. 2).

Pure functions on floats / numpy arrays and on CasADi symbols alike.  Frame and symbols exactly as
the paper's eq (5)-(7), angles in radians:

* O, the planting-wheel shaft, at the origin.  The arm OP (length R) is at angle theta:
  P = (-R sin theta, -R cos theta).
* The claw PM (length d) is at angle alpha:  M = P + d (sin alpha, -cos alpha)          (eq 5, 6)
* The crank arm PN (length r) is rigid with the claw, the angle NPM = beta:
  N = P - r (sin(beta - alpha), cos(beta - alpha))                                       (eq 7)
  (beta = 180 deg puts N straight opposite M.)
* The claw's angle to the arm is alpha + theta: 0 when the claw is stretched out along OP
  (|OM| = R + d), 180 deg when it is folded back onto the arm (|OM| = R - d, seed 003 §1(3)).

Inverse kinematics M -> (theta, alpha): with rho = |OM|, gamma = atan2(-x_M, -y_M) the angle of OM
in the theta convention and phi = acos((R^2 + rho^2 - d^2) / (2 R rho)) the angle between OP and OM,
theta = gamma + branch * phi.  branch = -1 is the paper's eq (7)/(7'): theta = 360 - arctg|x/y| - phi
below the x axis, 180 + arctg|x/y| - phi above it; branch = +1 is the other elbow, the one the
claw is on after folding through |OM| = R - d.  alpha = atan2(x_M + R sin theta, -(y_M + R cos theta)).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


class _Ops:
    """The functions of either world: CasADi's on symbols, numpy's on numbers."""

    sin: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    sqrt: Callable[[Any], Any]
    acos: Callable[[Any], Any]
    atan2: Callable[[Any, Any], Any]

    def __init__(self, symbolic: bool):
        self.sin, self.cos, self.sqrt = (ca.sin, ca.cos, ca.sqrt) if symbolic else (np.sin, np.cos, np.sqrt)
        self.acos = ca.acos if symbolic else np.arccos
        self.atan2 = ca.atan2 if symbolic else np.arctan2


def _ops(*xs) -> _Ops:
    return _Ops(_symbolic(*xs))


def pivot(R, theta) -> tuple[Any, Any]:
    """P, the claw pivot at the end of the arm."""
    m = _ops(R, theta)
    return -R * m.sin(theta), -R * m.cos(theta)


def claw_tip(R, d, theta, alpha) -> tuple[Any, Any]:
    """M, eq (5)-(6)."""
    m = _ops(R, d, theta, alpha)
    return -R * m.sin(theta) + d * m.sin(alpha), -R * m.cos(theta) - d * m.cos(alpha)


def roller_centre(R, r, beta, theta, alpha) -> tuple[Any, Any]:
    """N, eq (7): the roller centre at the end of the crank arm PN."""
    m = _ops(R, r, beta, theta, alpha)
    return -R * m.sin(theta) - r * m.sin(beta - alpha), -R * m.cos(theta) - r * m.cos(beta - alpha)


def fold_cosine(R, d, x, y):
    """cos phi = (R^2 + rho^2 - d^2) / (2 R rho): in [-1, 1] exactly where the arm reaches M."""
    rho2 = x * x + y * y
    return (R * R + rho2 - d * d) / (2.0 * R * _ops(x, y).sqrt(rho2))


def inverse(R, d, x, y, branch: float) -> tuple[Any, Any]:
    """(theta, alpha) putting the claw tip at M = (x, y); branch = -1 (eq 7) or +1 (the folded-over elbow).

    Undefined (NaN on floats) where |OM| lies outside [R - d, R + d]."""
    m = _ops(R, d, x, y)
    gamma = m.atan2(-x, -y)
    phi = m.acos(fold_cosine(R, d, x, y))
    theta = gamma + branch * phi
    alpha = m.atan2(x + R * m.sin(theta), -(y + R * m.cos(theta)))
    return theta, alpha


def inverse_rates(R, d, theta, alpha, slope):
    """The paper's hand-derived rates along the path y(x) (seed 003 §2): (dtheta/dx_M, dalpha/dx_M).

        dtheta/dx = (cos alpha y' - sin alpha) / (R sin(alpha + theta))
        dalpha/dx = (cos theta y' + sin theta) / (d sin(alpha + theta))
    Kept as a cross-check of the AD derivatives (tests); the kind itself differentiates by CasADi AD."""
    m = _ops(R, d, theta, alpha, slope)
    s = m.sin(alpha + theta)
    return (m.cos(alpha) * slope - m.sin(alpha)) / (R * s), (m.cos(theta) * slope + m.sin(theta)) / (d * s)

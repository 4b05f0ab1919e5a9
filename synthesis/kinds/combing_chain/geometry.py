"""The combing chain of seed 002 §四.3 (Shimamoto; eq 12-13, Fig. 22), on floats or CasADi symbols.

Frame: x along the travel direction (forward), y up, the plant's root at the origin.  The machine
moves forward at V_s; the chain leans back at theta to the ground and its tine runs up it at V_r
(relative to the machine), i.e. along (-cos theta, sin theta).  A plant of initial angle beta
(measured from the backward direction -x, so beta < 90 deg leans toward the coming machine: face
cut) is met by the tine at A, height h, a distance e ahead of the cut point C.

    at contact the root lies  D = e + h cot(beta)  ahead of C                    (problems/combing_chain/CHAIN.md)
    the cut comes when C reaches the root:  t = D / V_s
    meanwhile the tine runs  s = V_r t = K D  up the chain (K = V_r / V_s), so at the cut it sits at
        x = e - s cos(theta),   y = h + s sin(theta)    from the root,
    and the plant (root -> tine) stands at
        tan(delta) = y / (-x) = (K D sin(theta) + h) / (K D cos(theta) - e)        eq (12)
    and reaches L = |root -> tine| = (e sin(theta) + h cos(theta)) / sin(delta - theta)     eq (13)

delta depends on beta, V_s and V_r only through s = K D (the chain travel before the cut), and
falls monotonically from 180 deg - atan(h/e) (s = 0) to theta (s -> infinity).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

DEG = math.pi / 180.0


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX)) for x in xs)


def _plain(r):
    """numpy scalars as Python floats (a numpy scalar times a CasADi symbol is not a symbol)."""
    return float(r) if np.ndim(r) == 0 else r


def _atan2(y, x):
    return ca.atan2(y, x) if _symbolic(y, x) else _plain(np.arctan2(y, x))


def _sin(x):
    return ca.sin(x) if _symbolic(x) else _plain(np.sin(x))


def _cos(x):
    return ca.cos(x) if _symbolic(x) else _plain(np.cos(x))


def _tan(x):
    return ca.tan(x) if _symbolic(x) else _plain(np.tan(x))


def _sqrt(x):
    return ca.sqrt(x) if _symbolic(x) else _plain(np.sqrt(x))


def root_lead(h, e, beta_deg):
    """D = e + h cot(beta), mm: how far the root lies ahead of the cut point when the tine meets the plant."""
    b = beta_deg * DEG
    return e + h * _cos(b) / _sin(b)


def time_to_cut(h, e, beta_deg, machine_speed):
    """t = D / V_s, s (h, e in mm, V_s in m/s): from the tine meeting the plant to the cut."""
    return root_lead(h, e, beta_deg) / (1000.0 * machine_speed)


def chain_travel(chain_speed, machine_speed, h, e, beta_deg):
    """s = K D = V_r t, mm: how far the tine runs up the chain before the cut."""
    return chain_speed / machine_speed * root_lead(h, e, beta_deg)


def tine_at_cut(s, h, theta_deg, e):
    """(x, y) of the tine from the root at the cut, mm (x forward, y up)."""
    th = theta_deg * DEG
    return e - s * _cos(th), h + s * _sin(th)


def delta_of_travel(s, h, theta_deg, e):
    """The plant's angle before the cut, deg (from -x, as beta): the direction root -> tine."""
    x, y = tine_at_cut(s, h, theta_deg, e)
    return _atan2(y, -x) / DEG


def delta(chain_speed, machine_speed, h, theta_deg, e, beta_deg):
    """Eq (12), derived: delta (deg) of a plant of initial angle beta at chain speed V_r, machine speed V_s."""
    return delta_of_travel(chain_travel(chain_speed, machine_speed, h, e, beta_deg), h, theta_deg, e)


def plant_length(s, h, theta_deg, e):
    """Eq (13), first form: L = |root -> tine| at the cut, mm (a plant this long has its tip at the tine)."""
    x, y = tine_at_cut(s, h, theta_deg, e)
    return _sqrt(x * x + y * y)


# ---- the forms as printed (seed 002 eq 12, 13), for the tests and the reading -------------------------------

def delta_printed(K, h, theta_deg, e, beta_deg):
    """Eq (12) as printed: tan(delta) = (K (e + h cot beta) sin theta + h) / (K (e + h cot beta) cos theta - e),
    delta taken in (0, 180) deg (the numerator is positive)."""
    d = e + h / _tan(beta_deg * DEG)
    th = theta_deg * DEG
    num, den = K * d * _sin(th) + h, K * d * _cos(th) - e
    ang = np.arctan(num / den) / DEG
    return ang if ang > 0 else ang + 180.0


def K_printed(delta_deg, h, theta_deg, e, beta_deg):
    """Eq (12), second line as printed: K = (h + e tan delta) cos delta / ((e + h cot beta) sin(delta - theta)).
    Written as (h cos delta + e sin delta) / (...), the same where tan delta exists, so it holds at 90 deg too."""
    dl, th = delta_deg * DEG, theta_deg * DEG
    return (h * _cos(dl) + e * _sin(dl)) / (root_lead(h, e, beta_deg) * _sin(dl - th))


def K_printed_tan(delta_deg, h, theta_deg, e, beta_deg):
    """The same, literally with tan delta (undefined at delta = 90 deg)."""
    dl, th = delta_deg * DEG, theta_deg * DEG
    return (h + e * _tan(dl)) * _cos(dl) / (root_lead(h, e, beta_deg) * _sin(dl - th))


def plant_length_printed(delta_deg, h, theta_deg, e):
    """Eq (13), second form as printed: L = (e tan theta + h) / (sin delta + cos delta tan theta).
    It does not follow from the first form (see :func:`plant_length_derived`): the sign of the second
    denominator term is wrong."""
    dl, th = delta_deg * DEG, theta_deg * DEG
    return (e * _tan(th) + h) / (_sin(dl) + _cos(dl) * _tan(th))


def plant_length_derived(delta_deg, h, theta_deg, e):
    """Eq (13), second form derived: the tine's line x sin theta + y cos theta = e sin theta + h cos theta
    met by the ray at delta: L = (e tan theta + h) / (sin delta - cos delta tan theta)."""
    dl, th = delta_deg * DEG, theta_deg * DEG
    return (e * _tan(th) + h) / (_sin(dl) - _cos(dl) * _tan(th))


def delta_limits(h, theta_deg, e) -> tuple[float, float]:
    """(inf, sup) of delta over every chain speed: theta (V_r -> infinity) and 180 - atan(h/e) (V_r -> 0), deg."""
    return float(theta_deg), 180.0 - math.degrees(math.atan2(h, e))


def beta_limit(h, e) -> float:
    """The largest initial angle whose root is still ahead of the cut when the tine meets it: D(beta) > 0
    for beta < 180 - atan(h / e), deg."""
    return 180.0 - math.degrees(math.atan2(h, e))


def K_for_delta(delta_deg, h, theta_deg, e, beta_deg) -> float:
    """The speed ratio that brings a plant of initial angle beta to delta (the inverse of eq 12)."""
    return float(K_printed(delta_deg, h, theta_deg, e, beta_deg))

"""Start points of the path-synthesis multistart: a design of the right Grashof class and crank angles.

The shared Latin hypercube (synthesis.multistart) spreads the designs over the bounds; each row
becomes an IPOPT start as follows.

1. *Grashof class.*  A random set of lengths is rarely a crank-rocker, and then the loop does not
   even close at some crank angles.  The lengths are pulled along the straight line towards the
   anchor, the design of the box with the largest Grashof slack (a linear programme, solved once),
   just far enough that every slack is >= 5 % of the anchor's.  The class is a convex polytope, so
   the pulled start stays in the bounds and keeps as much of its randomness as it can.  With
   grashof = "any" the rows are pulled into the crank-rockers: a random linkage of a wide box mostly
   closes the loop at none of its start angles, and IPOPT stops at iteration 0 on NaN.
2. *Which start is what.*  Start 0 is the given design (with its crank angles, if the spec gives them).

   ============================  ==================================================================
   timing and targets            start index
   ============================  ==================================================================
   prescribed                    even: the row as it is; odd: the best placed of the row and
                                 SCREENED - 1 random designs (seeded by the seed and the index)
   free, < SCREEN_MIN_TARGETS    even: the row as it is; 2k + 1: the k-th best of the pool
   free, >= SCREEN_MIN_TARGETS   4k + 3: the k-th best distinct shape of screen.py; 4k + 1: the k-th
                                 best of the pool; even: the row as it is, its design first fitted
                                 at its own crank angles (StartPoint.timing_first)
   ============================  ==================================================================

   *Placed*: the coupler curve laid onto the targets by the best similarity (scale, turn, shift;
   Umeyama's closed form with nearest-point refinement).  The *pool*: POOL random designs (seeded by
   the seed only, so every worker builds the same pool) screened once, vectorised: each coupler curve
   against the targets at trial arc-length correspondences (POOL_PHASES phases, both directions, for
   an open arc SPANS of the curve) with the best similarity whose scale keeps the lengths in their
   bounds, then placed.  The *screen* (screen.py): thousands of normalised linkage shapes traced
   vectorised and laid onto the targets, the best ones DISTINCT apart, each finished here
   (``finish``: nearest-point crank angles on the fine curve).  Every placed or screened start of
   free timing then gets REFIT_ROUNDS alternations of a linear least-squares refit of (x0, y0, rcx,
   rcy) -- the coupler point is linear in them once the links, frame angle and crank angles are
   fixed -- and the nearest-point crank angles, while the residual falls.  The even starts keep the
   hypercube's spread: their long IPOPT trajectories reach optima the screened shapes miss (egg16,
   d_shape22: problems/fourbar_path/INEXACT.md).
3. *Crank angles (free timing).*  Each target's angle starts at the nearest point of the start's
   coupler curve, unwrapped in the crank direction.  With direction "either", start 0 and the pool
   starts take the direction whose unwrapped angles span less; the other even starts alternate
   counter-clockwise / clockwise, and so does every second screened shape (``finish``).  If the angles do not fit in one turn, they are spread over the turn in proportion to the arc
   length between the targets.  A screened shape whose crank only rocks (an open arc with
   grashof = "any": screen.py) takes the nearest points within one interval of its motion
   (``nearest_in_run``), never across a dead position.

4. *The auto order* (``--starts auto``, a screened set only: ``takes_auto_order``).  An auto run's batches grow by
   appending (synthesis.core.solve.AutoStarts), and its start i is the start of fixed index ``auto_role(i)``: the
   same kinds of start, in another order.  Start 0 is the given design and 1 .. AUTO_SCREENED the best screened
   shapes (placed and refitted, so a problem whose screened shapes fall into a few optima can stop by the rule after
   the first batch); from AUTO_SCREENED + 1 on, in blocks of four, the next screened shape, a hypercube row (with
   the continuation), the next of the pool, another hypercube row.  The hypercube rows are the core's per-index
   rows (uniform, not a Latin hypercube of the run's size), so start i does not depend on how many starts the run
   solves.  Measured on the inexact set (seeds 0-2): the rule held in no run (11-49 distinct optima at 512 starts),
   so every run solved its 512 starts once -- 0.52-0.60x the CPU of the fixed order's batches (1,008 starts), the
   same answers where both were run; a screened start costs no fewer IPOPT iterations there than the others
   (median 160 against 178 for the hypercube's), and most first hits are the hypercube's.

Measured: problems/fourbar_path/PATH.md (the synthetic-truth problems) and INEXACT.md (the
inexact set; the start mixes tried instead of this one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import casadi as ca
import numpy as np
from scipy.optimize import linprog

from synthesis.kinds.fourbar_path import screen
from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.kinds.fourbar_path.kinematics import BRANCHES, VARIABLES, coupler_function
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

TWO_PI = 2.0 * math.pi
CURVE_SAMPLES = 360
KEEP_SLACK = 0.05      # a pulled start keeps this fraction of the anchor's Grashof slack
SCREENED = 8           # candidate designs per screened start
PHASES = 12            # trial phases of the target <-> curve correspondence
ICP_ROUNDS = 5         # nearest-point refinements of the alignment
SIGNS = {"ccw": (1.0,), "cw": (-1.0,), "either": (1.0, -1.0)}
POOL = 1024            # candidate linkage shapes screened once per spec and seed (free timing)
POOL_PHASES = 24       # trial phases of the arc-length correspondence in the pool screening
SPANS = (0.25, 0.45, 0.7)   # open target arcs: trial fractions of the curve they cover
#: the screen (and the early cut, nlp.CUTS) serve target sets of at least this many points (the inexact set's 12-25);
#: smaller free-timing sets keep the pool starts and no cut: the screen's 1 s CPU is more than their
#: whole solve (10 synthetic 6-point problems: 1.4 s CPU with the pool, 6.1 s with the screen)
SCREEN_MIN_TARGETS = 12
DISTINCT = 0.05        # screened starts closer than this (nominal units: D, rad) to a better one are skipped
REFIT_ROUNDS = 4       # alternations of the linear refit of (x0, y0, rcx, rcy) and the nearest angles
CLOSING_GAP = 2.5      # targets form a loop when last -> first is at most this x the median gap
#: the screen (screen.py) and the pool rank their shapes against at most this many of the targets, spread evenly
#: through their order (ranking_targets); every start is then placed and finished on all of them.  The screen's
#: coarse curves have screen.GRID = 128 samples, so more targets than this refine no ranking, they only cost time
#: and memory: a 1,000-point set screened whole took 99 s and 4.3 GB (INEXACT.md, "Many targets").  A set of at
#: most this many is ranked on every target, as it always was
RANKING_TARGETS = 100
#: the auto order (``auto_role``): starts 1 .. AUTO_SCREENED are the best screened shapes, the auto run's first batch
#: (AutoStarts.first = 16) the given design and these only
AUTO_SCREENED = 15

#: the Grashof class as rows  A @ (r1, r2, r3, r4) >= 0  (synthesis.kinds.fourbar_path.rules.grashof_class)
CLASS_ROWS = {
    "crank-rocker": np.array([[-1, -1, 1, 1], [1, -1, -1, 1], [1, -1, 1, -1]], dtype=float),
    "double-crank": np.array([[-1, -1, 1, 1], [-1, 1, -1, 1], [-1, 1, 1, -1]], dtype=float),
}


@dataclass(frozen=True)
class StartPoint:
    design: np.ndarray       # r1..theta0, spec units
    theta: np.ndarray        # crank angle of each target, rad (empty for prescribed timing)
    sign: float              # +1 counter-clockwise, -1 clockwise
    #: an unplaced start of a screened set (a Latin-hypercube design and its curve's nearest crank angles): the NLP
    #: first fits the design at these crank angles, then frees them (nlp.TIMING_FIRST)
    timing_first: bool = False


# ---------------------------------------------------------------------------- Grashof class

def grashof_anchor(bounds: np.ndarray, grashof: str) -> tuple[np.ndarray, float] | None:
    """(lengths r1..r4 maximising the smallest class slack within the bounds, that slack); None for "any"."""
    if grashof not in CLASS_ROWS:
        return None
    a = CLASS_ROWS[grashof]
    # maximise t  s.t.  a @ r >= t, i.e.  -a @ r + t <= 0
    res = linprog(c=[0, 0, 0, 0, -1], A_ub=np.hstack([-a, np.ones((3, 1))]), b_ub=np.zeros(3),
                  bounds=[tuple(b) for b in bounds[:4]] + [(None, None)], method="highs")
    return np.asarray(res.x[:4]), float(-res.fun)


def pull_into_class(lengths: np.ndarray, anchor: np.ndarray, keep: float, grashof: str) -> np.ndarray:
    """The point of the segment anchor -> lengths nearest to ``lengths`` whose class slacks are >= keep."""
    a = CLASS_ROWS[grashof]
    s_start, s_anchor = a @ lengths, a @ anchor
    lam = 1.0
    for s1, s0 in zip(s_start, s_anchor):
        if s1 < keep:        # the slack along the segment is s0 + lam (s1 - s0), linear in lam
            lam = min(lam, (s0 - keep) / (s0 - s1))
    return anchor + max(lam, 0.0) * (lengths - anchor)


# ---------------------------------------------------------------------------- coupler curve

@lru_cache(maxsize=4)
def _curve_function(branch: int) -> ca.Function:
    return coupler_function(branch).map(CURVE_SAMPLES)


def _parameters(design: np.ndarray) -> np.ndarray:
    p = np.array(design, dtype=float)
    p[8] = math.radians(p[8])
    return p


def coupler_curve(design: np.ndarray, branch: int) -> tuple[np.ndarray, np.ndarray]:
    """(angles, (2, n) points) of the coupler curve over a turn, NaN where the loop does not close."""
    angles = np.linspace(0.0, TWO_PI, CURVE_SAMPLES, endpoint=False)
    return angles, np.asarray(_curve_function(branch)(angles.reshape(1, -1), _parameters(design))[0])


def points_at(design: np.ndarray, theta: np.ndarray, branch: int) -> np.ndarray:
    """(n, 2) coupler points at the crank angles ``theta`` (rad)."""
    return np.asarray(coupler_function(branch)(np.reshape(theta, (1, -1)), _parameters(design))[0]).T


# ---------------------------------------------------------------------------- crank angles

def unwrap_in_direction(angles: np.ndarray, sign: float) -> np.ndarray:
    """Angles unwrapped so each follows the previous one in direction ``sign`` by less than a turn."""
    out = [float(angles[0])]
    for a in angles[1:]:
        out.append(out[-1] + sign * ((sign * (a - out[-1])) % TWO_PI))
    return np.array(out)


def spread_by_arc_length(targets: np.ndarray, first: float, sign: float) -> np.ndarray:
    """Angles over one turn in proportion to the arc length along the closed polygon of the targets."""
    closed = np.vstack([targets, targets[:1]])
    seg = np.hypot(*np.diff(closed, axis=0).T)
    total = seg.sum()
    if total > 0:
        frac = np.concatenate([[0.0], np.cumsum(seg[:-1])]) / total
    else:
        frac = np.arange(len(targets)) / len(targets)
    return first + sign * TWO_PI * frac


def _nearest_samples(angles: np.ndarray, pos: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(angle of the nearest of the curve samples pos (2, K) at ``angles`` to each target, its squared distance)."""
    d2 = (pos[0][None, :] - targets[:, :1]) ** 2 + (pos[1][None, :] - targets[:, 1:]) ** 2
    d2 = np.where(np.isfinite(d2), d2, np.inf)
    k = np.argmin(d2, axis=1)
    return angles[k], d2[np.arange(len(targets)), k]


def nearest_angles(design: np.ndarray, targets: np.ndarray, branch: int) -> tuple[np.ndarray, np.ndarray]:
    """(angle of the nearest curve sample to each target, its squared distance), mm^2."""
    return _nearest_samples(*coupler_curve(design, branch), targets)


def shape_of(design: np.ndarray) -> np.ndarray:
    """(1, 6) the design's shape normalised to r1 = 1 (screen's form)."""
    return (np.asarray(design[:6], dtype=float) / design[0])[None, :]


def nearest_in_run(design: np.ndarray, targets: np.ndarray, branch: int) -> tuple[np.ndarray, np.ndarray]:
    """nearest_angles for a linkage whose crank only rocks: every target's nearest point within one interval of
    crank angles over which the loop closes (screen.rocking_runs; the one nearer to the targets in sum), so the
    crank reaches every target without passing a dead position; inf where the loop closes nowhere."""
    _, first, last = screen.rocking_runs(shape_of(design))
    best = (np.full(len(targets), math.inf), np.full(len(targets), math.inf))
    for a, b in zip(first, last):
        angles = screen.run_angles(a, b, CURVE_SAMPLES)
        found = _nearest_samples(angles, points_at(design, angles, branch).T, targets)
        if np.sum(found[1]) < np.sum(best[1]):
            best = found
    return best


def ordered_angles(nearest: np.ndarray, targets: np.ndarray, direction: str) -> tuple[np.ndarray, float]:
    """(crank angles in order within one turn, direction sign) starting from the nearest-point angles."""
    options = []
    for s in SIGNS[direction]:
        th = unwrap_in_direction(nearest, s)
        options.append((abs(th[-1] - th[0]), -s, th))       # ties go to counter-clockwise
    span, neg_sign, theta = min(options, key=lambda o: (o[0], o[1]))
    sign = -neg_sign
    if span > TWO_PI * (1.0 - 0.5 / len(targets)):
        theta = spread_by_arc_length(targets, float(nearest[0]), sign)
    return theta, sign


# ---------------------------------------------------------------------------- alignment

def similarity(src: np.ndarray, dst: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(scale s, rotation a, translation t) minimising sum |s R(a) src_i + t - dst_i|^2 (no reflection).

    For 2-D points written as complex numbers the optimum is z = <a, b> / <a, a> of the centred
    sets: s = |z|, a = arg z (Umeyama 1991, in the plane).
    """
    mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
    za = (src[:, 0] - mu_s[0]) + 1j * (src[:, 1] - mu_s[1])
    zb = (dst[:, 0] - mu_d[0]) + 1j * (dst[:, 1] - mu_d[1])
    z = np.vdot(za, zb) / max(np.vdot(za, za).real, 1e-300)
    s, ang = abs(z), float(np.angle(z))
    t = mu_d - s * _rotation(ang) @ mu_s
    return s, ang, t


def _rotation(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def _fit(curve: np.ndarray, idx: np.ndarray, targets: np.ndarray) -> tuple[float, tuple]:
    """Residual and similarity of the best fit of curve[idx] onto the targets."""
    src = curve[idx]
    s, a, t = similarity(src, targets)
    moved = s * src @ _rotation(a).T + t
    return float(np.sum((moved - targets) ** 2)), (s, a, t)


def align(curve: np.ndarray, targets: np.ndarray, signs: tuple, timed_idx: np.ndarray | None):
    """(curve sample of each target, similarity) that lays the curve on the targets.

    Prescribed timing fixes the correspondence.  Free timing tries PHASES phases of the arc-length
    spread in each allowed direction, then refines the best one by nearest points (ICP).
    """
    if timed_idx is not None:
        return timed_idx, _fit(curve, timed_idx, targets)[1]
    n = len(curve)
    frac = spread_by_arc_length(targets, 0.0, 1.0) / TWO_PI
    best = None
    for sign in signs:
        for k in range(PHASES):
            idx = np.round((k / PHASES + sign * frac) * n).astype(int) % n
            res, sim = _fit(curve, idx, targets)
            if best is None or res < best[0]:
                best = (res, idx, sim)
    assert best is not None, "SIGNS gives every direction at least one turning sense"
    _, idx, sim = best
    for _ in range(ICP_ROUNDS):
        s, a, t = sim
        moved = s * curve @ _rotation(a).T + t
        idx = np.argmin(((moved[None, :, :] - targets[:, None, :]) ** 2).sum(axis=2), axis=1)
        sim = _fit(curve, idx, targets)[1]
    return idx, sim


def _scale_limits(values: np.ndarray, bounds: np.ndarray) -> tuple[float, float]:
    """The range of s with lo <= s * v <= hi for every (v, [lo, hi]); (1, 1) when there is none."""
    lo_s, hi_s = 0.0, math.inf
    for v, (lo, hi) in zip(values, bounds):
        if v > 0:
            lo_s, hi_s = max(lo_s, lo / v), min(hi_s, hi / v)
        elif v < 0:
            lo_s, hi_s = max(lo_s, hi / v), min(hi_s, lo / v)
        elif not lo <= 0.0 <= hi:
            return 1.0, 1.0
    return (lo_s, hi_s) if lo_s <= hi_s else (1.0, 1.0)


def moved_design(design: np.ndarray, bounds: np.ndarray, sim: tuple, mean_src: np.ndarray,
                 mean_dst: np.ndarray) -> np.ndarray:
    """The design whose coupler curve is the similarity ``sim`` of the given one, kept within the bounds."""
    s, a, _ = sim
    lo_s, hi_s = _scale_limits(design[:6], bounds[:6])
    s = min(max(s, lo_s), hi_s)
    theta0 = design[8] + math.degrees(a)
    lo, hi = bounds[8]
    if hi - lo >= 360.0:                        # a full circle of frame angles: wrap into it
        theta0 = lo + (theta0 - lo) % 360.0
    theta0 = min(max(theta0, lo), hi)
    rot = _rotation(math.radians(theta0 - design[8]))    # the turn that is left after the bounds
    t = mean_dst - s * rot @ mean_src           # refit the translation for that scale and turn
    out = design.copy()
    out[:6] *= s
    out[6:8] = s * rot @ design[6:8] + t
    out[8] = theta0
    return np.clip(out, bounds[:, 0], bounds[:, 1])


def refit_placement(design: np.ndarray, theta: np.ndarray, targets: np.ndarray, bounds: np.ndarray,
                    branch: int) -> np.ndarray:
    """The design with (x0, y0, rcx, rcy) refitted to the targets at the crank angles ``theta``.

    With the links, the frame angle and the crank angles fixed, the coupler point P = O + A + (rcx + i rcy) u
    (complex; u the unit vector A -> B) is linear in O = x0 + i y0 and rcx + i rcy: a 2-unknown complex
    least-squares problem, solved in closed form, its answer clipped to the bounds."""
    d = {name: design[k] for k, name in enumerate(VARIABLES)}
    d.update(x0=0.0, y0=0.0)
    j = joint_positions(d, theta, branch)
    a, u = j["A"], (j["B"] - j["A"]) / design[2]
    t = targets[:, 0] + 1j * targets[:, 1]
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(u))):
        return design
    m = np.column_stack([np.ones_like(u), u])
    sol, *_ = np.linalg.lstsq(m, t - a, rcond=None)
    out = design.copy()
    out[6], out[7], out[4], out[5] = sol[0].real, sol[0].imag, sol[1].real, sol[1].imag
    return np.clip(out, bounds[:, 0], bounds[:, 1])


# ---------------------------------------------------------------------------- the screened pool

def is_closed_loop(targets: np.ndarray) -> bool:
    """Whether the targets go round a loop: the gap from the last back to the first is at most
    CLOSING_GAP x the median gap between neighbours."""
    gaps = np.hypot(*np.diff(targets, axis=0).T)
    return bool(np.hypot(*(targets[0] - targets[-1])) <= CLOSING_GAP * np.median(gaps))


def ranking_targets(targets: np.ndarray) -> np.ndarray:
    """The targets the screen and the pool rank shapes against: all of them up to RANKING_TARGETS, else
    RANKING_TARGETS of them evenly spread through the given order, the first and the last among them."""
    if len(targets) <= RANKING_TARGETS:
        return targets
    return targets[np.round(np.linspace(0.0, len(targets) - 1.0, RANKING_TARGETS)).astype(int)]


def arc_fractions(targets: np.ndarray, closed: bool) -> np.ndarray:
    """Each target's fraction of the arc length along the polygon of the targets (closed: of the loop)."""
    pts = np.vstack([targets, targets[:1]]) if closed else targets
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    if cum[-1] <= 0:
        return np.arange(len(targets)) / len(targets)
    return (cum[:-1] if closed else cum) / cum[-1]


def pool_curves(designs: np.ndarray, branch: int) -> np.ndarray:
    """(M, CURVE_SAMPLES) complex coupler curves of M designs over a turn (NaN where the loop is open);
    vectorised numpy (the construction of construction.py, the same branch convention)."""
    angles = np.linspace(0.0, TWO_PI, CURVE_SAMPLES, endpoint=False)
    d = {name: designs[:, k:k + 1] for k, name in enumerate(VARIABLES)}
    return joint_positions(d, angles[None, :], branch)["P"]


def scale_limits(designs: np.ndarray, bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per design the range [lo, hi] of scale factors s with s * (r1..r4, rcx, rcy) within the bounds."""
    v = designs[:, :6]
    lo_b, hi_b = bounds[:6, 0], bounds[:6, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = lo_b / v, hi_b / v
    lo = np.where(v > 0, a, np.where(v < 0, b, 0.0))
    hi = np.where(v > 0, b, np.where(v < 0, a, np.inf))
    return np.max(lo, axis=1), np.min(hi, axis=1)


def correspondences(targets: np.ndarray, signs: tuple, closed: bool) -> np.ndarray:
    """(C, N) trial curve fractions (of the curve's arc length) of the targets: PHASES phases in each
    direction; an open arc also spans SPANS of the curve."""
    frac = arc_fractions(targets, closed)
    rows = []
    for sign in signs:
        for span in ((1.0,) if closed else SPANS):
            for k in range(POOL_PHASES):
                rows.append((k / POOL_PHASES + sign * span * frac) % 1.0)
    return np.array(rows)


def pool_residuals(curves: np.ndarray, targets: np.ndarray, u: np.ndarray, s_lo: np.ndarray,
                   s_hi: np.ndarray) -> np.ndarray:
    """Per curve the smallest residual of the targets against the curve points at arc-length
    fractions u (each row one trial), after the best similarity with its scale within [s_lo, s_hi];
    inf for a curve that does not close over the whole turn."""
    zb = targets[:, 0] + 1j * targets[:, 1]
    zb = zb - zb.mean()
    bb = float(np.sum(np.abs(zb) ** 2))
    out = np.full(len(curves), np.inf)
    n = curves.shape[1]
    for m, c in enumerate(curves):
        if not np.all(np.isfinite(c)):
            continue
        seg = np.abs(np.diff(np.append(c, c[0])))
        s = np.concatenate([[0.0], np.cumsum(seg)])
        if s[-1] <= 0:
            continue
        idx = np.rint(np.interp(u, s / s[-1], np.arange(n + 1))).astype(int) % n
        za = c[idx]
        za = za - za.mean(axis=1, keepdims=True)
        aa = np.sum(np.abs(za) ** 2, axis=1)
        cross = np.abs(np.sum(np.conj(za) * zb, axis=1))
        scale = np.clip(cross / np.maximum(aa, 1e-300), s_lo[m], s_hi[m])
        out[m] = float(np.min(bb - 2.0 * scale * cross + scale ** 2 * aa))
    return out


# ---------------------------------------------------------------------------- the starts

def takes_auto_order(spec: FourbarPathSpec) -> bool:
    """Whether ``--starts auto`` numbers this spec's starts in the auto order (``auto_role``): free timing with
    at least SCREEN_MIN_TARGETS targets, the sets that are screened (StartMaker.screening)."""
    return spec.targets.crank_deg is None and len(spec.targets.points) >= SCREEN_MIN_TARGETS


def auto_role(index: int) -> int:
    """The fixed-order index whose kind of start the auto order's start ``index`` is (module docstring, 4): 0 the
    given design; 1 .. AUTO_SCREENED the screened shapes of rank 1 .. AUTO_SCREENED (fixed 3, 7, ...); then blocks of
    four: the next screened shape, a hypercube start, the next of the pool (fixed 1, 5, ...), a hypercube start (the
    k-th hypercube start of the auto order is fixed index 2 (k + 1), its crank direction alternating as there)."""
    if index <= AUTO_SCREENED:
        return 4 * index - 1 if index > 0 else 0
    block, slot = divmod(index - AUTO_SCREENED - 1, 4)
    if slot == 0:
        return 4 * (AUTO_SCREENED + 1 + block) - 1
    if slot == 2:
        return 4 * block + 1
    return 2 * (2 * block + (slot == 3) + 1)

_SCREENED: dict = {}      # the last screened list of this process (StartMaker.screened)


def forget_screened() -> None:
    """Drop this process's screened list, so the next StartMaker screens afresh (a study timing the screen)."""
    _SCREENED.clear()


def distinct(designs: np.ndarray, residuals: np.ndarray, size: float,
             keep: int = 512) -> tuple[np.ndarray, np.ndarray]:
    """The first ``keep`` designs (in the given order) each farther than DISTINCT (max-norm, nominal units:
    lengths / the targets' size, theta0 in rad) from every one kept before it."""
    unit = np.array([size] * 8 + [180.0 / math.pi])
    z = designs / unit
    kept: list[int] = []
    for i in range(len(z)):
        if len(kept) >= keep:
            break
        if kept:
            gap = np.abs(z[kept] - z[i])
            gap[:, 8] = np.minimum(gap[:, 8], TWO_PI - gap[:, 8])
            if np.min(np.max(gap, axis=1)) <= DISTINCT:
                continue
        kept.append(i)
    return designs[kept], residuals[kept]


class StartMaker:
    """Turns a Latin-hypercube row into an IPOPT start; built once per spec and seed."""

    def __init__(self, spec: FourbarPathSpec, seed: int, auto_order: bool = False):
        self.spec = spec
        self.seed = seed
        self.bounds = np.array(spec.bounds_array(), dtype=float)
        self.targets = np.array(spec.targets.points, dtype=float)
        self.branch = BRANCHES[spec.branch]
        self.anchor = grashof_anchor(self.bounds, spec.rules.grashof)
        self.timed_theta = None if spec.targets.crank_deg is None else np.radians(spec.targets.crank_deg)
        self.closed = is_closed_loop(self.targets)
        self.ranking = ranking_targets(self.targets)      # what the screen and the pool rank shapes against
        self.pool_grashof = "crank-rocker" if spec.rules.grashof == "any" else spec.rules.grashof
        self.pool_anchor = grashof_anchor(self.bounds, self.pool_grashof)
        self._ranked: np.ndarray | None = None
        self._screened: tuple[np.ndarray, np.ndarray] | None = None
        self.screening = self.timed_theta is None and len(self.targets) >= SCREEN_MIN_TARGETS
        #: an auto run's starts (``auto_role``): only where ``takes_auto_order`` (the screened sets)
        self.auto_order = auto_order and takes_auto_order(spec)

    def in_class(self, design: np.ndarray) -> np.ndarray:
        out = np.array(design, dtype=float)
        if self.anchor is not None and self.anchor[1] > 0:
            out[:4] = pull_into_class(out[:4], self.anchor[0], KEEP_SLACK * self.anchor[1], self.spec.rules.grashof)
        elif self.anchor is None and self.pool_anchor is not None and self.pool_anchor[1] > 0:
            # grashof = "any": a crank-rocker start closes the loop at every crank angle (a random one
            # often closes at none of the start angles, and IPOPT stops at iteration 0 on NaN)
            out[:4] = pull_into_class(out[:4], self.pool_anchor[0], KEEP_SLACK * self.pool_anchor[1], self.pool_grashof)
        return out

    def __call__(self, index: int, x: np.ndarray) -> StartPoint:
        if self.auto_order and index > 0:         # the auto order's start is this kind of the fixed order's
            index = auto_role(index)
        design = self.in_class(x)
        if index == 0 and self.spec.design.crank_deg is not None:
            given = np.radians(self.spec.design.crank_deg)
            return StartPoint(design, given, 1.0 if given[-1] >= given[0] else -1.0)
        if self.screening and index % 4 == 3:          # 3, 7, 11, ...: the screened shapes, best first
            return self.from_screen((index + 1) // 4)
        if self.screening and index % 4 == 1:          # 1, 5, 9, ...: the pool, best first
            return self.placed(self.ranked[((index - 1) // 4) % len(self.ranked)], 0)[1]
        if self.timed_theta is None and not self.screening and index % 2 == 1:
            return self.from_pool(index)
        if index % 2 == 0:
            start = self.as_it_is(design, index)
            return replace(start, timing_first=self.screening and index > 0)     # screened: free timing
        rng = np.random.default_rng([self.seed, index])
        lo, hi = self.bounds[:, 0], self.bounds[:, 1]
        candidates = [design] + [self.in_class(lo + rng.random(len(lo)) * (hi - lo)) for _ in range(SCREENED - 1)]
        scored = [self.placed(c, index) for c in candidates]
        return min(scored, key=lambda pair: pair[0])[1]

    @property
    def ranked(self) -> np.ndarray:
        """The pool of candidate designs, best placement residual first (built on first use)."""
        if self._ranked is None:
            rng = np.random.default_rng([self.seed, 19])
            lo, hi = self.bounds[:, 0], self.bounds[:, 1]
            designs = np.array([self.pool_class(lo + rng.random(len(lo)) * (hi - lo)) for _ in range(POOL)])
            curves = pool_curves(designs, self.branch)
            s_lo, s_hi = scale_limits(designs, self.bounds)
            u = correspondences(self.ranking, SIGNS[self.spec.rules.direction], self.closed)
            res = pool_residuals(curves, self.ranking, u, s_lo, s_hi)
            order = np.argsort(res, kind="stable")
            self._ranked = designs[order[np.isfinite(res[order])]]
            if len(self._ranked) == 0:
                self._ranked = designs
        return self._ranked

    @property
    def screened(self) -> tuple[np.ndarray, np.ndarray]:
        """(designs, residual mm^2 on the ranking targets) of the best distinct screened shapes, best first (screen.py
        on ``ranking``; one list per spec and seed, cached per process: a forked worker inherits its parent's)."""
        if self._screened is None:
            key = (self.targets.tobytes(), self.bounds.tobytes(), self.branch, self.spec.rules.grashof,
                   self.spec.rules.direction, self.seed)
            if key not in _SCREENED:
                designs, res = screen.screen(self.ranking, self.bounds, self.branch, self.spec.rules.grashof,
                                             SIGNS[self.spec.rules.direction], self.closed,
                                             arc_fractions(self.ranking, self.closed), self.seed)
                _SCREENED.clear()
                _SCREENED[key] = distinct(designs, res, float(np.max(np.ptp(self.targets, axis=0))) or 1.0)
            self._screened = _SCREENED[key]
        return self._screened

    @property
    def reference(self) -> float | None:
        """The path error (mm^2) of the best screened start (the early cut's yardstick); None: no screening."""
        if not self.screening:
            return None
        designs, _ = self.screened
        if len(designs) == 0:
            return None
        residual = self.finish(designs[0], 1)[0]
        return residual if math.isfinite(residual) else None

    def from_screen(self, index: int) -> StartPoint:
        """Start ``index`` (>= 1): the (index - 1)-th best distinct screened shape, its crank angles the
        nearest points of its coupler curve and (x0, y0, rcx, rcy) refitted to them (``finish``)."""
        designs, _ = self.screened
        if len(designs) == 0:
            return self.from_pool(index)
        return self.finish(designs[(index - 1) % len(designs)], index)[1]

    def finish(self, design: np.ndarray, index: int = 0) -> tuple[float, StartPoint]:
        """(residual mm^2, start) of a placed design: nearest-point crank angles on the fine curve, then
        REFIT_ROUNDS linear refits of (x0, y0, rcx, rcy) while the residual falls.  ``index`` is the screened
        shape's rank + 1 (from_screen): with direction "either" an even rank unwraps its angles in the direction
        ``direction(index)`` gives, counter-clockwise and clockwise in turn, as the unscreened starts do -- a spread
        measured to reach the best known more often than the best-fitting direction for every shape (INEXACT.md)
        --, except a shape whose crank only rocks: the order of its angles within its one interval of
        motion is its direction (forced to the spec's when the spec fixes one)."""
        moved = np.clip(design, self.bounds[:, 0], self.bounds[:, 1])
        rocking = len(screen.rocking_runs(shape_of(moved))[0]) > 0
        nearest_of = nearest_in_run if rocking else nearest_angles
        nearest, d2 = nearest_of(moved, self.targets, self.branch)
        for _ in range(REFIT_ROUNDS):
            refit = refit_placement(moved, nearest, self.targets, self.bounds, self.branch)
            near2, e2 = nearest_of(refit, self.targets, self.branch)
            if not np.sum(e2) < np.sum(d2):
                break
            moved, nearest, d2 = refit, near2, e2
        if rocking:       # the crank only rocks: the angles stay as found, in one interval of its motion
            allowed = SIGNS[self.spec.rules.direction]        # not direction(index): see the docstring
            sign = (1.0 if nearest[-1] >= nearest[0] else -1.0) if len(allowed) > 1 else allowed[0]
            theta = nearest
        else:
            theta, sign = ordered_angles(nearest, self.targets, self.direction(index))
        residual = float(np.sum(d2))
        return (residual if math.isfinite(residual) else math.inf), StartPoint(moved, theta, sign)

    def pool_class(self, design: np.ndarray) -> np.ndarray:
        """A pool candidate of a class whose crank turns fully (for "any": a crank-rocker)."""
        out = np.array(design, dtype=float)
        if self.pool_anchor is not None and self.pool_anchor[1] > 0:
            out[:4] = pull_into_class(out[:4], self.pool_anchor[0], KEEP_SLACK * self.pool_anchor[1],
                                      self.pool_grashof)
        return out

    def from_pool(self, index: int) -> StartPoint:
        ranked = self.ranked
        k = (index - 1) // 2
        return self.placed(ranked[k % len(ranked)], 0)[1]

    def direction(self, index: int) -> str:
        """The crank direction a start may take: the spec's, or for "either" on the unscreened starts
        after start 0, counter-clockwise and clockwise in turn (starts 4, 8, ... and 2, 6, ...)."""
        d = self.spec.rules.direction
        if d == "either" and index > 0 and index % 2 == 0:
            return "ccw" if index % 4 == 0 else "cw"
        return d

    def as_it_is(self, design: np.ndarray, index: int = 0) -> StartPoint:
        if self.timed_theta is not None:
            return StartPoint(design, np.zeros(0), 1.0)
        nearest, _ = nearest_angles(design, self.targets, self.branch)
        theta, sign = ordered_angles(nearest, self.targets, self.direction(index))
        return StartPoint(design, theta, sign)

    def placed(self, design: np.ndarray, index: int = 0) -> tuple[float, StartPoint]:
        """(fit residual, start) of the design with its coupler curve moved onto the targets."""
        angles, pos = coupler_curve(design, self.branch)
        ok = np.all(np.isfinite(pos), axis=0)
        if ok.sum() < CURVE_SAMPLES // 2:             # grashof = "any": too little of a curve to place
            return math.inf, self.as_it_is(design, index)
        angles, curve = angles[ok], pos[:, ok].T
        timed_idx = None
        if self.timed_theta is not None:
            gap = (angles[None, :] - self.timed_theta[:, None] + math.pi) % TWO_PI - math.pi
            timed_idx = np.argmin(np.abs(gap), axis=1)
        idx, sim = align(curve, self.targets, SIGNS[self.direction(index)], timed_idx)
        moved = moved_design(design, self.bounds, sim, curve[idx].mean(axis=0), self.targets.mean(axis=0))
        if self.timed_theta is not None:
            d2 = np.sum((points_at(moved, self.timed_theta, self.branch) - self.targets) ** 2, axis=1)
            start = StartPoint(moved, np.zeros(0), 1.0)
        else:
            nearest, d2 = nearest_angles(moved, self.targets, self.branch)
            for _ in range(REFIT_ROUNDS):
                refit = refit_placement(moved, nearest, self.targets, self.bounds, self.branch)
                near2, e2 = nearest_angles(refit, self.targets, self.branch)
                if not np.sum(e2) < np.sum(d2):
                    break
                moved, nearest, d2 = refit, near2, e2
            theta, sign = ordered_angles(nearest, self.targets, self.direction(index))
            start = StartPoint(moved, theta, sign)
        residual = float(np.sum(d2))
        return (residual if math.isfinite(residual) else math.inf), start

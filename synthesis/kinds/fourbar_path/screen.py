"""Screening of candidate linkage shapes for free-timing path synthesis.

The fastest published path-synthesis methods do not start a local optimiser from random designs: they
screen many cheap candidate *shapes* and start it only from the best few.  A shape is a four-bar in a
normalised frame -- input pivot O = 0, output pivot O' = 1 (r1 = 1, theta0 = 0) -- with link ratios
r2, r3, r4 and the coupler point (rcx, rcy) in that unit.  Its coupler curve c(theta2) is traced,
vectorised in numpy over a crank-angle grid, for every shape at once (construction.joint_positions,
the spec's assembly branch).  The targets t_i are laid onto it by a similarity z -> a z + b (a complex:
scale |a| and turn arg a; b the image of O): with the correspondence fixed, the best (a, b) is a
complex linear least-squares solve in closed form (Umeyama in the plane); with free timing the
correspondence is the nearest curve point of each target, so the fit alternates the two (a few ICP
rounds), starting from the best of trial arc-length correspondences (phases, both directions, for an
open target arc several spans of the curve).  |a| is kept within the scales that put every length of
the shape in its bounds, b within the input pivot's bounds.  The shapes are ranked by the residual
sum |a c(theta_i) + b - t_i|^2 (mm^2, the NLP's objective), and the best are the starts: design =
the shape scaled by |a|, turned by arg a, shifted to b; crank angles = each target's nearest curve
parameter (refined by starts.StartMaker on the fine curve).

An open target arc with grashof = "any" needs no full turn: it is also laid onto ROCKING shapes of any class whose
crank only rocks, each over an interval of crank angles where its loop closes (``rocking_runs``, in closed form;
sampled on a cosine grid, ``run_angles``), the targets' arc lengths along that open curve (``open_trials``).  The
two families are ranked together.

Everything is a function of the spec and the seed (numpy's generator seeded by [seed, SEED_TAG]), so
every worker screens the same shapes and gets the same list; the list is cached per process (a forked
worker inherits the one its parent made when it built the NLP).
"""

from __future__ import annotations

import math
import multiprocessing
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from synthesis.core.executor import default_workers
from synthesis.kinds.fourbar_path.construction import joint_positions

SHAPES = 12000         # candidate shapes screened per spec and seed
GRID = 128             # crank-angle samples of each coarse coupler curve
PHASES = 24            # trial phases of the arc-length correspondence
SPANS = (0.2, 0.35, 0.5, 0.7)   # open target arcs: trial fractions of the curve they cover
ICP_ROUNDS = 4         # nearest-point / similarity alternations on the coarse curves
SEED_TAG = 1919        # the shapes' generator is seeded by [seed, SEED_TAG]
#: shapes per vectorised block (memory: CHUNK x targets x GRID complex numbers).  Each shape's row is computed by the
#: same operations whatever block holds it, so the list is the same for any CHUNK; 64 keeps a block's arrays (13 MB at
#: the 100 targets the screen ranks at most: starts.RANKING_TARGETS) near the cache: 512 took twice the CPU seconds at
#: 100 targets (5.3 s against 2.7 s) and 1.4 times at 25 (1.05 s against 0.76 s)
CHUNK = 64
#: threads that screen the blocks (None: the CPUs this process may use, at most MAX_THREADS; 1 in a worker process,
#: whose sibling workers hold the other cores).  The screen runs in the main process before the workers start, so
#: alone it held the run's other cores idle (0.55-1.6 s of the ten inexact problems' 2.2-8 s runs on 2 cores); numpy
#: releases the GIL in its array loops, and each block is computed by the same operations on the same rows whatever
#: thread runs it, so the list is the same for any thread count (tests/test_fourbar_path_inexact.py).  Each thread
#: holds one block (CHUNK)
THREADS: int | None = None
MAX_THREADS = 4
TWO_PI = 2.0 * math.pi


def _log_uniform(rng, lo: float, hi: float, n: int) -> np.ndarray:
    return np.exp(rng.uniform(math.log(lo), math.log(hi), n))


def _draw_coupler_points(rng: np.random.Generator, out: np.ndarray) -> None:
    """Fill the coupler points (rcx, rcy) = out[:, 4:6] of shapes (r1 = 1, r2, r3, r4 in out[:, :4]): polar about the
    crank pin A, the radius a log-uniform multiple of the coupler r3 (half of the shapes) or of the frame r1 (the
    other half), the angle uniform."""
    n = len(out)
    rad = np.where(rng.random(n) < 0.5, out[:, 2] * _log_uniform(rng, 0.1, 4.0, n), _log_uniform(rng, 0.02, 2.0, n))
    ang = rng.uniform(0.0, TWO_PI, n)
    out[:, 4], out[:, 5] = rad * np.cos(ang), rad * np.sin(ang)


def sample_shapes(rng: np.random.Generator, n: int, grashof: str) -> np.ndarray:
    """(n, 6) normalised shapes (r1 = 1, r2, r3, r4, rcx, rcy) whose crank turns fully: crank-rockers
    (r2 shortest, s + l <= p + q) or, for "double-crank" and a quarter of "any", double-cranks (r1 shortest)."""
    out = np.empty((n, 6))
    kinds = np.zeros(n, dtype=int)                 # 0 crank-rocker, 1 double-crank
    if grashof == "double-crank":
        kinds[:] = 1
    elif grashof == "any":
        kinds[rng.random(n) < 0.25] = 1
    r3 = _log_uniform(rng, 0.04, 5.0, n)
    r4 = _log_uniform(rng, 0.04, 5.0, n)
    frac = rng.uniform(0.06, 0.95, n)
    # crank-rocker: r1 = 1, r3, r4 drawn, r2 the shortest with room s + l <= p + q
    others = np.column_stack([np.ones(n), r3, r4])
    longest = others.max(axis=1)
    room = np.minimum(others.min(axis=1), others.sum(axis=1) - 2.0 * longest)
    r2_cr = frac * room
    # double-crank: the frame r1 = 1 shortest; r2, r3, r4 >= 1 with l + 1 <= p + q
    r2_dc = _log_uniform(rng, 1.05, 4.0, n)
    ok_cr = room > 0.02
    out[:, 0] = 1.0
    out[:, 1] = np.where(kinds == 0, r2_cr, r2_dc)
    out[:, 2] = np.where(kinds == 0, r3, np.maximum(r3, 1.05))
    out[:, 3] = np.where(kinds == 0, r4, np.maximum(r4, 1.05))
    lengths = out[:, :4]
    s, l = lengths.min(axis=1), lengths.max(axis=1)
    grashof_ok = s + l <= lengths.sum(axis=1) - s - l - 0.02
    valid = np.where(kinds == 0, ok_cr, grashof_ok)
    _draw_coupler_points(rng, out)
    return out[valid]


#: the share of the shapes drawn in units of the crank (sample_long_shapes) rather than of the frame
LONG_SHARE = 0.5
#: their longest link, in crank lengths
LONG = 30.0


def sample_long_shapes(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 6) crank-rockers drawn in units of the crank (r2 = 1), returned normalised to r1 = 1.  The frame-unit
    draw above rarely makes a crank much shorter than the frame, so it rarely proposes the linkages a wide box
    favours: a short crank driving long links (frame and rocker 10-17 cranks on the inexact set's best designs,
    the frame at its upper bound, close to a slider-crank).  Here two links p, q are log-uniform in [1.2, LONG]
    cranks, the third l uniform in [max(p, q), p + q - 1] (the crank shortest and s + l <= p + q: Grashof), the
    three dealt to frame, coupler and rocker in a random order; the coupler point polar about the crank pin,
    its radius log-uniform in [0.3, LONG] cranks."""
    p = _log_uniform(rng, 1.2, LONG, n)
    q = _log_uniform(rng, 1.2, LONG, n)
    lo = np.maximum(p, q)
    hi = p + q - 1.0 - 0.02           # > lo: p, q >= 1.2
    l = lo + rng.random(n) * (hi - lo)
    links = np.column_stack([l, p, q])
    order = np.argsort(rng.random((n, 3)), axis=1)               # a random deal of (l, p, q) to (r1, r3, r4)
    links = np.take_along_axis(links, order, axis=1)
    r1, r3, r4 = links[:, 0], links[:, 1], links[:, 2]
    rad = _log_uniform(rng, 0.3, LONG, n)
    ang = rng.uniform(0.0, TWO_PI, n)
    return np.column_stack([np.ones(n), 1.0 / r1, r3 / r1, r4 / r1, rad * np.cos(ang) / r1, rad * np.sin(ang) / r1])


#: open target arcs with grashof = "any": shapes whose crank only rocks, screened on the crank's range of motion
ROCKING = 6000
#: their trial spans of that range (open curves: the targets' arc starts anywhere in it, no wrap)
ROCKING_SPANS = (0.35, 0.5, 0.7, 1.0)


def sample_rocking_shapes(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 6) normalised shapes (r1 = 1) of any Grashof class: r2, r3, r4 log-uniform in [0.02, 6]; the coupler
    point as in sample_shapes.  rocking_runs keeps those whose crank cannot turn fully."""
    out = np.empty((n, 6))
    out[:, 0] = 1.0
    out[:, 1:4] = _log_uniform(rng, 0.02, 6.0, 3 * n).reshape(n, 3)
    _draw_coupler_points(rng, out)
    return out


def rocking_runs(shapes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(shape index, first angle, last angle) of every interval of crank angles over which the loop of a shape
    whose crank cannot turn fully closes.  The frame-to-crank-pin distance d, d(theta)^2 = 1 + r2^2 - 2 r2 cos theta,
    must lie in [|r3 - r4|, r3 + r4]; d grows with |theta| on [0, pi], so the closing angles are +-[a, b]: one
    interval around 0 (a = 0), one around pi (b = pi), or two mirror intervals [a, b] and [-b, -a]."""
    r2, r3, r4 = shapes[:, 1], shapes[:, 2], shapes[:, 3]
    lo = np.maximum(np.abs(r3 - r4), np.abs(1.0 - r2))
    hi = np.minimum(r3 + r4, 1.0 + r2)
    angle = lambda d: np.arccos(np.clip((1.0 + r2 * r2 - d * d) / (2.0 * r2), -1.0, 1.0))   # noqa: E731
    a, b = angle(lo), angle(hi)
    at_zero = np.abs(1.0 - r2) >= np.abs(r3 - r4)          # the folded limit is not reached: a = 0
    at_pi = 1.0 + r2 <= r3 + r4                            # the extended limit is not reached: b = pi
    usable = (lo < hi) & ~(at_zero & at_pi) & (b - a > 1e-3)
    inset = 1e-6
    idx, first, last = [], [], []
    one = usable & (at_zero | at_pi)
    k = np.flatnonzero(one & at_zero)
    idx.append(k)
    first.append(-b[k] + inset)
    last.append(b[k] - inset)
    k = np.flatnonzero(one & at_pi)
    idx.append(k)
    first.append(a[k] + inset)
    last.append(TWO_PI - a[k] - inset)
    k = np.flatnonzero(usable & ~at_zero & ~at_pi)
    idx += [k, k]
    first += [a[k] + inset, -b[k] + inset]
    last += [b[k] - inset, -a[k] - inset]
    return np.concatenate(idx), np.concatenate(first), np.concatenate(last)


def run_angles(first: np.ndarray, last: np.ndarray, samples: int) -> np.ndarray:
    """(R, samples) crank angles over each interval [first, last], crowded towards its ends like a cosine grid:
    at a dead position the coupler point moves as the square root of the crank angle's distance to it, so
    samples even in theta would leave the curve's ends coarse; theta = middle + half-width sin(phi), phi even,
    spaces the points evenly in that square root near each end."""
    phi = np.linspace(-0.5 * math.pi, 0.5 * math.pi, samples)
    mid, half = 0.5 * (np.asarray(first) + np.asarray(last)), 0.5 * (np.asarray(last) - np.asarray(first))
    return mid[..., None] + half[..., None] * np.sin(phi)


def open_trials(fractions: np.ndarray, signs: tuple) -> np.ndarray:
    """(C, N) trial fractions of the targets along an open curve: each span of ROCKING_SPANS placed at PHASES
    starts from one end of the curve to the other, in each direction."""
    rows = []
    for sign in signs:
        for span in ROCKING_SPANS:
            for k in range(PHASES if span < 1.0 else 1):
                start = k / (PHASES - 1) * (1.0 - span)
                rows.append(start + span * fractions if sign > 0 else start + span * (1.0 - fractions))
    return np.clip(np.array(rows), 0.0, 1.0)


def _by_blocks(job, n: int) -> list:
    """job(rows) for the row slices of CHUNK out of n, in order, run by up to THREADS threads (joined before returning:
    no thread outlives the call, so a worker forked afterwards inherits none; on an error the blocks not begun are
    dropped).  A job sets its own numpy error state: a thread does not inherit the caller's."""
    blocks = [slice(lo, lo + CHUNK) for lo in range(0, n, CHUNK)]
    if THREADS is not None:
        threads = max(1, THREADS)
    elif multiprocessing.parent_process() is not None:
        threads = 1
    else:
        threads = min(default_workers(), MAX_THREADS)
    if threads == 1 or len(blocks) < 2:
        return [job(rows) for rows in blocks]
    pool = ThreadPoolExecutor(min(threads, len(blocks)), thread_name_prefix="screen")
    try:
        return list(pool.map(job, blocks))
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def shape_points(shapes: np.ndarray, theta: np.ndarray, branch: int) -> np.ndarray:
    """(S, K) complex coupler points of the shapes in their normalised frame (O = 0, O' = 1) at crank angles
    ``theta`` ((K,) for all, or (S, K) one row per shape); NaN where the loop does not close."""
    theta = np.atleast_2d(theta)

    def block(rows: slice) -> np.ndarray:
        d = {"r1": shapes[rows, 0:1], "r2": shapes[rows, 1:2], "r3": shapes[rows, 2:3], "r4": shapes[rows, 3:4],
             "rcx": shapes[rows, 4:5], "rcy": shapes[rows, 5:6], "x0": 0.0, "y0": 0.0, "theta0": 0.0}
        return joint_positions(d, theta if len(theta) == 1 else theta[rows], branch)["P"]
    if len(shapes) == 0:
        return block(slice(0, 0))
    return np.concatenate(_by_blocks(block, len(shapes)))


def shape_curves(shapes: np.ndarray, branch: int, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(crank angles (samples,), complex coupler curves (S, samples)) of the shapes over a turn; NaN where the
    loop does not close."""
    theta = np.linspace(0.0, TWO_PI, samples, endpoint=False)
    return theta, shape_points(shapes, theta, branch)


def scale_room(shapes: np.ndarray, bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per shape the scales s with s * (r1, r2, r3, r4, rcx, rcy) within their bounds ([lo, hi]; lo > hi: none)."""
    v = shapes[:, :6]
    lo_b, hi_b = bounds[:6, 0], bounds[:6, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = lo_b / v, hi_b / v
    lo = np.where(v > 0, a, np.where(v < 0, b, np.where(lo_b <= 0.0, 0.0, np.inf)))
    hi = np.where(v > 0, b, np.where(v < 0, a, np.where(hi_b >= 0.0, np.inf, 0.0)))
    return np.max(lo, axis=1), np.min(hi, axis=1)


def _similarity(c: np.ndarray, t: np.ndarray, s_lo: np.ndarray, s_hi: np.ndarray):
    """Best a, b (complex) of sum |a c + b - t|^2 over the last axis, |a| clipped to [s_lo, s_hi]; and that
    residual.  c: (..., N), t: (N,), s_lo/s_hi broadcast over the leading axes."""
    cm = c.mean(axis=-1, keepdims=True)
    tm = t.mean()
    cc, tc = c - cm, t - tm
    aa = np.sum(np.abs(cc) ** 2, axis=-1)
    cross = np.sum(np.conj(cc) * tc, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = cross / aa
    mod = np.abs(a)
    clipped = np.clip(mod, s_lo, s_hi)
    a = np.where(mod > 0, a * (clipped / np.where(mod > 0, mod, 1.0)), clipped)
    b = tm - a * cm[..., 0]
    res = np.sum(np.abs(a[..., None] * c + b[..., None] - t) ** 2, axis=-1)
    return a, b, res


def trial_fractions(fractions: np.ndarray, signs: tuple, closed: bool) -> np.ndarray:
    """(C, N) trial curve fractions of the targets (PHASES phases per direction; open arcs SPANS each)."""
    rows = []
    for sign in signs:
        for span in ((1.0,) if closed else SPANS):
            for k in range(PHASES):
                rows.append((k / PHASES + sign * span * fractions) % 1.0)
    return np.array(rows)


def arc_index(cum: np.ndarray, trials: np.ndarray) -> np.ndarray:
    """(B, C, N) index of the last sample of each curve at or before each trial fraction: (the number of cum[b, :] <=
    trials[c, n]) - 1, clipped to [0, K - 1]; cum (B, K) ascending along each row.  Counted by one merge of every
    curve's samples into the sorted trial fractions -- B K binary searches in C N values and a running count --
    instead of a binary search per (curve, trial, target) in the B K samples (the screen's costliest step)."""
    nb, k = cum.shape
    flat = trials.ravel()
    order = np.argsort(flat, kind="stable")
    qs = flat[order]
    m = qs.size
    # cum_j <= qs[i]  <=>  i >= (the first sorted trial at or above cum_j)
    first = np.searchsorted(qs, cum, side="left")                                  # (B, K) in [0, m]
    hits = np.bincount((np.arange(nb)[:, None] * (m + 1) + first).ravel(), minlength=nb * (m + 1))
    at_or_below = np.cumsum(hits.reshape(nb, m + 1), axis=1)[:, :m]               # (B, m): samples <= qs[i]
    count = np.empty((nb, m), dtype=np.int64)
    count[:, order] = at_or_below
    return np.clip(count - 1, 0, k - 1).reshape(nb, *trials.shape)


def _block(curves: np.ndarray, t: np.ndarray, trials: np.ndarray, s_lo: np.ndarray, s_hi: np.ndarray,
           closed_curve: bool = True):
    """Screen one block of curves (B, K), full-turn (closed) or a crank's range of motion (open): (a, b,
    residual)."""
    nb, k = curves.shape
    ends = np.concatenate([curves, curves[:, :1]], axis=1) if closed_curve else curves
    seg = np.abs(np.diff(ends, axis=1))
    cum = np.concatenate([np.zeros((nb, 1)), np.cumsum(seg, axis=1)], axis=1)
    cum = (cum[:, :-1] if closed_curve else cum) / cum[:, -1:]     # (B, K) arc-length fraction of each sample
    rows = np.arange(nb)[:, None, None]
    idx = arc_index(cum, trials)
    a, b, res = _similarity(curves[rows, idx], t, s_lo[:, None], s_hi[:, None])
    best = np.argmin(np.where(np.isfinite(res), res, np.inf), axis=1)
    pick = np.arange(nb)
    a, b, res, idx = a[pick, best], b[pick, best], res[pick, best], idx[pick, best]
    for _ in range(ICP_ROUNDS):
        moved = a[:, None] * curves + b[:, None]                          # (B, K)
        d2 = np.abs(moved[:, None, :] - t[None, :, None]) ** 2            # (B, N, K)
        idx = np.argmin(d2, axis=2)
        a2, b2, res2 = _similarity(curves[np.arange(nb)[:, None], idx], t, s_lo, s_hi)
        better = res2 < res
        a, b, res = np.where(better, a2, a), np.where(better, b2, b), np.where(better, res2, res)
    return a, b, res


def _fit_family(shapes: np.ndarray, curves: np.ndarray, t: np.ndarray, trials: np.ndarray, bounds: np.ndarray,
                closed_curve: bool):
    """(shapes, a, b, residual) of one family of shapes with their curves (S, K): those whose curve closes at every
    sample and whose scale room in the bounds is not empty, each laid onto the targets t by _block, CHUNK at a time."""
    ok = np.all(np.isfinite(curves), axis=1)
    shapes, curves = shapes[ok], curves[ok]
    s_lo, s_hi = scale_room(shapes, bounds)
    fit = s_lo <= s_hi
    shapes, curves, s_lo, s_hi = shapes[fit], curves[fit], s_lo[fit], s_hi[fit]
    a = np.empty(len(shapes), complex)
    b = np.empty(len(shapes), complex)
    res = np.empty(len(shapes))

    def block(rows: slice) -> None:
        a[rows], b[rows], res[rows] = _block(curves[rows], t, trials, s_lo[rows], s_hi[rows], closed_curve)
    _by_blocks(block, len(shapes))
    return shapes, a, b, res


def screen(targets: np.ndarray, bounds: np.ndarray, branch: int, grashof: str, signs: tuple, closed: bool,
           fractions: np.ndarray, seed: int, shapes: int = SHAPES) -> tuple[np.ndarray, np.ndarray]:
    """(designs r1..theta0 in spec units, residual mm^2), best first, of the screened shapes that fit in
    the bounds (see the module docstring)."""
    rng = np.random.default_rng([seed, SEED_TAG])
    long = int(round(LONG_SHARE * shapes)) if grashof in ("crank-rocker", "any") else 0
    families: list[np.ndarray] = []
    for family, wanted in ((lambda k: sample_shapes(rng, k, grashof), shapes - long),
                           (lambda k: sample_long_shapes(rng, k), long)):
        blocks, count = [], 0
        for _ in range(40):                  # draw until `wanted` valid ones (a bounded number of draws)
            if count >= wanted:
                break
            blocks.append(family(wanted))
            count += len(blocks[-1])
        families += [np.concatenate(blocks)[:wanted]] if blocks else []
    cand = np.concatenate(families)
    t = targets[:, 0] + 1j * targets[:, 1]
    cand, a, b, res = _fit_family(cand, shape_curves(cand, branch, GRID)[1], t,
                                  trial_fractions(fractions, signs, closed), bounds, closed_curve=True)
    if grashof == "any" and not closed and ROCKING > 0:
        # an open arc needs no full turn: with grashof = "any" the linkages whose crank only rocks are candidates
        # too, each laid onto the targets along the open curve of its range of motion
        rock = sample_rocking_shapes(rng, ROCKING)
        which, first, last = rocking_runs(rock)
        rock = rock[which]
        rock, ra, rb, rres = _fit_family(rock, shape_points(rock, run_angles(first, last, GRID), branch), t,
                                         open_trials(fractions, signs), bounds, closed_curve=False)
        cand, a, b, res = (np.concatenate([cand, rock]), np.concatenate([a, ra]), np.concatenate([b, rb]),
                           np.concatenate([res, rres]))
    scale = np.abs(a)
    design = np.column_stack([cand[:, :6] * scale[:, None], b.real, b.imag,
                              np.degrees(np.angle(a)) % 360.0])
    lo, hi = bounds[:, 0], bounds[:, 1]
    theta0 = design[:, 8]
    if hi[8] - lo[8] >= 360.0:
        design[:, 8] = lo[8] + (theta0 - lo[8]) % 360.0
    inside = np.all((design >= lo - 1e-9) & (design <= hi + 1e-9), axis=1) & np.isfinite(res)
    design, res = np.clip(design[inside], lo, hi), res[inside]
    order = np.argsort(res, kind="stable")
    return design[order], res[order]

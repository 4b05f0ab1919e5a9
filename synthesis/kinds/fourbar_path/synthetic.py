"""Path-synthesis problems with a known zero-error answer: targets sampled from a random crank-rocker.

Used by the tests (the proof that the multistart finds a global optimum when one with zero error
exists) and by ``agrisynth bench fourbar_path``.  Everything is a function of the seed.

The mechanism: link lengths uniform in [10, 55] mm, redrawn until it is a Grashof crank-rocker with
every class slack >= 2 mm and a transmission angle within [35, 145] deg over the turn (so it meets
the rules [30, 150] of the problem with room); coupler point, input pivot uniform in [-50, 50] mm;
frame angle uniform in [0, 360) deg; open branch.  The targets: n coupler points at crank angles
evenly spaced over one counter-clockwise turn from a random phase.  The problem's bounds are those
of the kind's first problem statement: r in [5, 60], rcx, rcy, x0, y0 in [-60, 60], theta0 in [0, 360].
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import cast

import numpy as np

from synthesis.kinds.fourbar_path.construction import joint_positions
from synthesis.kinds.fourbar_path.kinematics import VARIABLES, cos_transmission
from synthesis.kinematics.fourbar import crank_rotation_slacks
from synthesis.spec import LoadedSpec
from synthesis.spec.common import validate
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec

BOUNDS = {"r1": [5, 60], "r2": [5, 60], "r3": [5, 60], "r4": [5, 60], "rcx": [-60, 60], "rcy": [-60, 60],
          "x0": [-60, 60], "y0": [-60, 60], "theta0": [0, 360]}
#: [linkage]: every variable free within BOUNDS, starting at the middle (nothing of the truth is given)
LINKAGE = {n: {"init": 0.5 * (lo + hi), "bounds": [lo, hi]} for n, (lo, hi) in BOUNDS.items()}
RULES = {"grashof": "crank_rocker", "transmission_angle": [30, 150]}
SEEDS = tuple(range(10))
POINT_COUNTS = (6, 10, 18)


def random_crank_rocker(seed: int) -> tuple[dict[str, float], float]:
    """(design r1..theta0, phase of the first target in deg) of the seed's mechanism."""
    rng = np.random.default_rng(seed)
    while True:
        r = rng.uniform(10.0, 55.0, 4)
        if min(cast(dict[str, float], crank_rotation_slacks(*r)).values()) < 2.0:      # floats in, floats out
            continue
        mu_min = math.degrees(math.acos(cos_transmission(0.0, *r)))
        mu_max = math.degrees(math.acos(cos_transmission(math.pi, *r)))
        if mu_min >= 35.0 and mu_max <= 145.0:
            break
    rest = [rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(-50, 50),
            rng.uniform(0, 360)]
    phase = float(rng.uniform(0, 360))
    return dict(zip(VARIABLES, (float(v) for v in np.concatenate([r, rest])))), phase


def sample_targets(design: dict, phase_deg: float, n: int, span_deg: float = 360.0) -> tuple[np.ndarray, np.ndarray]:
    """(n, 2) coupler points and their crank angles (deg), evenly over one counter-clockwise turn, or
    (span_deg < 360) evenly from the phase to phase + span_deg, both ends included."""
    if span_deg >= 360.0:
        crank = phase_deg + 360.0 * np.arange(n) / n
    else:
        crank = phase_deg + span_deg * np.arange(n) / (n - 1)
    p = joint_positions(design, np.radians(crank), branch=1)["P"]
    return np.column_stack([p.real, p.imag]), crank


def truth_name(seed: int, n: int, timed: bool, span_deg: float = 360.0) -> str:
    arc = "" if span_deg >= 360.0 else f"_arc{span_deg:g}"
    return f"truth{seed}_n{n}{arc}_{'timed' if timed else 'free'}"


def truth_data(seed: int, n: int, timed: bool, solver: dict | None = None, span_deg: float = 360.0) -> dict:
    """The spec (as TOML-like data) of the seed's problem with n targets, timing prescribed or free,
    over the whole turn or a crank span of span_deg."""
    design, phase = random_crank_rocker(seed)
    points, crank = sample_targets(design, phase, n, span_deg)
    targets: dict = {"points": points.tolist()}
    if timed:
        targets["crank_deg"] = crank.tolist()
    over = "" if span_deg >= 360.0 else f" over {span_deg:g} deg of crank"
    return {"kind": "fourbar_path", "name": truth_name(seed, n, timed, span_deg),
            "source": f"synthetic: {n} coupler points{over} of random crank-rocker {seed} "
                      f"(synthesis.kinds.fourbar_path.synthetic)",
            "targets": targets, "linkage": {n: dict(v) for n, v in LINKAGE.items()}, "rules": dict(RULES), "solver": dict(solver or {})}


def truth_spec(seed: int, n: int, timed: bool, solver: dict | None = None, span_deg: float = 360.0) -> LoadedSpec:
    """The problem as a loaded spec (what ``agrisynth solve`` would see)."""
    return loaded_spec(truth_data(seed, n, timed, solver, span_deg))


def loaded_spec(data: dict) -> LoadedSpec:
    """A spec's data (as TOML-like data) as a loaded spec (what ``agrisynth solve`` would see)."""
    model = validate(FourbarPathSpec, data, prefix="fourbar_path")
    sha = hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()
    return LoadedSpec(model, Path(f"<{data['name']}>"), sha)


#: a digitiser's noise (mm, the standard deviation of each coordinate of each target): a curve traced from a drawing
#: or a point tracked on high-speed video is a fifth of a millimetre off, so no four-bar passes through its targets
DIGITISER_NOISE_MM = 0.2
NOISE_SEED_TAG = 7       # the noise is drawn by numpy's generator seeded [seed, n, NOISE_SEED_TAG]


def noisy_truth_data(seed: int, n: int, timed: bool, noise_mm: float = DIGITISER_NOISE_MM,
                     solver: dict | None = None) -> dict:
    """:func:`truth_data` over the whole turn, every target then moved by a seeded normal offset of ``noise_mm`` in
    x and in y: a digitised coupler curve of a known linkage, as many points as a designer brings (the many-target
    study of bench.py and its tests).  The crank angles (timed) are the true ones."""
    data = truth_data(seed, n, timed, solver)
    rng = np.random.default_rng([seed, n, NOISE_SEED_TAG])
    points = np.asarray(data["targets"]["points"], dtype=float) + rng.normal(0.0, noise_mm, (n, 2))
    data["targets"]["points"] = points.tolist()
    data["name"] = f"noisy{seed}_n{n}_{'timed' if timed else 'free'}"
    data["source"] = (f"synthetic: {n} coupler points of random crank-rocker {seed}, each moved by a normal "
                      f"digitiser error of {noise_mm:g} mm in x and y (synthesis.kinds.fourbar_path.synthetic)")
    return data

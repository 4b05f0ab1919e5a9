"""``agrisynth check`` for kind fourbar_path, and the independent re-check of every solve.

What is independent of the NLP and what is not: joint positions come from complex numbers and an
inverse cosine (the textbook construction, not fourbar.coupler_joint); loop closure is read off
those float positions, |r3 - r4| <= |O'A| <= r3 + r4, on a 0.1 deg grid over the whole turn (the NLP
has polynomial rows at the targets only) and every joint must be a finite number there; the
Grashof class is the textbook statement on the sorted lengths (s + l <= p + q and the crank -- r2,
or the frame r1 for a double-crank -- is the shortest; the NLP has three linear rows); the
transmission angle is measured between the joint positions on the same grid (the NLP uses its
closed-form extremes); the order of the angles is written out here again.  Shared with the NLP:
nothing but the record format (constraints.base.Rule) and the spec.

Which design ``check`` evaluates: each variable's [design] value, else its fixed number in [bounds],
else the midpoint of its [lo, hi] (the result notes which).  The crank angle of each target: the
prescribed targets.crank_deg, else [design] crank_deg, else the crank angle of the nearest point of
the coupler curve (a 0.1 deg grid refined by bounded scalar minimisation) -- then the `sequence`
rule tells whether those nearest points come in order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from constraints import Rule, not_evaluated
from constraints.grashof_class import CLASSES
from constraints.transmission import transmission_rules
from synthesis.kinematics.coupler_point import BRANCHES, VARIABLES, coupler_function, design_parameters
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.spec.fourbar_path import FourbarPathSpec

TWO_PI = 2.0 * math.pi
TURN_SAMPLES = 3600          # the re-check grid over a full turn (0.1 deg)
FINE = 10                    # "any": this many times the solver's samples between targets
TRAJECTORY_SAMPLES = 361


def joint_positions(design: dict, theta, branch: int) -> dict[str, np.ndarray]:
    """Complex positions of O, A, B, O', P at crank angles ``theta`` (rad); NaN where the loop is open.

    Local frame O = 0, O' = r1: A = r2 e^{i theta}; B = O' + r4 e^{i(delta - branch gamma)} with delta the
    direction O' -> A and gamma the angle at O' of the triangle O'AB (law of cosines).  The global frame
    is the local one turned by theta0 and shifted to (x0, y0).
    """
    th = np.asarray(theta, dtype=float)
    r1, r2, r3, r4 = (design[k] for k in ("r1", "r2", "r3", "r4"))
    a = r2 * np.exp(1j * th)
    oa = a - r1
    d = np.abs(oa)
    with np.errstate(invalid="ignore", divide="ignore"):
        gamma = np.arccos((r4 * r4 + d * d - r3 * r3) / (2.0 * r4 * d))
    b = r1 + r4 * np.exp(1j * (np.angle(oa) - branch * gamma))
    p = a + (design["rcx"] + 1j * design["rcy"]) * (b - a) / r3
    turn = np.exp(1j * np.radians(design["theta0"]))      # design values may be arrays (broadcast)
    shift = design["x0"] + 1j * np.asarray(design["y0"])
    place = lambda z: shift + turn * z   # noqa: E731
    return {"O": place(np.zeros_like(a)), "A": place(a), "B": place(b), "O'": place(r1 + 0 * a), "P": place(p)}


def transmission_deg(joints: dict) -> np.ndarray:
    """Angle at B between B -> A and B -> O' (deg, in [0, 180])."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.degrees(np.abs(np.angle((joints["A"] - joints["B"]) / (joints["O'"] - joints["B"]))))


def nearest_crank_angles(design: dict, targets: np.ndarray, branch: int) -> np.ndarray:
    """Crank angle (rad) of the point of the coupler curve nearest to each target."""
    grid = np.linspace(0.0, TWO_PI, TURN_SAMPLES, endpoint=False)
    pts = joint_positions(design, grid, branch)["P"]
    out = []
    for tx, ty in targets:
        dist = np.abs(pts - (tx + 1j * ty))
        if not np.any(np.isfinite(dist)):
            out.append(float("nan"))
            continue
        k = int(np.nanargmin(dist))
        h = TWO_PI / TURN_SAMPLES
        f = lambda t: abs(joint_positions(design, np.array([t]), branch)["P"][0] - (tx + 1j * ty))  # noqa: E731
        res = minimize_scalar(lambda t: np.nan_to_num(f(t), nan=1e30), bounds=(grid[k] - h, grid[k] + h),
                              method="bounded", options={"xatol": 1e-12})
        out.append(float(res.x) if res.fun <= dist[k] else float(grid[k]))
    return np.array(out)


@dataclass
class Evaluation:
    rules: list[Rule]
    crank_deg: list[float]
    errors_mm: np.ndarray            # distance target -> coupler point, NaN where the loop is open
    timing: str                      # "prescribed" / "given" / "solved" / "nearest"

    @property
    def sum_sq(self) -> float:
        return float(np.sum(self.errors_mm ** 2))


def crank_motion(spec: FourbarPathSpec, thetas: np.ndarray) -> np.ndarray:
    """The crank angles the rules are checked over: a full turn, or target to target for grashof "any"."""
    if spec.rules.grashof != "any":
        return np.linspace(0.0, TWO_PI, TURN_SAMPLES, endpoint=False)
    per = FINE * spec.solver.samples
    if len(thetas) == 1:
        return thetas
    steps = [a + (b - a) * np.arange(per) / per for a, b in zip(thetas, thetas[1:])]
    return np.concatenate(steps + [thetas[-1:]])


def evaluate(spec: FourbarPathSpec, design: dict, crank_deg: list[float] | None = None,
             timing: str = "given") -> Evaluation:
    """Every rule of the spec for a design, independently of the solver."""
    branch = BRANCHES[spec.branch]
    targets = np.array(spec.targets.points, dtype=float)
    if spec.timed:
        crank_deg, timing = list(spec.targets.crank_deg), "prescribed"
    elif crank_deg is None:
        nearest = np.degrees(nearest_crank_angles(design, targets, branch))
        crank_deg, timing = unwrapped(nearest, spec.rules.direction), "nearest"
    thetas = np.radians(np.array(crank_deg, dtype=float))
    located = bool(np.all(np.isfinite(thetas)))     # False: no coupler curve to find the targets on
    at_targets = joint_positions(design, thetas, branch)
    errors = np.abs(at_targets["P"] - (targets[:, 0] + 1j * targets[:, 1]))
    lim = spec.rules
    rules: list[Rule] = []
    if lim.grashof != "any":
        rules.append(grashof_by_sorted_lengths(lim.grashof, design))
    motion = crank_motion(spec, thetas) if located else np.linspace(0.0, TWO_PI, TURN_SAMPLES, endpoint=False)
    where = ("over the turn (0.1 deg grid) and at every target" if lim.grashof != "any"
             else "at the targets and between them")
    closure_angles = np.concatenate([motion, thetas[np.isfinite(thetas)]])
    rules.append(closure_rule(design, closure_angles, branch, where))
    if lim.transmission_angle is not None:
        mu = transmission_deg(joint_positions(design, motion, branch))
        missing = None if np.all(np.isfinite(mu)) else "the loop does not close everywhere on the crank's motion"
        rules += transmission_rules(mu, lim.transmission_angle, missing=missing)
    if not spec.timed and lim.order:
        sign, direction = _direction(lim.direction, list(crank_deg))
        what = f"targets met in order within one turn, crank {direction}"
        rules.append(order_rule(np.array(crank_deg, dtype=float), sign, what) if located else
                     not_evaluated("sequence", 0.0, None, "deg", what,
                                   "no crank angle of the targets: the loop closes at no crank angle"))
    return Evaluation(rules, [float(a) for a in crank_deg], errors, timing)


def grashof_by_sorted_lengths(grashof: str, design: dict) -> Rule:
    """The Grashof class as the textbook states it: s + l <= p + q (s, p, q, l the sorted lengths) and
    the link that must turn fully (the crank r2; the frame r1 for a double-crank) is the shortest.
    Values (mm): p + q - s - l and (shortest of the other three) - that link; both >= 0."""
    lengths = {k: float(design[k]) for k in ("r1", "r2", "r3", "r4")}
    s, p, q, l = sorted(lengths.values())
    turning = "r2" if grashof == "crank-rocker" else "r1"
    others = min(v for k, v in lengths.items() if k != turning)
    return Rule("grashof", np.array([p + q - s - l, others - lengths[turning]]), 0.0, None, "mm", 10.0,
                f"{grashof}: {CLASSES[grashof]}")


def closure_rule(design: dict, thetas: np.ndarray, branch: int, where: str) -> Rule:
    """Loop closure from the float joint positions: |r3 - r4| <= |O'A| <= r3 + r4 at every angle, and
    every joint a finite number there.  Value: the smaller closure margin at the worst angle (mm)."""
    r3, r4 = float(design["r3"]), float(design["r4"])
    joints = joint_positions(design, thetas, branch)
    d = np.abs(joints["A"] - joints["O'"])
    margin = np.minimum(d - abs(r3 - r4), r3 + r4 - d)
    finite = np.all([np.isfinite(z) for z in joints.values()], axis=0)
    # a closing margin where the construction still gave no number counts as open (by a hair)
    margin = np.where((margin >= 0.0) & ~finite, -np.finfo(float).tiny, margin)
    return Rule("assembly", margin, 0.0, None, "mm", 1.0, where)


def order_rule(crank_deg: np.ndarray, sign: float, what: str) -> Rule:
    """Each step sign * (theta_{i+1} - theta_i) >= 0 and the whole span sign * (theta_N - theta_1) <= 360
    deg; values (deg): the steps and 360 minus the span."""
    steps = sign * np.diff(crank_deg)
    return Rule("sequence", np.concatenate([steps, [360.0 - sign * (crank_deg[-1] - crank_deg[0])]]),
                0.0, None, "deg", 10.0, what)


def unwrapped(angles_deg: np.ndarray, direction: str) -> list[float]:
    """Angles in [0, 360) made to follow each other in the crank direction, each step less than a turn
    (direction "either": whichever way spans less)."""
    if not np.all(np.isfinite(angles_deg)):
        return [float(a) for a in angles_deg]
    options = []
    for sign in {"ccw": (1.0,), "cw": (-1.0,), "either": (1.0, -1.0)}[direction]:
        steps = sign * ((sign * np.diff(angles_deg)) % 360.0)
        out = angles_deg[0] + np.concatenate([[0.0], np.cumsum(steps)])
        options.append((abs(out[-1] - out[0]), -sign, out))
    return [float(a) for a in min(options, key=lambda o: (o[0], o[1]))[2]]


def _direction(direction: str, crank_deg: list[float]) -> tuple[float, str]:
    if direction == "either":
        direction = "ccw" if crank_deg[-1] >= crank_deg[0] else "cw"
    return (1.0 if direction == "ccw" else -1.0), direction


def trajectory(spec: FourbarPathSpec, design: dict, crank_deg: list[float], sign: float = 1.0) -> dict | None:
    """The coupler point over one turn from the first target, the crank turning counter-clockwise
    (sign +1) or clockwise (-1); grashof "any": from the first target's angle to the last's."""
    branch = BRANCHES[spec.branch]
    if spec.rules.grashof != "any":
        start = math.radians(crank_deg[0])
        theta = start + sign * np.linspace(0.0, TWO_PI, TRAJECTORY_SAMPLES)
    else:
        a, b = math.radians(crank_deg[0]), math.radians(crank_deg[-1])
        theta = np.linspace(a, b, TRAJECTORY_SAMPLES)
    omega = spec.crank_speed * TWO_PI / 60.0        # |d theta / dt|
    rate = omega * (1.0 if theta[-1] >= theta[0] else -1.0)
    f = coupler_function(branch)
    p = np.array(design_parameters(design), dtype=float)
    pos, d1, d2 = (np.asarray(v) for v in f(theta.reshape(1, -1), p))
    ok = np.all(np.isfinite(np.vstack([pos, d1, d2])), axis=0)
    if not ok.any():
        return None
    theta, pos, d1, d2 = theta[ok], pos[:, ok], d1[:, ok], d2[:, ok]
    return {
        "frame": "ground", "crank_speed_rpm": spec.crank_speed,
        "t": (np.abs(theta - theta[0]) / omega).tolist(), "crank_deg": np.degrees(theta).tolist(),
        "x": pos[0].tolist(), "y": pos[1].tolist(),
        "vx": (d1[0] * rate).tolist(), "vy": (d1[1] * rate).tolist(),
        "ax": (d2[0] * omega**2).tolist(), "ay": (d2[1] * omega**2).tolist(),
    }


def path_facts(spec: FourbarPathSpec, ev: Evaluation) -> dict:
    """The kind-specific part of result.json."""
    errors = ev.errors_mm
    finite = bool(np.all(np.isfinite(errors)))
    return {
        "source": spec.source,
        "branch": spec.branch,
        "grashof": spec.rules.grashof,
        "timing": ev.timing,
        "targets": [list(p) for p in spec.targets.points],
        "target_errors_mm": [float(e) if math.isfinite(e) else None for e in errors],
        "path_error": {"sum_squared_mm2": ev.sum_sq if finite else None,
                       "rms_mm": float(np.sqrt(np.mean(errors ** 2))) if finite else None,
                       "max_mm": float(np.max(errors)) if finite else None},
    }


def result_design(design: dict, crank_deg: list[float], spec: FourbarPathSpec) -> dict:
    out = {n: float(design[n]) for n in VARIABLES}
    out["crank_deg"] = [float(a) if math.isfinite(a) else None for a in crank_deg]     # None: not found
    out["branch"] = spec.branch
    return out


def run_check(loaded: LoadedSpec) -> Result:
    spec: FourbarPathSpec = loaded.model
    design = spec.design_values()
    ev = evaluate(spec, design, spec.design.crank_deg)
    records = [r.record().to_json() for r in ev.rules]
    facts = path_facts(spec, ev)
    if not all(np.isfinite(ev.errors_mm)):
        open_at = [i for i, e in enumerate(ev.errors_mm) if not math.isfinite(e)]
        facts["note"] = f"the loop does not close at target(s) {open_at}: no coupler point there"
    midpoints = spec.midpoint_variables()
    if midpoints:
        facts["midpoint_variables"] = midpoints
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=result_design(design, ev.crank_deg, spec), rules=records,
                  trajectory=trajectory(spec, design, ev.crank_deg, _direction("either", ev.crank_deg)[0]),
                  extra=facts)

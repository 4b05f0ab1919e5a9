"""``agrisynth check`` for kind fourbar_path, and the re-check of every solver start.

Both evaluate the spec's rules with :func:`synthesis.kinds.fourbar_path.rule_set.path_rules`, the function the
NLP builds its constraints from, here on floats: the Grashof class (exact, linear), closure at the
targets, the transmission angle at its exact extremes over a full turn, the order of the crank angles;
for grashof = "any" closure and transmission along the crank's motion from target to target, 10x
more finely sampled than the NLP; the [dynamics.limits] over a turn on 10x the NLP's crank angles, and with a
[dynamics] table result.json's ``facts.dynamics`` (dynamics.py).  The coupler point is the closed form of
``kinematics.coupler_point``.  The textbook complex-number construction
(:mod:`synthesis.kinds.fourbar_path.construction`) is the tests' independent oracle of both.

Which design ``check`` evaluates: each [linkage] variable's fixed number or ``init``.  The crank angle
of each target: the
prescribed targets.crank_deg, else [design] crank_deg, else the crank angle of the nearest point of
the coupler curve (a 0.1 deg grid refined by bounded scalar minimisation) -- then the `sequence`
rule tells whether those nearest points come in order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

import numpy as np
from scipy.optimize import minimize_scalar

from synthesis.constraints import Rule
from synthesis.core.verdict import FINE
from synthesis.kinds.fourbar_path.dynamics import dynamics_facts_of
from synthesis.kinds.fourbar_path.rule_set import path_rules
from synthesis.kinds.fourbar_path.kinematics import BRANCHES, VARIABLES, coupler_function, design_parameters
from synthesis.core.kind import ResultTable, figure_text
from synthesis.result import Result
from synthesis.spec import LoadedSpec
from synthesis.kinds.fourbar_path.spec import FourbarPathSpec, same_targets

TWO_PI = 2.0 * math.pi
TURN_SAMPLES = 3600          # the grid of the nearest-point search over a full turn (0.1 deg)
TRAJECTORY_SAMPLES = 361


def nearest_crank_angles(design: dict, targets: np.ndarray, branch: int) -> np.ndarray:
    """Crank angle (rad) of the point of the coupler curve nearest to each target (NaN: no curve)."""
    p = np.array(design_parameters(design), dtype=float)
    f = coupler_function(branch)
    grid = np.linspace(0.0, TWO_PI, TURN_SAMPLES, endpoint=False)
    pts = np.asarray(f(grid.reshape(1, -1), p)[0])
    out = []
    for tx, ty in targets:
        dist = np.hypot(pts[0] - tx, pts[1] - ty)
        if not np.any(np.isfinite(dist)):
            out.append(float("nan"))
            continue
        k = int(np.nanargmin(dist))
        h = TWO_PI / TURN_SAMPLES

        def gap(t: float, tx=tx, ty=ty) -> float:
            x, y = (float(c) for c in np.asarray(f(t, p)[0]).ravel())
            return float(np.nan_to_num(math.hypot(x - tx, y - ty), nan=1e30))

        res = minimize_scalar(gap, bounds=(grid[k] - h, grid[k] + h), method="bounded", options={"xatol": 1e-12})
        out.append(float(res.x) if res.fun <= dist[k] else float(grid[k]))
    return np.array(out)


def coupler_points(design: dict, thetas: np.ndarray, branch: int) -> np.ndarray:
    """(n, 2) coupler points at the crank angles ``thetas`` (rad), NaN where the loop is open."""
    p = np.array(design_parameters(design), dtype=float)
    return np.asarray(coupler_function(branch)(np.reshape(thetas, (1, -1)), p)[0]).T


@dataclass
class Evaluation:
    rules: list[Rule]
    crank_deg: list[float]
    errors_mm: np.ndarray            # distance target -> coupler point, NaN where the loop is open
    timing: str                      # "prescribed" / "given" / "solved" / "nearest"
    direction: str                   # crank direction of the sequence: "ccw" / "cw" ("given": prescribed timing)

    @property
    def sum_sq(self) -> float:
        return float(np.sum(self.errors_mm ** 2))


def evaluate(spec: FourbarPathSpec, design: dict, crank_deg: list[float] | None = None,
             timing: str = "given", direction: str | None = None) -> Evaluation:
    """Every rule of the spec for a design (floats), the crank angle of each target (deg; None: the
    nearest points of the coupler curve) and the crank direction ("ccw" / "cw"; None: from the angles).
    ValueError for a design that is not a set of numbers."""
    bad = [n for n in VARIABLES if not math.isfinite(float(design[n]))]
    if bad:
        raise ValueError(f"the design is not a number at {', '.join(bad)}")
    branch = BRANCHES[spec.branch]
    targets = np.array(spec.targets.points, dtype=float)
    if spec.targets.crank_deg is not None:          # timed: the targets prescribe every crank angle
        crank_deg, timing = list(spec.targets.crank_deg), "prescribed"
    elif crank_deg is None:
        nearest = np.degrees(nearest_crank_angles(design, targets, branch))
        crank_deg, timing = unwrapped(nearest, spec.rules.direction), "nearest"
    thetas = np.radians(np.array(crank_deg, dtype=float))
    located = bool(np.all(np.isfinite(thetas)))     # False: no coupler curve to find the targets on
    errors = np.hypot(*(coupler_points(design, thetas, branch) - targets).T)
    if spec.timed:
        direction, sign = "given", 1.0
    else:
        if direction is None:
            direction = _direction(spec.rules.direction, list(crank_deg))[1]
        sign = 1.0 if direction == "ccw" else -1.0
    rules = path_rules(spec, {n: float(design[n]) for n in VARIABLES}, list(thetas) if located else None, sign,
                       FINE * spec.solver.samples, FINE * spec.solver.dynamics_samples)
    return Evaluation(rules, [float(a) for a in crank_deg], errors, timing, direction)


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
    facts = {
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
    # the pairs of targets closer than SAME_TARGET of the set's size: one point of the path each (spec.same_targets)
    same = [[i, j] for i, j, _ in same_targets(spec.targets.points, spec.targets.crank_deg)]
    if same:
        facts["same_targets"] = same
    return facts


def result_branch(result: Result) -> int:
    """The sign (+1 open, -1 crossed) of a result's assembly, ``facts.branch`` (schema version 3; a version-2 file
    is read with it moved there); "open" where a hand-edited file gives none."""
    return BRANCHES[result.extra.get("branch", "open")]


def result_design(design: dict, crank_deg: list[float]) -> dict:
    out: dict[str, float | None | list[float | None]] = {
        n: float(design[n]) if math.isfinite(design[n]) else None for n in VARIABLES}         # JSON has no NaN
    out["crank_deg"] = [float(a) if math.isfinite(a) else None for a in crank_deg]     # None: not found
    return out            # the assembly (spec.branch) is a fact (path_facts), not a design value: schema version 3


def run_check(loaded: LoadedSpec) -> Result:
    spec = cast(FourbarPathSpec, loaded.model)     # load_spec validated it with this kind's model
    design = spec.design_values()
    ev = evaluate(spec, design, spec.design.crank_deg)
    records = [r.record().to_json() for r in ev.rules]
    sign = _direction("either", ev.crank_deg)[0]
    facts = {**path_facts(spec, ev), **dynamics_facts_of(spec, design, sign)}
    notes = [spec.targets.same_targets_note()]
    if not all(np.isfinite(ev.errors_mm)):
        open_at = [i for i, e in enumerate(ev.errors_mm) if not math.isfinite(e)]
        notes.append(f"the loop does not close at target(s) {open_at}: no coupler point there")
    if any(notes):
        facts["note"] = "; ".join(n for n in notes if n)
    return Result(kind=spec.kind, name=spec.name, spec_sha256=loaded.sha256, status="evaluated",
                  design=result_design(design, ev.crank_deg), rules=records,
                  trajectory=trajectory(spec, design, ev.crank_deg, sign),
                  extra=facts)


#: a headline lists each target's error up to this many targets (more: the summary line, and the report's table)
HEADLINE_TARGETS = 12


def target_error_rows(result: Result) -> list[dict]:
    """Each target's error from result.json facts: ``{"target": 1-based number (the figure's label), "x", "y",
    "error_mm"}`` (error None where the loop does not close there)."""
    facts = result.extra or {}
    targets, errors = facts.get("targets") or [], facts.get("target_errors_mm") or []
    return [{"target": i + 1, "x": float(p[0]), "y": float(p[1]), "error_mm": e}
            for i, (p, e) in enumerate(zip(targets, errors))]


def headline(result: Result) -> list[str]:
    """The path error an engineer reads first: rms and maximum (at which target) over the targets, then each
    target's error (up to HEADLINE_TARGETS targets), all from result.json facts."""
    rows = target_error_rows(result)
    summary = (result.extra or {}).get("path_error") or {}
    if not rows:
        return []
    measured = [r for r in rows if r["error_mm"] is not None]
    if len(measured) < len(rows):
        missing = ", ".join(str(r["target"]) for r in rows if r["error_mm"] is None)
        line = f"path error: the loop does not close at target(s) {missing}"
    else:
        worst = max(measured, key=lambda r: r["error_mm"])
        line = (f"path error over {len(rows)} targets: rms {figure_text(summary.get('rms_mm'), 'mm')}, max "
                f"{figure_text(summary.get('max_mm'), 'mm')} at target {worst['target']}")
    if len(rows) > HEADLINE_TARGETS:
        return [line]
    return [line] + [f"target {r['target']} ({r['x']:.4g}, {r['y']:.4g}) mm: error {figure_text(r['error_mm'], 'mm')}"
                     for r in rows]


def target_error_table(result: Result) -> ResultTable:
    """The report's table of the path error at each target (:func:`target_error_rows`)."""
    return ResultTable("Path error per target", ("target", "x, mm", "y, mm", "error, mm"),
                       tuple((r["target"], r["x"], r["y"], r["error_mm"]) for r in target_error_rows(result)))

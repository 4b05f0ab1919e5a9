"""Helpers of the fourbar_path tests: write a spec as a TOML file, run the CLI, and the independent
oracle of a design (the textbook construction, nothing of the solver's kinematics or rules)."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import numpy as np

from synthesis.kinds.fourbar_path.construction import joint_positions

ROOT = Path(__file__).resolve().parent.parent
PATH_LIBRARY = ROOT / "problems" / "fourbar_path"


def transmission_deg(joints: dict) -> np.ndarray:
    """The transmission angle: the angle at B between B -> A and B -> O' (deg, in [0, 180]), measured between the
    joint positions (the oracle's, not the rules' closed form)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.degrees(np.abs(np.angle((joints["A"] - joints["B"]) / (joints["O'"] - joints["B"]))))


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):             # a free variable: an inline table {init = .., bounds = [..]}
        return "{" + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + "}"
    return repr(float(v)) if isinstance(v, float) else str(v)


def toml_text(data: dict) -> str:
    """A spec dict (plain values at the top, one level of tables) as TOML."""
    lines = [f"{k} = {_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"\n[{k}]")
            lines += [f"{kk} = {_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def write_spec(folder: Path, data: dict, name: str = "spec.toml") -> Path:
    path = folder / name
    path.write_text(toml_text(data))
    return path


def cli(*args: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    from solving import agrisynth

    return agrisynth(*args, cwd=cwd, timeout=timeout)


# ---------------------------------------------------------------------------- the independent oracle

TURN = np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False)       # 0.1 deg, 0 and 180 deg on it
FINE = 10


def independent_path_error(spec, design: dict, thetas) -> float:
    """sum |P - T|^2 (mm^2) of the coupler point at crank angles ``thetas`` (rad) by the textbook construction
    (construction.joint_positions, not the NLP's closed form)."""
    branch = {"open": 1, "crossed": -1}[spec.branch]
    targets = np.asarray(spec.targets.points, dtype=float)
    p = joint_positions(design, np.asarray(thetas, dtype=float), branch)["P"]
    return float(np.sum(np.abs(p - (targets[:, 0] + 1j * targets[:, 1])) ** 2))


def independent_check(spec, design: dict, crank_deg: list[float]) -> dict[str, float]:
    """A design checked from scratch, sharing nothing with the solver or with ``check`` but the spec:
    joint positions from the textbook complex-number construction (construction.joint_positions, not
    kinematics.coupler_point), the Grashof class from the sorted lengths, closure and transmission
    angle measured between the float joint positions on a 0.1 deg grid over the turn (grashof "any":
    target to target, 10x the solver's samples per gap), the order of the angles written out again.

    Returns {what: margin} (>= 0 holds; -inf where a joint is not a number) and "path_error_mm2", the
    sum of squared distances of the constructed coupler point to the targets."""
    branch = {"open": 1, "crossed": -1}[spec.branch]
    thetas = np.radians(np.asarray(crank_deg, dtype=float))
    out: dict[str, float] = {"path_error_mm2": independent_path_error(spec, design, thetas)}
    lim = spec.rules
    if lim.grashof != "any":
        lengths = {k: float(design[k]) for k in ("r1", "r2", "r3", "r4")}
        s, pp, q, long = sorted(lengths.values())
        turning = "r2" if lim.grashof == "crank-rocker" else "r1"
        others = min(v for k, v in lengths.items() if k != turning)
        out["textbook_grashof"] = min(pp + q - s - long, others - lengths[turning])
        motion = TURN
    else:
        per = FINE * spec.solver.samples
        steps = [a + (b - a) * np.arange(per) / per for a, b in zip(thetas, thetas[1:])]
        motion = np.concatenate(steps + [thetas[-1:]])
    angles = np.concatenate([motion, thetas])
    joints = joint_positions(design, angles, branch)
    d = np.abs(joints["A"] - joints["O'"])
    r3, r4 = float(design["r3"]), float(design["r4"])
    finite = all(np.all(np.isfinite(z)) for z in joints.values())
    out["measured_closure"] = float(np.min(np.minimum(d - abs(r3 - r4), r3 + r4 - d))) if finite else -math.inf
    if lim.transmission_angle is not None:
        lo, hi = lim.transmission_angle
        mu = transmission_deg(joint_positions(design, motion, branch))
        ok = bool(np.all(np.isfinite(mu)))
        out["measured_transmission_min"] = float(mu.min() - lo) if ok else -math.inf
        out["measured_transmission_max"] = float(hi - mu.max()) if ok else -math.inf
    if not spec.timed and lim.order:
        c = np.asarray(crank_deg, dtype=float)
        sign = {"ccw": 1.0, "cw": -1.0}.get(lim.direction, 1.0 if c[-1] >= c[0] else -1.0)
        out["written_out_order"] = float(min(np.min(sign * np.diff(c)), 360.0 - sign * (c[-1] - c[0])))
    return out


def independent_failures(spec, design: dict, crank_deg: list[float], tol: float = 1e-9) -> list[str]:
    """The independent checks a design fails (margin < -tol)."""
    return [k for k, v in independent_check(spec, design, crank_deg).items() if k != "path_error_mm2" and v < -tol]

"""Figures of a fourbar_path result, drawn from result.json alone (never re-solving).

coupler_curve.png   the coupler curve, the targets (numbered) with their error, the linkage at the
                    first target
linkage.gif         the linkage over one cycle (report.gif: the still parts drawn once)
coupler_curves.png  ``agrisynth compare``: several results' curves and targets overlaid, baseline first
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.kinds.fourbar_path.check import result_branch  # noqa: E402
from synthesis.kinds.fourbar_path.construction import joint_positions  # noqa: E402
from synthesis.kinds.fourbar_path.kinematics import VARIABLES  # noqa: E402
from synthesis.report.gif import save_gif  # noqa: E402
from synthesis.report.labels import candidate_label  # noqa: E402
from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402

GIF_FRAMES = 36
#: the coupler-curve figure numbers at most about this many targets (every k-th of a longer set, target 1 first):
#: a digitised curve's hundreds of numbers would hide the curve, and each costs its drawing time
NUMBERED_TARGETS = 30
#: above this many targets their crosses are drawn smaller, so a dense set still shows the curve between them
SMALL_MARKS_ABOVE = 100
LINK: dict[str, Any] = dict(color="0.25", lw=2.2, solid_capstyle="round", zorder=4)


def _design(result: Result) -> tuple[dict, int]:
    return {n: result.design[n] for n in VARIABLES}, result_branch(result)


def _curve(result: Result) -> tuple[np.ndarray, np.ndarray]:
    tr = result.trajectory
    if tr:
        return np.asarray(tr["x"]), np.asarray(tr["y"])
    return np.zeros(0), np.zeros(0)


def _targets(result: Result) -> np.ndarray:
    return np.asarray(result.extra.get("targets", []), dtype=float).reshape(-1, 2)


def _linkage_lines(ax, joints: dict, k: int = 0) -> list:
    """Draw crank OA, coupler triangle ABP, output link O'B and the ground pivots; returns the artists."""
    z = {n: complex(v[k]) for n, v in joints.items()}
    artists = []
    for a, b in (("O", "A"), ("A", "B"), ("B", "O'"), ("A", "P"), ("B", "P")):
        style = dict(LINK) if (a, b) != ("A", "P") and (a, b) != ("B", "P") else dict(LINK, lw=1.2, ls="--")
        artists += ax.plot([z[a].real, z[b].real], [z[a].imag, z[b].imag], **style)
    artists += ax.plot([z["O"].real, z["O'"].real], [z["O"].imag, z["O'"].imag], ls=":", color="0.5", lw=1.0)
    artists += ax.plot([z["O"].real, z["O'"].real], [z["O"].imag, z["O'"].imag], "^", color="k", ms=9, zorder=5)
    artists += ax.plot([z["A"].real, z["B"].real], [z["A"].imag, z["B"].imag], "o", color="w", mec="k", ms=6,
                       zorder=6)
    artists += ax.plot([z["P"].real], [z["P"].imag], "o", color="tab:red", ms=6, zorder=7)
    return artists


def _annotate(ax, joints: dict, k: int = 0) -> None:
    """Joint letters and each link's length (mm) at its middle."""
    z = {n: complex(v[k]) for n, v in joints.items()}
    for name, p in z.items():
        ax.annotate(name, (p.real, p.imag), textcoords="offset points", xytext=(5, 5), fontsize=9,
                    fontweight="bold", zorder=8)
    # each length beside its link's middle, off the link along its normal; the links that often run nearly along
    # another (the ground beside the rocker, the coupler triangle's two sides to P) on opposite sides
    sides = {("O", "O'"): -1.0, ("B", "P"): -1.0}
    for a, b in (("O", "O'"), ("O", "A"), ("A", "B"), ("B", "O'"), ("A", "P"), ("B", "P")):
        m, d = (z[a] + z[b]) / 2, z[b] - z[a]
        normal = 1j * d / abs(d) if abs(d) > 0 else 1j
        off = 11.0 * sides.get((a, b), 1.0) * normal
        ax.annotate(f"{abs(d):.1f}", (m.real, m.imag), textcoords="offset points", xytext=(off.real, off.imag),
                    ha="center", va="center", fontsize=7.5, color="0.3", zorder=8,
                    bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7))


def _frame_axes(ax, result: Result, joints_all: list[np.ndarray]) -> None:
    pts = np.concatenate([np.asarray(j) for j in joints_all if np.size(j)])
    pts = pts[np.isfinite(pts)]
    if pts.size:
        pad = 0.08 * max(np.ptp(pts.real), np.ptp(pts.imag), 1.0)
        ax.set_xlim(pts.real.min() - pad, pts.real.max() + pad)
        ax.set_ylim(pts.imag.min() - pad, pts.imag.max() + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x, mm")
    ax.set_ylabel("y, mm")
    ax.grid(alpha=0.3)


def _title(result: Result) -> str:
    err = result.extra.get("path_error", {}) or {}
    obj = result.objective["value"] if result.objective else err.get("sum_squared_mm2")
    tail = f", sum of squared errors {obj:.3g} mm$^2$" if obj is not None else ""
    return f"{result.name} ({result.extra.get('branch', 'open')} branch){tail}"


def coupler_curve_figure(result: Result, path: Path) -> None:
    """Coupler curve, targets with their error segments, and the linkage at the first target."""
    design, branch = _design(result)
    targets = _targets(result)
    crank = np.radians(np.asarray(result.design.get("crank_deg", []), dtype=float))
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    x, y = _curve(result)
    ax.plot(x, y, color="tab:blue", lw=1.4, label="coupler curve", zorder=2)
    at_targets = joint_positions(design, crank, branch)["P"] if crank.size else np.zeros(0)
    # each target's error segment, all in one collection (one artist, not one per target)
    segments = [[(t[0], t[1]), (p.real, p.imag)] for t, p in zip(targets, at_targets) if np.isfinite(p)]
    if segments:
        ax.add_collection(LineCollection(segments, colors="tab:red", linewidths=0.8, zorder=3))
    every = -(-len(targets) // NUMBERED_TARGETS)           # ceil: 1 up to NUMBERED_TARGETS targets
    for i in range(0, len(targets), max(every, 1)):
        ax.annotate(str(i + 1), targets[i], textcoords="offset points", xytext=(4, 4), fontsize=8)
    if targets.size:
        small = len(targets) > SMALL_MARKS_ABOVE
        ax.plot(targets[:, 0], targets[:, 1], "x", color="tab:red", ms=3 if small else 7, mew=0.8 if small else 1.6,
                label="targets" if every <= 1 else f"targets (every {every}th numbered)", zorder=3)
    joints = joint_positions(design, crank[:1] if crank.size else np.zeros(1), branch)
    if all(np.isfinite(v[0]) for v in joints.values()):
        _linkage_lines(ax, joints)
        _annotate(ax, joints)
        ax.plot([], [], **LINK, label="linkage at target 1 (lengths in mm)")
    _frame_axes(ax, result, [x + 1j * y, targets[:, 0] + 1j * targets[:, 1] if targets.size else np.zeros(0),
                             *joints.values()])
    legend_below(ax, ncol=3, fontsize=8)
    ax.set_title(_title(result), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def linkage_animation(result: Result, path: Path) -> None:
    """The linkage over one cycle of the trajectory (GIF, GIF_FRAMES frames)."""
    design, branch = _design(result)
    tr = result.trajectory
    fig, ax = plt.subplots(figsize=(6.4, 5.8))          # 640 x 580 px at dpi 100
    if not tr:     # nothing moves: a one-frame GIF that says why
        ax.text(0.5, 0.5, "the linkage does not assemble", ha="center", transform=ax.transAxes)
        save_gif(fig, lambda k: [], 1, path, fps=1, dpi=64)
        plt.close(fig)
        return
    crank = np.radians(np.asarray(tr["crank_deg"], dtype=float))
    frames = np.linspace(0, len(crank) - 1, GIF_FRAMES, endpoint=False).astype(int)
    joints = joint_positions(design, crank[frames], branch)
    targets = _targets(result)
    ax.plot(tr["x"], tr["y"], color="tab:blue", lw=1.0, alpha=0.7)
    if targets.size:
        ax.plot(targets[:, 0], targets[:, 1], "x", color="tab:red", ms=6, mew=1.4)
    _frame_axes(ax, result, list(joints.values()))
    ax.set_title(f"{result.name}: one cycle", fontsize=9)
    z = {n: np.asarray(v) for n, v in joints.items()}
    ax.plot([z["O"][0].real, z["O'"][0].real], [z["O"][0].imag, z["O'"][0].imag], "^", color="k", ms=8, zorder=5)
    chain, = ax.plot([], [], **LINK)                                    # O - A - B - O'
    triangle, = ax.plot([], [], color="0.25", lw=1.0, ls="--", zorder=4)  # A - P - B
    pins, = ax.plot([], [], "o", color="w", mec="k", ms=5, zorder=6)
    point, = ax.plot([], [], "o", color="tab:red", ms=6, zorder=7)
    counter = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=10, zorder=9,
                      bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="0.8"))
    fig.tight_layout()

    def draw(k: int):
        o, a, b, o2, p = (z[n][k] for n in ("O", "A", "B", "O'", "P"))
        chain.set_data([o.real, a.real, b.real, o2.real], [o.imag, a.imag, b.imag, o2.imag])
        triangle.set_data([a.real, p.real, b.real], [a.imag, p.imag, b.imag])
        pins.set_data([a.real, b.real], [a.imag, b.imag])
        point.set_data([p.real], [p.imag])
        counter.set_text(f"frame {k + 1}/{GIF_FRAMES}, crank {np.degrees(crank[frames[k]]) % 360:.0f} deg")
        return chain, triangle, pins, point, counter

    save_gif(fig, draw, GIF_FRAMES, path, fps=12, dpi=100)
    plt.close(fig)


def compare_coupler_curves(results: list[Result], folder: Path) -> list[str]:
    """Several results' coupler curves and targets overlaid (baseline first); returns the file names."""
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    everything = []
    for k, result in enumerate(results):
        colour = colours[k % len(colours)]
        x, y = _curve(result)
        err = (result.extra.get("path_error") or {}).get("sum_squared_mm2")
        label = candidate_label(result.name, k, len(results)) + (f", {err:.3g} mm$^2$" if err is not None else "")
        ax.plot(x, y, color=colour, lw=1.4 if k else 2.0, label=label)
        targets = _targets(result)
        if targets.size:
            ax.plot(targets[:, 0], targets[:, 1], "x" if k == 0 else "+", color=colour, ms=8, mew=1.4)
            everything.append(targets[:, 0] + 1j * targets[:, 1])
        everything.append(x + 1j * y)
    _frame_axes(ax, results[0], everything)
    legend_below(ax, ncol=3, fontsize=8)
    ax.set_title("coupler curves and targets", fontsize=10)
    fig.tight_layout()
    fig.savefig(folder / "coupler_curves.png", dpi=110)
    plt.close(fig)
    return ["coupler_curves.png"]


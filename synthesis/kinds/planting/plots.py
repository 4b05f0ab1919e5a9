"""Trajectory plot of a planting_fourbar result, drawn from result.json alone (never re-solving)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402

COLOURS = {"P1": "tab:green", "P2": "tab:olive", "P3": "tab:brown",
           "P4": "tab:red", "P5": "tab:purple", "P6": "tab:orange"}


def style_plane(ax) -> None:
    """Equal scales, X and Y in mm, light grid: every drawing of a plane mechanism."""
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("X, mm")
    ax.set_ylabel("Y, mm")
    ax.grid(alpha=0.3)


def _seedbed_lines(ax, seedbed: dict, span: float) -> None:
    t = math.radians(seedbed["tilt_deg"])
    ux, uy = math.cos(t), math.sin(t)
    nx, ny = -uy, ux
    for offset, label, style in ((0.0, "seedbed bottom", "-"), (seedbed["thickness"], "seedbed top", "--"),
                                 (seedbed["seedling_height"], "seedling top", ":")):
        cx, cy = seedbed["x"] + offset * nx, seedbed["y"] + offset * ny
        ax.plot([cx - span * ux, cx + span * ux], [cy - span * uy, cy + span * uy], style,
                color="tab:green", lw=0.9, label=label)


def trajectory_figure(result: Result, path: Path) -> None:
    """Machine frame (with seedbed and soil lines) and ground frame, P1-P6 marked."""
    tr = result.trajectory
    fig, (ax_m, ax_g) = plt.subplots(1, 2, figsize=(11, 5.2))
    pts = result.extra.get("precision_points", {})
    soil = result.extra.get("soil_level_mm")
    if tr is not None:
        ax_m.plot(tr["machine"]["x"], tr["machine"]["y"], color="tab:blue", lw=1.4, label="claw tip")
        ax_g.plot(tr["x"], tr["y"], color="tab:blue", lw=1.4, label="claw tip")
        xs = tr["machine"]["x"] + tr["x"]
        span = max(xs) - min(xs)
        if "seedbed" in result.extra:
            _seedbed_lines(ax_m, result.extra["seedbed"], 0.35 * span + 40)
        for ax, frame_x in ((ax_m, tr["machine"]["x"]), (ax_g, tr["x"])):
            if soil is not None:
                ax.axhline(soil, color="saddlebrown", lw=1.0, label="soil surface")
            for name, p in pts.items():
                if p.get("found"):
                    x = p["x"] if ax is ax_m else p["x_ground"]
                    ax.plot(x, p["y"], "o", color=COLOURS[name], ms=6)
                    ax.annotate(name, (x, p["y"]), textcoords="offset points", xytext=(5, 4), fontsize=9)
    ax_m.set_title("machine frame (forward = +X)")
    ax_g.set_title(f"ground frame, {result.extra.get('operation', {}).get('forward_speed_m_s', '?')} m/s")
    for ax in (ax_m, ax_g):
        style_plane(ax)
    legend_below(ax_m, fontsize=7)
    fig.suptitle(f"{result.name}: claw-tip trajectory", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

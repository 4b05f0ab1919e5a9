"""Figures of a rotary_planetary result, drawn from result.json alone (its facts' curves; the pitch curves from the
design in closed form)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.kinds.rotary_planetary.export import pitch_curve_columns  # noqa: E402
from synthesis.report.legends import legend_below, save_overlay  # noqa: E402
from synthesis.result import Result  # noqa: E402

#: claw attitude ticks drawn along the loop, and their length (mm)
TICKS, TICK_MM = 24, 25.0


def _loop(ax, x, y, att, motion: dict, title: str) -> None:
    ax.plot(x, y, "-", color="tab:blue", lw=1.5, label="claw tip")
    step = max(1, len(x) // TICKS)
    for i in range(0, len(x) - 1, step):
        a = math.radians(att[i])
        ax.plot([x[i] - TICK_MM * math.cos(a), x[i]], [y[i] - TICK_MM * math.sin(a), y[i]], "-",
                color="tab:red", lw=1.0, label="claw (root to tip)" if i == 0 else None)
    ax.axhline(motion.get("soil_y_mm", 0.0), color="saddlebrown", lw=1.0, label="soil surface")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (rearwards), mm")
    ax.set_ylabel("y (up), mm")
    ax.set_title(title, fontsize=10)


def trajectory_figure(result: Result, path: Path) -> None:
    """The claw tip's loop in the machine frame (with the key poses) and in the ground frame, claw attitude ticks."""
    motion = result.extra.get("motion", {})
    c = motion["curves"]
    x, y, xg, att = (np.asarray(c[k], dtype=float) for k in ("x", "y", "x_ground", "claw_attitude_deg"))
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 5.8))
    _loop(ax, x, y, att, motion, "machine frame (origin: carrier axis)")
    ax.plot([0.0], [0.0], "k+", ms=10)
    for name, p in (motion.get("poses") or {}).items():
        t = p["target"]
        ax.plot(t["x"], t["y"], "o", mfc="none", color="tab:green", ms=8)
        ax.annotate(f"{name} ({p['miss_mm']:.2f} mm)", (t["x"], t["y"]), textcoords="offset points", xytext=(6, 6),
                    fontsize=8, color="tab:green")
    # two turns on the ground: the two arms' loops half a turn apart follow each other by the plant spacing
    spacing = motion.get("plant_spacing_mm", 0.0)
    for j in range(3):
        _loop(ax2, xg - j * spacing, y, att, motion, "ground frame (x_ground = x - V t), three plants") if j == 0 \
            else ax2.plot(xg - j * spacing, y, "-", color="tab:blue", lw=0.8, alpha=0.5)
    legend_below(ax)
    legend_below(ax2)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def law_figure(result: Result, path: Path) -> None:
    """The pair ratios over a turn and the planet's (arm's) swing F."""
    c = result.extra.get("motion", {})["curves"]
    phi = np.asarray(c["carrier_deg"], dtype=float)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    ax.plot(phi, c["pair1_ratio"], label="pair 1 (sun -> idler 1)")
    ax.plot(phi, c["pair2_ratio"], label="pair 2 (idler 2 -> planet)")
    ax.plot(phi, np.asarray(c["pair1_ratio"]) * np.asarray(c["pair2_ratio"]), "k--", lw=1, label="train (product)")
    ax.set_xlabel("carrier angle, deg")
    ax.set_ylabel("ratio i = r_driver / r_driven")
    ax.set_xlim(0, 360)
    ax.grid(alpha=0.3)
    legend_below(ax)
    ax2.plot(phi, c["claw_attitude_deg"], color="tab:red", label="claw attitude")
    ax2.set_xlabel("carrier angle, deg")
    ax2.set_ylabel("deg from +x")
    ax2.set_xlim(0, 360)
    ax2.grid(alpha=0.3)
    legend_below(ax2)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def pitch_curves_figure(result: Result, path: Path) -> None:
    """The four pitch curves, each in its own frame about its axis."""
    c = pitch_curve_columns(result.design, 721)
    fig, axes = plt.subplots(1, 4, figsize=(14, 4))
    for ax, (title, col) in zip(axes, (("sun (fixed)", "pair1_driver"), ("idler gear 1", "pair1_driven"),
                                       ("idler gear 2", "pair2_driver"), ("planet", "pair2_driven"))):
        a, r = np.radians(c[f"{col}_deg"]), c[f"{col}_radius_mm"]
        ax.plot(r * np.cos(a), r * np.sin(a), "-", color="tab:blue")
        ax.plot([0], [0], "k+", ms=10)
        ax.set_aspect("equal")
        ax.set_title(f"{title}: r {r.min():.1f}-{r.max():.1f} mm", fontsize=9)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def compare_figure(results: list[Result], folder: Path) -> list[str]:
    """The claw tip's loop (machine frame) and the claw's attitude over a turn of every candidate, baseline first."""
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    for k, r in enumerate(results):
        c = ((r.extra or {}).get("motion") or {}).get("curves")
        if not c:
            continue
        style = "-" if k == 0 else "--"
        ax.plot(c["x"], c["y"], style, lw=1.3, label=r.name)
        ax2.plot(c["carrier_deg"], c["claw_attitude_deg"], style, lw=1.3, label=r.name)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (rearwards), mm")
    ax.set_ylabel("y (up), mm")
    ax2.set_xlabel("carrier angle, deg")
    ax2.set_ylabel("claw attitude, deg from +x")
    return save_overlay(fig, (ax, ax2), folder, "compare_rotary_planetary.png")

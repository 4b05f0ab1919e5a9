"""Figures of a tillage_linkage result, drawn from result.json alone (never re-solving)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402

TURNS = 3       # crank turns drawn in the ground frame (Fig. 20)


def _machine(ax, result: Result) -> None:
    f, d = result.extra, result.design
    c = f["curve"]
    ground = -f["height_c_mm"]
    ax.plot(c["x"], c["y"], "-", color="tab:green", lw=1.6, label="tool tip D (eq 7)")
    a_pt = np.array(f["positions"][0]["A"])
    t = np.linspace(0.0, 2 * np.pi, 200)
    ax.plot(a_pt[0] + d["a"] * np.cos(t), a_pt[1] + d["a"] * np.sin(t), ":", color="grey", lw=0.9,
            label="crank circle (B)")
    for k, p in enumerate(f["positions"]):
        b, dd = np.array(p["B"]), np.array(p["D"])
        ax.plot(*np.column_stack([b, dd]), "-", color="tab:blue", lw=0.8, alpha=0.6)
        ax.annotate(f"{k + 1}'", dd, textcoords="offset points", xytext=(3, -9), fontsize=7, color="tab:green")
        ax.annotate(f"{k + 1}", b, textcoords="offset points", xytext=(3, 3), fontsize=7, color="tab:blue")
    ax.plot(*a_pt, "ks", ms=6)
    ax.annotate("A", a_pt, textcoords="offset points", xytext=(6, -12))
    ax.plot(0, 0, "ko", ms=6)
    ax.annotate("C (rollers)", (0, 0), textcoords="offset points", xytext=(6, -12), fontsize=8)
    ax.axhline(ground, color="saddlebrown", lw=1.4, label="ground")
    ax.axhspan(ground - 1.5 * max(f["lowest_point"]["depth_mm"], 1.0), ground, color="saddlebrown", alpha=0.12)
    lo = f["lowest_point"]
    ax.set_title(f"depth {lo['depth_mm']:.1f} mm, lift {f['highest_point']['lift_mm']:.1f} mm, slot angle "
                 f"<= {f['bar_slot_angle_max_deg']:.1f} deg, engagement {f['bar_engagement_mm']:.1f} mm", fontsize=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x, mm (machine frame, travel to +x)")
    ax.set_ylabel("y, mm (C at 0)")
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=7)


def _ground(ax, result: Result) -> None:
    tr = result.trajectory
    assert tr is not None, "the figures are drawn from a result with its trajectory"
    x, y = np.array(tr["x"]), np.array(tr["y"])
    advance = result.extra["operation"]["advance_per_turn_mm"]
    for k in range(TURNS):
        ax.plot(x + k * advance, y, "-", color="tab:green", lw=1.3, label="tool tip D" if k == 0 else None)
    ax.axhline(0.0, color="saddlebrown", lw=1.4, label="ground")
    ax.axhspan(min(y.min(), 0.0) - 20.0, 0.0, color="saddlebrown", alpha=0.12)
    vx = np.array(tr["vx"])
    soil = y < 0.0
    ax.plot(x[soil], y[soil], ".", color="tab:red", ms=2.5,
            label=f"in the soil (ground speed <= {vx[soil].max() / 1000.0:.3f} m/s)" if soil.any() else None)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("X, mm (ground frame)")
    ax.set_ylabel("height above ground, mm")
    op = result.extra["operation"]
    ax.set_title(f"Fig. 20: {op['crank_speed_r_min']:g} r/min, {op['forward_speed_m_s']:g} m/s, "
                 f"{advance:.0f} mm per turn", fontsize=9)
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=7)


def _rates(ax, result: Result) -> None:
    c = result.extra["curve"]
    ax.plot(c["crank_deg"], c["speed_mm_per_rad"], color="tab:blue", label="v = |dD/domega| (eq 9), mm/rad")
    ax.plot(c["crank_deg"], c["acceleration_mm_per_rad2"], color="tab:orange",
            label="|d2D/domega2| (eq 11), mm/rad^2")
    ax2 = ax.twinx()
    ax2.plot(c["crank_deg"], c["direction_deg"], ":", color="tab:purple", label="direction delta (eq 10), deg")
    ax2.plot(c["crank_deg"], c["bar_angle_deg"], "--", color="tab:grey", label="bar angle phi to AC (eq 3), deg")
    ax2.set_ylabel("deg")
    for w0, w1 in result.extra["soil_phases_crank_deg"]:
        for lo, hi in ((w0, min(w1, 360.0)), (0.0, w1 - 360.0)) if w1 > 360.0 else ((w0, w1),):
            ax.axvspan(lo, hi, color="saddlebrown", alpha=0.12)
    ax.set_xlabel("crank angle omega, deg (shaded: in the soil)")
    ax.set_ylabel("per unit crank angle")
    ax.grid(alpha=0.3)
    entries = [e for a in (ax, ax2) for e in zip(*a.get_legend_handles_labels())]   # one legend, both y axes
    legend_below(ax, ncol=2, fontsize=7, handles=[h for h, _ in entries], labels=[t for _, t in entries])


def tillage_figure(result: Result, path: Path) -> None:
    fig, axes = plt.subplots(1, 3, figsize=(18, 5.6))
    _machine(axes[0], result)
    _ground(axes[1], result)
    _rates(axes[2], result)
    d = result.design
    fig.suptitle(f"{result.name}: a {d['a']:.1f}, b {d['b']:.1f}, c {d['c']:.1f} mm, theta {d['theta']:.2f} deg, "
                 f"C {d['height_c']:.1f} mm above ground", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def compare_figure(results: list[Result], folder: Path) -> list[str]:
    """The tool tip's ground-frame path of every candidate (one turn), baseline first."""
    fig, ax = plt.subplots(figsize=(9, 4.8))
    for k, r in enumerate(results):
        tr = r.trajectory
        if not tr:
            continue
        ax.plot(tr["x"], tr["y"], "-" if k == 0 else "--", lw=1.4,
                label=f"{r.name} (depth {r.extra['lowest_point']['depth_mm']:.1f} mm)")
    ax.axhline(0.0, color="saddlebrown", lw=1.2)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("X, mm (ground frame)")
    ax.set_ylabel("height above ground, mm")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        legend_below(ax, ncol=2, fontsize=8)
    fig.tight_layout()
    name = "compare_tillage_path.png"
    fig.savefig(folder / name, dpi=110)
    plt.close(fig)
    return [name]

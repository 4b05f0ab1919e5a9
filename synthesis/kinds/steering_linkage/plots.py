"""Figures of a steering_linkage result, drawn from result.json alone (never re-solving)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402


def _linkage(ax, facts: dict) -> None:
    positions = facts.get("positions", [])
    colours = plt.cm.viridis(np.linspace(0.0, 0.85, max(1, len(positions))))
    for p, colour in zip(positions, colours):
        kl, tl, tr, kr = (np.array(p[k]) for k in ("K_L", "T_L", "T_R", "K_R"))
        label = f"inside {p['inside_deg']:g} deg, outside {p['outside_deg']:.2f} deg"
        ax.plot(*np.column_stack([kl, tl]), "-", color=colour, lw=2.2)
        ax.plot(*np.column_stack([kr, tr]), "-", color=colour, lw=2.2)
        ax.plot(*np.column_stack([tl, tr]), "--", color=colour, lw=1.2, label=label)
    if positions:
        kl, kr = np.array(positions[0]["K_L"]), np.array(positions[0]["K_R"])
        ax.plot(*np.column_stack([kl, kr]), "k-", lw=3.0, label="front axle (kingpins)")
        for name, p in (("K_L", kl), ("K_R", kr)):
            ax.plot(*p, "ks", ms=6)
            ax.annotate(name, p, textcoords="offset points", xytext=(-10, 8), fontsize=8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x, mm (to the right kingpin)")
    ax.set_ylabel("y, mm (forward)")
    ax.grid(alpha=0.3)
    legend_below(ax, fontsize=7)


def steering_figure(result: Result, path: Path) -> None:
    """The trapezoid at several inside locks (left turn) and its steering error over the range, with the
    published Table 12 points where the result carries them."""
    facts = result.extra
    d = result.design
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 5.2))
    _linkage(ax, facts)
    ax.set_title(f"arm {d['arm_length']:.2f} mm, base angle {d['base_angle']:.3f} deg, tie rod "
                 f"{facts.get('tie_rod_length_mm', float('nan')):.2f} mm", fontsize=10)
    curve = facts.get("curve")
    if curve:
        ax2.plot(curve["inside_deg"], curve["error_deg"], color="tab:blue", lw=1.6,
                 label=f"this trapezoid: outside - Ackermann (max {facts['max_steering_error_deg']:.3f} deg)")
        axb = ax2.twinx()
        mu = np.minimum(np.array(curve["mu_outer_deg"]), 180.0 - np.array(curve["mu_outer_deg"]))
        mi = np.minimum(np.array(curve["mu_inner_deg"]), 180.0 - np.array(curve["mu_inner_deg"]))
        axb.plot(curve["inside_deg"], mu, ":", color="tab:purple", lw=1.0, label="transmission angle, outer arm")
        axb.plot(curve["inside_deg"], mi, "-.", color="tab:purple", lw=1.0, label="transmission angle, inner arm")
        axb.set_ylabel("tie-rod transmission angle (acute), deg", color="tab:purple")
    else:
        ax2.text(0.5, 0.5, f"dead centre at inside lock {facts.get('dead_centre_inside_deg', float('nan')):.2f} deg",
                 ha="center", transform=ax2.transAxes)
    rows = facts.get("table12", {}).get("rows", [])
    if rows:
        b = [r["inside_deg"] for r in rows]
        ax2.plot(b, [r["actual_error_vs_consistent_ackermann_deg"] for r in rows], "o", color="tab:red",
                 label="published actual - Ackermann (fitted w)")
        ax2.plot(b, [-r["error_of_printed_columns_deg"] for r in rows], "x", color="tab:orange",
                 label="published actual - published accurate")
    ax2.axhline(0.0, color="k", lw=0.6)
    ax2.set_xlabel("inside lock beta, deg")
    ax2.set_ylabel("steering error alpha - alpha_Ackermann, deg")
    ax2.grid(alpha=0.3)
    twin = [a for a in fig.axes if a is not ax2 and a.get_position().bounds == ax2.get_position().bounds]
    entries = [e for a in [ax2, *twin] for e in zip(*a.get_legend_handles_labels())]   # one legend, both y axes
    legend_below(ax2, ncol=2, fontsize=7, handles=[h for h, _ in entries], labels=[t for _, t in entries])
    radius = facts.get("turning_radius", {})
    title = (f"{result.name}: steering trapezoid; turning radius L / sin(beta_max) = "
             f"{radius.get('value_mm', float('nan')) / 1000:.2f} m at inside lock {radius.get('inside_lock_deg', float('nan')):g} deg")
    model3 = facts.get("table12", {}).get("turning_radius")
    if model3:
        title += (f" (Model-3 at {model3['inside_lock_deg']:g} deg: {model3['named_value_mm'] / 1000:.2f} m, "
                  f"printed {model3['printed_mm'] / 1000:.1f} m)")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def compare_figure(results: list[Result], folder: Path) -> list[str]:
    """The steering error of every candidate over its range, baseline first."""
    fig, ax = plt.subplots(figsize=(8, 4.6))
    for k, r in enumerate(results):
        curve = r.extra.get("curve")
        if not curve:
            continue
        ax.plot(curve["inside_deg"], curve["error_deg"], "-" if k == 0 else "--", lw=1.4,
                label=f"{r.name} (max {r.extra['max_steering_error_deg']:.3f} deg)")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("inside lock beta, deg")
    ax.set_ylabel("alpha - alpha_Ackermann, deg")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        legend_below(ax, ncol=2, fontsize=8)
    fig.tight_layout()
    name = "compare_steering_error.png"
    fig.savefig(folder / name, dpi=110)
    plt.close(fig)
    return [name]

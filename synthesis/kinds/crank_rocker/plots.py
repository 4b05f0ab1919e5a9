"""Figures of a crank_rocker result, drawn from result.json alone (never re-solving)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.legends import legend_below, save_overlay  # noqa: E402
from synthesis.result import Result  # noqa: E402

EXTREME_STYLE = {"folded": ("tab:blue", "folded extreme"), "extended": ("tab:red", "extended extreme")}


def _linkage(ax, joints: dict, colour: str, label: str) -> None:
    g, a, f, e = (np.array(joints[k]) for k in ("G", "A", "F", "E"))
    ax.plot(*np.column_stack([g, f]), "-", color=colour, lw=2.2, label=f"{label}: crank GF")
    ax.plot(*np.column_stack([f, e]), "-", color=colour, lw=1.4, alpha=0.8)
    ax.plot(*np.column_stack([a, e]), "--", color=colour, lw=1.8)
    for name, p in (("F", f), ("E", e)):
        ax.plot(*p, "o", color=colour, ms=4)
        ax.annotate(name, p, textcoords="offset points", xytext=(4, 4), fontsize=8, color=colour)


def extremes_figure(result: Result, path: Path) -> None:
    """The mechanism at its two extreme positions (crank circle, rocker arc) and its motion over a turn."""
    motion = result.extra.get("motion", {})
    d = result.design
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5.2))
    ax.plot([0, d["l10"]], [0, 0], "k-", lw=2.5, label="frame AG")
    t = np.linspace(0, 2 * math.pi, 200)
    ax.plot(d["l7"] * np.cos(t), d["l7"] * np.sin(t), ":", color="grey", lw=0.8)
    for name, p in (("G", (0, 0)), ("A", (d["l10"], 0))):
        ax.plot(*p, "ks", ms=6)
        ax.annotate(name, p, textcoords="offset points", xytext=(-12, -12), fontsize=9)
    if motion.get("crank_turns"):
        for key, (colour, label) in EXTREME_STYLE.items():
            _linkage(ax, motion["extremes"][key]["joints"], colour, label)
        c = motion["curve"]
        ax.plot(c["E_x"], c["E_y"], "-", color="tab:green", lw=1.0, label="rocker tip E")
        ax2.plot(c["crank_deg"], c["rocker_deg"], color="tab:green", label="rocker angle beta")
        ax2b = ax2.twinx()
        ax2b.plot(c["crank_deg"], c["transmission_deg"], color="tab:purple", lw=1.0, label="transmission angle mu")
        gmin = result.extra["requirements"]["min_transmission_angle_deg"]
        for v in (gmin, 180 - gmin):
            ax2b.axhline(v, color="tab:purple", ls=":", lw=0.8)
        ax2b.set_ylabel("transmission angle mu, deg", color="tab:purple")
        for key, (colour, label) in EXTREME_STYLE.items():
            ax2.axvline(motion["extremes"][key]["crank_deg"], color=colour, ls="--", lw=0.9, label=label)
        ax2.set_title(f"K = {motion['time_ratio']:.4f}, swing = {motion['rocker_swing_deg']:.3f} deg, "
                      f"gamma_min = {motion['min_transmission_angle_deg']:.3f} deg", fontsize=10)
    else:
        ax2.text(0.5, 0.5, "the crank cannot make a full turn", ha="center", transform=ax2.transAxes)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x, mm (G at the origin, A on +x)")
    ax.set_ylabel("y, mm")
    ax.grid(alpha=0.3)
    legend_below(ax, fontsize=7)
    ax.set_title(" ".join(f"{k} = {v:.2f}" for k, v in d.items()) + " mm", fontsize=10)
    ax2.set_xlabel("crank angle from G -> A, deg")
    ax2.set_ylabel("rocker angle A -> E, deg", color="tab:green")
    ax2.grid(alpha=0.3)
    legend_below(ax2, fontsize=7)
    fig.suptitle(f"{result.name}: crank-rocker at its extreme positions", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def compare_figure(results: list[Result], folder: Path) -> list[str]:
    """Rocker angle and transmission angle over a turn of every candidate, baseline first."""
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    for k, r in enumerate(results):
        m = r.extra.get("motion", {})
        if not m.get("crank_turns"):
            continue
        c = m["curve"]
        style = "-" if k == 0 else "--"
        label = f"{r.name} (K {m['time_ratio']:.3f}, psi {m['rocker_swing_deg']:.2f}, gmin {m['min_transmission_angle_deg']:.2f})"
        beta = np.array(c["rocker_deg"])
        ax.plot(c["crank_deg"], beta - beta.min(), style, lw=1.3, label=label)
        ax2.plot(c["crank_deg"], c["transmission_deg"], style, lw=1.3, label=r.name)
    ax.set_xlabel("crank angle, deg")
    ax.set_ylabel("rocker angle above its minimum, deg")
    ax2.set_xlabel("crank angle, deg")
    ax2.set_ylabel("transmission angle mu, deg")
    return save_overlay(fig, (ax, ax2), folder, "compare_crank_rocker.png")

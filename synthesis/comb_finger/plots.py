"""Figures of a comb_finger result, drawn from result.json alone: the front view (Fig. 28b reconstructed: both
units' tip circles and drums, S, R, E, F, D, P) and the side view of the combing (the tip's rise over the
machine's travel, against the straight line of eq 21)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from synthesis.result import Result  # noqa: E402


def finger_figure(result: Result, path: Path) -> None:
    ex = result.extra
    pts, cv = ex["points_mm"], ex["curves"]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12.5, 5.2), gridspec_kw={"width_ratios": [1.3, 1]})
    rho = cv["drum_radius_mm"]
    for sign, colour in ((1, "tab:blue"), (-1, "tab:orange")):
        xs = [sign * x for x in cv["tip_circle"]["x"]]
        ax.plot(xs + xs[:1], cv["tip_circle"]["y"] + cv["tip_circle"]["y"][:1], color=colour, lw=1.3)
        sx, sy = sign * pts["S"][0], pts["S"][1]
        ax.add_patch(plt.Circle((sx, sy), rho, fill=True, alpha=0.15, color=colour))
        ax.plot([sx, sign * pts["R"][0]], [sy, pts["R"][1]], color=colour, lw=1.0)
        ax.plot(sx, sy, "+", color=colour, ms=9)
        ax.plot(sign * pts["R"][0], pts["R"][1], "o", color=colour, ms=4)
    for name in ("S", "R", "E", "F", "D", "P"):
        x, y = pts[name]
        ax.annotate(name, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=9)
    ax.plot([pts["D"][0], pts["R"][0]], [pts["D"][1], pts["R"][1]], ":", color="grey", lw=1.0)
    ax.plot([0, 0], [0, pts["F"][1] * 1.1], "--", color="grey", lw=0.8)
    half = ex["row_spacing_mm"] / 2.0
    for xline in (-half, half):
        ax.axvline(xline, color="tab:red", lw=0.8, ls="-.")
    ax.axhline(0.0, color="saddlebrown", lw=1.5)
    ax.set_aspect("equal")
    ax.set_xlabel("across the row from its centre line, mm (dash-dot: half the row spacing)")
    ax.set_ylabel("above the ground line, mm")
    ax.set_title(f"{result.name}: front view (Fig. 28b), alpha {result.design['alpha']:.3g} deg, "
                 f"PD {ex['root_clearance_PD_mm']:.3g} mm", fontsize=9)
    c = cv["combing"]
    ax2.plot(c["travel_mm"], c["rise_mm"], color="tab:blue", lw=1.5, label="finger tip (turn from its lowest point to F)")
    ax2.plot([0, c["travel_mm"][-1]], [0, c["rise_mm"][-1]], "--", color="black", lw=1.0,
             label=f"eq 21 straight line: theta = {ex['combing_angle_theta_deg']:.3g} deg")
    ax2.set_aspect("equal")
    ax2.set_xlabel("machine travel V_s t, mm")
    ax2.set_ylabel("tip rise above its lowest point, mm")
    ax2.set_title(f"side view: t = {ex['combing_time_s']:.3g} s, l = {ex['combing_lift_l_mm']:.3g} mm, "
                  f"V_s = {ex['machine_speed_m_s']:g} m/s", fontsize=9)
    ax2.legend(fontsize=8)
    for a in (ax, ax2):
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

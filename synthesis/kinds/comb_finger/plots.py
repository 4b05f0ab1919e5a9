"""Figures of a comb_finger result, drawn from result.json alone: the front view (Fig. 28b reconstructed: both
units' tip circles and drums, S, R, E, F, D, P) and the side view of the combing (the tip's rise over the
machine's travel, against the straight line of eq 21)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from synthesis.report.legends import legend_below  # noqa: E402
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
    legend_below(ax2, ncol=1, fontsize=8)
    for a in (ax, ax2):
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def comparison(results: list[Result]):
    """The figure of :func:`compare_figure`: every candidate's finger tip, baseline first -- the front view (its tip
    circle) and the side view of its combing turn, from the tip's lowest point to F over the machine's travel, with
    the eq 21 chord (the combing angle theta) dotted.  Drawn from each result's facts (``curves``), which results of
    every schema version hold."""
    fig, (front, side) = plt.subplots(1, 2, figsize=(12.5, 5.0), gridspec_kw={"width_ratios": [1, 1.3]})
    for k, r in enumerate(results):
        cv = r.extra["curves"]
        colour, style = f"C{k % 10}", "-" if k == 0 else "--"
        circle = cv["tip_circle"]
        front.plot(circle["x"] + circle["x"][:1], circle["y"] + circle["y"][:1], style, color=colour, lw=1.3,
                   label=r.name)
        c = cv["combing"]
        side.plot(c["travel_mm"], c["rise_mm"], style, color=colour, lw=1.4,
                  label=f"{r.name}: theta {r.extra['combing_angle_theta_deg']:.3g} deg")
        side.plot([0.0, c["travel_mm"][-1]], [0.0, c["rise_mm"][-1]], ":", color=colour, lw=1.0)
    front.axvline(0.0, color="grey", lw=0.8, ls="--")
    front.axhline(0.0, color="saddlebrown", lw=1.5)
    front.set_aspect("equal", adjustable="datalim")
    front.set_xlabel("across the row from its centre line, mm")
    front.set_ylabel("above the ground line, mm")
    front.set_title("front view: the left finger's tip circle (machine frame)", fontsize=9)
    side.set_aspect("equal", adjustable="datalim")
    side.set_xlabel("machine travel V_s t from the tip's lowest point, mm")
    side.set_ylabel("tip rise above its lowest point, mm")
    side.set_title("side view, ground frame: the combing turn to F (dotted: the eq 21 chord)", fontsize=9)
    for ax in (front, side):
        ax.grid(alpha=0.3)
        legend_below(ax, ncol=2, fontsize=8)
    fig.tight_layout()
    return fig


def compare_figure(results: list[Result], folder: Path) -> list[tuple[str, str]]:
    """compare_comb_finger.png (:func:`comparison`)."""
    fig = comparison(results)
    fig.savefig(folder / "compare_comb_finger.png", dpi=110)
    plt.close(fig)
    return [("compare_comb_finger.png", "the candidates' finger tips: front view, and the combing turn over the "
                                        "machine's travel with its eq 21 chord (the combing angle)")]

"""Figures of a guide_tube result, drawn from result.json alone (never re-solving)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.errors import NothingToDraw  # noqa: E402
from synthesis.report.labels import baseline_note  # noqa: E402
from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402

PHASES = (("t_fall", "free fall (eq 14)", "tab:blue"), ("t_slide", "slide on the wall (eq 17)", "tab:orange"),
          ("t_after", "wall end to paddy (eq 19-21)", "tab:green"))


def _unavailable(result: Result, path: Path) -> bool:
    """A run whose design could not be evaluated (e.g. every start sticks) has no drop facts: say so."""
    if "tubes" in result.extra:
        return False
    fig, ax = plt.subplots(figsize=(8, 2.5))
    ax.axis("off")
    sticks = result.extra.get("sticks")       # a checked design whose seedling sticks: where, and what to change
    text = (f"{result.name}: no drop to draw: " + sticks if isinstance(sticks, str)
            else f"{result.name}: no design the drop model could evaluate ({result.status})")
    ax.text(0.5, 0.5, "\n".join(textwrap.wrap(text, 100)), ha="center", va="center", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def _label(tube: dict) -> str:
    return tube["name"] + (f"/{tube['mirror']}" if tube.get("mirror") else "")


def _spacing_rule_limit(result: Result) -> float | None:
    rule = next((r for r in result.rules if r["name"] == "spacing_error"), None)
    return None if rule is None else rule["limit"][1]


def _spacing_axis(ax, result: Result, label: str | None = None, colour: str = "tab:red") -> None:
    sweep = result.extra["row_spacing_sweep"]
    ax.plot(sweep["spacing_mm"], sweep["spacing_error_mm"], color=colour, lw=1.5, label=label)


def drop_times_figure(result: Result, path: Path) -> None:
    """Phase breakdown of each tube's drop time, and the plant-position error over the row spacings."""
    if _unavailable(result, path):
        return
    ex = result.extra
    tubes = ex["tubes"]
    rows = ex["rows"]
    fig, (ax_t, ax_e) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1.2, 1]})
    y = np.arange(len(tubes))
    left = np.zeros(len(tubes))
    for key, label, colour in PHASES:
        widths = np.array([t[key] for t in tubes])
        ax_t.barh(y, widths, left=left, color=colour, label=label, height=0.55)
        left += widths
    for yi, t in zip(y, tubes):
        ax_t.annotate(f"t_z = {t['t_z']:.4f} s  (delta = {t['delta_deg']:.2f} deg)", (t["t_z"], yi),
                      xytext=(4, 0), textcoords="offset points", va="center", fontsize=8)
    ax_t.set_yticks(y, [f"tube {_label(t)}" for t in tubes])
    ax_t.set_xlim(0, 1.45 * max(t["t_z"] for t in tubes))
    ax_t.set_xlabel("time, s")
    ax_t.set_title(f"drop time at {rows['design_spacing_mm']:g} mm row spacing: spread "
                   f"{1000 * ex['landing_time_spread_s']:.3g} ms = {ex['spacing_error_mm']:.3g} mm "
                   f"at {rows['forward_speed']:g} m/s", fontsize=9)
    legend_below(ax_t, fontsize=7)
    _spacing_axis(ax_e, result, "forward speed x landing-time spread")
    limit = _spacing_rule_limit(result)
    if limit is not None:
        ax_e.axhline(limit, color="k", ls="--", lw=0.9, label=f"limit {limit:g} mm")
    ax_e.axvline(rows["design_spacing_mm"], color="grey", ls=":", lw=0.9, label="design row spacing")
    ax_e.set_xlabel("row spacing, mm")
    ax_e.set_ylabel("plant-position error, mm")
    speed = rows["forward_speed"]
    spread_axis = ax_e.secondary_yaxis("right", functions=(lambda e: e / speed, lambda ms: ms * speed))
    spread_axis.set_ylabel("landing-time spread, ms")
    ax_e.set_ylim(bottom=0)
    ax_e.grid(alpha=0.3)
    legend_below(ax_e, ncol=1, fontsize=7)
    ax_e.set_title("plant-position error over the row spacings (same angles)", fontsize=9)
    fig.suptitle(f"{result.name}: guide-tube drop times (mu = {ex['physics']['mu']:.4g}, "
                 f"{ex['physics']['mu_source']})", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def drop_profile_figure(result: Result, path: Path) -> None:
    """Height above the paddy against time (ODE), with the closed form's phase ends marked."""
    if _unavailable(result, path):
        return
    ex = result.extra
    fig, ax = plt.subplots(figsize=(8, 5))
    for tube, colour in zip(ex["tubes"], plt.rcParams["axes.prop_cycle"].by_key()["color"]):
        ode = tube["ode"]
        ax.plot(ode["profile_t"], ode["profile_height_mm"], color=colour, lw=1.4,
                label=f"tube {_label(tube)}, delta = {tube['delta_deg']:.2f} deg (ODE)")
        below = tube["h5_mm"] + tube["h6_mm"]
        ends_t = [tube["t_fall"], tube["t_fall"] + tube["t_slide"], tube["t_z"]]
        ends_h = [below + tube["h2_mm"], below, 0.0]
        ax.plot(ends_t, ends_h, "o", color=colour, mfc="none", ms=7)
    ax.plot([], [], "o", color="k", mfc="none", label="phase ends, closed form")
    ax.set_xlabel("time after the drop, s")
    ax.set_ylabel("height above the paddy, mm")
    ax.set_ylim(bottom=0)
    ax.set_xlim(left=0)
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=8)
    ax.set_title(f"{result.name}: drop profiles at {ex['rows']['design_spacing_mm']:g} mm row spacing; "
                 f"closed form - ODE <= {ex['closed_form_vs_ode_max_s']:.1e} s", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def sensitivity_figure(result: Result, path: Path) -> None:
    """Plant-position error when mu or v_L is 20 % off the value the design used."""
    if _unavailable(result, path):
        return
    ex = result.extra
    sens = ex["sensitivity"]
    change = [100 * (f - 1) for f in sens["factors"]]
    fig, ax = plt.subplots(figsize=(8, 5))
    for key, label, colour in (("mu", f"friction mu (nominal {ex['physics']['mu']:.3g})", "tab:red"),
                               ("terminal_speed", f"float speed v_L (nominal {ex['physics']['terminal_speed']} m/s)",
                                "tab:blue")):
        for which, style, suffix in (("design_spacing_mm", "-o", f"at {ex['rows']['design_spacing_mm']:g} mm"),
                                     ("worst_over_spacings_mm", "--", "worst over the row spacings")):
            values = [np.nan if v is None else v for v in sens[key][which]]
            ax.plot(change, values, style, color=colour, lw=1.3, ms=4, label=f"{label}, {suffix}")
            for c, v in zip(change, sens[key][which]):
                if v is None:
                    ax.annotate("sticks", (c, 0), color=colour, fontsize=7, rotation=90, va="bottom")
    ax.set_xlabel("change of the parameter, %")
    ax.set_ylabel("plant-position error, mm")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=7)
    ax.set_title(f"{result.name}: sensitivity of the plant-position error "
                 f"({ex['rows']['forward_speed']:g} m/s)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def compare_figures(results: list[Result], folder: Path) -> list[str]:
    """Candidates overlaid (baseline first): drop time per tube, plant-position error over row spacing."""
    name = "guide_tube_compare.png"
    # a run whose design the drop model could not evaluate (every start sticks) has no drop facts: it is named, not
    # drawn, and the others are
    missing = [res.name for res in results if "tubes" not in res.extra]
    baseline_drawn = "tubes" in results[0].extra
    results = [res for res in results if "tubes" in res.extra]
    if not results:
        raise NothingToDraw(f"no candidate has a design the drop model could evaluate ({', '.join(missing)})")
    fig, (ax_t, ax_e) = plt.subplots(1, 2, figsize=(12, 4.6))
    width = 0.8 / len(results)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (res, colour) in enumerate(zip(results, colours * 10)):
        tubes = res.extra["tubes"]
        x = np.arange(len(tubes)) + (k - (len(results) - 1) / 2) * width
        bars = ax_t.bar(x, [t["t_z"] for t in tubes], width, color=colour,
                        label=f"{res.name}: " + ", ".join(f"{t['name']} {t['delta_deg']:.1f} deg" for t in tubes))
        # the bars start at 0 s (a bar's length is its time); the differences, a few ms, are written on them
        ax_t.bar_label(bars, labels=[f"{t['t_z']:.4f}" for t in tubes], fontsize=7, rotation=90, padding=2)
        _spacing_axis(ax_e, res, res.name, colour)
    first = results[0].extra["tubes"]
    ax_t.set_xticks(np.arange(len(first)), [f"tube {_label(t)}" for t in first])
    hi = max(t["t_z"] for r in results for t in r.extra["tubes"])
    ax_t.set_ylim(0.0, 1.25 * hi)           # room for the value labels above the bars
    ax_t.set_ylabel("landing time t_z, s (value on each bar)")
    legend_below(ax_t, ncol=2, fontsize=7)
    ax_e.set_xlabel("row spacing, mm")
    ax_e.set_ylabel("plant-position error, mm")
    ax_e.set_ylim(bottom=0)
    ax_e.grid(alpha=0.3)
    legend_below(ax_e, ncol=2, fontsize=7)
    not_drawn = f"; not drawn, no design the drop model could evaluate: {', '.join(missing)}" if missing else ""
    first = " compared (baseline first)" if baseline_drawn else " compared"
    fig.suptitle("guide tubes" + baseline_note(first, len(results)) + not_drawn, fontsize=11)
    fig.tight_layout()
    fig.savefig(folder / name, dpi=110)
    plt.close(fig)
    return [name]

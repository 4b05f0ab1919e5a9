"""Figures of a clamp_cam result, drawn from result.json alone (never re-solving).

motion.png   follower displacement, velocity, acceleration and pressure angle over a turn (and, with a [dynamics]
             table, the contact force)
profile.png  working profile, pitch curve, base circle and the roller at the segment starts
compare      the same, several results overlaid (baseline first) for ``agrisynth compare``
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.legends import legend_below, legend_right  # noqa: E402
from synthesis.result import Result  # noqa: E402

SEGMENT_COLOURS = {"rise": "#fde0c5", "far_dwell": "#e8f0fa", "return": "#fbd3d3", "near_dwell": "#f3f3f3"}


def _limit(result: Result, name: str):
    for r in result.rules:
        if r["name"] == name:
            return r["limit"][1]
    return None


def _shade_segments(ax, follower: dict) -> None:
    crank, seg = np.array(follower["crank_deg"]), follower["segment"]
    start = 0
    for i in range(1, len(seg) + 1):
        if i == len(seg) or seg[i] != seg[start]:
            ax.axvspan(crank[start], crank[min(i, len(seg) - 1)], color=SEGMENT_COLOURS[seg[start]], lw=0)
            start = i


def _motion_axes(results: list[Result], title: str, contact: bool = False):
    """Follower s, v, a and pressure angle over a turn; ``contact``: a fifth panel, the first result's contact force
    (facts.dynamics of a spec with a [dynamics] table)."""
    fig, axes = plt.subplots(5 if contact else 4, 1, figsize=(9, 11.5 if contact else 9.5), sharex=True)
    unit = results[0].extra["follower"]["unit"]
    labels = (f"s, {unit}", f"v, {unit}/s", f"a, {unit}/s$^2$", "pressure angle, deg")
    keys = ("s", "v", "a", "pressure_angle_deg")
    if len(results) == 1:
        for ax in axes:
            _shade_segments(ax, results[0].extra["follower"])
    for k, res in enumerate(results):
        f = res.extra["follower"]
        for ax, key in zip(axes, keys):
            ax.plot(f["crank_deg"], f[key], lw=1.3, color=f"C{k}", label=res.name if ax is axes[0] else None)
    for ax, label in zip(axes, labels):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    rise, ret = _limit(results[0], "pressure_angle_rise"), _limit(results[0], "pressure_angle_return")
    for value, text in ((rise, "rise limit"), (ret, "return limit")):
        if value is not None:
            for sign in (1, -1):
                axes[3].axhline(sign * value, ls="--", lw=0.9, color="tab:red" if text == "rise limit" else "tab:purple",
                                label=text if sign == 1 else None)
    legend_below(axes[3], fontsize=7)
    legend_right(axes[0], fontsize=7)
    if contact:
        _contact_panel(axes[4], results[0])
    axes[-1].set_xlabel("crank angle on the picker's clock, deg (0 = pick)")
    axes[-1].set_xlim(0, 360)
    axes[-1].set_xticks(np.arange(0, 361, 30))
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def _contact_panel(ax, result: Result) -> None:
    """Contact force between roller and cam over the turn, with its limit and the spring's load."""
    dyn = result.extra["dynamics"]
    crank = dyn["crank_deg"]
    ax.plot(crank, dyn["contact_force_N"], lw=1.3, color="C0", label="contact force, N")
    spring = dyn.get("spring_force_N")
    if spring is not None:
        ax.plot(crank, spring, lw=1.0, ls=":", color="C2", label="spring force, N")
    jump = dyn.get("jump_speed_rpm")
    ax.axhline(0.0, color="0.5", lw=0.8)
    least = _lower_limit(result, "contact_force_min")
    if least is not None:
        ax.axhline(least, ls="--", lw=0.9, color="tab:red", label=f"min contact force {least:g} N")
    ax.set_ylabel("contact force, N")
    ax.grid(alpha=0.3)
    ax.set_title(f"jump speed {'never' if jump is None else f'{jump:.4g} r/min'}", fontsize=8, loc="left")
    legend_below(ax, fontsize=7)


def _lower_limit(result: Result, name: str):
    for r in result.rules:
        if r["name"] == name:
            return r["limit"][0]
    return None


def motion_figure(result: Result, path: Path) -> None:
    cam = result.extra["cam"]
    contact = isinstance((result.extra or {}).get("dynamics"), dict) and "contact_force_N" in result.extra["dynamics"]
    fig = _motion_axes([result], f"{result.name}: {cam['law']} law, {cam['stroke']:g} {cam['stroke_unit']} stroke, "
                                 f"{cam['crank_speed_rpm']:g} r/min", contact=contact)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _draw_profile(ax, result: Result, colour: str, label: str, details: bool) -> None:
    prof = result.extra["profile"]
    wx, wy = np.append(prof["working"]["x"], prof["working"]["x"][0]), np.append(prof["working"]["y"],
                                                                                  prof["working"]["y"][0])
    ax.plot(wx, wy, color=colour, lw=1.6, label=f"{label} working profile")
    if details:
        px, py = np.append(prof["pitch"]["x"], prof["pitch"]["x"][0]), np.append(prof["pitch"]["y"],
                                                                                prof["pitch"]["y"][0])
        ax.plot(px, py, "--", color="tab:gray", lw=0.9, label="pitch curve (roller centre)")
        t = np.linspace(0, 2 * np.pi, 361)
        r0 = prof["base_radius"]
        ax.plot(r0 * np.cos(t), r0 * np.sin(t), ":", color="tab:gray", lw=0.8, label="base circle")
        rr = prof["roller_radius"]
        angles = np.array(prof["cam_angle_deg"])
        starts = result.extra["cam"]["segment_starts_crank_deg"]
        rise0 = starts["rise"]
        for name, crank in starts.items():
            i = int(np.argmin(np.abs(angles - (crank - rise0) % 360.0)))
            cx, cy = prof["pitch"]["x"][i], prof["pitch"]["y"][i]
            ax.add_patch(plt.Circle((cx, cy), rr, fill=False, color="tab:orange", lw=0.9))
            ax.annotate(name.replace("_", " "), (cx, cy), textcoords="offset points", xytext=(6, 6), fontsize=7)
        if "outer" in prof:
            ax.plot(prof["outer"]["x"], prof["outer"]["y"], color="tab:blue", lw=0.9, label="outer flank")
    ax.plot(0, 0, "+", color="k")


def profile_figure(result: Result, path: Path) -> None:
    cam = result.extra["cam"]
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    _draw_profile(ax, result, "k", "", details=True)
    note = (f"min working radius of curvature {cam['min_working_radius_mm']:.3g} mm"
            + ("  (UNDERCUT)" if cam["undercut"] else ""))
    ax.set_title(f"{result.name}: cam frame, {result.extra['profile']['rotation']} rotation\n{note}", fontsize=10)
    ax.set_aspect("equal")
    ax.set_xlabel("x, mm")
    ax.set_ylabel("y, mm")
    ax.grid(alpha=0.3)
    legend_below(ax, fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def compare_figure(results: list[Result], folder: Path) -> list[str]:
    """Overlay several cams (baseline first): motion over a turn and working profiles."""
    folder = Path(folder)
    fig = _motion_axes(results, "clamp cams compared: " + ", ".join(r.name for r in results))
    fig.savefig(folder / "cam_motion_compare.png", dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(7.5, 7.5))
    for k, res in enumerate(results):
        _draw_profile(ax, res, f"C{k}", res.name, details=False)
    ax.set_aspect("equal")
    ax.set_xlabel("x, mm")
    ax.set_ylabel("y, mm")
    ax.grid(alpha=0.3)
    legend_below(ax, fontsize=7)
    ax.set_title("working profiles (cam frame, cam angle 0 = start of the rise)", fontsize=10)
    fig.tight_layout()
    fig.savefig(folder / "cam_profile_compare.png", dpi=110)
    plt.close(fig)
    return ["cam_motion_compare.png", "cam_profile_compare.png"]

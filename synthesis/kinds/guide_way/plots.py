"""Figures of a guide_way result, drawn from result.json alone (never re-solving).

guide_way.png  claw-tip path, roller-centre line and both walls of the groove, undercut stretches marked
cycle.png      curvature of the centre line (as radius) and pressure angle over the arm angle
animation.gif  arm, claw, crank arm and roller over the controlled path
compare        paths, centre lines and the cycle plots of several results overlaid (baseline first)
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.gif import save_gif  # noqa: E402
from synthesis.report.legends import legend_below, legend_right  # noqa: E402
from synthesis.result import Result  # noqa: E402

ANIMATION_FRAMES = 72


def _draw_guide(ax, res: Result, colour: str | None, label: str, details: bool) -> None:
    f = res.extra
    for k, c in enumerate(f["curves"]):
        ax.plot(c["claw_x"], c["claw_y"], color=colour or f"C{k}", lw=1.6,
                label=(f"{label}: claw tip" if colour else f"claw tip {c['name']}") if (k == 0 or not colour) else None)
        ax.plot(c["centre_x"], c["centre_y"], color=colour or f"C{k}", lw=1.0, ls="--",
                label=f"{label}: roller centre" if k == 0 else None)
        for side in ("left", "right"):
            ax.plot(c[f"{side}_x"], c[f"{side}_y"], color=colour or "0.35", lw=0.6,
                    label=("groove walls" if not colour else None) if (k == 0 and side == "left") else None)
    spline = f.get("spline")
    if spline:
        u = spline["uncontrolled_claw"]
        ax.plot(u["x"], u["y"], color=colour or "0.5", lw=1.0, ls=":", label=f"{label}: uncontrolled" if colour else
                "uncontrolled (not guided)")
    if details:
        keys = f["controlled_keys"]
        pts = [(f["curves"][0]["claw_x"][0], f["curves"][0]["claw_y"][0])] + \
              [(c["claw_x"][-1], c["claw_y"][-1]) for c in f["curves"]]
        for name, (x, y) in zip(keys, pts):
            ax.plot(x, y, "ko", ms=3)
            ax.annotate(name, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=9)
        for name, e in (spline or {}).get("keys", {}).items():      # a key point the path misses: its target too
            if f"path_at_{name}" in e:
                (tx, ty), (px, py) = e["target"], e["point"]
                ax.plot([px, tx], [py, ty], color="tab:red", lw=0.8)
                ax.plot(tx, ty, "s", mfc="none", mec="tab:red", ms=7)
                ax.annotate(f"{name} target (missed by {e['miss_mm']:.3g} mm)", (tx, ty), textcoords="offset points",
                            xytext=(4, -12), fontsize=8, color="tab:red")
        for u in f["undercut"]:
            ax.plot(*u["smallest_at_centre"], "rx", ms=9, mew=2)
        ax.plot(0, 0, "k+", ms=10)
        t = np.linspace(0, 2 * np.pi, 200)
        R = f["arm"]["radius"]
        ax.plot(R * np.cos(t), R * np.sin(t), color="0.8", lw=0.6, ls=":")


def guide_figure(result: Result, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(8.5, 8.5))
    _draw_guide(ax, result, None, result.name, details=True)
    n = len(result.extra["undercut"])
    ax.set_title(f"{result.name}: claw-tip path, roller-centre line and groove walls (mm)"
                 + (f"\n{n} undercut stretch(es) marked x" if n else ""), fontsize=10)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    legend_below(ax, fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _rule_limit(result: Result, name: str, side: int):
    return next((r["limit"][side] for r in result.rules if r["name"] == name), None)


def _fold_window(result: Result) -> list[tuple[float, float]]:
    """The arm angles (deg) where the pressure-angle rule is not held: within ``fold_window_deg`` of the fold's
    arriving and leaving angles (synthesis.kinds.guide_way.scene.pressure_masks)."""
    f = result.extra
    w, fold = f.get("fold_window_deg") or 0.0, (f.get("fold") or {}).get("point")
    at = (f.get("key_theta_deg") or {}).get(fold) or {}
    if w <= 0 or "arriving" not in at or "leaving" not in at:
        return []
    return [(at["arriving"] - w, at["arriving"]), (at["leaving"], at["leaving"] + w)]


def _draw_limits(axes, results: list[Result]) -> None:
    """Each design's own limits (the rules it is checked against: they may differ between specs), in its colour
    when several are drawn (a limit two designs share is drawn once, naming both), and the fold window where its
    pressure-angle rule is not held."""
    several = len(results) > 1
    radii: dict[float, list[int]] = {}
    angles: dict[float, list[int]] = {}
    for k, res in enumerate(results):
        radius, limit = _rule_limit(res, "no_undercut", 0), _rule_limit(res, "pressure_angle", 1)
        if radius is not None:
            radii.setdefault(radius, []).append(k)
        if limit is not None:
            angles.setdefault(limit, []).append(k)

    def style(ks: list[int]) -> tuple[str, str]:
        return ("tab:red", "") if not several else (f"C{ks[0]}", f" ({', '.join(results[k].name for k in ks)})")

    for radius, ks in radii.items():
        colour, whose = style(ks)
        rollers = sorted({results[k].extra["arm"]["roller_radius"] for k in ks})
        roller = f"roller {rollers[0]:g} mm + margin {radius - rollers[0]:g} mm" if len(rollers) == 1 else "roller + margin"
        axes[0].axhline(radius, color=colour, ls="--", lw=0.9, label=f"smallest radius allowed {radius:g} mm{whose}: "
                                                                     f"{roller}")
    for limit, ks in angles.items():
        colour, whose = style(ks)
        axes[1].axhline(limit, color=colour, ls="--", lw=0.9, label=f"limit {limit:g} deg{whose}")
    drawn: set = set()
    for k, res in enumerate(results):
        colour, whose = style([k])
        for j, (lo, hi) in enumerate(_fold_window(res)):
            key = (round(lo % 360.0, 6), round(hi % 360.0, 6))
            if key in drawn:
                continue
            drawn.add(key)
            label = f"fold window{whose}: pressure angle not held" if j == 0 else None
            for a, b in _wrapped(lo, hi):
                axes[1].axvspan(a, b, color=colour if several else "0.5", alpha=0.12, label=label)
                label = None


def _wrapped(lo: float, hi: float) -> list[tuple[float, float]]:
    """[lo, hi] deg as spans within [0, 360]."""
    lo, hi = lo % 360.0, lo % 360.0 + (hi - lo)
    return [(lo, min(hi, 360.0))] + ([(0.0, hi - 360.0)] if hi > 360.0 else [])


def _cycle_axes(results: list[Result], title: str):
    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for k, res in enumerate(results):
        for j, c in enumerate(res.extra["curves"]):
            th = np.array(c["theta_deg"]) % 360.0
            order = np.argsort(th) if np.any(np.diff(th) < -180) else slice(None)
            colour = f"C{k}" if len(results) > 1 else f"C{j}"
            lab = res.name if (len(results) > 1 and j == 0) else (c["name"] if len(results) == 1 else None)
            radius = 1.0 / np.maximum(np.abs(np.array(c["curvature_per_mm"])), 1e-9)
            axes[0].plot(th[order], np.minimum(radius, 300.0)[order], color=colour, lw=1.2, label=lab)
            axes[1].plot(th[order], np.array(c["pressure_angle_deg"])[order], color=colour, lw=1.2)
    _draw_limits(axes, results)
    axes[0].set_ylabel("centre-line radius of curvature, mm (cut at 300)")
    axes[1].set_ylabel("pressure angle, deg")
    axes[1].set_xlabel("arm angle theta, deg")
    for ax in axes:
        ax.grid(alpha=0.3)
        legend_right(ax, fontsize=7)
    axes[1].set_xlim(0, 360)
    axes[1].set_xticks(np.arange(0, 361, 30))
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def cycle_figure(result: Result, path: Path) -> None:
    fig = _cycle_axes([result], f"{result.name}: curvature and pressure angle over the controlled path")
    fig.savefig(path, dpi=100)
    plt.close(fig)


def animation(result: Result, path: Path, frames: int = ANIMATION_FRAMES) -> None:
    """Arm OP, claw PM, crank arm PN and the roller over the controlled path (frames evenly in arm angle)."""
    f = result.extra
    cat = lambda key: np.concatenate([np.array(c[key]) for c in f["curves"]])  # noqa: E731
    th = cat("theta_deg")
    px, py, mx, my, nx, ny = (cat(k) for k in ("pivot_x", "pivot_y", "claw_x", "claw_y", "centre_x", "centre_y"))
    idx = np.linspace(0, th.size - 1, frames).astype(int)
    rr = f["arm"]["roller_radius"]
    fig, ax = plt.subplots(figsize=(6, 6))
    _draw_guide(ax, result, None, result.name, details=False)
    lim = max(np.max(np.abs(np.concatenate([mx, my, nx, ny]))) + rr, f["arm"]["radius"]) * 1.08
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.grid(alpha=0.2)
    arm_line, = ax.plot([], [], "k-", lw=3)
    claw_line, = ax.plot([], [], "-", color="tab:green", lw=2.5)
    crank_line, = ax.plot([], [], "-", color="tab:purple", lw=2.5)
    roller = plt.Circle((0, 0), rr, fill=False, color="tab:purple", lw=1.5)
    ax.add_patch(roller)
    text = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=10)
    legend = ax.get_legend()
    if legend:
        legend.remove()

    def frame(k):
        i = idx[k]
        arm_line.set_data([0, px[i]], [0, py[i]])
        claw_line.set_data([px[i], mx[i]], [py[i], my[i]])
        crank_line.set_data([px[i], nx[i]], [py[i], ny[i]])
        roller.center = (nx[i], ny[i])
        text.set_text(f"frame {k + 1}/{frames}, theta = {th[i] % 360:.1f} deg")
        return arm_line, claw_line, crank_line, roller, text

    save_gif(fig, frame, frames, path, fps=10, dpi=100)
    plt.close(fig)


def compare_figures(results: list[Result], folder: Path) -> list[str]:
    folder = Path(folder)
    fig, ax = plt.subplots(figsize=(8.5, 8.5))
    for k, res in enumerate(results):
        _draw_guide(ax, res, f"C{k}", res.name, details=False)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    legend_below(ax, fontsize=7)
    ax.set_title("claw paths, roller-centre lines and groove walls compared (mm)", fontsize=10)
    fig.tight_layout()
    fig.savefig(folder / "guide_way_compare.png", dpi=100)
    plt.close(fig)
    fig = _cycle_axes(results, "guide ways compared: " + ", ".join(r.name for r in results))
    fig.savefig(folder / "cycle_compare.png", dpi=100)
    plt.close(fig)
    return ["guide_way_compare.png", "cycle_compare.png"]

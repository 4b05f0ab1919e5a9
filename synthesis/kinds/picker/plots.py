"""Figures of the picker kinds, drawn from result.json alone (never re-solving)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.gif import save_gif  # noqa: E402
from synthesis.report.legends import legend_below, save_overlay  # noqa: E402
from synthesis.result import Result  # noqa: E402

DOUBLE_CRANK = (("A", "B"), ("B", "C"), ("C", "D"), ("A", "D"), ("C", "M"))
DRIVE = (("G", "F"), ("F", "E"), ("A", "E"), ("A", "G"))


def _target_arc(ax, arc: dict) -> None:
    c, r = arc["centre"], arc["radius"]
    ang = np.radians(arc["start_deg"] + arc["sweep_deg"] * np.linspace(0.0, 1.0, 100))
    ax.plot(c[0] + r * np.cos(ang), c[1] + r * np.sin(ang), "-", color="tab:green", lw=5, alpha=0.25,
            label="target arc M1 -> M2")
    for name in ("m1", "m2"):
        ax.plot(*arc[name], "*", color="tab:green", ms=11)
        ax.annotate(name.upper(), arc[name], textcoords="offset points", xytext=(6, -12), fontsize=9)


def _draw_links(ax, joints: dict, links, colour: str, lw: float, alpha: float) -> None:
    for p, q in links:
        if p in joints and q in joints:
            ax.plot([joints[p][0], joints[q][0]], [joints[p][1], joints[q][1]], "-", color=colour, lw=lw, alpha=alpha)


def path_figure(result: Result, path: Path) -> None:
    """The double crank drawn at its 10 target crank angles over the clamp path, with the target arc."""
    ex = result.extra
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12.5, 5.6), gridspec_kw={"width_ratios": [1.5, 1]})
    _target_arc(ax, ex["target_arc"])
    cc = ex.get("coupler_curve", {})
    if cc.get("x"):
        ax.plot(cc["x"], cc["y"], ":", color="grey", lw=0.8, label="coupler curve (full crank turn)")
    positions = ex["positions"]
    for k, pos in enumerate(positions):
        alpha = 0.9 if k in (0, len(positions) - 1) else 0.25
        _draw_links(ax, pos["joints"], DOUBLE_CRANK, "tab:blue", 1.6, alpha)
    first = positions[0]["joints"]
    for name in ("A", "D"):
        ax.plot(*first[name], "ks", ms=6)
        ax.annotate(name, first[name], textcoords="offset points", xytext=(-12, -12), fontsize=9)
    ax.plot(ex["path"]["x"], ex["path"]["y"], "-", color="tab:red", lw=1.6, label="clamp point M (working swing)")
    pts = ex["arc_error"]["points"]
    ax.plot([p["target_x"] for p in pts], [p["target_y"] for p in pts], "o", mfc="none", color="tab:green",
            label="target points")
    ax.plot([p["x"] for p in pts], [p["y"] for p in pts], ".", color="tab:red", label="M at the target crank angles")
    ax.plot(0, 0, "k+", ms=10)
    ax.annotate("O", (0, 0), textcoords="offset points", xytext=(4, 4), fontsize=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x, mm (origin: power-output bar)")
    ax.set_ylabel("y, mm (up)")
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=7)
    err = ex["arc_error"]
    ax.set_title(f"eq (4) = {err['eq4_sum_mm']:.4g} mm, RMS {err['rms_mm']:.3g} mm, max {err['max_mm']:.3g} mm",
                 fontsize=10)
    ax2.bar(range(1, len(pts) + 1), [p["distance"] for p in pts], color="tab:red")
    ax2.set_xlabel("target point (1 = M1)")
    ax2.set_ylabel("|M - target|, mm")
    ax2.grid(alpha=0.3, axis="y")
    ax2b = ax2.twinx()
    ax2b.plot(np.linspace(1, len(pts), len(ex["path"]["transmission_deg"])), ex["path"]["transmission_deg"],
              color="tab:purple", lw=1.0)
    ax2b.set_ylabel("transmission angle at C over the swing, deg", color="tab:purple")
    fig.suptitle(f"{result.name}: double crank over its working swing", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def compare_figure(results: list[Result], folder: Path) -> list[str]:
    """Clamp paths and point errors of several double-crank designs, baseline first."""
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12.5, 5.0))
    if results and "target_arc" in results[0].extra:
        _target_arc(ax, results[0].extra["target_arc"])
    for k, r in enumerate(results):
        ex = r.extra
        if "path" not in ex:
            continue
        style = "-" if k == 0 else "--"
        err = ex["arc_error"]
        ax.plot(ex["path"]["x"], ex["path"]["y"], style, lw=1.4, label=f"{r.name}: eq (4) {err['eq4_sum_mm']:.3g} mm")
        ax2.semilogy(range(1, len(err["points"]) + 1), [max(p["distance"], 1e-6) for p in err["points"]],
                     "o" + style, label=r.name)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x, mm")
    ax.set_ylabel("y, mm")
    ax2.set_xlabel("target point (1 = M1)")
    ax2.set_ylabel("|M - target|, mm (log)")
    return save_overlay(fig, (ax, ax2), folder, "compare_picker_double_crank.png")


def picker_figure(result: Result, path: Path) -> None:
    """Clamp path over one crank turn with the target arc, and the clamp speed against time."""
    tr, ex = result.trajectory, result.extra
    assert tr is not None, "a picker result carries its trajectory (combined.run_check writes it)"
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12.5, 5.2))
    _target_arc(ax, ex["target_arc"])
    _draw_links(ax, ex["frames"][0]["joints"], DOUBLE_CRANK, "tab:blue", 1.6, 0.8)
    _draw_links(ax, ex["frames"][0]["joints"], DRIVE, "tab:orange", 1.6, 0.8)
    ax.plot(tr["x"], tr["y"], "-", color="tab:red", lw=1.4, label="clamp point M over a turn")
    for name, inst in ex["instants"].items():
        ax.plot(inst["x"], inst["y"], "o", color="k", ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x, mm")
    ax.set_ylabel("y, mm")
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=7)
    ax.set_title("linkage at picking (blue: double crank, orange: crank-rocker)", fontsize=10)
    ax2.plot(tr["t"], tr["speed_m_s"], color="tab:red", label="|v_M|")
    for name, inst in ex["instants"].items():
        ax2.axvline(inst["t"], color="k", ls="--", lw=0.8)
        label = f"{name} {inst['t']:.3f} s"
        if "published_t" in inst:
            label += f" (paper {inst['published_t']:g})"
        ax2.annotate(label, (inst["t"], 0.0), rotation=90, fontsize=7, textcoords="offset points", xytext=(3, 8))
    ax2.set_xlabel("t, s")
    ax2.set_ylabel("clamp-point speed, m/s")
    ax2.grid(alpha=0.3)
    ax2b = ax2.twinx()
    ax2b.plot(tr["t"], tr["crank_ab_deg"], color="tab:blue", lw=0.9)
    ax2b.set_ylabel("crank AB angle phi1, deg", color="tab:blue")
    fig.suptitle(f"{result.name}: {ex['operation']['crank_speed_rpm']:g} r/min", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def picker_animation(result: Result, path: Path) -> None:
    """One cycle of the combined picker as an animated GIF (report.gif)."""
    tr, ex = result.trajectory, result.extra
    assert tr is not None, "a picker result carries its trajectory (combined.run_check writes it)"
    frames = ex["frames"]
    xs = [p[0] for f in frames for p in f["joints"].values()] + tr["x"]
    ys = [p[1] for f in frames for p in f["joints"].values()] + tr["y"]
    fig, ax = plt.subplots(figsize=(6.4, 5.0))
    pad = 20.0
    ax.set_xlim(min(xs) - pad, max(xs) + pad)
    ax.set_ylim(min(ys) - pad, max(ys) + pad)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    _target_arc(ax, ex["target_arc"])
    ax.plot(tr["x"], tr["y"], "-", color="tab:red", lw=0.8, alpha=0.5)
    lines = [ax.plot([], [], "-", color="tab:blue", lw=2)[0] for _ in DOUBLE_CRANK]
    lines += [ax.plot([], [], "-", color="tab:orange", lw=2)[0] for _ in DRIVE]
    dot, = ax.plot([], [], "o", color="tab:red")
    label = ax.set_title("")

    def draw(k: int):
        j = frames[k]["joints"]
        for line, (p, q) in zip(lines, DOUBLE_CRANK + DRIVE):
            line.set_data([j[p][0], j[q][0]], [j[p][1], j[q][1]])
        dot.set_data([j["M"][0]], [j["M"][1]])
        label.set_text(f"{result.name}: frame {k + 1}/{len(frames)}, t = {frames[k]['t']:.2f} s")
        return lines + [dot, label]

    fps = max(1, round(len(frames) / (2 * ex["operation"]["period_s"])))    # half speed: one cycle in 2 periods
    save_gif(fig, draw, len(frames), path, fps=fps, dpi=110)     # 704 x 550 px
    plt.close(fig)

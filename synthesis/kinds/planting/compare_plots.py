"""planting_fourbar candidates overlaid: paths, speeds and accelerations, the linkage at P1-P6, an animation.

Drawn from result.json data alone: the trajectory samples, the precision points and the design
(the linkage is placed from the design's lengths and angles; nothing is re-solved).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.kinds.planting.kinematics import ArmDesign, joint_positions  # noqa: E402
from synthesis.kinds.planting.plots import COLOURS as POINT_COLOURS, style_plane  # noqa: E402
from synthesis.report.gif import save_gif  # noqa: E402
from synthesis.report.labels import baseline_note, candidate_label  # noqa: E402
from synthesis.report.legends import legend_below, legend_right  # noqa: E402
from synthesis.result import Result  # noqa: E402

POINTS = ("P1", "P2", "P3", "P4", "P5", "P6")
#: acceleration-sign phases (synthesis.kinds.planting.rules.acceleration) shaded on the time plots
PHASES = (("hold", "P3", "P4", "#cfe8ff"), ("throw", "P4", "P5", "#ffe0c2"), ("release", "P5", "P6", "#e3d7f5"))
ANIMATION_FRAMES = 36


def _colour(i: int) -> str:
    return f"C{i % 10}"


def _label(result: Result, i: int, n: int = 2) -> str:
    """The candidate's legend entry; "(baseline)" only beside other candidates, never on a run's own figure."""
    return candidate_label(result.name, i, n)


def _design(result: Result) -> ArmDesign:
    d = result.design
    return ArmDesign.of_result(d)


def paths_figure(results: list[Result], path: Path) -> None:
    """Claw-tip paths in the machine and ground frames, P1-P6 marked, soil lines dashed."""
    fig, (ax_m, ax_g) = plt.subplots(1, 2, figsize=(12, 5.4))
    for i, r in enumerate(results):
        tr, col = r.trajectory, _colour(i)
        if tr is None:
            continue
        ax_m.plot(tr["machine"]["x"], tr["machine"]["y"], color=col, lw=1.4, label=_label(r, i, len(results)))
        ax_g.plot(tr["x"], tr["y"], color=col, lw=1.4, label=_label(r, i, len(results)))
        soil = r.extra.get("soil_level_mm")
        for ax in (ax_m, ax_g):
            if soil is not None:
                ax.axhline(soil, color=col, lw=0.8, ls="--")
        for name, p in r.extra.get("precision_points", {}).items():
            if p.get("found"):
                ax_m.plot(p["x"], p["y"], "o", color=POINT_COLOURS[name], mec=col, ms=6)
                ax_g.plot(p["x_ground"], p["y"], "o", color=POINT_COLOURS[name], mec=col, ms=6)
                if i == 0:
                    ax_m.annotate(name, (p["x"], p["y"]), textcoords="offset points", xytext=(5, 4), fontsize=8)
        if i == 0 and "seedbed" in r.extra:
            sb = r.extra["seedbed"]
            t = math.radians(sb["tilt_deg"])
            span = 0.3 * (max(tr["machine"]["x"]) - min(tr["machine"]["x"])) + 40
            ax_m.plot([sb["x"] - span * math.cos(t), sb["x"] + span * math.cos(t)],
                      [sb["y"] - span * math.sin(t), sb["y"] + span * math.sin(t)], color="0.35", lw=1,
                      label="seedbed bottom" + baseline_note(" (baseline)", len(results)))
    ax_m.set_title("machine frame (dashed: soil surface)")
    ax_g.set_title("ground frame")
    for ax in (ax_m, ax_g):
        style_plane(ax)
    legend_below(ax_m, fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def kinematics_figure(results: list[Result], path: Path) -> None:
    """Ground-frame speeds and the vertical acceleration against time, acceleration-rule phases shaded.
    In the units of the rule table: speeds in m/s (p2_speed), the acceleration in mm/s^2 (accel_*)."""
    fig, axes = plt.subplots(3, 1, figsize=(11, 8), sharex=True)
    for i, r in enumerate(results):
        tr, col = r.trajectory, _colour(i)
        if tr is None:
            continue
        t = np.asarray(tr["t"])
        axes[0].plot(t, np.asarray(tr["vx"]) / 1000.0, color=col, label=_label(r, i, len(results)))
        axes[1].plot(t, np.asarray(tr["vy"]) / 1000.0, color=col)
        axes[2].plot(t, tr["ay"], color=col)
        pts = r.extra.get("precision_points", {})
        if i == 0:
            for phase, a, b, shade in PHASES:
                if pts.get(a, {}).get("found") and pts.get(b, {}).get("found"):
                    ta, tb = pts[a]["t"], pts[b]["t"]
                    for ax in axes:
                        ax.axvspan(ta, tb, color=shade, alpha=0.7, lw=0)
                    axes[2].text(0.5 * (ta + tb), 0.98, phase, transform=axes[2].get_xaxis_transform(),
                                 ha="center", va="top", fontsize=8)
        for name, p in pts.items():
            if p.get("found"):
                axes[2].axvline(p["t"], color=col, lw=0.5, ls=":")
    axes[0].set_ylabel("v_x ground, m/s")
    axes[1].set_ylabel("v_y, m/s")
    axes[2].set_ylabel("a_y, mm/s²")
    axes[2].axhline(0.0, color="k", lw=0.6)
    axes[2].set_xlabel("time from soil exit P6, s (shaded: the " + baseline_note("baseline's ", len(results))
                       + "hold / throw / release phases)")
    legend_right(axes[0], fontsize=7)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


#: the line style of each link :func:`_linkage_segments` gives, in its order
LINK_STYLES = (":", "-", "-", "-", "-", "-")


def _linkage_segments(joints: dict[str, np.ndarray], k: int) -> list[tuple[list, list]]:
    """The (xs, ys) of every line of the linkage at sample k: frame O-O', crank O-A, coupler triangle A-B-C,
    rocker O'-B (LINK_STYLES), then the two pivots and the joints A, B (markers)."""
    o, op, a, b, c = (joints[n][:, k] for n in ("O", "O'", "A", "B", "C"))
    pairs = ((o, op), (o, a), (a, b), (op, b), (a, c), (b, c), (o, op), (a, b))
    return [([p[0], q[0]], [p[1], q[1]]) for p, q in pairs]


def _draw_linkage(ax, joints: dict[str, np.ndarray], k: int, colour: str, alpha: float = 1.0):
    """Frame O-O', crank O-A, coupler triangle A-B-C, rocker O'-B at sample k; returns the artists
    (:func:`_move_linkage` puts them at another sample)."""
    segments = _linkage_segments(joints, k)
    lines = []
    for (xs, ys), style in zip(segments, LINK_STYLES):
        lines += ax.plot(xs, ys, style, color=colour, lw=1.6, alpha=alpha)
    lines += ax.plot(*segments[6], "^", color="k", ms=6)
    lines += ax.plot(*segments[7], "o", color=colour, ms=3.5, alpha=alpha)
    return lines


def _move_linkage(lines: list, joints: dict[str, np.ndarray], k: int) -> None:
    """The artists of :func:`_draw_linkage` put at sample k."""
    for line, (xs, ys) in zip(lines, _linkage_segments(joints, k), strict=True):
        line.set_data(xs, ys)


#: the joints annotate_linkage letters, in its order
JOINT_NAMES = ("O", "O'", "A", "B", "C")


def annotate_linkage(ax, joints: dict[str, np.ndarray], k: int = 0, lengths: bool = True, colour: str = "k",
                     fontsize: float = 8) -> list:
    """Joint letters at sample k and (``lengths``) each link's length, mm, at its middle; returns the artists."""
    artists = []
    for name in JOINT_NAMES:
        x, y = joints[name][:, k]
        artists.append(ax.annotate(name, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=fontsize,
                                   fontweight="bold", color=colour, zorder=8))
    if lengths:
        for p, q in (("O", "O'"), ("O", "A"), ("A", "B"), ("O'", "B"), ("A", "C"), ("B", "C")):
            a, b = joints[p][:, k], joints[q][:, k]
            artists.append(ax.annotate(f"{np.hypot(*(b - a)):.1f}", (a + b) / 2, textcoords="offset points",
                                       xytext=(0, -9), ha="center", fontsize=fontsize - 1, color="0.3", zorder=8,
                                       bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.7)))
    return artists


def linkage_figure(results: list[Result], path: Path) -> None:
    """The linkage of every candidate at each of its precision points P1-P6 (machine frame)."""
    fig, axes = plt.subplots(2, 3, figsize=(12, 7.6), sharex=True, sharey=True)
    for i, r in enumerate(results):
        design, col = _design(r), _colour(i)
        tr = r.trajectory
        for ax, name in zip(axes.ravel(), POINTS):
            p = r.extra.get("precision_points", {}).get(name, {})
            if tr is not None:
                ax.plot(tr["machine"]["x"], tr["machine"]["y"], color=col, lw=0.6, alpha=0.5)
            if not p.get("found"):
                continue
            joints = joint_positions(design, math.radians(p["crank_deg"]))
            _draw_linkage(ax, joints, 0, col)
            if i == 0:          # letters on every panel, link lengths (mm) on the first
                annotate_linkage(ax, joints, 0, lengths=name == "P1", colour=col)
            ax.plot(p["x"], p["y"], "o", color=POINT_COLOURS[name], mec=col, ms=7)
    for ax, name in zip(axes.ravel(), POINTS):
        ax.set_title(name, fontsize=10)
        ax.set_aspect("equal", adjustable="box")
        ax.grid(alpha=0.3)
    handles = [plt.Line2D([], [], color=_colour(i), label=_label(r, i, len(results))) for i, r in enumerate(results)]
    fig.legend(handles=handles, loc="lower center", ncol=min(4, len(results)), fontsize=8)
    fig.suptitle("linkage at the precision points (machine frame, mm)", fontsize=11)
    # fixed margins, not tight_layout: the six panels share their axes, so only the outer ones carry tick labels,
    # and measuring every panel's ticks for the layout was half the figure's time
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.11, top=0.92, wspace=0.06, hspace=0.14)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def animation_figure(results: list[Result], path: Path, frames: int = ANIMATION_FRAMES) -> None:
    """Every candidate's linkage over one crank turn (machine frame), as a small looping GIF."""
    fig, ax = plt.subplots(figsize=(8.0, 6.4))          # 720 x 576 px at dpi 90: legible legend and counter
    theta = np.linspace(0.0, 2 * np.pi, frames, endpoint=False)
    all_joints = [joint_positions(_design(r), theta) for r in results]
    for i, (r, joints) in enumerate(zip(results, all_joints)):
        if r.trajectory is not None:
            ax.plot(r.trajectory["machine"]["x"], r.trajectory["machine"]["y"], color=_colour(i), lw=0.7,
                    alpha=0.6, label=_label(r, i, len(results)))
        soil = r.extra.get("soil_level_mm")
        if soil is not None:
            ax.axhline(soil, color=_colour(i), lw=0.6, ls="--")
    xy = np.hstack([j[n] for j in all_joints for n in j])
    pad = 15.0
    ax.set_xlim(xy[0].min() - pad, xy[0].max() + pad)
    ax.set_ylim(xy[1].min() - pad, xy[1].max() + pad)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    legend_below(ax, ncol=2, fontsize=9)
    ax.set_title("one crank turn (machine frame, mm)", fontsize=11)
    fig.tight_layout()                  # room for the legend under the drawing
    counter = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=10,
                      bbox=dict(boxstyle="round,pad=0.2", fc="white", ec="0.8"))
    # every frame moves the same artists, made at the first (after the counter: the order a full redraw keeps)
    linkages: list[list] = []
    letters: list = []

    def frame(k: int):
        if not linkages:
            linkages.extend(_draw_linkage(ax, joints, k, _colour(i)) for i, joints in enumerate(all_joints))
            if len(all_joints) == 1:
                letters.extend(annotate_linkage(ax, all_joints[0], k, lengths=False, fontsize=9))
        for lines, joints in zip(linkages, all_joints):
            _move_linkage(lines, joints, k)
        for letter, name in zip(letters, JOINT_NAMES):
            letter.xy = tuple(all_joints[0][name][:, k])
        counter.set_text(f"frame {k + 1}/{frames}, crank {np.degrees(theta[k]):.0f} deg")
        return [line for lines in linkages for line in lines] + letters + [counter]

    save_gif(fig, frame, frames, path, fps=12, dpi=90, shared_palette=True)
    plt.close(fig)


def overlay_figures(results: list[Result], folder: Path) -> list[tuple[str, str]]:
    """All comparison figures of planting_fourbar candidates: [(file name, caption)]."""
    figures = [
        ("paths.png", "claw-tip paths overlaid, machine and ground frames, P1-P6 marked, soil surface dashed",
         paths_figure),
        ("kinematics.png", "ground-frame speeds and vertical acceleration over one cycle, rule phases shaded",
         kinematics_figure),
        ("linkage.png", "the linkage at the six precision points", linkage_figure),
        ("animation.gif", "the linkage over one crank turn", animation_figure),
    ]
    for name, _, draw in figures:
        draw(results, folder / name)
    return [(name, caption) for name, caption, _ in figures]


# one run's own figures (report.html of a check or solve): the same drawings of one candidate
def kinematics_of_one(result: Result, path: Path) -> None:
    kinematics_figure([result], path)


def linkage_of_one(result: Result, path: Path) -> None:
    linkage_figure([result], path)


def animation_of_one(result: Result, path: Path) -> None:
    animation_figure([result], path)

"""Candidates' traced points overlaid, for any kind whose results carry a ``trajectory`` (trajectory keys).

Drawn from result.json alone: the path in its frame and the speed over one cycle.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.labels import candidate_label  # noqa: E402
from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402


def trajectory_overlay(results: list[Result], folder: Path) -> list[tuple[str, str]]:
    """trajectories.png: path (left) and speed against time (right), one colour per candidate."""
    fig, (ax_path, ax_speed) = plt.subplots(1, 2, figsize=(12, 5))
    for i, r in enumerate(results):
        tr = r.trajectory
        if not tr:
            continue
        label = candidate_label(r.name, i, len(results))
        ax_path.plot(tr["x"], tr["y"], color=f"C{i % 10}", lw=1.4, label=label)
        ax_path.plot(tr["x"][0], tr["y"][0], "o", color=f"C{i % 10}", ms=5)
        speed = np.hypot(np.asarray(tr["vx"], float), np.asarray(tr["vy"], float)) / 1000.0
        ax_speed.plot(tr["t"], speed, color=f"C{i % 10}", lw=1.2, label=label)
    frame = results[0].trajectory.get("frame", "") if results[0].trajectory else ""
    ax_path.set_title(f"traced point, {frame} frame (dot: t = 0)", fontsize=10)
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.set_xlabel("X, mm")
    ax_path.set_ylabel("Y, mm")
    ax_speed.set_title("speed of the traced point", fontsize=10)
    ax_speed.set_xlabel("t, s")
    ax_speed.set_ylabel("speed, m/s")
    for ax in (ax_path, ax_speed):
        ax.grid(alpha=0.3)
    legend_below(ax_path, ncol=2, fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / "trajectories.png", dpi=100)
    plt.close(fig)
    return [("trajectories.png", "the traced points of the candidates overlaid: path and speed over one cycle")]

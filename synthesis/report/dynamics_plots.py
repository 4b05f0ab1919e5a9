"""The dynamics figure of a four-bar kind, from result.json's ``facts.dynamics`` alone (docs/ARCHITECTURE.md
"Dynamics"): input torque, power, shaking force and shaking moment over a crank turn, the peaks marked; and the
comparison's overlay of every candidate that has them."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report import has_dynamics  # noqa: E402
from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402


def dynamics_figure(result: Result, path: Path) -> None:
    """Four panels over the crank angle: input torque (N m), power (W), shaking force (x, y, magnitude, N), shaking
    moment about the crank pivot (N m)."""
    if not has_dynamics(result):
        raise ValueError("the result holds no facts.dynamics of a driven linkage (the spec has no [dynamics] table, "
                         "or its kind's dynamics have a figure of their own)")
    dyn = result.extra["dynamics"]
    crank = np.asarray(dyn["crank_deg"], float)
    torque, power = np.asarray(dyn["input_torque_Nm"], float), np.asarray(dyn["power_W"], float)
    force = np.asarray(dyn["shaking_force_N"], float).reshape(-1, 2)
    magnitude = np.hypot(force[:, 0], force[:, 1])
    moment = np.asarray(dyn["shaking_moment_Nm"], float)
    fig, axes = plt.subplots(4, 1, figsize=(7.5, 10.4), sharex=True)
    panels = ((axes[0], torque, "input torque, N m"), (axes[1], power, "input power, W"),
              (axes[3], moment, "shaking moment, N m"))
    for ax, values, label in panels:
        ax.plot(crank, values, color="C0", label=label)
        k = int(np.argmax(np.abs(values)))
        ax.plot(crank[k], values[k], "o", color="C3", label=f"peak |{label.split(',')[0]}| {abs(values[k]):.3g} at "
                                                           f"{crank[k]:.0f} deg")
        ax.axhline(0.0, color="0.6", lw=0.8)
        ax.set_ylabel(label)
        legend_below(ax)
    ax = axes[2]
    ax.plot(crank, force[:, 0], color="C1", label="shaking force x, N")
    ax.plot(crank, force[:, 1], color="C2", label="shaking force y, N")
    ax.plot(crank, magnitude, color="C0", label=f"|shaking force|, peak {magnitude.max():.3g} N")
    ax.set_ylabel("shaking force, N")
    legend_below(ax)
    axes[3].set_xlabel("crank angle, deg")
    fig.suptitle(f"{result.name}: dynamics at {dyn['crank_speed_rpm']:g} r/min")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def dynamics_overlay(results: list[Result], path: Path) -> None:
    """The candidates that hold ``facts.dynamics`` overlaid: input torque, |shaking force| and shaking moment over
    the crank angle, each candidate's peak in its legend; a candidate without them is named as left out."""
    shown = [r for r in results if has_dynamics(r)]
    if not shown:
        raise ValueError("no candidate holds a driven linkage's facts.dynamics (none of the specs has a [dynamics] "
                         "table)")
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.4), sharex=True)
    labels = ("input torque, N m", "|shaking force|, N", "shaking moment, N m")
    for i, r in enumerate(shown):
        dyn = r.extra["dynamics"]
        crank = np.asarray(dyn["crank_deg"], float)
        force = np.asarray(dyn["shaking_force_N"], float).reshape(-1, 2)
        series = (np.asarray(dyn["input_torque_Nm"], float), np.hypot(force[:, 0], force[:, 1]),
                  np.asarray(dyn["shaking_moment_Nm"], float))
        for ax, values in zip(axes, series):
            ax.plot(crank, values, color=f"C{i % 10}", label=f"{r.name}: peak {np.abs(values).max():.3g} at "
                                                             f"{dyn['crank_speed_rpm']:g} r/min")
    for ax, label in zip(axes, labels):
        ax.axhline(0.0, color="0.6", lw=0.8)
        ax.set_ylabel(label)
        legend_below(ax)
    axes[-1].set_xlabel("crank angle, deg")
    left_out = [r.name for r in results if not has_dynamics(r)]
    title = "dynamics of the candidates"
    if left_out:
        title += f" (no [dynamics] table: {', '.join(left_out)})"
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)

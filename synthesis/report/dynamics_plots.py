"""The dynamics figure of a four-bar kind, from result.json's ``facts.dynamics`` alone (docs/ARCHITECTURE.md
"Dynamics"): input torque, power and shaking force over a crank turn, the peaks marked."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402


def has_dynamics(result: Result) -> bool:
    return bool((result.extra or {}).get("dynamics"))


def dynamics_figure(result: Result, path: Path) -> None:
    """Three panels over the crank angle: input torque (N m), power (W), shaking force (x, y, magnitude, N)."""
    dyn = (result.extra or {}).get("dynamics")
    if not dyn:
        raise ValueError("the result holds no facts.dynamics (the spec has no [dynamics] table)")
    crank = np.asarray(dyn["crank_deg"], float)
    torque, power = np.asarray(dyn["input_torque_Nm"], float), np.asarray(dyn["power_W"], float)
    force = np.asarray(dyn["shaking_force_N"], float).reshape(-1, 2)
    magnitude = np.hypot(force[:, 0], force[:, 1])
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 8.0), sharex=True)
    panels = ((axes[0], torque, "input torque, N m"), (axes[1], power, "input power, W"))
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
    ax.set_xlabel("crank angle, deg")
    legend_below(ax)
    fig.suptitle(f"{result.name}: dynamics at {dyn['crank_speed_rpm']:g} r/min")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)

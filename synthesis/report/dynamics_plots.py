"""The dynamics figure of a four-bar kind, from result.json's ``facts.dynamics`` alone (docs/ARCHITECTURE.md
"Dynamics"): input torque, power, shaking force and shaking moment over a crank turn, the peaks marked, and, with a
``[dynamics] drive`` (``facts.dynamics.speed_fluctuation``), the crank's speed over the turn on top and the torque and
shaking force at that speed beside the constant-speed ones; and the comparison's overlay of every candidate that has
them."""

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
    moment about the crank pivot (N m); with a speed fluctuation, a fifth on top: the crank speed (r/min) that a
    constant motor torque and the flywheel give, its mean and extremes, and the torque and |shaking force| at that
    speed drawn dashed in their panels."""
    if not has_dynamics(result):
        raise ValueError("the result holds no facts.dynamics of a driven linkage (the spec has no [dynamics] table, "
                         "or its kind's dynamics have a figure of their own)")
    dyn = result.extra["dynamics"]
    crank = np.asarray(dyn["crank_deg"], float)
    torque, power = np.asarray(dyn["input_torque_Nm"], float), np.asarray(dyn["power_W"], float)
    force = np.asarray(dyn["shaking_force_N"], float).reshape(-1, 2)
    magnitude = np.hypot(force[:, 0], force[:, 1])
    moment = np.asarray(dyn["shaking_moment_Nm"], float)
    fluctuation = dyn.get("speed_fluctuation") or {}
    speed_panel = bool(fluctuation.get("found"))
    fig, axes = plt.subplots(4 + speed_panel, 1, figsize=(7.5, 10.4 + 2.6 * speed_panel), sharex=True)
    if speed_panel:
        _speed_panel(axes[0], crank, fluctuation)
        axes = axes[1:]
    panels = ((axes[0], torque, "input torque, N m"), (axes[1], power, "input power, W"),
              (axes[3], moment, "shaking moment, N m"))
    for ax, values, label in panels:
        ax.plot(crank, values, color="C0", label=label + (" (constant speed)" if speed_panel and ax is axes[0] else ""))
        k = int(np.argmax(np.abs(values)))
        ax.plot(crank[k], values[k], "o", color="C3", label=f"peak |{label.split(',')[0]}| {abs(values[k]):.3g} at "
                                                           f"{crank[k]:.0f} deg")
        ax.axhline(0.0, color="0.6", lw=0.8)
        ax.set_ylabel(label)
    ax = axes[2]
    ax.plot(crank, force[:, 0], color="C1", label="shaking force x, N")
    ax.plot(crank, force[:, 1], color="C2", label="shaking force y, N")
    ax.plot(crank, magnitude, color="C0", label=f"|shaking force|, peak {magnitude.max():.3g} N")
    ax.set_ylabel("shaking force, N")
    if speed_panel:
        shaft = np.asarray(fluctuation["shaft_torque_Nm"], float)
        axes[0].plot(crank, shaft, "--", color="C4", label=f"at the fluctuating speed, peak {np.abs(shaft).max():.3g}")
        slow = np.asarray(fluctuation["shaking_force_N"], float).reshape(-1, 2)
        slow_magnitude = np.hypot(slow[:, 0], slow[:, 1])
        axes[2].plot(crank, slow_magnitude, "--", color="C4",
                     label=f"|shaking force| at the fluctuating speed, peak {slow_magnitude.max():.3g} N")
    for ax in axes:
        legend_below(ax, ncol=2 if speed_panel else 3)
    axes[3].set_xlabel("crank angle, deg")
    fig.suptitle(f"{result.name}: dynamics at {dyn['crank_speed_rpm']:g} r/min")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _speed_panel(ax, crank: np.ndarray, fluctuation: dict) -> None:
    """The crank speed over the turn (r/min) with its mean and extremes, the flywheel and the coefficient named."""
    rpm = 60.0 / (2.0 * np.pi)
    speed = np.asarray(fluctuation["crank_speed_radps"], float) * rpm
    ax.plot(crank, speed, color="C0", label=f"crank speed, flywheel {fluctuation['flywheel_inertia_kgm2']:.3g} kg m^2")
    ax.axhline(fluctuation["mean_crank_speed_radps"] * rpm, color="0.6", lw=0.8,
               label=f"mean over time {fluctuation['mean_crank_speed_radps'] * rpm:.4g} r/min")
    for key in ("omega_min", "omega_max"):
        ax.plot(fluctuation[f"{key}_at_crank_deg"], fluctuation[f"{key}_radps"] * rpm, "o", color="C3")
    ax.plot([], [], "o", color="C3", label=f"min {fluctuation['omega_min_radps'] * rpm:.4g}, max "
                                           f"{fluctuation['omega_max_radps'] * rpm:.4g} r/min: fluctuation "
                                           f"{fluctuation['coefficient']:.3g}")
    sizing = fluctuation.get("flywheel_for_coefficient")
    if sizing:
        ax.plot([], [], " ", label=f"{sizing['coefficient']:.3g} needs {sizing['inertia_kgm2']:.3g} kg m^2 (gives "
                                   f"{sizing['achieved_coefficient']:.3g})")
    ax.set_ylabel("crank speed, r/min")
    legend_below(ax, ncol=2)


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

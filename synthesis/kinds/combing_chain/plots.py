"""Figures of a combing_chain result, drawn from result.json alone (never re-solving): the plant angle
before the cut over the initial plant angle at the ends and middle of each gear's machine speeds, with
the window and the printed Table 13 figures (the paper's Fig. 23 as curves), and eq 13's plant length."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from synthesis.report.legends import legend_below  # noqa: E402
from synthesis.result import Result  # noqa: E402

STYLES = ("-", "--", ":", "-.")


def _draw(ax_d, ax_l, result: Result, colour=None, label_prefix: str = "", published: bool = True) -> None:
    ex = result.extra
    cv = ex["curves"]
    beta = cv["beta_deg"]
    gears = sorted({s["gear"] for s in cv["series"]})
    cmap = plt.get_cmap("viridis")
    for s in cv["series"]:
        same = [x for x in cv["series"] if x["gear"] == s["gear"]]
        k = same.index(s)
        c = colour or cmap(0.15 + 0.7 * (k / max(1, len(same) - 1)))
        gear = f"gear {s['gear']}, " if len(gears) > 1 else ""
        lab = f"{label_prefix}{gear}V_s {s['machine_speed']:.3g} m/s, V_r {s['chain_speed']:.3g} m/s"
        style = STYLES[(s["gear"] - 1) % len(STYLES)]
        ax_d.plot(beta, s["delta_deg"], style, color=c, lw=1.4, label=lab)
        ax_l.plot(beta, [v / 10.0 for v in s["plant_length_mm"]], style, color=c, lw=1.4, label=lab)
    window = ex.get("window_deg")
    if window:
        ax_d.axhspan(window[0], window[1], color="tab:green", alpha=0.12, label=f"window {window[0]:g}-{window[1]:g} deg")
    if published:
        pts = [p for p in ex.get("published", []) if p["quantity"] == "delta"]
        for p in pts:
            ok = p["reproduced"]
            ax_d.plot(p["beta_deg"], p["published"], "o" if ok else "x", color="tab:red", ms=6, mfc="none" if ok else None)
            ax_d.plot(p["beta_deg"], p["ours"], ".", color="black", ms=5)
        if pts:
            ax_d.plot([], [], "o", color="tab:red", mfc="none", label="Table 13 printed (reproduced)")
            if any(not p["reproduced"] for p in pts):
                ax_d.plot([], [], "x", color="tab:red", label="Table 13 printed (not reproduced)")
            ax_d.plot([], [], ".", color="black", label="ours at the operating point read")


def delta_figure(result: Result, path: Path) -> None:
    """delta over beta (Fig. 23 as curves) and eq 13's plant length over beta."""
    fig, (ax_d, ax_l) = plt.subplots(1, 2, figsize=(12.5, 4.8))
    _draw(ax_d, ax_l, result)
    ch = result.extra["chain"]
    ax_d.axhline(90.0, color="grey", lw=0.6)
    ax_d.set_xlabel("initial plant angle beta, deg (< 90: face cut, > 90: back cut)")
    ax_d.set_ylabel("plant angle before the cut delta, deg")
    ax_d.set_title(f"{result.name}: h {ch['h_mm']:g} mm, theta {ch['theta_deg']:g} deg, e {ch['e_mm']:g} mm",
                   fontsize=9)
    ax_l.set_xlabel("initial plant angle beta, deg")
    ax_l.set_ylabel("eq 13: plant length with its tip at the tine at the cut, cm")
    for a in (ax_d, ax_l):
        a.grid(alpha=0.3)
    legend_below(ax_d, ncol=2, fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def compare_figure(results: list[Result], folder: Path) -> list[str]:
    """The candidates' delta over beta, one colour each."""
    fig, (ax_d, ax_l) = plt.subplots(1, 2, figsize=(12.5, 4.8))
    colours = plt.get_cmap("tab10")
    for i, r in enumerate(results):
        _draw(ax_d, ax_l, r, colour=colours(i % 10), label_prefix=f"{r.name}: ", published=False)
    ax_d.set_xlabel("initial plant angle beta, deg")
    ax_d.set_ylabel("plant angle before the cut delta, deg")
    ax_l.set_xlabel("initial plant angle beta, deg")
    ax_l.set_ylabel("eq 13 plant length, cm")
    for a in (ax_d, ax_l):
        a.grid(alpha=0.3)
    legend_below(ax_d, ncol=2, fontsize=7)
    fig.tight_layout()
    name = "compare_combing_chain.png"
    fig.savefig(folder / name, dpi=110)
    plt.close(fig)
    return [name]

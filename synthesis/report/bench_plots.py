"""The bench's figures (``agrisynth bench`` writes them; ``compare`` draws a bench's error plot too): the error of
every method against its run time, and a sample sweep's error against its time.

Both axes are logarithmic and fitted to the data drawn (a factor :data:`MARGIN` beyond it), not to a fixed range:
two points do not sit on eight empty decades.  A value of 0 -- an exact optimum, no violation -- has no place on a
log axis; it is drawn on a dotted floor line a decade below the smallest nonzero value of its axes, whose tick is
labelled "0" and whose legend entry says so.  Ticks are the decades in view (the 1-2-5 steps, or every step, where
fewer than two decades are), only they are labelled, and a tick too close to the floor's "0" is left out, so no
two labels overlap (tests/test_bench_generic.py measures their boxes).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter, NullLocator  # noqa: E402

from synthesis.report.legends import legend_below  # noqa: E402

#: the axes reach this factor beyond the data on either side (log scale)
MARGIN = 1.6
#: a tick closer than this factor to the floor line, or than NEAR_FLOOR_SHARE of the axis (log), is not labelled:
#: its label would touch, or be read as, the floor's "0"
NEAR_FLOOR = 4.0
NEAR_FLOOR_SHARE = 0.08
MARKERS = ["o", "s", "^", "D", "v"]
DPI = 110


def zero_floor(values) -> float:
    """Where a 0 is drawn: a decade below the smallest positive finite value (1 when none is positive)."""
    positive = [v for v in values if v is not None and math.isfinite(v) and v > 0]
    return min(positive) / 10.0 if positive else 1.0


def on_log_axis(value, floor: float) -> float:
    """``value`` as drawn: itself when positive, the floor when 0 (or below: a gap rounding under the best known),
    NaN (not drawn) when it is no number or infinite."""
    if value is None or not math.isfinite(value):
        return math.nan
    return value if value > 0 else floor


def best_so_far(row: dict, best_known: float) -> list[tuple[float, float]]:
    """The median run's best-so-far gap to ``best_known`` (0 at or below it) against time, drawn as steps: one point
    per improvement, held to the median run's end (a trace whose one improvement came early is then a line, not a
    lone point far from the run's marker)."""
    trace = [(t, max(f - best_known, 0.0)) for t, f in row["trace"] if f is not None and math.isfinite(f)]
    end = row.get("median_s")
    if trace and isinstance(end, (int, float)) and math.isfinite(end) and end > trace[-1][0]:
        trace.append((end, trace[-1][1]))
    return trace


def _finite_positive(values) -> list[float]:
    return [v for v in values if v is not None and math.isfinite(v) and v > 0]


def _log_ticks(lo: float, hi: float, floor: float | None = None) -> list[float]:
    """Ticks within [lo, hi], none near the floor line (:data:`NEAR_FLOOR`): the decades, or where fewer than
    two of them are in view the 1-2-5 steps, or where still fewer every step of 1 to 9 times a decade."""
    decades = [10.0 ** k for k in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)]
    near = max(NEAR_FLOOR, (hi / lo) ** NEAR_FLOOR_SHARE)
    ticks: list[float] = []
    for steps in ((1,), (1, 2, 5), tuple(range(1, 10))):
        ticks = [d * m for d in decades for m in steps if lo <= d * m <= hi
                 and (floor is None or not floor / near < d * m < floor * near)]
        if len(ticks) >= 2:
            break
    return ticks


def _tick_text(value: float, position=None) -> str:
    exponent = math.floor(math.log10(value) + 1e-9)
    mantissa = value / 10.0 ** exponent
    if -2 <= exponent <= 3:
        return f"{value:g}"
    return f"1e{exponent}" if abs(mantissa - 1.0) < 1e-9 else f"{mantissa:.0f}e{exponent}"


def fit_log_axis(ax, axis: str, values, floor: float | None = None) -> None:
    """Limits of ``ax``'s ``axis`` ("x" or "y") a factor MARGIN beyond ``values`` (and the floor line, when given),
    ticks at :func:`_log_ticks` labelled plainly, the floor's tick labelled "0", no minor tick labels."""
    data = _finite_positive(values) + ([floor] if floor is not None else [])
    lo, hi = (min(data), max(data)) if data else (1.0, 10.0)
    lo, hi = lo / MARGIN, hi * MARGIN
    labels = {t: _tick_text(t) for t in _log_ticks(lo, hi, floor)}
    if floor is not None:
        labels[floor] = "0"
    which = ax.yaxis if axis == "y" else ax.xaxis
    (ax.set_ylim if axis == "y" else ax.set_xlim)(lo, hi)
    which.set_major_locator(FixedLocator(sorted(labels)))
    which.set_major_formatter(FuncFormatter(lambda v, pos: labels.get(v, _tick_text(v))))
    which.set_minor_locator(NullLocator())
    which.set_minor_formatter(NullFormatter())


def _floor_handle(floor_of: str, values) -> Line2D:
    """The legend entry of the floor line: where a 0 of ``values`` is drawn, and why there."""
    where = ("a decade below the smallest nonzero value" if _finite_positive(values)
             else "every value is 0")
    return Line2D([], [], color="0.55", lw=0.9, ls=":", label=f"0 ({floor_of}): drawn on this dotted line, {where}")


def plot_error_vs_time(results: list[dict], path: Path) -> None:
    """error_vs_time.png: :func:`error_figure` drawn."""
    _save(error_figure(results), path)


def plot_sample_sweep(sweep: dict, path: Path) -> None:
    """samples_<problem>.png: :func:`sweep_figure` drawn."""
    _save(sweep_figure(sweep), path)


def _save(fig, path: Path) -> None:
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def problem_colours(n: int) -> list:
    """A colour per problem, distinct for up to 20: matplotlib's ten (tab20's dark half, the default cycle), then
    tab20's light half (a default bench has 12 to 19 problems: the ten-colour cycle gave two problems one colour)."""
    tab20 = list(plt.get_cmap("tab20").colors)
    order = tab20[0::2] + tab20[1::2]
    return [order[p % len(order)] for p in range(n)]


def error_figure(results: list[dict]):
    """Log-log: objective gap and worst violation against wall time, per problem (colour) and method
    (marker); every repeat a point, the median run's best-so-far trace a line."""
    colours = problem_colours(len(results))
    methods = list(dict.fromkeys(row["method"] for res in results for row in res["rows"]))
    fig, (ax_gap, ax_vio) = plt.subplots(1, 2, figsize=(13, 6))
    gaps, violations, times = _error_values(results)
    gap_floor, vio_floor = zero_floor(gaps), zero_floor(violations)
    for p, res in enumerate(results):
        colour = colours[p]
        for row in res["rows"]:
            k = methods.index(row["method"])
            m, fill = MARKERS[k % len(MARKERS)], (colour if k == 0 else "none")
            gaps_of = [_gap(o, res) for o in row["objectives"]]
            ax_gap.plot(row["wall_s"], [on_log_axis(g, gap_floor) if not _below(g, res) else math.nan for g in gaps_of],
                        m, color=colour, ms=6, mfc=fill, alpha=0.8)
            # a run below the best known missed a rule (the best known is the best design meeting them all): not a
            # gap of 0, so marked apart at the floor
            below = [t for t, g in zip(row["wall_s"], gaps_of) if _below(g, res)]
            if below:
                ax_gap.plot(below, [gap_floor] * len(below), "x", color="red", ms=8, mew=1.6)
            trace = best_so_far(row, res["best_known"])
            if trace:
                ax_gap.plot([t for t, _ in trace], [on_log_axis(g, gap_floor) for _, g in trace],
                            "-" if k == 0 else "--", color=colour, lw=0.9, alpha=0.6, drawstyle="steps-post")
            ax_vio.plot([row["median_s"]], [on_log_axis(row["worst_violation"], vio_floor)], m, color=colour, ms=7,
                        mfc=fill)
        ax_gap.plot([], [], "-", color=colour, label=res["problem"])
    for k, method in enumerate(methods):
        for ax in (ax_gap, ax_vio):
            ax.plot([], [], MARKERS[k % len(MARKERS)], color="0.3", mfc="none" if k else "0.3", label=method)
    for ax, floor, values, what, title, ylabel in (
            (ax_gap, gap_floor, gaps, "gap", "objective gap to the best known", _gap_label(results)),
            (ax_vio, vio_floor, violations, "no violation", "worst rule violation (fine re-check grid)",
             "normalised violation")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axhline(floor, color="0.55", lw=0.9, ls=":")
        fit_log_axis(ax, "x", times)
        fit_log_axis(ax, "y", values, floor)
        ax.set_xlabel("wall time, s")
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
        handles, labels = ax.get_legend_handles_labels()
        if handles:     # a bench with no result has nothing to name (matplotlib warns)
            handles.append(_floor_handle(what, values))
            labels = labels + [handles[-1].get_label()]
            if ax is ax_gap and any(_below(_gap(o, res), res) for res in results for row in res["rows"]
                                    for o in row["objectives"]):
                handles.append(Line2D([], [], marker="x", color="red", ls="none", ms=8, mew=1.6))
                labels.append("below the best known: a rule missed (not a gap of 0)")
            legend_below(ax, ncol=2, fontsize=7, handles=handles, labels=labels)
    fig.suptitle("error against run time (points: repeats; lines: best so far in the median run)", fontsize=10)
    fig.tight_layout()
    return fig


def _gap(objective, res: dict) -> float | None:
    return None if objective is None or not math.isfinite(objective) else objective - res["best_known"]


def _below(gap: float | None, res: dict) -> bool:
    """A gap below the best known by more than round-off: a run that missed a rule."""
    best = res.get("best_known")
    scale = max(1.0, abs(best)) if isinstance(best, (int, float)) and math.isfinite(best) else 1.0
    return gap is not None and gap < -1e-9 * scale


def _gap_label(results: list[dict]) -> str:
    """The gap axis' label with the objectives' unit: one unit when the problems share it, else where to read them."""
    units = {(row.get("details") or {}).get("objective_unit") for res in results for row in res["rows"]
             if isinstance(row.get("details"), dict) and (row.get("details") or {}).get("objective_unit")}
    units.discard("-")
    if len(units) == 1:
        return f"objective - best known, {units.pop()}"
    return "objective - best known (each problem's unit: bench.md)" if units else "objective - best known"


def _error_values(results: list[dict]) -> tuple[list, list, list]:
    """(every gap drawn, every violation drawn, every time drawn) of the error plot: its axes' data."""
    gaps, violations, times = [], [], []
    for res in results:
        for row in res["rows"]:
            gaps += [_gap(o, res) for o in row["objectives"]] + [g for _, g in best_so_far(row, res["best_known"])]
            violations.append(row["worst_violation"])
            times += list(row["wall_s"]) + [row["median_s"]] + [t for t, _ in best_so_far(row, res["best_known"])]
    return gaps, violations, times


def sweep_figure(sweep: dict):
    """Log-log: fine-grid worst violation and objective gap to the finest count against median wall time, each
    count's samples on the top axis at its time."""
    rows = sweep["rows"]
    t = [r["median_s"] for r in rows]
    keys = (("worst_violation", "worst violation (fine grid, normalised)", "o"),
            ("objective_gap", "objective gap to the finest count", "s"))
    values = [r[key] for r in rows for key, _, _ in keys]
    floor = zero_floor(values + [sweep["violation_target"]])
    fig, ax = plt.subplots(figsize=(7, 5))
    ax.set_xscale("log")
    ax.set_yscale("log")
    for key, label, marker in keys:
        ax.plot(t, [on_log_axis(r[key], floor) for r in rows], marker + "-", label=label)
    ax.axhline(sweep["violation_target"], color="0.5", lw=0.8, ls="-.", label=f"violation target "
                                                                           f"{sweep['violation_target']:g}")
    ax.axhline(floor, color="0.55", lw=0.9, ls=":")
    fit_log_axis(ax, "x", t)
    fit_log_axis(ax, "y", values + [sweep["violation_target"]], floor)
    top = ax.secondary_xaxis("top")
    top.xaxis.set_major_locator(FixedLocator(t))
    counts = {x: " ".join(str(n) for n in r["samples"].values()) for r, x in zip(rows, t)}
    top.xaxis.set_major_formatter(FuncFormatter(lambda v, pos: counts.get(v, "")))
    top.xaxis.set_minor_locator(NullLocator())
    top.set_xlabel("samples", fontsize=8)
    ax.set_xlabel("median wall time, s")
    ax.set_ylabel("violation (normalised) or objective gap")
    ax.set_title(f"{sweep['problem']}: sample counts ({', '.join(rows[0]['samples'])})", fontsize=10)
    ax.grid(alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    handles.append(_floor_handle("exact", values + [sweep["violation_target"]]))
    legend_below(ax, ncol=1, fontsize=8, handles=handles, labels=labels + [handles[-1].get_label()])
    fig.tight_layout()
    return fig

"""A figure of one design never calls it "baseline"; beside other candidates the first one is.

Every kind's comparison overlay (``Kind.compare_figures``) is drawn from the checked library example of the kind,
once alone and once beside a renamed copy, and every text matplotlib would draw (legend entries, titles,
axis labels) is read off the figures before they are saved."""

from __future__ import annotations

import dataclasses

import matplotlib
import pytest

matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

from conftest import LIBRARY  # noqa: E402
from synthesis import kinds  # noqa: E402
from synthesis.spec import load_spec  # noqa: E402

OVERLAID = [k for k in kinds.names() if kinds.get(k).compare_figures() is not None and kinds.get(k).example]


def drawn_texts(monkeypatch, writer, results, folder) -> list[str]:
    """Every text of every figure ``writer`` saves: legend entries, titles, axis labels, suptitles."""
    texts: list[str] = []
    save = Figure.savefig

    def reading(fig, *args, **kwargs):
        for text in fig.findobj(matplotlib.text.Text):
            if text.get_text():
                texts.append(text.get_text())
        return save(fig, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", reading)
    writer(results, folder)
    return texts


@pytest.mark.parametrize("kind_name", [pytest.param(k, marks=pytest.mark.slow)
                                       if k in ("planting_fourbar", "clamp_cam") else k for k in OVERLAID])
def test_one_design_is_never_the_baseline(kind_name, tmp_path, monkeypatch):
    kind = kinds.get(kind_name)
    loaded = load_spec(LIBRARY / kind.example)
    result = kinds.checker(kind_name)(loaded)
    writer = kinds.compare_figures(kind_name)
    alone = drawn_texts(monkeypatch, writer, [result], tmp_path)
    assert alone and not [t for t in alone if "baseline" in t]
    other = dataclasses.replace(result, name=f"{result.name}_copy")
    both = drawn_texts(monkeypatch, writer, [result, other], tmp_path)
    assert f"{result.name}_copy" in " ".join(both)
    assert not [t for t in both if "baseline" in t and result.name not in t and "first" not in t
                and "baseline's" not in t and "seedbed" not in t], both


def test_planting_kinematics_figure_speaks_the_rule_tables_units(tmp_path, monkeypatch):
    """Speeds in m/s as p2_speed, the vertical acceleration in mm/s^2 as accel_*; the plotted
    numbers are the trajectory's converted (ground vx in m/s, ay unchanged)."""
    import numpy as np

    from synthesis.kinds.planting.compare_plots import kinematics_figure

    result = kinds.checker("planting_fourbar")(load_spec(LIBRARY / "planting_arm" / "taiwan_example1.toml"))
    units = {r["name"]: r["unit"] for r in result.rules}
    assert (units["p2_speed"], units["accel_hold"]) == ("m/s", "mm/s^2")
    figures: list[Figure] = []
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: figures.append(fig))
    kinematics_figure([result], tmp_path / "kinematics.png")
    axes = figures[0].axes
    assert [ax.get_ylabel() for ax in axes] == ["v_x ground, m/s", "v_y, m/s", "a_y, mm/s²"]
    vx, ay = axes[0].lines[0].get_ydata(), axes[2].lines[0].get_ydata()
    assert np.max(vx) == pytest.approx(max(result.trajectory["vx"]) / 1000.0, rel=1e-12)
    assert np.min(ay) == pytest.approx(min(result.trajectory["ay"]), rel=1e-12)


def test_guide_tube_bars_start_at_zero_and_carry_their_values(tmp_path, monkeypatch):
    """The comparison bar chart's time axis started at 0.9 x the shortest time (0.40 s), which
    made a few ms look like a factor; the bars now start at 0 s and each is labelled with its t_z."""
    from synthesis.kinds.guide_tube.plots import compare_figures

    first = kinds.checker("guide_tube")(load_spec(LIBRARY / "guide_tube" / "cai2020_tubes.toml"))
    other = kinds.checker("guide_tube")(load_spec(LIBRARY / "guide_tube" / "cai2020_delta2.toml"))
    figures: list[Figure] = []
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: figures.append(fig))
    compare_figures([first, other], tmp_path)
    ax = figures[0].axes[0]
    assert ax.get_ylim()[0] == 0.0
    labels = [t.get_text() for t in ax.texts]
    assert labels == [f"{t['t_z']:.4f}" for r in (first, other) for t in r.extra["tubes"]]


#: kind -> its run figures (every PNG of Kind.figures, the first is the kind's main figure)
RUN_FIGURES = {k: [n for n in kinds.get(k).figures() if n.endswith(".png")] for k in kinds.names()
               if kinds.get(k).example}


def legend_overlaps(fig: Figure) -> list[str]:
    """Each legend of ``fig`` (of an axes or of the figure) that covers an axes' data area or reaches past the
    figure's edge, as drawn at the figure's own size and dpi (the saved image is that canvas)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)           # the figure's own canvas is gone once pyplot closed it
    canvas.draw()
    renderer = canvas.get_renderer()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends)
    out = []
    for legend in legends:
        box = legend.get_window_extent(renderer)
        for i, ax in enumerate(fig.axes):
            if ax.get_visible() and box.overlaps(ax.get_window_extent(renderer)):
                out.append(f"legend {[t.get_text() for t in legend.get_texts()][:3]} over axes {i} "
                           f"({ax.get_title() or ax.get_xlabel()})")
        inside = fig.bbox
        if box.x0 < inside.x0 - 1 or box.y0 < inside.y0 - 1 or box.x1 > inside.x1 + 1 or box.y1 > inside.y1 + 1:
            out.append(f"legend {[t.get_text() for t in legend.get_texts()][:3]} past the figure's edge")
    return out


@pytest.mark.parametrize("kind_name", [pytest.param(k, marks=pytest.mark.slow)
                                       if k in ("planting_fourbar", "rotary_planetary") else k for k in RUN_FIGURES])
def test_legends_stay_outside_the_drawing(kind_name, tmp_path, monkeypatch):
    """Every legend of every run figure lies beside the axes (below or right of them), never over a link, a label
    or a curve, and inside the figure: its bounding box meets no axes' data area (the coupler curve's legend covered
    a link and its length label)."""
    kind = kinds.get(kind_name)
    result = kinds.checker(kind_name)(load_spec(LIBRARY / kind.example))
    drawn: list[Figure] = []
    monkeypatch.setattr(Figure, "savefig", lambda fig, *a, **k: drawn.append(fig))
    found = {}
    for name in RUN_FIGURES[kind_name]:
        drawn.clear()
        kind.figures()[name](result, tmp_path / name)
        assert drawn, name
        legends = sum(len(f.legends) + sum(ax.get_legend() is not None for ax in f.axes) for f in drawn)
        found[name] = (legends, [o for f in drawn for o in legend_overlaps(f)])
    assert {name: overlaps for name, (_, overlaps) in found.items() if overlaps} == {}
    assert sum(n for n, _ in found.values()) >= 1, found        # the kind's figures have legends to judge
    monkeypatch.undo()
    for name in [n for n in kind.figures() if n.endswith(".svg")]:     # an SVG canvas places the legends too
        kind.figures()[name](result, tmp_path / name)
        assert (tmp_path / name).stat().st_size > 10_000, name

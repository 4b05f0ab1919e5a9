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


@pytest.mark.parametrize("kind_name", [pytest.param(k, marks=pytest.mark.slow) if k == "planting_fourbar" else k
                                       for k in OVERLAID])
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

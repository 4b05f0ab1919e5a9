"""Issue 17: a figure of one design never calls it "baseline"; beside other candidates the first one is.

Every kind's comparison overlay (``Kind.compare``) is drawn from the checked library example of the kind,
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

OVERLAID = [k for k in kinds.names() if kinds.get(k).compare is not None and kinds.get(k).example]


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


@pytest.mark.parametrize("kind_name", OVERLAID)
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

"""Legends beside a figure's drawing, never on it: below an axes (under its tick labels and x label) or right of it.

A legend placed inside the axes (``loc="best"``) covered a link and its length label on the coupler-curve figure.
Placed here its box lies outside every axes' data area; the figure's ``tight_layout`` (which counts legends) then
makes room for it inside the figure, so it is called after the legend is placed.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import RendererAgg
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.transforms import BboxBase, IdentityTransform
import numpy as np

#: inches between the axes' outer decorations (tick labels, axis label) and the legend
GAP = 0.08


#: characters a legend entry's line holds below an axes (two columns fit an 8-inch figure) and right of one: a longer
#: entry (a candidate's 100-character spec name) is wrapped rather than pushed off the figure -- two such names had
#: clipped a legend on both sides, one of 195 characters left no room for the legend at all
BELOW_WIDTH, RIGHT_WIDTH = 48, 32


def _wrapped(label: str, width: int) -> str:
    """``label`` folded into lines of at most ``width`` characters (a long name without spaces broken too)."""
    if len(label) <= width:
        return label
    return "\n".join(textwrap.wrap(label, width, break_long_words=True, break_on_hyphens=False)) or label


def _entries(ax: Axes, handles, labels, width: int) -> tuple[list, list]:
    if handles is not None:
        found = list(labels if labels is not None else [h.get_label() for h in handles])
        return list(handles), [_wrapped(str(text), width) for text in found]
    found_handles, found_labels = ax.get_legend_handles_labels()
    return found_handles, [_wrapped(text, width) for text in found_labels]


def _twins(ax: Axes) -> list[Axes]:
    """``ax`` and the axes drawn on the same spot (twinx/twiny): their tick labels surround the same box."""
    box = ax.get_position().bounds
    return [a for a in ax.figure.axes if a is ax or a.get_position().bounds == box]


def _renderer(fig: Figure):
    """What measures the labels: the canvas's renderer, or (an SVG or PDF canvas, which keeps none) an Agg renderer of
    the figure's size: text is measured the same by both."""
    if hasattr(fig.canvas, "get_renderer"):
        return fig.canvas.get_renderer()
    width, height = fig.bbox.size
    return RendererAgg(int(width), int(height), fig.dpi)


class _Beside(BboxBase):
    """The edge (in pixels: the legend is given an identity transform) a legend hangs from: under the axes' x tick labels and x label (``below``) or right of its (and its
    twins') y tick labels and y label.  Measured again whenever the axes' box changes, so it follows the figure's
    tight_layout (call it after the labels are set) and the dpi of savefig."""

    def __init__(self, ax: Axes, below: bool):
        super().__init__()
        self.ax, self.below = ax, below
        self.set_children(ax.bbox)      # measured again when the axes move (tight_layout) or the dpi changes (savefig)

    def get_points(self) -> np.ndarray:
        self._invalid = 0               # valid until the axes' box changes again (else no change would reach us)
        fig = self.ax.figure
        renderer = _renderer(fig)
        box = self.ax.get_window_extent(renderer)
        gap = GAP * fig.dpi
        if self.below:
            reach = [a.xaxis.get_tightbbox(renderer) for a in _twins(self.ax) if a.xaxis.get_visible()]
            y = min([box.y0] + [b.y0 for b in reach if b is not None]) - gap
            return np.array([[box.x0, y], [box.x1, y]])
        reach = [a.yaxis.get_tightbbox(renderer) for a in _twins(self.ax) if a.yaxis.get_visible()]
        x = max([box.x1] + [b.x1 for b in reach if b is not None]) + gap
        return np.array([[x, box.y1], [x, box.y1]])


def legend_below(ax: Axes, *, ncol: int = 3, fontsize: float = 8, handles=None, labels=None) -> Legend | None:
    """The axes' legend centred under it, ``ncol`` entries a row; None when nothing is labelled."""
    handles, labels = _entries(ax, handles, labels, BELOW_WIDTH)
    if not handles:
        return None
    return ax.legend(handles, labels, loc="upper center", bbox_to_anchor=_Beside(ax, below=True),
                     bbox_transform=IdentityTransform(),
                     ncol=min(ncol, len(handles)), fontsize=fontsize, frameon=False, borderaxespad=0.0)


def legend_right(ax: Axes, *, fontsize: float = 8, handles=None, labels=None) -> Legend | None:
    """The axes' legend right of it, its top level with the axes' top; None when nothing is labelled."""
    handles, labels = _entries(ax, handles, labels, RIGHT_WIDTH)
    if not handles:
        return None
    return ax.legend(handles, labels, loc="upper left", bbox_to_anchor=_Beside(ax, below=False),
                     bbox_transform=IdentityTransform(), fontsize=fontsize,
                     frameon=False, borderaxespad=0.0)


def save_overlay(fig: Figure, axes, folder: Path, name: str) -> list[str]:
    """A kind's compare overlay finished the one way they share: every axes gridded with its candidates' legend
    below it, laid out, written to ``folder / name`` at 110 dpi and closed; the file names written."""
    for ax in axes:
        ax.grid(alpha=0.3)
        legend_below(ax, ncol=2, fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / name, dpi=110)
    plt.close(fig)
    return [name]

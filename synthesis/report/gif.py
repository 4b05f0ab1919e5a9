"""Animated GIFs of a figure whose still parts are drawn once.

matplotlib's ``Animation.save`` redraws the whole figure for every frame -- axes, ticks, grid, legend, every text --
even with ``blit=True`` (blitting serves only the interactive backends).  A report's linkage animation is mostly
still: planting's 36 frames took 4.1 of a 7 s ``agrisynth check``.  Here the figure is drawn once without the
artists that move, that picture is kept, and each frame restores it and draws the frame's artists on top (the
blitting of matplotlib's interactive backends, into images).  Still artists that a full redraw puts above a moving
one -- of the same axes, higher in z-order or equal and added later, and the figure's own legends and texts -- are
left out of the kept picture and drawn with each frame in the full redraw's order.  What is not layered so: the
axes' grid, ticks and spines (always below the moving artists), other axes overlapping the moving artists' axes
(twins), and the still artists between a later frame's lower z-order and frame 0's.  PIL assembles the frames as
PillowWriter does (an opaque frame as RGB, one duration each, looping).
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Iterable

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.axis import Axis
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.spines import Spine
from PIL import Image


def _still_above(fig: Figure, moving: list[Artist]) -> list[Artist]:
    """The still artists a full redraw draws after a moving one: in an axes with moving artists, those higher in
    z-order than its lowest moving artist, or equal and added after it (not the grid, ticks, spines); and the
    figure's own artists (legends, texts, suptitle), drawn after every axes."""
    ids = {id(a) for a in moving}
    above = []
    for ax in fig.axes:
        children = ax.get_children()
        ranks = [(a.get_zorder(), i) for i, a in enumerate(children) if id(a) in ids]
        if not ranks:
            continue
        lowest = min(ranks)
        above += [a for i, a in enumerate(children)
                  if id(a) not in ids and a is not ax.patch and not isinstance(a, (Axis, Spine)) and a.get_visible()
                  and (a.get_zorder(), i) > lowest]
    return above + [a for a in fig.get_children()
                    if id(a) not in ids and a is not fig.patch and not isinstance(a, Axes) and a.get_visible()]


def _in_drawing_order(fig: Figure, artists: list[Artist]) -> list[Artist]:
    """The artists as a full redraw orders them: axes by axes, within one by z-order, ties in the order added;
    artists of no axes (the figure's own) last."""
    ids = {id(a) for a in artists}
    ordered, placed = [], set()
    for ax in fig.axes:
        mine = [a for a in ax.get_children() if id(a) in ids]
        ordered += sorted(mine, key=lambda a: a.get_zorder())
        placed |= {id(a) for a in mine}
    return ordered + [a for a in artists if id(a) not in placed]


def save_gif(fig: Figure, draw_frame: Callable[[int], Iterable[Artist]], frames: int, path: Path | str,
             fps: float, dpi: float) -> None:
    """Write ``frames`` (>= 1) frames of ``fig`` to ``path`` as a looping GIF at ``fps`` frames a second and ``dpi``.

    ``draw_frame(k)`` puts frame k's moving artists on the figure (updating them, or removing the last frame's and
    adding new ones) and returns every artist it changed: an artist changed but not returned stays as the kept
    picture has it.  The axes' limits must be set (nothing is rescaled per frame, as a full redraw would)."""
    if frames < 1:
        raise ValueError(f"a GIF needs at least one frame, got frames = {frames}")
    kept_dpi = fig.dpi
    fig.set_dpi(dpi)
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    moving = list(draw_frame(0))
    above = _still_above(fig, moving)
    for artist in moving + above:
        artist.set_animated(True)            # canvas.draw leaves animated artists out: the kept picture
    canvas.draw()
    still = canvas.copy_from_bbox(fig.bbox)
    images = []
    for k in range(frames):
        if k:
            moving = list(draw_frame(k))
        canvas.restore_region(still)
        for artist in _in_drawing_order(fig, moving + above):
            fig.draw_artist(artist)
        rgba = np.asarray(canvas.buffer_rgba())
        image = Image.frombuffer("RGBA", (rgba.shape[1], rgba.shape[0]), rgba.tobytes(), "raw", "RGBA", 0, 1)
        # as PillowWriter: an opaque frame goes to RGB, which PIL turns into a GIF palette better than RGBA
        images.append(image if image.getextrema()[3][0] < 255 else image.convert("RGB"))
    for artist in moving + above:
        artist.set_animated(False)
    fig.set_dpi(kept_dpi)
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)

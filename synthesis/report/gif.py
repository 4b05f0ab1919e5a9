"""Animated GIFs of a figure whose still parts are drawn once.

matplotlib's ``Animation.save`` redraws the whole figure for every frame -- axes, ticks, grid, legend, every text --
even with ``blit=True`` (blitting serves only the interactive backends).  A report's linkage animation is mostly
still: planting's 36 frames took 4.1 of a 7 s ``agrisynth check``.  Here the figure is drawn once without the
artists that move, that picture is kept, and each frame restores it and draws the frame's artists on top (the
blitting of matplotlib's interactive backends, into images).  Still artists that a full redraw puts above a moving
one -- of the same axes, higher in z-order or equal and added later, and the figure's own legends and texts -- are
drawn with each frame in the full redraw's order, unless no moving artist of any frame comes near them (a legend
below the axes, a title): those share no pixel with a moving one, so the kept picture holds them.  What is not
layered so: the axes' grid, ticks and spines (always below the moving artists), other axes overlapping the moving
artists' axes (twins), and the still artists between a later frame's lower z-order and frame 0's.

The frames are written with PIL.  By default as PillowWriter does (an opaque frame as RGB, which PIL quantises to a
palette of its own, one duration each, looping).  With ``shared_palette`` one palette serves every frame: PIL's
median cut of the first frame and of every pixel a later frame changes, each pixel written as the entry the median
cut gave its colour.  Quantising every whole frame was most of an animation's time (planting: 0.8 of 1.5 s CPU);
shared, a pixel no moving artist touches keeps its entry from frame to frame (per-frame palettes shifted up to 1,900
still pixels of a planting frame to another shade), so PIL writes each later frame's unchanged pixels transparent
(the entry left free for it), and the file is smaller (planting: 280 instead of 454 kB).  The colours are a median
cut's either way: planting's frames are off the drawn pixels by 0.025 of 255 on average, 54 at most (a few
antialiased edge pixels; per-frame palettes: 0.013 and 64).
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
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.spines import Spine
from matplotlib.text import Text
from matplotlib.transforms import Bbox
from PIL import Image

#: pixels around an artist's measured box that its drawing may still colour (antialiasing, line caps and joins)
MARGIN_PX = 3.0
#: points a legend's shadow may lie beside its frame (matplotlib offsets it by 2 points; the rest is a safe margin)
SHADOW_PT = 10.0


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


def _box(artist: Artist, renderer, dpi: float) -> Bbox | None:
    """The pixels a drawn ``artist`` can colour: its window extent (a text's with its box patch, a legend's with its
    frame) widened by its line width and MARGIN_PX; None for an artist of another kind or one that cannot be
    measured (then it is taken to reach everywhere)."""
    if not isinstance(artist, (Line2D, Text, Legend, Patch)):
        return None
    try:
        boxes = [artist.get_window_extent(renderer)]
        widths = [artist.get_linewidth() if isinstance(artist, (Line2D, Patch)) else 0.0]
        if isinstance(artist, Line2D) and artist.get_marker() not in (None, "None", "", " "):
            widths.append(artist.get_markeredgewidth())
        frame = (artist.get_bbox_patch() if isinstance(artist, Text) else
                 artist.get_frame() if isinstance(artist, Legend) and artist.get_frame_on() else None)
        if isinstance(artist, Text) and frame is not None:
            artist.update_bbox_position_size(renderer)      # the box as the text now is, not as last drawn
        if frame is not None:
            boxes.append(frame.get_window_extent(renderer))
            widths.append(frame.get_linewidth())
        if isinstance(artist, Legend) and artist.shadow:
            widths.append(SHADOW_PT)
        box = Bbox.union(boxes)
    except Exception:       # noqa: BLE001 - an artist that cannot say where it draws is taken to draw everywhere
        return None
    if not np.all(np.isfinite(box.get_points())):
        return None
    return box.padded(max(widths) * dpi / 72.0 + MARGIN_PX)


def _clip_box(artist: Artist) -> Bbox | None:
    """The rectangle ``artist`` is clipped to (its axes' box, for a line plotted there), widened by the pixel its
    edge rounds into: it colours nothing outside, wherever it moves; None when it is not clipped to one."""
    box = artist.get_clip_box() if artist.get_clip_on() and artist.get_clip_path() is None else None
    return None if box is None else Bbox(box.get_points()).padded(1.0)


def _overlaps(a: Bbox, b: Bbox) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def _near_moving(fig: Figure, canvas: FigureCanvasAgg, draw_frame: Callable[[int], Iterable[Artist]], frames: int,
                 above: list[Artist]) -> list[Artist]:
    """Of the still artists drawn above the moving ones (as the figure was last drawn), those that some frame's
    moving artists come near.  Every frame is put on the figure to measure its moving artists; the figure is left
    at the last one measured."""
    renderer = canvas.get_renderer()
    boxes = {id(a): _box(a, renderer, fig.dpi) for a in above}
    near = {id(a) for a in above if boxes[id(a)] is None}
    for k in range(frames):
        if len(near) == len(above):
            break
        for artist in draw_frame(k):
            if not artist.get_visible():
                continue
            reach = _clip_box(artist) or _box(artist, renderer, fig.dpi)
            near |= {id(a) for a in above if id(a) not in near
                     and (reach is None or _overlaps(reach, boxes[id(a)]))}    # type: ignore[arg-type]
    return [a for a in above if id(a) in near]


class _SharedPalette:
    """The frames of a GIF with one palette: the first frame whole, each later one as the pixels it changes."""

    def __init__(self) -> None:
        self.first: np.ndarray | None = None          # (h, w) RGBA pixels, each as one uint32
        self.changes: list[tuple[np.ndarray, np.ndarray]] = []      # per later frame: (flat indices, pixels)

    def add(self, rgba: np.ndarray) -> None:
        pixels = np.ascontiguousarray(rgba).view(np.uint32)[..., 0]
        if self.first is None:
            self.first = pixels.copy()
            return
        where = np.flatnonzero(pixels != self.first)
        self.changes.append((where, pixels.ravel()[where]))

    def frame(self, k: int) -> np.ndarray:
        """Frame k's RGBA pixels (h, w, 4)."""
        assert self.first is not None
        pixels = self.first.copy()
        if k:
            where, changed = self.changes[k - 1]
            pixels.ravel()[where] = changed
        return pixels.view(np.uint8).reshape(*pixels.shape, 4)

    def opaque(self) -> bool:
        assert self.first is not None
        alpha = lambda p: p.view(np.uint8)[3::4]       # noqa: E731 - RGBA bytes of pixels stored as uint32
        return bool(alpha(self.first.ravel()).min() == 255
                    and all(alpha(c).min(initial=255) == 255 for _, c in self.changes))

    def images(self) -> list[Image.Image]:
        """The frames as palette images sharing one palette (opaque frames only)."""
        assert self.first is not None
        h, w = self.first.shape
        colours = np.concatenate([self.first.ravel()] + [c for _, c in self.changes])
        strip = Image.frombuffer("RGBA", (len(colours), 1), colours.tobytes(), "raw", "RGBA", 0, 1).convert("RGB")
        # PIL's median cut, as for a frame of its own, to one entry fewer than a GIF holds: PIL writes the pixels a
        # frame leaves as they were in the entry left free, transparent, which compresses to almost nothing
        quantised = strip.convert("P", palette=Image.Palette.ADAPTIVE, colors=255)
        palette = quantised.getpalette()
        assert palette is not None
        entries = np.asarray(quantised).ravel()
        first = entries[:h * w].reshape(h, w)
        images, start = [], h * w
        for k in range(len(self.changes) + 1):
            index = first.copy()
            if k:
                where, changed = self.changes[k - 1]
                index.ravel()[where] = entries[start:start + len(where)]
                start += len(where)
            image = Image.fromarray(index)
            image.putpalette(palette)           # the entries' image, "L", becomes a palette image
            images.append(image)
        return images


def _pillow_frame(rgba: np.ndarray) -> Image.Image:
    """A frame as PillowWriter hands it to PIL: an opaque frame as RGB, which PIL turns into a GIF palette better
    than RGBA."""
    image = Image.frombuffer("RGBA", (rgba.shape[1], rgba.shape[0]), rgba.tobytes(), "raw", "RGBA", 0, 1)
    return image if rgba[..., 3].min() < 255 else image.convert("RGB")


def save_gif(fig: Figure, draw_frame: Callable[[int], Iterable[Artist]], frames: int, path: Path | str,
             fps: float, dpi: float, *, shared_palette: bool = False) -> None:
    """Write ``frames`` (>= 1) frames of ``fig`` to ``path`` as a looping GIF at ``fps`` frames a second and ``dpi``.

    ``draw_frame(k)`` puts frame k's moving artists on the figure (updating them, or removing the last frame's and
    adding new ones) and returns every artist it changed: an artist changed but not returned stays as the kept
    picture has it.  It may be called more than once for a frame, in any order.  The axes' limits must be set
    (nothing is rescaled per frame, as a full redraw would).  ``shared_palette``: one palette for every frame
    (module docstring) instead of PillowWriter's palette per frame."""
    if frames < 1:
        raise ValueError(f"a GIF needs at least one frame, got frames = {frames}")
    kept_dpi = fig.dpi
    fig.set_dpi(dpi)
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    moving = list(draw_frame(0))
    above = _still_above(fig, moving)
    for artist in moving:
        artist.set_animated(True)            # canvas.draw leaves animated artists out: the kept picture
    canvas.draw()
    if above:
        above = _near_moving(fig, canvas, draw_frame, frames, above)
        moving = list(draw_frame(0))
        if above:                            # drawn again without the still artists a moving one may cover
            for artist in moving + above:
                artist.set_animated(True)
            canvas.draw()
    still = canvas.copy_from_bbox(fig.bbox)
    shared = _SharedPalette() if shared_palette else None
    images = []
    for k in range(frames):
        if k:
            moving = list(draw_frame(k))
        canvas.restore_region(still)
        for artist in _in_drawing_order(fig, moving + above):
            fig.draw_artist(artist)
        rgba = np.asarray(canvas.buffer_rgba())
        if shared is not None:
            shared.add(rgba)
        else:
            images.append(_pillow_frame(rgba))
    for artist in moving + above:
        artist.set_animated(False)
    fig.set_dpi(kept_dpi)
    if shared is not None:
        # see-through pixels: PIL's own palette for each frame, which keeps them
        images = shared.images() if shared.opaque() else [_pillow_frame(shared.frame(k)) for k in range(frames)]
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)

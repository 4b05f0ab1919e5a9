"""report.gif draws a figure's still parts once and each frame's moving artists on top: its GIF must be the one
matplotlib's FuncAnimation + PillowWriter (a full redraw per frame) writes, pixel for pixel, including still artists
above the moving ones (a legend, markers of a higher z-order) and frames that replace their artists."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.animation import FuncAnimation, PillowWriter  # noqa: E402
from PIL import Image, ImageSequence  # noqa: E402

from synthesis.report.gif import save_gif  # noqa: E402

FRAMES = 8


def _figure(replace_artists: bool):
    """A linkage-like figure: a still curve, still pivots above the links (zorder 5), a legend over the links' way, a
    still line of the link's z-order added after it, a figure text across the link's way, a counter; the moving
    link either updated in place or removed and drawn anew each frame (planting's way)."""
    fig, ax = plt.subplots(figsize=(3.2, 2.6))
    t = np.linspace(0.0, 2.0 * np.pi, 200)
    ax.plot(np.cos(t), np.sin(t), color="tab:blue", lw=1.0, label="curve")
    ax.plot([0.0, 0.9], [0.0, 0.6], "^", color="k", ms=9, zorder=5, label="pivots")
    ax.set_xlim(-1.2, 1.2)
    ax.set_ylim(-1.2, 1.2)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=7)
    counter = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=8, zorder=9)   # the link lowest
    link, = ax.plot([], [], color="0.25", lw=3.0, zorder=4)
    ax.plot([-1.0, 1.0], [0.2, 0.2], color="tab:green", lw=4.0, zorder=4)   # z-order equal, added after: above
    fig.text(0.5, 0.45, "figure text", fontsize=14, ha="center")            # the figure's own: above every axes
    drawn: list = []

    def frame(k: int):
        a = 2.0 * np.pi * k / FRAMES
        xs, ys = [0.0, np.cos(a), 0.9], [0.0, np.sin(a), 0.6]      # through both pivots and, at times, the legend
        counter.set_text(f"frame {k + 1}/{FRAMES}")
        if not replace_artists:
            link.set_data(xs, ys)
            return [link, counter]
        for artist in drawn:
            artist.remove()
        drawn[:] = ax.plot(xs, ys, color="tab:red", lw=3.0, zorder=4) + [ax.text(np.cos(a), np.sin(a), "A", zorder=9)]
        return drawn + [counter]

    return fig, frame


def _frames(path) -> list[np.ndarray]:
    with Image.open(path) as gif:
        return [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(gif)]


def _info(path) -> dict:
    with Image.open(path) as gif:
        return dict(gif.info)


@pytest.mark.parametrize("replace_artists", [False, True])
def test_the_gif_is_the_full_redraw_pixel_for_pixel(tmp_path, replace_artists):
    fig, frame = _figure(replace_artists)
    FuncAnimation(fig, frame, frames=FRAMES, blit=False).save(tmp_path / "full.gif", writer=PillowWriter(fps=5),
                                                             dpi=80)
    plt.close(fig)
    fig, frame = _figure(replace_artists)
    save_gif(fig, frame, FRAMES, tmp_path / "kept.gif", fps=5, dpi=80)
    plt.close(fig)
    full, kept = _frames(tmp_path / "full.gif"), _frames(tmp_path / "kept.gif")
    assert len(full) == len(kept) == FRAMES
    assert _info(tmp_path / "kept.gif")["duration"] == _info(tmp_path / "full.gif")["duration"] == 200
    assert _info(tmp_path / "kept.gif")["loop"] == 0
    for k, (a, b) in enumerate(zip(full, kept)):
        assert a.shape == b.shape == (208, 256, 3)
        assert np.array_equal(a, b), f"frame {k}: {int(np.sum(np.any(a != b, axis=2)))} pixels differ"
    assert len({f.tobytes() for f in kept}) == FRAMES          # every frame shows its own pose


def test_no_frame_is_refused(tmp_path):
    fig, frame = _figure(False)
    with pytest.raises(ValueError, match="at least one frame"):
        save_gif(fig, frame, 0, tmp_path / "none.gif", fps=5, dpi=80)
    plt.close(fig)
    assert not (tmp_path / "none.gif").exists()


def _drawn_frames(replace_artists: bool) -> list[np.ndarray]:
    """Each frame as the canvas draws it in full (RGB, no palette): what a GIF approximates."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    fig, frame = _figure(replace_artists)
    fig.set_dpi(80)
    canvas = FigureCanvasAgg(fig)
    out = []
    for k in range(FRAMES):
        frame(k)
        canvas.draw()
        out.append(np.asarray(canvas.buffer_rgba())[..., :3].copy())
    plt.close(fig)
    return out


@pytest.mark.parametrize("replace_artists", [False, True])
def test_a_shared_palette_keeps_the_frames_colours_and_never_flickers_a_still_pixel(tmp_path, replace_artists):
    """save_gif(shared_palette=True): one palette for every frame.  Against the frames drawn in full, the colours
    are off by at most a palette's rounding (mean below 1/255 of full scale, no pixel by more than 64 of 255), and a
    pixel that two consecutive drawn frames share is the same in the two GIF frames (per-frame palettes may shade
    it differently)."""
    fig, frame = _figure(replace_artists)
    save_gif(fig, frame, FRAMES, tmp_path / "shared.gif", fps=5, dpi=80, shared_palette=True)
    plt.close(fig)
    drawn, shared = _drawn_frames(replace_artists), _frames(tmp_path / "shared.gif")
    assert len(shared) == FRAMES
    for k, (a, b) in enumerate(zip(drawn, shared)):
        assert a.shape == b.shape
        error = np.abs(a.astype(int) - b.astype(int))
        assert error.mean() < 1.0 and error.max() <= 64, f"frame {k}"
    for k in range(FRAMES - 1):
        still = np.all(drawn[k] == drawn[k + 1], axis=2)
        assert still.mean() > 0.5                                   # most of the picture stays
        assert np.array_equal(shared[k][still], shared[k + 1][still]), f"frames {k} and {k + 1}"
    assert len({f.tobytes() for f in shared}) == FRAMES

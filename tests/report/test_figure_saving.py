"""report.chapter.save_png_tight: the report's figures as matplotlib's bbox_inches="tight" saves them, in one draw."""

import io

import matplotlib.figure
import matplotlib.pyplot as plt  # Agg: tests/conftest.py
import numpy as np
import pytest
from PIL import Image

from flexdigit.report.chapter import save_png_tight

# Tolerances, each with the reason for its size
SIZE_PX = 3  # the tight box rounded to pixels once (here) or at two dpi-scaled stages (matplotlib)
INK_PX = 3  # where the drawing's non-white pixels end, the same rounding


def _figure(outside_legend=False, anchor_x=1.05):
    fig, axs = plt.subplots(1, 2, figsize=(8, 3.5))
    x = np.linspace(0, 10, 200)
    for k, ax in enumerate(axs):
        ax.plot(x, np.sin(x + k), label=f"sin(x + {k})")
        ax.set(title=f"panel {k}", xlabel="time (s)", ylabel="amplitude (V)")
    if outside_legend:
        axs[1].legend(loc="center left", bbox_to_anchor=(anchor_x, 0.5))  # beyond the figure's own canvas
    else:
        axs[1].legend()
    fig.suptitle("a title above everything")
    return fig


def _png(save):
    buf = io.BytesIO()
    save(buf)
    return np.asarray(Image.open(io.BytesIO(buf.getvalue())).convert("L"))


def _ink_box(gray):
    rows, cols = np.nonzero(gray < 250)
    return np.array([rows.min(), gray.shape[0] - rows.max(), cols.min(), gray.shape[1] - cols.max()])


def test_one_draw_crops_to_matplotlibs_tight_box(monkeypatch):
    fig = _figure()
    draws = _count_draws(monkeypatch)
    ours = _png(lambda f: save_png_tight(fig, f, dpi=110))
    assert len(draws) == 1
    theirs = _png(lambda f: fig.savefig(f, format="png", dpi=110, bbox_inches="tight"))
    assert np.all(np.abs(np.array(ours.shape) - np.array(theirs.shape)) <= SIZE_PX)
    # the same margins around the drawing: the 0.1 in pad (11 px) on every side, nothing cut
    assert np.all(np.abs(_ink_box(ours) - _ink_box(theirs)) <= INK_PX)
    assert fig.dpi == plt.rcParams["figure.dpi"]
    assert fig.canvas is not None  # the figure is left as it was
    plt.close(fig)


def _count_draws(monkeypatch):
    draws = []
    original = matplotlib.figure.Figure.draw
    monkeypatch.setattr(matplotlib.figure.Figure, "draw", lambda self, r: draws.append(1) or original(self, r))
    return draws


@pytest.mark.parametrize(("anchor_x", "n_draws"), [(1.05, 1), (4.0, 2)])
def test_a_legend_beyond_the_figure_is_kept(monkeypatch, anchor_x, n_draws):
    # 1.05: within the canvas's margin (one draw); 4.0: beyond it too (a second draw on the tight box)
    fig = _figure(outside_legend=True, anchor_x=anchor_x)
    draws = _count_draws(monkeypatch)
    ours = _png(lambda f: save_png_tight(fig, f, dpi=80))
    assert len(draws) == n_draws
    theirs = _png(lambda f: fig.savefig(f, format="png", dpi=80, bbox_inches="tight"))
    assert ours.shape[1] > 8 * 80  # wider than the figure: the legend is in
    assert np.all(np.abs(np.array(ours.shape) - np.array(theirs.shape)) <= SIZE_PX)
    assert np.all(np.abs(_ink_box(ours) - _ink_box(theirs)) <= INK_PX)
    plt.close(fig)

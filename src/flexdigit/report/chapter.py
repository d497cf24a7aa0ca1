"""What a report chapter is made of, and the context every chapter builder receives.

A chapter module (listed in :data:`flexdigit.report.CHAPTERS`) exposes ``build(ctx) -> Chapter``. Adding a
chapter to the report is adding one module and one line to that list.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexdigit._result_table import ResultTable
from flexdigit.params import RigParams
from flexdigit.report.results import Entry

__all__ = ["Chapter", "Figure", "ReportContext", "ResultTable"]


@dataclass
class Figure:
    """A figure saved as ``figures/<name>.png``; ``thesis_ref`` names the thesis figure it stands beside."""

    name: str
    caption: str
    thesis_ref: str = ""


@dataclass
class Chapter:
    """One chapter of the reproduce report: its tables are :class:`~flexdigit._result_table.ResultTable` of
    numbers (the library studies' own), shown formatted in ``index.html`` and as numbers in ``results.json``."""

    slug: str
    title: str
    paragraphs: list[str] = field(default_factory=list)
    entries: list[Entry] = field(default_factory=list)
    tables: list[ResultTable] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)


@dataclass
class ReportContext:
    """What every chapter builder gets: the rig parameters, where to save figures, a seed, a speed switch."""

    out_dir: Path
    params: RigParams = field(default_factory=RigParams)
    seed: int = 0
    fast: bool = False

    @property
    def figure_dir(self) -> Path:
        path = self.out_dir / "figures"
        path.mkdir(parents=True, exist_ok=True)
        return path

    def rng(self, stream: int = 0) -> np.random.Generator:
        """A generator for one chapter's random stream: same seed and stream, same numbers."""
        return np.random.default_rng([self.seed, stream])

    def save_figure(self, fig, name: str, caption: str, thesis_ref: str = "") -> Figure:
        """Save a matplotlib figure as ``figures/<name>.png``, close it, and return its :class:`Figure`."""
        import matplotlib.pyplot as plt

        from flexdigit._io import atomic_path

        # the report folder was checked before any chapter ran (report.build.check_report_dir): ours to replace
        with atomic_path(self.figure_dir / f"{name}.png", force=True) as tmp:
            save_png_tight(fig, tmp, dpi=FIGURE_DPI)
        plt.close(fig)
        return Figure(name, caption, thesis_ref)


FIGURE_DPI = 110
_PAD_IN = 0.1  # matplotlib's savefig.pad_inches


def save_png_tight(fig, path, dpi: float = FIGURE_DPI) -> None:
    """``fig.savefig(path, format="png", dpi=dpi, bbox_inches="tight")`` in one draw instead of two.

    matplotlib draws a figure once to find its tight bounding box and again to save it: ~55 % of the report's
    figure time (issue 15). Here the figure is drawn once on an Agg canvas, its tight box read from that draw, and
    the pixels cropped to it (with savefig's 0.1 in pad, less where the canvas ends). A figure with something
    drawn beyond its canvas (a legend outside it), which a crop cannot reach, is saved by savefig as before.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    original_dpi, original_canvas = fig.dpi, fig.canvas
    try:
        fig.dpi = dpi
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        box = fig.get_tightbbox(canvas.get_renderer())
        width_in, height_in = fig.get_size_inches()
        if box.x0 >= 0 and box.y0 >= 0 and box.x1 <= width_in and box.y1 <= height_in:
            pixels = np.asarray(canvas.buffer_rgba())
            x0, x1 = max(0, round((box.x0 - _PAD_IN) * dpi)), round((box.x1 + _PAD_IN) * dpi)
            y0, y1 = max(0, round((height_in - box.y1 - _PAD_IN) * dpi)), round((height_in - box.y0 + _PAD_IN) * dpi)
            Image.fromarray(pixels[y0:y1, x0:x1]).save(path, format="png")
            return
    finally:
        fig.dpi = original_dpi
        fig.set_canvas(original_canvas)
    fig.savefig(path, format="png", dpi=dpi, bbox_inches="tight")

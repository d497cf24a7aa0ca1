"""What a report chapter is made of, and the context every chapter builder receives.

A chapter module (listed in :data:`flexdigit.report.CHAPTERS`) exposes ``build(ctx) -> Chapter``. Adding a
chapter to the report is adding one module and one line to that list.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexdigit._io import atomic_path
from flexdigit._repr import fields_summary
from flexdigit._result_table import ResultTable
from flexdigit.params import RigParams
from flexdigit.report.results import Entry

__all__ = [
    "Chapter",
    "Figure",
    "ReportContext",
    "ResultTable",
    "skipped",
    "DERIVED_CALIBRATION_SOURCE",
    "without_columns",
]

#: The twin calibration's source in a report of a digit other than the thesis rig with no calibration given: the
#: thesis's fit scaled to the digit's description (report.build's use_calibration block).
DERIVED_CALIBRATION_SOURCE = "derived from the digit's description"


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

    __repr__ = fields_summary


def skipped(slug: str, title: str, reason: str) -> Chapter:
    """A chapter that does not apply to the report's digit: no entries, one paragraph saying why."""
    return Chapter(slug=slug, title=title, paragraphs=[f"Skipped for this digit: {reason}"])


def without_columns(table: ResultTable, columns: tuple[str, ...]) -> ResultTable:
    """``table`` with the cells of ``columns`` blank (NaN: "n/a" in index.html, null in results.json): the thesis
    rig's printed figures in a table of another digit, never beside its own by accident."""
    import dataclasses
    import math

    blank = {j for j, name in enumerate(table.columns) if name in columns}
    rows = tuple(tuple(math.nan if j in blank else cell for j, cell in enumerate(row)) for row in table.rows)
    return dataclasses.replace(table, rows=rows)


@dataclass
class ReportContext:
    """What every chapter builder gets: the rig parameters, where to save figures, a seed, a speed switch."""

    out_dir: Path
    params: RigParams = field(default_factory=RigParams)
    seed: int = 0
    fast: bool = False

    @property
    def thesis_rig(self) -> bool:
        """Whether the report is the thesis rig's (its figures are compared with the thesis's) or another digit's
        (the thesis's columns are not applicable, its rig's own experiments skipped)."""
        return self.params == RigParams()

    @property
    def gauges_text(self) -> str:
        """The digit's gauges in words, as chapter texts and captions name them: "three gauges" on the thesis rig,
        "four gauges" on a four-gauge digit."""
        count = len(self.params.geometry.gauge_positions_m)
        words = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight")
        return f"{words[count] if count < len(words) else count} gauge{'' if count == 1 else 's'}"

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

        # the report folder was checked before any chapter ran (report.build.check_report_dir): ours to replace
        with atomic_path(self.figure_dir / f"{name}.png", force=True) as tmp:
            save_png_tight(fig, tmp, dpi=FIGURE_DPI)
        plt.close(fig)
        return Figure(name, caption, thesis_ref)


FIGURE_DPI = 110
_PAD_IN = 0.1  # matplotlib's savefig.pad_inches
_MARGIN_IN = 1.5  # canvas drawn beyond the figure on every side, for labels and legends that overhang it


def save_png_tight(fig, path, dpi: float = FIGURE_DPI) -> None:
    """``fig.savefig(path, format="png", dpi=dpi, bbox_inches="tight")`` in one draw instead of three.

    matplotlib draws a figure once to find its tight bounding box and again to save it (~55 % of the report's
    figure time, issue 15). Here the figure is drawn once, on a canvas that reaches :data:`_MARGIN_IN` beyond it on
    every side (as savefig shifts the figure for a tight box: the drawing is unchanged), its tight box read from
    that draw, and the pixels cropped to it with savefig's 0.1 in pad. Only a drawing that reaches beyond that
    margin (a legend far outside the axes) is drawn a second time, on a canvas of its own tight box.
    """
    from matplotlib.transforms import Bbox

    width_in, height_in = fig.get_size_inches()
    area = Bbox.from_extents(-_MARGIN_IN, -_MARGIN_IN, width_in + _MARGIN_IN, height_in + _MARGIN_IN)
    pixels, box = _draw_area(fig, area, dpi)
    if box.x0 < _PAD_IN or box.y0 < _PAD_IN or box.x1 > area.width - _PAD_IN or box.y1 > area.height - _PAD_IN:
        area = Bbox.from_extents(area.x0 + box.x0, area.y0 + box.y0, area.x0 + box.x1, area.y0 + box.y1)
        pixels, box = _draw_area(fig, area.padded(_PAD_IN), dpi)
    height_px = pixels.shape[0]
    x0, x1 = max(0, round((box.x0 - _PAD_IN) * dpi)), round((box.x1 + _PAD_IN) * dpi)
    y0, y1 = max(0, height_px - round((box.y1 + _PAD_IN) * dpi)), height_px - round((box.y0 - _PAD_IN) * dpi)
    from PIL import Image

    Image.fromarray(pixels[y0:y1, x0:x1]).save(path, format="png")


def _draw_area(fig, area, dpi: float):
    """Draw ``fig`` once on an Agg canvas covering ``area`` (inches, in the figure's own frame): its RGBA pixels
    and the drawing's tight box in inches from the canvas's lower left corner. The figure is left as it was."""
    from matplotlib._tight_bbox import adjust_bbox  # what savefig(bbox_inches=...) uses; private, matplotlib pinned
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    original_dpi, original_canvas = fig.dpi, fig.canvas
    restore = None
    try:
        fig.dpi = dpi
        canvas = FigureCanvasAgg(fig)
        restore = adjust_bbox(fig, area, canvas.get_renderer(), dpi)
        canvas.draw()
        box = fig.get_tightbbox(canvas.get_renderer())
        return np.asarray(canvas.buffer_rgba()).copy(), box
    finally:
        if restore is not None:
            restore()
        fig.dpi = original_dpi
        fig.set_canvas(original_canvas)

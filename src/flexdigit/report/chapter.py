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
            fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
        plt.close(fig)
        return Figure(name, caption, thesis_ref)

"""The figures every command draws with ``--plot FILE``: one style (the report's), saved atomically by suffix.

A shared leaf (it imports no domain): each domain draws its own figure (``identify.fit_plot``,
``control.design_plot``, ...) on :func:`new_figure` and returns the matplotlib ``Figure``, so a test reads its
axes and lines; the command saves it with :func:`save_plot`. matplotlib is imported on first use only
(``flexdigit --help`` stays fast), and figures are made without pyplot (no global state, no display needed).
The style is the reproduce report's (:mod:`flexdigit.report`): its DPI, figure sizes of 6-10 by 3.4-6 inches,
matplotlib's default colours, units in every axis label.
"""

from __future__ import annotations

import os
from pathlib import Path

from flexdigit._io import atomic_path, check_output
from flexdigit.errors import ParameterError

__all__ = ["FIGURE_DPI", "PLOT_FORMATS", "check_plot", "new_figure", "save_plot", "add_plot_flag"]

#: Pixels per inch of a PNG (the report's figures are saved at this DPI).
FIGURE_DPI = 110
#: The file formats ``--plot`` writes, by the file's suffix.
PLOT_FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}


def _format(path: Path, command: str) -> str:
    fmt = PLOT_FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ParameterError(
            f"The '--plot' parameter of flexdigit {command} must be a file ending in .png, .svg or .pdf. "
            f"Got {str(path)!r} instead."
        )
    return fmt


def check_plot(path: str | os.PathLike | None, command: str, *, force: bool = False) -> Path | None:
    """``--plot``'s file checked before the work that draws it (its suffix, its folder, no clobber without
    ``force``); None when no plot was asked for."""
    if path is None:
        return None
    path = Path(path)
    _format(path, command)
    return check_output(path, force=force)


def new_figure(nrows: int = 1, ncols: int = 1, *, figsize=(7.0, 3.6), **subplots):
    """A matplotlib ``Figure`` and its axes (``Figure.subplots``), in the report's size and layout."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    return fig, fig.subplots(nrows, ncols, **subplots)


def save_plot(fig, path: str | os.PathLike, command: str = "", *, force: bool = False) -> Path:
    """Save ``fig`` to ``path`` (PNG, SVG or PDF by its suffix) atomically; an existing file only with ``force``."""
    path = Path(path)
    fmt = _format(path, command)
    metadata = {"Date": None} if fmt == "svg" else {"CreationDate": None} if fmt == "pdf" else {}
    with atomic_path(path, force=force) as tmp:
        fig.savefig(tmp, format=fmt, dpi=FIGURE_DPI, metadata=metadata)
    return path


def add_plot_flag(parser, what: str) -> None:
    """Add ``--plot FILE`` to a sub-command's parser; ``what`` says what the figure shows."""
    parser.add_argument(
        "--plot",
        metavar="FILE",
        default=None,
        help=f"draw {what} to FILE (.png, .svg or .pdf by its suffix; an existing FILE only with --force)",
    )

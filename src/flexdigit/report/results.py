"""The entries of ``results.json``: one figure of the thesis (or a new one) next to ours.

An entry is ``{key, section, thesis, ours, unit, rel_error, status, note}``. ``thesis`` is the number as printed;
``status`` is ``match`` (within the stated tolerance), ``discrepancy`` (the note explains it and gives the
corrected figure) or ``new`` (a figure the thesis does not have).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

__all__ = ["Entry", "relative_error", "compare", "new"]

Status = Literal["match", "discrepancy", "new"]


@dataclass(frozen=True)
class Entry:
    """One line of ``results.json``."""

    key: str
    section: str
    thesis: float | str | None
    ours: float | str | None
    unit: str
    rel_error: float | None
    status: Status
    note: str = ""


def relative_error(thesis: float, ours: float) -> float:
    """``|ours - thesis| / |thesis|`` (absolute error when the thesis figure is 0).

    Examples
    --------
    >>> round(relative_error(100.0, 101.0), 6)
    0.01
    """
    if thesis == 0:
        return abs(ours)
    return abs(ours - thesis) / abs(thesis)


def compare(
    key: str,
    section: str,
    thesis: float,
    ours: float,
    unit: str,
    *,
    rtol: float,
    note: str = "",
    discrepancy_note: str = "",
) -> Entry:
    """Compare a printed figure with ours: ``match`` within ``rtol``, else ``discrepancy``.

    ``note`` is kept in both cases; ``discrepancy_note`` (why they differ, with the corrected figure) is
    appended only when they do not match, and is required then, so no discrepancy goes unexplained.

    Examples
    --------
    >>> compare("x", "3.1", 0.0025, 0.00251, "", rtol=0.01).status
    'match'
    """
    ours_f, thesis_f = float(ours), float(thesis)
    if not (math.isfinite(ours_f) and math.isfinite(thesis_f)):
        err = None
        status: Status = "discrepancy"
    else:
        err = relative_error(thesis_f, ours_f)
        status = "match" if err <= rtol else "discrepancy"
    text = note
    if status == "discrepancy":
        if not discrepancy_note:
            raise ValueError(f"results entry {key!r} differs from the thesis (rel_error {err}) with no explanation")
        text = f"{note} {discrepancy_note}".strip()
    return Entry(key, section, thesis_f, ours_f, unit, err, status, text)


def new(key: str, section: str, ours: float | str, unit: str, note: str) -> Entry:
    """A figure the thesis does not report."""
    value = float(ours) if not isinstance(ours, str) else ours
    return Entry(key, section, None, value, unit, None, "new", note)

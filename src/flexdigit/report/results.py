"""The entries of ``results.json``: one figure of the thesis (or a new one) next to ours.

An entry is ``{key, section, thesis, ours, unit, rel_error, status, note}``. ``thesis`` is the number as printed;
``status`` is ``match`` (within the stated tolerance), ``discrepancy`` (the note explains it and gives the
corrected figure) or ``new`` (a figure the thesis does not have).

On a digit other than the thesis rig (``reproduce --params mine.toml``) the thesis's figures are of another digit:
inside :func:`thesis_comparisons` ``(False)`` every entry's ``thesis`` is :data:`NOT_APPLICABLE`, its ``rel_error``
None and its status ``new`` (:func:`not_applicable`), so no figure of that digit is compared with the thesis's by
accident.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import Literal

__all__ = ["Entry", "relative_error", "compare", "new", "NOT_APPLICABLE", "not_applicable", "thesis_comparisons"]

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


#: The ``thesis`` column of an entry computed for a digit other than the thesis rig.
NOT_APPLICABLE = "not applicable"

#: Whether entries are compared with the thesis's figures (the thesis rig) or not (any other digit); a stack.
_COMPARING = [True]


@contextlib.contextmanager
def thesis_comparisons(enabled: bool) -> Iterator[None]:
    """Inside the block, :func:`compare` compares with the thesis (``enabled``, the thesis rig) or marks the thesis
    column :data:`NOT_APPLICABLE` (another digit). Process-wide; the previous setting comes back on exit."""
    _COMPARING.append(bool(enabled))
    try:
        yield
    finally:
        _COMPARING.pop()


def not_applicable(entry: Entry) -> Entry:
    """``entry`` for a digit other than the thesis rig: its ``thesis`` column :data:`NOT_APPLICABLE`, no relative
    error, status ``new``; an entry the thesis has no figure for is returned as it is.

    Examples
    --------
    >>> once = not_applicable(Entry("x", "3.1", 2.0, 2.5, "", 0.25, "discrepancy", "why"))
    >>> once.thesis, not_applicable(once) == once   # marked once, however often it passes here
    ('not applicable', True)
    """
    if (entry.thesis is None and entry.status == "new") or entry.thesis == NOT_APPLICABLE:
        return entry
    note = f"thesis figure of the thesis rig, not applicable to this digit. {entry.note}".strip()
    return replace(entry, thesis=NOT_APPLICABLE, rel_error=None, status="new", note=note)


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
    if not _COMPARING[-1]:  # another digit: its figure stands alone, never against the thesis rig's
        return not_applicable(Entry(key, section, thesis_f, ours_f, unit, None, "discrepancy", note))
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

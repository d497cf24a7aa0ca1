"""The figure of a calibration (``flexdigit calibrate ... --plot``): the twin's residual on every target.

One bar per target: twin minus measured in units of the target's scale (1 % of a release test's wn or zeta, the
reading resolution of a deflection: what the fit weighs), each annotated with the residual in the target's own
unit; a target without a scale is shown relative to its measured value, in %.
"""

from __future__ import annotations

import numpy as np

from flexdigit._plot import new_figure

__all__ = ["residual_figure"]


def residual_figure(result, *, limit: float | None = None, title: str = ""):
    """The residual per target of a :class:`~flexdigit.calibrate.twin_fit.CalibrationResult` (its
    ``residual_rows``) as horizontal bars; ``limit`` (in scales) drawn as the refusal threshold. A ``Figure``."""
    rows = result.residual_rows()
    names, values, notes = [], [], []
    for r in rows:
        scale = r.get("scale")
        if scale:
            values.append(r["residual"] / scale)
            names.append(r["target"])
        else:
            values.append(100 * (r["relative"] or 0.0))
            names.append(f"{r['target']} (% of measured)")
        notes.append(f"{r['residual']:+.3g} {r['unit']}".rstrip())
    height = max(2.6, 0.32 * len(rows) + 1.4)
    fig, ax = new_figure(figsize=(8.0, height))
    y = np.arange(len(rows))
    ax.barh(y, values, color=["C3" if limit is not None and abs(v) > limit else "C0" for v in values])
    for yi, v, note in zip(y, values, notes, strict=True):
        ax.annotate(note, (v, yi), xytext=(4 if v >= 0 else -4, 0), textcoords="offset points",
                    ha="left" if v >= 0 else "right", va="center", fontsize=7)  # fmt: skip
    ax.set_yticks(y, names, fontsize=7)
    ax.invert_yaxis()
    ax.axvline(0.0, color="k", lw=0.5)
    if limit is not None:
        for side in (-limit, limit):
            ax.axvline(side, color="C3", ls=":", lw=0.8)
    ax.set_xlabel("residual, twin - measured (in scales: 1 % of wn or zeta, a reading resolution)")
    ax.margins(x=0.25)
    ax.set_title(title or "calibrated twin against its targets", fontsize=9)
    return fig

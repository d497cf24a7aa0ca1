"""The figure of a load estimator's predictions (``flexdigit train|predict ... --plot``): predicted vs actual.

Each reading's prediction against its true value, with the line of perfect prediction, in the target's unit:
the load's position in mm from the tip, its mass in g, the thesis's position number, or contact (thesis 6.6 and
7.3 judged the networks by corr2 and the spread about that line).
"""

from __future__ import annotations

import numpy as np

from flexdigit._plot import new_figure
from flexdigit.errors import ParameterError

__all__ = ["TARGET_UNITS", "target_unit", "prediction_figure"]

#: Per target: what it is, the unit it is shown in, and the factor from its SI value to that unit.
TARGET_UNITS: dict[str, tuple[str, str, float]] = {
    "position": ("load position from the tip", "mm", 1e3),
    "magnitude": ("load", "g", 1e3),
    "position_index": ("position number", "", 1.0),
    "contact": ("contact (1 = loaded)", "", 1.0),
}


def target_unit(target: str) -> tuple[str, str, float]:
    """``(what, unit, scale)`` of a target (``"position"`` -> ``("load position from the tip", "mm", 1e3)``)."""
    if target.replace("-", "_") not in TARGET_UNITS:
        raise ParameterError(
            f"The 'target' parameter of target_unit must be one of {', '.join(TARGET_UNITS)}. Got {target!r} instead."
        )
    return TARGET_UNITS[target.replace("-", "_")]


def prediction_figure(actual, predicted, target: str, title: str = ""):
    """Predicted against actual values (SI, as the estimators give them), shown in the target's unit; a
    matplotlib ``Figure`` with the readings and the line y = x.

    Examples
    --------
    >>> fig = prediction_figure([0.01, 0.05], [0.012, 0.049], "position")
    >>> fig.axes[0].get_xlabel()
    'actual load position from the tip (mm)'
    """
    what, unit, scale = target_unit(target)
    a = np.asarray(actual, float).ravel() * scale
    p = np.asarray(predicted, float).ravel() * scale
    label = f" ({unit})" if unit else ""
    fig, ax = new_figure(figsize=(5.5, 5.0))
    ax.plot(a, p, "o", ms=3, alpha=0.6, label="readings")
    finite = np.isfinite(np.concatenate([a, p]))
    both = np.concatenate([a, p])[finite]
    lo, hi = (float(both.min()), float(both.max())) if both.size else (0.0, 1.0)
    ax.plot([lo, hi], [lo, hi], color="k", lw=0.8, ls="--", label="perfect prediction")
    ax.set_xlabel(f"actual {what}{label}")
    ax.set_ylabel(f"predicted {what}{label}")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title, fontsize=9)
    return fig

"""Scores of a tactile estimator: the thesis's corr2 and percentage error, and what a user needs (mm, %, accuracy).

Examples
--------
>>> corr2([1, 2, 3], [1, 2, 3.5]) > 0.99
True
>>> float(rmse([0, 0], [3, 4]))
3.5355339059327378
"""

from __future__ import annotations

import numpy as np

from flexdigit._validation import check_array
from flexdigit.errors import ParameterError


def _pair(a, b, owner: str) -> tuple[np.ndarray, np.ndarray]:
    x = check_array(a, "a", owner)
    y = check_array(b, "b", owner)
    if x.shape != y.shape:
        raise ParameterError(f"{owner} needs two arrays of the same shape. Got {x.shape} and {y.shape}.")
    return x, y


def corr2(a, b) -> float:
    """MATLAB's ``corr2``: the correlation coefficient of two equal-size arrays (6.9, ref. [27]).

    ``sum((A - mean A)(B - mean B)) / sqrt(sum((A - mean A)^2) sum((B - mean B)^2))`` over every element.
    """
    x, y = _pair(a, b, "corr2")
    dx, dy = x - x.mean(), y - y.mean()
    denom = np.sqrt(np.sum(dx * dx) * np.sum(dy * dy))
    if denom == 0:
        return float("nan")
    return float(np.sum(dx * dy) / denom)


def percentage_error(predicted, actual) -> np.ndarray:
    """Per-sample ``100 |predicted - actual| / |actual|`` (figures 6.18, 7.9); NaN where ``actual`` is 0."""
    p, a = _pair(predicted, actual, "percentage_error")
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 100.0 * np.abs(p - a) / np.abs(a)
    out[a == 0] = np.nan
    return out


def rmse(predicted, actual) -> float:
    """Root-mean-square error, in the unit of the inputs."""
    p, a = _pair(predicted, actual, "rmse")
    return float(np.sqrt(np.mean((p - a) ** 2)))


def accuracy(predicted, actual) -> float:
    """Fraction of equal labels."""
    p, a = _pair(predicted, actual, "accuracy")
    return float(np.mean(p == a))


def relative_rmse(predicted, actual) -> float:
    """RMS of the relative error ``(predicted - actual) / actual`` (the magnitude criterion, "within 10 %")."""
    p, a = _pair(predicted, actual, "relative_rmse")
    if np.any(a == 0):
        raise ParameterError("relative_rmse needs non-zero actual values (use loaded samples only).")
    return float(np.sqrt(np.mean(((p - a) / a) ** 2)))

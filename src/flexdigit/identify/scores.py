"""Model validation: MATLAB's ``corr2`` (the thesis's accuracy figure, 3.1.2, 3.2.4), the NRMSE fit, and the
Ljung-Box test of residual whiteness.

The thesis validates each model by the correlation between the measured and the modelled response computed with
MATLAB's ``corr2`` (99.10 % for the digit, 96.81 % for the servo). ``corr2`` is a correlation coefficient, not an
accuracy: a model with the right shape and the wrong gain scores 1. :func:`nrmse_fit` is the figure MATLAB's
``compare`` and python-control users report, ``100 (1 - ||y - yhat|| / ||y - mean(y)||)``, which penalises both.

Examples
--------
>>> corr2([[1, 2], [3, 4]], [[2, 4], [6, 8.0]])
1.0
>>> nrmse_fit([1, 2, 3, 4], [1, 2, 3, 4])
100.0
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from flexdigit._validation import check_array, check_int

__all__ = ["corr2", "nrmse_fit", "LjungBox", "ljung_box"]


def corr2(a, b) -> float:
    """2-D correlation coefficient, exactly as MATLAB's ``corr2`` defines it.

    ``r = sum((A - mean(A)) (B - mean(B))) / sqrt(sum((A - mean(A))^2) sum((B - mean(B))^2))``, the sums and
    means running over all elements of the two same-size arrays (1-D arrays are one row).

    Parameters
    ----------
    a, b : array_like
        Same-shape arrays (1-D or 2-D), finite.

    Returns
    -------
    float
        The correlation coefficient in [-1, 1]; NaN when either array is constant (MATLAB returns NaN too).

    Examples
    --------
    >>> round(corr2([1, 2, 3], [1, 3, 2]), 6)
    0.5
    """
    x = check_array(a, "a", "corr2")
    y = check_array(b, "b", "corr2")
    if x.shape != y.shape or x.ndim > 2:
        raise ValueError(
            f"The 'a' and 'b' parameters of corr2 must be 1-D or 2-D arrays of the same shape. "
            f"Got shapes {x.shape} and {y.shape} instead."
        )
    da = x - x.mean()
    db = y - y.mean()
    den = np.sqrt(np.sum(da * da) * np.sum(db * db))
    if den == 0:
        return float("nan")
    return float(np.sum(da * db) / den)


def nrmse_fit(y, y_model) -> float:
    """Normalised-RMSE fit in percent, ``100 (1 - ||y - y_model|| / ||y - mean(y)||)`` (MATLAB ``compare``).

    100 is a perfect fit, 0 is no better than the mean, negative is worse than the mean.

    Examples
    --------
    >>> round(nrmse_fit([0, 1, 2, 3], [0, 1, 2, 4]), 2)
    55.28
    """
    y_ = check_array(y, "y", "nrmse_fit", ndim=1)
    m = check_array(y_model, "y_model", "nrmse_fit", ndim=1, shape=(len(y_),))
    den = np.linalg.norm(y_ - y_.mean())
    if den == 0:
        return float("nan")
    return float(100.0 * (1.0 - np.linalg.norm(y_ - m) / den))


@dataclass(frozen=True)
class LjungBox:
    """The Ljung-Box portmanteau test of ``lags`` autocorrelations: ``q`` and its chi-square ``p_value``."""

    q: float
    lags: int
    p_value: float


def ljung_box(x, lags: int, *, fitted_parameters: int = 0) -> LjungBox:
    """Ljung-Box test that ``x`` is white: ``Q = n (n + 2) sum_k r_k^2 / (n - k)``, ``k = 1..lags``.

    Under whiteness ``Q`` follows a chi-square distribution with ``lags - fitted_parameters`` degrees of freedom
    (Ljung and Box, Biometrika 1978); a small ``p_value`` says the residuals of a model still hold structure.
    Written out (five lines) rather than taken from statsmodels, which would be a dependency for this alone; it
    matches ``statsmodels.stats.diagnostic.acorr_ljungbox`` (same estimator of ``r_k``, mean removed, biased
    denominator).

    Parameters
    ----------
    x : array_like
        1-D series (e.g. model residuals), finite, longer than ``lags + 1``.
    lags : int
        Number of autocorrelations tested.
    fitted_parameters : int
        Degrees of freedom taken by a fitted model (ARMA orders); 0 for residuals of a deterministic fit.

    Examples
    --------
    >>> r = ljung_box(np.random.default_rng(0).normal(size=500), 10)
    >>> r.lags, r.p_value > 0.05                  # white noise: no evidence against whiteness
    (10, True)
    >>> ljung_box(np.sin(0.3 * np.arange(500)), 10).p_value < 1e-6
    True
    """
    v = check_array(x, "x", "ljung_box", ndim=1)
    h = check_int(lags, "lags", "ljung_box", low=1, high=max(1, v.size - 2))
    df = check_int(fitted_parameters, "fitted_parameters", "ljung_box", low=0, high=h - 1)
    d = v - v.mean()
    n = d.size
    den = float(np.dot(d, d))
    if den == 0.0:
        return LjungBox(0.0, h, 1.0)
    r = np.array([np.dot(d[: n - k], d[k:]) for k in range(1, h + 1)]) / den
    q = float(n * (n + 2) * np.sum(r**2 / (n - np.arange(1, h + 1))))
    return LjungBox(q, h, float(stats.chi2.sf(q, h - df)))

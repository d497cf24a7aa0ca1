"""Model validation: MATLAB's ``corr2`` (the thesis's accuracy figure, 3.1.2, 3.2.4) and the NRMSE fit.

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

import numpy as np

from flexdigit._validation import check_array


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

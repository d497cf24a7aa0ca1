"""corr2 and the NRMSE fit against hand-computed values (MATLAB's definitions)."""

import math

import numpy as np
import pytest

from flexdigit.identify.scores import corr2, nrmse_fit


def test_corr2_matches_matlab_definition_on_hand_computed_2d_example():
    # A = [1 2; 3 4], B = [2 1; 4 5]: mean(A) = 2.5, mean(B) = 3, sum(dA dB) = 1.5 + 1 + 0.5 + 3 = 6,
    # sum(dA^2) = 5, sum(dB^2) = 10, so corr2 = 6 / sqrt(50) (by hand, MATLAB corr2's formula)
    assert corr2([[1, 2], [3, 4]], [[2, 1], [4, 5]]) == pytest.approx(6 / math.sqrt(50), rel=1e-15)


def test_corr2_runs_over_all_elements_not_columns():
    a = np.array([[1.0, 5.0], [2.0, 9.0], [3.0, 4.0]])
    b = np.array([[2.0, 1.0], [3.0, 8.0], [7.0, 4.0]])
    # over all elements it is the Pearson coefficient of the flattened arrays (numpy corrcoef as the oracle)
    assert corr2(a, b) == pytest.approx(np.corrcoef(a.ravel(), b.ravel())[0, 1], rel=1e-12)
    # and not the mean of per-column correlations
    per_column = np.mean([np.corrcoef(a[:, k], b[:, k])[0, 1] for k in range(2)])
    assert abs(corr2(a, b) - per_column) > 0.1


def test_corr2_ignores_gain_and_offset_unlike_the_nrmse_fit():
    y = np.sin(np.linspace(0, 6, 200))
    assert corr2(y, 3 * y + 1) == pytest.approx(1.0, abs=1e-12)
    assert nrmse_fit(y, 3 * y + 1) < 0


def test_corr2_constant_is_nan_and_shapes_must_match():
    assert math.isnan(corr2([1, 1, 1], [1, 2, 3]))
    with pytest.raises(ValueError, match="same shape"):
        corr2([1, 2, 3], [1, 2])


def test_nrmse_fit_hand_computed():
    # y = [0 1 2 3], model [0 1 2 4]: ||y - yhat|| = 1, ||y - mean y|| = sqrt(5): 100 (1 - 1/sqrt(5))
    assert nrmse_fit([0, 1, 2, 3], [0, 1, 2, 4]) == pytest.approx(100 * (1 - 1 / math.sqrt(5)), rel=1e-12)
    assert nrmse_fit([0, 1, 2, 3], [1.5] * 4) == pytest.approx(0.0, abs=1e-12)

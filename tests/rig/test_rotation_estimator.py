"""The gauge -> beam-rotation map on synthetic sweeps with a known answer (fast; the twin runs are in
test_sim_control.py).

The synthetic sweep is what the twin's calibration sweep looks like: three gauges that all follow the one sweep
parameter, ``g = a + s theta + noise`` with the twin's sensitivities (about 5.1, 7.1, 5.2 mV/deg), 9 commands from
0 to 40 deg and 2 mV / sqrt(5) of noise per averaged reading. The closed-form oracle for the Gauss-Markov inverse of
that model is ``w = W s / (s' W s)``.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexdigit.errors import DataFileError, ParameterError
from flexdigit.rig.rotation import RotationEstimator

SENS_V_PER_DEG = np.array([5.1e-3, 7.1e-3, 5.2e-3])
OFFSET_V = np.array([-0.12, 0.60, 0.035])
ANGLES_DEG = np.linspace(0.0, 40.0, 9)
NOISE_V = 0.002 / np.sqrt(5)


def sweep(seed: int, noise_v=NOISE_V):
    rng = np.random.default_rng(seed)
    X = OFFSET_V + np.outer(ANGLES_DEG, SENS_V_PER_DEG) + rng.normal(0.0, 1.0, (ANGLES_DEG.size, 3)) * noise_v
    return X, ANGLES_DEG


def test_sensitivity_map_matches_the_gauss_markov_closed_form_and_ignores_the_seed():
    oracle = SENS_V_PER_DEG / (SENS_V_PER_DEG @ SENS_V_PER_DEG)  # [49.3, 68.6, 50.3] deg/V
    coefs = np.array([RotationEstimator().fit(*sweep(seed)).coef_ for seed in range(20)])
    # the slopes are fitted over a 40 deg span, so the noise moves them by ~0.3 %; allow 3 %
    np.testing.assert_allclose(coefs, np.broadcast_to(oracle, coefs.shape), rtol=0.03)
    est = RotationEstimator().fit(*sweep(0))
    clean = OFFSET_V + 17.0 * SENS_V_PER_DEG
    assert est.predict_one(clean) == pytest.approx(17.0, abs=0.2)


def test_least_squares_map_is_ill_posed_on_collinear_gauges():
    # why the default changed: the unconstrained fit inverts the noise in the two directions the sweep never moves,
    # so its weights swing by far more than the sensitivities do, and change sign (twin: 113/64/-6.5 deg/V)
    coefs = np.array([RotationEstimator(method="lstsq").fit(*sweep(seed)).coef_ for seed in range(20)])
    spread = np.ptp(coefs, axis=0) / np.abs(coefs.mean(axis=0))
    assert np.all(spread > 0.5)
    assert np.any(coefs < 0)


def test_noise_weights_favour_the_quiet_gauge():
    noise = np.array([0.001, 0.004, 0.004])
    est = RotationEstimator(noise_v=noise).fit(*sweep(3, noise_v=noise))
    weight = 1.0 / noise**2
    s = est.gauge_v_per_deg_
    np.testing.assert_allclose(est.coef_, weight * s / (s @ (weight * s)), rtol=1e-12)  # W s / (s' W s)
    assert est.coef_[0] > 4 * est.coef_[1]


def test_tare_moves_the_zero_only():
    est = RotationEstimator().fit(*sweep(1))
    rest = OFFSET_V + 0.5 * SENS_V_PER_DEG
    est.tare([rest, rest])
    assert est.predict_one(rest) == pytest.approx(0.0, abs=1e-12)
    step = OFFSET_V + 30.5 * SENS_V_PER_DEG
    assert est.predict_one(step) == pytest.approx(30.0, abs=0.2)


@pytest.mark.parametrize(
    ("kwargs", "data", "error", "match"),
    [
        ({"method": "pca"}, None, ParameterError, "'method' parameter of RotationEstimator"),
        ({"noise_v": [0.002, 0.0, 0.002]}, None, ParameterError, "'noise_v' parameter of RotationEstimator"),
        ({"noise_v": [0.002, 0.002]}, None, ParameterError, "'noise_v' parameter of RotationEstimator"),
        ({}, (np.zeros((9, 3)), np.full(9, 10.0)), DataFileError, "must vary across the sweep"),
        ({}, (np.ones((9, 3)), ANGLES_DEG), DataFileError, "did not change over the sweep"),
        ({}, (np.zeros((3, 3)), ANGLES_DEG[:3]), DataFileError, "n >= 4 angles"),
    ],
)
def test_bad_input_names_the_culprit(kwargs, data, error, match):
    X, y = data if data is not None else sweep(0)
    with pytest.raises(error, match=match):
        RotationEstimator(**kwargs).fit(X, y)

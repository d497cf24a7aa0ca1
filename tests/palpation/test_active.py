"""Active sensing (issue 13 item 4): readings at several commands under one hang, against chapter 7's settings.

The covariance model of a hang (white noise per reading, one friction draw shared across commands) is checked
against readings drawn through the twin's own static path (``static_gauges_v`` with shared ``friction_draws``);
the Bayes limits against the single-reading limit of the same settings, computed by the existing
``protocol_limits`` (chapter 7's 22.5 mm is that figure over the test split's identifiable readings).
"""

import numpy as np
import pytest

from flexdigit.palpation.active import HangInversion, HangPosterior, simulate_hangs
from flexdigit.tactile.bounds import TwinGaugeModel, active_limits, hang_readings_model, protocol_limits

COV_REL = 0.1
MODEL = TwinGaugeModel()
L = 0.27
COMMANDS = [0, 20, 40]
# table 7.1: 25 and 37.5 g, 0..18 cm from the tip in 2 cm steps
A, M = (g.ravel() for g in np.meshgrid(L - np.arange(0, 0.181, 0.02), [0.025, 0.0375], indexing="ij"))


def test_hang_covariance_matches_readings_drawn_by_the_twin():
    mean, chol = hang_readings_model(MODEL, [0.2], [0.0375], COMMANDS)
    v = simulate_hangs(MODEL, [0.2], [0.0375], COMMANDS, repetitions=3000, seed=3)
    cov = chol[0] @ chol[0].T
    assert np.all(np.abs(v.mean(axis=0) - mean[0]) < 4 * np.sqrt(np.diag(cov) / len(v)) + 1e-4)  # 4 SE, an LSB
    emp = np.cov(v.T)
    # the friction's cross-command covariance of each gauge (the structure the protocol exploits), and variances
    for g in range(3):
        rows = np.arange(3) * 3 + g
        np.testing.assert_allclose(emp[np.ix_(rows, rows)], cov[np.ix_(rows, rows)], rtol=COV_REL, atol=2e-7)


def test_reading_at_three_commands_beats_the_single_reading_limit():
    lim = active_limits(MODEL, A, M, COMMANDS, samples=2000, seed=0)
    single = protocol_limits(MODEL, np.repeat(A, 3), np.repeat(M, 3), np.tile(COMMANDS, A.size), samples=2000)
    # the generic Gaussian limit reproduces protocol_limits' single-reading figure on the same settings
    assert lim["single_position_rmse_m"] == pytest.approx(np.sqrt(np.nanmean(single.position_mse_m2)), rel=0.05)
    assert lim["position_rmse_m"] < 0.35 * lim["single_position_rmse_m"]  # measured: 5.7 mm against 23.5 mm
    assert lim["magnitude_rel_rmse"] < 0.6 * lim["single_magnitude_rel_rmse"]  # 5.8 % against 12.4 %
    # the Bayes estimator on readings the twin draws reaches the limit (it is the estimator the limit scores)
    posterior = HangPosterior(MODEL, COMMANDS, A, M).fit()
    v = simulate_hangs(MODEL, A, M, COMMANDS, repetitions=40, seed=8)
    est = posterior.predict(v)
    rmse = np.sqrt(np.mean((est[:, 0] - np.repeat(L - A, 40)) ** 2))
    assert rmse == pytest.approx(lim["position_rmse_m"], rel=0.2)


def test_hang_inversion_needs_no_prior_and_still_beats_one_reading():
    inversion = HangInversion(MODEL, COMMANDS, position_step_m=2e-3, mass_steps=31).fit()
    v = simulate_hangs(MODEL, A, M, COMMANDS, repetitions=10, seed=2)
    est = inversion.predict(v)
    rmse = np.sqrt(np.mean((est[:, 0] - np.repeat(L - A, 10)) ** 2))
    assert rmse < 0.0225  # chapter 7's single-reading Bayes limit (docs/guide/tactile.md), which knows the protocol

"""Fit quality: the Ljung-Box test against statsmodels, and the problems a fit reveals, on known answers."""

import numpy as np
import pytest

from flexdigit.identify.quality import assess
from flexdigit.identify.scores import ljung_box

from .records import step_shape


def _ar1(n, phi, seed):
    e = np.random.default_rng(seed).normal(size=n)
    x = np.zeros(n)
    for k in range(1, n):
        x[k] = phi * x[k - 1] + e[k]
    return x


def test_ljung_box_matches_statsmodels():
    # reference: statsmodels 0.14.4 acorr_ljungbox(x, lags=[12]) on these seeded series (run once, outside the suite)
    white = ljung_box(np.random.default_rng(7).normal(size=300), 12)
    assert white.q == pytest.approx(10.75956333539728, rel=1e-12)
    assert white.p_value == pytest.approx(0.5496288403855989, rel=1e-10)
    ar = ljung_box(_ar1(300, 0.3, 8), 12)
    assert ar.q == pytest.approx(39.294048478325394, rel=1e-12)
    assert ar.p_value == pytest.approx(9.411410216910204e-05, rel=1e-8)


def test_ljung_box_p_values_are_uniform_on_white_noise():
    # a test at level 0.05 rejects about 5 % of white series: 200 seeded series, binomial 98 % band 4-17
    p = np.array([ljung_box(np.random.default_rng(s).normal(size=400), 10).p_value for s in range(200)])
    assert 4 <= np.sum(p < 0.05) <= 17


def _step_record(seed, noise=0.01, t0=0.2):
    t = np.arange(0, 2, 0.002)
    model = 1.0 + 0.4 * step_shape(t - t0, 20.53, 0.5629)
    return t, model, model + np.random.default_rng(seed).normal(0, noise * 0.4, t.size)


def test_the_true_model_leaves_nothing_unexplained():
    t, model, y = _step_record(0)
    q = assess(t, y, model, kind="step", wn_rad_s=20.53, zeta=0.5629, amplitude=0.4, t0_s=0.2, noise_std=0.004)
    assert q.problems == ()
    assert q.warnings == ()
    assert q.misfit_percent < 2
    assert q.fit_percent > 95
    assert q.residual_std == pytest.approx(0.004, rel=0.1)


def test_a_wrong_model_is_a_poor_fit():
    t, _, y = _step_record(1)
    wrong = 1.0 + 0.4 * step_shape(t - 0.2, 14.0, 0.5629)  # wn 32 % low
    q = assess(t, y, wrong, kind="step", wn_rad_s=14.0, zeta=0.5629, amplitude=0.4, t0_s=0.2, noise_std=0.004)
    assert [p.code for p in q.problems] == ["poor-fit"]
    assert q.misfit_percent > 10
    assert any("residuals not white" in w for w in q.warnings)
    # the thesis method's own errors are a warning, not a refusal of the record
    q = assess(t, y, wrong, kind="step", wn_rad_s=14.0, zeta=0.5629, amplitude=0.4, t0_s=0.2, method="thesis")
    assert q.problems == ()
    assert any("deviates from the thesis method's model" in w for w in q.warnings)


def test_a_second_step_after_the_first_settled_is_named():
    t, model, y = _step_record(2)
    y = y + 0.3 * step_shape(t - 1.2, 20.53, 0.5629)
    q = assess(t, y, model, kind="step", wn_rad_s=20.53, zeta=0.5629, amplitude=0.4, t0_s=0.2, noise_std=0.004)
    assert q.problems[0].code == "two-steps"
    assert "moves again from about 1.2" in q.problems[0].message


def test_clipping_is_saturation():
    t, model, y = _step_record(3, noise=0.005)
    rail = 1.0 + 0.4 * 1.08  # below the 12 % overshoot
    q = assess(t, np.minimum(y, rail), model, kind="step", wn_rad_s=20.53, zeta=0.5629, amplitude=0.4, t0_s=0.2,
               noise_std=0.002)  # fmt: skip
    assert q.problems[0].code == "saturated"
    assert f"stuck at {rail:.6g}" in q.problems[0].message


def test_a_clipped_final_level_is_saturation_even_where_the_model_follows_it():
    # an overdamped step into the rail: the model can settle on the rail too, but no noisy record holds one value
    t = np.arange(0, 2, 0.002)
    model = 1.0 + 0.4 * step_shape(t - 0.2, 20.0, 1.2)
    y = np.minimum(model + np.random.default_rng(4).normal(0, 0.004, t.size), 1.35)
    fitted = np.minimum(model, 1.35)
    q = assess(t, y, fitted, kind="step", wn_rad_s=20.0, zeta=1.2, amplitude=0.35, t0_s=0.2, noise_std=0.004)
    assert q.problems[0].code == "saturated"
    assert "times as many as any other value" in q.problems[0].message


def test_a_quantised_plateau_is_not_saturation():
    # a 12-bit ADC with noise below one step: the plateau shares its samples with the neighbouring levels
    t = np.arange(0, 2, 0.002)
    model = 1.0 + 0.4 * step_shape(t - 0.2, 20.0, 1.2)
    lsb = 10.0 / 4096
    y = np.round((model + np.random.default_rng(5).normal(0, 0.8 * lsb, t.size)) / lsb) * lsb
    q = assess(t, y, model, kind="step", wn_rad_s=20.0, zeta=1.2, amplitude=0.4, t0_s=0.2, noise_std=0.8 * lsb)
    assert [p.code for p in q.problems] == []
    # and quantised coarser than its noise (0.2 LSB): the plateau is one value, but no noise is seen either
    y = np.round((model + np.random.default_rng(6).normal(0, 0.2 * lsb, t.size)) / lsb) * lsb
    q = assess(t, y, model, kind="step", wn_rad_s=20.0, zeta=1.2, amplitude=0.4, t0_s=0.2, noise_std=0.0)
    assert [p.code for p in q.problems] == []

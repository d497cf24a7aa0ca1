"""Contact estimation from the gauges (issue 13 item 2) against known answers and closed forms.

The readings come from the twin's statics at a finer resolution (9 cells per section) than the estimator's model
(3), so the estimator never inverts its own forward model exactly. Tolerances are named here.
"""

import math

import numpy as np
import pytest
from scipy.stats import norm

from flexdigit.errors import ParameterError
from flexdigit.palpation.contact_estimation import ContactEstimator, ContactGaugeModel
from flexdigit.tactile.bounds import CONTACT_ZONES, contact_bounds, fisher_sd, gaussian_bayes_limits, line_bounds

NOISE_FREE_POSITION_M = 1.5e-3  # a 3-cell model reading 9-cell statics (model error ~0.4 %, tests/twin)
NOISE_FREE_FORCE_REL = 0.02
SD_REL = 0.2  # the Fisher standard deviation against the spread of 400 seeded estimates
BAYES_ABS = 0.01

MODEL = ContactGaugeModel()
TRUTH = ContactGaugeModel(cells_per_section=9)


@pytest.fixture(scope="module")
def estimator():
    return ContactEstimator(MODEL, commands=[20]).fit()


@pytest.mark.parametrize("position, force", [(0.15, -0.2), (0.2, -0.1), (0.235, -0.3)])
def test_point_contact_is_found_where_the_gauges_see_it(estimator, position, force):
    e = estimator.predict(TRUTH.point_v([position], [force], 20), 20)
    assert e.contact[0]
    assert e.point_position_m[0] == pytest.approx(position, abs=NOISE_FREE_POSITION_M)
    assert e.point_force_n[0] == pytest.approx(force, rel=NOISE_FREE_FORCE_REL)


def test_a_line_load_over_a_gauge_is_told_from_a_point_with_25_readings():
    # 0.5 N over 120..200 mm covers gauge 2 (135 mm): its moment there differs from the point's by ~F w / 8, worth
    # chi^2 ~ 3.6 against the best point in one reading at 2 mV and 25 x that in the mean of 25
    line = TRUTH.line_v([0.16], [0.08], [-0.5], 20)
    one = ContactEstimator(MODEL, commands=[20]).fit().predict(line, 20)
    many = ContactEstimator(MODEL, commands=[20], n_readings=25).fit().predict(line, 20)
    assert abs(one.log_odds_distributed[0]) < 3  # one reading cannot tell
    assert many.kind[0] == "distributed"
    assert many.log_odds_distributed[0] > 5
    assert many.position_m[0] == pytest.approx(0.16, abs=5e-3)
    assert many.extent_m[0] == pytest.approx(0.08, abs=0.02)
    assert many.force_n[0] == pytest.approx(-0.5, rel=0.03)


def test_nothing_touching_is_no_contact_at_the_threshold_rate(estimator):
    rng = np.random.default_rng(5)
    v = MODEL.free_v([20])[0] + MODEL.noise_v * rng.standard_normal((1000, 3))
    e = estimator.predict(v, 20)
    # chi^2 (2 dof) beyond 13.8 happens 0.1 % of the time; 1000 readings: a handful at most
    assert np.mean(e.contact) < 0.006
    assert np.all(e.force_n[~e.contact] == 0.0)


def test_standard_deviations_match_the_spread_of_estimates(estimator):
    rng = np.random.default_rng(11)
    clean = TRUTH.point_v([0.2], [-0.2], 20)
    v = clean + MODEL.noise_v * rng.standard_normal((400, 3))
    e = ContactEstimator(MODEL, commands=[20], classify=False).fit().predict(v, 20)
    assert np.std(e.point_position_m) == pytest.approx(np.median(e.position_sd_m), rel=SD_REL)
    assert np.std(e.point_force_n) == pytest.approx(np.median(e.force_sd_n), rel=SD_REL)


def test_zones_follow_the_statics_of_a_pinned_tip():
    b = contact_bounds(MODEL, [0.02, 0.10, 0.20, 0.268], -0.1, 20)
    # before gauge 1 nothing bends; between gauges 1 and 2 only F (s - x1) is seen; the rigid tip support: the
    # cable's pinned tip angle absorbs the load's moment, only the force is seen
    assert list(b.zone) == [CONTACT_ZONES[0], CONTACT_ZONES[1], CONTACT_ZONES[3], CONTACT_ZONES[2]]
    assert math.isfinite(b.force_crlb_n[3])
    assert b.force_crlb_n[3] < 0.01
    assert b.position_crlb_m[3] > 0.027


def test_averaging_readings_shrinks_the_bound_as_one_over_sqrt_n():
    one = contact_bounds(MODEL, [0.2], -0.1, 20)
    many = contact_bounds(MODEL, [0.2], -0.1, 20, n_readings=25)
    assert many.position_crlb_m[0] == pytest.approx(one.position_crlb_m[0] / 5, rel=1e-6)


def test_line_load_bounds_shrink_as_one_over_sqrt_n():
    one = line_bounds(MODEL, [0.17], [0.04], [-0.5], 20)
    many = line_bounds(MODEL, [0.17], [0.04], [-0.5], 20, n_readings=25)
    for key in ("centre_m", "extent_m", "total_n"):
        assert np.isfinite(one[key][0])
        assert many[key][0] == pytest.approx(one[key][0] / 5, rel=1e-6)
    # 150..190 mm covers no gauge: the moments at the gauges are a point's at 170 mm, and only the taut cable's
    # tension (the pinned tip angle integrates the moment over the strip: a difference of F w^2 / 24) sees the
    # extent, far less sharply than the total
    assert many["extent_m"][0] / 0.04 > 10 * many["total_n"][0] / 0.5


def test_fisher_sd_against_the_closed_form():
    # gauges = J theta with J = [[1, 0], [1, 1], [0, 2]], sigma 0.1: F = J'J / 0.01, by hand inv([[2, 1], [1, 5]])
    jac = np.array([[[1.0, 0.0], [1.0, 1.0], [0.0, 2.0]]])
    sd = fisher_sd(jac, [0.1, 0.1, 0.1])[0]
    inv = np.array([[5.0, -1.0], [-1.0, 2.0]]) / 9.0 * 0.01
    np.testing.assert_allclose(sd, np.sqrt(np.diag(inv)), rtol=1e-12)
    assert np.all(np.isinf(fisher_sd(np.array([[[1.0, 2.0], [2.0, 4.0], [0.0, 0.0]]]), 0.1)[0]))


def test_bayes_limit_of_two_gaussian_settings_is_the_closed_form():
    # two settings d apart in one reading coordinate, equal priors: the Bayes error is Phi(-d / 2 sigma)
    d, sigma = 1.0, 0.4
    out = gaussian_bayes_limits([[0.0], [d]], [[sigma], [sigma]], labels=["a", "b"], samples=40000, seed=1)
    assert out["label_error"] == pytest.approx(norm.cdf(-d / (2 * sigma)), abs=BAYES_ABS)
    # correlated noise: the Cholesky factor is used as such (a reading along the correlated direction)
    chol = np.linalg.cholesky(np.array([[1.0, 0.9], [0.9, 1.0]]) * sigma**2)
    two = gaussian_bayes_limits([[0.0, 0.0], [d, -d]], np.stack([chol, chol]), labels=[0, 1], samples=40000)
    mahalanobis = math.sqrt(np.array([d, -d]) @ np.linalg.solve(chol @ chol.T, np.array([d, -d])))
    assert two["label_error"] == pytest.approx(norm.cdf(-mahalanobis / 2), abs=BAYES_ABS)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: ContactEstimator(MODEL, side="left").fit(), "'side'"),
        (lambda: ContactEstimator(MODEL, region_m=(0.2, 0.2005)).fit(), "'region_m'"),
        (lambda: ContactEstimator(MODEL, n_readings=0).fit(), "'n_readings'"),
        (lambda: ContactEstimator(MODEL).fit().predict(np.zeros((2, 5))), "3 gauge columns"),
        (lambda: MODEL.point_v([0.3], [-0.1], 20), "'position_m'"),
        (lambda: MODEL.point_v([0.2], [-0.1], 300), "'command'"),
        (lambda: MODEL.line_v([0.26], [0.04], [-0.1], 20), "must lie on the digit"),
    ],
)
def test_bad_inputs_are_named(make, message):
    with pytest.raises(ParameterError, match=message):
        make()


def test_the_estimators_keep_scikit_learns_contract():
    # issue 15's Estimator: __init__ stores, fit validates, predict before fit is NotFittedError, clone works
    from sklearn.base import clone

    from flexdigit._estimator import NotFittedError
    from flexdigit.palpation.active import HangInversion, HangPosterior

    est = ContactEstimator(MODEL, n_readings=4, classify=False)
    assert clone(est).get_params()["n_readings"] == 4
    for unfitted in (est, HangInversion(object(), [0]), HangPosterior(object(), [0], [0.1], [0.02])):
        with pytest.raises(NotFittedError, match="not fitted"):
            unfitted.predict(np.zeros((1, 4)))
    with pytest.raises(ParameterError, match="^The 'model' parameter of HangInversion must be an object with"):
        HangInversion(object(), [20]).fit()


def test_contact_studys_interval_has_the_gaussian_width():
    # errors of 25-reading estimates are near Gaussian: the pooled RMS's relative standard error is 1 / sqrt(2 n)
    # over n estimates, so the 95 % interval spans 2 x 1.96 / sqrt(2 n) of the ratio (seeded bootstrap: +-25 %)
    from flexdigit.palpation.palpation_studies import contact_study

    c = contact_study(positions_m=[0.16, 0.17, 0.18, 0.19], forces_n=(0.2,), n_readings=25, repetitions=100, seed=1)
    lo, hi = c["position_ratio_ci95"]
    n = c["zone_counts"]["identifiable"] * 100
    assert n == 400
    assert lo < c["position_ratio"] < hi
    assert (hi - lo) / c["position_ratio"] == pytest.approx(2 * 1.96 / math.sqrt(2 * n), rel=0.25)

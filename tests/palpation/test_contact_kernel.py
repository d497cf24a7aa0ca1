"""The contact estimator's compiled path (issue 13: an estimate within 1 ms) against plain numpy and the model.

The compiled kernels (:mod:`flexdigit.palpation._contact_kernel`) replaced numpy code that did the same arithmetic;
here a plain numpy rewrite of that arithmetic (written out term by term, not Horner's scheme) is the reference,
and the numbers must agree to rounding (``KERNEL_REL``). The line load's standard deviations now come from
derivative tables instead of six static solves per reading: they are checked against
:func:`flexdigit.tactile.bounds.line_bounds` (central differences of the model's statics, the old path) within
``LINE_SD_REL`` wherever the gauges see the load's extent.
"""

import numpy as np
import pytest

from flexdigit.palpation import _contact_kernel
from flexdigit.palpation.contact_estimation import ContactEstimator, ContactGaugeModel, _log_evidence
from flexdigit.tactile.bounds import contact_bounds, fisher_sd, line_bounds

KERNEL_REL = 1e-9  # same arithmetic in another order: rounding only
LINE_SD_REL = 0.01  # table polynomials (within 6 uV of the statics) against fresh central differences
POINT_SD_REL = 0.05  # the table's slope between 1 mm grid entries against point_jacobian's 0.2 mm differences
SEEN_EXTENT_SD_M = 1.0  # beyond this the extent is not seen: the Fisher matrix is at fisher_sd's conditioning limit

MODEL = ContactGaugeModel()


@pytest.fixture(scope="module")
def estimator():
    return ContactEstimator(MODEL, commands=[20]).fit()


@pytest.fixture(scope="module")
def readings():
    rng = np.random.default_rng(11)
    n = 60
    s, f = rng.uniform(0.05, 0.27, n), -rng.uniform(0.03, 0.5, n)
    points = MODEL.point_v(s, f, 20)
    c, w = rng.uniform(0.08, 0.2, n), rng.uniform(0.03, 0.12, n)
    lines = MODEL.line_v(c, w, f, 20)
    return np.vstack([points, lines]) + MODEL.noise_v * rng.standard_normal((2 * n, 3))


def _poly(coef, f):
    """sum_k coef_k f^k (k = 1..K) and its slope, term by term: coef (K, G, 3), f (B, G) -> (B, G, 3) each."""
    x = f[..., None]
    value = sum(coef[k] * x ** (k + 1) for k in range(coef.shape[0]))
    slope = sum((k + 1) * coef[k] * x**k for k in range(coef.shape[0]))
    return value, slope


def _reference_profile(est, r, coef, half):
    w, sign, lim = est.weight_, est.sign_, est.max_force_n
    a1 = coef[0]
    f = (r * w) @ a1.T / np.sum(a1 * w * a1, axis=1)
    clip = lambda f: np.clip(f * sign, 0.0, lim) * sign  # noqa: E731

    def newton(f, mask):
        for _ in range(2):
            f = np.where(mask, clip(f), f)
            value, slope = _poly(coef, f)
            res = r[:, None, :] - value
            step = -np.sum(w * res * slope, axis=2) / np.sum(w * slope**2, axis=2)
            f = np.where(mask, f - step, f)
        return clip(f)

    every = np.ones(f.shape, dtype=bool)
    if half < 0:
        f = newton(f, every)
    else:
        f = clip(f)
        value, _ = _poly(coef, f)
        best = np.argmin(np.sum(w * (r[:, None, :] - value) ** 2, axis=2), axis=1)
        centre = np.clip(best, half, coef.shape[1] - 1 - half)
        window = np.abs(np.arange(coef.shape[1])[None, :] - centre[:, None]) <= half
        f = newton(f, window)
    value, slope = _poly(coef, f)
    return f, np.sum(w * (r[:, None, :] - value) ** 2, axis=2), np.sum(w * slope**2, axis=2)


@pytest.mark.parametrize("table, half", [("point", -1), ("point", 3), ("line", -1)])
def test_the_compiled_profile_is_the_numpy_arithmetic(estimator, readings, table, half):
    t = estimator.tables_[20]
    r = readings - t["g0"]
    got = estimator._profile(r, t[table], half=half)
    want = _reference_profile(estimator, r, t[table], half)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_allclose(g, w, rtol=KERNEL_REL, atol=1e-12)


def test_refinement_and_evidence_are_the_numpy_arithmetic(estimator, readings):
    t = estimator.tables_[20]
    force, cost, curv = estimator._profile(readings - t["g0"], t["point"])
    grid = estimator.s_grid_
    pos, f, c = estimator._refine(force, cost, grid)
    i = np.argmin(cost, axis=1)
    b = np.arange(i.size)
    edge = (i == 0) | (i == grid.size - 1)  # the digit's ends: the grid entry itself (copied, so exactly)
    assert 0 < edge.sum() < i.size / 2
    np.testing.assert_array_equal(pos[edge], grid[i[edge]])
    np.testing.assert_array_equal(f[edge], force[b[edge], i[edge]])
    i, b = i[~edge], b[~edge]  # inside: the parabola through the best and its neighbours
    c0, c1, c2 = cost[b, i - 1], cost[b, i], cost[b, i + 1]
    shift = np.clip(0.5 * (c0 - c2) / (c0 - 2 * c1 + c2), -1, 1)
    side = np.where(shift >= 0, force[b, i + 1], force[b, i - 1])
    np.testing.assert_allclose(pos[b], grid[i] + shift * (grid[1] - grid[0]), rtol=KERNEL_REL)
    np.testing.assert_allclose(f[b], force[b, i] + np.abs(shift) * (side - force[b, i]), rtol=KERNEL_REL)
    np.testing.assert_allclose(c[b], c1 - 0.25 * (c0 - c2) * shift, rtol=KERNEL_REL)
    terms = -0.5 * cost + 0.5 * np.log(2 * np.pi / curv)
    want = np.log(np.mean(np.exp(terms - terms.max(axis=1, keepdims=True)), axis=1)) + terms.max(axis=1)
    np.testing.assert_allclose(_log_evidence(cost, curv), want, rtol=KERNEL_REL)


def test_the_compiled_fisher_inverse_is_numpys():
    rng = np.random.default_rng(2)
    jac = rng.standard_normal((50, 3, 3))
    jac[:5, :, 2] = jac[:5, :, 0] * 3.0 + 1e-12 * rng.standard_normal((5, 3))  # singular: every sd inf
    jac[5:8, :, 1] = 0.0  # a parameter the gauges do not reach
    sigma = np.array([0.002, 0.003, 0.0025])
    got = np.empty((50, 3))
    _contact_kernel.fisher_sd(jac, 1.0 / sigma**2, got)
    want = fisher_sd(jac, sigma)
    assert np.all(np.isinf(got[:8]))
    assert np.all(np.isinf(want[:8]))
    np.testing.assert_allclose(got[8:], want[8:], rtol=KERNEL_REL)


def test_point_standard_deviations_match_the_models_bounds(estimator):
    # the estimator's sds at the truth are the Cramer-Rao bounds, from the model by finite differences
    s = np.array([0.15, 0.18, 0.2, 0.21, 0.24, 0.25])
    f = np.array([-0.1, -0.2, -0.1, -0.3, -0.2, -0.1])
    sd = estimator._point_sd(s, f, estimator.tables_[20])
    bound = contact_bounds(MODEL, s, f, 20)
    np.testing.assert_allclose(sd[:, 0], bound.position_crlb_m, rtol=POINT_SD_REL)
    np.testing.assert_allclose(sd[:, 1], bound.force_crlb_n, rtol=POINT_SD_REL)


def test_line_standard_deviations_from_the_tables_match_the_statics(estimator, readings):
    e = estimator.predict(readings, 20)
    line = e.kind == "distributed"
    assert line.sum() >= 20
    old = line_bounds(MODEL, e.line_centre_m[line], e.line_extent_m[line], e.line_total_n[line], 20)
    seen = old["extent_m"] < SEEN_EXTENT_SD_M
    assert seen.sum() >= 10
    for key, new in (("centre_m", e.position_sd_m), ("extent_m", e.extent_sd_m), ("total_n", e.force_sd_n)):
        np.testing.assert_allclose(new[line][seen], old[key][seen], rtol=LINE_SD_REL)
    # where the extent is not seen, neither path claims it is
    assert np.all(~(e.extent_sd_m[line][~seen] < SEEN_EXTENT_SD_M))


def test_one_reading_is_estimated_as_in_a_batch(estimator, readings):
    # the latency path (one row) and a batch give the same numbers (a point and a line load): exactly, as the
    # compiled kernel computes each row on its own with no BLAS call, so the batch size is the only change
    batch = estimator.predict(readings, 20).as_dict()
    for i in (0, 70):
        one = estimator.predict(readings[i : i + 1], 20).as_dict()
        for key, value in one.items():
            np.testing.assert_array_equal(np.asarray(value), np.asarray(batch[key][i : i + 1]), err_msg=key)

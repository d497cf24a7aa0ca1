"""Least-squares, ARX and linear fits against known systems (issue 4: lsq within 2 % on noisy records)."""

import math

import control
import numpy as np
import pytest

from flexdigit.errors import DataFileError
from flexdigit.identify.fit import SecondOrderFit, fit_arx, fit_linear, second_order_response
from flexdigit.identify.identification import identify
from flexdigit.identify.timeseries import TimeSeries
from flexdigit.reference import thesis_value
from oracles import DIGIT, SERVO, release_record, step_record

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)

SEEDS = range(5)


@pytest.mark.parametrize("seed", SEEDS)
def test_lsq_recovers_digit_from_noisy_release_within_2_percent(seed):
    # noise: 2 % of the initial deflection, white; truth: the digit of 3.1.2
    t, y = release_record(seed, noise=0.02)
    r = identify(TimeSeries.from_arrays(t, y), "release", method="lsq")
    assert r.wn_rad_s == pytest.approx(DIGIT["wn_rad_s"], rel=0.02)
    assert r.zeta == pytest.approx(DIGIT["zeta"], rel=0.02)
    assert r.t0_s == pytest.approx(0.5, abs=0.01)
    assert r.corr2 > 0.99


@pytest.mark.parametrize("seed", SEEDS)
def test_lsq_recovers_servo_from_noisy_step_within_2_percent(seed):
    # noise: 2 % of the step; truth: MT(s) of 3.2.4
    t, y = step_record(seed, noise=0.02)
    r = identify(TimeSeries.from_arrays(t, y), "step", method="lsq", t0_s=0.2)
    assert r.wn_rad_s == pytest.approx(SERVO["wn_rad_s"], rel=0.02)
    assert r.zeta == pytest.approx(SERVO["zeta"], rel=0.02)


def test_thesis_method_on_the_same_noisy_releases_misses_by_more_than_2_percent():
    # issue 4: "report the thesis method's error on the same data next to it". Same 5 records as the lsq test
    # above (2 % white noise, the digit of 3.1.2). Measured: thesis wn -1.0, +1.6, +7.2, -1.7, +3.9 %; zeta -1.1,
    # +1.3, -3.6, +5.7, -1.1 %; lsq on the same records at most 0.03 % in wn and 0.8 % in zeta. The thesis's
    # errors are one undershoot and one settling instant read through the noise, plus the +3 % bias of 4/(zeta Ts).
    thesis_err, lsq_err = [], []
    for seed in SEEDS:
        series = TimeSeries.from_arrays(*release_record(seed, noise=0.02))
        for method, out in (("thesis", thesis_err), ("lsq", lsq_err)):
            r = identify(series, "release", method=method)
            out.append((r.wn_rad_s / DIGIT["wn_rad_s"] - 1, r.zeta / DIGIT["zeta"] - 1))
    thesis_err, lsq_err = np.abs(thesis_err), np.abs(lsq_err)
    assert thesis_err[:, 0].max() == pytest.approx(0.072, abs=0.002)  # worst wn: +7.2 % (seed 2)
    assert thesis_err[:, 1].max() == pytest.approx(0.057, abs=0.002)  # worst zeta: +5.7 % (seed 3)
    assert np.mean(thesis_err[:, 0]) > 0.02  # mean |error| 3.1 % in wn: outside issue 4's 2 %
    assert lsq_err.max() < 0.01
    assert np.all(lsq_err < thesis_err)  # on every record, both parameters


def test_release_that_does_not_oscillate_needs_allow_overdamped():
    # issue 4's bad-file case "no overshoot in a release test", for the API: every method refuses by default
    t = np.arange(0, 3, 0.002)
    y = second_order_response(t, "release", 10.0, 1.5, 0.0, 1.0, 0.2)
    y = y + np.random.default_rng(0).normal(0, 0.005, t.size)
    series = TimeSeries.from_arrays(t, y, channel="sg1", source="rec.csv")
    for method in ("lsq", "arx", "thesis"):
        with pytest.raises(DataFileError, match="rec.csv:sg1: no undershoot .* expected an oscillating decay"):
            identify(series, "release", method=method)
    r = identify(series, "release", method="lsq", allow_overdamped=True)
    assert r.features is None
    assert r.wn_rad_s == pytest.approx(10.0, rel=0.05)
    assert r.zeta == pytest.approx(1.5, rel=0.05)


def test_thesis_method_on_the_same_records_is_biased_high_in_wn():
    # the thesis's wn = 4/(zeta Ts) on the same noisy steps: the exact-Ts bias alone is +21 % at zeta 0.5629
    errors = []
    for seed in SEEDS:
        t, y = step_record(seed, noise=0.02)
        r = identify(TimeSeries.from_arrays(t, y), "step", method="thesis", t0_s=0.2)
        errors.append(r.wn_rad_s / SERVO["wn_rad_s"] - 1)
    assert 0.1 < np.mean(errors) < 0.35


def test_confidence_intervals_cover_the_truth_at_the_stated_rate():
    # 95 % intervals from the Jacobian: over 20 noisy steps, the truth falls outside rarely (binomial: P(>4) < 2 %)
    misses = 0
    for seed in range(20):
        t, y = step_record(100 + seed, noise=0.03)
        f = SecondOrderFit(kind="step", t0_s=0.2).fit(t, y)
        for name in ("wn_rad_s", "zeta"):
            e = f.estimates_[name]
            misses += not (e.ci_low <= SERVO[name] <= e.ci_high)
    assert misses <= 4


def test_fit_with_delay_finds_a_dead_time():
    t = np.arange(0, 2, 0.002)
    step = control.step_response(control.tf([421.5], [1, 23.11, 421.5]), t).outputs  # MT(s) of 3.2.4
    y = np.interp(t - 0.05, t, step, left=0.0)  # the step response delayed by 50 ms
    f = SecondOrderFit(kind="step", fit_t0=True, t0_s=0.0).fit(t, y)
    assert f.t0_ == pytest.approx(0.05, abs=2e-3)
    assert f.wn_ == pytest.approx(20.53, rel=0.01)


def test_arx_recovers_zoh_discretisation_of_servo_model():
    # oracle: python-control's zero-order-hold discretisation of MT(s); ARX(2, 2) on noise-free data is exact
    dt = 0.01
    sysd = control.c2d(control.tf([421.5], [1, 23.11, 421.5]), dt, "zoh")
    k = np.arange(300)
    u = np.where(k >= 10, 51.0, 0.0)
    y = control.forced_response(sysd, k * dt, u).outputs
    arx = fit_arx(y, u, dt_s=dt, na=2, nb=2, nk=1, constant=False)
    np.testing.assert_allclose(arx.a, sysd.den[0][0] / sysd.den[0][0][0], atol=1e-9)
    np.testing.assert_allclose(np.sort_complex(arx.poles), np.sort_complex(sysd.poles()), atol=1e-9)
    wn, zeta = arx.dominant_mode()
    assert wn == pytest.approx(20.53, rel=1e-3)
    assert zeta == pytest.approx(0.5629, rel=1e-3)
    assert float(arx.transfer_function().dcgain()) == pytest.approx(1.0, rel=1e-6)


def test_ar_model_of_release_gives_wn_and_zeta():
    dt = 0.005
    t = np.arange(0, 6, dt)
    a = DIGIT["zeta"] * DIGIT["wn_rad_s"]
    wd = DIGIT["wn_rad_s"] * math.sqrt(1 - DIGIT["zeta"] ** 2)
    y = 0.2 + np.exp(-a * t) * np.cos(wd * t)  # exact poles -a +- j wd
    wn, zeta = fit_arx(y, dt_s=dt, na=2).dominant_mode()
    assert wn == pytest.approx(DIGIT["wn_rad_s"], rel=1e-6)
    assert zeta == pytest.approx(DIGIT["zeta"], rel=1e-6)


def test_linear_fit_of_table_3_6_against_numpy_polyfit():
    commands = np.array(thesis_value("conversion.table_3_4_commands"), dtype=float)
    y_sg2 = np.array(thesis_value("conversion.table_3_6_y_sg2_mm"))
    r = fit_linear(commands, y_sg2)
    slope, intercept = np.polyfit(commands, y_sg2, 1)  # independent least-squares line
    assert r.slope.value == pytest.approx(slope, rel=1e-12)
    assert r.intercept.value == pytest.approx(intercept, rel=1e-12)
    np.testing.assert_allclose(r.residuals, y_sg2 - (slope * commands + intercept), atol=1e-12)
    # standard error of the slope from the closed form s / sqrt(Sxx)
    s = math.sqrt(np.sum(r.residuals**2) / (commands.size - 2))
    assert r.slope.stderr == pytest.approx(s / math.sqrt(np.sum((commands - commands.mean()) ** 2)), rel=1e-10)
    assert r.slope.ci_low < slope < r.slope.ci_high
    # the thesis's printed a = 0.9047 mm per command (E 3.17) is not this least-squares slope (0.871), see models
    assert r.slope.value == pytest.approx(0.8713, abs=1e-3)
    assert r.as_model().slope == r.slope.value


@pytest.mark.parametrize("kind", ["release", "step"])
def test_arx_method_on_records_with_half_percent_noise_within_2_percent(kind):
    # the ARX route pre-filters input and output alike; equation-error least squares is still biased by noise
    # (up to ~5 % on steps at 2 % noise, see the report's table), so it is held to 2 % at 0.5 % noise
    gen, truth = (release_record, DIGIT) if kind == "release" else (step_record, SERVO)
    t, y = gen(3, noise=0.005)
    r = identify(TimeSeries.from_arrays(t, y), kind, method="arx", t0_s=None if kind == "release" else 0.2)
    assert r.wn_rad_s == pytest.approx(truth["wn_rad_s"], rel=0.02)
    assert r.zeta == pytest.approx(truth["zeta"], rel=0.02)


def test_lsq_fits_an_overdamped_step_the_thesis_method_cannot():
    # zeta 1.5: no overshoot, so no %OS; the fit starts from the rise time and still finds the parameters, once
    # allowed (issue 11: an overdamped record is refused without --allow-overdamped)
    t = np.arange(0, 3, 0.002)
    y = second_order_response(t, "step", 10.0, 1.5, 0.0, 1.0, 0.1) + np.random.default_rng(0).normal(0, 0.005, t.size)
    series = TimeSeries.from_arrays(t, y)
    with pytest.raises(DataFileError, match=r"step test is overdamped \(zeta = 1.49.* pass --allow-overdamped"):
        identify(series, "step", method="lsq", t0_s=0.1)
    r = identify(series, "step", method="lsq", t0_s=0.1, allow_overdamped=True)
    assert r.features is None
    assert r.wn_rad_s == pytest.approx(10.0, rel=0.05)
    assert r.zeta == pytest.approx(1.5, rel=0.05)


# --- robust loss, drift, long records (issue 11) -----------------------------------------------------------------
def _spiky_step(seed, *, n_spikes=12, drift=0.0, t_end=2.0, dt=0.002):
    """The servo's step (3.2.4) with 1 % noise, single-sample spikes of 30-50 % of the step, and a linear drift."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, t_end, dt)
    y = second_order_response(t, "step", SERVO["wn_rad_s"], SERVO["zeta"], 0.5, 1.0, 0.2) + drift * t
    y += rng.normal(0.0, 0.01, t.size)
    hit = rng.choice(np.arange(100, 400), n_spikes, replace=False)  # in the transient, where they bias most
    y[hit] += rng.choice([-1, 1], n_spikes) * rng.uniform(0.3, 0.5, n_spikes)
    return t, y


def test_robust_loss_is_not_biased_by_spikes_where_least_squares_is():
    # known answer: MT(s) of 3.2.4; the same spiky records fitted both ways
    robust, plain = [], []
    for seed in range(5):
        t, y = _spiky_step(seed)
        for loss, out in (("soft_l1", robust), ("linear", plain)):
            f = SecondOrderFit("step", t0_s=0.2, loss=loss).fit(t, y)
            out.append(max(abs(f.wn_ / SERVO["wn_rad_s"] - 1), abs(f.zeta_ / SERVO["zeta"] - 1)))
    assert max(robust) < 0.01  # measured 0.2-0.6 %
    assert max(plain) > 2 * max(robust)


def test_drift_is_fitted_with_the_model():
    t, y = _spiky_step(7, n_spikes=0, drift=0.05)  # 0.05 units/s: 10 % of the step over the record
    f = SecondOrderFit("step", t0_s=0.2, loss="soft_l1", drift=True).fit(t, y)
    assert f.drift_per_s_ == pytest.approx(0.05, abs=0.003)
    assert f.wn_ == pytest.approx(SERVO["wn_rad_s"], rel=0.01)
    assert f.zeta_ == pytest.approx(SERVO["zeta"], rel=0.02)
    assert f.predict(t)[-1] == pytest.approx(1.5 + 0.05 * t[-1], abs=0.005)  # the prediction carries the drift


def test_robust_confidence_intervals_are_calibrated():
    # the sandwich covariance of the robust loss: about 95 % of 40 intervals cover the truth (binomial 99 %: >= 34)
    covered = 0
    for seed in range(40):
        t, y = _spiky_step(100 + seed, n_spikes=4)
        f = SecondOrderFit("step", fit_t0=True, t0_s=0.21, loss="soft_l1", drift=True).fit(t, y)
        e = f.estimates_["wn_rad_s"]
        covered += e.ci_low <= SERVO["wn_rad_s"] <= e.ci_high
    assert covered >= 34


@pytest.mark.parametrize("kind", ["step", "release"])
def test_analytic_jacobian_matches_finite_differences(kind):
    from flexdigit.identify.fit import _Model

    t = np.linspace(0, 3, 1501)
    model = _Model(t, kind, 0.31, True, True)
    p = np.array([20.5, 0.56, 0.5, 1.3, 0.3, 0.01])
    np.testing.assert_allclose(model.jacobian(p), model._numeric_jacobian(p), rtol=0, atol=2e-5 * 20.5)


def test_long_record_fitted_first_on_block_medians_gives_the_direct_answer(monkeypatch):
    from flexdigit.identify import fit as fit_module

    t, y = _spiky_step(11, t_end=10.0, dt=0.0005)  # 20,000 samples
    coarse_first = SecondOrderFit("step", fit_t0=True, t0_s=0.21, loss="soft_l1").fit(t, y)
    monkeypatch.setattr(fit_module, "_MAX_DIRECT_SAMPLES", 10**9)
    direct = SecondOrderFit("step", fit_t0=True, t0_s=0.21, loss="soft_l1").fit(t, y)
    assert coarse_first.wn_ == pytest.approx(direct.wn_, rel=1e-5)
    assert coarse_first.zeta_ == pytest.approx(direct.zeta_, rel=1e-5)

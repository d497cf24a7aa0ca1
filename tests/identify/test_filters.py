"""The SVD, FFT and Butterworth filters of 3.2.4 on signals with known clean parts."""

import math

import numpy as np
import pytest

from flexdigit.identify.filters import (
    apply_filter,
    butter_filter,
    fft_filter,
    noise_reduction,
    singular_spectrum,
    svd_filter,
)
from flexdigit.identify.fit import SecondOrderFit, second_order_response
from oracles import DIGIT


def _damped_sinusoid(seed, noise=0.05):
    t = np.arange(0, 6, 0.004)
    clean = second_order_response(t, "release", DIGIT["wn_rad_s"], DIGIT["zeta"], 0.0, 1.0, 0.0)
    return t, clean, clean + np.random.default_rng(seed).normal(0, noise, t.size)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_svd_filter_removes_80_percent_of_noise_and_keeps_wn_within_1_percent(seed):
    t, clean, noisy = _damped_sinusoid(seed)
    filtered = svd_filter(noisy, rank=2)  # 3.2.4: keep the two leading singular values
    assert noise_reduction(clean, noisy, filtered) >= 0.8
    fit = SecondOrderFit(kind="release", fit_t0=False, t0_s=0.0).fit(t, filtered)
    assert fit.wn_ == pytest.approx(DIGIT["wn_rad_s"], rel=0.01)


def test_svd_filter_reproduces_a_rank_two_signal_exactly_and_its_spectrum_shows_the_rank():
    k = np.arange(300)
    x = np.exp(-0.01 * k) * np.sin(0.2 * k)  # a damped sinusoid: Hankel rank 2
    np.testing.assert_allclose(svd_filter(x, rank=2, window=50), x, atol=1e-12)
    s = singular_spectrum(x, window=50)
    assert s[2] < 1e-10 * s[0] < s[1]


def test_svd_rank_trade_off_too_low_loses_the_offset():
    t, clean, noisy = _damped_sinusoid(0)
    offset = 0.5
    # a decay on an offset is rank 3: rank 2 (the thesis's choice) cannot hold the offset and the oscillation
    r2 = noise_reduction(clean + offset, noisy + offset, svd_filter(noisy + offset, rank=2))
    r3 = noise_reduction(clean + offset, noisy + offset, svd_filter(noisy + offset, rank=3))
    assert r3 >= 0.8
    assert r2 < r3 - 0.2


def test_fft_filter_keeps_exact_harmonics_and_removes_the_rest():
    n = 256
    k = np.arange(n)
    low = np.cos(2 * np.pi * 3 * k / n) + 0.5
    high = 0.3 * np.sin(2 * np.pi * 40 * k / n)
    np.testing.assert_allclose(fft_filter(low + high, harmonics=10), low, atol=1e-12)
    np.testing.assert_allclose(fft_filter(low + high, harmonics=40), low + high, atol=1e-12)


def test_fft_filter_trade_off_described_in_3_2_4():
    # a noisy servo step (not periodic): too few harmonics ring (Gibbs) and distort, too many keep the noise
    t = np.arange(0, 2, 0.002)
    clean = second_order_response(t, "step", 20.53, 0.5629, 0.0, 1.0, 0.2)
    noisy = clean + np.random.default_rng(0).normal(0, 0.05, t.size)
    reduction = {n: noise_reduction(clean, noisy, fft_filter(noisy, n)) for n in (3, 30, 400)}
    assert reduction[30] > reduction[3]
    assert reduction[30] > reduction[400]
    assert reduction[3] < 0  # so few harmonics make it "even more irregular than the original"
    assert reduction[400] < 0.3  # so many keep most of the noise
    # the end ringing of a non-periodic record: the filtered step starts far from its first sample
    assert abs(fft_filter(noisy, 30)[0] - clean[0]) > 0.2


def test_butterworth_is_zero_phase():
    t = np.arange(0, 4, 0.001)
    x = np.sin(2 * np.pi * 2 * t)
    y = butter_filter(x + 0.2 * np.sin(2 * np.pi * 150 * t), 1000, 20)
    middle = slice(500, -500)
    # no lag: the filtered 2 Hz wave lines up with the clean one sample for sample (a causal filter lags ~ms)
    assert np.max(np.abs(y[middle] - x[middle])) < 2e-3
    lag = np.argmax(np.correlate(y[middle], x[middle], "full")) - (x[middle].size - 1)
    assert lag == 0


def test_apply_filter_rejects_unknown_names():
    with pytest.raises(ValueError, match="'filter' parameter must be one of"):
        apply_filter(np.arange(10.0), np.zeros(10), "kalman")


def test_butter_cutoff_must_be_below_nyquist():
    with pytest.raises(ValueError, match="cutoff_hz"):
        butter_filter(np.zeros(100), 100.0, 60.0)
    assert math.isfinite(butter_filter(np.ones(100), 100.0, 10.0)[50])


def test_butter_filter_is_scipys_sosfiltfilt_bit_for_bit():
    # butter_filter runs sosfiltfilt's steps itself with the design cached: scipy's own call is the reference, on
    # seeded random lengths (short records too, where the padding is the whole record), rates, cut-offs, orders,
    # each filtered twice (the second from the cache). Exact: the same scipy steps in the same order, in one
    # process (a cache, not another algorithm), so equal on whatever BLAS and CPU both run on
    from scipy import signal

    rng = np.random.default_rng(15)
    for _ in range(60):
        n, order = int(rng.integers(4, 2000)), int(rng.integers(1, 9))
        fs = float(rng.uniform(50, 2000))
        fc = float(rng.uniform(0.01, 0.49)) * fs
        x = rng.standard_normal(n).cumsum()
        sos = signal.butter(order, fc, btype="low", fs=fs, output="sos")
        expected = signal.sosfiltfilt(sos, x, padlen=min(n - 1, 3 * (2 * len(sos) + 1) * 10))
        np.testing.assert_array_equal(butter_filter(x, fs, fc, order), expected)
        np.testing.assert_array_equal(butter_filter(x, fs, fc, order), expected)

"""Closed-loop maps, norms only of stable loops, margins and Monte Carlo (thesis 4.4-4.6)."""

import control as ct
import numpy as np
import pytest

from flexdigit.control.analysis import (
    additive_tolerance,
    hinf_norm,
    loop_maps,
    margins,
    monte_carlo_stability,
    root_locus,
    step_metrics,
)
from flexdigit.errors import ParameterError, UnstableError

G = ct.tf([2.0], [1.0, 3.0, 2.0])
K = ct.tf([1.5, 1.0], [1.0, 0.0])  # PI

# Tolerances, each with the reason for its size
CLOSED_FORM_RTOL = 1e-6  # a closed form against a frequency-grid peak refined by python-control
PEAK_W_RTOL = 1e-4  # the resonant frequency, where the peak is flat (second order in the error)
SETTLING_RTOL = 0.01  # a settling time read on a 1000-point time grid
MONTE_CARLO_ATOL = 0.06  # 200 samples of a 1/6 probability: 2.5 standard deviations (0.026)
ROOTS_ATOL = 1e-6  # two root finders on one polynomial: a double root at a breakaway gain splits as sqrt(eps)
ROOTS_EXACT_RTOL = 1e-12  # the same companion matrix through the same LAPACK routine: rounding at most


def test_maps_equal_feedback_formulas():
    # oracle: python-control's feedback() closed-form S, T, KS
    maps = loop_maps(G, K)
    w = 1.3j
    L = G(w) * K(w)
    assert maps.T_zw(w) == pytest.approx(1 / (1 + L))
    assert maps.T_yw(w) == pytest.approx(L / (1 + L))
    assert maps.T_uw(w) == pytest.approx(K(w) / (1 + L))
    assert maps.T_pq(w) == pytest.approx(-K(w) / (1 + L))


def test_hinf_norm_closed_form():
    # ||1/(s^2 + 2 z s + 1)|| = 1/(2 z sqrt(1 - z^2)) at w = sqrt(1 - 2 z^2)
    z = 0.1
    g, w = hinf_norm(ct.tf([1.0], [1.0, 2 * z, 1.0]))
    assert g == pytest.approx(1 / (2 * z * np.sqrt(1 - z**2)), rel=CLOSED_FORM_RTOL)
    assert w == pytest.approx(np.sqrt(1 - 2 * z**2), rel=PEAK_W_RTOL)


def test_unstable_loop_raises():
    with pytest.raises(UnstableError, match="unstable"):
        additive_tolerance(G, ct.tf([-10.0], [1.0]))


def test_step_metrics_first_order():
    # 1/(s + 1): 2 % settling at ln(50) = 3.91 s
    m = step_metrics(ct.tf([1.0], [1.0, 1.0]), t_final=10)
    assert m["settling_time_s"] == pytest.approx(np.log(50), rel=SETTLING_RTOL)
    assert m["final"] == pytest.approx(1.0)


def test_margins_pure_gain_loop():
    # L = 4/(s+1)^3: phase crossover at sqrt(3) rad/s, gain margin 8/4 = 2
    m = margins(ct.tf([4.0], [1.0, 3.0, 3.0, 1.0]), ct.tf([1.0], [1.0]))
    assert m["gain_margin"] == pytest.approx(2.0, rel=CLOSED_FORM_RTOL)
    assert m["phase_crossover_rad_s"] == pytest.approx(np.sqrt(3), rel=CLOSED_FORM_RTOL)
    assert 1 < m["disk_gain_margin"] < m["gain_margin"]  # disk margins are never larger


def test_monte_carlo_is_seeded_and_finds_instability():
    def family(gain=1.0):
        return gain * ct.tf([4.0], [1.0, 3.0, 3.0, 1.0])

    a = monte_carlo_stability(family, ct.tf([1.0], [1.0]), {"gain": 1.5}, n=200, seed=3)
    b = monte_carlo_stability(family, ct.tf([1.0], [1.0]), {"gain": 1.5}, n=200, seed=3)
    assert a == b
    # gain > 2 is unstable: P(1 + 1.5 U > 2) = P(U > 2/3) = 1/6 for U uniform in [-1, 1]
    assert 1 - a["stable_fraction"] == pytest.approx(1 / 6, abs=MONTE_CARLO_ATOL)


@pytest.mark.parametrize("seed", range(6))
def test_root_locus_is_python_controls_roots_gain_by_gain(seed):
    # the batched companion eigenvalues against python-control's root_locus_map (np.roots per gain) on random
    # strictly proper and biproper loops; each row's poles compared as sets (LAPACK orders them its own way)
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 7))
    m = int(rng.integers(0, n + 1))
    sys = ct.tf(rng.normal(size=m + 1), np.concatenate([[1.0], rng.normal(size=n)]))
    gains = np.concatenate([[0.0], np.logspace(-3, 3, 50)])
    ours = root_locus(sys, gains)
    theirs = ct.root_locus_map(sys, gains=gains).loci
    assert ours.shape == theirs.shape == (gains.size, n)
    for a, b in zip(ours, theirs, strict=True):
        scale = max(1.0, np.abs(b).max())
        # match each of ours to the nearest of theirs: within root-finding precision of a well-separated root
        assert np.abs(a[:, None] - b[None, :]).min(axis=1).max() <= ROOTS_ATOL * scale
        assert np.abs(b[:, None] - a[None, :]).min(axis=1).max() <= ROOTS_ATOL * scale


def test_root_locus_of_a_double_integrator_is_the_closed_form():
    # 1 + k / s^2: poles at +-j sqrt(k)
    gains = np.array([0.0, 1.0, 4.0, 9.0])
    loci = root_locus(ct.tf([1.0], [1.0, 0.0, 0.0]), gains)
    np.testing.assert_allclose(
        np.sort(loci.imag, axis=1), np.column_stack([-np.sqrt(gains), np.sqrt(gains)]), atol=1e-7
    )
    np.testing.assert_allclose(loci.real, 0.0, atol=1e-7)


@pytest.mark.parametrize("bad", [[0.0, np.nan], [1.0, np.inf], ["k"]])
def test_root_locus_refuses_gains_that_are_not_finite_numbers(bad):
    with pytest.raises(ParameterError, match="'gains' parameter of root_locus"):
        root_locus(ct.tf([1.0], [1.0, 2.0, 1.0]), bad)


@pytest.mark.parametrize("seed", range(4))
def test_root_locus_rows_are_np_roots_over_sixteen_decades(seed):
    # the report's controller loci: k over 16 decades, where the leading coefficient of den + k num is ~1e-12 of
    # the others and one root runs off to infinity; and an integrator, whose k = 0 row has a root at exactly 0.
    # Reference: np.roots row by row (what the batched companion matrices must equal: the same LAPACK call)
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 7))
    den = np.concatenate([[1.0], rng.uniform(0.5, 3.0, n - 1), [0.0]])  # an integrator
    num = rng.normal(size=n)  # one degree below den
    gains = np.concatenate([[0.0], np.logspace(-8, 8, 400)])
    ours = root_locus(ct.tf(num, den), gains)
    assert ours.shape == (gains.size, n)
    for k, row in zip(gains, ours, strict=True):
        ref = np.sort_complex(np.roots(np.trim_zeros(np.polyadd(den, k * num), "f")))
        np.testing.assert_allclose(np.sort_complex(row[~np.isnan(row)]), ref, rtol=ROOTS_EXACT_RTOL)

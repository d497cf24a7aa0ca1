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
    step_metrics,
)
from flexdigit.errors import UnstableError

G = ct.tf([2.0], [1.0, 3.0, 2.0])
K = ct.tf([1.5, 1.0], [1.0, 0.0])  # PI

# Tolerances, each with the reason for its size
CLOSED_FORM_RTOL = 1e-6  # a closed form against a frequency-grid peak refined by python-control
PEAK_W_RTOL = 1e-4  # the resonant frequency, where the peak is flat (second order in the error)
SETTLING_RTOL = 0.01  # a settling time read on a 1000-point time grid
MONTE_CARLO_ATOL = 0.06  # 200 samples of a 1/6 probability: 2.5 standard deviations (0.026)


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

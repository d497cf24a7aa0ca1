"""Discretisation methods against SciPy/python-control and the closed-form s -> z maps (thesis 5.1, appendix E)."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest
from scipy import signal

from flexdigit.control.discretise import (
    FirstOrderTustin,
    discretise,
    forward_euler_stability_limit_s,
    halve_step,
    map_s_to_z,
)
from flexdigit.errors import DesignError
from flexdigit.reference import thesis_value

K39 = ct.tf(thesis_value("hinf.k_39hz_num"), thesis_value("hinf.k_39hz_den"))  # E 4.x, 4.7 as printed
BEAM = ct.tf([103.3], [1, 0.543, 103.3])  # the lightly damped digit factor of the printed plant (reference note)

# Tolerances, each with the reason for its size
EXACT_RTOL = 1e-12  # the same map computed two ways (ours and SciPy's or python-control's): rounding only
EXACT_ATOL = 1e-12  # ... for entries that are zero
SIMULATION_RTOL = 1e-10  # a recursion run over 50 samples against python-control's forced_response
POLE_MAP_RTOL = 1e-6  # poles of the discretised system against the closed-form s -> z map of the continuous ones
PRINTED_POLE_RTOL = 1e-3  # 245.04, the printed pole, to its 4 digits
ZERO_LIMIT_RTOL = 1e-2  # 2 zeta/wn from the printed plant's rounded beam factor


@pytest.mark.parametrize("T", [0.001, 0.005, 0.02])
def test_forward_euler_equals_scipy_euler(T):
    # independent oracle: scipy.signal.cont2discrete(method="euler")
    ss = ct.ss(K39)
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((ss.A, ss.B, ss.C, ss.D), T, method="euler")
    ours = discretise(ss, T, "forward_euler")
    np.testing.assert_allclose(ours.A, Ad, rtol=EXACT_RTOL, atol=EXACT_ATOL)
    np.testing.assert_allclose(ours.B, Bd, rtol=EXACT_RTOL)
    assert ours.dt == T
    assert isinstance(discretise(K39, T, "forward_euler"), ct.TransferFunction)


@pytest.mark.parametrize("method", ["tustin", "forward_euler", "backward_euler", "zoh"])
def test_poles_land_where_the_closed_form_map_says(method):
    T = 0.005
    poles_d = np.sort_complex(discretise(K39, T, method).poles())
    expected = np.sort_complex(map_s_to_z(K39.poles(), T, method))
    np.testing.assert_allclose(poles_d, expected, rtol=POLE_MAP_RTOL)


@pytest.mark.parametrize("method", ["tustin", "forward_euler", "backward_euler"])
def test_zeros_land_where_the_closed_form_map_says(method):
    T = 0.004
    d = discretise(BEAM * ct.tf([1, 20], [1, 50]), T, method)
    finite = map_s_to_z(np.array([-20.0]), T, method)
    zeros = d.zeros()
    assert np.min(np.abs(zeros - finite[0])) < 1e-6


def test_tustin_prewarp_matches_the_continuous_response_at_the_prewarp_frequency():
    T, w0 = 0.02, 10.16  # 20 ms and the beam mode
    c = complex(BEAM(1j * w0))
    warped = discretise(BEAM, T, "tustin", prewarp_rad_s=w0)
    plain = discretise(BEAM, T, "tustin")
    assert abs(complex(warped(np.exp(1j * w0 * T))) - c) < 1e-6 * abs(c)
    assert abs(complex(plain(np.exp(1j * w0 * T))) - c) > 0.1 * abs(c)  # the lightly damped peak moves without it


def test_bad_requests_are_named():
    with pytest.raises(DesignError, match="prewarp"):
        discretise(K39, 0.01, "zoh", prewarp_rad_s=5.0)
    with pytest.raises(DesignError, match="Nyquist"):
        discretise(K39, 0.02, "tustin", prewarp_rad_s=200.0)
    with pytest.raises(DesignError, match="continuous"):
        discretise(discretise(K39, 0.01), 0.01)
    with pytest.raises(ValueError, match="method"):
        discretise(K39, 0.01, "simpson")


def test_forward_euler_limits_of_the_39hz_design():
    # issue 6 / 5.1.2: the fast pole leaves the unit circle above 2/245 s, the beam-mode zeros above 2 zeta/wn
    fast = forward_euler_stability_limit_s(K39.poles())
    zeros = forward_euler_stability_limit_s(K39.zeros())
    assert fast == pytest.approx(2 / 245.04, rel=PRINTED_POLE_RTOL)  # 8.16 ms
    # 5.26 ms from table 4.3's zeros; the 4-figure printed coefficients put the zero at -0.2731, hence 1 %
    assert zeros == pytest.approx(2 * 0.2715 / (0.2715**2 + 10.1594**2), rel=ZERO_LIMIT_RTOL)
    # and the numerical discretisation agrees on either side of the limit
    assert np.max(np.abs(discretise(K39, 0.98 * fast, "forward_euler").poles())) < 1
    assert np.max(np.abs(discretise(K39, 1.02 * fast, "forward_euler").poles())) > 1
    assert forward_euler_stability_limit_s([0.5 + 1j]) == 0.0


@pytest.mark.parametrize("A,B,T", [(0.5, 0.1, 0.01), (0.0, 0.02, 0.02), (0.05, 0.2, 0.001)])
def test_appendix_e_difference_equation_is_tustin(A, B, T):
    f = FirstOrderTustin(A, B, T)
    oracle = ct.sample_system(ct.tf([A, 1.0], [B, 1.0]), T, method="tustin")  # python-control's bilinear
    num, den = oracle.num[0][0], oracle.den[0][0]
    np.testing.assert_allclose([f.b0, f.b1], num / den[0], rtol=EXACT_RTOL)
    np.testing.assert_allclose(f.a1, den[1] / den[0], rtol=EXACT_RTOL)
    e = np.sin(np.arange(50) * 0.3) + 1.0
    _, u = ct.forced_response(oracle, np.arange(50) * T, e)
    np.testing.assert_allclose(f.simulate(e), u, rtol=SIMULATION_RTOL, atol=EXACT_ATOL)


def test_step_halving_on_forward_euler_of_a_first_order_lag():
    # y' = -a y + a, step; forward Euler y_k = 1 - (1 - aT)^k: unstable for T > 2/a, converging as T halves
    a = 100.0

    def response(T):
        t = np.arange(0, 0.2 + T / 2, T)
        return t, 1 - (1 - a * T) ** np.arange(len(t))

    result = halve_step(response, 0.032, tolerance=0.05)
    alphas = [h[0] for h in result.history]
    assert alphas[:2] == [0.032, 0.016]
    assert result.history[0][1] > 1  # 32 ms > 2/a = 20 ms: unstable, far from the 16 ms response
    assert result.converged
    assert result.history[-1][1] <= 0.05
    assert all(h[1] > 0.05 for h in result.history[:-1])
    # the chosen alpha really meets the tolerance against alpha/2 (recomputed independently)
    t1, y1 = response(result.period_s)
    t2, y2 = response(result.period_s / 2)
    assert np.max(np.abs(y1 - np.interp(t1, t2, y2))) <= 0.05 * np.max(np.abs(y2))

"""Bridge, amplifier and ADC (E 2.1-2.4, 2.5) against hand-derived resistances, scipy's Butterworth and the
card's stated range and resolution."""

import math

import numpy as np
import pytest
import scipy.signal

from flexdigit.errors import ParameterError
from flexdigit.models import bridge
from flexdigit.params import Sensors

# Tolerances, each with the reason for its size
EXACT_RTOL = 1e-12  # the bridge formula against the same arithmetic written out here
ANALYTIC_RTOL = 1e-9  # E 2.2-2.4 written out, and SciPy's Butterworth response, against ours: rounding only
ZERO_ATOL = 1e-15  # a bridge ratio that is zero


def test_wheatstone_ratio_by_hand():
    # R1=121, R2=119, R3=R4=120: (121*120 - 119*120) / (240 * 240) = 240/57600
    assert bridge.wheatstone_ratio(121, 119, 120, 120) == pytest.approx(240 / 57600, rel=EXACT_RTOL)


@pytest.mark.parametrize(
    ("kind", "expected"),
    [
        ("half", lambda gf, e: gf / 4 * 2 * e),  # E 2.4
        ("full", lambda gf, e: gf * e),  # E 2.3
        ("quarter", lambda gf, e: gf * e / (2 * (2 + gf * e))),  # E 2.2 with one active arm
    ],
)
def test_bridge_ratio_closed_forms(kind, expected):
    s = Sensors(bridge=kind, gauge_factor=2.1)
    eps = np.array([-2e-3, -1e-5, 0.0, 3e-4, 5e-3])
    assert np.allclose(bridge.bridge_ratio(eps, s), expected(2.1, eps), rtol=ANALYTIC_RTOL, atol=ZERO_ATOL)


def test_quarter_bridge_linear_form_is_gf_eps_over_4():
    s = Sensors(bridge="quarter")
    assert bridge.bridge_ratio(1e-3, s, linear=True) == pytest.approx(0.8e-3 / 4)
    # the exact form is smaller by the factor 2/(2 + GF eps)
    assert bridge.bridge_ratio(1e-3, s) == pytest.approx(0.8e-3 / 4 * 2 / (2 + 0.8e-3))


def test_gauge_voltage_of_the_thesis_chain():
    # half bridge, GF 0.8 (6.4), Vs 1 V (assumed), gain 10,000 (2.5.1): 100 microstrain -> 0.4 V
    assert bridge.gauge_voltage_v(1e-4) == pytest.approx(0.4, rel=ANALYTIC_RTOL)
    assert bridge.strain_from_voltage(0.4) == pytest.approx(1e-4)


def test_lowpass_matches_scipy_butterworth_response():
    s = Sensors(amplifier_lowpass_order=4)
    lp = bridge.lowpass_tf(s)
    w = 2 * math.pi * np.array([10.0, 470.0, 2000.0])
    _, h = scipy.signal.freqs(*scipy.signal.butter(4, 2 * math.pi * 470, analog=True), worN=w)
    ours = np.array([complex(lp(1j * x)) for x in w])
    assert np.allclose(ours, h, rtol=ANALYTIC_RTOL)
    assert abs(ours[1]) == pytest.approx(1 / math.sqrt(2), rel=ANALYTIC_RTOL)
    assert float(bridge.amplifier_tf(s).dcgain()) == pytest.approx(10_000)


def test_adc_resolution_and_clipping():
    s = Sensors()
    lsb = 10.0 / 2**16
    assert s.adc_lsb_v == pytest.approx(lsb)
    v = np.array([-7.0, -5.0, -lsb / 3, 0.0, 0.4 * lsb, 0.6 * lsb, 4.9999, 7.0, np.nan])
    codes = bridge.adc_counts(v, s)
    assert codes.tolist() == [0, 0, 32768, 32768, 32768, 32769, 65535, 65535, 0]
    inside = v[1:-2]
    assert np.all(np.abs(bridge.adc_quantise(inside, s) - inside) <= lsb / 2 + 1e-15)
    assert bridge.adc_clipped(v[:-1], s).tolist() == [True, False, False, False, False, False, False, True]


def test_bad_bridge_type_is_named():
    with pytest.raises(ParameterError, match="bridge"):
        bridge.bridge_ratio(1e-3, bridge="eighth")

"""The sensor chain against E 2.2-2.4, scipy's Butterworth and the ADC's arithmetic."""

import numpy as np
import pytest
import scipy.signal

from flexdigit.params import RigParams, Sensors
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.sensors import SensorChain, adc, bridge_ratio, lowpass_group_delay_s


@pytest.mark.parametrize(("bridge", "per_strain"), [("quarter", 0.8 / 4), ("half", 0.8 / 2), ("full", 0.8)])
def test_bridge_small_strain_forms(bridge, per_strain):
    # E 2.3 (full: GF eps), E 2.4 (half: GF/4 * 2 eps), quarter GF eps / 4, to first order in eps
    eps = 1e-6
    assert float(bridge_ratio(eps, -eps, Sensors(bridge=bridge))) == pytest.approx(per_strain * eps, rel=1e-5)


def test_axial_strain_cancels_in_half_and_full_bridges_only():
    axial = 2e-5
    assert float(bridge_ratio(axial, axial, Sensors(bridge="half"))) == 0.0
    assert float(bridge_ratio(axial, axial, Sensors(bridge="full"))) == 0.0
    # quarter bridge: (R1 - R)/(2(R1 + R)) with R1 = R (1 + GF eps) (E 2.2)
    gf = 0.8
    assert float(bridge_ratio(axial, axial, Sensors(bridge="quarter"))) == pytest.approx(
        gf * axial / (2 * (2 + gf * axial)), rel=1e-12
    )


def test_lowpass_as_delay_matches_scipy_lsim_on_digit_frequencies():
    # the twin applies the 470 Hz Butterworth as its DC group delay; check against the full filter at 2 Hz
    s = Sensors()
    b, a = scipy.signal.butter(s.amplifier_lowpass_order, 2 * np.pi * s.amplifier_lowpass_hz, analog=True)
    t = np.linspace(0, 1.0, 200_001)
    w = 2 * np.pi * 2.0
    _, y, _ = scipy.signal.lsim((b, a), np.sin(w * t), t)
    tau = lowpass_group_delay_s(s.amplifier_lowpass_hz, s.amplifier_lowpass_order)
    assert tau == pytest.approx(np.sqrt(2) / (2 * np.pi * 470.0), rel=1e-9)  # 2nd-order Butterworth: sqrt(2)/wc
    settled = t > 0.2
    assert np.max(np.abs(y[settled] - np.sin(w * (t[settled] - tau)))) < 1e-4


def test_adc_clips_and_quantises_to_16_bits():
    s = Sensors()
    lsb = 10.0 / 2**16
    out = adc([7.0, -9.0, 0.3 * lsb, 0.7 * lsb], s)
    np.testing.assert_allclose(out, [5.0 - lsb, -5.0, 0.0, lsb])


def test_noise_is_seeded_and_has_the_calibrated_level():
    p = RigParams()
    cal = Calibration(noise_white_v=(0.01, 0.02, 0.0), noise_drift_v_per_sqrt_s=(0.0, 0.0, 0.0))
    chains = [SensorChain(p, cal, np.random.default_rng(seed)) for seed in (5, 5, 6)]
    samples = [np.array([c.sample(np.zeros(3), 0.001 * k) for k in range(4000)]) for c in chains]
    np.testing.assert_array_equal(samples[0], samples[1])  # exact: one seed, one code path, one machine
    assert not np.array_equal(samples[0], samples[2])
    np.testing.assert_allclose(samples[0].std(axis=0), [0.01, 0.02, 0.0], atol=1e-3)


def test_drift_is_a_random_walk_with_the_calibrated_rate():
    p = RigParams()
    cal = Calibration(noise_white_v=(0.0,) * 3, noise_drift_v_per_sqrt_s=(0.01,) * 3)
    ends = []
    for seed in range(300):
        chain = SensorChain(p, cal, np.random.default_rng(seed))
        for k in range(11):
            v = chain.sample(np.zeros(3), 0.4 * k)
        ends.append(v)
    # after 4 s the spread is 0.01 * sqrt(4) = 0.02 V
    assert np.std(np.array(ends)) == pytest.approx(0.02, rel=0.1)


def test_inlined_quantiser_agrees_with_models_bridge():
    from flexdigit.models.bridge import adc_quantise

    chain = SensorChain(RigParams(), Calibration(), np.random.default_rng(0))
    v = np.random.default_rng(1).uniform(-6, 6, 10_000)
    np.testing.assert_array_equal(chain._quantise(v), adc_quantise(v, RigParams().sensors))


@pytest.mark.parametrize("bridge", ["quarter", "half", "full"])
def test_chain_output_is_gain_times_bridge_ratio_plus_offset(bridge):
    p = RigParams().replace(sensors=Sensors(bridge=bridge))
    cal = Calibration(channel_gain=(0.1, 0.2, 0.3), channel_offset_v=(0.01, -0.02, 0.0))
    chain = SensorChain(p, cal, np.random.default_rng(0))
    kappa = np.array([[0.5, -2.0, 3.0], [0.0, 1.0, -1.0]])  # 1/m
    axial = np.array([[-8.0, 0.0, 2.0], [5.0, -5.0, 0.0]])  # N
    half_t = p.geometry.strip_thickness_m / 2
    eps_ax = axial / (p.material.youngs_modulus_pa * p.geometry.cross_section_m2)
    ratio = bridge_ratio(kappa * half_t + eps_ax, -kappa * half_t + eps_ax, p.sensors)
    expected = 1e4 * 1.0 * np.array([0.1, 0.2, 0.3]) * ratio + np.array([0.01, -0.02, 0.0])
    np.testing.assert_allclose(chain.clean_v(kappa, axial), expected, rtol=1e-12, atol=1e-15)

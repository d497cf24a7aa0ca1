"""Unequal gauge chains (issue 24, trial 2 items 1, 3, 4): where a gauge rails, how finely it reads, and the map's
noise weights.

References: a gauge's rail angle is its rail over its own volts per degree at rest (the statics are near linear
in the cable's range: 0.5 deg allows their curvature over 20 deg); the Gauss-Markov weights ``W s / (s' W s)``
with ``W = 1 / noise^2`` (Kariya & Kurata, Generalized Least Squares, 2004, ch. 2) worked by hand.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from flexdigit.models.bridge import gauge_noise_scale
from flexdigit.params import RigParams, adc_range_notes, load_params
from flexdigit.rig.gauge_rails import gauge_rails, rail_lines, railed_readings, resolution_lines
from flexdigit.rig.rotation import RotationEstimator

DIGITS2 = Path(__file__).resolve().parents[1] / "data" / "handmade_digits2"
#: How far (deg) the rail found on the statics may sit from the linear reference: the chain's curvature over 20 deg.
RAIL_TOLERANCE_DEG = 0.5


def _with_gains(params: RigParams, gains) -> RigParams:
    return dataclasses.replace(params, sensors=dataclasses.replace(params.sensors, amplifier_gains_v_per_v=gains))


def test_a_gauge_amplified_to_rail_at_20_deg_is_found_there_and_said_once():
    stainless = load_params(DIGITS2 / "stainless_eight_full_gains.toml")
    reach = gauge_rails(stainless)
    assert [r.rail_deg for r in reach] == [None] * 8  # gauge 8 (gain 6000) rails at ~65 deg, past the 59 deg range
    gains = list(stainless.sensors.amplifier_gains_v_per_v)
    rail_v = stainless.sensors.adc_range_v[1]
    gains[1] *= rail_v / (20.0 * reach[1].v_per_deg)  # gauge 2 reaches +5 V at 20 deg, on the linear reference
    hot = _with_gains(stainless, tuple(gains))
    reach = gauge_rails(hot)
    assert reach[1].rail_deg == pytest.approx(20.0, abs=RAIL_TOLERANCE_DEG)
    assert [r.rail_deg for k, r in enumerate(reach) if k != 1] == [None] * 7
    lines = rail_lines(reach, hot)
    assert len(lines) == 1
    assert lines[0].startswith("[sensors] gauge 2 reaches the ADC's 5 V rail")


def test_the_thesis_rig_reads_inside_its_range_and_finely():
    reach = gauge_rails(RigParams())
    assert rail_lines(reach, RigParams()) == []
    assert resolution_lines(reach, RigParams()) == []
    assert adc_range_notes(RigParams()) == []


def test_a_unipolar_adc_and_a_coarse_one_are_flagged_naming_the_key():
    unipolar = load_params(DIGITS2 / "heavy_supports_10bit.toml")
    (line,) = adc_range_notes(unipolar)
    assert line.startswith("[sensors] adc_range_v = [0, 3.3] cannot read")
    bipolar = load_params(DIGITS2 / "heavy_supports_10bit_bipolar.toml")
    assert adc_range_notes(bipolar) == []
    reach = gauge_rails(bipolar)
    # 10 bits over 5 V is 4.9 mV a step; the finest gauge's volts per degree over it
    finest = max(abs(r.v_per_deg) for r in reach) / (5.0 / 2**10)
    assert max(r.steps_per_deg for r in reach) == pytest.approx(finest, rel=1e-12)
    assert finest < 1.0 / 0.6  # under one step over 2 % of 30 deg
    (line,) = resolution_lines(reach, bipolar)
    assert "adc_bits = 10" in line
    assert "raise the amplifier gain or the ADC's bits" in line


def test_noise_weights_only_with_unequal_amplifiers():
    assert gauge_noise_scale(RigParams().sensors, 3) is None
    stainless = load_params(DIGITS2 / "stainless_eight_full_gains.toml")
    np.testing.assert_array_equal(
        gauge_noise_scale(stainless.sensors, 8), [500, 750, 1000, 1500, 2000, 3000, 4000, 6000]
    )
    equal = _with_gains(stainless, (2000.0,) * 8)
    assert gauge_noise_scale(equal.sensors, 8) is None


@pytest.mark.slow
def test_the_stainless_digit_with_gains_500_to_6000_meets_the_step_figures(capsys):
    """Trial 2 item 1: before, overshoot 11.5 % and settling 2.44 s on seed 0 (its estimate 44 %); issue 24's
    figures: settles in < 1 s, < 10 % overshoot, the true rotation within 2 %."""
    from flexdigit.cli import main

    path = DIGITS2 / "stainless_eight_full_gains.toml"
    assert main(["run", "--params", str(path), "--setpoint-deg", "30", "--seed", "0", "--json", "--no-progress"]) == 0
    out = json.loads(capsys.readouterr().out)
    true = out["step_metrics"]["true"]
    assert true["settling_time_s"] < 1.0
    assert true["overshoot_percent"] < 10.0
    assert abs(out["true_final_rotation_deg"] - 30.0) < 0.02 * 30.0
    weights = np.asarray(out["rotation_map"]["coef_deg_per_v"]) * [500, 750, 1000, 1500, 2000, 3000, 4000, 6000]
    assert weights.max() / weights.min() < 3.0  # no gauge dominates for its amplifier alone (1.4; before: 130)


def test_noise_weighted_map_counts_gauges_by_their_noise_in_degrees():
    # two gauges on one rotation, the second amplified 4 times (and its noise with it)
    theta = np.array([0.0, 10.0, 20.0, 30.0])
    gauges = np.c_[0.01 * theta, 0.04 * theta]
    equal = RotationEstimator().fit(gauges, theta)
    weighted = RotationEstimator(noise_v=[1e-3, 4e-3]).fit(gauges, theta)
    # equal: s / (s's) = [0.01, 0.04] / 0.0017; weighted: W s / (s'Ws), W = [1e6, 62500]
    np.testing.assert_allclose(equal.coef_, [0.01 / 0.0017, 0.04 / 0.0017], rtol=1e-9)
    np.testing.assert_allclose(weighted.coef_, [1e4 / 200.0, 2500.0 / 200.0], rtol=1e-9)
    # each gauge then carries half the estimate: coef x sensitivity equal
    np.testing.assert_allclose(weighted.coef_ * [0.01, 0.04], [0.5, 0.5], rtol=1e-9)
    np.testing.assert_allclose(weighted.predict(gauges), theta, atol=1e-9)


def test_railed_readings_are_counted_per_gauge():
    sensors = RigParams().sensors  # +-5 V, 16 bits
    top = 5.0 - 10.0 / 2**16  # the highest code
    readings = [[0.1, 5.0, -4.99], [0.2, top, -5.0], [0.3, 1.0, -5.0]]
    said = railed_readings(readings, sensors)
    assert said == (
        "gauge 2 stuck at the rail (sensors.adc_range_v = [-5, 5] V) in 2 of 3 readings; "
        "gauge 3 stuck at the rail (sensors.adc_range_v = [-5, 5] V) in 2 of 3 readings"
    )
    assert railed_readings([[0.1, top - 10.0 / 2**16, -5.0 + 10.0 / 2**16]], sensors) is None


def test_collect_refuses_a_dataset_read_at_the_rail_unless_allowed(tmp_path):
    from flexdigit.errors import DataFileError
    from flexdigit.tactile.protocols import Protocol
    from flexdigit.tactile.runner import collect

    unipolar = load_params(DIGITS2 / "heavy_supports_10bit.toml")
    small = Protocol("small", (0.0125,), (0.0, 0.05), repetitions=1, no_load_repetitions=1)
    out = tmp_path / "railed.parquet"
    with pytest.raises(DataFileError, match=r"gauge 1 stuck at the rail .* in 3 of 3 readings; gauge 2"):
        collect(small, out=out, params=unipolar, seed=0)
    assert not out.exists()
    dataset = collect(small, out=out, params=unipolar, seed=0, allow_rail=True)  # resumes the journal
    assert out.exists()
    assert np.all(dataset.gauges_v == 0.0)


def test_a_record_of_a_few_adc_steps_is_called_quantised_not_saturated():
    from flexdigit.identify.quality import QUANTISED_STEPS, _quantised

    lsb = 10.0 / 2**10  # a 10-bit ADC over +-5 V
    t = np.linspace(0.0, 8.0, 4001)
    release = 0.044 * np.exp(-0.6 * t) * np.cos(12.4 * t)  # ~9 steps peak to peak
    coarse = np.round(release / lsb) * lsb
    problem = _quantised(coarse, "V")
    assert problem.code == "quantised"
    assert problem.message.startswith("quantised: the record spans 9 ADC steps of 0.00977 V")
    assert "raise the amplifier gain or the ADC's bits" in problem.message
    fine = np.round(release / (lsb / 64)) * (lsb / 64)
    assert _quantised(fine, "V") is None
    assert QUANTISED_STEPS == 16

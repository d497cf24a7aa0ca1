"""A coarse ADC's steps are noise the design must see (issue 24: heavy_supports_10bit_bipolar overshot 13.5 %).

Its 10 bits over +-2.5 V step 4.88 mV; its gauges' white noise is 0.1 mV (the thesis's scaled to its amplifier). The
design model counted the white noise alone (0.020 deg of measured rotation), chose an observer that took every step
of the reading for motion, and the loop swung the command 15..34 about 26: the tip left the band by 13.5 %. A
uniform rounding error of step ``q`` has variance ``q^2 / 12`` (Widrow and Kollar, *Quantization Noise*, 2008,
ch. 4), so each reading's standard deviation is ``sqrt(white^2 + q^2 / 12)``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from flexdigit.cli import main
from flexdigit.control.design20ms import digit_mount
from flexdigit.control.digit_model import digit_model
from flexdigit.params import RigParams, load_params

BIPOLAR = Path(__file__).parents[1] / "data" / "handmade_digits2" / "heavy_supports_10bit_bipolar.toml"
#: The digit's gauges' white noise, V (the derived calibration's, twin_calibration; its three gauges alike).
WHITE_V = 1e-4


def _with_adc_bits(params: RigParams, bits: int) -> RigParams:
    data = params.to_dict()
    data["sensors"]["adc_bits"] = bits
    return RigParams.from_dict(data)


def test_a_coarse_adcs_steps_are_in_the_measured_rotations_noise():
    """The same digit with 10 and 16 bits: the gauges, their weights and their white noise are one, so the two
    models' noise differs by the readings' sd alone: ``sqrt(w^2 + q10^2/12) / sqrt(w^2 + q16^2/12)`` = 13.80."""
    ten = load_params(BIPOLAR)
    sixteen = _with_adc_bits(ten, 16)
    span_v = ten.sensors.adc_range_v[1] - ten.sensors.adc_range_v[0]
    q10, q16 = span_v / 2**10, span_v / 2**16
    expected = math.sqrt(WHITE_V**2 + q10**2 / 12) / math.sqrt(WHITE_V**2 + q16**2 / 12)
    assert expected == pytest.approx(13.80, abs=0.01)
    mount = digit_mount(ten)
    coarse = digit_model(ten, orientation=mount).measurement_sd_deg
    fine = digit_model(sixteen, orientation=mount).measurement_sd_deg
    assert coarse / fine == pytest.approx(expected, rel=1e-9)


@pytest.mark.slow
def test_the_bipolar_10_bit_digits_step_settles_without_overshoot(capsys):
    """`run --params` on the digit (seed 0): was 13.5 % overshoot and no settling in 3 s; now its design's observer
    filters the ADC's steps."""
    code = main(["run", "--params", str(BIPOLAR), "--setpoint-deg", "30", "--seed", "0", "--json"])
    run = json.loads(capsys.readouterr().out)
    assert code == 0, run
    true = run["step_metrics"]["true"]
    assert true["overshoot_percent"] < 10.0
    assert true["settling_time_s"] is not None
    assert true["settling_time_s"] < 1.0
    assert abs(run["true_final_rotation_deg"] - 30.0) < 0.02 * 30.0

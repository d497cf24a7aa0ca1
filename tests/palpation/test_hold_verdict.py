"""A hold's verdict says what happened (issue 24): "within 10 % after X s" only when the force stayed within 10 % over
the whole figures' window, and a hold whose tare would read a gauge on an ADC rail is refused before it moves.

References: a first-order rise ``f(t) = F (1 - exp(-t / tau))`` whose entry into the 10 % band is known in closed
form (``t = tau ln 10``); the statics of a digit whose 0..3.3 V ADC reads its balanced bridges' 0 V straight (the
twin's sensor chain: a bridge is balanced straight, ``flexdigit.params.adc_range_notes``).

Tolerances: ``SAMPLE = 0.02`` s, one loop period (the settling time is the first sample inside the band).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexdigit.cli.palpate import _hold_data
from flexdigit.errors import ParameterError
from flexdigit.palpation.contact_estimation import ContactGaugeModel
from flexdigit.palpation.palpation import ForceHold, _hold_figures, check_tare_rails
from flexdigit.params import RigParams
from flexdigit.twin.digit_calibration import twin_calibration

SAMPLE = 0.02


def _rise(tau_s: float, duration_s: float = 10.0, window_s: float = 3.0) -> ForceHold:
    """A hold of 0.1 N whose true force rises to it with time constant ``tau_s`` (no overshoot)."""
    t = np.arange(0.0, duration_s, SAMPLE)
    force = 0.1 * (1.0 - np.exp(-t / tau_s))
    figures = _hold_figures(t, force, 0.1, window_s)
    return ForceHold(0.1, t, np.full(t.size, 20), force, force, *figures, "completed", window_s=window_s)


def test_a_hold_that_enters_the_band_inside_the_window_is_not_settled():
    """tau 3.9 s enters 10 % at 8.98 s (the next sample 9.00 s), after the window's start at 7 s
    (thick_stiff_strong_servo's case)."""
    held = _rise(3.9)
    assert held.settling_s == pytest.approx(3.9 * math.log(10.0), abs=SAMPLE)
    assert not held.settled()
    assert "not settled: within 10 % only from 9.00 s" in held.settle_note()


def test_a_hold_that_enters_the_band_before_the_window_is_settled():
    """tau 2 s enters 10 % at 4.6 s, before the window: its steady figures are a steady state."""
    held = _rise(2.0)
    assert held.settled()
    assert held.settle_note() == ""


def test_a_hold_never_in_the_band_says_so():
    """tau 30 s ends at 28 % of the setpoint: never within 10 %."""
    held = _rise(30.0)
    assert "never within 10 %" in held.settle_note()


def _model(adc_range_v) -> ContactGaugeModel:
    params = RigParams.from_dict({"sensors": {"adc_range_v": adc_range_v}})
    return ContactGaugeModel(params, twin_calibration(params))


def test_a_tare_below_the_adcs_zero_rail_is_refused_naming_the_gauge():
    """A 0..3.3 V ADC on the thesis rig: gauge 1 reads below 0 V straight (its rest under gravity, as the +-5 V
    range reads it), the other two above; only gauge 1 is named, with its reading."""
    rest = _model([-5.0, 5.0]).free_v([8])[0]
    assert rest[0] < 0.0
    with pytest.raises(ParameterError, match=rf"would read gauge 1 {rest[0]:+.3f} V, on or within") as refused:
        check_tare_rails(_model([0.0, 3.3]))
    assert "gauge 2" not in str(refused.value)


def test_a_tare_inside_the_adcs_range_is_accepted():
    """The thesis rig's +-5 V reads its gauges at rest far from either rail."""
    check_tare_rails(_model([-5.0, 5.0]))


def test_palpates_text_and_json_say_not_settled():
    """`palpate --protocol hold`'s text and --json: no "within 10 % after" where the window still rose."""
    data, text = _hold_data(_rise(3.9))
    assert data["settled"] is False
    assert "within 10 % after" not in text
    assert data["settle_note"] in text

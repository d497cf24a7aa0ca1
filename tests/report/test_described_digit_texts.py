"""The report of a described digit (``reproduce --params``) in its own words (issue 28's newcomer): its gauge
count, "n/a" where a table has no figure, and no NaN text where the cable is slack."""

import math
import warnings

import pytest

from digits import newcomer_digit
from flexdigit.params import Geometry, RigParams, Sensors
from flexdigit.report.build import _cell
from flexdigit.report.chapter import ReportContext
from flexdigit.tactile.thesis_experiments import equivalent_servo_angle
from flexdigit.twin.digit_calibration import calibration_for


def test_texts_count_the_digits_gauges(tmp_path):
    assert ReportContext(tmp_path).gauges_text == "three gauges"  # the thesis rig's texts unchanged
    assert ReportContext(tmp_path, params=newcomer_digit()).gauges_text == "four gauges"
    one = RigParams(geometry=Geometry(gauge_positions_m=(0.045,)), sensors=Sensors(adc_channels=(0,)))
    assert ReportContext(tmp_path, params=one).gauges_text == "one gauge"


def test_a_table_cell_without_a_figure_reads_n_a():
    assert _cell(float("nan")) == "n/a"
    assert _cell(0.1234567) == "0.123457"


def test_the_friction_as_a_servo_angle_leaves_out_the_slack_settings():
    # at command 0 with no load the newcomer's cable is slack: its tension does not move with the servo (0 / 0);
    # the median was NaN, printed "median nan deg = nan us", with a RuntimeWarning naming a source line
    params = newcomer_digit()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        eq = equivalent_servo_angle(params, calibration_for(params))
    assert (eq["taut"], eq["settings"]) == (62, 63)
    assert all(math.isfinite(eq[k]) for k in ("median_deg", "min_deg", "max_deg", "median_us"))
    # the thesis rig's 63 settings are all taut: its figure is the one its report printed (1.42 deg)
    thesis = equivalent_servo_angle()
    assert (thesis["taut"], thesis["settings"]) == (63, 63)
    assert thesis["median_deg"] == pytest.approx(1.4185306224077299, rel=1e-6)  # its results.json, to solver rounding

"""``reproduce --params`` on a digit where a thesis figure cannot be had the thesis's way (issue 24, "never a
traceback"): each cause of the exits 1 measured on the hand-made digits, on a digit built for it.

- a release that settles after the fast report's 5 s (heavy supports: Ts = 4/(zeta wn) = 6.6 s): its record is
  lengthened until it settles, and the thesis's wn = 4/(zeta Ts) is measured, not read off a record cut short;
- gauges a 10-bit ADC cannot resolve in a release test (the thesis rig on 10 bits): "not applicable" and identify's
  reason, never a figure fitted to the ADC's steps;
- the sensitivity study's datasheet ranges (the thesis's steel, 195-215 GPa) about a PEEK strip: the same relative
  spread about the digit's own modulus, not a steel range its servo cannot bend.
"""

from __future__ import annotations

import pytest

from digits import write_digit
from flexdigit.calibrate.chapter3_twin import release_fit
from flexdigit.errors import ParameterError
from flexdigit.identify.chapter3_identification import RELEASE_SETTLING_TIMES, twin_identification
from flexdigit.identify.response import settling_formula_bias
from flexdigit.models.second_order import settling_time_from_wn
from flexdigit.params import RigParams, load_params
from flexdigit.reference import thesis_value
from flexdigit.report import ch3_identify, ch3_twin
from flexdigit.report.ch8_studies import REPORT_PARAMETERS
from flexdigit.report.chapter import ReportContext
from flexdigit.report.results import thesis_comparisons
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.studies.spec import load_spec
from flexdigit.twin.calibration import default_calibration, use_calibration
from flexdigit.twin.digit_calibration import calibration_for
from flexdigit.twin.twin import release_dynamics

#: The thesis geometry on 70 mm sections and 25 mm supports (tests/data/handmade_digits2/heavy_supports_10bit's,
#: on the thesis's 16-bit ADC): housed mode 7.34 rad/s, zeta 0.082, Ts = 6.6 s, past the fast report's 5 s record.
HEAVY_SUPPORTS = {
    "geometry": {
        "section_length_m": 0.07,
        "support_lengths_m": [0.025, 0.025, 0.025],
        "strip_length_m": 0.21,
        "digit_length_m": 0.285,
        "gauge_positions_m": [0.05, 0.14, 0.23],
    }
}
#: The thesis rig on a 10-bit +-5 V ADC (9.8 mV steps): a 20 mm release spans ~11 steps at gauge 1.
COARSE_ADC = {"sensors": {"adc_bits": 10}}
#: The thesis method's wn = 4/(zeta Ts) on the tip (the housed mode's own response) is high by the formula's own
#: bias on an exact second-order response (identify.response.settling_formula_bias: 2.4 % at zeta 0.082) and by the
#: %OS of one extremum: within twice that bias. Read off the 5 s record cut before it settled it was 71 % high.
THESIS_WN_BIASES = 2.0
#: Least squares on the whole record gives the housed mode back within issue 4's 3 % (test_twin_identification).
LSQ_RTOL = 0.03
#: The thesis rig on a 1.5 x 15 mm PEEK strip (tests/data/handmade_digits/peek_two_sections's): at the steel's
#: 195 GPa the thesis servo could not bend it.
PEEK = {
    "geometry": {"strip_thickness_m": 0.0015, "strip_width_m": 0.015},
    "material": {"youngs_modulus_pa": 3.6e9, "strip_density_kg_m3": 1320.0},
}
#: The thesis-tolerances spec's modulus range, 195-215 GPa about table 3.7's 205 GPa (studies/specs).
STEEL_E_PA = (195e9, 205e9, 215e9)
#: A scaled range's ends are the steel's ratios times the digit's modulus, to rounding.
SCALED_RTOL = 1e-12


def _fields():
    return tuple({name.split("[")[0] for name in REPORT_PARAMETERS})


def test_a_slow_release_is_recorded_until_it_settles(tmp_path):
    params = load_params(write_digit("thesis", tmp_path, **HEAVY_SUPPORTS))
    calibration = calibration_for(params)  # as reproduce --params runs it
    mode = release_dynamics(params, calibration)
    settling = settling_time_from_wn(mode.wn_housing_rad_s, mode.zeta_housing)
    assert settling > 5.0, "the digit no longer settles after the fast record: it tests nothing"
    with use_calibration(calibration):
        r = twin_identification(params, seed=0, fast=True)
    assert r.tip.t_s[-1] >= RELEASE_SETTLING_TIMES * settling - r.tip.dt_s
    thesis = r.tip_fits["thesis"]
    bias = float(settling_formula_bias([mode.zeta_housing])[0])
    assert thesis.features.settling_time_s < r.tip.t_s[-1]
    assert thesis.wn_rad_s == pytest.approx(mode.wn_housing_rad_s, rel=THESIS_WN_BIASES * bias)
    assert r.tip_fits["lsq"].wn_rad_s == pytest.approx(mode.wn_housing_rad_s, rel=LSQ_RTOL)


def test_the_thesis_rigs_release_record_is_as_long_as_before():
    # table 3.2's housed mode settles in 4/(zeta wn) = 4.50 s: the margin keeps it inside the fast report's 5 s (and
    # the full report's 8 s), so the thesis rig's 509 entries keep their records
    wn = thesis_value("digit.release_tests_with_housing.wn_avg_rad_s")
    zeta = thesis_value("digit.release_tests_with_housing.zeta_avg")
    assert RELEASE_SETTLING_TIMES * settling_time_from_wn(wn, zeta) < 5.0


def test_a_release_no_gauge_resolves_gives_the_reason_not_a_figure(tmp_path):
    params = load_params(write_digit("thesis", tmp_path, **COARSE_ADC))
    with use_calibration(calibration_for(params)):
        fit = release_fit(True, duration_s=5.0, seed=0, params=params)
    assert fit.refused is not None
    assert "no release record could be identified" in fit.refused
    assert fit.gauge_fit() is None
    assert fit.wn_rad_s != fit.wn_rad_s  # NaN: no figure


@pytest.mark.slow
def test_the_identification_chapter_of_a_coarse_digit_says_not_applicable(tmp_path):
    params = load_params(write_digit("thesis", tmp_path, **COARSE_ADC))
    with use_calibration(calibration_for(params)), thesis_comparisons(False):
        chapter = ch3_identify.build(ReportContext(out_dir=tmp_path, params=params, fast=True))
    ours = {e.key: e.ours for e in chapter.entries}
    # the thesis method's figure off the same record too (it read 56.8 rad/s off a 13.1 rad/s mode)
    for key in (
        "identify.digit.lsq.wn_rad_s",
        "identify.digit.lsq.zeta",
        "identify.digit.validation_corr2",
        "identify.digit.thesis.wn_rad_s",
        "identify.digit.thesis.zeta",
        "identify.digit.thesis.validation_corr2",
    ):
        assert str(ours[key]).startswith("not applicable: twin release_test:gauge1: cannot identify"), key
    # the tip of the same release (no ADC) is still identified, and the servo's steps
    assert isinstance(ours["identify.digit_tip.lsq.wn_rad_s"], float)
    assert isinstance(ours["identify.servo.lsq.wn_rad_s"], float)
    assert "(not identified)" in chapter.paragraphs[-1]


@pytest.mark.slow
def test_the_twin_chapter_of_a_coarse_digit_says_not_applicable(tmp_path):
    params = load_params(write_digit("thesis", tmp_path, **COARSE_ADC))
    with use_calibration(calibration_for(params)), thesis_comparisons(False):
        chapter = ch3_twin.build(ReportContext(out_dir=tmp_path, params=params, fast=True))
    ours = {e.key: e.ours for e in chapter.entries}
    for housing in ("with_housing", "without_housing"):
        for figure in ("wn_rad_s", "zeta"):
            key = f"twin.release_{housing}.{figure}"
            assert str(ours[key]).startswith("not applicable: no release record could be identified"), key
    assert "twin_release_tests" in [f.name for f in chapter.figures]  # the records are still drawn


def test_the_studies_ranges_are_scaled_to_a_peek_strip(tmp_path):
    params = load_params(write_digit("thesis", tmp_path, **PEEK))
    baseline = ParameterSet(params, default_calibration())
    with pytest.raises(ParameterError, match="reaches 1.95e\\+11"):  # the steel's range: the servo cannot bend it
        load_spec("thesis-tolerances", baseline=baseline, fields=_fields())
    spec = load_spec("thesis-tolerances", baseline=baseline, fields=_fields(), scaled=True)
    e = next(p for p in spec.parameters if p.name == "material.youngs_modulus_pa")
    assert e.low == pytest.approx(3.6e9 * STEEL_E_PA[0] / STEEL_E_PA[1], rel=SCALED_RTOL)
    assert e.high == pytest.approx(3.6e9 * STEEL_E_PA[2] / STEEL_E_PA[1], rel=SCALED_RTOL)
    assert "scaled" in e.source


def test_the_thesis_rigs_ranges_are_the_specs_own():
    spec = load_spec("thesis-tolerances", baseline=ParameterSet(RigParams(), default_calibration()), scaled=True)
    e = next(p for p in spec.parameters if p.name == "material.youngs_modulus_pa")
    assert (e.low, e.high) == (STEEL_E_PA[0], STEEL_E_PA[2])  # a ratio of 1: the spec's numbers as written

"""A design study with ``[design] calibration = "scaled"`` scores each design on the calibration the commands give
its exported file (issue 24, "one default"): the baseline's where the design keeps its structure, else the
baseline's scaled to the design by the laws of :mod:`flexdigit.twin.digit_calibration`. The default,
``"baseline"``, scores every design on the baseline's calibration unscaled (channels averaged for another gauge
count), as before: a 1.25 x design keeps the thesis rig's 10 mm support masses and its 0.27 m cable's stiffness
while ``flexdigit study design --export`` gives the commands the scaled one."""

from __future__ import annotations

import pytest

from digits import DIGITS
from flexdigit.params import RigParams
from flexdigit.studies.design_study import Candidate, design_calibration, design_parameter_set
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.twin.calibration import packaged_calibration
from flexdigit.twin.digit_calibration import calibration_for, twin_calibration

# The laws are products of ratios: rounding's worth of relative error
LAW_RTOL = 1e-12
THESIS = Candidate(3, "thesis", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.0)
BIG = Candidate(3, "thesis", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.25)


def test_the_thesis_design_keeps_the_packaged_calibration():
    ps = design_parameter_set(ParameterSet(), THESIS, calibration="scaled")
    assert ps.calibration == packaged_calibration()
    # another bridge, ADC, servo step or a second cable keep the structure, and the fitted values with it
    c = Candidate(3, "thesis", "full", 12, 219 / 1016, 5.715e-3, 5.0, 1.0)
    assert design_parameter_set(ParameterSet(), c, calibration="scaled").calibration == packaged_calibration()


def test_by_default_a_design_keeps_the_baselines_calibration():
    """The default (the report's showcase): the baseline's calibration as it is, a new gauge count's channels
    averaged."""
    assert design_parameter_set(ParameterSet(), BIG).calibration == packaged_calibration()
    six = design_parameter_set(ParameterSet(), Candidate(6, "equal", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.0))
    ref = packaged_calibration()
    assert six.calibration.channel_gain == pytest.approx([sum(ref.channel_gain) / 3] * 6, rel=LAW_RTOL)
    assert six.calibration.channel_offset_v == (0.0,) * 6


@pytest.mark.parametrize(
    "candidate",
    [
        Candidate(3, "thesis", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.25),
        Candidate(6, "equal", "full", 12, 219 / 1016, 8e-3, 5.0, 0.75),
        Candidate(4, "equal", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.0),
    ],
    ids=["size-1.25", "6-gauges-e8mm-size-0.75", "4-gauges"],
)
def test_a_design_is_scored_on_the_calibration_its_exported_file_gets(candidate):
    ps = design_parameter_set(ParameterSet(), candidate, calibration="scaled")
    assert ps.calibration == twin_calibration(ps.description())  # what `--params exported.toml` runs on


def test_a_resized_design_scales_its_supports_and_cable():
    ref = packaged_calibration()
    cal = design_parameter_set(ParameterSet(), BIG, calibration="scaled").calibration
    # 12.5 mm supports: a block l_s w 2e, 1.25 x the mass; the cable runs 1.25 x as far, k = EA / l
    assert cal.support_mass_kg == pytest.approx([1.25 * m for m in ref.support_mass_kg], rel=LAW_RTOL)
    assert cal.cable_stiffness_n_m == pytest.approx(ref.cable_stiffness_n_m / 1.25, rel=LAW_RTOL)
    assert cal.housing_ei_n_m2 == ref.housing_ei_n_m2  # a cross-section property: the section is unchanged
    # the gauges at the thesis's relative places keep their channels
    assert cal.channel_gain == pytest.approx(ref.channel_gain, rel=LAW_RTOL)
    # a longer digit is slower: its beta grows as its first mode falls (the materials keep their loss factor)
    assert cal.strip_beta_s > ref.strip_beta_s


def test_a_user_baseline_is_scaled_from_its_own_calibration():
    """A study about a user's digit (two sections, two full-bridge gauges) scales that digit's calibration, with
    that digit as the reference rig, not the thesis rig's."""
    params = RigParams.from_dict(DIGITS["two-sections"])
    own = calibration_for(params).replace(cable_stiffness_n_m=40_000.0)  # as if fitted to its records
    baseline = ParameterSet(params, own)
    assert design_calibration(baseline, params) == own
    c = Candidate(2, "equal", "full", 16, 219 / 254, 5.715e-3, 0.0, 1.25)
    ps = design_parameter_set(baseline, c, calibration="scaled")
    assert ps.calibration.cable_stiffness_n_m == pytest.approx(40_000.0 / 1.25, rel=LAW_RTOL)


def test_a_parameter_set_without_a_calibration_takes_the_digits_default():
    params = RigParams.from_dict(DIGITS["two-sections"])
    assert ParameterSet(params).calibration == twin_calibration(params) == calibration_for(params)
    assert ParameterSet().calibration == packaged_calibration()


def test_the_setting_is_read_from_the_spec_and_checked():
    from flexdigit.errors import ParameterError
    from flexdigit.studies.design_study import DesignSettings
    from flexdigit.studies.spec import spec_from_toml

    spec = spec_from_toml("[study]\nname = 'x'\n[design]\ncalibration = 'scaled'\n", source="spec.toml")
    assert DesignSettings.from_spec(spec).calibration == "scaled"
    assert DesignSettings().calibration == "baseline"
    bad = spec_from_toml("[study]\nname = 'x'\n[design]\ncalibration = 'fitted'\n", source="spec.toml")
    with pytest.raises(ParameterError, match=r"spec.toml: \[design\] calibration must be 'baseline' or 'scaled'"):
        DesignSettings.from_spec(bad)


def test_a_scaled_study_is_another_study():
    """A study on scaled calibrations does not resume the journal of one on the baseline's (whose fingerprint is
    the one it had before the setting existed: tests/studies/test_design_taper.py)."""
    import dataclasses

    from flexdigit.studies.design_study import DesignSettings, study_fingerprint
    from flexdigit.studies.spec import load_spec

    spec = load_spec("thesis-design")
    settings = DesignSettings.from_spec(spec)
    scaled = dataclasses.replace(settings, calibration="scaled")
    assert study_fingerprint(spec, scaled) != study_fingerprint(spec, settings)

"""The contact and gauge models a user builds from Python for a described digit take the digit's own calibration by
default (:func:`flexdigit.twin.digit_calibration.twin_calibration`), as the commands do: before, both defaulted to
the packaged thesis fit whatever the digit (docs/digits.md, "Not yet")."""

from __future__ import annotations

from digits import write_digit
from flexdigit.palpation.contact_estimation import ContactGaugeModel
from flexdigit.params import RigParams, load_params
from flexdigit.tactile.bounds import TwinGaugeModel
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.digit_calibration import twin_calibration


def test_a_described_digits_models_default_to_its_own_calibration(tmp_path):
    params = load_params(write_digit("two-sections", tmp_path))
    own = twin_calibration(params)
    assert own != default_calibration()  # two sections, two gauges: not the thesis fit
    assert TwinGaugeModel(params).calibration == own
    assert ContactGaugeModel(params).calibration == own
    # one value per gauge of this digit (the thesis fit has three)
    assert TwinGaugeModel(params).noise_v.shape == (2,)


def test_the_thesis_rigs_models_keep_the_packaged_calibration():
    assert TwinGaugeModel(RigParams()).calibration == default_calibration()
    assert ContactGaugeModel().calibration == default_calibration()

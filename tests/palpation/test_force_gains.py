"""Force control derived from the digit (issue 24, docs/digits.md "Not yet"): the loop's integral gain keeps the
thesis rig's crossover (gain x the force a command presses) on any digit, and the gauge model is the rig's own.

References: the thesis rig's own gains (30 commands / s / N, 4 commands / s: the loop chapter 8 of the report
runs, whose figures stay as they were); a 4:1 gearing divides the cable a command draws by 4, so the force a
command presses by about 4 (the contact statics are nearly linear over a 0.1 N press) and its gain is about 4 x 30
(the report's rule before: the rates per turn of the pulley); the true contact force of the twin for the hold.

Tolerances: ``GEAR_REL = 0.05``: the statics' force per command of the geared digit against a quarter of the
thesis rig's (0.0068 against 0.0266 / 4: 2.5 % off, the press not exactly linear); ``HOLD = 0.10``: the issue's
10 % of the setpoint, over the last 3 s of an 8 s hold; ``OVERSHOOT = 0.20``: the report's bound.
"""

from __future__ import annotations

import json

import pytest

from digits import DIGITS, write_digit
from flexdigit.cli import main
from flexdigit.palpation import palpation_studies as studies
from flexdigit.palpation.contact_estimation import ContactGaugeModel
from flexdigit.palpation.palpation import (
    THESIS_APPROACH_RATE,
    THESIS_FORCE_GAIN,
    force_gains,
    hold_force,
    rig_contact_model,
)
from flexdigit.params import RigParams
from flexdigit.rig.base import open_rig
from flexdigit.twin.contact import Tissue
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.records import release_orientation

GEAR_REL = 0.05
HOLD = 0.10
OVERSHOOT = 0.20


def _digit(name: str):
    params = RigParams.from_dict(DIGITS[name])
    orientation = release_orientation(params)  # hung tip down if it buckles tip up (the 0.5 m digit)
    return params, ContactGaugeModel(params, twin_calibration(params), orientation=orientation)


def test_the_thesis_rig_keeps_its_gains():
    gains = force_gains(ContactGaugeModel(), 0.1, region_m=(0.15, 0.27))
    assert gains["gain"] == THESIS_FORCE_GAIN == 30.0
    assert gains["approach_rate"] == THESIS_APPROACH_RATE == 4.0
    assert 0.02 < gains["force_per_command_n"] < 0.035  # "~0.03 N a whole command step presses" (ForceController)


def test_a_geared_digit_gets_the_gain_of_a_turn_of_its_pulley():
    params, model = _digit("six-gauges-geared")
    length = params.geometry.digit_length_m
    gains = force_gains(model, 0.1, region_m=(0.55 * length, length))
    assert gains["gain"] == pytest.approx(4.0 * THESIS_FORCE_GAIN, rel=GEAR_REL)
    assert gains["approach_rate"] == 4.0 * THESIS_APPROACH_RATE


@pytest.mark.parametrize("name", ["five-sections-eight-gauges", "four-sections-two-cables"])
def test_a_long_digit_and_a_pair_hold_their_force(name):
    """The 0.5 m digit pressed 0.011 N a command: with the thesis's gain it was 23 % short after 8 s."""
    params, model = _digit(name)
    length = params.geometry.digit_length_m
    placed = Tissue(0.55 * length, length + 0.08, 0.1 * length, 1000.0)  # the report's layout on a digit
    f = studies.force_study((1000.0,), duration_s=8.0, seed=2, model=model, placed=placed)
    run = f["runs"][0]
    assert abs(f["steady_error"][0]) < HOLD, f
    assert f["overshoot"][0] < OVERSHOOT
    assert run.gain > 1.3 * THESIS_FORCE_GAIN if name.startswith("five") else run.gain > THESIS_FORCE_GAIN


def test_the_rig_model_is_the_rigs_digit_and_calibration():
    """A 2-gauge digit's force hold without a model: read through its own calibration (before: the thesis rig's
    3-gauge calibration, refused for 2 gauges), on its twin's mount."""
    params = RigParams.from_dict(DIGITS["short"])
    calibration = twin_calibration(params)
    with open_rig("sim", params, seed=0, calibration=calibration, orientation="hanging", dt_s=0.005) as rig:
        model = rig_contact_model(rig)
        assert model.calibration == calibration
        assert model.orientation == "hanging"
        rig.place_tissue(Tissue(0.09, 0.23, 0.015, 1000.0))
        held = hold_force(rig, 0.1, duration_s=0.5, region_m=(0.09, 0.15))
    assert held.gain == force_gains(model, 0.1, region_m=(0.09, 0.15))["gain"]


def test_palpate_holds_force_on_a_digit_from_the_command_line(tmp_path, capsys):
    digit = write_digit("two-sections", tmp_path)
    tissue = tmp_path / "tissue.toml"
    tissue.write_text(
        '[tissue]\nname = "block"\nside = "cable"\nstart_mm = 121.0\nend_mm = 300.0\ngap_mm = 22.0\n'
        "modulus_n_m2 = 1000.0\n"
    )
    argv = ["palpate", "--params", str(digit), "--tissue", str(tissue), "--protocol", "hold", "--json"]
    assert main(argv) == 0
    held = json.loads(capsys.readouterr().out)
    assert held["kind"] == "force"
    assert held["scored_on"] == "true contact force (twin)"
    assert abs(held["steady_error"]) < HOLD, held["steady_error"]


def test_a_digits_gains_inside_its_calibration_context_scale_from_the_thesis_rig():
    """Inside `reproduce --params` the default calibration is the digit's (8 sections here): the thesis rig's force
    per command that the gains scale from must still be the thesis rig's own (it raised "housing_ei_n_m2 must have
    3 values" in the report's palpation chapter, and its cache would keep a value from whichever context came first)."""
    from flexdigit.palpation import palpation as module
    from flexdigit.twin.calibration import use_calibration

    params, model = _digit("five-sections-eight-gauges")
    length = params.geometry.digit_length_m
    module._thesis_force_per_command.cache_clear()
    outside = force_gains(model, 0.1, region_m=(0.55 * length, length))
    module._thesis_force_per_command.cache_clear()
    with use_calibration(model.calibration, "digit"):
        inside = force_gains(model, 0.1, region_m=(0.55 * length, length))
    assert inside["gain"] == outside["gain"]
    assert inside["gain"] > THESIS_FORCE_GAIN  # a long digit presses less a command: a larger gain

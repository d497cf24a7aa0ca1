"""Chapter 8 on a described digit takes the palpation library's layout and the digit's own calibration (issue 24
item 3): the sweep is ``palpate --params``'s, the gauge model the twin's, and no figure the chapter cannot stand
behind is reported as a number."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from flexdigit.models.cable import tip_rotation_per_command_deg
from flexdigit.palpation.palpation import PalpationProtocol, digit_protocol
from flexdigit.params import RigParams, load_params
from flexdigit.report import ch8_palpation
from flexdigit.report.ch8_palpation import DigitSetting, estimate_label
from flexdigit.twin.calibration import packaged_calibration
from flexdigit.twin.digit_calibration import twin_calibration

DIGITS = Path(__file__).resolve().parents[1] / "data" / "handmade_digits"


def _setting(name: str) -> DigitSetting:
    return DigitSetting(load_params(DIGITS / f"{name}.toml"), "vertical", True)


def test_a_fine_step_digit_sweeps_as_far_in_tip_rotation_as_the_thesis():
    # design front 30: 0.31 deg of tip a command (5.6 thesis commands' worth), gear ratio 1; scaled by the gear
    # ratio its sweep stopped at 149, 22 commands = 6.8 deg of tip past straight instead of the thesis's 38 deg
    digit = _setting("design_front_30_six_gauges_pair")
    sweep = digit.protocol(2)
    thesis_deg = 22 * tip_rotation_per_command_deg(RigParams())  # 8..30 at 1.735 deg a command (the cable model)
    step_deg = tip_rotation_per_command_deg(digit.params)
    assert sweep.tare_command == digit.params.actuator.equilibrium_command == 127
    assert abs((sweep.commands[-1] - sweep.tare_command) * step_deg - thesis_deg) <= step_deg  # within one step
    assert len(sweep.commands) == 12  # 8, 10, .., 30 each its own command on a finer servo


@pytest.mark.parametrize("name", ["design_front_30_six_gauges_pair", "four_sections_geared_eight"])
def test_the_chapter_sweeps_as_palpate_lays_the_sweep_out(name):
    digit = _setting(name)
    thesis = PalpationProtocol(commands=tuple(range(8, 31, 3)))
    model = digit.contact_model()
    assert digit.protocol(3) == digit_protocol(
        thesis, digit.params, laid_out=("commands", "tare_command", "settle_s"), model=model
    )
    # the thesis's command 20 (contact estimates) on a 3:1 geared digit straight at 8: 8 + 3 x 12
    if name == "four_sections_geared_eight":
        assert digit.command(12) == 44


def test_the_gauge_model_reads_the_digits_own_calibration():
    digit = _setting("seven_sections_pair_mixed")
    model = digit.contact_model(3)
    assert model.calibration == twin_calibration(digit.params)
    own, thesis = (np.asarray(c.channel_gain, dtype=float) for c in (model.calibration, packaged_calibration()))
    assert own.shape != thesis.shape or not np.allclose(own, thesis)  # seven sections: not the thesis's fit


def test_a_bayes_limit_below_the_prior_grid_is_not_reported_as_a_number():
    # the trial's seven-section pair: palpation.active.bayes_magnitude = 1.6e-16 (rounding of a posterior that sits
    # on the true setting), now a text; a limit the grid resolves stays the number it is
    text = ch8_palpation._resolved(1.6e-16, ch8_palpation.MASS_SPACING_REL)
    assert isinstance(text, str)
    assert text.startswith("not determined")
    assert ch8_palpation._resolved(0.08, ch8_palpation.MASS_SPACING_REL) == 0.08
    assert ch8_palpation._resolved(0.0123, ch8_palpation.HANG_STEP_M, 1000.0) == pytest.approx(12.3, rel=1e-12)


def test_the_force_figure_says_how_many_readings_the_estimate_averages():
    assert estimate_label(SimpleNamespace(region={})) == "estimate (one reading)"
    assert estimate_label(SimpleNamespace(region={"average_readings": 1})) == "estimate (one reading)"
    assert estimate_label(SimpleNamespace(region={"average_readings": 8})) == "estimate (mean of 8 readings)"


@pytest.mark.slow
def test_the_chapter_of_a_seven_section_pair_built_alone(tmp_path):
    # built outside `reproduce` (no use_calibration block): every model reads the digit's own calibration (before,
    # active sensing's gauge model read the thesis's 3-section fit and raised); ~20 s on one core
    from flexdigit.report.chapter import ReportContext

    params = load_params(DIGITS / "seven_sections_pair_mixed.toml")
    chapter = ch8_palpation.build(ReportContext(out_dir=tmp_path, params=params, fast=True))
    entries = {e.key: e.ours for e in chapter.entries}
    assert str(entries["palpation.active.bayes_magnitude"]).startswith("not determined")  # was 1.6e-16
    assert 0.0 < entries["palpation.active.bayes_position_mm"] < entries["palpation.active.single_bayes_position_mm"]
    assert abs(entries["palpation.stiffness.max_rel_error"]) < 4 * entries["palpation.stiffness.rel_bound"]
    assert "127..149 laid out from its straight command 127" in chapter.paragraphs[0]
    active = next(t for t in chapter.tables if t.key == "palpation.active")
    hang = next(r for r in active.rows if r[0].startswith("Bayes limit, one hang"))
    assert np.isnan(hang[2])  # its magnitude cell blank, as the entry
    assert hang[1] == pytest.approx(entries["palpation.active.bayes_position_mm"], rel=1e-12)


@pytest.mark.slow
def test_a_fine_step_digit_fits_its_stiffness(tmp_path):
    # design front 30 (0.31 deg of tip a command): swept 127..149 the digit never reached the body and the
    # stiffness bound's information matrix was singular (LinAlgError: the chapter failed in reproduce); ~7 s
    from flexdigit.report.chapter import ReportContext

    params = load_params(DIGITS / "design_front_30_six_gauges_pair.toml")
    chapter = ch8_palpation.build(ReportContext(out_dir=tmp_path, params=params, fast=True))
    entries = {e.key: e.ours for e in chapter.entries}
    assert abs(entries["palpation.stiffness.max_rel_error"]) < 4 * entries["palpation.stiffness.rel_bound"]
    assert abs(entries["palpation.scan.inclusion_error_mm"]) < 10.0  # issue 13: within 10 mm
    assert "127..250 laid out from its straight command 127" in chapter.paragraphs[0]

"""The built-in sweep laid out on a digit (issue 24: the thesis rig's 8..30 ran on every digit; on an antagonistic
pair, straight at 127, that is 119 commands the wrong way, a runaway at -124 deg; on a 0.31 deg servo 22 fine steps
that never reached the tissue).

References: the thesis rig's protocol itself (the layout must give it back unchanged); the digits' straight
commands from their files (127 for a pair, tests/digits.py); the tip rotation per command of the design study's
front design 30 from the trial report (0.31 deg) against the thesis rig's 1.735 (thesis 3.4, E 3.15 with r_M / e).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from digits import DIGITS
from flexdigit.errors import ParameterError
from flexdigit.palpation.palpation import (
    PalpationProtocol,
    check_sweep_commands,
    command_scale,
    digit_protocol,
    towards,
)
from flexdigit.params import RigParams, load_params

HANDMADE = Path(__file__).parents[1] / "data" / "handmade_digits"
PAIR = RigParams.from_dict(DIGITS["four-sections-two-cables"])
#: the thesis sweep's last command past straight (8..30)
THESIS_PAST = 22


def _coarse(times: float) -> RigParams:
    """The pair with a pulley ``times`` the thesis rig's 11.5 mm: ``times`` the tip rotation a command."""
    return RigParams.from_dict({**DIGITS["four-sections-two-cables"], "actuator": {"pulley_radius_m": 0.0115 * times}})


def test_on_the_thesis_rig_the_builtin_sweep_is_unchanged():
    assert digit_protocol(PalpationProtocol(), RigParams()) == PalpationProtocol()


def test_a_pair_sweeps_from_its_straight_command_towards_the_tissue():
    cable = digit_protocol(PalpationProtocol(), PAIR, "cable")
    assert cable.tare_command == 127
    assert cable.commands == tuple(range(127, 127 + THESIS_PAST + 1))
    opposite = digit_protocol(PalpationProtocol(), PAIR, "opposite")
    assert opposite.tare_command == 127
    assert opposite.commands == tuple(range(127, 127 - THESIS_PAST - 1, -1))


def test_a_finer_step_sweeps_as_far_in_tip_rotation():
    front30 = load_params(HANDMADE / "design_front_30_six_gauges_pair.toml")
    tip_deg = 1.735 / command_scale(front30)
    assert tip_deg == pytest.approx(0.31, abs=0.005)  # the trial report's figure
    laid = digit_protocol(PalpationProtocol(), front30)
    assert laid.tare_command == 127
    # 38 deg of tip at its last command, as on the thesis rig, to one of its commands
    assert abs((laid.commands[-1] - 127) * tip_deg - THESIS_PAST * 1.735) <= tip_deg
    assert len(laid.commands) == 23


def test_a_geared_digit_takes_its_gearing_per_thesis_command():
    geared = load_params(HANDMADE / "four_sections_geared_eight.toml")  # 3:1
    laid = digit_protocol(PalpationProtocol(commands=tuple(range(8, 31, 2))), geared)
    assert laid.commands == tuple(range(8, 8 + 3 * THESIS_PAST + 1, 6))


def test_a_coarser_step_keeps_each_command_once():
    coarse = _coarse(4.0)  # 4 thesis steps a command
    laid = digit_protocol(PalpationProtocol(), coarse)
    assert laid.commands == tuple(range(127, 127 + round(THESIS_PAST / 4) + 1))


def test_a_coarse_step_with_too_few_commands_is_refused():
    coarse = _coarse(8.0)
    with pytest.raises(ParameterError, match="fewer than 3 distinct commands"):
        digit_protocol(PalpationProtocol(commands=(8, 10, 12)), coarse)


def test_a_files_own_commands_are_kept_and_checked():
    mine = PalpationProtocol(commands=(8, 9, 10), tare_command=8)
    assert digit_protocol(mine, PAIR, laid_out=()) == mine
    with pytest.raises(ParameterError, match="command 8 bends this digit away .* straight command is 127"):
        check_sweep_commands(mine, PAIR, "cable")
    check_sweep_commands(PalpationProtocol(commands=(127, 130, 133), tare_command=127), PAIR, "cable")
    check_sweep_commands(mine, RigParams(), "cable")  # the thesis rig: its own


def test_a_single_cable_never_presses_the_other_side():
    assert towards(RigParams(), "cable") == 1
    assert towards(PAIR, "opposite") == -1
    with pytest.raises(ParameterError, match="single cable bends it towards its cable side only"):
        towards(RigParams(), "opposite")


def test_a_region_narrowed_to_the_tissues_end_keeps_two_grid_steps():
    """The 0.49 m section's contact centroid lies at soft-block's end (350 mm) of its region: the hold's search was
    narrowed to 349-350 mm, one grid step, and ContactEstimator refused it ('region_m' error, exit 2)."""
    from flexdigit.palpation.contact_estimation import ContactEstimator, ContactGaugeModel
    from flexdigit.palpation.palpation import force_region
    from flexdigit.twin.digit_calibration import twin_calibration

    params = load_params(HANDMADE / "one_long_section_full.toml")  # stands tip up
    model = ContactGaugeModel(params, twin_calibration(params))
    region = force_region(model, 0.1, region_m=(0.15, 0.35))
    low, high = region["region_m"]
    assert region["narrowed"]
    assert high == pytest.approx(0.35)
    assert high - low > 0.002
    ContactEstimator(model, region_m=region["region_m"]).fit()  # accepted

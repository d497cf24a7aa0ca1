"""The thesis's actuated protocol (table 7.1: commands 0, 20, 40 on a rig straight at 8, operating 8..43) on a
digit's own commands (issue 24: ``reproduce --params`` on a cable pair read chapter 7 at 0..40, 90+ commands the
wrong way of its straight 127, every gauge at a rail): one layout for ``flexdigit collect --params`` and the
report's chapter 7 (:func:`flexdigit.tactile.protocols.digit_commands`).

Hand figures: the fractions of the thesis's range are (0 - 8) / 35, (20 - 8) / 35 and (40 - 8) / 35; on a pair
straight at 127 operating 92..162 (35 a side) they are 127 - 8, 127 + 12 and 127 + 32; on the study's front
digit 11 (straight at 8, operating 8..26: 18 commands) 8 - 8 x 18/35 = 3.89, 8 + 12 x 18/35 = 14.17 and
8 + 32 x 18/35 = 24.46.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from flexdigit.params import RigParams, load_params
from flexdigit.tactile.protocols import load_protocol
from flexdigit.tactile.thesis_experiments import _digit_protocol
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import static_gauges_v

DIGITS2 = Path(__file__).resolve().parents[1] / "data" / "handmade_digits2"
PAIR = DIGITS2 / "pair_tiny_pretension_tiny_e.toml"


def test_a_pairs_actuated_protocol_bends_it_both_ways_inside_its_range():
    pair = load_params(PAIR)
    protocol = load_protocol("thesis-7.1", pair)
    assert protocol.actuation_commands == (119, 139, 159)
    low, high = pair.actuator.operating_commands
    straight = pair.actuator.equilibrium_command
    assert all(low <= c <= high for c in protocol.actuation_commands)
    assert min(protocol.actuation_commands) < straight < max(protocol.actuation_commands)
    assert "commands 119/139/159" in protocol.name
    assert protocol.sample_count == load_protocol("thesis-7.1").sample_count  # the same tests, at its commands
    # the twin's statics (noise-free) at those commands: the readings move both ways from the straight digit's; at
    # the thesis's 0..40 all of them are bent one way, 80-127 commands past straight
    cal = twin_calibration(pair)  # the digit's twin, as collect's
    commands = np.array([straight, *protocol.actuation_commands, 0, 20, 40])
    zeros = np.zeros(commands.size)
    volts = static_gauges_v(zeros, zeros, commands, params=pair, calibration=cal, adc=False)
    moved = np.sign(volts[1:, 0] - volts[0, 0])
    assert set(moved[:3]) == {-1.0, 1.0}
    assert len(set(moved[3:])) == 1


def test_the_thesis_rig_and_a_shorter_range_by_hand():
    assert load_protocol("thesis-7.1", RigParams()).actuation_commands == (0, 20, 40)
    front = load_params(DIGITS2 / "study_front11.toml")  # straight at 8, operating 8..26
    assert load_protocol("thesis-7.1", front).actuation_commands == (4, 14, 24)
    assert load_protocol("thesis-6.1", front).actuation_commands == ()  # not actuated: nothing to lay out


def test_collect_and_the_reports_chapter_7_lay_it_out_alike():
    from flexdigit.cli.collect import _digit_protocol as collect_protocol

    pair = load_params(PAIR)
    _, collected = collect_protocol(argparse.Namespace(params=str(PAIR), protocol="thesis-7.1", refine=1))
    assert _digit_protocol("thesis-7.1", pair) == collected

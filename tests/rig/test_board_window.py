"""The board's own ADC window checked against a digit's gauge chains at export (build) time (issue 24: a digit
whose amplified bridge swings past it built, then faulted "adc_rail" at run time; trial two's
stainless_eight_full_gains, gains 500..6000).

Reference: the firmware's conversion (firmware/flexdigit_board.c): a gauge's volts ride on 2.5 V into a 10-bit
ADC over 0..5 V, ``count = floor((v + 2.5) / (5 / 1024))``, and a count of 0 or 1023 faults "adc_rail". The
chain's output is proportional to its amplifier gain, so the gain the message suggests brings the swing to 95 % of
the window (within the 3 figures it is rounded down to).
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import pytest

from flexdigit.cli import main
from flexdigit.params import RigParams, load_params
from flexdigit.rig.gauge_rails import BOARD_FIT_SHARE, board_rail_lines, gauge_rails

DIGITS2 = Path(__file__).resolve().parents[1] / "data" / "handmade_digits2"
STAINLESS = DIGITS2 / "stainless_eight_full_gains.toml"
#: A suggested gain is rounded down to 3 significant figures: its swing lands at most 1 % under 95 % of the window
ROUNDING = 0.01


def _count(volts: float) -> int:
    """The firmware's ADC count of a gauge's volts (flexdigit_board.c), before the ADC's own clipping."""
    return math.floor((volts + 2.5) / (5.0 / 1024.0))


def _faults(params: RigParams) -> list[int]:
    """The gauges (1-based) whose swing over the operating range the board reads at count 0 or >= 1023."""
    return [r.gauge for r in gauge_rails(params) if _count(r.span_v[0]) <= 0 or _count(r.span_v[1]) >= 1023]


def test_the_thesis_rig_fits_the_board():
    assert _faults(RigParams()) == []
    assert board_rail_lines(RigParams()) == []


def test_a_railing_digit_is_named_gauge_by_gauge_with_the_gain_that_fits():
    stainless = load_params(STAINLESS)
    railing = _faults(stainless)
    assert railing == [6, 7, 8]  # gains 3000, 4000, 6000 of full bridges: +2.8, +3.2, +4.6 V at 59 deg
    lines = board_rail_lines(stainless)
    assert [int(re.match(r"\[sensors\] gauge (\d+) ", line)[1]) for line in lines] == railing
    reach = {r.gauge: r for r in gauge_rails(stainless)}
    gains = list(stainless.sensors.amplifier_gains_v_per_v)
    for gauge, line in zip(railing, lines, strict=True):
        assert f"{reach[gauge].span_v[1]:+.2f} V" in line
        assert "adc_rail" in line
        gains[gauge - 1] = float(re.search(r"<= ([0-9.]+) fits it", line)[1])
    fitted = dataclasses.replace(
        stainless, sensors=dataclasses.replace(stainless.sensors, amplifier_gains_v_per_v=tuple(gains))
    )
    assert _faults(fitted) == []
    assert board_rail_lines(fitted) == []
    top = 2.5 - 5.0 / 1024.0
    for r in gauge_rails(fitted):
        if r.gauge in railing:
            assert r.span_v[1] == pytest.approx(BOARD_FIT_SHARE * top, rel=ROUNDING)


def test_export_refuses_to_build_it_in_one_line(tmp_path, capsys):
    out = tmp_path / "ctrl.c"
    assert main(["export", "controller", "--params", str(STAINLESS), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    for said in (str(STAINLESS), "gauge 8 reads +0.00..+4.61 V", "adc_rail"):
        assert said in err
    assert not out.exists()
    assert not out.with_suffix(".h").exists()

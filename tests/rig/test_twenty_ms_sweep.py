"""Regression (issue-24 campaign, digit 0: a cable pair straight at 127): the report's 20 ms study mapped the
gauges over the thesis's commands 8..32, which bend a pair far backwards against the ADC's rail, so the map
found "the gauges did not change over the sweep" and ``reproduce --params`` failed its chapter 5. It sweeps the
digit's own range now, as ``run --params`` does (:func:`flexdigit.rig.rotation.sweep_commands`)."""

from __future__ import annotations

import pytest

from digit_campaign import campaign_digit
from flexdigit.params import RigParams
from flexdigit.rig import chapter5_studies
from flexdigit.rig.rotation import sweep_commands


class _Swept(Exception):
    pass


@pytest.mark.parametrize("fast", [True, False])
def test_the_twenty_ms_study_sweeps_the_digits_own_range(fast, monkeypatch):
    asked = []

    def calibrate_rotation(rig, commands, **kwargs):
        asked.append(tuple(commands))
        raise _Swept

    monkeypatch.setattr(chapter5_studies, "calibrate_rotation", calibrate_rotation)
    pair = RigParams.from_dict(campaign_digit(0))
    with pytest.raises(_Swept):
        chapter5_studies.twenty_ms_study(pair, fast=fast)
    with pytest.raises(_Swept):
        chapter5_studies.twenty_ms_study(RigParams(), fast=fast)
    digit, thesis = asked
    assert min(digit) < pair.actuator.equilibrium_command == 127 < max(digit)  # both ways about straight
    assert set(digit) <= set(sweep_commands(pair))
    assert thesis == ((8, 14, 20, 26, 32) if fast else (8, 11, 14, 17, 20, 23, 26, 29, 32))  # chapter 5's own

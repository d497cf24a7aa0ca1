"""The DAQ backend with a fake uldaq module: channel/range mapping (table 2.2) and the missing-package message."""

from __future__ import annotations

import builtins
import enum
import types

import numpy as np
import pytest

from digits import _equal as equal_positions
from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams, Sensors
from flexdigit.rig.backends.daq_backend import MISSING_ULDAQ, DaqRig, uldaq_range
from flexdigit.rig.base import open_rig


def fake_uldaq(voltages):
    """Enough of uldaq's API (names checked against uldaq 1.2.3) to record what the backend asks for."""
    calls = []

    class Range(enum.IntEnum):
        BIP10VOLTS = 1
        BIP5VOLTS = 6
        BIP2VOLTS = 9

    class AiInputMode(enum.IntEnum):
        DIFFERENTIAL = 1
        SINGLE_ENDED = 2

    class Ai:
        def a_in(self, channel, mode, rng, flags):
            calls.append((channel, mode, rng, flags))
            return voltages[channel]

    class Device:
        def __init__(self, descriptor):
            self.descriptor = descriptor
            self.state = "new"

        def connect(self):
            self.state = "connected"

        def get_ai_device(self):
            return Ai()

        def disconnect(self):
            self.state = "disconnected"

        def release(self):
            self.state = "released"

    mod = types.SimpleNamespace(
        Range=Range,
        AiInputMode=AiInputMode,
        AInFlag=types.SimpleNamespace(DEFAULT=0),
        InterfaceType=types.SimpleNamespace(ANY=7),
        get_daq_device_inventory=lambda interface: ["PCI-DAS1602/16"],
        DaqDevice=Device,
        calls=calls,
    )
    return mod


def test_reads_gauge_channels_0_1_2_at_plus_minus_5v():
    ul = fake_uldaq({0: 0.1, 1: -0.2, 2: 0.3, 3: 9.9})
    rig = DaqRig(0, uldaq=ul)
    reading = rig.read()
    np.testing.assert_allclose(reading.gauges_v, [0.1, -0.2, 0.3])
    assert [c[0] for c in ul.calls] == [0, 1, 2]  # table 2.2: Ch 0, 1, 2 high
    assert {c[2] for c in ul.calls} == {ul.Range.BIP5VOLTS}  # 2.5.1: +-5 V
    assert {c[1] for c in ul.calls} == {ul.AiInputMode.SINGLE_ENDED}
    assert np.isnan(reading.pot_v)
    with pytest.raises(RigError, match="cannot move the servo"):
        rig.write_command(20)
    rig.close()
    assert rig._device.state == "released"


def test_channels_and_range_come_from_params():
    ul = fake_uldaq({4: 1.0, 5: 2.0, 6: 3.0})
    params = RigParams().replace(sensors=Sensors(adc_channels=(4, 5, 6), adc_range_v=(-10.0, 10.0)))
    rig = DaqRig(0, params, uldaq=ul, input_mode="differential")
    np.testing.assert_allclose(rig.read().gauges_v, [1.0, 2.0, 3.0])
    assert {c[2] for c in ul.calls} == {ul.Range.BIP10VOLTS}
    with pytest.raises(ParameterError, match="adc_range_v"):
        uldaq_range((0.0, 5.0), ul)


def test_missing_board_is_a_rig_error():
    with pytest.raises(RigError, match="no such MCC device; found 1"):
        DaqRig(3, uldaq=fake_uldaq({}))


def test_missing_uldaq_gives_an_install_hint(monkeypatch):
    real_import = builtins.__import__

    def no_uldaq(name, *args, **kwargs):
        if name == "uldaq":
            raise ImportError("No module named 'uldaq'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_uldaq)
    with pytest.raises(RigError, match="optional 'uldaq' package") as info:
        open_rig("daq://0")
    assert str(info.value) == MISSING_ULDAQ


def test_pot_channel_from_the_url_is_read_after_the_gauges():
    # 3.2.4 wires the pot to "one of the channels" of the card; the value is whatever that channel reads
    ul = fake_uldaq({0: 0.1, 1: -0.2, 2: 0.3, 3: 1.47})
    rig = open_rig("daq://0?pot=3", uldaq=ul)
    reading = rig.read()
    np.testing.assert_allclose(reading.gauges_v, [0.1, -0.2, 0.3])
    assert reading.pot_v == 1.47
    assert [c[0] for c in ul.calls] == [0, 1, 2, 3]
    assert {c[2] for c in ul.calls} == {ul.Range.BIP5VOLTS}  # same +-5 V range (the pot spans 0.47..2.48 V)
    rig.close()
    # no pot option, or pot=none: NaN as before, and channel 3 is never read
    for url in ("daq://0", "daq://0?pot=none"):
        ul = fake_uldaq({0: 0.1, 1: -0.2, 2: 0.3, 3: 1.47})
        assert np.isnan(open_rig(url, uldaq=ul).read().pot_v)
        assert [c[0] for c in ul.calls] == [0, 1, 2]


@pytest.mark.parametrize(
    ("url", "match"),
    [
        ("daq://0?pot=x", r"option pot='x' must be an integer inside \[0, inf\) or 'none' \(the analog input"),
        ("daq://0?pot=-1", r"option pot='-1' must be an integer inside \[0, inf\) or 'none'"),
        ("daq://0?pot=1", r"'pot_channel' parameter of DaqRig must differ from the gauge channels \(0, 1, 2\)\. Got 1"),
        ("daq://0?pots=3", "unknown option 'pots'; a daq URL takes pot, input_mode"),
    ],
)
def test_bad_pot_option_names_the_option_and_value(url, match):
    with pytest.raises(ParameterError, match=match):
        open_rig(url, uldaq=fake_uldaq({}))


@pytest.mark.parametrize("count", [1, 5, 8])
def test_a_digit_of_g_gauges_reads_g_channels_then_the_pot(count, tmp_path):
    """A ``params`` digit of ``count`` gauges on channels 0..G-1 (issue 24): G values, the pot on the next channel."""
    volts = {ch: 0.1 * (ch + 1) for ch in range(count)} | {count: 1.47}
    params = RigParams.from_dict(
        {
            "geometry": {"gauge_positions_m": equal_positions(count, 0.27)},
            "sensors": {"adc_channels": list(range(count))},
        }
    )
    rig = open_rig(f"daq://0?pot={count}", params, uldaq=(ul := fake_uldaq(volts)))
    reading = rig.read()
    np.testing.assert_allclose(reading.gauges_v, [0.1 * (ch + 1) for ch in range(count)])
    assert reading.pot_v == 1.47
    assert [c[0] for c in ul.calls] == [*range(count), count]
    rig.close()

"""A digit of 7 or 8 gauges on the reference firmware (issue 24 item 5): the ATmega328P's ADC6 and ADC7.

An Uno's DIP ATmega328P brings out ADC0..ADC5 (A0..A5); the TQFP/MLF package of an Arduino Nano or Pro Mini also
has ADC6 and ADC7 (A6, A7: analogue-only inputs), which simavr's ATmega328P core converts like the others
(simavr/cores/sim_megax8.h: ``[6] = AVR_ADC_SINGLE(6), [7] = AVR_ADC_SINGLE(7)`` in the ADC's mux table). The image
of a 7- or 8-gauge digit is built for such a board (``target=nano adc_channels=8`` in its banner); the host refuses
a digit of more gauges than its board declares, in one line.

References: the ATmega328P datasheet (24.7: ADC = Vin x 1024 / Vref, truncated) for the emulated pins; issue 24's
step figures (settling < 1 s, overshoot < 10 %, within 2 % of the setpoint) on the twin's true rotation; and
flexdigit's Python loop on the twin (``flexdigit run --params``, same design, period and rotation map, its servo
driven as the board's Timer1 drives it, the pulse the image's 5 ms after the tick) by issue 25's criteria.
"""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
import serial

from flexdigit.cli import main
from flexdigit.errors import ParameterError
from flexdigit.params import load_params
from flexdigit.rig.backends.board_backend import BoardRig
from flexdigit.rig.backends.stream_framing import encode_line
from flexdigit.rig.base import open_rig

from .board_helpers import compare_steps

#: Issue 24's step figures: settling (2 %) under 1 s, overshoot under 10 %, the true final rotation within 2 %.
SETTLING_LIMIT_S, OVERSHOOT_LIMIT_PERCENT, FINAL_FRACTION = 1.0, 10.0, 0.02
#: The noise seeds of the board/Python comparison: a typical figure over seeds, as test_board.py's (one seed decides
#: nothing: a peak near the 2 % band moves the settling time by a whole oscillation). Four keep the test under a
#: minute; the eight-gauge digit's figures spread less by seed than the thesis rig's at 2 ms (0.53 s +- 0.01 s).
STEP_SEEDS = range(4)
#: The firmware's sources (firmware/) and the stream protocol's header (examples/flexdigit_stream/).
FIRMWARE = Path(__file__).resolve().parents[2] / "firmware"
STREAM_H = FIRMWARE.parent / "examples" / "flexdigit_stream"
#: A Nano's flash less its old 2 kB bootloader (the new Optiboot takes 512 bytes) and the ATmega328P's RAM, bytes.
NANO_FLASH_BYTES, RAM_BYTES = 30_720, 2_048
#: The image's servo pulse after the control tick, ms (a digit's image: firmware/Makefile's PULSE_DELAY_MS).
DIGIT_PULSE_DELAY_MS = 5


def _banner(doc: dict) -> str:
    return " ".join(doc["board"]["info_lines"])


@pytest.mark.slow
@pytest.mark.parametrize("gauges", [7, 8])
def test_a_digit_of_seven_or_eight_gauges_holds_its_step_on_a_nano(mapped_digit_firmware, capsys, gauges):
    elf, params, _ = mapped_digit_firmware(gauges)  # -Werror: a warning fails the build
    out = subprocess.run(["avr-size", "-A", str(elf)], capture_output=True, text=True, check=True).stdout
    sizes = {line.split()[0]: int(line.split()[1]) for line in out.splitlines() if line.startswith(".")}
    assert sizes[".text"] + sizes.get(".data", 0) < NANO_FLASH_BYTES
    assert sizes.get(".data", 0) + sizes.get(".bss", 0) < RAM_BYTES - 512  # room for the stack
    args = ["run", "--on-board", "--params", str(params), "--backend", f"hil://{elf}", "--duration", "2"]
    assert main([*args, "--setpoint-deg", "30", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert f"gauges={gauges} " in _banner(doc)
    assert "target=nano adc_channels=8" in _banner(doc)  # the board it needs: A6 (and A7)
    assert doc["board"]["faults"] == []
    m = doc["step_metrics"]["true"]
    assert m["settling_time_s"] < SETTLING_LIMIT_S
    assert m["overshoot_percent"] < OVERSHOOT_LIMIT_PERCENT
    assert abs(doc["true_final_rotation_deg"] - 30.0) < FINAL_FRACTION * 30.0


@pytest.mark.slow
def test_the_emulated_adc6_and_adc7_convert_as_the_datasheet_says(mapped_digit_firmware):
    """The gauges on ADC6 and ADC7 are read as the others (the board streams each count less 512)."""
    elf, path, _ = mapped_digit_firmware(8)
    rng = np.random.default_rng(11)
    with open_rig(f"hil://{elf}", load_params(path), mode="host") as rig:
        for gauge_v in rng.uniform(-2.49, 2.49, 6):
            rig.gauge_override = {6: gauge_v, 7: -gauge_v / 3}
            rig.wait(0.045)  # two stream lines (20 ms): the newest used the new volts
            pins_v = [2.5 + round(v * 1e4) / 1e4 for v in (gauge_v, -gauge_v / 3)]  # 0.1 mV on the pins
            assert rig.latest.gauges[6:] == tuple(math.floor(v * 1024 / 5.0) - 512 for v in pins_v), f"{gauge_v:+.4f}"
            assert len(rig.latest.gauges) == 8


@pytest.mark.slow
def test_an_eight_gauge_digits_step_on_the_board_is_the_python_loops(mapped_digit_firmware):
    """The loop on the board against flexdigit's loop on the twin, same design, period, map and servo timing."""
    elf, params, rotation_map = mapped_digit_firmware(8)
    board, _ = compare_steps(elf, 0.020, rotation_map, STEP_SEEDS, params, pulse_delay_ms=DIGIT_PULSE_DELAY_MS)
    assert board["settling_time_s"] < SETTLING_LIMIT_S


def test_an_eight_gauge_digit_on_a_board_declaring_six_inputs_is_refused_in_one_line(tmp_path):
    """A board whose image was built for an Uno (its banner: 6 analogue inputs) cannot read an 8-gauge digit."""
    from digits import write_digit

    params = load_params(write_digit("five-sections-eight-gauges", tmp_path))
    port = serial.serial_for_url("loop://", timeout=0)
    port.write(b"# flexdigit-stream 2 period_us=20000 gauges=8 straight=8 range=0..254 target=uno adc_channels=6\r\n")
    port.write(encode_line(0, 0, [0] * 8, pot=8, rotation_udeg=0))
    now = [0.0]

    def sleep(seconds):
        now[0] += seconds

    with pytest.raises(ParameterError) as refused:
        BoardRig("loop", params, serial=port, clock=lambda: now[0], sleep=sleep, startup=0.5)
    message = str(refused.value)
    assert "the board declares 6 analogue inputs (uno: A0..A5); the digit has 8 gauges" in message
    assert "BOARD=nano" in message
    assert "\n" not in message
    assert not port.is_open


def test_an_uno_image_of_eight_gauges_does_not_build(tmp_path):
    """``make BOARD=uno`` for an 8-gauge digit: the compiler's #error, naming the Nano (no image is made)."""
    ctrl_h = tmp_path / "ctrl.h"
    ctrl_h.write_text(
        "#define FD_CTRL_HAS_MEASURE 1\n#define FD_CTRL_GAUGES 8\n#define FD_CTRL_PERIOD_US 20000UL\n"
        "#define FD_CTRL_COMMAND_EQ 8\n#define FD_CTRL_COMMAND_MIN 0\n#define FD_CTRL_COMMAND_MAX 254\n"
        "#define FD_CTRL_FIXED_POINT 0\n#define FD_CTRL_OK 0\n#define FD_CTRL_SETPOINT_SCALE 1.0f\n"
        "typedef struct { float x; } fd_ctrl_t;\n"
    )
    cmd = ["avr-gcc", "-mmcu=atmega328p", "-DF_CPU=16000000UL", "-DBOARD_ADC_CHANNELS=6", "-std=c99", "-fsyntax-only"]
    cmd += [f"-I{tmp_path}", f"-I{STREAM_H}", str(FIRMWARE / "flexdigit_board.c")]
    done = subprocess.run(cmd, capture_output=True, text=True)
    assert done.returncode != 0
    assert "the Uno reads at most 6 gauges" in done.stderr
    assert "make BOARD=nano" in done.stderr

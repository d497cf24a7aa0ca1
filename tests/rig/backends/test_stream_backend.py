"""``stream://``: the protocol on bytes, the source on a pty fed by hand, and the whole rig against the emulator.

Independent oracles: the CRC's published check value (CRC-16/XMODEM of "123456789" is 0x31C3), lines the tests
build themselves with ``binascii.crc_hqx`` (not the package's encoder), the reference firmware's C code compiled by
gcc (its lines must decode), and the emulator's twin's own tip rotation for the closed loop.
"""

from __future__ import annotations

import binascii
import math
import os
import shutil
import subprocess
import sys
import time
import tty

import numpy as np
import pytest

from flexdigit.errors import ParameterError, RigError
from flexdigit.rig.backends.stream_backend import StreamRig, StreamSource
from flexdigit.rig.backends.stream_emulator import Faults, StreamEmulator
from flexdigit.rig.backends.stream_framing import LineDecoder, crc16_xmodem, decode_line, encode_line
from flexdigit.rig.base import open_rig
from flexdigit.rig.loop import run_loop
from flexdigit.rig.sample_log import read_log
from oracles import eventually

from ..helpers import HostOpens

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="needs os.openpty")

EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "..", "..", "examples", "flexdigit_stream")


def hand_line(seq, t_us, *values) -> bytes:
    """A protocol line built here, independently of the package's encoder."""
    payload = ",".join(str(v) for v in (seq, t_us, *values)).encode()
    return b"$" + payload + b"*%04x\n" % binascii.crc_hqx(payload, 0)


# -- the protocol on bytes -------------------------------------------------------------------------------------
def test_crc_is_the_published_xmodem_check_value():
    assert crc16_xmodem(b"123456789") == 0x31C3  # CRC catalogue, CRC-16/XMODEM "check"


def test_lines_round_trip_and_split_anywhere():
    rng = np.random.default_rng(0)
    lines, samples = b"", []
    for seq in range(200):
        gauges = tuple(int(v) for v in rng.integers(-32768, 32768, 3))
        pot = None if seq % 3 else int(rng.integers(0, 1024))
        lines += encode_line(seq, seq * 10_000, gauges, pot)
        samples.append((seq, seq * 10_000, gauges, pot))
    decoder, events = LineDecoder(), []
    cuts = np.sort(rng.integers(0, len(lines), 300))
    for a, b in zip([0, *cuts], [*cuts, len(lines)], strict=True):
        events += decoder.feed(lines[a:b])  # a line cut anywhere is kept until its newline comes
    assert [(e.sample.seq, e.sample.t_us, e.sample.gauges, e.sample.pot) for e in events] == samples
    assert decode_line(hand_line(5, 7, 1, -2, 3)[:-1]).sample.gauges == (1, -2, 3)  # lower-case hex is fine


def test_every_single_byte_error_is_caught():
    # CRC-16 detects every burst of up to 16 bits: no one-byte change can decode as a (different) valid sample
    line = encode_line(4242, 123456789, (-1200, 30500, 7), 512)[:-2]
    for i in range(len(line)):
        for byte in b"0123456789-,$*ABCDEF#x":
            if byte == line[i]:
                continue
            event = decode_line(line[:i] + bytes([byte]) + line[i + 1 :])
            assert event.kind != "sample", (i, chr(byte))


@pytest.mark.parametrize(
    ("line", "reason"),
    [
        (b"7,100,1,2,3*0000", "no '$'"),
        (b"$7,100,1,2,3", "no '*'"),
        (b"$7,100,1,2,3*zzzz", "not hexadecimal"),
        (hand_line(7, 100, 1, 2)[:-1], "4 fields"),
        (hand_line(7, 100, 1, 2, "x")[:-1], "not an integer"),
        (hand_line(70000, 100, 1, 2, 3)[:-1], "out of range"),
    ],
)
def test_garbled_lines_say_why(line, reason):
    event = decode_line(line)
    assert event.kind == "garbled"
    assert reason in event.reason


def test_a_runaway_line_is_dropped_not_buffered():
    decoder = LineDecoder()
    assert [e.reason for e in decoder.feed(b"x" * 500)] == ["no line end in 200 bytes"]
    assert decoder.feed(hand_line(1, 2, 3, 4, 5))[0].sample.gauges == (3, 4, 5)


# -- the source on a pty fed by hand -----------------------------------------------------------------------------
@pytest.fixture
def pty_port():
    master, slave = os.openpty()
    tty.setraw(slave)
    yield master, os.ttyname(slave)
    for fd in (master, slave):
        try:
            os.close(fd)
        except OSError:
            pass


def send_when_opened(master, data: bytes) -> None:
    """Write to the pty once the source has opened it (pyserial empties the input buffer when it opens a port)."""
    HostOpens(master).send(data)


def test_source_reads_volts_counts_gaps_and_refuses_another_protocol_version(pty_port):
    master, port = pty_port
    send_when_opened(master, b"# flexdigit-stream 1 adc=test\n" + hand_line(0, 0, 800, -1600, 2400, 4000))
    source = StreamSource(port, scale=0.000125, pot_scale=0.005, startup=2.0)
    gauges, pot = source.read_gauges()
    np.testing.assert_allclose(gauges, [0.1, -0.2, 0.3])  # counts x 125 uV
    assert pot == pytest.approx(20.0)
    os.write(master, hand_line(3, 30_000, 8, 8, 8) + b"$3,1,2*FFFF\n")  # lines 1 and 2 lost, then garbage
    assert eventually(lambda: source.stats()["garbled"] >= 1, timeout_s=30.0)
    stats = source.stats()
    assert (stats["samples"], stats["dropped"], stats["garbled"], stats["info"]) == (2, 2, 1, 1)
    assert math.isnan(source.read_gauges()[1])  # this line has no pot
    os.write(master, b"# flexdigit-stream 3 adc=future\n")
    assert eventually(lambda: source.stats()["info"] == 2, timeout_s=30.0)  # read: the refusal is set with it
    with pytest.raises(RigError, match="protocol 3; this flexdigit reads versions 1 and 2"):
        source.read_gauges()
    source.close()
    assert source.closed


def test_a_silent_board_is_refused_at_open_naming_the_baud(pty_port):
    _, port = pty_port
    with pytest.raises(RigError, match="no valid line within 0.2 s.*baud=57600"):
        StreamSource(port, baud=57600, startup=0.2)


def test_a_gauge_on_the_rail_is_a_sensor_fault(pty_port):
    master, port = pty_port
    send_when_opened(master, hand_line(0, 0, 1, 32767, 1))
    source = StreamSource(port, startup=2.0)
    with pytest.raises(RigError, match="gauge 2 at the stream ADC's rail"):
        source.read_gauges()
    source.close()


@pytest.mark.parametrize(
    ("query", "match"),
    [
        ("rate=100", "unknown option 'rate'; a stream URL takes baud, scale"),
        ("baud=fast", "option baud='fast' must be an integer"),
        ("timeout=0", r"option timeout=.0. must be a finite number inside \(0, 60\]"),
        ("max_bad=1.5", r"option max_bad=.1.5. must be a finite number inside \[0, 1\]"),
        ("bits=16.5", "option bits='16.5' must be an integer"),
    ],
)
def test_bad_stream_options_name_the_option(query, match):
    with pytest.raises(ParameterError, match=match):
        open_rig(f"stream:///dev/null?{query}")


# -- end to end against the emulator ------------------------------------------------------------------------------
def test_stream_rig_reads_the_emulator_and_cannot_move_the_servo():
    with StreamEmulator(seed=3) as emulator:
        rig = open_rig(f"stream://{emulator.port}?timeout=0.5")
        assert isinstance(rig, StreamRig)
        readings = []
        for _ in range(10):
            rig.wait(0.03)  # the stream runs at 100 lines/s: a fresh line between reads
            readings.append(rig.read())
        # the emulator's resting digit: 0.1, 0.5, 0.2 V with 2 mV of noise, quantised to 125 uV
        np.testing.assert_allclose(np.mean([r.gauges_v for r in readings], axis=0), [0.1, 0.5, 0.2], atol=0.005)
        with pytest.raises(RigError, match="cannot move the servo"):
            rig.write_command(20)
        stats = rig.stats()  # (the banner went out before the port was opened: pyserial empties it on opening)
        assert stats["samples"] >= 10
        assert stats["garbled"] == 0
        assert stats["dropped"] == 0
        rig.close()
        emulator.close()


@pytest.fixture(scope="module")
def rotation_map():
    from flexdigit.rig.rotation import calibrate_rotation

    # the emulator's twin is the default twin: its map, calibrated on another twin in virtual time
    return calibrate_rotation(open_rig("sim", seed=1))


def closed_loop(emulator, rotation_map, tmp_path, duration_s=2.0, **daq):
    from flexdigit.rig.controllers import make_controller

    query = "".join(f"&daq.{k}={v}" for k, v in daq.items())
    rig = open_rig(f"serial://{emulator.servo_port}?daq=stream://{emulator.port}{query}")
    controller = make_controller("digital20", rig, estimator=rotation_map)
    log = tmp_path / "run.jsonl"
    result = run_loop(rig, controller, 20.0, duration_s, log_path=log)
    return rig, result, log


@pytest.mark.slow
def test_the_whole_rig_closes_the_loop_through_the_stream(rotation_map, tmp_path):
    with StreamEmulator(twin=True, seed=0) as emulator:
        # (daq.timeout: a pause of the emulator's thread on a loaded machine is not a silent stream here)
        rig, result, log = closed_loop(emulator, rotation_map, tmp_path, timeout=5)
        assert result.ok, result.message
        # the emulator's twin (true rotation) followed the 20 deg step within one command quantum (1.7 deg)
        assert abs(emulator.tip_rotation_deg() - 20.0) < 1.7
        stats = rig.companions[0].stats()
        assert stats["samples"] > 150
        assert stats["garbled"] == 0
        assert stats["dropped"] == 0
        assert eventually(lambda: emulator.commands[-1] == 8, timeout_s=30.0)
        assert rig.closed  # relaxed and released at the end


@pytest.mark.slow
@pytest.mark.parametrize(
    ("faults", "match"),
    [(Faults(stop_after=150), "stream silent"), (Faults(garble_after=150), "stream garbled")],
    ids=["stops", "garbles"],
)
def test_a_stream_that_stops_or_garbles_mid_run_ends_in_the_safe_state(rotation_map, tmp_path, faults, match):
    with StreamEmulator(twin=True, seed=1, faults=faults) as emulator:
        # the garbled stream's run: a pause of the emulator's thread on a loaded machine is not a silent stream
        daq = {"timeout": 5} if faults.garble_after is not None else {}
        rig, result, log = closed_loop(emulator, rotation_map, tmp_path, duration_s=4.0, **daq)
        assert result.status == "fault", result.message
        assert match in result.message, result.message
        assert result.safe_command_sent
        assert "relaxed to command 8" in result.message
        assert eventually(lambda: emulator.commands[-1] == 8, timeout_s=30.0)  # the board got the safe command
        assert rig.closed
        assert rig.companions[0].closed  # both ports released
        header, samples, footer = read_log(log)
        assert footer["stop"] == "fault"
        assert match in footer["message"]
        assert 0.5 < samples[-1]["t"] < 3.5  # it ran, then stopped at the fault (150 lines = 1.5 s of stream)


def test_a_vanishing_stream_port_is_a_rig_error():
    emulator = StreamEmulator(seed=2)
    source = StreamSource(emulator.port, startup=2.0)
    source.read_gauges()
    emulator.close()  # the board is unplugged: the pty's far end closes
    deadline = time.monotonic() + 30
    with pytest.raises(RigError, match="port failed|stream silent"):
        while time.monotonic() < deadline:
            source.read_gauges()
            time.sleep(0.02)
    source.close()


@pytest.mark.parametrize(
    ("url", "match"),
    [
        ("serial://loop://?daq=stream:///dev/null&pot=3", "a stream sends the pot in its lines"),
        ("serial://loop://?daq=stream:///dev/null&daq.rate=5", "unknown option 'rate'; a stream URL takes"),
        ("serial://loop://?daq=ftp://x", "daq=.* must be a board number, daq://BOARD or stream://PORT"),
        ("serial://loop://?daq=%C2%B2", "daq=.* must be a board number"),  # '²': int() raised ValueError
        ("serial://loop://?daq.baud=5", "daq.baud needs a gauge source"),
    ],
)
def test_serial_with_a_bad_stream_option_names_it(url, match):
    with pytest.raises(ParameterError, match=match):
        open_rig(url)


# -- the reference firmware's C code -----------------------------------------------------------------------------
@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler to build the firmware's protocol code")
def test_the_firmware_lines_decode(tmp_path):
    main = tmp_path / "main.c"
    main.write_text(
        '#include "flexdigit_stream.h"\n'
        "int main(void) {\n"
        "  char line[FLEXDIGIT_STREAM_LINE_MAX];\n"
        "  int n = flexdigit_format_line(line, 65535, 4294967295UL, -2147483647L - 1, 2147483647L, 0, 1, -5);\n"
        "  fwrite(line, 1, n, stdout);\n"
        "  n = flexdigit_format_line(line, 0, 1000, 120, -45, 3000, 0, 0);\n"
        "  fwrite(line, 1, n, stdout);\n"
        "  return 0;\n"
        "}\n"
    )
    exe = tmp_path / "fw"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", "-I", EXAMPLES, str(main), "-o", str(exe)], check=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True).stdout
    events = LineDecoder().feed(out)
    assert [e.kind for e in events] == ["sample", "sample"]
    assert events[0].sample.seq == 65535
    assert events[0].sample.t_us == 4294967295
    assert events[0].sample.gauges == (-2147483648, 2147483647, 0)
    assert events[0].sample.pot == -5
    assert events[1].sample.gauges == (120, -45, 3000)
    assert events[1].sample.pot is None
    assert out.splitlines()[1] + b"\n" == encode_line(0, 1000, (120, -45, 3000)).replace(b"\r", b"")


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler to build the firmware's protocol code")
def test_the_firmware_version_2_lines_decode_for_one_to_eight_gauges(tmp_path):
    main = tmp_path / "main.c"
    main.write_text(
        '#include "flexdigit_stream.h"\n'
        "int main(void) {\n"
        "  char line[FLEXDIGIT_STREAM_LINE_MAX];\n"
        "  int32_t g[8] = {-2147483647L - 1, 2147483647L, 3, -4, 5, -6, 7, -8};\n"
        "  for (int count = 0; count <= 9; count++) {\n"
        "    uint16_t seq = (uint16_t)(65530 + count);\n"
        "    int n = flexdigit_format_line_v2(line, seq, 4294967295UL, g, count, count % 2, -5);\n"
        "    fwrite(line, 1, (size_t)n, stdout);\n"
        "  }\n"
        "  return 0;\n"
        "}\n"
    )
    exe = tmp_path / "fw2"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", "-I", EXAMPLES, str(main), "-o", str(exe)], check=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True).stdout
    events = LineDecoder().feed(out)  # counts 0 and 9 are refused by the firmware: no line
    assert [e.kind for e in events] == ["sample"] * 8
    g = (-2147483648, 2147483647, 3, -4, 5, -6, 7, -8)
    for count, event in enumerate(events, start=1):
        assert event.sample.gauges == g[:count]
        assert event.sample.pot == (-5 if count % 2 else None)
        assert event.sample.seq == (65530 + count) % 65536
    assert out.splitlines()[0] + b"\n" == encode_line(65531, 4294967295, g[:1], -5).replace(b"\r", b"")


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler to build the firmware's protocol code")
def test_the_boards_lines_with_its_rotation_estimate_decode(tmp_path):
    """The board firmware's lines (flexdigit_format_line_v2_rotation): 8 gauges of any 32-bit count, its command
    in the pot's field and its rotation estimate, micro-degrees, at the longest a line can be."""
    main = tmp_path / "main.c"
    main.write_text(
        '#include "flexdigit_stream.h"\n'
        "int main(void) {\n"
        "  char line[FLEXDIGIT_STREAM_LINE_MAX];\n"
        "  int32_t g[8] = {-2147483647L - 1, -2147483647L - 1, -2147483647L - 1, -2147483647L - 1,\n"
        "                  -2147483647L - 1, -2147483647L - 1, -2147483647L - 1, -2147483647L - 1};\n"
        "  int n = flexdigit_format_line_v2_rotation(line, 65535, 4294967295UL, g, 8, -2147483647L - 1,\n"
        "                                            -2147483647L - 1);\n"
        "  fwrite(line, 1, (size_t)n, stdout);\n"
        "  n = flexdigit_format_line_v2_rotation(line, 7, 20000, g + 7, 1, 130, 29981250L);\n"
        "  fwrite(line, 1, (size_t)n, stdout);\n"
        "  return flexdigit_format_line_v2_rotation(line, 7, 20000, g, 9, 130, 0) != 0;\n"
        "}\n"
    )
    exe = tmp_path / "fw3"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", "-I", EXAMPLES, str(main), "-o", str(exe)], check=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True).stdout
    longest, short = LineDecoder().feed(out)
    assert longest.sample.gauges == (-(2**31),) * 8
    assert (longest.sample.pot, longest.sample.rotation_udeg) == (-(2**31), -(2**31))
    assert len(out.splitlines()[0]) + 2 < 152  # FLEXDIGIT_STREAM_LINE_MAX: the NUL fits too
    assert (short.sample.gauges, short.sample.pot, short.sample.rotation_deg) == ((-(2**31),), 130, 29.98125)
    assert out.splitlines()[1] + b"\n" == encode_line(7, 20000, [-(2**31)], 130, rotation_udeg=29981250).replace(
        b"\r", b""
    )

"""Fuzz the rig URL parser, the servo-board framing and the gauge stream's lines (issue 16).

URLs: any generated URL (known and unknown schemes, declared and unknown options, values of every shape) is
parsed into options that satisfy their backend's declarations, or refused with a one-line ParameterError; never
another exception. Framing: whatever commands a controller asks for (any real, huge, negative), on any valid
framing, the bytes sent to the board decode into frames whose position is never 255 (nor the sync byte) and
never beyond the framing's highest position. Stream lines: any bytes from a gauge stream decode into samples,
information and garbled lines (never an exception, never a sample out of the protocol's ranges), and every sample
the firmware could send comes back as sent, however the bytes are cut.
"""

from __future__ import annotations

import math
import urllib.parse

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from flexdigit.errors import ParameterError
from flexdigit.rig.backends import (
    board_backend,
    daq_backend,
    hil_backend,
    replay_backend,
    serial_backend,
    sim_backend,
    stream_backend,
)
from flexdigit.rig.backends.serial_backend import SerialRig
from flexdigit.rig.backends.servo_board import FrameDecoder, Framing, encode_frame
from flexdigit.rig.backends.stream_framing import (
    MAX_GAUGES,
    SEQ_MODULUS,
    TIME_MODULUS_US,
    LineDecoder,
    crc16_xmodem,
    encode_line,
)
from flexdigit.rig.base import BACKENDS, clamp_command, rig_url_options

from .strategies import numbers

MODULES = {"sim": sim_backend, "sim+paced": sim_backend, "serial": serial_backend, "daq": daq_backend}
MODULES.update(replay=replay_backend, stream=stream_backend, hil=hil_backend, board=board_backend)
DECLARED = sorted({opt.name for m in MODULES.values() for opt in m.URL_OPTIONS})

values = st.one_of(
    numbers.map(str),
    st.sampled_from(["", "none", "0x10", "0xFF", "1e3", "-0", "yes", "off", "horizontal", "single_ended", " 3 "]),
    st.text(max_size=8),
)


@st.composite
def urls(draw) -> str:
    scheme = draw(st.one_of(st.sampled_from(sorted(BACKENDS)), st.text(max_size=6)))
    location = draw(st.one_of(st.just(""), st.sampled_from(["loop://", "/dev/ttyUSB0", "0", "run.jsonl"]), st.text()))
    keys = draw(st.lists(st.one_of(st.sampled_from([*DECLARED, "daq.baud"]), st.text(max_size=6)), max_size=4))
    query = "&".join(f"{urllib.parse.quote(k)}={urllib.parse.quote(draw(values))}" for k in keys)
    sep = "://" if location or draw(st.booleans()) else ""
    return f"{scheme}{sep}{location}" + (f"?{query}" if query else "")


@given(url=urls())
def test_url_parser(url):
    try:
        parsed, options = rig_url_options(url)
    except ParameterError as exc:
        assert str(exc)
        assert "\n" not in str(exc)
        return
    declared = {opt.name: opt for opt in MODULES[parsed.scheme].URL_OPTIONS}
    prefixes = getattr(MODULES[parsed.scheme], "URL_PREFIXES", ())
    for key, value in options.items():
        if any(key.startswith(prefix) for prefix in prefixes):
            assert isinstance(value, str)  # the nested source's option, as text: its own backend checks it
            continue
        opt = declared[key]  # nothing undeclared gets through
        if value is None:
            assert opt.none
        elif opt.kind in ("int", "float"):
            assert isinstance(value, int if opt.kind == "int" else float)
            assert math.isfinite(value)
            assert opt.low is None or value >= opt.low
            assert opt.high is None or value <= opt.high
        elif opt.kind == "bool":
            assert isinstance(value, bool)
        elif opt.kind == "choice":
            assert value in opt.choices


@st.composite
def framings(draw) -> Framing:
    max_channel = draw(st.integers(0, 253))
    max_position = draw(st.integers(1, 254))
    sync = draw(st.integers(max(max_channel, max_position) + 1, 255))
    return Framing(sync=sync, max_channel=max_channel, max_position=max_position)


class _Port:
    """A pyserial-like port that keeps what was written."""

    def __init__(self) -> None:
        self.sent = bytearray()

    def write(self, data: bytes) -> int:
        self.sent += data
        return len(data)

    def flush(self) -> None:
        pass

    def close(self) -> None:
        pass


@given(framing=framings(), data=st.data(), commands=st.lists(numbers, max_size=20))
def test_frames_never_carry_255_or_a_position_beyond_the_framing(framing, data, commands):
    channel = data.draw(st.integers(0, framing.max_channel))
    port = _Port()
    rig = SerialRig("fuzz", framing=framing, channel=channel, serial=port, sensor=lambda: ([0.0, 0.0, 0.0], 1.0))
    for command in commands:
        try:
            sent = rig.write_command(command)
        except ParameterError:  # NaN: refused, nothing sent
            assert isinstance(command, float)
            assert math.isnan(command)
            continue
        assert 0 <= sent <= framing.max_position
    rig.close()  # relaxes: one more frame
    decoder = FrameDecoder(framing)
    frames = decoder.feed(bytes(port.sent))
    assert decoder.dropped_bytes == 0
    assert len(port.sent) == 3 * len(frames)
    assert all(
        ch == channel and 0 <= pos <= framing.max_position and pos not in (255, framing.sync) for ch, pos in frames
    )


@given(channel=st.integers(-5, 300), position=st.one_of(st.integers(-5, 300), numbers))
def test_encode_frame_refuses_what_it_cannot_send(channel, position):
    try:
        frame = encode_frame(channel, position)
    except ParameterError as exc:
        assert "\n" not in str(exc)
        return
    assert frame[0] == 0xFF
    assert 0xFF not in frame[1:]
    assert frame[2] <= 254


@given(command=numbers)
def test_clamp_command_never_gives_255(command):
    assume(not (isinstance(command, float) and math.isnan(command)))
    assert 0 <= clamp_command(command) <= 254


@given(stream=st.binary(max_size=300), framing=framings())
def test_the_decoder_never_yields_the_sync_byte_as_a_position(stream, framing):
    for ch, pos in FrameDecoder(framing).feed(stream):
        assert ch <= framing.max_channel
        assert pos != framing.sync


@given(stream=st.binary(max_size=600))
def test_any_stream_bytes_decode_into_events_never_an_exception(stream):
    for event in LineDecoder().feed(stream):
        assert event.kind in ("sample", "info", "garbled")
        if event.kind == "sample":
            sample = event.sample
            assert 0 <= sample.seq < SEQ_MODULUS
            assert 0 <= sample.t_us < TIME_MODULUS_US
            assert all(isinstance(v, int) for v in (*sample.gauges, *([sample.pot] if sample.pot is not None else [])))
        elif event.kind == "garbled":
            assert event.reason
            assert "\n" not in event.reason


counts = st.integers(-(2**31), 2**31 - 1)


@given(
    samples=st.lists(
        st.tuples(
            st.integers(0, SEQ_MODULUS - 1),
            st.integers(0, TIME_MODULUS_US - 1),
            st.tuples(counts, counts, counts),
            st.none() | counts,
        ),
        min_size=1,
        max_size=10,
    ),
    data=st.data(),
)
def test_every_sample_the_firmware_sends_comes_back_however_cut(samples, data):
    stream = b"".join(encode_line(*sample) for sample in samples)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    decoder, events = LineDecoder(), []
    for a, b in zip([0, *cuts], [*cuts, len(stream)], strict=True):
        events += decoder.feed(stream[a:b])
    assert [(e.sample.seq, e.sample.t_us, e.sample.gauges, e.sample.pot) for e in events] == samples


# ``make fuzz`` (seed 0) found 'daq://\n?baud=0': the messages quote the URL as given, so a newline in it broke
# the one-line error in two. A URL with a control character (also %-encoded in the location) is refused first.
@pytest.mark.parametrize(
    "url", ["daq://\n?baud=0", "daq://\n?baud=0&baud=0", "replay://run%0A.jsonl", "sim\t?seed=1", "serial://\x00"]
)
def test_a_url_with_a_control_character_is_refused_on_one_line(url):
    with pytest.raises(ParameterError, match="must be printable text") as caught:
        rig_url_options(url)
    assert "\n" not in str(caught.value)


# -- version 2 (issue 24): 1 to 8 gauges a line, version 1's three-gauge lines still read --------------------------
@given(
    samples=st.lists(
        st.tuples(
            st.integers(0, SEQ_MODULUS - 1),
            st.integers(0, TIME_MODULUS_US - 1),
            st.lists(counts, min_size=1, max_size=8).map(tuple),
            st.none() | counts,
            st.sampled_from([1, 2]),
        ),
        min_size=1,
        max_size=10,
    ),
    data=st.data(),
)
def test_every_version_2_sample_comes_back_however_cut_beside_version_1(samples, data):
    lines = [(seq, t, g, pot, version if len(g) == 3 else 2) for seq, t, g, pot, version in samples]
    stream = b"".join(encode_line(seq, t, g, pot, version=v) for seq, t, g, pot, v in lines)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    decoder, events = LineDecoder(), []
    for a, b in zip([0, *cuts], [*cuts, len(stream)], strict=True):
        events += decoder.feed(stream[a:b])
    assert [(e.sample.seq, e.sample.t_us, e.sample.gauges, e.sample.pot) for e in events] == [s[:4] for s in lines]


@given(
    samples=st.lists(
        st.tuples(
            st.integers(0, SEQ_MODULUS - 1),
            st.lists(counts, min_size=1, max_size=8).map(tuple),
            counts,
            st.none() | st.integers(-(2**31), 2**31 - 1),
        ),
        min_size=1,
        max_size=10,
    ),
)
def test_the_boards_rotation_estimate_comes_back_and_lines_without_it_still_read(samples):
    """The board's lines (issue 24 item 5): the gauges, its command in the pot's field and, when it sends one, its
    rotation estimate in micro-degrees; lines without the estimate (the images before it) read as before."""
    stream = b"".join(encode_line(seq, 0, g, pot, version=2, rotation_udeg=r) for seq, g, pot, r in samples)
    events = LineDecoder().feed(stream)
    got = [(e.sample.seq, e.sample.gauges, e.sample.pot, e.sample.rotation_udeg) for e in events]
    assert got == samples
    assert [e.sample.rotation_deg for e in events] == [None if r is None else r / 1e6 for *_, r in samples]


@given(fields=st.lists(st.binary(max_size=12), max_size=14))
def test_any_version_2_payload_with_a_good_checksum_decodes_or_is_garbled(fields):
    """A board's line with the right checksum but any fields after ``V2``: a sample of 1-8 gauges, or garbled."""
    payload = b",".join([b"V2", *fields]).replace(b"\n", b"").replace(b"\r", b"").replace(b"*", b"")
    line = b"$" + payload + b"*" + f"{crc16_xmodem(payload):04X}".encode() + b"\r\n"
    for event in LineDecoder().feed(line):
        assert event.kind in ("sample", "garbled")
        if event.kind == "sample":
            assert 1 <= len(event.sample.gauges) <= MAX_GAUGES
            # the gauges, then nothing, the pot, or the pot and the board's rotation estimate
            assert len(payload.split(b",")) - 4 - len(event.sample.gauges) in (0, 1, 2)
            assert (event.sample.rotation_udeg is None) == (len(payload.split(b",")) < 6 + len(event.sample.gauges))
        else:
            assert event.reason
            assert "\n" not in event.reason


@given(count=st.integers(-2, 12), values=st.lists(counts, min_size=0, max_size=10))
def test_a_version_2_line_whose_count_disagrees_with_its_fields_is_garbled(count, values):
    assume(not (1 <= count <= MAX_GAUGES and len(values) in (count, count + 1, count + 2)))
    payload = ",".join(["V2", "1", "2", str(count), *map(str, values)]).encode()
    line = b"$" + payload + b"*" + f"{crc16_xmodem(payload):04X}".encode() + b"\r\n"
    (event,) = LineDecoder().feed(line)
    assert event.kind == "garbled"
    assert event.reason.startswith("version 2:")

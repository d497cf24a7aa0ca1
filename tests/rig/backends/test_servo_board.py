"""Mini SSC framing on bytes (thesis 2.5.3: sync 0xFF, servo number, position 0..254)."""

import pytest

from flexdigit.errors import ParameterError
from flexdigit.rig.backends.servo_board import MINI_SSC, FrameDecoder, Framing, encode_frame


def test_frame_is_sync_channel_position():
    # Mini SSC convention: 0xFF, channel, position
    assert encode_frame(0, 8) == b"\xff\x00\x08"
    assert encode_frame(3, 254) == b"\xff\x03\xfe"


@pytest.mark.parametrize("position", [255, -1, 1000, 8.5, True])
def test_position_255_and_junk_can_never_be_sent(position):
    with pytest.raises(ParameterError, match="position"):
        encode_frame(0, position)


def test_channel_range_follows_framing():
    with pytest.raises(ParameterError, match="channel"):
        encode_frame(8, 10)
    assert encode_frame(15, 10, Framing(max_channel=15)) == b"\xff\x0f\x0a"


def test_framing_rejects_sync_inside_payload_range():
    with pytest.raises(ParameterError, match="sync"):
        Framing(sync=0x80, max_position=254)


def test_decoder_round_trips_every_position_and_resyncs():
    stream = b"".join(encode_frame(ch, pos) for ch in (0, 7) for pos in range(255))
    dec = FrameDecoder()
    # feed in awkward chunks, with garbage and a torn frame in front
    data = b"\x01\x02\xff\x00" + stream
    frames = []
    for i in range(0, len(data), 7):
        frames += dec.feed(data[i : i + 7])
    assert frames == [(ch, pos) for ch in (0, 7) for pos in range(255)]
    assert dec.dropped_bytes == 3  # 2 garbage bytes + the torn frame's channel byte
    assert MINI_SSC.max_position == 254

"""The serial backend through a real pseudo-terminal pair, with a fake MILINST board decoding frames on the far end."""

from __future__ import annotations

import math
import os
import select
import sys
import threading

import numpy as np
import pytest

from flexdigit.errors import ParameterError, RigError
from flexdigit.rig.backends.serial_backend import SerialRig
from flexdigit.rig.backends.servo_board import FrameDecoder, Framing
from flexdigit.rig.base import open_rig
from flexdigit.rig.loop import run_loop
from flexdigit.rig.sample_log import read_log

from ..helpers import PI, FakeClock

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="needs os.openpty")


class FakeBoard(threading.Thread):
    """Reads the master side of a pty and decodes Mini SSC frames, as the MILINST board would."""

    def __init__(self):
        super().__init__(daemon=True)
        self.master, self.slave = os.openpty()
        self.port = os.ttyname(self.slave)
        self.decoder = FrameDecoder()
        self.frames: list[tuple[int, int]] = []
        self.got = threading.Condition()
        self._halt = threading.Event()
        self.start()

    def run(self):
        while not self._halt.is_set():
            try:
                ready, _, _ = select.select([self.master], [], [], 0.01)
                if ready:
                    data = os.read(self.master, 64)
                    with self.got:
                        self.frames += self.decoder.feed(data)
                        self.got.notify_all()
            except OSError:
                return

    def wait_frames(self, n, timeout=5.0):
        with self.got:
            self.got.wait_for(lambda: len(self.frames) >= n, timeout)
        return list(self.frames)

    def vanish(self):
        """Unplug: the far end closes, the next write fails with EIO."""
        self._halt.set()
        self.join(1.0)
        os.close(self.master)

    def close(self):
        if not self._halt.is_set():
            self.vanish()
        os.close(self.slave)


@pytest.fixture
def board():
    b = FakeBoard()
    yield b
    b.close()


def test_commands_reach_the_board_as_frames(board):
    rig = open_rig(f"serial://{board.port}?baud=9600&channel=2", sensor=lambda: (np.zeros(3), math.nan))
    assert isinstance(rig, SerialRig)
    assert rig.channel == 2
    assert rig.baud == 9600
    assert rig.write_command(43) == 43
    assert rig.write_command(300) == 254  # clamped; 255 is never sent
    assert rig.write_command(-7.2) == 0
    rig.close()  # relaxes: equilibrium command 8
    # first frame: the explicit equilibrium sent at open (bumpless start), last: the relax on close
    assert board.wait_frames(5) == [(2, 8), (2, 43), (2, 254), (2, 0), (2, 8)]
    assert "baud=9600" in repr(rig)
    assert "closed" in repr(rig)


def test_bad_url_options_name_the_culprit(board):
    with pytest.raises(ParameterError, match="baud"):
        open_rig(f"serial://{board.port}?baud=fast")
    with pytest.raises(ParameterError, match="channel"):
        open_rig(f"serial://{board.port}?channel=9")
    with pytest.raises(RigError, match="cannot open"):
        open_rig("serial:///dev/no-such-servo-board")


def test_framing_from_the_url_reaches_the_board(board):
    # a board with a 0xFE sync byte and positions up to 200: frames are (0xFE, channel, position)
    # the board decodes that framing before the port opens, so the bumpless start's frame is decoded too
    board.decoder = FrameDecoder(Framing(sync=0xFE, max_channel=3, max_position=200))
    rig = open_rig(f"serial://{board.port}?sync=0xFE&max_position=200&max_channel=3&channel=3")
    assert rig.framing == Framing(sync=0xFE, max_channel=3, max_position=200)
    rig.write_command(150)
    assert rig.write_command(230) == 200  # clamped to the framing's highest position, never refused mid-run
    rig.close()
    assert board.wait_frames(4) == [(3, 8), (3, 150), (3, 200), (3, 8)]
    # options left out keep their Mini SSC values; decimal works as well as hexadecimal
    rig = open_rig(f"serial://{board.port}?sync=254&max_position=253")
    assert rig.framing == Framing(sync=254, max_channel=7, max_position=253)
    rig.close()


@pytest.mark.parametrize(
    ("query", "match"),
    [
        ("sync=start", "option sync='start' must be an integer"),
        ("max_position=2.5", "option max_position='2.5' must be an integer"),
        ("sync=300", r"option sync='300' must be an integer inside \[0, 255\] \(the frame's sync byte"),
        ("sync=0x10", "'sync' parameter of Framing must be above every channel and position byte"),
        ("max_position=255", r"option max_position='255' must be an integer inside \[1, 254\]"),
        ("max_channel=2&channel=3", r"'channel' parameter of SerialRig must be an integer inside \[0, 2\]. Got 3"),
        ("pot=3", "option pot=3 needs the gauge card too"),
        ("speed=9600", "unknown option 'speed'; a serial URL takes baud, channel, sync"),
    ],
)
def test_bad_framing_options_name_the_option_and_value(board, query, match):
    with pytest.raises(ParameterError, match=match):
        open_rig(f"serial://{board.port}?{query}")


def test_framing_given_twice_is_refused(board):
    with pytest.raises(ParameterError, match="not both"):
        open_rig(f"serial://{board.port}?sync=0xFE", framing=Framing())


def test_board_vanishing_mid_run_stops_the_loop_safely(tmp_path, board):
    clock = FakeClock()
    rig = SerialRig(board.port, sensor=lambda: (np.array([0.01, 0.0, 0.0]), math.nan), clock=clock, sleep=clock.sleep)
    board.wait_frames(1)
    n_before = 10

    def unplug(k, t, y, command):
        if k == n_before - 1:
            board.vanish()

    log = tmp_path / "run.jsonl"
    result = run_loop(rig, PI(), setpoint=0.02, duration_s=1.0, period_s=0.02, log_path=log, on_sample=unplug)
    assert result.status == "fault"
    assert "port lost" in result.message
    assert board.port in result.message
    assert "could NOT send the safe command" in result.message  # the board is gone: we say so, we do not pretend
    assert not result.safe_command_sent
    assert rig.closed
    header, samples, footer = read_log(log)
    assert len(samples) == n_before
    assert [s["k"] for s in samples] == list(range(n_before))
    assert footer["stop"] == "fault"


def test_serial_with_daq_reads_the_card_and_releases_it(board):
    from .test_daq_backend import fake_uldaq

    ul = fake_uldaq({0: 0.25, 1: 0.5, 2: 0.75, 3: 1.5})
    rig = open_rig(f"serial://{board.port}?channel=0&daq=0&pot=3", uldaq=ul)
    np.testing.assert_allclose(rig.read().gauges_v, [0.25, 0.5, 0.75])
    assert rig.read().pot_v == 1.5  # the pot channel passed through to the card
    assert rig.write_command(30) == 30
    card = rig.companions[0]
    rig.close()
    assert card.closed
    assert card._device.state == "released"
    assert board.wait_frames(3)[-2:] == [(0, 30), (0, 8)]

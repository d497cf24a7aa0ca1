"""``board://``, the host side of a real Uno running the reference firmware, against the same image on simavr.

The test stands in for the wall clock: it runs the harness with its UART on a pty (``flexdigit_hil --pty``) and
advances the AVR when the rig sleeps (the rig's injected clock and sleep), while :class:`BoardRig` talks to the
firmware over the pty as it would over ``/dev/ttyACM0``. The ADC pins sit at 2.5 V (the gauges at 0 V): these
tests are about the conversation (modes, commands, heartbeats, faults), not the digit.
"""

from __future__ import annotations

import subprocess
import time

import pytest
import serial

from flexdigit.rig.backends.board_backend import BoardRig
from flexdigit.rig.backends.board_link import BAUD
from flexdigit.rig.base import open_rig

STEP_US = 500
#: Wall-clock bound on bytes the harness said it wrote reaching the rig's side of the pty, s.
PTY_WAIT_S = 5.0


class CountingSerial(serial.Serial):
    """A pyserial port that counts the bytes written and read (the emulator is told how many the host sent)."""

    def __init__(self, *args, **kwargs) -> None:
        self.written = self.taken = 0
        super().__init__(*args, **kwargs)

    def write(self, data) -> int:
        self.written += len(data)
        return super().write(data)

    def read(self, size: int = 1) -> bytes:
        data = super().read(size)
        self.taken += len(data)
        return data


class Emulator:
    """The firmware on simavr, in simulated time, its UART a pty; the time is the rig's clock."""

    def __init__(self, elf) -> None:
        self.proc = subprocess.Popen(
            [str(elf.parent / "flexdigit_hil"), str(elf), "--pty"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        self.port = CountingSerial(self.proc.stdout.readline().split()[1], baudrate=BAUD, timeout=0)
        self.t_s, self.told, self.sent = 0.0, 0, 0

    def clock(self) -> float:
        return self.t_s

    def advance(self, seconds: float) -> None:
        for _ in range(max(1, round(seconds / (STEP_US * 1e-6)))):
            request = "V 25000 25000 25000 25000\n"
            if self.port.written > self.told:
                request += f"U {self.port.written - self.told}\n"
                self.told = self.port.written
            self.proc.stdin.write(request + f"R {STEP_US}\n")
            self.proc.stdin.flush()
            self.sent += int(self.proc.stdout.readline().split()[-1])  # the reply ends with the bytes sent
            self.t_s += STEP_US * 1e-6
            # what the board sent is on the pty before the rig looks: its reads repeat exactly
            deadline = time.monotonic() + PTY_WAIT_S
            while self.port.in_waiting < self.sent - self.port.taken and time.monotonic() < deadline:
                time.sleep(0.0005)

    def close(self) -> None:
        self.proc.stdin.write("Q\n")
        self.proc.stdin.flush()
        self.proc.wait(timeout=5)


@pytest.fixture
def emulator(firmware):
    emu = Emulator(firmware(0.020, "float"))
    yield emu
    emu.close()


def _rig(emu, **options) -> BoardRig:
    return BoardRig("/dev/ttyACM0", serial=emu.port, clock=emu.clock, sleep=emu.advance, **options)


@pytest.mark.slow
def test_host_mode_follows_the_hosts_commands_and_heartbeats(emulator):
    with _rig(emulator, mode="host") as rig:
        rig.write_command(30)
        rig.wait(1.0)  # past the board's 0.5 s timeout: the heartbeats keep it in host mode
        reading = rig.read()
        assert rig.board.latest.pot == 30  # the command the board applied this period
        assert abs(reading.gauges_v).max() <= 5.0 / 1024  # 2.5 V on the pins: 0 V of gauge, within a count
        assert rig.board.faults == []
        assert [mode for _, mode in rig.board.mode_marks] == [1]
        said = rig._port.written
    # closing relaxed the digit ("C8"), put the board in its safe state ("M0") and released the port
    assert rig._port.written == said + len(b"C8\nM0\n")
    assert not rig._port.is_open


@pytest.mark.slow
def test_a_silent_host_is_a_fault_the_next_read_raises(emulator):
    rig = _rig(emulator, mode="host")
    try:
        rig.write_command(25)
        rig.wait(0.1)
        emulator.advance(0.7)  # the host says nothing (no heartbeat)
        with pytest.raises(OSError, match="host_timeout"):
            rig.read()
        assert rig.board.latest.pot == 8  # relaxed to the equilibrium command
    finally:
        rig.close()


@pytest.mark.slow
def test_board_mode_closes_the_loop_on_the_board(emulator):
    with _rig(emulator, mode="board", setpoint_deg=20.0) as rig:
        rig.wait(0.5)
        assert [mode for _, mode in rig.board.mode_marks] == [2]
        assert rig.board.tare_deg == rig.board.tare_deg  # the board tared its map and said so
        # the pins say 0 deg while 20 are asked: the board's controller drives the servo up, the host only watches
        assert rig.board.latest.pot > 8
        assert rig.board.period_s(rig.where) == pytest.approx(0.020)


def test_no_board_on_the_port_is_one_line_not_a_hang():
    port = serial.serial_for_url("loop://", timeout=0)
    now = [0.0]

    def sleep(seconds):
        now[0] += seconds

    with pytest.raises(OSError, match=r"board://loop: no sample from the board in 0.5 s"):
        BoardRig("loop", serial=port, clock=lambda: now[0], sleep=sleep, startup=0.5)
    assert not port.is_open


def test_url_options_are_checked():
    with pytest.raises(ValueError, match="mode"):
        open_rig("board:///dev/ttyACM0?mode=wild")
    with pytest.raises(ValueError, match="serial port"):
        open_rig("board://")

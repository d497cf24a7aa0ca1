"""Test doubles for the rig tests: a virtual-time linear rig, a fake clock and a tiny PI (no wall-clock dependence).

A plain module the tests import (``from .helpers import FakeClock``); tests/rig/conftest.py only makes fixtures of
them.
"""

from __future__ import annotations

import fcntl
import math
import os
import select
import struct
import termios
import threading
import time

import numpy as np

from flexdigit.rig.base import Rig

__all__ = ["FakeClock", "FirstOrderRig", "PI", "HostOpens"]


class FakeClock:
    """A monotonic clock that only moves when told (pyserial's Timeout tests do the same)."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += max(seconds, 0.0)


class FirstOrderRig(Rig):
    """A rig whose gauge 1 follows the command through a first-order lag, in virtual time.

    gauge_v = gain_v * (command - 8) filtered by tau_s; gauges 2, 3 are half and a quarter of it. ``faults`` maps a
    sample index (count of reads) to a callable that misbehaves (returns NaN, clips, raises).
    """

    name = "first-order"

    def __init__(self, tau_s=0.1, gain_v=0.05, faults=None, **kwargs):
        self.clock_ = FakeClock()
        kwargs.setdefault("clock", self.clock_)
        kwargs.setdefault("sleep", self._advance)
        super().__init__(**kwargs)
        self.tau_s, self.gain_v = tau_s, gain_v
        self.state_v = 0.0
        self.reads = 0
        self.sent: list[int] = []
        self.faults = faults or {}

    def _advance(self, seconds):
        # exact discretisation of the first-order lag over the wait
        target = self.gain_v * (self.command - 8)
        self.state_v = target + (self.state_v - target) * math.exp(-seconds / self.tau_s)
        self.clock_.sleep(seconds)

    def _read(self):
        self.reads += 1
        if self.reads in self.faults:
            return self.faults[self.reads](self)
        return np.array([1.0, 0.5, 0.25]) * self.state_v, math.nan

    def _send(self, command):
        self.sent.append(command)


class PI:
    """A tiny PI on gauge 1 for loop tests (the runtime controller has its own tests)."""

    def __init__(self, kp=20.0, ki=200.0, period_s=0.02):
        self.kp, self.ki, self.period_s = kp, ki, period_s

    def reset(self, command):
        self.integral = float(command)

    def measure(self, reading):
        return float(reading.gauges_v[0])

    def step(self, setpoint, reading):
        e = setpoint - self.measure(reading)
        self.integral += self.ki * self.period_s * e
        return self.integral + self.kp * e


class HostOpens:
    """When the host has opened the far end of a pty, known from the pty itself, not from a fixed delay.

    pyserial empties the port's input when it opens it (as the host of a USB board does), so a line a test board
    writes before that is lost, and a fixed head start (0.2 s, 0.3 s) loses it on a loaded machine. In packet mode
    (``TIOCPKT``, tty_ioctl(4)) the master reads a status byte with ``TIOCPKT_FLUSHREAD`` set when the other end
    flushes its input: :meth:`wait` returns once that has happened, so the first line goes out after the flush.
    Only for a board that writes to its master and never reads it (in packet mode reads carry a status byte).
    """

    def __init__(self, master: int) -> None:
        self.master = master
        fcntl.ioctl(master, termios.TIOCPKT, struct.pack("i", 1))
        self.opened = threading.Event()

    def wait(self, timeout_s: float = 60.0, halt: threading.Event | None = None) -> bool:
        """Block until the host has opened (flushed) the port; False after ``timeout_s`` or once ``halt`` is set."""
        deadline = time.monotonic() + timeout_s
        while not self.opened.is_set():
            if (halt is not None and halt.is_set()) or time.monotonic() > deadline:
                return False
            ready, _, _ = select.select([self.master], [], [], 0.05)
            if not ready:
                continue
            try:
                status = os.read(self.master, 4096)[:1]
            except OSError:
                return False
            if status and status[0] & termios.TIOCPKT_FLUSHREAD:
                self.opened.set()
        return True

    def send(self, data: bytes, timeout_s: float = 60.0) -> threading.Thread:
        """Write ``data`` once the host has opened the port (in a thread, as a board streams while the host opens)."""

        def run():
            if self.wait(timeout_s):
                os.write(self.master, data)

        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        return thread

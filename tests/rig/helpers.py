"""Test doubles for the rig tests: a virtual-time linear rig, a fake clock and a tiny PI (no wall-clock dependence).

A plain module the tests import (``from .helpers import FakeClock``); tests/rig/conftest.py only makes fixtures of
them.
"""

from __future__ import annotations

import math

import numpy as np

from flexdigit.rig.base import Rig

__all__ = ["FakeClock", "FirstOrderRig", "PI"]


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

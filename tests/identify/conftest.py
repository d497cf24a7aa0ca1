"""Synthetic release and step records with known parameters (the oracle of the identification tests)."""

import numpy as np
import pytest

from flexdigit.identify.fit import second_order_response

#: The thesis's digit (3.1.2: E(s), 13.10 rad/s, 0.068) and servo (3.2.4: MT(s), 20.53 rad/s, 0.5629).
DIGIT = {"wn_rad_s": 13.0995, "zeta": 0.06791}
SERVO = {"wn_rad_s": 20.53, "zeta": 0.5629}


def release_record(seed, *, noise=0.02, wn=DIGIT["wn_rad_s"], zeta=DIGIT["zeta"], hold_s=0.5, dt=0.002, t_end=8.0):
    """Free decay from 1 V (relative to 0.2 V at rest) after holding it ``hold_s``, plus white noise (V)."""
    t = np.arange(0.0, t_end, dt)
    y = second_order_response(t, "release", wn, zeta, 0.2, 1.0, hold_s)
    return t, y + np.random.default_rng(seed).normal(0.0, noise, t.size)


def step_record(seed, *, noise=0.02, wn=SERVO["wn_rad_s"], zeta=SERVO["zeta"], dt=0.002, t_end=2.0):
    """Unit step from 0.5 (before t = 0.2 s) plus white noise of ``noise`` times the step."""
    t = np.arange(0.0, t_end, dt)
    y = second_order_response(t, "step", wn, zeta, 0.5, 1.0, 0.2)
    return t, y + np.random.default_rng(seed).normal(0.0, noise, t.size)


@pytest.fixture
def release():
    return release_record


@pytest.fixture
def step():
    return step_record

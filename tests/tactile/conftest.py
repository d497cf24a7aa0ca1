"""Fixtures of the tactile tests: the closed-form cantilever rig (tests/cantilever.py), independent of the twin.

Strain at gauge i from a point load m at a (from the base) is proportional to the bending moment there,
m g (a - x_i) for a > x_i and 0 otherwise (Euler-Bernoulli cantilever); plus seeded white noise.
"""

from __future__ import annotations

import pytest

from cantilever import NOISE_V, CantileverRig  # noqa: F401 (NOISE_V: used by test modules)
from oracles import GAIN_V_PER_NM, GAUGES_M, cantilever_gauges_v  # noqa: F401 (used by test modules)


@pytest.fixture
def make_rig():
    """The :class:`CantileverRig` class (tests import nothing from conftest under --import-mode=importlib)."""
    return CantileverRig


@pytest.fixture
def cantilever_model():
    return cantilever_gauges_v

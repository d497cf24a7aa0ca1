"""Fixtures of the rig tests, made from the test doubles of tests/rig/helpers.py."""

from __future__ import annotations

import pytest

from .helpers import FakeClock


@pytest.fixture
def fake_clock():
    return FakeClock()

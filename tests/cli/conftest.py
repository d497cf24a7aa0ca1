"""Fixtures of the command-line tests."""

from __future__ import annotations

import pytest

from cantilever import CantileverRig


@pytest.fixture
def make_rig():
    """The closed-form :class:`~cantilever.CantileverRig` class (``flexdigit collect`` on a rig without the twin)."""
    return CantileverRig

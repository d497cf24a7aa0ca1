"""Synthetic release and step records with known parameters (closed forms of ``tests/oracles.py``)."""

import pytest

from oracles import DIGIT, SERVO, release_record, step_record  # noqa: F401 (DIGIT, SERVO: used by test modules)


@pytest.fixture
def release():
    return release_record


@pytest.fixture
def step():
    return step_record

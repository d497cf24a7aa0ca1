"""Fixtures for the calibration tests: the perturbed rig's records (flexdigit.calibrate.synthetic) once a session."""

from __future__ import annotations

import pytest

from flexdigit.calibrate.synthetic import RigRecords, make_records, perturbed
from flexdigit.twin.calibration import packaged_calibration


@pytest.fixture(scope="session")
def perturbed_rig(tmp_path_factory) -> RigRecords:
    return make_records(tmp_path_factory.mktemp("perturbed_rig"), perturbed(packaged_calibration()))

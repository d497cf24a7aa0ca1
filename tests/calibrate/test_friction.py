"""The cable-guide friction's level: from a measured repeatability (closed form) and by a 1-D fit to a score.

Reference values: the ratio a twin was built with (known answer), and the closed form of corr2 for independent
signal and noise; statistical tolerances from the standard error of a standard deviation of N readings,
1/sqrt(2 N), with a margin of ~5 of those.
"""

import numpy as np
import pytest

from flexdigit.calibrate.friction import fit_level, friction_ratio_from_repeatability
from flexdigit.calibrate.targets import CalibrationTargets
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.twin import Twin


def _cal(ratio):
    return default_calibration().replace(cable_friction_ratio=ratio)


def test_friction_ratio_recovered_from_a_synthetic_repeatability_record():
    # a user with a rig: 1000 readings of the unloaded digit held at command 30, tapped between readings, from a
    # twin with a known ratio
    truth = 0.05
    n = 1000
    twin = Twin(seed=11, calibration=_cal(truth), orientation="horizontal", command=30)
    volts = []
    for _ in range(n):
        twin.advance(0.02)
        twin.disturb()  # tap the digit between readings: each sees the cable settle afresh in its guides
        volts.append(twin.read()[0])
    targets = CalibrationTargets.from_records(actuated_rest=(30, np.array(volts)))
    assert targets.actuated_repeatability_command == 30
    got = friction_ratio_from_repeatability(
        RigParams(), _cal(0.0), targets.actuated_repeatability_command, targets.actuated_repeatability_v
    )
    assert got == pytest.approx(truth, rel=0.07)  # ~5 standard errors of a 1000-reading spread


def test_fit_level_recovers_a_noise_level_from_corr2():
    # closed form: corr2(y, y + s n) = 1 / sqrt(1 + s^2 var(n) / var(y)) for independent y and n
    rng = np.random.default_rng(0)
    y, noise = rng.uniform(1, 10, 20000), rng.standard_normal(20000)

    def corr2(s):
        return float(np.corrcoef(y, y + s * noise)[0, 1])

    s_true = np.std(y) * np.sqrt(1 / 0.9**2 - 1)  # level that gives corr2 0.9 in the limit
    assert fit_level(corr2, 0.9, bracket=(0.0, 10.0)) == pytest.approx(s_true, rel=0.02)
    with pytest.raises(ParameterError, match="'target' parameter of fit_level"):
        fit_level(corr2, 0.5, bracket=(0.0, 1.0))

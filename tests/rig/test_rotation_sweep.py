"""The map of a digit whose gauges drift: the referenced sweep (straight before, between and after the commands) and
the tare at rest, against synthetic gauges whose sensitivities, drift and noise are known (seeded, virtual time).

Oracle: the gauges are ``offset + s theta(command) + drift(t) + noise`` with ``theta`` linear in the command, so
the map that holds the true rotation has the weights ``s / (s . s)`` exactly; a linear drift is cancelled exactly by
the straight readings' linear interpolation (up to the readings' noise), and a plain sweep leans by the drift per
step over the rotation per step (computed here from the sweep's own visit times).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig
from flexdigit.rig.rotation import calibrate_rotation, sweep_protocol, tare_at_rest

from .helpers import FakeClock

SENS_V_PER_DEG = np.array([4.8e-3, 2.0e-3])  # a coarse gauge and a coarser one (quarter bridges of a short digit)
OFFSET_V = np.array([0.03, -0.01])
DEG_PER_COMMAND = 1.7
NOISE_V = 0.002  # the twin's white noise a reading
#: A digit other than the thesis rig (two gauges): its default sweep is the referenced one.
DIGIT = RigParams.from_dict({"geometry": {"gauge_positions_m": [0.06, 0.2]}, "sensors": {"adc_channels": [0, 1]}})
#: The thesis rig (two channels read here: the oracle has two gauges; its protocols are the thesis rig's).
THESIS = RigParams()


class DriftingRig(Rig):
    """At rest at once after each command (no dynamics): gauges ``OFFSET + s theta + drift_v_per_s t + noise``,
    ``theta = DEG_PER_COMMAND (command - straight) + curvature theta^2`` read as the true tip rotation."""

    name = "drifting"

    def __init__(self, drift_v_per_s, *, noise_v=NOISE_V, seed=0, params=DIGIT):
        self.clock_ = FakeClock()
        super().__init__(params, clock=self.clock_, sleep=self.clock_.sleep)
        self.drift = np.asarray(drift_v_per_s, dtype=float)
        self.noise_v = noise_v
        self.rng = np.random.default_rng(seed)

    def tip_rotation_deg(self) -> float:
        return DEG_PER_COMMAND * (self.command - self.params.actuator.equilibrium_command)

    def _read(self):
        theta = self.tip_rotation_deg()
        gauges = OFFSET_V + SENS_V_PER_DEG * theta + self.drift * self.clock_.now
        return gauges + self.noise_v * self.rng.standard_normal(gauges.size), math.nan

    def _send(self, command):
        pass


def _held_deg(estimator, at_deg: float) -> float:
    """The true rotation at which the (tared at straight, drift-free) map reads ``at_deg``: gauges on the true
    lines, drift-free, so the answer is the map's own error."""
    u = estimator.coef_ @ SENS_V_PER_DEG  # deg read per true deg
    return at_deg / u


def test_the_referenced_sweep_cancels_a_linear_drift_that_leans_the_plain_one():
    drift = np.array([1.0e-3, -0.5e-3])  # V/s: under the noise over a 1 s window, so each reading settles
    plain = calibrate_rotation(DriftingRig(drift), sweep="plain")
    referenced = calibrate_rotation(DriftingRig(drift))
    assert referenced.sweep_ == "referenced"
    # the plain sweep's lean: each command is read one visit (its settle time) later than the one before, so each
    # gauge's fitted slope grows by drift * (time per visit) / (deg per visit)
    per_visit_s = float(np.mean(plain.settle_time_s_))
    step_deg = float(np.mean(np.diff(plain.rotation_deg_)))
    leaned = SENS_V_PER_DEG + drift * per_visit_s / step_deg
    np.testing.assert_allclose(plain.gauge_v_per_deg_, leaned, rtol=0.02)
    assert abs(_held_deg(plain, 30.0) - 30.0) > 0.5  # the lean costs the held rotation > 0.5 deg at 30 deg
    # referenced to straight before and after each command, the slopes are the gauges' own, to the noise: 50
    # readings of 2 mV a window (0.28 mV, 0.06 deg on the first gauge) a point, over a 40 deg sweep; the held
    # rotation's spread from that noise is 0.053 deg (30 seeds, mean -0.016: unbiased), so 0.2 deg is ~4 sd
    np.testing.assert_allclose(referenced.gauge_v_per_deg_, SENS_V_PER_DEG, rtol=0.01)
    assert _held_deg(referenced, 30.0) == pytest.approx(30.0, abs=0.2)
    # the waits are every visit's: straight, then each other command and straight again
    commands = referenced.commands_
    assert len(referenced.settle_time_s_) == 2 * (len(commands) - 1) + 1


def test_without_drift_both_sweeps_agree_within_the_noise():
    plain = calibrate_rotation(DriftingRig([0.0, 0.0], seed=3), sweep="plain")
    referenced = calibrate_rotation(DriftingRig([0.0, 0.0], seed=3))
    np.testing.assert_allclose(referenced.gauge_v_per_deg_, plain.gauge_v_per_deg_, rtol=0.01)
    np.testing.assert_allclose(referenced.gauge_v_per_deg_, SENS_V_PER_DEG, rtol=0.01)


def test_the_thesis_rig_keeps_its_plain_sweep_and_a_protractor_is_not_asked_twice_as_often():
    assert sweep_protocol(RigParams()) == "plain"
    assert sweep_protocol(DIGIT) == "referenced"
    assert sweep_protocol(DIGIT, reference=lambda command: 0.0) == "plain"
    est = calibrate_rotation(DriftingRig([0.0, 0.0], params=THESIS))
    assert not hasattr(est, "sweep_")  # a plain map saves and logs as before
    with pytest.raises(ParameterError, match="sweep='referenced' reads the digit at rest"):
        calibrate_rotation(DriftingRig([0.0, 0.0]), settle_s=1.0, sweep="referenced")


def test_a_digit_is_tared_on_a_window_at_rest_the_thesis_rig_on_five_readings():
    # the tare's error is the noise of the mean it reads: 1.6 mV / sqrt(5) in map units on five readings, / sqrt(50)
    # on the 1 s window; over 40 seeded rigs the window's spread is ~sqrt(10) times smaller
    est = calibrate_rotation(DriftingRig([0.0, 0.0], noise_v=1e-5))
    per_reading_deg = NOISE_V * float(np.linalg.norm(est.coef_))
    spreads = {}
    for params in (DIGIT, THESIS):
        tares = []
        for seed in range(40):
            rig = DriftingRig([0.0, 0.0], seed=100 + seed, params=params)
            rest = tare_at_rest(est, rig)
            assert est.predict_one(rest) == pytest.approx(0.0, abs=1e-9)  # tared where it rests
            tares.append(est.tare_deg_)
        spreads[params == THESIS] = np.std(tares)
    assert spreads[True] == pytest.approx(per_reading_deg / math.sqrt(5), rel=0.3)
    assert spreads[False] == pytest.approx(per_reading_deg / math.sqrt(50), rel=0.3)

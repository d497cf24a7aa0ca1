"""Control at 20 ms on the nonlinear twin through the sim backend (issue 6's acceptance figures).

Figures asserted (issue 6, "Control that works at 20 ms"), on the twin's TRUE tip rotation (``step_test`` scores
``SimRig.tip_rotation_deg``, not the gauges' estimate the loop runs on): a 0 -> 30 deg beam-rotation step settles
within 2 % in under 1.0 s, overshoots under 10 %, ends within one command quantum, and the loop stays stable for
+-30 % plant gain; the printed 39 Hz controller digitised by forward Euler (the thesis's 5.2 implementation) fails
there. The figures must hold whichever twin the gauge -> rotation map was calibrated on: each case pairs a
calibration seed with a different rig seed ((1, 0) is what ``flexdigit run --backend sim`` does by default, and
the pair on which the earlier least-squares map let settling reach 1.000 s).
"""

from __future__ import annotations

import numpy as np
import pytest

from flexdigit.control.design20ms import design_20ms
from flexdigit.rig.backends.sim_backend import SimRig
from flexdigit.rig.base import open_rig
from flexdigit.rig.rotation import calibrate_rotation
from flexdigit.rig.safety import ROTATION_RANGE_DEG
from flexdigit.rig.sample_log import read_log
from flexdigit.rig.step_test import step_test

pytestmark = pytest.mark.slow

#: (calibration seed, rig seed)
PAIRS = [(1, 0), (1, 4), (0, 2), (2, 3), (3, 1)]
CAL_SEEDS = sorted({c for c, _ in PAIRS})
#: beam rotation per command of the design model (1.735 deg, the cable model): one command quantum
QUANTUM_DEG = design_20ms().deg_per_command


@pytest.fixture(scope="module")
def estimators():
    # the static calibration sweep on its own twin per seed (about 1-3 s each), shared by the module
    return {seed: calibrate_rotation(open_rig("sim", seed=seed)) for seed in CAL_SEEDS}


def test_calibration_map_is_accurate_and_does_not_depend_on_the_seed(estimators):
    coefs = np.array([est.coef_ for est in estimators.values()])
    for est in estimators.values():
        assert est.residual_deg_ < 0.3  # < 1/5 of a command quantum (1.7 deg)
        assert np.all(est.gauge_v_per_deg_ > 0)  # every gauge bends the same way under the cable
        assert est.coef_ @ est.gauge_v_per_deg_ == pytest.approx(1.0)  # reads the sweep's own slope back
    assert np.all(coefs > 0)  # no gauge subtracted from another (the least-squares map had -6.5 deg/V on seed 1)
    # the weights' spread across seeds: measured < 1.3 % (least squares: 113 vs 51 deg/V on gauge 1)
    spread = np.ptp(coefs, axis=0) / coefs.mean(axis=0)
    assert np.all(spread < 0.03)


@pytest.mark.parametrize(("cal_seed", "rig_seed"), PAIRS)
def test_digital20_meets_the_step_figures_on_the_twin(estimators, cal_seed, rig_seed, tmp_path):
    rig = open_rig("sim", seed=rig_seed)
    st = step_test(rig, "digital20", estimator=estimators[cal_seed], log_path=tmp_path / "step.jsonl")
    m = st.metrics
    assert st.result.ok
    assert m.bounded
    # measured 0.46-0.76 s, 1.4-2.2 %, 0.31 deg = 0.18 quantum (command 26 gives 30.31 deg on the twin)
    assert m.settling_time_s < 1.0  # 2 % band, issue 6
    assert m.overshoot_percent < 10.0
    assert m.final_error_quanta < 1.0  # within one command quantum
    # the loop's estimate stays within one quantum of the true rotation through the transient (measured <= 1.4
    # deg; the ill-posed least-squares map read 41.5 deg at a true 31 deg)
    assert np.max(np.abs(st.result.measurement - st.rotation_deg)) < QUANTUM_DEG
    assert rig.closed
    assert st.result.safe_command_sent
    _, samples, footer = read_log(tmp_path / "step.jsonl")
    assert len(samples) == 150
    assert footer["stop"] == "completed"


@pytest.mark.parametrize("gain", [0.7, 1.3])
@pytest.mark.parametrize(("cal_seed", "rig_seed"), PAIRS[:3])
def test_digital20_stays_stable_for_30_percent_gain_error(estimators, cal_seed, rig_seed, gain):
    st = step_test(open_rig("sim", seed=rig_seed), "digital20", estimator=estimators[cal_seed], gain=gain)
    m = st.metrics
    assert st.result.ok
    assert m.bounded
    assert m.final_error_quanta < 1.0
    assert np.ptp(st.rotation_deg[-25:]) < 3.5  # no growing oscillation: last 0.5 s within two quanta
    # measured at x1.3: 18.5-20.6 % overshoot, settled (2 %) in 0.36-0.38 s; at x0.7: < 2.1 %, 0.84-1.04 s
    assert m.overshoot_percent < (25.0 if gain > 1 else 5.0)
    assert m.settling_time_s < 1.5


def test_thesis_39hz_forward_euler_at_20ms_fails_on_the_twin(estimators):
    st = step_test(open_rig("sim", seed=1), "thesis39-euler", estimator=estimators[0], guard=False)
    # the command bangs between the ends of the range (the unstable pole at z = -3.9 alternates sign)
    commands = st.result.command[20:]
    assert np.mean((commands == 0) | (commands >= 240)) > 0.5
    assert st.metrics.settling_time_s == np.inf
    assert st.metrics.overshoot_percent > 100


def test_the_unstable_loop_is_stopped_by_the_default_guard(estimators):
    # issue 23: the library's loop guards by default, as flexdigit run does: the same unstable loop ends in the safe
    # state with a fault once the twin's true rotation leaves the physical range
    st = step_test(open_rig("sim", seed=1), "thesis39-euler", estimator=estimators[0])
    assert st.result.status == "fault"
    assert "runaway" in st.result.message
    assert st.result.safe_command_sent
    assert "relaxed to command 8" in st.result.message
    assert np.max(np.abs(st.rotation_deg)) < ROTATION_RANGE_DEG[1] + 30.0  # stopped within a sample or two of it


def test_thesis_39hz_tustin_at_20ms_does_not_move_the_digit(estimators):
    # stable, but the printed design's loop gain at DC is ~3e-4 (reference note): a 30 deg step asks for far
    # less than one command, so nothing moves
    st = step_test(open_rig("sim", seed=1), "thesis39-tustin", estimator=estimators[0])
    assert np.all(st.result.command == 8)
    assert abs(st.metrics.final_error_deg + 30) < 1.0


def test_sim_backend_virtual_time_is_deterministic_and_applies_loads():
    def run(seed):
        rig = SimRig(seed=seed)
        rig.write_command(20)
        rig.wait(0.5)
        rig.place_load(0.05, 0.2)
        rig.wait(0.5)
        r = rig.read()
        rig.close()
        return r

    a, b, c = run(4), run(4), run(5)
    assert a.time_s == pytest.approx(1.0)
    np.testing.assert_array_equal(a.gauges_v, b.gauges_v)  # same seed, same numbers: one path, one machine
    assert not np.array_equal(a.gauges_v, c.gauges_v)
    rig = SimRig(seed=4)
    rig.write_command(20)
    rig.wait(1.0)
    unloaded = rig.read().gauges_v
    assert not np.allclose(unloaded, a.gauges_v, atol=0.01)  # the 50 g load bends the digit
    assert rig.twin.loads == []
    assert rig.loads == []


def test_paced_mode_follows_the_injected_clock():
    from .helpers import FakeClock

    clock = FakeClock()
    rig = SimRig(paced=True, seed=0, clock=clock, sleep=clock.sleep)
    rig.write_command(20)
    clock.sleep(0.35)  # wall time passes with nobody asking: the twin catches up at the next read
    reading = rig.read()
    assert reading.time_s == pytest.approx(0.35)
    assert rig.twin.time_s == pytest.approx(0.35)
    rig.wait(0.15)
    assert rig.read().time_s == pytest.approx(0.5)
    assert rig.twin.time_s == pytest.approx(0.5)
    rig.close()
    assert rig.twin.servo.pending[-1][1] == 8 or rig.twin.servo.command == 8  # relaxed on close

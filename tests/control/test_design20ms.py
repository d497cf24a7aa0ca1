"""The sample-period study of 5.1 on the printed plant, and the direct 20 ms design on its linear model."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from flexdigit.control.design20ms import Weights, closed_loop, design_20ms, design_plant, thesis_controller
from flexdigit.control.discretise import forward_euler_stability_limit_s, sample_period_study, sampled_loop
from flexdigit.control.thesis_designs import printed_controller, thesis_plant
from flexdigit.errors import DesignError
from flexdigit.reference import thesis_value

G = thesis_plant("printed")  # 48.7/(s^4 + ...), table 4.1 / 3.5
K39 = printed_controller("39hz")  # 4.7

# Tolerances, each with the reason for its size
PRINTED_POLE_RTOL = 2e-3  # the printed pole 245.04 against our -245.07 (4 printed digits)
SPECTRAL_RADIUS_RTOL = 1e-3  # 1 - 245.07 x 0.02 against the eigenvalues of the sampled loop
CABLE_MODEL_RTOL = 1e-3  # 1.735 deg per command quoted to 4 digits
OFFSET_FREE_ATOL = 1e-3  # the step's final value with the disturbance observer (linear model)
PRINTED_2_DECIMALS_ATOL = 0.01  # a figure quoted to 2 decimals


@pytest.fixture(scope="module")
def study():
    periods = [0.0006, 0.001, 0.002, 0.005, 0.010, 0.020]
    return sample_period_study(G, K39, periods, methods=("tustin", "forward_euler"), t_final_s=2.0)


def test_tustin_at_1ms_is_the_continuous_loop(study):
    # figure 5.4: "almost identical"
    one_ms = study["tustin"][1]
    assert one_ms.period_s == 0.001
    assert one_ms.stable
    assert one_ms.error < 1e-4


def test_tustin_degrades_monotonically_with_the_period(study):
    errors = [loop.error for loop in study["tustin"]]
    assert all(b > a for a, b in zip(errors, errors[1:], strict=False))
    # 5 ms: still within 0.1 %; 20 ms: ~1 % off the continuous response (stable on the printed model)
    assert study["tustin"][3].error < 1e-3 < study["tustin"][5].error < 0.05
    assert all(loop.stable for loop in study["tustin"])


def test_forward_euler_is_unstable_above_its_limit(study):
    # figure 5.6 / 5.7: stable at 5 ms, unstable at 10 and 20 ms (thesis: "above 10 ms very instable")
    fe = {round(loop.period_s, 4): loop for loop in study["forward_euler"]}
    assert fe[0.005].stable
    assert not fe[0.010].stable
    assert not fe[0.020].stable
    limit = forward_euler_stability_limit_s(K39.poles())
    assert limit == pytest.approx(2 / 245.04, rel=PRINTED_POLE_RTOL)  # 8.2 ms, issue 6
    assert thesis_value("digital.euler_unstable_above_s") >= limit
    # the unstable loop pole is the controller's fast pole mapped by z = 1 + sT: 1 - 245.07 x 0.02 = -3.90
    assert fe[0.020].spectral_radius == pytest.approx(abs(1 - 245.0666 * 0.020), rel=SPECTRAL_RADIUS_RTOL)
    # and at 20 ms that pole (39 Hz) is above the 25 Hz Nyquist frequency
    assert 245.04 / (2 * np.pi) > 1 / (2 * 0.020)


def test_forward_euler_loses_the_beam_mode_cancellation(study):
    # the zeros sit on the lightly damped beam mode; z = 1 + sT pushes them off the held plant's poles
    fe = [loop.cancellation_error for loop in study["forward_euler"]]
    tu = [loop.cancellation_error for loop in study["tustin"]]
    assert all(f > 10 * t for f, t in zip(fe, tu, strict=True))
    fe_5 = study["forward_euler"][3]
    beam_zero = fe_5.controller_zeros_z[np.argmin(np.abs(fe_5.controller_zeros_z - 1))]
    assert abs(beam_zero) < 1  # at 5 ms still inside ...
    fe_10 = study["forward_euler"][4]
    assert np.max(np.abs(fe_10.controller_zeros_z)) > 1  # ... above 2 zeta/wn = 5.3 ms outside


def test_one_sample_delay_makes_tustin_at_20ms_worse_but_not_unstable():
    plain = sampled_loop(G, K39, 0.020, "tustin")
    delayed = sampled_loop(G, K39, 0.020, "tustin", delay_samples=1)
    assert delayed.stable
    assert delayed.error > 5 * plain.error


def test_20ms_design_is_stable_and_robust_on_its_model():
    d = design_20ms()
    assert d.period_s == pytest.approx(0.020)
    assert d.delay_samples == 1
    assert d.deg_per_command == pytest.approx(1.735, rel=CABLE_MODEL_RTOL)  # cable model, models.plant docstring
    for gain in (0.7, 1.0, 1.3):  # issue 6: +-30 % plant gain
        loop = closed_loop(d.plant_d, d.controller, gain)
        assert np.max(np.abs(loop.poles())) < 1
        y = np.squeeze(ct.step_response(loop, np.arange(150) * 0.02).outputs)
        assert y[-1] == pytest.approx(1.0, abs=OFFSET_FREE_ATOL)  # offset-free through the disturbance observer
    nominal = np.squeeze(ct.step_response(closed_loop(d.plant_d, d.controller), np.arange(150) * 0.02).outputs)
    t = np.arange(150) * 0.02
    assert nominal.max() < 1.10
    outside = np.nonzero(np.abs(nominal - 1) > 0.02)[0]
    assert t[outside[-1] + 1] < 1.0


def test_20ms_design_tolerates_the_latch_being_early_or_a_sample_late():
    # the twin's serial frame + PWM latch puts 0..19 ms between command and servo; the model assumes 20 ms
    d1 = design_20ms()
    for delay in (0, 2):
        other = design_20ms(delay_samples=delay).plant_d
        assert np.max(np.abs(closed_loop(other, d1.controller).poles())) < 1, delay


def test_observer_sees_the_applied_command():
    d = design_20ms()
    rt = d.runtime()
    assert rt.antiwindup == "back_calculation"
    assert np.array_equal(rt._q_gain, d.aw_gain)
    # the aw gain is the observer's input matrix: exactly one state (the delay) takes the command
    assert np.count_nonzero(d.aw_gain) == 1


def test_design_errors():
    with pytest.raises(DesignError, match="q_rate"):
        Weights(q_rate=-1)
    with pytest.raises(DesignError, match="deg_per_command"):
        design_plant(deg_per_command=0.0)
    with pytest.raises(DesignError, match="method"):
        thesis_controller("simpson")


def test_thesis_controller_forward_euler_at_20ms_is_unstable_as_a_runtime():
    rt = thesis_controller("forward_euler", 0.020)
    assert np.max(np.abs(rt.sys.poles())) == pytest.approx(3.90, abs=PRINTED_2_DECIMALS_ATOL)
    tustin = thesis_controller("tustin", 0.020)
    assert np.max(np.abs(tustin.sys.poles())) < 1


def test_digit_design_20ms_summary_on_the_thesis_rig_is_chapter_5s_design():
    from flexdigit.control.design20ms import digit_design_20ms_summary

    s, d = digit_design_20ms_summary(), design_20ms()
    # the same design as design_20ms(): 20 ms, one sample of transport delay (module docstring, step 1)
    assert (s["period_s"], s["delay_samples"], s["digit_mode"], s["dither"]) == (0.02, 1, None, False)
    assert s["deg_per_command"] == pytest.approx(d.deg_per_command, rel=1e-12)
    assert s["closed_loop_pole_radius"] == pytest.approx(float(np.max(np.abs(d.closed_loop_poles))), rel=1e-12)
    assert s["stable"]
    assert s["closed_loop_pole_radius"] < 1.0
    # offset-free (step 3 of the design): the linear 30 deg step ends at 30 deg; 1e-6 deg is far below a quantum
    step = s["linear_step_30deg"]
    assert step["final"] == pytest.approx(30.0, abs=1e-6)
    assert 0.0 < step["settling_time_s"] < 3.0

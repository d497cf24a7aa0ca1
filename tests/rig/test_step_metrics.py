"""Step figures (rise, 2 % settling, overshoot, steady-state error, IAE) against closed forms.

One implementation scores both the rig's measured steps (``rig.step_test.step_metrics``) and a linear model's
(``control.analysis.step_metrics``), so both are checked here on responses whose figures are known exactly:

- first order ``1 - exp(-t/tau)``: rise (10-90 %) ``tau ln 9``, 2 % settling ``tau ln 50``, no overshoot,
  IAE ``tau (1 - exp(-T/tau))`` over a record of length T;
- second order, ``wn``, ``zeta < 1``: overshoot ``exp(-pi zeta / sqrt(1 - zeta^2))`` at ``t = pi / wd``; the rise
  and settling instants are the roots of the analytic response (``scipy.optimize.brentq`` on the closed form, not
  on the samples) and the IAE is ``scipy.integrate.quad`` of the analytic error between its zeros;
- python-control's ``step_info`` on the same samples, as an independent implementation (it does not interpolate,
  so it agrees within one sample).
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from flexdigit.control.analysis import step_figures
from flexdigit.control.analysis import step_metrics as linear_step_metrics
from flexdigit.rig.step_test import step_metrics

#: crossing times are interpolated linearly: at 1 ms sampling they are good to well under a millisecond
TIME_ATOL_S = 1e-3
#: trapezoidal IAE at 1 ms on responses with time constants >= 0.05 s
IAE_RTOL = 1e-3


def second_order(t, wn, zeta):
    wd = wn * math.sqrt(1 - zeta**2)
    phi = math.acos(zeta)
    return 1 - np.exp(-zeta * wn * t) * np.sin(wd * t + phi) / math.sqrt(1 - zeta**2)


def second_order_oracle(wn, zeta, t_end, band=0.02):
    """Rise, settling, overshoot, IAE of the analytic unit step response, by root finding and quadrature."""
    wd = wn * math.sqrt(1 - zeta**2)

    def y(t):
        return float(second_order(np.array(t), wn, zeta))

    half = math.pi / wd  # the error changes sign every half damped period after the first crossing
    t10 = brentq(lambda t: y(t) - 0.1, 1e-9, half)
    t90 = brentq(lambda t: y(t) - 0.9, 1e-9, half)
    # last instant |y - 1| = band: search backwards over half periods for the last bracket
    envelope_end = -math.log(band * math.sqrt(1 - zeta**2)) / (zeta * wn)  # beyond it the error is below the band
    settle = 0.0
    k = int(envelope_end / half) + 1
    while k >= 0:
        a, b = k * half, (k + 1) * half
        grid = np.linspace(a, b, 200)
        err = np.abs(second_order(grid, wn, zeta) - 1) - band
        idx = np.nonzero(err > 0)[0]
        if idx.size:
            i = idx[-1]
            settle = brentq(lambda t: abs(y(t) - 1) - band, grid[i], grid[min(i + 1, grid.size - 1)])
            break
        k -= 1
    zeros = [0.0] + [(np.pi - math.acos(zeta)) / wd + j * half for j in range(int(t_end / half) + 2)]
    zeros = [z for z in zeros if z < t_end] + [t_end]
    iae = sum(quad(lambda t: abs(1 - y(t)), a, b)[0] for a, b in zip(zeros, zeros[1:], strict=False))
    overshoot = 100 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))
    return t90 - t10, settle, overshoot, half, iae


@pytest.mark.parametrize("tau", [0.05, 0.1, 0.3])
def test_first_order_figures_are_the_closed_forms(tau):
    t = np.arange(0.0, 3.0, 1e-3)
    f = step_figures(t, 1 - np.exp(-t / tau), target=1.0)
    assert f.rise_time_s == pytest.approx(tau * math.log(9), abs=TIME_ATOL_S)
    assert f.settling_time_s == pytest.approx(tau * math.log(50), abs=TIME_ATOL_S)
    assert f.overshoot_percent == 0.0
    assert f.iae == pytest.approx(tau * (1 - math.exp(-t[-1] / tau)), rel=IAE_RTOL)
    assert f.steady_state_error == pytest.approx(0.0, abs=1e-3)


@pytest.mark.parametrize(("wn", "zeta"), [(10.0, 0.2), (20.53, 0.5629), (5.0, 0.7)])
def test_second_order_figures_match_root_finding_and_quadrature(wn, zeta):
    t = np.arange(0.0, 4.0, 1e-3)
    rise, settle, overshoot, peak_t, iae = second_order_oracle(wn, zeta, t[-1])
    f = step_figures(t, second_order(t, wn, zeta), target=1.0)
    assert f.rise_time_s == pytest.approx(rise, abs=TIME_ATOL_S)
    assert f.settling_time_s == pytest.approx(settle, abs=TIME_ATOL_S)
    assert f.overshoot_percent == pytest.approx(overshoot, rel=1e-3)
    assert f.peak_time_s == pytest.approx(peak_t, abs=TIME_ATOL_S)
    assert f.iae == pytest.approx(iae, rel=IAE_RTOL)


def test_agrees_with_python_control_step_info_within_a_sample():
    t = np.arange(0.0, 4.0, 0.02)
    y = second_order(t, 10.0, 0.3)
    ours = step_figures(t, y, target=1.0)
    theirs = ct.step_info(y, timepts=t, final_output=1.0)
    assert ours.overshoot_percent == pytest.approx(theirs["Overshoot"], rel=1e-9)  # same sample, same peak
    assert abs(ours.settling_time_s - theirs["SettlingTime"]) <= 0.02  # theirs: the first sample inside
    assert abs(ours.rise_time_s - theirs["RiseTime"]) <= 0.02


def test_rig_step_a_step_down_after_a_delay_in_degrees_and_commands():
    # 30 -> 10 deg at t = 0.5 s, first order 0.1 s, ending 0.4 deg short of the setpoint (above it)
    tau, per_command = 0.1, 1.735
    t = np.arange(0.0, 4.0, 1e-3)
    y = np.where(t < 0.5, 30.0, 10.4 + 19.6 * np.exp(-(t - 0.5) / tau))
    m = step_metrics(t, y, 10.0, 0.5, per_command, initial_deg=30.0)
    assert m.final_error_deg == pytest.approx(0.4, abs=1e-6)
    assert m.final_error_commands == pytest.approx(0.4 / per_command, abs=1e-6)
    assert m.final_error_quanta == pytest.approx(0.4 / per_command, abs=1e-6)
    # 10 % of the 20 deg step is at 28 deg: 19.6 exp(-t/tau) = 17.6; 90 % at 12 deg: 19.6 exp(-t/tau) = 1.6
    assert m.rise_time_s == pytest.approx(tau * math.log(17.6 / 1.6), abs=TIME_ATOL_S)
    # within 2 % of the step (0.4 deg) of the setpoint: never, the response ends exactly 0.4 deg off
    assert m.settling_time_s == math.inf
    # IAE: 0.4 (t_end - 0.5) + 19.6 tau (1 - exp(-(t_end - 0.5)/tau))
    duration = t[-1] - 0.5
    assert m.iae_deg_s == pytest.approx(0.4 * duration + 19.6 * tau * (1 - math.exp(-duration / tau)), rel=IAE_RTOL)
    assert m.overshoot_percent == 0.0
    assert m.bounded


def test_a_response_that_never_settles_or_diverges():
    t = np.arange(0.0, 3.0, 0.02)
    ringing = 1 + 0.5 * np.sin(2 * np.pi * 2 * t)  # a limit cycle around the setpoint
    f = step_figures(t, ringing, target=1.0)
    # the peak is the largest sample (not interpolated): 2 Hz sampled at 50 Hz misses the crest by 0.2 %
    assert f.settling_time_s == math.inf
    assert f.overshoot_percent == pytest.approx(50.0, rel=0.005)
    assert not step_figures(t, np.exp(3 * t), target=1.0).bounded
    assert math.isnan(step_figures(t, np.full(t.size, np.nan), target=1.0).settling_time_s)


def test_linear_model_metrics_use_the_same_figures():
    # 1/(s + 1) from python-control's simulation: the same closed forms as the sampled first order
    m = linear_step_metrics(ct.tf([1.0], [1.0, 1.0]), t_final=10)
    assert m["settling_time_s"] == pytest.approx(math.log(50), abs=0.005)
    assert m["rise_time_s"] == pytest.approx(math.log(9), abs=0.005)
    assert m["iae"] == pytest.approx(1.0, rel=0.001)

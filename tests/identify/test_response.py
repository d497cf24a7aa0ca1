"""Response features against closed forms, python-control's step_info and the thesis tables."""

import math

import control
import numpy as np
import pytest
from scipy import optimize

from flexdigit.errors import DataFileError
from flexdigit.identify.fit import second_order_response
from flexdigit.identify.response import (
    analyze_response,
    free_response,
    overshoot_from_zeta,
    settling_formula_bias,
    zeta_from_log_decrement,
    zeta_from_overshoot,
)
from flexdigit.reference import thesis_value


def test_zeta_from_overshoot_reproduces_tables_3_1_and_3_2():
    for table in ("release_tests_without_housing", "release_tests_with_housing"):
        os_ = np.array(thesis_value(f"digit.{table}.percent_overshoot"), dtype=float)
        zeta = np.array(thesis_value(f"digit.{table}.zeta"))
        ok = np.isfinite(os_)  # table 3.2 row 2's %OS is garbled in print
        got = np.array([zeta_from_overshoot(v) for v in os_[ok]])
        np.testing.assert_allclose(got, zeta[ok], atol=5e-5)  # printed to 4 decimals


def test_release_percent_overshoot_is_first_undershoot_over_initial_deflection():
    # exact free decay, zeta 0.068: |x(pi/wd)| / x0 = exp(-zeta pi / sqrt(1 - zeta^2)) (closed form)
    wn, zeta = 13.1, 0.068
    t = np.linspace(0, 8, 40001)
    y = 0.3 + 2.0 * free_response(t, wn, zeta)
    f = analyze_response(t, y, "release", final_value=0.3)
    assert f.percent_overshoot == pytest.approx(overshoot_from_zeta(zeta), rel=1e-5)
    assert f.zeta_os == pytest.approx(zeta, rel=1e-4)
    assert f.peak_time_s == pytest.approx(math.pi / (wn * math.sqrt(1 - zeta**2)), abs=2e-4)
    assert f.wd_rad_s == pytest.approx(wn * math.sqrt(1 - zeta**2), rel=1e-4)
    assert f.wn_damped_rad_s == pytest.approx(wn, rel=1e-4)
    assert f.zeta_log_decrement == pytest.approx(zeta, rel=1e-3)


def test_step_features_match_python_control_step_info():
    sys = control.tf([421.5], [1, 23.11, 421.5])  # MT(s) of 3.2.4
    t = np.linspace(0, 2, 20001)
    y = control.step_response(sys, t).outputs
    ref = control.step_info(sys, T=t)
    f = analyze_response(t, y, "step")
    assert f.percent_overshoot == pytest.approx(ref["Overshoot"], rel=1e-4)
    assert f.peak_time_s == pytest.approx(ref["PeakTime"], abs=2e-4)
    assert f.rise_time_s == pytest.approx(ref["RiseTime"], abs=2e-4)
    assert f.settling_time_s == pytest.approx(ref["SettlingTime"], abs=2e-4)


def test_settling_time_and_bias_of_thesis_wn_formula_against_root_finding():
    # exact 2 % settling time of the servo model from the last crossing of |x| = 0.02 (scipy brentq)
    wn, zeta = 20.53, 0.5629
    wd = wn * math.sqrt(1 - zeta**2)
    ts = optimize.brentq(lambda t: free_response([t], wn, zeta)[0] + 0.02, math.pi / wd, 2 * math.pi / wd)
    assert settling_formula_bias([zeta])[0] == pytest.approx(4 / (zeta * ts * wn) - 1, rel=1e-4)
    assert settling_formula_bias([zeta])[0] == pytest.approx(0.2121, abs=5e-4)  # +21 % on the servo


def test_settling_formula_bias_small_for_light_damping_erratic_for_heavy():
    light = settling_formula_bias(np.array([0.001, 0.01, 0.068, 0.1]))
    # envelope: 4 / ln(50 / sqrt(1 - z^2)) - 1 = +2.2 % as zeta -> 0, plus up to half a damped period earlier
    assert light[0] == pytest.approx(4 / math.log(50) - 1, abs=1e-3)
    assert np.all((light > 0.02) & (light < 0.06))
    heavy = settling_formula_bias(np.linspace(0.3, 0.9, 13))
    # the last exit from the band jumps from one extremum to the next: the error swings over 30 points
    assert heavy.max() - heavy.min() > 0.3
    assert heavy.min() < 0 < heavy.max()


def test_zeta_from_log_decrement_inverts_closed_form():
    zeta = 0.068
    delta = 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
    assert zeta_from_log_decrement(delta) == pytest.approx(zeta, rel=1e-12)


def test_release_instant_found_after_a_hold(release):
    t, y = release(0, noise=0.01, hold_s=0.73)
    from flexdigit.identify.filters import apply_filter

    f = analyze_response(t, apply_filter(t, y, "butter"), "release")
    assert f.t0_s == pytest.approx(0.73, abs=0.01)


def test_overdamped_release_has_no_undershoot_and_says_so():
    t = np.linspace(0, 3, 1500)
    y = second_order_response(t, "release", 10.0, 1.5, 0.0, 1.0, 0.0)
    with pytest.raises(DataFileError, match="rec.csv:sg1: no undershoot in this release test"):
        analyze_response(t, y, "release", source="rec.csv:sg1")


def test_overdamped_step_has_no_overshoot_and_says_so():
    t = np.linspace(0, 3, 1500)
    y = second_order_response(t, "step", 10.0, 1.2, 0.0, 1.0, 0.0)
    with pytest.raises(DataFileError, match="no overshoot in this step test"):
        analyze_response(t, y, "step")

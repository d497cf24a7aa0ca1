"""The cable-guide friction noise (taut cable only): zero when slack, proportional to the tension, seeded, and its
file round trip (its calibration from a measured repeatability or a score: tests/calibrate/test_friction.py).

Reference values: the model of :mod:`flexdigit.twin.sensors` (sd of the friction moment at a gauge's section =
ratio x e x T, e the cable eccentricity of RigParams); statistical tolerances are set from the standard error of
a standard deviation estimated from N readings, 1/sqrt(2 N), with a margin of 4-5 of those.
"""

import numpy as np
import pytest

from flexdigit.errors import DataFileError, ParameterError
from flexdigit.params import RigParams
from flexdigit.twin.calibration import Calibration, default_calibration, load_calibration, save_calibration
from flexdigit.twin.twin import Twin, cached_digit, friction_sd_v, static_gauges_v

RATIO = 0.1


def _cal(ratio=RATIO):
    return default_calibration().replace(cable_friction_ratio=ratio)


def test_no_friction_without_a_taut_cable():
    # chapter 6: cable detached; and a vertical digit below the equilibrium command, where the cable is slack
    for kwargs in ({"cable": False, "orientation": "horizontal"}, {"orientation": "vertical", "command": 0}):
        a, b = Twin(seed=3, calibration=_cal(), **kwargs), Twin(seed=3, calibration=_cal(0.0), **kwargs)
        assert a.cable_tension_n() == 0.0
        for _ in range(5):
            a.advance(0.02)
            b.advance(0.02)
            np.testing.assert_array_equal(a.read()[0], b.read()[0])
    detached = static_gauges_v([0.025] * 4, [0.2] * 4, None, calibration=_cal(), seed=5)
    np.testing.assert_array_equal(detached, static_gauges_v([0.025] * 4, [0.2] * 4, None, calibration=_cal(0), seed=5))
    _, sol = static_gauges_v(
        [0.0], [0.0], [0], orientation="vertical", calibration=_cal(), adc=False, return_solution=True
    )
    assert sol.tension_n[0] == 0.0
    assert np.all(friction_sd_v(sol, calibration=_cal(), orientation="vertical") == 0.0)


def test_friction_sd_is_ratio_times_eccentricity_times_tension_through_the_local_compliance():
    params = RigParams()
    _, sol = static_gauges_v(
        [0.0, 0.025, 0.0375], [0.0, 0.2, 0.1], [0, 20, 40], calibration=_cal(), adc=False, return_solution=True
    )
    assert np.all(np.diff(sol.tension_n) > 0)  # more command, more tension
    chain = cached_digit(params, _cal(), True, "horizontal", 3)
    # the half bridge's volts per curvature: gain x excitation x channel gain x GF t / 4 (E 2.4, axial strain ~ 0)
    s = params.sensors
    v_per_kappa = (
        s.amplifier_gain_v_per_v
        * s.excitation_v
        * np.array(_cal().channel_gain)
        * s.gauge_factor
        * params.geometry.strip_thickness_m
        / 4
    )
    expected = (
        RATIO * params.geometry.cable_eccentricity_m * sol.tension_n[:, None] * chain.gauge_curvature_per_moment
    ) * v_per_kappa
    np.testing.assert_allclose(friction_sd_v(sol, calibration=_cal()), expected, rtol=1e-3)
    np.testing.assert_allclose(friction_sd_v(sol, calibration=_cal(2 * RATIO)), 2 * expected, rtol=1e-3)


def test_static_friction_draws_are_seeded_and_leave_the_white_noise_alone():
    args = ([0.025] * 3, [0.2] * 3, [0, 20, 40])
    one = static_gauges_v(*args, calibration=_cal(), seed=7, adc=False)
    np.testing.assert_array_equal(one, static_gauges_v(*args, calibration=_cal(), seed=7, adc=False))
    assert not np.array_equal(one, static_gauges_v(*args, calibration=_cal(), seed=8, adc=False))
    # the difference from the friction-free readings is the friction alone: sd x its own stream's draws
    without = static_gauges_v(*args, calibration=_cal(0.0), seed=7, adc=False)
    _, sol = static_gauges_v(*args, calibration=_cal(), adc=False, return_solution=True)
    xi = np.random.default_rng([7, 1]).standard_normal((3, 3))
    np.testing.assert_allclose(one - without, friction_sd_v(sol, calibration=_cal()) * xi, rtol=1e-3, atol=1e-7)


def test_static_spread_matches_white_plus_friction():
    n = 4000
    volts, sol = static_gauges_v([0.025] * n, [0.2] * n, [40] * n, calibration=_cal(), seed=1, return_solution=True)
    expected = np.sqrt(np.array(_cal().noise_white_v) ** 2 + friction_sd_v(sol, calibration=_cal())[0] ** 2)
    np.testing.assert_allclose(np.std(volts, axis=0), expected, rtol=4 / np.sqrt(2 * n) + 0.01)


def test_dynamic_twin_reading_spread_matches_the_static_model():
    # settled at command 40, horizontal, jolted before every reading (a weight re-hung): the readings scatter as
    # white noise plus friction at the static tension
    cal = _cal()
    twin = Twin(seed=2, calibration=cal, orientation="horizontal", command=40)
    n = 400
    reads = []
    for _ in range(n):
        twin.advance(0.02)
        twin.disturb()
        reads.append(twin.read()[0])
    _, sol = static_gauges_v([0.0], [0.0], [40], calibration=cal, adc=False, return_solution=True)
    assert twin.cable_tension_n() == pytest.approx(sol.tension_n[0], rel=1e-3)
    expected = np.sqrt(np.array(cal.noise_white_v) ** 2 + friction_sd_v(sol, calibration=cal)[0] ** 2)
    np.testing.assert_allclose(np.std(reads, axis=0), expected, rtol=5 / np.sqrt(2 * n))
    again = Twin(seed=2, calibration=cal, orientation="horizontal", command=40)
    again.advance(0.02)
    again.disturb()
    np.testing.assert_array_equal(again.read()[0], reads[0])


def test_friction_state_is_held_until_the_cable_is_jolted():
    # no jolt yet (the servo only pulled the cable): readings scatter as the white noise alone
    cal = _cal()
    twin = Twin(seed=4, calibration=cal, orientation="horizontal", command=40)
    twin.advance(0.02)
    quiet = []
    for _ in range(300):
        twin.advance(0.02)
        quiet.append(twin.read()[0])
    np.testing.assert_allclose(np.std(quiet, axis=0), cal.noise_white_v, rtol=5 / np.sqrt(600))
    # one jolt: every later reading carries the same offset, the white noise still the only scatter
    twin.disturb()
    held = []
    for _ in range(300):
        twin.advance(0.02)
        held.append(twin.read()[0])
    np.testing.assert_allclose(np.std(held, axis=0), cal.noise_white_v, rtol=5 / np.sqrt(600))
    _, sol = static_gauges_v([0.0], [0.0], [40], calibration=cal, adc=False, return_solution=True)
    shift = np.abs(np.mean(held, axis=0) - np.mean(quiet, axis=0))
    assert np.all(shift < 4 * friction_sd_v(sol, calibration=cal)[0])  # one draw of the friction, not more
    assert np.any(shift > 10 * np.array(cal.noise_white_v) / np.sqrt(300))  # and visibly there
    # hanging a weight is a jolt too
    before = twin._friction_xi.copy()
    twin.place_load(0.025, 0.2)
    assert not np.array_equal(before, twin._friction_xi)


def test_friction_ratio_is_validated_and_round_trips(tmp_path):
    with pytest.raises(ParameterError, match="cable_friction_ratio"):
        Calibration(cable_friction_ratio=-0.1)
    with pytest.raises(ParameterError, match="cable_friction_ratio"):
        Calibration(cable_friction_ratio=1.5)
    path = save_calibration(_cal(0.03), tmp_path / "cal.toml")
    assert load_calibration(path).cable_friction_ratio == 0.03
    (tmp_path / "bad.toml").write_text('based_on = "default"\n[calibration]\ncable_friction_ratio = "a lot"\n')
    with pytest.raises(DataFileError, match="bad.toml.*cable_friction_ratio"):
        load_calibration(tmp_path / "bad.toml")

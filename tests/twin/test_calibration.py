"""The default calibration against the thesis (tables 3.1, 3.2, 3.6, E 3.20-3.22), and calibrate() itself.

The release tests and the sweep are run as experiments on the twin (through the sensor chain, with noise) and
analysed like measurements, so the check covers the dynamics, the servo and the sensors, not only the fit.
Tolerances from issue 3: wn and zeta within 3 %, gauge-volt slopes within 5 %, deflections within the 0.5 mm
reading resolution where the thesis's own model agrees with its measurement.
"""

import numpy as np
import pytest

from flexdigit.errors import DataFileError
from flexdigit.reference import thesis_value
from flexdigit.twin import records as ex
from flexdigit.twin.calibration import (
    Calibration,
    CalibrationTargets,
    calibrate,
    default_calibration,
    default_fit_record,
    fit_damped_sine,
    load_calibration,
    noise_from_record,
    save_calibration,
)

RELEASE_RTOL = 0.03
SLOPE_RTOL = 0.05
DEFLECTION_ABS_MM = 0.5


#: Record lengths of the simulated release tests (s), as the report uses them: the bare digit's amplitude decays
#: with a time constant 1/(zeta wn) = 39 s, so a 12 s record holds too little decay for a zeta to survive the
#: noise (median over the gauges off by up to 3.1 % over 20 seeds at 12 s, 0.6-1.6 % at 30 s); the housed one's
#: is 1.1 s, and 8 s holds all of it.
RELEASE_DURATION_S = {False: 30.0, True: 8.0}


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize(
    ("housing", "table"),
    [pytest.param(False, "without_housing", marks=pytest.mark.slow), (True, "with_housing")],
)
def test_release_tests_reproduce_tables_3_1_and_3_2(housing, table, seed):
    # Analysed like the thesis's measurements: a damped-sine fit per gauge. wn is checked on every gauge (it is
    # set by the mechanics, and every gauge sees it to ~0.5 %); zeta on the median over the three gauges, as the
    # report does, because gauge 3 (nearest the tip, the smallest strain: ~14 mV of swing over 2 mV of white
    # noise and drift) alone scatters by +-5 % even on 30 s records. Several seeds, so a pass is not seed luck.
    res = ex.release_test(housing=housing, duration_s=RELEASE_DURATION_S[housing], sample_rate_hz=500, seed=seed)
    t = res.column("time_s")
    fits = [fit_damped_sine(t, res.column(f"gauge{gauge}_v")) for gauge in (1, 2, 3)]
    wn_thesis = thesis_value(f"digit.release_tests_{table}.wn_avg_rad_s")
    zeta_thesis = thesis_value(f"digit.release_tests_{table}.zeta_avg")
    for gauge, fit in enumerate(fits, start=1):
        assert fit["wn_rad_s"] == pytest.approx(wn_thesis, rel=RELEASE_RTOL), gauge
    zeta = float(np.median([fit["zeta"] for fit in fits]))
    assert zeta == pytest.approx(zeta_thesis, rel=RELEASE_RTOL)


def test_actuation_sweep_reproduces_e_3_20_to_3_22():
    res = ex.actuation_sweep(settle_s=2.5, samples=5, seed=2)
    commands = res.column("command")
    for gauge, fit in enumerate(thesis_value("conversion.v_sg_fit"), start=1):
        slope, offset = np.polyfit(commands, res.column(f"gauge{gauge}_v"), 1)
        assert slope == pytest.approx(fit["slope"], rel=SLOPE_RTOL)
        assert offset == pytest.approx(fit["offset"], abs=0.02)


def test_deflections_match_table_3_6_where_the_thesis_model_agrees():
    from flexdigit.params import RigParams
    from flexdigit.twin.twin import Twin

    targets = CalibrationTargets.from_thesis()
    weight = np.array(targets.deflection_weight)
    measured = np.array(targets.deflection_mm)
    assert weight.sum() >= 15  # 19 readings of table 3.6 are within 0.5 mm of table 3.4
    p = RigParams()
    for c, command in enumerate(targets.deflection_commands):
        if not weight[:, c].any():
            continue
        twin = Twin(seed=0, command=command)
        y_mm = twin.deflection_m(p.geometry.gauge_positions_m) * 1e3
        for g in range(3):
            if weight[g, c]:
                assert y_mm[g] == pytest.approx(measured[g, c], abs=DEFLECTION_ABS_MM), (g + 1, command)


@pytest.mark.slow
def test_recalibrating_reproduces_the_packaged_default():
    # the friction level's only evidence is the thesis's actuated corr2, scored by the tactile pipeline (~15 s)
    from flexdigit.tactile.thesis_experiments import actuated_corr2_score

    result = calibrate(CalibrationTargets.from_thesis(), friction_score=actuated_corr2_score)
    default = default_calibration()
    for name, value in default.to_dict().items():
        np.testing.assert_allclose(getattr(result.calibration, name), value, rtol=1e-5, atol=1e-12, err_msg=name)
    record = default_fit_record()
    assert len(record["residuals"]) == len(result.residuals)


@pytest.mark.slow
def test_calibrate_recovers_known_parameters_from_synthetic_records():
    # a user with a rig: records from a twin with a *different* calibration, fitted back from scratch
    truth = default_calibration().replace(support_mass_kg=(0.012,) * 3, housing_beta_s=0.03)
    bare = ex.release_test(housing=False, duration_s=10.0, sample_rate_hz=250, calibration=truth, seed=4)
    housed = ex.release_test(housing=True, duration_s=5.0, sample_rate_hz=250, calibration=truth, seed=5)
    # 12 readings a command: the cable-guide friction (taut cable) scatters single readings by ~10-40 mV
    sweep = ex.actuation_sweep(range(8, 44, 5), settle_s=2.5, samples=12, calibration=truth, seed=6)
    volts = np.column_stack([sweep.column(f"gauge{g}_v") for g in (1, 2, 3)])
    targets = CalibrationTargets.from_records(
        release_bare=(bare.column("time_s"), bare.column("gauge2_v")),
        release_housing=(housed.column("time_s"), housed.column("gauge2_v")),
        sweep=(sweep.column("command"), volts),
    )
    start = default_calibration().replace(housing_ei_n_m2=(truth.housing_ei_n_m2[1],) * 3)
    got = calibrate(targets, initial=start).calibration
    assert got.support_mass_kg[0] == pytest.approx(0.012, rel=0.02)
    assert got.housing_beta_s == pytest.approx(0.03, rel=0.05)
    np.testing.assert_allclose(got.channel_gain, truth.channel_gain, rtol=0.05)


def test_noise_estimates_from_a_resting_record():
    rng = np.random.default_rng(0)
    t = np.arange(0, 120, 0.01)
    walk = np.cumsum(0.003 * np.sqrt(0.01) * rng.standard_normal((t.size, 2)), axis=0)
    v = walk + np.array([0.002, 0.005]) * rng.standard_normal((t.size, 2))
    white, drift = noise_from_record(t, v)
    np.testing.assert_allclose(white, [0.002, 0.005], rtol=0.05)
    np.testing.assert_allclose(drift, [0.003, 0.003], rtol=0.3)


def test_calibration_file_round_trip_and_errors(tmp_path):
    cal = default_calibration().replace(pot_noise_v=0.001)
    path = save_calibration(cal, tmp_path / "cal.toml")
    assert load_calibration(path) == cal
    (tmp_path / "bad.toml").write_text("[calibration]\nsupport_mass_kg = [-1.0, 0.01, 0.01]\n")
    with pytest.raises(DataFileError, match="bad.toml.*support_mass_kg"):
        load_calibration(tmp_path / "bad.toml")
    (tmp_path / "typo.toml").write_text("[calibration]\nsuport_mass = 1\n")
    with pytest.raises(DataFileError, match="unknown key 'suport_mass'"):
        load_calibration(tmp_path / "typo.toml")
    (tmp_path / "broken.toml").write_text("[calibration\n")
    with pytest.raises(DataFileError, match="not valid TOML"):
        load_calibration(tmp_path / "broken.toml")


def test_calibration_rejects_nan():
    with pytest.raises(ValueError, match="strip_beta_s"):
        Calibration(strip_beta_s=float("nan"))

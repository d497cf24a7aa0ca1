"""Identification of the twin's simulated experiments recovers the thesis's E(s) and MT(s) (issue 4: within 3 %)."""

import json

import pytest

from flexdigit.cli import main
from flexdigit.identify.identification import identify
from flexdigit.identify.timeseries import read_timeseries, series_from_table
from flexdigit.params import RigParams
from flexdigit.reference import thesis_value
from flexdigit.twin.calibration import default_calibration
from flexdigit.twin.digit import build_digit
from flexdigit.twin.records import release_test, servo_step_test

# the thesis's models: E(s) of 3.1.2 (table 3.2 averages) and MT(s) of 3.2.4
DIGIT_WN, DIGIT_ZETA = (
    thesis_value("digit.release_tests_with_housing.wn_avg_rad_s"),
    thesis_value("digit.release_tests_with_housing.zeta_avg"),
)
SERVO_WN, SERVO_ZETA = thesis_value("actuator.model.wn_rad_s"), thesis_value("actuator.model.zeta")


@pytest.fixture(scope="module")
def release_file(tmp_path_factory):
    res = release_test(duration_s=5.0, sample_rate_hz=500.0, seed=0)
    return res.save(tmp_path_factory.mktemp("twin") / "release.csv")  # as a user would: through a file


def test_digit_from_twin_release_test_gauge1(release_file):
    r = identify(read_timeseries(release_file, "gauge1"), "release", method="lsq")
    assert r.wn_rad_s == pytest.approx(DIGIT_WN, rel=0.03)
    assert r.zeta == pytest.approx(DIGIT_ZETA, rel=0.03)


def test_digit_from_twin_release_test_tip(release_file):
    r = identify(read_timeseries(release_file, "tip_deflection"), "release", method="lsq")
    assert r.wn_rad_s == pytest.approx(DIGIT_WN, rel=0.03)
    assert r.zeta == pytest.approx(DIGIT_ZETA, rel=0.03)


@pytest.mark.slow  # 10-30 s: 30 s of the twin at 1 kHz, three 30,000-sample fits
def test_bare_digit_every_gauge_of_a_30_s_twin_release_is_identified(tmp_path):
    # the bare strip barely decays (zeta 0.0025: still half its deflection after 30 s), and gauge 3, near the tip,
    # swings less on its first undershoot than after it; each gauge must give the chain's first linear mode (a
    # release test integrates at 10 ms, twin.records: within 0.03 % on wn and 0.2 % on zeta)
    wn, zeta = (float(v[0]) for v in build_digit(RigParams(), default_calibration(), housing=False).linear_modes())
    path = release_test(housing=False, duration_s=30.0, seed=0).save(tmp_path / "bare.csv")
    for gauge in ("gauge1", "gauge2", "gauge3"):
        r = identify(read_timeseries(path, gauge), "release", method="lsq")
        assert r.wn_rad_s == pytest.approx(wn, rel=0.002), gauge
        assert r.zeta == pytest.approx(zeta, rel=0.03), gauge


@pytest.mark.parametrize("seed", [0, 1])
def test_servo_from_twin_step_test(seed, tmp_path):
    res = servo_step_test(command_to=51, sample_rate_hz=500.0, seed=seed)
    series = read_timeseries(res.save(tmp_path / "step.parquet"), "pot")
    assert series.u is not None  # the command column gives the step instant and size
    r = identify(series, "step", method="lsq")
    assert r.wn_rad_s == pytest.approx(SERVO_WN, rel=0.03)
    assert r.zeta == pytest.approx(SERVO_ZETA, rel=0.03)
    # gain: pot volts per command, (2.4755 - 0.46688) V over 254 commands (3.2.4)
    assert r.gain == pytest.approx((2.4755 - 0.46688) / 254, rel=0.03)
    # the servo board latches the command at its next 20 ms frame (5.2): the fitted instant is after the request
    assert 0.1 <= r.t0_s <= 0.1 + 0.021


def test_thesis_method_on_twin_step_overestimates_wn():
    res = servo_step_test(command_to=51, sample_rate_hz=500.0, seed=0)
    series = series_from_table(res, "pot")  # in memory this time
    r = identify(series, "step", method="thesis")
    assert r.zeta == pytest.approx(SERVO_ZETA, rel=0.05)
    assert r.wn_rad_s > 1.1 * SERVO_WN  # the +21 % bias of 4/(zeta Ts) at this damping (test_response)


def test_cli_reads_the_twin_file_with_the_readme_channel_name(release_file, capsys):
    # docs/guide/identify.md says --channel sg1; the twin's files name the column gauge1_v: sgN and gaugeN are one gauge
    assert main(["identify", "release", str(release_file), "--channel", "sg1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["channel"] == "gauge1"
    assert out["unit"] == "V"
    assert out["wn_rad_s"] == pytest.approx(DIGIT_WN, rel=0.03)


def test_twin_identification_of_a_stiff_damped_digit(tmp_path):
    # tests/digits.py's 0.16 m one-section digit decays in 1 / (zeta wn) = 0.16 s: its fast release record is cut
    # to 8 of those (not 5 s of exact zero at the tip, where the robust fit's intervals scattered, zeta +-61 %),
    # and the least-squares fits give back the twin's own housed mode (its linear modal analysis) within issue 4's 3 %
    # (the 20 mm release is not quite linear: zeta 1.1 % below)
    from digits import write_digit
    from flexdigit.identify.chapter3_identification import RELEASE_TIME_CONSTANTS, twin_identification
    from flexdigit.params import load_params
    from flexdigit.twin.calibration import use_calibration
    from flexdigit.twin.digit_calibration import calibration_for
    from flexdigit.twin.twin import release_dynamics

    params = load_params(write_digit("one-section", tmp_path))
    calibration = calibration_for(params)  # as reproduce --params runs it
    mode = release_dynamics(params, calibration)
    with use_calibration(calibration):
        r = twin_identification(params, seed=0, fast=True)
    tau = 1.0 / (mode.zeta_housing * mode.wn_housing_rad_s)
    assert r.tip.t_s[-1] == pytest.approx(RELEASE_TIME_CONSTANTS * tau, abs=0.01)
    for fit in (r.tip_fits["lsq"], r.fits[("digit", "lsq")]):
        assert fit.wn_rad_s == pytest.approx(mode.wn_housing_rad_s, rel=0.03)
        assert fit.zeta == pytest.approx(mode.zeta_housing, rel=0.03)

"""Simulated experiments: tables, metadata, files, determinism, bad input; and the CLI."""

import json

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.twin import records as ex


def test_static_load_test_follows_the_thesis_protocol():
    # 6.4-6.5: 3 weights x 16 positions x 25 repetitions, plus the no-load case
    t = ex.static_load_test(
        [0.0125, 0.025, 0.0075], [c / 100 for c in (0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 24)], seed=0
    )
    assert t.table.num_rows == 3 * 16 * 25 + 25
    assert set(np.unique(t.column("command"))) == {-1}
    np.testing.assert_allclose(t.column("position_from_base_m") + t.column("position_from_tip_m"), 0.27)
    assert t.metadata["units"]["gauge1_v"] == "V"
    assert t.metadata["seed"] == 0


def test_experiments_are_deterministic_per_seed():
    a = ex.servo_step_test(duration_s=0.3, seed=7)
    b = ex.servo_step_test(duration_s=0.3, seed=7)
    c = ex.servo_step_test(duration_s=0.3, seed=8)
    assert a.table.equals(b.table)
    assert not a.table.equals(c.table)


#: identify's fit of an 8 s housed release test (three gauges, 2 mV noise): wn to a few 0.01 %; the 20 ms serial-frame
#: integration step shortened the period by 0.23 %, what a calibration fitted to such records carries into stiffness
RELEASE_WN_RTOL = 0.001


def test_a_simulated_release_test_rings_at_the_twins_own_linear_modes():
    # the twin's linear modes (an eigen-analysis, no integration) are what its release record must show
    from flexdigit.identify.identification import identify
    from flexdigit.identify.timeseries import TimeSeries
    from flexdigit.params import RigParams
    from flexdigit.twin.calibration import packaged_calibration
    from flexdigit.twin.digit import build_digit

    cal = packaged_calibration()
    wn = float(build_digit(RigParams(), cal, housing=True).linear_modes()[0][0])
    rec = ex.release_test(housing=True, duration_s=8.0, sample_rate_hz=500, seed=1, calibration=cal)
    fits = [
        identify(TimeSeries.from_arrays(rec.column("time_s"), rec.column(f"gauge{g}_v"), channel=f"g{g}"), "release")
        for g in (1, 2, 3)
    ]
    assert float(np.median([f.wn_rad_s for f in fits])) == pytest.approx(wn, rel=RELEASE_WN_RTOL)


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_save_and_load_keep_table_and_metadata(tmp_path, suffix):
    res = ex.static_load_test([0.025], [0.0, 0.1], commands=[0, 20], repetitions=3, seed=2)
    path = res.save(tmp_path / f"run{suffix}")
    back = ex.TwinRecord.load(path)
    assert back.metadata["experiment"] == "static_load_test"
    assert back.metadata["arguments"]["commands"] == [0, 20]
    assert back.metadata["params"]["geometry"]["digit_length_m"] == 0.27
    for name in res.table.column_names:
        np.testing.assert_allclose(back.column(name), res.column(name))


def test_loading_a_foreign_file_says_what_is_wrong(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    pq.write_table(pa.table({"x": [1, 2]}), tmp_path / "other.parquet")
    with pytest.raises(DataFileError, match="other.parquet.*metadata"):
        ex.TwinRecord.load(tmp_path / "other.parquet")
    (tmp_path / "junk.parquet").write_text("not parquet")
    with pytest.raises(DataFileError, match="junk.parquet"):
        ex.TwinRecord.load(tmp_path / "junk.parquet")


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: ex.static_load_test([0.01], [0.30]), "beyond the tip"),
        (lambda: ex.static_load_test([-0.01], [0.1]), "loads_kg"),
        (lambda: ex.static_load_test([0.01], [0.1], commands=[255]), "commands"),
        (lambda: ex.servo_step_test(command_to=300), "command_to"),
        (lambda: ex.release_test(tip_deflection_m=float("nan")), "tip_deflection_m"),
        (lambda: ex.actuation_sweep([8, 9.5]), "commands"),
        (lambda: ex.release_test(duration_s=-1), "duration_s"),
    ],
)
def test_bad_experiment_inputs_raise_clear_errors(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def test_cli_simulate_writes_a_file_and_reports_json(tmp_path, capsys):
    out = tmp_path / "step.parquet"
    assert main(["simulate", "step", "--out", str(out), "--duration", "0.5", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["experiment"] == "servo_step_test"
    assert data["rows"] == 501
    assert ex.TwinRecord.load(out).table.num_rows == 501
    # the potentiometer settles on the params line for command 51 (3.2.4)
    assert data["findings"]["pot_end_v"] == pytest.approx(0.46688 + 51 * (2.4755 - 0.46688) / 254, abs=0.02)


def test_cli_bad_input_is_one_line_exit_2(tmp_path, capsys):
    assert main(["simulate", "load", "--out", str(tmp_path / "x.parquet"), "--positions-cm", "30"]) == 2
    err = capsys.readouterr().err
    assert "beyond the tip" in err
    assert "Traceback" not in err
    assert main(["simulate", "sweep", "--out", str(tmp_path / "x.csv"), "--commands", "8..x"]) == 2
    assert "--commands" in capsys.readouterr().err


@pytest.mark.parametrize("seed, orientation", [(0, "vertical"), (3, "horizontal")])
def test_actuation_sweep_on_the_compiled_kernel_reads_what_the_numpy_twin_reads(seed, orientation):
    # the sweep steps the digit with the compiled kernel by default; the numpy twin is the reference: its readings
    # (after the ADC's quantisation) must be the same numbers, not just close, over the operating commands. Exact
    # is fair after the ADC: a reading is a 153 uV code, and the two paths' floats agree to ~1e-15 V, so a code could
    # only differ for a voltage within that of a code boundary (odds ~1e-11 a reading)
    kwargs = dict(commands=range(8, 44, 5), settle_s=0.6, samples=5, seed=seed, orientation=orientation)
    fast, reference = ex.actuation_sweep(**kwargs), ex.actuation_sweep(**kwargs, compiled=False)
    assert fast.table.equals(reference.table)


@pytest.mark.parametrize("housing, seed", [(False, 4), (True, 0)])
def test_release_test_on_the_compiled_kernel_reads_what_the_numpy_twin_reads(housing, seed):
    # the release test steps the digit with the compiled kernel by default; the numpy twin is the reference: the
    # gauge readings (quantised, see above) the same numbers, the tip deflection (not quantised) within 1e-15 m
    kwargs = dict(housing=housing, duration_s=3.0, sample_rate_hz=500, seed=seed)
    fast, reference = ex.release_test(**kwargs), ex.release_test(**kwargs, compiled=False)
    for gauge in ("gauge1_v", "gauge2_v", "gauge3_v"):
        np.testing.assert_array_equal(fast.column(gauge), reference.column(gauge))
    np.testing.assert_allclose(
        fast.column("tip_deflection_m"), reference.column("tip_deflection_m"), rtol=0, atol=1e-15
    )


def test_release_orientation_hangs_only_a_digit_that_buckles_tip_up(tmp_path):
    # tests/digits.py: 0.5 m, 5 sections buckles tip up under its supports' weight (release_test refuses it so);
    # the thesis rig and the short digit stand (the thesis mounted its rig tip up, 2.2.4)
    from digits import write_digit
    from flexdigit.params import load_params
    from flexdigit.twin.digit_calibration import calibration_for
    from flexdigit.twin.records import release_orientation

    assert release_orientation() == "vertical"
    assert release_orientation(load_params(write_digit("short", tmp_path))) == "vertical"
    long = load_params(write_digit("five-sections-eight-gauges", tmp_path))
    assert release_orientation(long) == "hanging"
    cal = calibration_for(long)
    with pytest.raises(ParameterError, match="buckles"):
        ex.release_test(duration_s=0.1, params=long, calibration=cal)
    record = ex.release_test(duration_s=0.1, params=long, calibration=cal, orientation=release_orientation(long, cal))
    assert np.isfinite(record.column("tip_deflection_m")).all()

"""``flexdigit calibrate``'s readers on recordings laid out as other tools write them (issue 11 item 3, review).

Known answers: closed-form free decays (known wn, zeta) and tables of known numbers, written here with the standard
library's :mod:`csv` writer: units in parentheses or brackets (``SG 1 (mV)``, ``Time (ms)``), ``;`` with decimal
commas and nothing said about it, NaN / n/a for a deflection not read. What the readers return must be those numbers
in SI; a time column whose named unit contradicts ``--time-unit`` is refused, not silently rescaled.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from flexdigit.calibrate import record_files as records
from flexdigit.calibrate.targets import release_figures
from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.params import RigParams
from flexdigit.twin.calibration import load_calibration
from flexdigit.twin.digit import build_digit

#: identify's fit of a 2 kHz, 0.2 %-noise closed-form decay of 8 s: wn to ~0.1 %, zeta to ~1 %
RELEASE_WN_RTOL = 0.003
RELEASE_ZETA_RTOL = 0.03


def write(path, header, rows, *, delimiter=",", decimal="."):
    def cell(v):
        if isinstance(v, str):
            return v
        return repr(float(v)).replace(".", decimal)

    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, delimiter=delimiter, lineterminator="\r\n")
        writer.writerow(header)
        writer.writerows([cell(v) for v in row] for row in rows)
    return path


def free_decay(wn, zeta, *, fs, duration_s, amplitudes=(0.8, 0.5, 0.2), offsets=(0.01, -0.02, 0.03), seed=0):
    """Released from rest: x = A e^(-zeta wn t) (cos wd t + zeta wn / wd sin wd t) + offset + 2 mV noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(round(duration_s * fs)) / fs
    wd = wn * np.sqrt(1 - zeta**2)
    shape = np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    volts = np.column_stack(
        [a * shape + o + 0.002 * rng.standard_normal(t.size) for a, o in zip(amplitudes, offsets, strict=True)]
    )
    return t, volts


def test_a_release_test_in_millivolts_milliseconds_and_decimal_commas_is_identified(tmp_path):
    wn, zeta = 12.7, 0.041  # a housed digit near tables 3.1-3.2
    t, volts = free_decay(wn, zeta, fs=2000, duration_s=8.0)
    path = write(
        tmp_path / "release.csv",
        ["Time (ms)", "SG 1 (mV)", "Gauge_2 [mV]", "sg3 (mV)"],
        np.column_stack([t * 1e3, volts * 1e3]),
        delimiter=";",
        decimal=",",
    )
    series = records.read_release(path)
    assert [s.channel for s in series] == ["SG 1 (mV)", "Gauge_2 [mV]", "sg3 (mV)"]
    np.testing.assert_allclose(series[0].t_s, t, atol=1e-12)
    np.testing.assert_allclose(np.column_stack([s.y for s in series]), volts, rtol=1e-12)
    got = release_figures(series)
    assert got["wn_rad_s"] == pytest.approx(wn, rel=RELEASE_WN_RTOL)
    assert got["zeta"] == pytest.approx(zeta, rel=RELEASE_ZETA_RTOL)


def test_the_decimal_mark_given_for_a_release_test_is_used(tmp_path):
    # ','-separated with quoted decimal-comma cells: the one layout whose decimal comma needs saying
    t, volts = free_decay(9.5, 0.02, fs=500, duration_s=4.0)
    rows = np.column_stack([t, volts])
    path = tmp_path / "release.csv"
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, quoting=csv.QUOTE_ALL)
        writer.writerow(["time_s", "gauge1_v", "gauge2_v", "gauge3_v"])
        writer.writerows([repr(float(v)).replace(".", ",") for v in row] for row in rows)
    series = records.read_release(path, decimal=",")
    np.testing.assert_allclose(np.column_stack([s.y for s in series]), volts, rtol=1e-12)


def test_sweep_and_deflection_tables_with_units_in_brackets_and_missing_readings(tmp_path):
    rng = np.random.default_rng(5)
    commands = np.arange(8, 44, 4)
    volts = rng.uniform(-2, 2, (commands.size, 3))
    sweep = write(
        tmp_path / "sweep.txt",
        ["Cmd", "Gauge 1 [V]", "Gauge 2 [V]", "Gauge 3 [V]"],
        [[str(c), *v] for c, v in zip(commands, volts, strict=True)],
        delimiter="\t",
    )
    got_commands, got_volts = records.read_sweep(sweep)
    np.testing.assert_array_equal(got_commands, commands)
    np.testing.assert_allclose(got_volts, volts, rtol=1e-12)
    # a deflection table as a ruler gives it (thesis table 3.6): cm, with readings not taken written NaN or n/a
    cm = rng.uniform(0, 5, (commands.size, 3))
    cells = [[str(c), *row] for c, row in zip(commands, cm, strict=True)]
    cells[2][3], cells[5][1] = "NaN", "n/a"
    defl = write(tmp_path / "defl.csv", ["command", "y SG1 (cm)", "y_sg2 (cm)", "Y_SG3 (cm)"], cells, delimiter=";")
    got_commands, mm = records.read_deflections(defl)
    want = cm.T * 10
    want[2, 2] = want[0, 5] = np.nan
    np.testing.assert_array_equal(got_commands, commands)
    np.testing.assert_allclose(mm, want, rtol=1e-12)


def test_a_time_unit_that_contradicts_the_column_is_refused(tmp_path, capsys):
    t, volts = free_decay(12.0, 0.05, fs=1000, duration_s=2.0)
    path = write(tmp_path / "rest.csv", ["time_ms", "sg1_v", "sg2_v", "sg3_v"], np.column_stack([t * 1e3, volts]))
    assert main(["calibrate", "--rest", str(path), "--time-unit", "s", "--out", str(tmp_path / "c.toml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "rest.csv: column 'time_ms' says its time is in ms but the time unit s was given" in err[0]
    # told nothing, the named unit is used: the rest record's times come back in seconds
    got_t, got_v = records.read_rest(path)
    np.testing.assert_allclose(got_t, t, atol=1e-12)
    np.testing.assert_allclose(got_v, volts, rtol=1e-12)
    with pytest.raises(DataFileError, match="no time column"):
        records.read_rest(write(tmp_path / "r2.csv", ["clock", "sg1_v", "sg2_v", "sg3_v"], np.column_stack([t, volts])))


def test_calibrate_json_reports_the_release_figures_of_a_foreign_record(tmp_path, capsys):
    wn, zeta = 12.7, 0.041
    t, volts = free_decay(wn, zeta, fs=1000, duration_s=8.0, seed=2)
    path = write(
        tmp_path / "housed.csv",
        ["t [ms]", "SG1 (mV)", "SG2 (mV)", "SG3 (mV)"],
        np.column_stack([t * 1e3, volts * 1e3]),
        delimiter=";",
        decimal=",",
    )
    out = tmp_path / "cal.toml"
    code = main(["calibrate", "--release-housed", str(path), "--out", str(out), "--json", "--allow-poor-fit"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    housed = report["release_tests"]["housing"]
    assert housed["wn_rad_s"] == pytest.approx(wn, rel=RELEASE_WN_RTOL)
    assert housed["zeta"] == pytest.approx(zeta, rel=RELEASE_ZETA_RTOL)
    assert len(housed["records"]) == 3
    assert housed["skipped"] == []
    # the calibrated housed twin rings as the record does (its linear modes, no simulation)
    modes = build_digit(RigParams(), load_calibration(out), housing=True).linear_modes()
    assert float(modes[0][0]) == pytest.approx(wn, rel=RELEASE_WN_RTOL)
    assert float(modes[1][0]) == pytest.approx(zeta, rel=RELEASE_ZETA_RTOL)

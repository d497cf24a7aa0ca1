"""Absurd numbers and unit slips from the command line and in the files it reads (issue 22, "Plausible wrong
answers", "Unit slips"): each refused before any work, exit 2, one line on stderr naming the flag or key, the value
and the limit (and, a thousand times off, the likely unit slip).

The ranges themselves are declared once (flexdigit._validation.Plausible); tests/test_validation.py feeds every
declared flag and field its generated invalid values. These are the issue's own examples, through the CLI.
"""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main


def _refused(argv, capsys) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1, err
    assert "Traceback" not in err, err
    return err


@pytest.mark.parametrize(
    ("argv", "fragments"),
    [
        (["simulate", "load", "--loads-g", "1e308"], ["'--loads-g'", "1e+308 g", "inside [0.1, 2000] g"]),
        (["simulate", "load", "--loads-g", "0.025"], ["'--loads-g'", "did you mean kg (25 g)?"]),
        (["simulate", "sweep", "--commands", "8..1000000000"], ["'--commands'", "Got 1000000000", "[0, 254]"]),
        (["simulate", "sweep", "--settle", "1e308"], ["'--settle'", "1e+308 s", "inside [0, 60] s"]),
        (["simulate", "sweep", "--samples", "1000000000"], ["'--samples'", "Got 1000000000", "[1, 10000]"]),
        (["simulate", "release", "--duration", "-0.0"], ["'--duration'", "Got -0.0 s", "[0.01, 600] s"]),
        (["run", "--gain", "5e-324"], ["'--gain' parameter of flexdigit run", "5e-324", "[0.1, 10]"]),
        (["run", "--duration", "-0.0"], ["'--duration'", "-0.0 s", "(0, 86400] s"]),
        (["predict", "m.json", "d.parquet", "--limit", "-1"], ["'--limit'", "Got -1 instead", "[0, 1e+06]"]),
        (["calibrate", "--deflection-resolution-mm", "1e308"], ["'--deflection-resolution-mm'", "[0.001, 20] mm"]),
        (["stream-emulator", "--rate", "1e308"], ["'--rate' parameter of flexdigit stream-emulator", "1e+308 Hz"]),
        (["stream-emulator", "--duration", "-0.0"], ["'--duration'", "-0.0 s", "(0, 604800] s"]),
        (["train", "d.parquet", "--tol", "5e-324"], ["'--tol'", "5e-324"]),
        (["design", "hinf", "--filter-hz", "1e308"], ["'--filter-hz'", "1e+308 Hz"]),
    ],
)
def test_absurd_flags_are_refused_naming_flag_value_and_limit(argv, fragments, tmp_path, capsys):
    out = ["--out", str(tmp_path / "x.parquet")] if argv[0] in ("simulate", "calibrate") else []
    err = _refused([*argv, *out], capsys)
    for fragment in fragments:
        assert fragment in err, err
    assert list(tmp_path.iterdir()) == []


def test_refusal_is_json_under_json(capsys):
    assert main(["run", "--gain", "1e308", "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["error_type"] == "UsageError"
    assert "'--gain'" in doc["error"]
    assert doc["exit_code"] == 2


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ("[sensors]\namplifier_gain_v_per_v = 1e308\n", ["amplifier_gain_v_per_v", "1e+308"]),
        ("[geometry]\nstrip_thickness_m = 5e-324\n", ["strip_thickness_m", "5e-324"]),
        ("[actuator]\npwm_frequency_hz = 1e308\n", ["pwm_frequency_hz", "1e+308 Hz"]),
        ("[geometry]\nstrip_thickness_m = 0.381\n", ["strip_thickness_m", "did you mean mm (0.000381 m)?"]),
        ("[material]\nyoungs_modulus_pa = 205\n", ["youngs_modulus_pa", "did you mean GPa"]),
        ("[sensors]\ngauge_factor = 1e6\n", ["gauge_factor", "inside [0.5, 250]"]),
        # each field in range, together a strip the servo cannot bend (model printed K2 = 8.9e7 N m/rad)
        ("[geometry]\nstrip_thickness_m = 0.004\nstrip_width_m = 0.05\n", ["cannot bend", "K2 = "]),
    ],
)
@pytest.mark.parametrize("command", [["params"], ["model", "--params"]])
def test_params_files_with_absurd_values_or_unit_slips_are_refused(command, text, fragments, tmp_path, capsys):
    rig = tmp_path / "rig.toml"
    rig.write_text(text)
    err = _refused([*command, str(rig)], capsys)
    assert str(rig) in err
    for fragment in fragments:
        assert fragment in err, err


@pytest.mark.parametrize(
    ("body", "fragments"),
    [
        ("loads_g = [0.0125, 0.025]\npositions_from_tip_cm = [0, 1]\n", ["'loads_g'", "did you mean kg (12.5 g)?"]),
        ("loads_g = [1e308]\npositions_from_tip_cm = [0, 1]\n", ["'loads_g'", "1e+308 g"]),
        ("loads_g = [12.5]\npositions_from_tip_cm = [0, 1]\nsample_interval_s = 20\n",
         ["'sample_interval_s'", "did you mean ms (0.02 s)?"]),
        ("loads_g = [12.5]\npositions_from_tip_cm = [0, 1e308]\n", ["'positions_from_tip_cm'", "1e+308 cm"]),
    ],
)  # fmt: skip
def test_protocol_files_with_absurd_values_or_unit_slips_are_refused(body, fragments, tmp_path, capsys):
    protocol = tmp_path / "p.toml"
    protocol.write_text('name = "mine"\n' + body)
    err = _refused(["collect", str(protocol), "--out", str(tmp_path / "d.parquet")], capsys)
    assert str(protocol) in err
    for fragment in fragments:
        assert fragment in err, err
    assert not (tmp_path / "d.parquet").exists()


# ----------------------------------------------------------------------------- records and imported tables
def _write(path, text):
    path.write_text(text)
    return str(path)


def test_an_imported_gauge_cell_of_1e999_is_refused_naming_line_and_column(tmp_path, capsys):
    csv = _write(tmp_path / "r.csv", "g1,g2,g3,load,pos\n0.1,0.2,0.3,0.0125,0.05\n0.1,0.2,1e999,0.0125,0.05\n")
    argv = ["dataset", "import", csv, "--gauges", "g1,g2,g3", "--load", "load", "--position", "pos"]
    err = _refused([*argv, "--out", str(tmp_path / "d.parquet")], capsys)
    assert "r.csv: line 3, column 'g3': '1e999' is beyond a float's range" in err
    assert not (tmp_path / "d.parquet").exists()


def test_imported_gauges_in_mv_mapped_as_volts_are_named(tmp_path, capsys):
    csv = _write(tmp_path / "r.csv", "g1,g2,g3,load,pos\n150,2,3,0.0125,0.05\n150,2,3.1,0.0125,0.06\n")
    argv = ["dataset", "import", csv, "--gauges", "g1,g2,g3", "--load", "load", "--position", "pos"]
    err = _refused([*argv, "--out", str(tmp_path / "d.parquet")], capsys)
    assert "line 2, column 'g1'" in err
    assert "Got 150.0 V instead: did you mean mV (0.15 V)?" in err


def test_a_one_row_deflection_table_is_refused_not_fitted(tmp_path, capsys):
    table = _write(tmp_path / "d.csv", "command,y1_mm,y2_mm,y3_mm\n20,1.0,2.0,3.0\n")
    err = _refused(["calibrate", "--deflections", table, "--out", str(tmp_path / "c.toml")], capsys)
    assert "d.csv: a deflection table needs at least 2 rows; this file has 1" in err


def test_a_deflection_in_m_read_as_mm_is_refused(tmp_path, capsys):
    table = _write(tmp_path / "d.csv", "command,y1_m,y2_m,y3_m\n20,0.001,0.002,0.003\n30,0.002,0.004,2.5\n")
    err = _refused(["calibrate", "--deflections", table, "--out", str(tmp_path / "c.toml")], capsys)
    assert "line 3, column 'y3_m'" in err
    assert "Got 2500.0 mm instead" in err


def test_a_constant_actuated_rest_record_is_refused_not_fitted(tmp_path, capsys):
    rows = "".join("20,0.1,0.2,0.3\n" for _ in range(8))
    record = _write(tmp_path / "a.csv", "command,gauge1_v,gauge2_v,gauge3_v\n" + rows)
    err = _refused(["calibrate", "--actuated-rest", record, "--out", str(tmp_path / "c.toml")], capsys)
    assert "a.csv: an actuated-rest record whose gauge 1 holds one value (0.1 V)" in err
    assert not (tmp_path / "c.toml").exists()


def test_a_record_in_ms_read_as_seconds_is_named(tmp_path, capsys):
    import numpy as np

    t_ms = np.arange(400.0)  # 1 kHz, written in ms, read as s
    y = np.exp(-0.07 * 13 * t_ms / 1e3) * np.cos(13 * t_ms / 1e3)
    lines = "".join(f"{t:g},{v:.6f}\n" for t, v in zip(t_ms, y, strict=True))
    record = _write(tmp_path / "release.csv", "time,sg1_v\n" + lines)
    err = _refused(["identify", "release", record, "--time-unit", "s"], capsys)
    assert "column 'time'" in err
    assert "Got 1.0 s instead: did you mean ms (0.001 s)?" in err


def test_a_zero_outside_an_open_range_suggests_no_unit_slip(capsys):
    # hostile review: 'stream-emulator --duration 0' said 'Got 0.0 s instead: did you mean ms (0 s)?'
    assert main(["stream-emulator", "--duration", "0"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--duration" in err
    assert "(0, 604800]" in err
    assert "Got 0.0 s instead." in err
    assert "did you mean" not in err

"""Recordings from CSV/Parquet: every bad-file case gives a DataFileError naming file, column and line."""

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from flexdigit.errors import DataFileError
from flexdigit.identify.timeseries import (
    MIN_SAMPLES,
    TimeSeries,
    read_timeseries,
    series_from_table,
    split_unit,
    write_csv,
)


def _write(path, header, rows):
    path.write_text(header + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    return path


def _rows(n=50, dt=0.01):
    return [(round(k * dt, 6), round(np.sin(k / 5), 6), 8) for k in range(n)]


def test_reads_units_from_header_and_picks_first_channel(tmp_path):
    p = _write(tmp_path / "rec.csv", "time_ms,sg1_v,command", [(10 * k, 0.1 * k, 8 + (k > 5)) for k in range(30)])
    ts = read_timeseries(p)
    assert ts.channel == "sg1"
    assert ts.unit == "V"
    assert ts.t_s[1] == pytest.approx(0.01)  # ms -> s
    assert ts.u is not None
    assert ts.input_name == "command"
    assert read_timeseries(p, "sg1_v").y[3] == pytest.approx(0.3)


def test_time_unit_flag_for_a_bare_time_column(tmp_path):
    p = _write(tmp_path / "rec.csv", "time,pot_v", [(k, 0.5) for k in range(30)])
    with pytest.raises(DataFileError, match=r"rec.csv: time unit unknown \(column 'time' has no unit\)"):
        read_timeseries(p)
    assert read_timeseries(p, time_unit="ms").t_s[1] == pytest.approx(1e-3)


def test_csv_roundtrip_and_parquet_read(tmp_path):
    t = np.arange(0, 1, 0.01)
    ts = TimeSeries.from_arrays(t, np.cos(t), channel="sg2", unit="V", u=np.full(t.size, 8.0))
    back = read_timeseries(write_csv(tmp_path / "a.csv", ts))
    np.testing.assert_allclose(back.y, ts.y, rtol=1e-8)
    with pytest.raises(FileExistsError, match=r"a.csv: the file exists; pass --force to overwrite it"):
        write_csv(tmp_path / "a.csv", ts.with_y(np.zeros(t.size)))
    assert read_timeseries(tmp_path / "a.csv").y[0] == pytest.approx(np.cos(0.0))  # untouched
    write_csv(tmp_path / "a.csv", ts.with_y(np.zeros(t.size)), force=True)
    assert read_timeseries(tmp_path / "a.csv").y[0] == 0.0
    pq.write_table(pa.table({"time_s": t, "sg2_v": np.cos(t)}), tmp_path / "a.parquet")
    np.testing.assert_allclose(read_timeseries(tmp_path / "a.parquet", "sg2").y, np.cos(t))


def test_missing_file(tmp_path):
    with pytest.raises(DataFileError, match=r"nope.csv: no such file"):
        read_timeseries(tmp_path / "nope.csv")


def test_empty_file(tmp_path):
    (tmp_path / "e.csv").write_text("# only a comment\n")
    with pytest.raises(DataFileError, match=r"e.csv: empty file: expected a header row"):
        read_timeseries(tmp_path / "e.csv")


def test_missing_time_column(tmp_path):
    p = _write(tmp_path / "rec.csv", "sample,sg1_v,command", _rows())
    with pytest.raises(
        DataFileError, match=r"rec.csv: no time column: expected one named time_s .* sample, sg1_v, command"
    ):
        read_timeseries(p)


def test_missing_channel_column(tmp_path):
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v,command", _rows())
    with pytest.raises(DataFileError, match=r"rec.csv: no column 'sg3' \(columns: time_s, sg1_v, command\)"):
        read_timeseries(p, "sg3")


def test_cell_that_is_not_a_number_names_line_and_column(tmp_path):
    rows = _rows()
    rows[6] = (0.06, "0.1V", 8)  # data row 7 = file line 8 (header is line 1)
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v,command", rows)
    with pytest.raises(DataFileError, match=r"rec.csv: line 8, column 'sg1_v': '0.1V' is not a number"):
        read_timeseries(p)


def test_ragged_row(tmp_path):
    p = tmp_path / "rec.csv"
    p.write_text("time_s,sg1_v\n0,1\n0.01,1,5\n")
    with pytest.raises(DataFileError, match=r"rec.csv: line 3 has 3 fields, the header \(line 1\) has 2"):
        read_timeseries(p)


def test_non_monotonic_time_names_the_line(tmp_path):
    rows = _rows()
    rows[10] = (0.05, 0.0, 8)  # goes back from 0.09 to 0.05 on file line 12
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v,command", rows)
    with pytest.raises(
        DataFileError, match=r"column 'time_s', line 12: time must increase strictly, got 0.05 after 0.09"
    ):
        read_timeseries(p)


def test_repeated_time_is_not_increasing(tmp_path):
    rows = _rows()
    rows[4] = (0.03, 0.0, 8)
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v,command", rows)
    with pytest.raises(DataFileError, match=r"line 6: time must increase strictly, got 0.03 after 0.03"):
        read_timeseries(p)


def test_nan_run_names_column_and_lines(tmp_path):
    rows = _rows()
    for k in (20, 21, 22):
        rows[k] = (rows[k][0], "", 8)
    rows[30] = (rows[30][0], "nan", 8)
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v,command", rows)
    with pytest.raises(
        DataFileError, match=r"column 'sg1_v', line 22 to line 24: missing values \(NaN run of 3\) \(2 runs, 4 values"
    ):
        read_timeseries(p)


def test_nan_in_parquet_names_rows(tmp_path):
    y = np.sin(np.arange(40.0))
    y[5] = np.nan
    pq.write_table(pa.table({"time_s": np.arange(40) * 0.01, "sg1_v": y}), tmp_path / "r.parquet")
    with pytest.raises(DataFileError, match=r"r.parquet: column 'sg1_v', row 6: missing values \(NaN run of 1\)"):
        read_timeseries(tmp_path / "r.parquet")


def test_text_column_in_parquet(tmp_path):
    pq.write_table(pa.table({"time_s": [0.0, 0.1], "sg1_v": ["a", "b"]}), tmp_path / "r.parquet")
    with pytest.raises(DataFileError, match=r"r.parquet: column 'sg1_v' is not numeric"):
        read_timeseries(tmp_path / "r.parquet")


def test_too_few_samples(tmp_path):
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v,command", _rows(n=MIN_SAMPLES - 1))
    with pytest.raises(DataFileError, match=rf"rec.csv: too few samples: {MIN_SAMPLES - 1}, .* at least {MIN_SAMPLES}"):
        read_timeseries(p)


def test_dropped_samples_are_irregular_sampling(tmp_path):
    rows = _rows()
    del rows[15:18]  # a gap of 4 intervals between file lines 16 and 17
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v,command", rows)
    with pytest.raises(DataFileError, match=r"line 17: irregular sampling, a step of 0.04 where the median is 0.01"):
        read_timeseries(p)


def test_arrays_get_the_same_checks():
    with pytest.raises(DataFileError, match=r"array: column 'time', sample 3: time must increase strictly"):
        TimeSeries.from_arrays([0.0, 0.1, 0.2, 0.1] + [0.3 + 0.1 * k for k in range(30)], np.zeros(34))


def test_split_unit():
    assert split_unit("time_us") == ("time", "us")
    assert split_unit("sg_1_mv") == ("sg_1", "mV")
    assert split_unit("velocity_knots") == ("velocity_knots", "")


def test_binary_file_is_not_a_csv(tmp_path):
    (tmp_path / "rec.csv").write_bytes(b"time_s,sg1_v\n\xff\xfe\x00garbage")
    with pytest.raises(DataFileError, match=r"rec.csv: not a text CSV file"):
        read_timeseries(tmp_path / "rec.csv")


def test_unknown_suffix(tmp_path):
    (tmp_path / "rec.xlsx").write_text("x")
    with pytest.raises(DataFileError, match=r"rec.xlsx: unknown file type '.xlsx'"):
        read_timeseries(tmp_path / "rec.xlsx")


def test_series_from_in_memory_table_gets_the_same_checks():
    t = np.arange(40) * 0.01
    ts = series_from_table({"time_s": t, "pot_v": np.ones(40), "command": np.full(40, 51.0)}, "pot")
    assert ts.unit == "V"
    assert ts.u is not None
    assert ts.input_name == "command"
    y = np.ones(40)
    y[10:12] = np.nan
    with pytest.raises(DataFileError, match=r"table: column 'pot_v', row 11 to row 12: missing values"):
        series_from_table({"time_s": t, "pot_v": y}, "pot")


# --- layouts of recordings made elsewhere (issue 11) ------------------------------------------------------------
@pytest.mark.parametrize(
    ("header", "sep", "decimal", "comments", "index", "time_unit"),
    [
        ("time_ms;sg1_mv", ";", ",", 0, False, None),  # semicolons and a decimal comma
        ("Time (ms)\tPot (mV)", "\t", ".", 0, False, None),  # tabs, units in parentheses
        ("t[ms]  sg2[mV]", "  ", ".", 2, False, None),  # comment lines, runs of spaces, units in brackets
        (",time_ms,pot_mv", ",", ".", 0, True, None),  # pandas' to_csv index column
        ("time|y_mv", "|", ".", 0, False, "ms"),  # a bare time column and --time-unit
    ],
)
def test_layouts_of_other_rigs(tmp_path, header, sep, decimal, comments, index, time_unit):
    lines = [f"# rig B, note {k}" for k in range(comments)] + [header]
    for k in range(30):
        cells = [f"{10 * k}", f"{1.5 + k}".replace(".", decimal)]
        lines.append(sep.join(([str(k)] if index else []) + cells))
    p = tmp_path / "rec.csv"
    p.write_text("\n".join(lines) + "\n")
    ts = read_timeseries(p, time_unit=time_unit)
    assert ts.unit == "mV"
    assert ts.time_unit == "ms"
    assert ts.t_s[:2] == pytest.approx([0.0, 0.01])
    assert ts.y[:2] == pytest.approx([1.5, 2.5])  # not the index column


def test_time_unit_contradicting_a_column_unit_is_refused(tmp_path):
    p = _write(tmp_path / "rec.csv", "time_s,sg1_v", [(0.01 * k, 0.5) for k in range(30)])
    with pytest.raises(DataFileError, match=r"column 'time_s' says its time is in s but --time-unit ms was given"):
        read_timeseries(p, time_unit="ms")
    assert read_timeseries(p, time_unit="s").t_s[1] == pytest.approx(0.01)


def test_split_unit_in_brackets():
    assert split_unit("Time (ms)") == ("Time", "ms")
    assert split_unit("t [us]") == ("t", "us")
    assert split_unit("pot (V)") == ("pot", "V")
    assert split_unit("force [N]") == ("force", "N")
    assert split_unit("load (g)") == ("load", "g")  # kept as written

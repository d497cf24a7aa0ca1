"""A record with a hole (a sparse file: a run of NUL bytes with no line break, as a copy cut short or a disk image
leaves) is bad input named by file and line, never the CSV module's internal "field larger than field limit"."""

import json

from flexdigit._table import read_table
from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.identify.timeseries import read_timeseries

HOLE_BYTES = 300_000  # past csv's field limit (131072 characters)


def _sparse(path, header="time_s,sg1_v", rows=60):
    with open(path, "wb") as fh:
        fh.write((header + "\n" + "".join(f"{k * 0.01:.2f},{k % 7}\n" for k in range(rows))).encode())
        fh.truncate(fh.tell() + HOLE_BYTES)  # a hole: reads back as NUL bytes
        fh.seek(0, 2)
        fh.write(b"\n9.99,1\n")
    return path


def test_read_timeseries_names_the_line_of_the_hole(tmp_path):
    p = _sparse(tmp_path / "rec.csv")
    try:
        read_timeseries(p)
    except DataFileError as exc:
        text = str(exc)
    else:
        raise AssertionError("a record with a 300 kB line of NUL bytes was read")
    assert text.startswith(f"{p}: line 62:"), text
    assert "not a CSV row" in text, text


def test_read_table_names_the_line_of_the_hole(tmp_path):
    p = _sparse(tmp_path / "rec.csv", rows=800)  # the hole past the first 4 kB the binary check looks at
    try:
        read_table(p)
    except DataFileError as exc:
        text = str(exc)
    else:
        raise AssertionError("a table with a 300 kB line of NUL bytes was read")
    assert text.startswith(f"{p}: line 802:"), text


def test_identify_on_a_sparse_record_is_bad_input_not_an_internal_error(tmp_path, capsys):
    p = _sparse(tmp_path / "rec.csv")
    assert main(["identify", "step", str(p), "--json"]) == 2
    out = json.loads(capsys.readouterr().out)
    assert "internal error" not in json.dumps(out)
    assert str(p) in json.dumps(out)
    assert "line 62" in json.dumps(out)

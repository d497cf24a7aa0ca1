"""``dataset import`` on readings files as spreadsheets and other tools export them (issue 11 item 2, review).

Known answers: the closed-form cantilever of tests/tactile/conftest.py, written here with the standard library's
:mod:`csv` writer (not flexdigit's) in the layouts those tools produce: a decimal comma with ``;`` and nothing said
about it, Excel's ``sep=;`` first line, "Unicode text" (UTF-16 with a byte-order mark, tab-separated), MATLAB's
``%`` comments. The imported dataset must hold the same readings in SI; a slip in the map or the file is refused in
one line naming the file (and line, column).
"""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

from cantilever import NOISE_V
from flexdigit.cli import main
from flexdigit.tactile.dataset import load_dataset
from oracles import cantilever_gauges_v

LENGTH_M = 0.27  # the thesis digit, clamp to tip (RigParams default)
HEADER = ["t (s)", "SG1 (mV)", "SG2 (mV)", "SG3 (mV)", "Masse (g)", "Position ab Spitze (cm)"]
FLAGS = ["--gauges", ",".join(HEADER[1:4]), "--gauge-unit", "mV", "--load", HEADER[4], "--load-unit", "g"]
FLAGS += ["--position", HEADER[5], "--position-unit", "cm", "--position-from", "tip"]


def readings(seed=3):
    """Rows (time, 3 gauges in mV, mass in g, position from the tip in cm, None when unloaded) and the SI truth."""
    rng = np.random.default_rng(seed)
    rows, truth = [], []
    for mass_g in (20.0, 40.0):
        for _ in range(4):
            v = NOISE_V * rng.standard_normal(3)
            rows.append([len(rows) * 0.5, *(v * 1e3), 0.0, None])
            truth.append((v, 0.0, np.nan))
        for tip_cm in (1.5, 6.0, 10.5, 15.0, 19.5):
            for _ in range(4):
                v = cantilever_gauges_v(LENGTH_M - tip_cm / 100, mass_g / 1000)[0] + NOISE_V * rng.standard_normal(3)
                rows.append([len(rows) * 0.5, *(v * 1e3), mass_g, tip_cm])
                truth.append((v, mass_g / 1000, tip_cm / 100))
    return rows, truth


def export(rows, *, delimiter, decimal=".", first_lines=(), newline="\r\n", quoting=csv.QUOTE_MINIMAL) -> str:
    """The text a spreadsheet writes: ``first_lines`` verbatim, the header, the rows with the given decimal mark."""

    def cell(v):
        return "" if v is None else repr(float(v)).replace(".", decimal)

    buffer = io.StringIO()
    for line in first_lines:
        buffer.write(line + newline)
    writer = csv.writer(buffer, delimiter=delimiter, lineterminator=newline, quoting=quoting)
    writer.writerow(HEADER)
    writer.writerows([cell(v) for v in row] for row in rows)
    return buffer.getvalue()


def _import_and_check(path, tmp_path, capsys, *extra):
    out = tmp_path / "ds.parquet"
    assert main(["dataset", "import", str(path), "--out", str(out), *FLAGS, *extra, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    _, truth = readings()
    ds = load_dataset(out)
    np.testing.assert_allclose(ds.gauges_v, [t[0] for t in truth], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ds["load_kg"], [t[1] for t in truth], rtol=1e-12)
    np.testing.assert_allclose(ds["position_from_tip_m"], [t[2] for t in truth], atol=1e-12)
    return report, ds


def test_a_decimal_comma_export_imports_without_being_told(tmp_path, capsys):
    # a German Excel's "CSV (Trennzeichen-getrennt)": ';' and decimal commas, no flag saying so
    path = tmp_path / "messung.csv"
    path.write_text(export(readings()[0], delimiter=";", decimal=","), encoding="utf-8")
    report, ds = _import_and_check(path, tmp_path, capsys)
    assert (report["delimiter"], report["decimal"]) == (";", ",")
    assert ds.meta["rig"]["decimal"] == ","  # the metadata says how the file was read


def test_excel_sep_line_names_the_delimiter(tmp_path, capsys):
    path = tmp_path / "excel.csv"
    path.write_text(export(readings()[0], delimiter="|", first_lines=["sep=|"]), encoding="utf-8")
    report, _ = _import_and_check(path, tmp_path, capsys)
    assert report["delimiter"] == "|"


def test_unicode_text_export_utf16_tab_separated(tmp_path, capsys):
    # Excel's "Unicode Text (*.txt)": UTF-16 little-endian with a byte-order mark, tab-separated, CRLF
    path = tmp_path / "unicode.txt"
    path.write_bytes(export(readings()[0], delimiter="\t").encode("utf-16"))
    report, _ = _import_and_check(path, tmp_path, capsys)
    assert report["delimiter"] == "\t"


def test_matlab_percent_comments_are_skipped(tmp_path, capsys):
    path = tmp_path / "matlab.csv"
    text = export(
        readings()[0], delimiter=",", first_lines=["% writetable export", "% rig B, 2024-03-01"], newline="\n"
    )
    path.write_text(text, encoding="utf-8")
    _import_and_check(path, tmp_path, capsys)


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("flexdigit dataset: error: "), err
    return err[0]


def test_a_short_row_is_named_by_its_line_not_as_an_undetectable_delimiter(tmp_path, capsys):
    rows = readings()[0]
    text = export(rows, delimiter=";", decimal=",").splitlines()
    text[7] = text[7].rsplit(";", 1)[0]  # line 8 lost its last field
    path = tmp_path / "ragged.csv"
    path.write_text("\n".join(text) + "\n")
    assert main(["dataset", "import", str(path), "--out", str(tmp_path / "o.parquet"), *FLAGS]) == 2
    assert "ragged.csv: line 8 has 5 fields, the header (line 1) has 6" in _one_line_error(capsys)


def test_a_column_mapped_to_two_roles_is_refused(tmp_path, capsys):
    # gauges "SG1,SG1,SG3": a slip that would import a plausible dataset with gauge 2 a copy of gauge 1
    path = tmp_path / "r.csv"
    path.write_text(export(readings()[0], delimiter=","))
    flags = list(FLAGS)
    flags[1] = ",".join([HEADER[1], HEADER[1], HEADER[3]])
    assert main(["dataset", "import", str(path), "--out", str(tmp_path / "o.parquet"), *flags]) == 2
    assert "column 'SG1 (mV)' is mapped twice, as gauge 1 and as gauge 2" in _one_line_error(capsys)
    flags = [*FLAGS[:-5], HEADER[4], *FLAGS[-4:]]  # position = the mass column
    assert main(["dataset", "import", str(path), "--out", str(tmp_path / "o.parquet"), *flags]) == 2
    assert "is mapped twice, as the load column and as the position column" in _one_line_error(capsys)
    assert not (tmp_path / "o.parquet").exists()


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda p: p.mkdir(), "map.toml: not a file (a directory?); expected a column map TOML"),
        (lambda p: p.write_bytes(b'gauges = ["\xff\xfe"]\n'), "map.toml: not a text TOML file (byte 11 is not UTF-8)"),
    ],
)
def test_a_map_that_is_a_directory_or_not_text_is_named(tmp_path, capsys, make, message):
    path = tmp_path / "r.csv"
    path.write_text(export(readings()[0], delimiter=","))
    make(tmp_path / "map.toml")
    argv = ["dataset", "import", str(path), "--out", str(tmp_path / "o.parquet"), "--map", str(tmp_path / "map.toml")]
    assert main(argv) == 2
    assert message in _one_line_error(capsys)


def test_a_directory_given_as_the_readings_file_is_named(tmp_path, capsys):
    (tmp_path / "r.csv").mkdir()
    assert main(["dataset", "import", str(tmp_path / "r.csv"), "--out", str(tmp_path / "o.parquet"), *FLAGS]) == 2
    assert "r.csv: not a file (a directory?)" in _one_line_error(capsys)

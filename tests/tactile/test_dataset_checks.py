"""Datasets checked against their protocol on load (issue 16): an edited or truncated file, or readings beyond the
ADC range, used to train with rc 0. Each is now refused naming the file, sample and column."""

from __future__ import annotations

import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.tactile.dataset import export_csv, load_dataset
from flexdigit.tactile.protocols import Protocol
from flexdigit.tactile.runner import collect

SMALL = Protocol("small", (0.0125, 0.025), (0.0, 0.05, 0.10), repetitions=6, no_load_repetitions=3)


@pytest.fixture
def saved(tmp_path, make_rig):
    out = tmp_path / "d.parquet"
    collect(SMALL, make_rig(seed=1), out)
    return out


def _with_column(path, out, name, change):
    table = pq.read_table(path)
    values = np.array(table.column(name).to_pylist())
    change(values)
    i = table.column_names.index(name)
    pq.write_table(table.set_column(i, name, pa.array(values)), out)
    return out


@pytest.mark.parametrize(
    "column, change, culprit",
    [
        ("load_kg", lambda v: v.__setitem__(10, 0.05), r"sample 10 has load_kg = 0.05, but protocol 'small' takes"),
        ("position_from_tip_m", lambda v: v.__setitem__(7, 0.07), "sample 7 has position_from_tip_m = 0.07"),
        ("command", lambda v: v.__setitem__(0, 40), "sample 0 has command = 40"),
        ("gauge2_v", lambda v: v.__setitem__(5, 1e300), r"column 'gauge2_v' of sample 5 is 1e\+300 V, outside the ADC"),
        ("pot_v", lambda v: v.__setitem__(3, -7.5), r"column 'pot_v' of sample 3 is -7.5 V, outside the ADC range"),
        ("time_s", lambda v: v.__setitem__(3, np.inf), "column 'time_s' must be finite"),
    ],
)
def test_edited_datasets_are_refused(saved, tmp_path, column, change, culprit, capsys):
    bad = _with_column(saved, tmp_path / "bad.parquet", column, change)
    with pytest.raises(DataFileError, match=culprit):
        load_dataset(bad)
    assert main(["train", str(bad), "--hidden", "3", "--tol", "1e-4"]) == 2  # trained with rc 0 before
    assert "bad.parquet" in capsys.readouterr().err


def test_a_truncated_file_is_refused(saved, tmp_path, capsys):
    csv = export_csv(load_dataset(saved), tmp_path / "d.csv")
    lines = csv.read_text().splitlines()
    cut = tmp_path / "cut.csv"
    cut.write_text("\n".join(lines[:-5]) + "\n")  # the last five readings lost
    n = SMALL.sample_count
    with pytest.raises(DataFileError, match=f"holds {n - 5} of the {n} readings of 'small' \\(sample {n - 5} is"):
        load_dataset(cut)
    assert len(load_dataset(cut, partial=True)) == n - 5  # asked for: a partial dataset is readable
    table = pq.read_table(saved)
    pq.write_table(table.slice(0, 20), tmp_path / "short.parquet")
    assert main(["train", str(tmp_path / "short.parquet")]) == 2
    assert "holds 20 of the" in capsys.readouterr().err


def test_the_adc_range_comes_from_the_metadata(saved, tmp_path):
    table = pq.read_table(saved)
    meta = json.loads(table.schema.metadata[b"flexdigit"])
    assert meta["adc_range_v"] == [-5.0, 5.0]  # the thesis card (table 2.2), recorded at collection
    meta["adc_range_v"] = [-0.01, 0.01]  # a card set to +-10 mV could not have read these volts
    narrow = tmp_path / "narrow.parquet"
    pq.write_table(table.replace_schema_metadata({"flexdigit": json.dumps(meta)}), narrow)
    with pytest.raises(DataFileError, match=r"outside the ADC range -0.01..0.01 V"):
        load_dataset(narrow)

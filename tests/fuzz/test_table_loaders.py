"""Fuzz the table loaders (tactile datasets in Parquet and CSV, DAQ time series in CSV and Parquet): every
generated file loads or gives the project's one-line error naming the file (issue 16). Valid seeds are made here
from a protocol's plan and seeded numbers, a damped sine written with the csv module, and a tendon robot's gauge
readings (``flexdigit tdcr shape --readings``)."""

from __future__ import annotations

import io
import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import given
from hypothesis import strategies as st

from flexdigit.identify.timeseries import read_timeseries
from flexdigit.tactile.dataset import COLUMNS, Dataset, export_csv, load_dataset, make_meta, save_dataset
from flexdigit.tactile.protocols import Protocol
from flexdigit.tdcr import ROBOTS, read_readings, sense_shape

from .strategies import assert_loader_contract, edited_document, json_values, mutated_bytes, numbers

PROTOCOL = Protocol("fuzz", (0.0125, 0.025), (0.0, 0.05), repetitions=2, no_load_repetitions=1)


def _dataset() -> Dataset:
    rng = np.random.default_rng(3)
    plan = PROTOCOL.plan(0.270)
    n = PROTOCOL.sample_count
    columns = {name: np.asarray(plan[name], dtype=dtype) for name, dtype in COLUMNS.items() if name in plan}
    for name in ("gauge1_v", "gauge2_v", "gauge3_v"):
        columns[name] = rng.normal(0.0, 0.5, n)
    columns["pot_v"] = rng.uniform(0.47, 2.48, n)
    columns["time_s"] = np.arange(n) * 0.5
    return Dataset(columns, make_meta(PROTOCOL, {"url": "fuzz", "repr": "fuzz"}, 0.270))


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tables")
    save_dataset(_dataset(), folder / "valid.parquet")
    export_csv(_dataset(), folder / "valid.csv")
    t = np.arange(0, 2, 0.01)
    y = 0.3 * np.exp(-0.5 * t) * np.cos(20 * t)
    rows = "".join(f"{float(a)!r},{float(b)!r},8\n" for a, b in zip(t, y, strict=True))
    (folder / "rec.csv").write_text("time_s,sg1_v,command\n" + rows)
    pq.write_table(pa.table({"time_s": t, "sg1_v": y}), folder / "rec.parquet")
    shape = sense_shape(ROBOTS["rao2021"], tensions_n=[4, 0, 0, 0, 2, 0], stations_per_segment=2)
    gauges = zip(shape.layout.s_m, shape.layout.angles_deg, shape.layout.tilts_deg, shape.strains, strict=True)
    rows = "".join(f"{float(s)!r},{float(a)!r},{float(b)!r},{float(e)!r}\n" for s, a, b, e in gauges)
    (folder / "gauges.csv").write_text("s_m,angle_deg,tilt_deg,strain\n" + rows)  # a tendon robot's readings
    return folder


def test_the_seeds_load(folder):
    assert len(load_dataset(folder / "valid.parquet")) == PROTOCOL.sample_count
    assert len(load_dataset(folder / "valid.csv")) == PROTOCOL.sample_count
    assert read_timeseries(folder / "rec.csv", "sg1").t_s.size == 200
    assert read_timeseries(folder / "rec.parquet", "sg1").t_s.size == 200
    assert read_readings(folder / "gauges.csv", ROBOTS["rao2021"])[1].size == 24


def _bytes_test(seed_name, target_name, load):
    @given(data=st.data())
    def test(folder, data):
        valid = (folder / seed_name).read_bytes()
        path = folder / target_name
        path.write_bytes(data.draw(mutated_bytes(valid)))
        assert_loader_contract(load, path)

    return test


test_dataset_parquet_bytes = _bytes_test("valid.parquet", "bytes.parquet", load_dataset)
test_dataset_csv_bytes = _bytes_test("valid.csv", "bytes.csv", load_dataset)
test_timeseries_csv_bytes = _bytes_test("rec.csv", "bytes-rec.csv", lambda p: read_timeseries(p, "sg1"))
test_timeseries_parquet_bytes = _bytes_test("rec.parquet", "bytes-rec.parquet", lambda p: read_timeseries(p, "sg1"))
test_gauge_readings_bytes = _bytes_test("gauges.csv", "bytes-gauges.csv", lambda p: read_readings(p, ROBOTS["rao2021"]))

#: Column values a table may hold: numbers of every kind, text, nulls, booleans.
cells = st.one_of(numbers, st.none(), st.booleans(), st.text(max_size=6))


@st.composite
def edited_table(draw, table: pa.Table) -> pa.Table:
    """``table`` with a column dropped, retyped, renamed, a cell changed, rows cut or duplicated."""
    name = draw(st.sampled_from(table.column_names))
    i = table.column_names.index(name)
    kind = draw(st.sampled_from(["drop", "cell", "cell", "type", "rename", "rows"]))
    if kind == "drop":
        return table.drop([name])
    if kind == "rename":
        return table.rename_columns([draw(st.text(max_size=8)) if c == name else c for c in table.column_names])
    if kind == "rows":
        a = draw(st.integers(0, table.num_rows))
        b = draw(st.integers(0, table.num_rows))
        return pa.concat_tables([table.slice(0, a), table.slice(b)])
    values = table.column(name).to_pylist()
    if kind == "cell":
        values[draw(st.integers(0, len(values) - 1))] = draw(numbers)
        try:
            column = pa.array(values, type=table.schema.field(name).type)
        except (pa.ArrowException, OverflowError, TypeError, ValueError):  # a value the type cannot hold
            column = pa.array([str(v) for v in values])
    else:
        try:
            column = (
                pa.array([draw(cells)] * len(values)) if draw(st.booleans()) else pa.array([str(v) for v in values])
            )
        except (pa.ArrowException, OverflowError):  # an integer beyond 64 bits: as text
            column = pa.array([str(v) for v in values])
    return table.set_column(i, name, column)


@given(data=st.data())
def test_dataset_parquet_values(folder, data):
    table = pq.read_table(folder / "valid.parquet")
    meta = json.loads(table.schema.metadata[b"flexdigit"])
    if data.draw(st.booleans()):
        table = data.draw(edited_table(table))
    else:
        meta = data.draw(edited_document(meta, json_values))
    table = table.replace_schema_metadata({"flexdigit": json.dumps(meta)})
    path = folder / "values.parquet"
    pq.write_table(table, path)
    assert_loader_contract(load_dataset, path)


@given(data=st.data())
def test_dataset_csv_values(folder, data):
    first, rest = (folder / "valid.csv").read_text().split("\n", 1)
    meta = data.draw(edited_document(json.loads(first[2:]), json_values))
    path = folder / "values.csv"
    path.write_text("# " + json.dumps(meta) + "\n" + rest)
    assert_loader_contract(load_dataset, path)


@given(data=st.data())
def test_timeseries_parquet_values(folder, data):
    table = data.draw(edited_table(pq.read_table(folder / "rec.parquet")))
    path = folder / "values-rec.parquet"
    sink = io.BytesIO()
    pq.write_table(table, sink)
    path.write_bytes(sink.getvalue())
    assert_loader_contract(lambda p: read_timeseries(p, "sg1"), path)


# Regressions that ``make fuzz`` (seed 0) found at 10,000 examples, pinned as plain tests.


def _flip_first_byte_of_name(valid: bytes, name: bytes) -> bytes:
    """``valid`` (a Parquet file) with the first byte of ``name`` in its footer schema turned into 0x80, which is
    not UTF-8: the one-byte flip the fuzzer found (a thrift string is its length byte, then its bytes)."""
    i = valid.index(bytes([0x18, len(name)]) + name) + 2
    return valid[:i] + b"\x80" + valid[i + 1 :]


@pytest.mark.parametrize(
    "seed_name, column, load",
    [
        ("valid.parquet", b"repetition", load_dataset),
        ("rec.parquet", b"sg1_v", lambda p: read_timeseries(p, "sg1")),
    ],
)
def test_a_column_name_that_is_not_utf8_is_refused_naming_the_file(folder, seed_name, column, load):
    path = folder / f"not-utf8-{seed_name}"
    path.write_bytes(_flip_first_byte_of_name((folder / seed_name).read_bytes(), column))
    error = assert_loader_contract(load, path)
    assert "not UTF-8" in str(error)


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_a_stored_protocol_with_an_unknown_key_is_named_on_one_line(folder, fmt):
    dataset = _dataset()
    dataset.meta["protocol"]["\n"] = False  # the key the fuzzer found: a newline
    path = folder / f"newline-key.{fmt}"
    (save_dataset if fmt == "parquet" else export_csv)(dataset, path)
    error = assert_loader_contract(load_dataset, path)
    assert "unknown protocol key '\\n'" in str(error)


@pytest.mark.parametrize("renamed, expected", [("time_s", "no time column"), ("sg1_v", "no column 'sg1'")])
def test_a_column_named_with_a_newline_is_listed_on_one_line(folder, renamed, expected):
    table = pq.read_table(folder / "rec.parquet")
    table = table.rename_columns(["\n" if c == renamed else c for c in table.column_names])
    path = folder / "newline-column.parquet"
    pq.write_table(table, path)
    error = assert_loader_contract(lambda p: read_timeseries(p, "sg1"), path)
    assert expected in str(error)
    assert "'\\n'" in str(error)

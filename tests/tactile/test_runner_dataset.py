import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from flexdigit.errors import DataFileError, OutputExistsError, ParameterError, RigError
from flexdigit.tactile.dataset import COLUMNS, export_csv, load_dataset
from flexdigit.tactile.protocols import Protocol, load_protocol
from flexdigit.tactile.runner import collect, journal_path

SMALL = Protocol(
    "small",
    loads_kg=(0.0125, 0.025),
    positions_from_tip_m=(0.0, 0.05, 0.10),
    repetitions=4,
    no_load_repetitions=3,
    settle_s=0.5,
)


def test_collect_writes_parquet_matching_closed_form(tmp_path, make_rig, cantilever_model):
    out = tmp_path / "d.parquet"
    ds = collect(SMALL, make_rig(seed=1), out)
    assert out.exists()
    assert not journal_path(out).exists()
    assert len(ds) == SMALL.sample_count == 2 * (3 + 3 * 4)
    back = load_dataset(out, SMALL)
    np.testing.assert_array_equal(back.gauges_v, ds.gauges_v)
    # the readings are the closed-form cantilever strain plus noise of 2 mV (conftest)
    loaded = back["load_kg"] > 0
    expected = cantilever_model(back["position_from_base_m"][loaded], back["load_kg"][loaded])
    assert np.max(np.abs(back.gauges_v[loaded] - expected)) < 0.01
    assert np.allclose(back["position_from_base_m"][loaded] + back["position_from_tip_m"][loaded], 0.270)
    assert back.meta["rig"]["url"] == "cantilever"


def test_interrupted_collection_resumes_without_loss_or_duplicate(tmp_path, make_rig):
    out = tmp_path / "d.parquet"
    with pytest.raises(KeyboardInterrupt):
        collect(SMALL, make_rig(seed=1, fail_after=11), out)
    assert not out.exists()
    partial = load_dataset(journal_path(out), SMALL)
    assert partial["sample"].tolist() == list(range(11))
    # a crash in the middle of writing a line leaves a partial line: it must be dropped, not duplicated
    with journal_path(out).open("a") as fh:
        fh.write('{"sample": 11, "test": 0, "gauge1_v": 0.1')
    with pytest.raises(RigError):
        collect(SMALL, make_rig(seed=2, fail_after=5, error=lambda: RigError("port vanished")), out)
    ds = collect(SMALL, make_rig(seed=3), out)
    assert ds["sample"].tolist() == list(range(SMALL.sample_count))
    np.testing.assert_array_equal(ds.gauges_v[:11], partial.gauges_v)  # the first readings kept as taken
    plan = SMALL.plan(0.270)
    for name in ("load_kg", "position_index", "repetition", "test"):
        np.testing.assert_array_equal(ds[name], plan[name])


def test_same_seed_same_dataset(tmp_path, make_rig):
    a = collect(SMALL, make_rig(seed=7), tmp_path / "a.parquet")
    b = collect(SMALL, make_rig(seed=7), tmp_path / "b.parquet")
    np.testing.assert_array_equal(a.gauges_v, b.gauges_v)  # exact: one seed, one code path, one machine


def test_resume_refuses_another_protocol_and_existing_output(tmp_path, make_rig):
    out = tmp_path / "d.parquet"
    with pytest.raises(KeyboardInterrupt):
        collect(SMALL, make_rig(fail_after=3), out)
    other = Protocol("other", loads_kg=(0.01,), positions_from_tip_m=(0.0,), repetitions=2)
    with pytest.raises(DataFileError, match="written by protocol 'small'"):
        collect(other, make_rig(), out)
    collect(SMALL, make_rig(), out)
    with pytest.raises(OutputExistsError, match="the file exists; pass --force"):
        collect(SMALL, make_rig(), out)


@pytest.fixture
def saved(tmp_path, make_rig):
    out = tmp_path / "d.parquet"
    collect(SMALL, make_rig(seed=1), out)
    return out


def test_csv_round_trip(saved, tmp_path, make_rig):
    ds = load_dataset(saved)
    csv = export_csv(ds, tmp_path / "d.csv")
    back = load_dataset(csv, SMALL)
    np.testing.assert_array_equal(back.gauges_v, ds.gauges_v)
    np.testing.assert_array_equal(back["command"], ds["command"])


def _rewrite(path, table):
    pq.write_table(table, path)


def test_corrupt_and_mismatched_datasets_give_clear_errors(saved, tmp_path, make_rig):
    table = pq.read_table(saved)
    with pytest.raises(DataFileError, match="collected with protocol 'small'"):
        load_dataset(saved, load_protocol("thesis-6.1"))
    bad = tmp_path / "missing.parquet"
    _rewrite(bad, table.drop(["gauge2_v"]))
    with pytest.raises(DataFileError, match="missing column 'gauge2_v'"):
        load_dataset(bad)
    bad = tmp_path / "dtype.parquet"
    i = table.column_names.index("gauge1_v")
    _rewrite(bad, table.set_column(i, "gauge1_v", pa.array([str(v) for v in table.column("gauge1_v").to_pylist()])))
    with pytest.raises(DataFileError, match="column 'gauge1_v' has type string, expected float"):
        load_dataset(bad)
    bad = tmp_path / "nometa.parquet"
    _rewrite(bad, table.replace_schema_metadata({}))
    with pytest.raises(DataFileError, match="no flexdigit metadata"):
        load_dataset(bad)
    bad = tmp_path / "edited.parquet"
    meta = json.loads(table.schema.metadata[b"flexdigit"])
    meta["protocol"]["repetitions"] = 5
    _rewrite(bad, table.replace_schema_metadata({"flexdigit": json.dumps(meta)}))
    with pytest.raises(DataFileError, match="does not match its fingerprint"):
        load_dataset(bad)
    bad = tmp_path / "dup.parquet"
    _rewrite(bad, pa.concat_tables([table, table.slice(0, 1)]))
    with pytest.raises(DataFileError, match="repeats a sample"):
        load_dataset(bad)
    bad = tmp_path / "junk.parquet"
    bad.write_bytes(b"not parquet at all")
    with pytest.raises(DataFileError, match="not a readable Parquet file"):
        load_dataset(bad)
    bad = tmp_path / "junk.csv"
    bad.write_text("# {}\nsample,test\n1,2\n")
    with pytest.raises(DataFileError, match="missing column"):
        load_dataset(bad)
    assert set(COLUMNS) <= set(table.column_names)


def test_rehang_on_hardware_asks_the_operator_and_waits_the_settle_time(make_rig):
    rig = make_rig()
    said = []
    rig.operator = said.append
    t0 = rig.clock()
    rig.rehang(2.5)
    assert said == ["Lift every weight and hang it again at the same place."]
    assert rig.clock() - t0 == pytest.approx(2.5)
    with pytest.raises(ParameterError, match="settle_s"):
        rig.rehang(-1.0)

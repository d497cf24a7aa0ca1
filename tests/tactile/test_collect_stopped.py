"""``flexdigit collect`` stopped by SIGTERM, SIGHUP or SIGINT, then rerun as it was (issue 22): the stop exits 128 +
the signal naming it, leaves the journal and no dataset or temporary file, and the plain rerun resumes to the very
dataset an uninterrupted collection gives (the runner replays the journal on the deterministic twin; the same
machine, so equal bit for bit, as tests/tactile/test_resume.py's kill -9 trials)."""

from __future__ import annotations

import signal
import subprocess
import sys

import numpy as np
import pytest

from children import STOPS, lines, start, stop, wait_until
from flexdigit.tactile.dataset import COLUMNS, load_dataset
from flexdigit.tactile.runner import journal_path

PROTOCOL = (
    'name = "stopped"\nloads_g = [12.5, 25.0]\npositions_from_tip_cm = [0, 4, 8, 12]\nactuation_commands = [20]\n'
    "repetitions = 6\nno_load_repetitions = 3\nsettle_s = 1.5\nrehang = true\n"
)
#: Readings journalled before the signal: the collection is under way (the journal's first line is its header).
READINGS_BEFORE_STOP = 3


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("reference")
    protocol = folder / "p.toml"
    protocol.write_text(PROTOCOL)
    out = folder / "ref.parquet"
    argv = ["collect", str(protocol), "--seed", "3", "--no-progress", "--out", str(out)]
    subprocess.run([sys.executable, "-m", "flexdigit.cli", *argv], check=True, capture_output=True)
    return protocol, load_dataset(out)


@pytest.mark.slow
@pytest.mark.parametrize("signum, code", STOPS, ids=[s.name for s, _ in STOPS])
def test_a_stopped_collection_resumes_to_the_same_dataset(tmp_path, reference, signum, code):
    protocol, ref = reference
    out = tmp_path / "d.parquet"
    argv = ["collect", protocol, "--seed", "3", "--no-progress", "--out", out, "--json"]
    proc = start(*argv)
    wait_until(lambda: lines(journal_path(out)) > READINGS_BEFORE_STOP, proc)
    exit_code, result, err = stop(proc, signum)
    name = signal.Signals(signum).name
    assert exit_code == code, err
    assert result["signal"] == name
    assert result["error"] == f"interrupted by {name}"
    assert not out.exists()
    assert journal_path(out).exists()  # no dataset yet: the journal, for the rerun
    assert sorted(p.name for p in tmp_path.iterdir()) == [journal_path(out).name]  # no temporary file
    done = subprocess.run([sys.executable, "-m", "flexdigit.cli", *map(str, argv)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    resumed = load_dataset(out)
    for column in COLUMNS:
        np.testing.assert_array_equal(resumed[column], ref[column], err_msg=column)
    assert resumed.meta["settings"] == ref.meta["settings"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.parquet"]  # the journal removed once done


@pytest.mark.slow
def test_a_stopped_collection_closes_its_recording_naming_the_signal(tmp_path, reference):
    from mcap.reader import make_reader

    protocol, _ = reference
    out, record = tmp_path / "d.parquet", tmp_path / "d.mcap"
    proc = start("collect", protocol, "--seed", "3", "--no-progress", "--out", out, "--record", record, "--json")
    wait_until(lambda: lines(journal_path(out)) > READINGS_BEFORE_STOP, proc)
    exit_code, result, err = stop(proc, signal.SIGTERM)
    assert exit_code == 143, err
    with open(record, "rb") as fh:  # the mcap library's reader: the summary and footer of a clean close
        reader = make_reader(fh)
        (stopped,) = [m.metadata for m in reader.iter_metadata() if m.name == "flexdigit.stop"]
        assert reader.get_summary().statistics.message_count > READINGS_BEFORE_STOP
    assert stopped["stop"] == "interrupted"
    assert stopped["signal"] == "SIGTERM"


#: Rows of the foreign file: enough for the import to run some seconds, within the readers' row limit
#: (flexdigit._io.RECORDS_ROW_LIMIT, 1e6): reading them took 3 s of CPU on the shared machine.
IMPORT_ROWS = 999_998
#: CPU time of the child before the signal, s: past its imports (~1 s), reading the rows.
IMPORT_CPU_BEFORE_STOP_S = 2.0


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the child's CPU time from /proc")
def test_a_stopped_import_leaves_the_old_dataset(tmp_path):
    from children import cpu_s

    readings = tmp_path / "readings.csv"
    readings.write_text("g1,g2,g3,m,x\n" + "0.11,0.52,0.03,25,40\n0.10,0.50,0.02,0,0\n" * (IMPORT_ROWS // 2))
    columns = tmp_path / "columns.toml"
    columns.write_text(
        'gauges = ["g1", "g2", "g3"]\ngauge_unit = "V"\nload = "m"\nload_unit = "g"\nposition = "x"\n'
        'position_unit = "mm"\nposition_from = "tip"\n'
    )
    out = tmp_path / "lab.parquet"
    out.write_bytes(b"the dataset of last week")
    proc = start("dataset", "import", readings, "--map", columns, "--out", out, "--force", "--json")
    wait_until(lambda: cpu_s(proc.pid) > IMPORT_CPU_BEFORE_STOP_S, proc)
    exit_code, result, err = stop(proc, signal.SIGTERM)
    assert exit_code == 143, err
    assert result["signal"] == "SIGTERM"
    assert out.read_bytes() == b"the dataset of last week"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["columns.toml", "lab.parquet", "readings.csv"]

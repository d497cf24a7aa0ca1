"""Execution: Dask gives the serial run's numbers, a killed study resumes, journals are never mixed."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pyarrow.parquet as pq
import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.studies.execution import JOURNAL_NAME, Journal, RowRecord, parse_scheduler

SPEC = """
[study]
name = "exec"
seed = 4
metrics = ["release_wn_rad_s", "rotation_gain_deg_per_command", "bayes_position_limit_mm"]
[sensitivity]
morris_trajectories = 2
sobol_n = 4
chunk_size = 3
bayes_samples = 50
[parameters.material.youngs_modulus_pa]
distribution = "uniform"
relative = 0.05
[parameters.calibration.housing_ei_n_m2]
distribution = "normal"
relative_sd = 0.1
[parameters.geometry.cable_eccentricity_m]
distribution = "uniform"
delta = 0.3e-3
[parameters.calibration.noise_white_v]
distribution = "uniform"
relative = 0.5
"""


def _cli(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "flexdigit.cli", *args], capture_output=True, text=True, **kwargs)


def _evaluations(out):
    return pq.read_table(out / "evaluations.parquet").to_pandas()


@pytest.mark.slow
def test_dask_workers_give_the_serial_numbers(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    runs = {}
    for workers in (0, 2):
        out = tmp_path / f"w{workers}"
        assert (
            main(["study", "sensitivity", str(spec), "--out", str(out), "--workers", str(workers), "--no-progress"])
            == 0
        )
        runs[workers] = _evaluations(out)
    assert len(runs[0]) == 2 * 5 + 2 * 4 * 6  # Morris r (d + 1) + Sobol 2N (d + 2)
    # bit for bit: every number of every row, computed in 2 worker processes in whatever order they finished
    assert runs[2].equals(runs[0])


@pytest.mark.slow
def test_a_killed_study_resumes_without_recomputing(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC.replace("chunk_size = 3", "chunk_size = 1").replace("sobol_n = 4", "sobol_n = 8"))
    ref = tmp_path / "ref"
    assert main(["study", "sensitivity", str(spec), "--out", str(ref), "--workers", "0", "--no-progress"]) == 0
    out = tmp_path / "killed"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "flexdigit.cli",
            "study",
            "sensitivity",
            str(spec),
            "--out",
            str(out),
            "--workers",
            "0",
            "--no-progress",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    journal = out / JOURNAL_NAME
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if journal.exists() and len(journal.read_text().splitlines()) >= 6:
            break
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    before = journal.read_text().splitlines()
    rows_total = len(_evaluations(ref))
    assert 6 <= len(before) < rows_total + 1, "the kill must land mid-study"
    assert not (out / "evaluations.parquet").exists()
    done = _cli("study", "sensitivity", str(spec), "--out", str(out), "--workers", "0", "--no-progress")
    assert done.returncode == 0, done.stderr
    after = journal.read_text().splitlines()
    # the rows done before the kill were kept, not recomputed; each row appears once
    assert after[: len(before) - 1] == before[:-1]
    rows = [json.loads(line)["row"] for line in after[1:]]
    assert sorted(rows) == list(range(rows_total))
    assert _evaluations(out).equals(_evaluations(ref))


def test_journal_refuses_other_settings_and_drops_a_cut_line(tmp_path):
    path = tmp_path / JOURNAL_NAME
    j = Journal(path, {"fingerprint": "aaa"})
    j.append([RowRecord(0, {"x": 1.0}), RowRecord(1, {}, "ValueError: bad")])
    with path.open("a") as fh:
        fh.write('{"row": 2, "val')  # a kill in the middle of a line
    again = Journal(path, {"fingerprint": "aaa"})
    assert sorted(again.records) == [0, 1] and again.records[1].error == "ValueError: bad"
    assert path.read_text().endswith("}\n")
    with pytest.raises(DataFileError, match="other settings"):
        Journal(path, {"fingerprint": "bbb"})
    assert Journal(path, {"fingerprint": "bbb"}, force=True).records == {}
    path.write_text("not json\n")
    with pytest.raises(DataFileError, match="line 1"):
        Journal(path, {"fingerprint": "aaa"})


def test_infinite_values_round_trip_through_the_journal(tmp_path):
    path = tmp_path / JOURNAL_NAME
    Journal(path, {"fingerprint": "f"}).append([RowRecord(3, {"settling_time_s": float("inf")})])
    assert np.isinf(Journal(path, {"fingerprint": "f"}).records[3].values["settling_time_s"])


@pytest.mark.parametrize("bad", ["localhost:8786", "tcp://", "http://host:1", "tcp://a b:1"])
def test_scheduler_address_is_checked(bad):
    with pytest.raises(ParameterError, match="scheduler"):
        parse_scheduler(bad)
    assert parse_scheduler("tcp://127.0.0.1:8786") == "tcp://127.0.0.1:8786"


def test_unreachable_scheduler_is_one_line(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    code = main(
        [
            "study",
            "sensitivity",
            str(spec),
            "--out",
            str(tmp_path / "o"),
            "--scheduler",
            "tcp://127.0.0.1:9",
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and "Traceback" not in "\n".join(err)
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err[-1]


def test_a_finished_study_is_not_overwritten(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC.replace('"bayes_position_limit_mm"', '"release_zeta"'))
    args = ["study", "sensitivity", str(spec), "--out", str(tmp_path / "o"), "--workers", "0", "--no-progress"]
    assert main(args) == 0
    before = (tmp_path / "o" / "summary.json").read_text()
    capsys.readouterr()
    assert main(args) == 2
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "o" / "summary.json").read_text() == before
    assert main([*args, "--force"]) == 0

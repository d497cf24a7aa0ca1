"""Execution: Dask gives the serial run's numbers, a killed study resumes, a dead worker fails only its task,
journals are never mixed."""

import dataclasses
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
from flexdigit.studies import execution
from flexdigit.studies.execution import (
    JOURNAL_NAME,
    TASK_FAILED,
    TASK_ROWS_MAX,
    Journal,
    RowRecord,
    parse_scheduler,
    retry_rows,
    task_sizes,
)
from flexdigit.studies.sensitivity import SensitivitySettings, run_sensitivity, write_outputs
from flexdigit.studies.spec import StudySpec, spec_from_toml

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


def _evaluations(out):
    return pq.read_table(out / "evaluations.parquet").to_pandas()


#: The study a kill or a signal stops mid-way: one row a chunk, 106 rows, so a stop lands between rows.
RESUMED_SPEC = SPEC.replace("chunk_size = 3", "chunk_size = 1").replace("sobol_n = 4", "sobol_n = 8")


@pytest.fixture(scope="module")
def resumed_ref(tmp_path_factory):
    """:data:`RESUMED_SPEC`'s serial run, its evaluations: what every stopped-then-resumed study must give. Run once
    for the module (the killed study and the SIGTERM-stopped ones, 0 and 2 workers, each compared with it): it was
    run three times, the same command on the same spec."""
    root = tmp_path_factory.mktemp("resumed-ref")
    spec = root / "spec.toml"
    spec.write_text(RESUMED_SPEC)
    ref = root / "ref"
    assert main(["study", "sensitivity", str(spec), "--out", str(ref), "--workers", "0", "--no-progress"]) == 0
    return _evaluations(ref)


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
def test_a_killed_study_resumes_without_recomputing(tmp_path, resumed_ref):
    spec = tmp_path / "spec.toml"
    spec.write_text(RESUMED_SPEC)
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
    rows_total = len(resumed_ref)
    assert 6 <= len(before) < rows_total + 1, "the kill must land mid-study"
    assert not (out / "evaluations.parquet").exists()
    # the rerun in this process: the claim is the journal's (the rows it keeps), not a process's
    assert main(["study", "sensitivity", str(spec), "--out", str(out), "--workers", "0", "--no-progress"]) == 0
    after = journal.read_text().splitlines()
    # the rows done before the kill were kept, not recomputed; each row appears once
    assert after[: len(before) - 1] == before[:-1]
    rows = [json.loads(line)["row"] for line in after[1:]]
    assert sorted(rows) == list(range(rows_total))
    assert _evaluations(out).equals(resumed_ref)


_DYING = """
import dataclasses
import os

from flexdigit.studies.spec import StudySpec


@dataclasses.dataclass(frozen=True)
class DyingSpec(StudySpec):
    die_on: str = ""
    sentinel: str = ""

    def parameter_set(self, values, label="sample"):
        if label == self.die_on and os.path.exists(self.sentinel):
            os._exit(3)  # no exception, no cleanup: as an out-of-memory kill or a segfault
        return super().parameter_set(values, label)
"""


@pytest.mark.slow
def test_a_worker_dying_mid_task_fails_that_task_only_and_a_rerun_computes_it(tmp_path, monkeypatch):
    import importlib

    import dask

    # a spec whose row 7 kills the worker process evaluating it while the file `die` exists, in a module the
    # workers (fresh processes) import
    (tmp_path / "dying_spec.py").write_text(_DYING)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))
    dying_spec = importlib.import_module("dying_spec")
    spec = spec_from_toml(SPEC.replace(', "bayes_position_limit_mm"', ""))
    settings = SensitivitySettings.from_spec(spec)
    sentinel = tmp_path / "die"
    sentinel.touch()
    fields = {f.name: getattr(spec, f.name) for f in dataclasses.fields(StudySpec)}
    dying = dying_spec.DyingSpec(**fields, die_on="row 7", sentinel=str(sentinel))
    assert dying.fingerprint() == spec.fingerprint()
    ref = run_sensitivity(spec, tmp_path / "ref", settings=settings, workers=0, progress=False)
    assert not ref.failed_rows
    out = tmp_path / "out"
    # one task in flight per worker (a dying worker takes only its running task with it); Dask gives a task up
    # once 2 workers died running it (allowed-failures 1: the default 3 only costs more worker restarts)
    config = {"distributed.scheduler.allowed-failures": 1, "distributed.scheduler.worker-saturation": 1.0}
    with dask.config.set(config):
        first = run_sensitivity(dying, out, settings=settings, workers=2, progress=False)
    # chunk_size 3: row 7's task holds rows 6-8; it is reported, the other 55 rows are the serial run's numbers
    assert first.failed_rows == [6, 7, 8]
    assert all(first.errors[i].startswith(f"{TASK_FAILED}KilledWorker") for i in (6, 7, 8))
    for metric in spec.metrics:
        keep = np.setdiff1d(np.arange(len(first.values)), [6, 7, 8])
        np.testing.assert_array_equal(first.outputs[metric][keep], ref.outputs[metric][keep])
        assert np.all(np.isnan(first.outputs[metric][[6, 7, 8]]))
    write_outputs(first, out)
    summary = json.loads((out / "summary.json").read_text())
    reported = {r["row"]: r for r in summary["failed_rows"]}
    assert sorted(reported) == [6, 7, 8]
    assert reported[7]["parameters"] == pytest.approx(dict(zip(spec.names, ref.values[7], strict=True)), rel=1e-15)
    # the metrics see NaN on 3 rows: no indices from a subset of the design, the row and its parameters named
    assert all("row 6" in first.refused[m] and spec.names[0] in first.refused[m] for m in spec.metrics)
    # a rerun (the cause gone) computes those 3 rows only and gives the serial study, exactly: a row's numbers do
    # not depend on the worker that ran it (exactness is the property; one machine, no stored number)
    assert retry_rows(out) == 3
    lines = len((out / JOURNAL_NAME).read_text().splitlines())
    sentinel.unlink()
    again = run_sensitivity(dying, out, settings=settings, workers=0, progress=False)
    assert len((out / JOURNAL_NAME).read_text().splitlines()) == lines + 3
    assert retry_rows(out) == 0
    assert not again.failed_rows
    assert not again.refused
    for metric in spec.metrics:
        np.testing.assert_array_equal(again.outputs[metric], ref.outputs[metric])


@dataclasses.dataclass(frozen=True)
class _ClosingSpec(StudySpec):
    """A spec whose row ``close_on`` closes the worker evaluating it while the file ``sentinel`` exists: a worker
    of an in-process cluster (no nanny), so no worker is left and none comes back. Without the file, the row
    takes ``slow_s`` longer: a long task on a live cluster."""

    close_on: str = ""
    sentinel: str = ""
    slow_s: float = 0.0

    def parameter_set(self, values, label="sample"):
        if label == self.close_on and os.path.exists(self.sentinel):
            from distributed import get_worker

            worker = get_worker()
            worker.loop.add_callback(worker.close)
        elif label == self.close_on:
            time.sleep(self.slow_s)
        return super().parameter_set(values, label)


def test_a_study_whose_workers_are_all_gone_ends_in_one_line_and_a_rerun_resumes(tmp_path, monkeypatch):
    from distributed import LocalCluster

    # the study looks at its cluster every 0.1 s and gives up after 0.5 s without a worker (the shipped values
    # are for a nanny's restart on a loaded machine; the path is the same)
    monkeypatch.setattr(execution, "WORKER_CHECK_S", 0.1)
    monkeypatch.setattr(execution, "NO_WORKER_GRACE_S", 0.5)
    spec = spec_from_toml(SPEC.replace(', "bayes_position_limit_mm"', ""))
    settings = SensitivitySettings.from_spec(spec)
    sentinel = tmp_path / "close"
    sentinel.touch()
    fields = {f.name: getattr(spec, f.name) for f in dataclasses.fields(StudySpec)}
    ref = run_sensitivity(spec, tmp_path / "ref", settings=settings, workers=0, progress=False)
    # the last row (in the last task: the earlier ones are done by then) closes the worker; on the rerun it takes
    # twice the grace: a long task is waited for, never cut
    last = len(ref.values) - 1
    closing = _ClosingSpec(**fields, close_on=f"row {last}", sentinel=str(sentinel), slow_s=1.0)
    out = tmp_path / "out"
    cluster_args = {"n_workers": 1, "threads_per_worker": 1, "processes": False, "protocol": "tcp://"}
    cluster_args |= {"host": "127.0.0.1", "dashboard_address": None}
    with LocalCluster(**cluster_args) as cluster, pytest.raises(OSError) as info:
        run_sensitivity(closing, out, settings=settings, scheduler=cluster.scheduler_address, progress=False)
    message = str(info.value)
    assert len(message.splitlines()) == 1
    assert "has had no worker for 0.5 s" in message
    assert "rerun the same command to resume" in message
    # every row finished before the worker went is journalled, with the serial run's numbers
    journal = Journal(out / JOURNAL_NAME, json.loads((out / JOURNAL_NAME).open().readline()))
    kept = sorted(journal.records)
    assert f"({len(kept)} rows journalled" in message
    assert 0 < len(kept) < len(ref.values)  # the study did stop short, some rows done
    assert last not in kept
    for metric in spec.metrics:
        got = [journal.records[r].values[metric] for r in kept]
        np.testing.assert_array_equal(got, ref.outputs[metric][kept], err_msg=metric)
    # a rerun on a cluster with a worker computes the other rows only, the last for 1 s, and gives the serial
    # study, exactly
    before = (out / JOURNAL_NAME).read_text().splitlines()
    sentinel.unlink()
    with LocalCluster(**cluster_args) as cluster:
        again = run_sensitivity(closing, out, settings=settings, scheduler=cluster.scheduler_address, progress=False)
    after = (out / JOURNAL_NAME).read_text().splitlines()
    assert after[: len(before)] == before
    assert len(after) == 1 + len(ref.values)
    assert not again.failed_rows
    for metric in spec.metrics:
        np.testing.assert_array_equal(again.outputs[metric], ref.outputs[metric], err_msg=metric)


@pytest.mark.slow
def test_a_finished_study_with_failed_tasks_is_rerun_not_refused(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC.replace(', "bayes_position_limit_mm"', ""))
    out = tmp_path / "o"
    args = ["study", "sensitivity", str(spec), "--out", str(out), "--workers", "0", "--no-progress"]
    assert main(args) == 0
    journal = Journal(
        out / JOURNAL_NAME, {"fingerprint": json.loads((out / JOURNAL_NAME).open().readline())["fingerprint"]}
    )
    good = journal.records[4]
    journal.append([RowRecord(4, {}, f"{TASK_FAILED}KilledWorker: all workers died")])  # as a dead worker leaves it
    assert retry_rows(out) == 1
    capsys.readouterr()
    assert main([*args, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["failed_rows"] == []
    assert Journal(out / JOURNAL_NAME, journal.header).records[4].values == good.values
    assert retry_rows(out) == 0
    assert main(args) == 2  # finished, nothing to retry: refused as before


def test_journal_refuses_other_settings_and_drops_a_cut_line(tmp_path):
    path = tmp_path / JOURNAL_NAME
    j = Journal(path, {"fingerprint": "aaa"})
    j.append([RowRecord(0, {"x": 1.0}), RowRecord(1, {}, "ValueError: bad")])
    with path.open("a") as fh:
        fh.write('{"row": 2, "val')  # a kill in the middle of a line
    again = Journal(path, {"fingerprint": "aaa"})
    assert sorted(again.records) == [0, 1]
    assert again.records[1].error == "ValueError: bad"
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
    assert code == 2
    assert "Traceback" not in "\n".join(err)
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


@pytest.mark.slow
@pytest.mark.parametrize("workers", ["0", "2"])
def test_a_study_stopped_by_sigterm_resumes_without_recomputing(tmp_path, resumed_ref, workers):
    """Issue 22: SIGTERM (kill, a batch scheduler) stops a study as Ctrl-C does: exit 143 with the JSON error
    naming it, the journal's finished rows kept, no outputs yet; the plain rerun computes only the rest."""
    from children import lines, stop, wait_until

    spec = tmp_path / "spec.toml"
    spec.write_text(RESUMED_SPEC)
    out = tmp_path / "stopped"
    argv = ["study", "sensitivity", str(spec), "--out", str(out), "--workers", workers, "--no-progress", "--json"]
    proc = subprocess.Popen([sys.executable, "-m", "flexdigit.cli", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    journal = out / JOURNAL_NAME
    wait_until(lambda: lines(journal) >= 6, proc)
    code, result, err = stop(proc, signal.SIGTERM)
    assert code == 143, err
    assert result["signal"] == "SIGTERM"
    assert result["error"] == "interrupted by SIGTERM"
    before = journal.read_text().splitlines()
    rows_total = len(resumed_ref)
    assert 6 <= len(before) < rows_total + 1, "the stop must land mid-study"
    assert not (out / "evaluations.parquet").exists()
    # the rerun in this process: the claim is the journal's (the rows it keeps), not a process's
    assert main(["study", "sensitivity", str(spec), "--out", str(out), "--workers", "0", "--no-progress"]) == 0
    after = journal.read_text().splitlines()
    assert after[: len(before)] == before  # every row finished before the stop was kept whole, not recomputed
    assert _evaluations(out).equals(resumed_ref)


def test_dask_tasks_take_consecutive_blocks_shrinking_to_one_at_the_end():
    # guided sizes, worked by hand: ceil(left / (4 slots x 2 workers)) blocks of the 40 left, then of 35, 30, ...
    assert task_sizes(40, 2, 1) == [5, 5, 4, 4, 3, 3, 2, 2, 2, 2] + [1] * 8
    # the N = 1024 study's 5,144 blocks of 8 on 2 workers: 32 blocks (256 rows) a task at most, single blocks last
    sizes = task_sizes(5144, 2, 8)
    assert sum(sizes) == 5144
    assert sizes[0] == TASK_ROWS_MAX // 8 == 32
    assert sizes == sorted(sizes, reverse=True)
    assert sizes[-8:] == [1] * 8
    assert len(sizes) < 5144 / 20  # what the client, the scheduler and the workers' event loops handle
    # blocks larger than the cap: one a task; and no workers yet known: sized as for one
    assert task_sizes(3, 2, 10**6) == [1, 1, 1]
    assert task_sizes(9, 0, 1) == task_sizes(9, 1, 1) == [3, 2, 1, 1, 1, 1]

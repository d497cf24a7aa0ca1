"""Journals that cannot mix, and kill -9 at random points of a collection (issue 16).

The reference is an uninterrupted collection on the twin; every interrupted one, resumed (possibly killed again),
must give the same dataset, reading for reading and bit for bit: the runner replays the journalled readings on the
deterministic twin before it continues (tactile/runner.py), and checks them on the way.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError, OutputExistsError
from flexdigit.tactile.dataset import COLUMNS, load_dataset, row_checksum
from flexdigit.tactile.protocols import Protocol, load_protocol
from flexdigit.tactile.runner import collect, journal_path
from flexdigit.tactile.thesis_experiments import twin_rig

#: Actuated, re-hung before every loaded reading: the twin's white noise, drift, friction and the digit's swing
#: all carry history from one reading to the next (the hardest case for a resume).
KILL9 = Protocol(
    "kill9",
    loads_kg=(0.0125, 0.025),
    positions_from_tip_m=(0.0, 0.04, 0.08, 0.12),
    actuation_commands=(20,),
    repetitions=4,
    no_load_repetitions=3,
    settle_s=1.5,
    rehang=True,
)
TRIALS = 24
SEED = 3


def _collect_on_twin(out, stop_after=None, seed=SEED, settle_s=None):
    rig = twin_rig(KILL9, seed=seed)
    try:
        return collect(KILL9, rig, out, rig_url="sim", stop_after=stop_after, settle_s=settle_s)
    finally:
        rig.close()


def _assert_same_dataset(a, b):
    # exact: a resumed collection keeps the readings it journalled and redraws the rest from the same seeded
    # streams on the same machine; nothing here is compared with a number made elsewhere
    for name in COLUMNS:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
    assert a.meta["settings"] == b.meta["settings"]


def _child(out):  # runs in a forked process that the test kills with SIGKILL
    try:
        _collect_on_twin(out)
    finally:
        os._exit(0)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ref")
    dataset = _collect_on_twin(folder / "ref.parquet")  # also warms the twin's caches the forked children share
    start = time.perf_counter()
    _collect_on_twin(folder / "again.parquet")  # how long a child takes: its kill instants span this
    return dataset, time.perf_counter() - start


def test_a_stopped_collection_resumes_to_the_uninterrupted_dataset(tmp_path, reference):
    ref, _ = reference
    out = tmp_path / "d.parquet"
    for _ in range(3):  # three stops at 7, 14 and 21 readings, then to the end
        partial = _collect_on_twin(out, stop_after=7)
        assert len(partial) in (7, 14, 21)
        assert journal_path(out).exists()
    _assert_same_dataset(_collect_on_twin(out), ref)
    assert not journal_path(out).exists()


@pytest.mark.slow
def test_kill_9_at_random_points_then_resume_gives_the_same_dataset(tmp_path, reference):
    """>= 20 trials, each killed once or twice at a random instant (a seeded draw) of the child's run."""
    ref, seconds = reference
    rng = np.random.default_rng(16)
    context = multiprocessing.get_context("fork")
    kills_with_readings = 0
    for trial in range(TRIALS):
        out = tmp_path / f"t{trial}.parquet"
        for _ in range(1 + trial % 2):
            child = context.Process(target=_child, args=(out,))
            child.start()
            time.sleep(rng.uniform(0.0, 1.2 * seconds))
            os.kill(child.pid, signal.SIGKILL)
            child.join()
            if journal_path(out).exists() and journal_path(out).stat().st_size > 0:
                lines = journal_path(out).read_bytes().count(b"\n")
                kills_with_readings += lines > 1
        if out.exists() and not journal_path(out).exists():
            resumed = load_dataset(out)  # the child finished before the kill
        else:
            resumed = _collect_on_twin(out)
        _assert_same_dataset(resumed, ref)
        assert not journal_path(out).exists()
        assert len(list(tmp_path.glob(f".t{trial}.parquet.*"))) <= 1
    assert kills_with_readings >= TRIALS // 3  # most kills landed mid-collection, not before or after it


@pytest.mark.slow
def test_kill_9_of_the_command_then_rerun(tmp_path):
    """The same through ``flexdigit collect`` in a process of its own (kill -9 of the real command)."""
    protocol = tmp_path / "p.toml"
    protocol.write_text(
        'name = "kill9"\nloads_g = [12.5, 25.0]\npositions_from_tip_cm = [0, 4, 8, 12]\nactuation_commands = [20]\n'
        "repetitions = 4\nno_load_repetitions = 3\nsettle_s = 1.5\nrehang = true\n"
    )
    exe = [sys.executable, "-m", "flexdigit.cli"]
    ref = tmp_path / "ref.parquet"
    argv = ["collect", str(protocol), "--seed", "3", "--no-progress", "--out"]
    subprocess.run([*exe, *argv, str(ref)], check=True, capture_output=True)
    out = tmp_path / "d.parquet"
    rng = np.random.default_rng(1)
    for _ in range(2):
        proc = subprocess.Popen([*exe, *argv, str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        while not journal_path(out).exists() and proc.poll() is None:
            time.sleep(0.01)
        time.sleep(rng.uniform(0.0, 0.3))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        if out.exists() and not journal_path(out).exists():
            break
    if not out.exists() or journal_path(out).exists():
        done = subprocess.run([*exe, *argv, str(out), "--json"], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        # the file's protocol (a TOML tares before each position and reads when steady: more than KILL9's samples)
        assert json.loads(done.stdout)["samples"] == load_protocol(protocol).sample_count
    _assert_same_dataset(load_dataset(out), load_dataset(ref))


# -- journals that cannot mix ---------------------------------------------------------------------------------
def test_a_resume_with_another_seed_or_settle_is_refused_naming_it(tmp_path):
    out = tmp_path / "d.parquet"
    _collect_on_twin(out, stop_after=5)
    with pytest.raises(DataFileError, match=r"started with rig.seed=3; this run has rig.seed=4"):
        _collect_on_twin(out, seed=4)
    with pytest.raises(DataFileError, match=r"started with settle_s=1.5; this run has settle_s=0.0"):
        _collect_on_twin(out, settle_s=0)  # 0 is a value, and another one
    assert len(load_dataset(journal_path(out))) == 5  # the journal was left as it was


def test_cli_resume_with_other_settings_is_refused_and_settle_0_is_recorded(tmp_path, capsys):
    """Issue 16: `collect --settle -1` journalled a reading before failing, and a resume without --settle then
    labelled no-load voltages as loaded; a resume with --seed 4 mixed silently; --settle 0 was not recorded."""
    protocol = tmp_path / "p.toml"
    protocol.write_text('name = "t"\nloads_g = [12.5]\npositions_from_tip_cm = [0, 5]\nrepetitions = 2\n')
    out = tmp_path / "d.parquet"
    base = ["collect", str(protocol), "--out", str(out), "--no-progress"]
    assert main([*base, "--settle", "-1"]) == 2
    assert not journal_path(out).exists()
    assert not out.exists()  # refused before the first reading
    from flexdigit.rig.base import open_rig
    from flexdigit.tactile.protocols import protocol_from_toml
    from flexdigit.tactile.runner import collect as collect_
    from flexdigit.tactile.runner import sim_options

    started = protocol_from_toml(protocol.read_text())  # the command's protocol, its TOML defaults and all
    assert started == Protocol("t", (0.0125,), (0.0, 0.05), repetitions=2, wait_until_steady=True,
                               tare_each_position=True)  # fmt: skip
    rig = open_rig("sim", seed=3, **sim_options(started))  # the rig `flexdigit collect` opens (numpy stepping)
    collect_(started, rig, out, settle_s=0, stop_after=3)
    assert main([*base, "--seed", "4", "--settle", "0", "--json"]) == 2
    err = json.loads(capsys.readouterr().out)["error"]
    assert "rig.seed=3; this run has rig.seed=4" in err
    assert main([*base, "--seed", "3", "--json"]) == 2  # the protocol's settle (1 s) is not the journal's 0
    assert "settle_s=0.0; this run has settle_s=1.0" in json.loads(capsys.readouterr().out)["error"]
    assert main([*base, "--seed", "3", "--settle", "0", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["resumed"]
    assert doc["settings"]["settle_s"] == 0.0
    assert doc["settings"]["rig"]["seed"] == 3
    assert load_dataset(out).meta["settings"]["settle_s"] == 0.0


def test_an_edited_journal_is_caught_by_the_replay(tmp_path):
    out = tmp_path / "d.parquet"
    _collect_on_twin(out, stop_after=6)
    lines = journal_path(out).read_text().splitlines()
    row = json.loads(lines[3])
    row["gauge2_v"] += 1e-3
    row["crc"] = row_checksum(row)  # a forged edit, checksum and all: the replay still catches it on the twin
    lines[3] = json.dumps(row)
    journal_path(out).write_text("\n".join(lines) + "\n")
    with pytest.raises(DataFileError, match="sample 2's gauge2_v is .* in the journal but the rig gives"):
        _collect_on_twin(out)


def test_existing_outputs_and_missing_directories_are_refused_before_any_reading(tmp_path, capsys):
    out = tmp_path / "d.parquet"
    out.write_bytes(b"precious")
    with pytest.raises(OutputExistsError):
        _collect_on_twin(out)
    assert out.read_bytes() == b"precious"
    assert not journal_path(out).exists()
    assert main(["collect", "thesis-6.1", "--out", str(tmp_path / "no" / "d.parquet")]) == 2
    assert "the directory" in capsys.readouterr().err
    assert not (tmp_path / "no").exists()


def test_a_stop_between_writing_the_dataset_and_removing_the_journal_is_finished(tmp_path, reference, monkeypatch):
    import flexdigit.tactile.runner as runner

    ref, _ = reference
    out = tmp_path / "d.parquet"
    save = runner.save_dataset

    def save_then_die(dataset, path, **kwargs):
        save(dataset, path, **kwargs)
        raise KeyboardInterrupt  # killed after the rename, before the journal is removed

    monkeypatch.setattr(runner, "save_dataset", save_then_die)
    with pytest.raises(KeyboardInterrupt):
        _collect_on_twin(out)
    monkeypatch.setattr(runner, "save_dataset", save)
    assert out.exists()
    assert journal_path(out).exists()
    _assert_same_dataset(_collect_on_twin(out), ref)  # finished: nothing collected again, the journal removed
    assert not journal_path(out).exists()
    # a dataset beside the journal of another, unfinished run is not silently taken for it
    other = tmp_path / "other.parquet"
    _collect_on_twin(other, stop_after=4)
    journal_path(other).rename(journal_path(out))
    with pytest.raises(DataFileError, match="beside a journal"):
        _collect_on_twin(out)

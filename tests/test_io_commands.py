"""Files in and out through the commands (issue 22 items 3 and 4): what a path points at, a full disk, two runs
into one output, names that are not UTF-8, inputs that are not regular files or too large.

Hangs are turned into failures: every command that could hang (a FIFO input) runs in a subprocess with a timeout.
Memory is asserted with ``resource.getrusage`` in a wrapper process, never time.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys

import pytest

from flexdigit._io import RECORDS_ROW_LIMIT, output_lock
from flexdigit.cli import main
from flexdigit.rig.base import open_rig
from flexdigit.rig.rotation import calibrate_rotation, save_rotation_map

#: A command that could hang on a FIFO gets this long before the test fails (s); each takes ~2 s when it works.
HANG_TIMEOUT_S = 90
#: Peak memory allowed to a command refusing a 10-million-row CSV (kB): the interpreter with numpy, pyarrow and
#: flexdigit imported takes ~150 MB; reading the 170 MB file into Python rows took more than 6 GB.
MAX_RSS_KB = 600_000

EXE = [sys.executable, "-m", "flexdigit.cli"]


@pytest.fixture(scope="module")
def rotation_map(tmp_path_factory):
    """The twin's rotation map, made once: a ``run`` subprocess given it skips ~1.5 s of calibrating the twin (the
    claims below are about the log, the lock and the disk, not the map)."""
    path = tmp_path_factory.mktemp("map") / "map.json"
    save_rotation_map(calibrate_rotation(open_rig("sim", seed=1)), path)
    return str(path)


def _run(argv, cwd, timeout=HANG_TIMEOUT_S):
    try:
        return subprocess.run([*EXE, *argv], cwd=cwd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"flexdigit {' '.join(map(str, argv))} hung for {timeout} s")


def _one_line(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    return lines[0]


# ------------------------------------------------------------------------------------------------------ inputs
#: Commands and where the special file goes; "{f}" is replaced by the special file's name (with its suffix).
INPUTS = {
    "params": (["params", "{f}.toml"], "a rig parameter TOML"),
    "simulate --params": (["simulate", "release", "--params", "{f}.toml", "--out", "o.csv"], "a rig parameter TOML"),
    "identify": (["identify", "release", "{f}.csv"], "a CSV or Parquet record"),
    "replay log": (["run", "--backend", "replay://{f}.jsonl"], "a flexdigit loop log"),
    "rotation map": (["run", "--rotation-map", "{f}.json", "--duration", "0.1"], "a rotation calibration JSON"),
    "study spec": (["study", "sensitivity", "{f}.toml", "--out", "o"], "a study spec TOML"),
    "protocol": (["collect", "{f}.toml", "--out", "o.parquet"], "a protocol TOML"),
    "calibration": (["collect", "thesis-6.1", "--calibration", "{f}.toml", "--out", "o.parquet"], "calibration"),
    "tissue": (["palpate", "--tissue", "{f}.toml"], "a tissue TOML"),
    "model": (["predict", "{f}.json", "d.parquet"], "a model file"),
    "dataset": (["train", "{f}.parquet", "--model", "m.json"], "Parquet"),
    "calibrate records": (["calibrate", "--out", "c.toml", "--sweep", "{f}.csv"], "a CSV-like text or .parquet"),
    "dataset import": (
        ["dataset", "import", "{f}.csv", "--out", "o.parquet", "--gauges", "a,b,c", "--load", "l", "--position", "p"],
        "a CSV-like",
    ),
}


def _links(tmp_path, target) -> None:
    for suffix in (".toml", ".csv", ".jsonl", ".json", ".parquet"):
        (tmp_path / f"in{suffix}").symlink_to(target)


#: One child runs every command of INPUTS through ``flexdigit.cli.main`` (the interpreter and flexdigit imported
#: once, not 13 times), each under ``SIGALRM`` so a hang is a failure naming it: ``{name: [exit code or "hung",
#: stderr]}`` as JSON on stdout.
_FIFO_CHILD = """
import contextlib, io, json, signal, sys
from flexdigit.cli import main

def _hung(*_):
    raise TimeoutError

signal.signal(signal.SIGALRM, _hung)
results = {}
for name, argv in json.loads(sys.argv[1]).items():
    err = io.StringIO()
    signal.alarm(int(sys.argv[2]))
    try:
        with contextlib.redirect_stderr(err):
            code = main(argv)
    except TimeoutError:
        code = "hung"
    finally:
        signal.alarm(0)
    results[name] = [code, err.getvalue()]
print(json.dumps(results))
"""


@pytest.fixture(scope="module")
def fifo_inputs(tmp_path_factory):
    """Every command of INPUTS given the same FIFO (``in.*``: symlinks to it), in one child process."""
    where = tmp_path_factory.mktemp("fifo")
    os.mkfifo(where / "fifo")
    _links(where, where / "fifo")
    argvs = {name: [a.replace("{f}", "in") for a in argv] for name, (argv, _) in INPUTS.items()}
    child = [sys.executable, "-c", _FIFO_CHILD, json.dumps(argvs), str(HANG_TIMEOUT_S)]
    timeout = HANG_TIMEOUT_S * (len(INPUTS) + 1)
    try:
        done = subprocess.run(child, cwd=where, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"the commands given a FIFO hung for {timeout} s")
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(INPUTS))
def test_a_fifo_input_is_refused_in_one_line_never_hangs(fifo_inputs, name):
    """A FIFO as params, model, rotation map, replay log or study spec hung forever (12 commands)."""
    code, stderr = fifo_inputs[name]
    assert code != "hung", f"flexdigit {name} hung for {HANG_TIMEOUT_S} s on a FIFO"
    line = _one_line(stderr)
    assert code == 2, line
    assert "in." in line, line
    assert "is a FIFO (named pipe)" in line, line
    assert INPUTS[name][1] in line, line


@pytest.mark.parametrize("name", ["params", "identify", "model", "calibrate records", "replay log"])
@pytest.mark.parametrize("target", ["/dev/null", "/dev/zero", "/dev/urandom"])
def test_a_device_input_is_refused_naming_it(tmp_path, capsys, monkeypatch, name, target):
    """A symlink to /dev/null read as an empty params file (the thesis defaults); /dev/zero grew past 6 GB."""
    _links(tmp_path, target)
    monkeypatch.chdir(tmp_path)
    argv, what = INPUTS[name]
    assert main([a.replace("{f}", "in") for a in argv]) == 2
    line = _one_line(capsys.readouterr().err)
    assert f"is a character device (a symlink to {target}), not a regular file" in line, line
    assert what in line, line


def test_a_directory_input_is_refused_naming_it(tmp_path, capsys):
    (tmp_path / "rig.toml").mkdir()
    assert main(["params", str(tmp_path / "rig.toml")]) == 2
    assert "rig.toml: is a directory, not a rig parameter TOML" in _one_line(capsys.readouterr().err)


def _big_csv(path, rows: int) -> None:
    """``time_s,sg1_v`` and ``rows`` rows, written a million at a time (~170 MB for 10 million)."""
    with path.open("wb") as fh:
        fh.write(b"time_s,sg1_v,sg2_v,sg3_v\n")
        block = b"".join(b"%.3f,1.25,0.5,0.25\n" % (i / 1000) for i in range(1000))
        for _ in range(rows // 1000):
            fh.write(block)


@pytest.mark.slow
def test_a_ten_million_row_csv_is_refused_by_name_in_bounded_memory(tmp_path):
    """identify and calibrate hung past a minute on it, dataset import took more than 6 GB."""
    big = tmp_path / "big.csv"
    _big_csv(big, 10_000_000)
    wrapper = (
        "import resource, subprocess, sys\n"
        "done = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
        "print(json.dumps([done.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, done.stderr]))\n"
    ).replace("import resource", "import json, resource")
    commands = [
        ["identify", "release", str(big)],
        ["calibrate", "--out", str(tmp_path / "c.toml"), "--sweep", str(big)],
        [
            "dataset",
            "import",
            str(big),
            "--out",
            str(tmp_path / "d.parquet"),
            "--gauges",
            "sg1_v,sg2_v,sg3_v",
            "--load",
            "sg1_v",
            "--position",
            "sg2_v",
        ],
    ]
    for argv in commands:
        out = subprocess.run(
            [sys.executable, "-c", wrapper, *EXE, *argv], capture_output=True, text=True, timeout=600
        ).stdout
        code, rss_kb, stderr = json.loads(out)
        line = _one_line(stderr)
        assert code == 2, line
        assert f"big.csv: more than {RECORDS_ROW_LIMIT:,} lines" in line, line
        assert rss_kb < MAX_RSS_KB, (argv[0], rss_kb)
    assert not (tmp_path / "d.parquet").exists()
    assert not (tmp_path / "c.toml").exists()


# ----------------------------------------------------------------------------------------------------- outputs
STEP = ["simulate", "step", "--duration", "0.2", "--rate", "100"]


@pytest.mark.parametrize("kind", ["fifo", "devnull-link", "dev-null"])
def test_an_output_onto_a_fifo_or_a_device_is_refused_even_with_force(tmp_path, capsys, kind):
    """--out (with --force) onto a FIFO or a device replaced it with a regular file (as root, /dev/null)."""
    if kind == "fifo":
        out = tmp_path / "o.parquet"
        os.mkfifo(out)
    elif kind == "devnull-link":
        out = tmp_path / "o.parquet"
        out.symlink_to(os.devnull)
    else:
        out = os.devnull
    before = os.lstat(out)
    assert main([*STEP, "--out", str(out), "--force"]) == 2
    line = _one_line(capsys.readouterr().err)
    assert "not a regular file" in line, line
    assert "not even with --force" in line, line
    assert os.lstat(out).st_ino == before.st_ino
    assert os.lstat(out).st_mode == before.st_mode
    assert sorted(os.listdir(tmp_path)) == ([] if kind == "dev-null" else ["o.parquet"])


def test_a_non_utf8_output_name_works(tmp_path):
    """`--out o\\xff.parquet` was refused with a codec error."""
    name = b"o\xff.parquet"
    done = subprocess.run(
        [*(os.fsencode(a) for a in EXE), *(a.encode() for a in STEP), b"--out", name],
        cwd=tmp_path,
        capture_output=True,
        timeout=HANG_TIMEOUT_S,
    )
    assert done.returncode == 0, done.stderr
    assert os.listdir(os.fsencode(tmp_path)) == [name]


def test_written_files_are_0644_under_umask_022(tmp_path):
    """Issue 28: every file flexdigit wrote was 0600 whatever the umask (in-process: the mode is the library's)."""
    before = os.umask(0o022)
    try:
        assert main([*STEP, "--out", str(tmp_path / "o.parquet")]) == 0
    finally:
        os.umask(before)
    assert oct((tmp_path / "o.parquet").stat().st_mode & 0o777) == oct(0o644)


@contextlib.contextmanager
def _small_tmpfs(path, size="1m"):
    """A tmpfs of ``size`` at ``path`` (root only: the test machines and CI run as root), unmounted after."""
    path.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)], capture_output=True)
    if done.returncode != 0:
        pytest.fail(f"cannot mount a tmpfs (run as root, or see test_io.py's injected ENOSPC): {done.stderr!r}")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


def _fill(directory, leave_bytes: int) -> None:
    st = os.statvfs(directory)
    with (directory / "filler").open("wb") as fh:
        fh.write(b"\0" * max(st.f_bavail * st.f_frsize - leave_bytes, 0))


@pytest.mark.skipif(os.geteuid() != 0, reason="mounting a tmpfs needs root; test_io.py injects ENOSPC instead")
def test_a_forced_log_on_a_disk_that_fills_keeps_the_old_log_and_names_it(tmp_path, monkeypatch, rotation_map):
    """`--log old.jsonl --force` on a disk that filled stopped at t = 1.6 s and the previous log was gone."""
    with _small_tmpfs(tmp_path / "disk") as disk:
        monkeypatch.chdir(disk)
        assert main(["run", "--log", "old.jsonl", "--duration", "1"]) == 0  # the old log (in-process: no claim)
        monkeypatch.undo()
        old = (disk / "old.jsonl").read_bytes()
        _fill(disk, 48 * 1024)
        done = _run(["run", "--log", "old.jsonl", "--force", "--duration", "60", "--rotation-map", rotation_map], disk)
        assert "old.jsonl: cannot write it: No space left on device" in done.stdout + done.stderr
        assert "log: old.jsonl is kept as it was" in done.stdout + done.stderr
        assert (disk / "old.jsonl").read_bytes() == old
        assert sorted(p.name for p in disk.iterdir()) == ["filler", "old.jsonl"]  # no temporary file


@pytest.mark.skipif(os.geteuid() != 0, reason="mounting a tmpfs needs root; test_io.py injects ENOSPC instead")
def test_a_forced_table_on_a_full_disk_keeps_the_old_file_and_names_it(tmp_path):
    with _small_tmpfs(tmp_path / "disk") as disk:
        (disk / "o.parquet").write_bytes(b"old results")
        _fill(disk, 8 * 1024)
        done = _run([*STEP, "--duration", "5", "--out", "o.parquet", "--force"], disk)
        line = _one_line(done.stderr)
        assert done.returncode == 2
        assert "o.parquet: cannot write it:" in line
        assert "previous file is kept" in line
        assert (disk / "o.parquet").read_bytes() == b"old results"
        assert sorted(p.name for p in disk.iterdir()) == ["filler", "o.parquet"]


# ------------------------------------------------------------------------------------------ two runs, one output
def test_a_second_run_appending_to_a_log_in_use_is_refused(tmp_path):
    """Two `run --log --append` at once left a log that no longer read back: the second is refused."""
    log = tmp_path / "r.jsonl"
    assert main(["run", "--log", str(log), "--duration", "0.2"]) == 0  # the first log: in-process (no claim)
    before = log.read_bytes()
    with output_lock(log):  # as a first run holds it for its whole length
        done = _run(["run", "--log", str(log), "--append", "--duration", "0.2"], tmp_path)
    line = _one_line(done.stderr)
    assert done.returncode == 2, line
    assert "r.jsonl: another flexdigit process" in line, line
    assert "is writing it" in line, line
    assert log.read_bytes() == before


def test_a_collect_into_an_output_in_use_is_refused_before_its_journal(tmp_path):
    out = tmp_path / "d.parquet"
    with output_lock(out):
        done = _run(["collect", "thesis-6.1", "--no-progress", "--out", str(out)], tmp_path)
    assert done.returncode == 2
    assert "d.parquet: another flexdigit process" in _one_line(done.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.slow
def test_two_collects_into_one_output_one_completes_one_is_refused(tmp_path):
    """Both died ("the journal was edited or mixed with another") and left a journal neither could resume."""
    from flexdigit.tactile.dataset import load_dataset

    out = tmp_path / "d.parquet"
    argv = [*EXE, "collect", "thesis-6.1", "--no-progress", "--out", str(out)]
    procs = [subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [(p.wait(timeout=600), p.stderr.read()) for p in procs]
    for p in procs:
        p.stdout.close()
        p.stderr.close()
    codes = sorted(code for code, _ in results)
    assert codes == [0, 2], results
    refused = next(err for code, err in results if code == 2)
    line = _one_line(refused)
    assert "d.parquet: another flexdigit process" in line or "d.parquet: the file exists" in line, line
    assert len(load_dataset(out)) == 1275  # thesis-6.1's readings, all of them, once
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.parquet"]


@pytest.mark.slow
def test_two_runs_appending_to_one_log_at_once_the_second_is_refused(tmp_path, rotation_map):
    """Two real `run --log --append` at once: the first (the paced twin, for up to 10 minutes) holds the log until
    the second has been refused, then SIGTERM stops it (as systemd would; SIGINT may be inherited ignored from a
    non-interactive shell); however slowly a loaded machine starts the second."""
    import signal
    import time

    from flexdigit.rig.loop import read_log_runs

    log = tmp_path / "r.jsonl"
    argv = ["run", "--backend", "sim+paced", "--log", str(log), "--append", "--rotation-map", rotation_map]
    first = subprocess.Popen([*EXE, *argv, "--duration", "600"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        for _ in range(600):  # until the first holds the log's lock (it is released only when the run ends)
            if (tmp_path / ".r.jsonl.lock").exists() or first.poll() is not None:
                break
            time.sleep(0.1)
        assert first.poll() is None, "the first run ended before the second could start"
        second = _run([*argv, "--duration", "0.2"], tmp_path)
        assert first.poll() is None, "the first run ended before the second was refused: the test proves nothing"
    finally:
        first.send_signal(signal.SIGTERM)
        out, err = first.communicate(timeout=300)
    assert second.returncode == 2
    assert "r.jsonl: another flexdigit process" in _one_line(second.stderr)
    assert first.returncode == 143, err  # 128 + SIGTERM: stopped as systemd stops a run
    runs = read_log_runs(log)
    # one run, whole up to the signal (its footer says so), nothing of the second mixed in
    assert len(runs) == 1
    assert runs[0][3]["stop"] == "interrupted"
    assert len(runs[0][2]) > 0


@pytest.mark.slow
@pytest.mark.skipif(os.geteuid() != 0, reason="mounting a tmpfs needs root; test_io.py injects ENOSPC instead")
def test_a_collect_on_a_disk_that_fills_names_its_journal_and_a_rerun_resumes(tmp_path, monkeypatch):
    from flexdigit.tactile.dataset import load_dataset

    with _small_tmpfs(tmp_path / "disk") as disk:
        _fill(disk, 40 * 1024)
        argv = ["collect", "thesis-6.1", "--no-progress", "--out", "d.parquet"]
        done = _run(argv, disk, timeout=600)
        line = _one_line(done.stderr)
        assert done.returncode == 2, line
        assert "cannot write it: No space left on device" in line, line
        assert "readings before are kept: free some space and rerun to resume" in line
        (disk / "filler").unlink()
        monkeypatch.chdir(disk)
        assert main(argv) == 0  # the rerun resumes (in-process: the journal is the library's, not a process's)
        monkeypatch.undo()
        assert len(load_dataset(disk / "d.parquet")) == 1275
        assert sorted(p.name for p in disk.iterdir()) == ["d.parquet"]

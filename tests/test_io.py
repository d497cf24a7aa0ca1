"""flexdigit._io: outputs are atomic and never clobber an existing file unless forced."""

from __future__ import annotations

import errno
import os
import re
import socket
import stat

import pytest

from flexdigit._io import (
    OutputStream,
    atomic_path,
    atomic_write,
    check_output,
    count_lines,
    output_lock,
    read_bytes,
    read_text,
)
from flexdigit.errors import DataFileError, OutputError, OutputExistsError


def test_write_then_refuse_existing_keeps_old_content(tmp_path):
    out = tmp_path / "x.txt"
    with atomic_write(out, "w") as fh:
        fh.write("first")
    with pytest.raises(OutputExistsError, match="x.txt: the file exists; pass --force"), atomic_write(out, "w") as fh:
        fh.write("second")
    assert out.read_text() == "first"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.txt"]  # no temporary file left behind


def test_force_replaces(tmp_path):
    out = tmp_path / "x.bin"
    out.write_bytes(b"old")
    with atomic_write(out, force=True) as fh:
        fh.write(b"new")
    assert out.read_bytes() == b"new"


def test_failure_inside_block_leaves_destination_untouched(tmp_path):
    out = tmp_path / "x.txt"
    out.write_text("precious")
    with pytest.raises(RuntimeError), atomic_write(out, "w", force=True) as fh:
        fh.write("half")
        raise RuntimeError("disk full")
    assert out.read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.txt"]


def test_failure_with_no_destination_creates_nothing(tmp_path):
    out = tmp_path / "y.parquet"
    with pytest.raises(RuntimeError), atomic_path(out) as tmp:
        tmp.write_bytes(b"partial")
        raise RuntimeError("killed")
    assert list(tmp_path.iterdir()) == []


def test_file_appearing_meanwhile_is_not_clobbered(tmp_path):
    out = tmp_path / "z.txt"
    with pytest.raises(OutputExistsError), atomic_write(out, "w") as fh:
        fh.write("ours")
        out.write_text("someone else's")
    assert out.read_text() == "someone else's"


def test_check_output_names_the_problem_before_work(tmp_path):
    with pytest.raises(FileNotFoundError, match="the directory .*missing does not exist"):
        check_output(tmp_path / "missing" / "out.json")
    with pytest.raises(IsADirectoryError, match="is a directory"):
        check_output(tmp_path, force=True)
    (tmp_path / "a").write_text("")
    with pytest.raises(OutputExistsError, match="pass --force"):
        check_output(tmp_path / "a")
    assert check_output(tmp_path / "a", force=True) == tmp_path / "a"


# -------------------------------------------------------------------------------- issue 22: atomic for real


def _names(directory) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


def test_an_injected_full_disk_keeps_the_old_file_names_it_and_leaves_no_debris(tmp_path):
    out = tmp_path / "fit.json"
    out.write_text("old")
    with pytest.raises(OutputError, match=r"fit.json: cannot write it: No space left on device; the previous file is"):
        with atomic_write(out, "w", force=True) as fh:
            fh.write("half")
            raise OSError(errno.ENOSPC, "No space left on device")
    assert out.read_text() == "old"
    assert _names(tmp_path) == ["fit.json"]


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT, errno.EACCES, errno.EROFS, errno.EIO])
def test_a_write_failing_at_fsync_is_a_failed_write_too(tmp_path, monkeypatch, code):
    """NFS and some disks report a full disk or quota only at fsync: the old file stays, the error names it."""
    out = tmp_path / "a.bin"
    out.write_bytes(b"old")

    def fsync(fd):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(os, "fsync", fsync)
    with pytest.raises(OutputError, match=rf"a.bin: cannot write it: {re.escape(os.strerror(code))}") as info:
        with atomic_write(out, force=True) as fh:
            fh.write(b"new")
    assert info.value.errno == code
    assert isinstance(info.value, OSError)
    assert out.read_bytes() == b"old"
    assert _names(tmp_path) == ["a.bin"]


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_written_files_honour_the_umask(tmp_path, umask, mode):
    """Issue 28: every file was 0600 (mkstemp's mode) whatever the umask; as a plain open(): 0o666 & ~umask."""
    old = os.umask(umask)
    try:
        with atomic_write(tmp_path / "a.txt", "w") as fh:
            fh.write("x")
        with atomic_path(tmp_path / "b.parquet") as tmp:
            tmp.write_bytes(b"x")
        stream = OutputStream(tmp_path / "c.jsonl", "new")
        stream.file.write("x\n")
        stream.close()
    finally:
        os.umask(old)
    for name in ("a.txt", "b.parquet", "c.jsonl"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == mode, name


def test_a_replaced_file_keeps_its_mode(tmp_path):
    out = tmp_path / "shared.csv"
    out.write_text("old")
    out.chmod(0o640)
    with atomic_write(out, "w", force=True) as fh:
        fh.write("new")
    assert stat.S_IMODE(out.stat().st_mode) == 0o640


def test_a_symlink_planted_at_the_temporary_name_is_never_followed(tmp_path, monkeypatch):
    import secrets

    victim = tmp_path / "victim"
    victim.write_text("precious")
    planted = tmp_path / ".out.txt.aaaa.tmp"
    planted.symlink_to(victim)
    names = iter(["aaaa", "bbbb"])
    monkeypatch.setattr(secrets, "token_hex", lambda n: next(names))
    with atomic_write(tmp_path / "out.txt", "w") as fh:
        fh.write("ours")
    assert victim.read_text() == "precious"
    assert (tmp_path / "out.txt").read_text() == "ours"
    assert planted.is_symlink()  # left as it was, not written through


def test_a_study_journal_never_follows_a_symlink_planted_at_its_old_temporary_name(tmp_path):
    """The study journal's header went through the fixed name .journal.jsonl.tmp: a planted symlink redirected it."""
    from flexdigit.studies.execution import JOURNAL_NAME, Journal

    victim = tmp_path / "victim"
    victim.write_text("precious")
    (tmp_path / f".{JOURNAL_NAME}.tmp").symlink_to(victim)
    Journal(tmp_path / JOURNAL_NAME, {"fingerprint": "f"})
    assert victim.read_text() == "precious"
    assert (tmp_path / JOURNAL_NAME).read_text().startswith("{")


def _special(tmp_path, kind):
    path = tmp_path / f"the-{kind}"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "devnull-link":
        path.symlink_to(os.devnull)
    elif kind == "directory":
        path.mkdir()
    elif kind == "socket":
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(str(path))
        sock.close()
    return path


SPECIAL = ["fifo", "devnull-link", "directory", "socket"]


@pytest.mark.parametrize("kind", SPECIAL)
def test_an_output_that_is_not_a_regular_file_is_refused_even_with_force(tmp_path, kind):
    path = _special(tmp_path, kind)
    before = os.lstat(path)
    for attempt in (
        lambda: check_output(path, force=True),
        lambda: atomic_write(path, force=True).__enter__(),
        lambda: OutputStream(path, "replace"),
        lambda: OutputStream(path, "append"),
    ):
        with pytest.raises(OSError, match=f"{path.name}: is a"):
            attempt()
    after = os.lstat(path)
    assert (after.st_ino, stat.S_IFMT(after.st_mode)) == (before.st_ino, stat.S_IFMT(before.st_mode))
    assert os.path.exists(os.devnull)
    assert stat.S_ISCHR(os.stat(os.devnull).st_mode)


@pytest.mark.parametrize("kind", ["fifo", "devnull-link", "socket"])
def test_an_input_that_is_not_a_regular_file_is_refused_naming_it(tmp_path, kind):
    """Opened non-blocking and fstat-ed: a FIFO without a writer returns at once instead of hanging."""
    path = _special(tmp_path, kind)
    what = {"fifo": "a FIFO", "devnull-link": "a character device (a symlink to /dev/null)", "socket": "a socket"}
    with pytest.raises(DataFileError, match=rf"the-{kind}: is {re.escape(what[kind])}.*expected a rig parameter TOML"):
        read_text(path, "a rig parameter TOML")


def test_dev_zero_is_refused_not_read_into_memory():
    with pytest.raises(DataFileError, match="/dev/zero: is a character device"):
        read_bytes("/dev/zero", "a model file")


def test_each_kind_of_input_has_a_stated_size_limit(tmp_path):
    path = tmp_path / "huge.toml"
    with path.open("wb") as fh:  # sparse: 17 MiB on paper, nothing on the disk
        fh.truncate(17 * 2**20)
    with pytest.raises(DataFileError, match=r"huge.toml: 17 MiB, more than the 16 MiB flexdigit reads as a rig param"):
        read_text(path, "a rig parameter TOML")


def test_count_lines_refuses_a_table_past_its_row_limit(tmp_path):
    path = tmp_path / "t.csv"
    path.write_bytes(b"t,y\n" + b"0,1\n" * 250)
    assert count_lines(path, "a CSV record", most=1000) == 251
    with pytest.raises(DataFileError, match=r"t.csv: more than 100 lines; flexdigit reads a CSV record of at most 100"):
        count_lines(path, "a CSV record", most=100)


def test_non_utf8_output_names_work(tmp_path):
    """Python hands a non-UTF-8 name over as surrogates; pyarrow, which takes UTF-8 only, writes an ASCII temp."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = tmp_path / os.fsdecode(b"o\xff.parquet")
    with atomic_path(out) as tmp:
        pq.write_table(pa.table({"a": [1, 2]}), tmp)
    assert os.listdir(os.fsencode(tmp_path)) == [b"o\xff.parquet"]
    with open(out, "rb") as fh:  # pyarrow takes UTF-8 names only: a file object
        assert pq.read_table(fh).column("a").to_pylist() == [1, 2]


# ------------------------------------------------------------------------------------------------ streams
def test_a_forced_stream_is_written_beside_the_old_file_and_replaces_it_at_a_complete_end(tmp_path):
    out = tmp_path / "log.jsonl"
    out.write_text("old\n")
    stream = OutputStream(out, "replace")
    stream.file.write("new\n")
    stream.file.flush()
    assert out.read_text() == "old\n"  # while the run goes on, the old log is whole
    assert stream.close(complete=True) == out
    assert out.read_text() == "new\n"
    assert _names(tmp_path) == ["log.jsonl"]


def test_a_stopped_forced_stream_keeps_the_old_file_and_its_own_as_partial(tmp_path):
    out = tmp_path / "log.jsonl"
    out.write_text("old\n")
    stream = OutputStream(out, "replace")
    stream.file.write("stopped run\n")
    assert stream.close(complete=False) == tmp_path / "log.partial.jsonl"
    assert out.read_text() == "old\n"
    assert (tmp_path / "log.partial.jsonl").read_text() == "stopped run\n"
    assert _names(tmp_path) == ["log.jsonl", "log.partial.jsonl"]


def test_a_forced_stream_that_fails_to_write_leaves_the_old_file_and_no_debris(tmp_path):
    out = tmp_path / "rec.mcap"
    out.write_bytes(b"old")
    stream = OutputStream(out, "replace", binary=True)
    stream.file.write(b"new")
    stream.abandon()
    assert out.read_bytes() == b"old"
    assert _names(tmp_path) == ["rec.mcap"]


def test_a_loop_log_on_a_full_disk_names_the_file_and_keeps_the_old_log(tmp_path, monkeypatch):
    """`palpate --log old.jsonl --force` on a disk that filled lost the old log and said only "[Errno 28]"."""
    from flexdigit.rig.loop import SampleLog

    out = tmp_path / "old.jsonl"
    out.write_text('{"format": "old"}\n')
    log = SampleLog(out, {"controller": "x"}, mode="replace")

    class Full:
        def __init__(self, inner):
            self.inner = inner

        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

        def __getattr__(self, name):
            return getattr(self.inner, name)

    log._file = Full(log._file)
    with pytest.raises(OutputError, match="old.jsonl: cannot write it: No space left on device; the previous file"):
        log.write({"k": 0})
    log.abandon()
    assert out.read_text() == '{"format": "old"}\n'
    assert _names(tmp_path) == ["old.jsonl"]


def test_a_second_writer_of_one_output_is_refused_not_mixed(tmp_path):
    """In one process the lock nests; another process (here: a subprocess) is refused while it is held."""
    import subprocess
    import sys

    out = tmp_path / "run.jsonl"
    code = (
        "import sys\nfrom flexdigit._io import OutputStream\n"
        "try:\n    OutputStream(sys.argv[1], 'append')\nexcept OSError as exc:\n    print(type(exc).__name__, exc)\n"
    )
    with output_lock(out), output_lock(out):
        done = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True, text=True, timeout=120)
        assert done.stdout.startswith("OutputBusyError "), done
        assert f"pid {os.getpid()}" in done.stdout, done
        assert "run.jsonl: another flexdigit process" in done.stdout
    assert _names(tmp_path) == []  # the lock file goes with the lock
    with OutputStream(out, "append").file as fh:  # free again
        fh.write("x\n")


def test_the_lock_is_released_when_its_holder_dies(tmp_path):
    """kill -9 (here os._exit) leaves the lock file but not the lock: the kernel drops a dead process's flock."""
    import subprocess
    import sys

    out = tmp_path / "d.parquet"
    code = (
        "import os, sys\nfrom flexdigit._io import output_lock\n"
        "held = output_lock(sys.argv[1])\nheld.__enter__()\nos._exit(9)\n"
    )
    subprocess.run([sys.executable, "-c", code, str(out)], timeout=120)
    assert (tmp_path / ".d.parquet.lock").exists()
    with output_lock(out):
        pass
    assert _names(tmp_path) == []


def test_a_parquet_table_past_the_row_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    import pyarrow as pa
    import pyarrow.parquet as pq

    from flexdigit import _io
    from flexdigit._table import read_table

    path = tmp_path / "t.parquet"
    pq.write_table(pa.table({"a": list(range(300))}), path)
    assert len(read_table(path).rows) == 300
    monkeypatch.setattr(_io, "RECORDS_ROW_LIMIT", 299)
    with pytest.raises(DataFileError, match=r"t.parquet: 300 rows; flexdigit reads a table of at most 299 rows"):
        read_table(path)


def test_a_large_record_is_announced_on_stderr_before_it_is_read(tmp_path, capsys):
    from flexdigit._io import LARGE_RECORD_LINES

    path = tmp_path / "big.csv"
    path.write_bytes(b"t,y\n" + b"0,1\n" * LARGE_RECORD_LINES)
    count_lines(path, "a CSV record")
    assert capsys.readouterr().err == f"flexdigit: reading {path}: {LARGE_RECORD_LINES + 1:,} lines\n"
    count_lines(tmp_path / "big.csv", "a CSV record", most=10**7)
    path.write_bytes(b"t,y\n0,1\n")
    count_lines(path, "a CSV record")
    assert capsys.readouterr().err.count("reading") == 1  # the large one only


def test_a_one_shot_write_is_refused_while_another_process_holds_the_lock_and_leaves_no_lock_file(tmp_path):
    import subprocess
    import sys

    out = tmp_path / "p.toml"
    code = (
        "import sys\nfrom flexdigit._io import atomic_write\n"
        "try:\n    atomic_write(sys.argv[1], 'w', force=True).__enter__()\n"
        "except OSError as exc:\n    print(type(exc).__name__, exc)\n"
    )
    with output_lock(out):
        with atomic_write(out, "w") as fh:  # this process holds it: allowed (a collection saving its dataset)
            fh.write("ours")
        done = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True, text=True, timeout=120)
    assert done.stdout.startswith("OutputBusyError "), done
    assert "p.toml: another flexdigit process" in done.stdout, done
    with atomic_write(out, "w", force=True) as fh:
        fh.write("again")
    assert _names(tmp_path) == ["p.toml"]
    assert out.read_text() == "again"


def test_the_next_locked_writer_removes_a_dead_writers_temporary_file_but_not_a_live_ones(tmp_path):
    # a writer killed outright (kill -9) leaves its temporary file, unlocked; one being written is flock-held
    import fcntl

    from flexdigit._io import output_lock

    out = tmp_path / "d.parquet"
    dead = tmp_path / ".d.parquet.0123456789ab.tmp"
    live = tmp_path / ".d.parquet.ba9876543210.tmp"
    other = tmp_path / ".e.parquet.0123456789ab.tmp"  # another output's
    for p in (dead, live, other):
        p.write_bytes(b"x")
    with open(live, "rb") as held:
        fcntl.flock(held.fileno(), fcntl.LOCK_EX)
        with output_lock(out):
            pass
        assert not dead.exists()
        assert live.exists()
    assert other.exists()

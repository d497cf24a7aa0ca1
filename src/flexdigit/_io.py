"""Files in and out: the one way flexdigit writes an output and opens an input.

Outputs (the guarantees docs/guide/reliability.md states, each tested in ``tests/test_io.py``):

- **Atomic**: a new file goes to a temporary file beside its destination, created exclusively (``O_EXCL |
  O_NOFOLLOW``: a symlink planted at its name is never followed), complete and fsynced, then renamed into place
  and the directory fsynced. A crash, Ctrl-C or a full disk leaves the destination as it was (absent, or the old
  file intact). A streamed output (a loop log, an MCAP recording: :class:`OutputStream`) that replaces an old one
  (``--force``) is written beside it the same way and renamed at the end; a new one is written in place (a crash
  keeps what was written); ``--append`` appends.
- **Named failures**: a failed write (full disk, quota, permission) raises :class:`~flexdigit.errors.OutputError`
  (an ``OSError``) naming the destination, and leaves the old file and no temporary file.
- **Modes honour the umask**, as a plain ``open`` would: files are created ``0o666 & ~umask`` (0644 under umask
  022), and a file that replaces another keeps the old one's mode.
- **Only regular files are replaced**: a FIFO, device, socket or directory at the destination (also through a
  symlink: ``--out /dev/null``) is refused, even with ``--force``. An existing file is refused unless ``force``.
- **One writer per output**: an advisory lock (``flock`` on ``.NAME.lock`` beside it, removed when released; the
  kernel releases it when the process dies), held by streams, collections and studies for their whole run,
  refuses a second writer of the same output (:class:`~flexdigit.errors.OutputBusyError`) instead of mixing the
  two; a one-shot atomic write is refused while another process holds it.
- Names that are not UTF-8 work (Python's surrogateescape); temporary names are ASCII.

Inputs: :func:`open_input` (and :func:`read_bytes`, :func:`read_text`, :func:`check_input`) open only regular
files: opened non-blocking and ``fstat``-ed, so a FIFO never hangs and a device (``/dev/zero``, a symlink to
``/dev/null``) or a directory is refused in one line naming it; each kind of file has a size limit
(:data:`SETTINGS_LIMIT`, :data:`MODEL_LIMIT`, :data:`LOG_LIMIT`, :data:`RECORDS_LIMIT`) stated in the message.

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> with atomic_write(d / "a.txt", "w") as fh:
...     _ = fh.write("one")
>>> with atomic_write(d / "a.txt", "w") as fh:  # doctest: +ELLIPSIS
...     _ = fh.write("two")
Traceback (most recent call last):
...
flexdigit.errors.OutputExistsError: .../a.txt: the file exists; pass --force to overwrite it
>>> (d / "a.txt").read_text()
'one'
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import os
import secrets
import stat
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any, BinaryIO

from flexdigit.errors import DataFileError, FlexdigitError, OutputBusyError, OutputError, OutputExistsError, one_line

__all__ = [
    "check_output",
    "atomic_path",
    "atomic_write",
    "output_lock",
    "OutputStream",
    "open_input",
    "check_input",
    "refuse_special",
    "read_bytes",
    "read_text",
    "count_lines",
    "SETTINGS_LIMIT",
    "MODEL_LIMIT",
    "LOG_LIMIT",
    "RECORDS_LIMIT",
    "RECORDS_ROW_LIMIT",
]

#: Largest settings file (a params, protocol, tissue, calibration or study-spec TOML, a rotation map JSON), bytes:
#: the largest packaged one is a few kB; 16 MiB is thousands of times that and still reads in a blink.
SETTINGS_LIMIT = 16 * 2**20
#: Largest saved model (JSON weights of an MLP), bytes: the thesis-sized models are under 1 MB.
MODEL_LIMIT = 256 * 2**20
#: Largest loop log, journal or replay log read whole, bytes: 1 GiB is ~5 million 20 ms samples (a day at 50 Hz).
LOG_LIMIT = 2**30
#: Largest record file (CSV/Parquet/MCAP), bytes.
RECORDS_LIMIT = 4 * 2**30
#: Most data rows of a text record (CSV) read into memory: 1 million rows is 17 minutes at 1 kHz, far more than a
#: release test, a calibration sweep or a tactile dataset holds, and reads in about a second in under 1 GB. A
#: larger file is refused by name after counting its lines in bounded memory (never hangs, never takes GBs).
RECORDS_ROW_LIMIT = 1_000_000

#: A record of this many lines or more is announced on stderr before it is read (~0.5 s and more).
LARGE_RECORD_LINES = 100_000

_KINDS = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFDIR: "a directory",
    stat.S_IFSOCK: "a socket",
}


def _kind(mode: int) -> str:
    return _KINDS.get(stat.S_IFMT(mode), "not a regular file")


def _size(n: int) -> str:
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("kiB", 2**10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n} bytes"


def _stat(path: Path) -> os.stat_result | None:
    """``os.stat`` (through symlinks) or None when nothing (or a dangling symlink) is there."""
    try:
        return os.stat(path)
    except FileNotFoundError:
        return None


def _through(path: Path) -> str:
    """`` (a symlink to TARGET)`` when ``path`` is a symlink, so the message says what it points at."""
    try:
        return f" (a symlink to {os.readlink(path)})" if path.is_symlink() else ""
    except OSError:
        return ""


# ------------------------------------------------------------------------------------------------------ outputs
def check_output(path: str | os.PathLike, *, force: bool = False, hint: str = "") -> Path:
    """Check that ``path`` can be written before the work that produces it starts; return it as a :class:`Path`.

    Refuses, naming the path: a parent directory that does not exist or is not writable, a directory, FIFO,
    device or socket at the path (even with ``force``: flexdigit replaces only regular files), and an existing
    file unless ``force`` (``hint`` adds another way out to that message, e.g. ``"or --append ..."``).
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"{path}: the directory {parent} does not exist")
    st = _stat(path)
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise IsADirectoryError(f"{path}: is a directory, not a file")
        if not stat.S_ISREG(st.st_mode):
            raise OutputError(
                f"{path}: is {_kind(st.st_mode)}{_through(path)}, not a regular file; flexdigit writes only regular "
                "files and never replaces anything else (not even with --force): choose a file name"
            )
        if not force:
            raise OutputExistsError(
                f"{path}: the file exists; pass --force to overwrite it" + (f" {hint}" if hint else "")
            )
    if not os.access(parent, os.W_OK):
        raise PermissionError(f"{path}: the directory {parent} is not writable")
    return path


def _safe(name: str) -> str:
    """``name`` in printable ASCII (for temporary and lock names: writers such as pyarrow take UTF-8 only)."""
    return "".join(c if c.isascii() and c.isprintable() else "_" for c in name)[:96]


def _create(path: Path, like: os.stat_result | None = None) -> int:
    """Create ``path`` exclusively, never through a symlink, with the umask's mode (or ``like``'s)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
    if like is not None:  # replacing a file keeps its mode, as open("w") on it would
        with contextlib.suppress(OSError):
            os.fchmod(fd, stat.S_IMODE(like.st_mode))
    return fd


def _new_temp(path: Path, like: os.stat_result | None, tag: str = "tmp") -> tuple[int, Path]:
    for _ in range(100):
        tmp = path.with_name(f".{_safe(path.name)}.{secrets.token_hex(6)}.{tag}")
        try:
            fd = _create(tmp, like)
        except FileExistsError:  # a name taken (or planted): draw another
            continue
        # held while the file is written: a temporary file nobody holds is a dead writer's (kill -9), which the
        # output's next locked writer removes (_sweep_dead_temps)
        with contextlib.suppress(OSError):
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return fd, tmp
    raise OutputError(f"{path}: cannot create a temporary file beside it (100 names taken)")


def _sweep_dead_temps(path: Path) -> None:
    """Remove the temporary files of ``path`` that no live writer holds (left by a writer killed outright).

    Called by the holder of ``path``'s lock; each candidate is opened without following a symlink and removed only
    if its ``flock`` can be taken (its writer is gone) and the name still points at the file locked."""
    prefix = f".{_safe(path.name)}."
    try:
        names = [n for n in os.listdir(path.parent if str(path.parent) else ".") if n.startswith(prefix)]
    except OSError:
        return
    for name in names:
        if not name.endswith(".tmp") or len(name) != len(prefix) + 12 + len(".tmp"):
            continue
        tmp = path.with_name(name)
        try:
            fd = os.open(tmp, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
        except OSError:
            continue
        try:
            if stat.S_ISREG(os.fstat(fd).st_mode):
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                if _same_file(fd, tmp):
                    os.unlink(tmp)
        except OSError:  # held by a live writer (or gone meanwhile): let it be
            pass
        finally:
            os.close(fd)


def _fsync_dir(directory: Path) -> None:
    """Make a rename in ``directory`` durable (a file system that cannot fsync a directory is let be)."""
    try:
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _same_file(fd: int, path: Path) -> bool:
    try:
        here = os.stat(path, follow_symlinks=False)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (here.st_dev, here.st_ino) == (mine.st_dev, mine.st_ino)


def _write_error(path: Path, exc: BaseException, existed: bool) -> OutputError:
    reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else one_line(exc)
    kept = "the previous file is kept" if existed else "nothing was written"
    err = OutputError(f"{path}: cannot write it: {reason}; {kept}")
    err.errno = getattr(exc, "errno", None)
    return err


def _publish(tmp: Path, path: Path, force: bool) -> None:
    if force:
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)  # fails if the name exists: a file that appeared meanwhile is never clobbered
    except FileExistsError:
        raise OutputExistsError(f"{path}: the file exists; pass --force to overwrite it") from None
    except OSError:  # no hard links here (some network or FAT file systems): check, then rename
        if os.path.lexists(path):
            raise OutputExistsError(f"{path}: the file exists; pass --force to overwrite it") from None
        os.replace(tmp, path)


@contextlib.contextmanager
def _atomic(path: str | os.PathLike, force: bool) -> Iterator[tuple[int, Path]]:
    path = check_output(path, force=force)
    # a one-shot write needs no lock of its own (the rename publishes a whole file; without force a file that
    # appeared meanwhile is kept), so it leaves no lock file behind a kill -9; it is refused while another process
    # holds the output's lock (a run logging to it, a collection writing it)
    _refuse_if_busy(path)
    old = _stat(path)
    fd, tmp = _new_temp(path, old)
    try:
        try:
            yield fd, tmp
            if not _same_file(fd, tmp):
                raise OutputError(f"{path}: its temporary file {tmp.name} was replaced while it was written")
            os.fsync(fd)  # flushes the file, whichever descriptor wrote it
            _publish(tmp, path, force)
            _fsync_dir(path.parent if str(path.parent) else Path("."))
        except FlexdigitError:
            raise
        except OSError as exc:
            raise _write_error(path, exc, old is not None) from exc
    finally:
        os.close(fd)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, force: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; when the block ends cleanly, move it to ``path`` in one step.

    For writers that want a file name (``pyarrow.parquet.write_table``, ``matplotlib``'s ``savefig``). If the block
    raises, the temporary file is removed and ``path`` is untouched; an ``OSError`` (full disk) becomes an
    :class:`~flexdigit.errors.OutputError` naming ``path``. Without ``force`` the final move refuses to replace a
    file that appeared meanwhile (a hard link, which fails if the name exists, where the file system allows it).
    """
    with _atomic(path, force) as (_, tmp):
        yield tmp


@contextlib.contextmanager
def atomic_write(
    path: str | os.PathLike, mode: str = "wb", *, force: bool = False, encoding: str | None = None, **open_kwargs: Any
) -> Iterator[IO]:
    """Open a temporary file for writing; when the block ends cleanly it replaces ``path`` atomically.

    ``mode`` is ``"w"`` (text, UTF-8 unless ``encoding``) or ``"wb"``; see :func:`atomic_path` for the rest.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"The 'mode' parameter of atomic_write must be 'w' or 'wb'. Got {mode!r} instead.")
    if mode == "w" and encoding is None:
        encoding = "utf-8"
    with _atomic(path, force) as (fd, _), open(os.dup(fd), mode, encoding=encoding, **open_kwargs) as fh:
        yield fh
        fh.flush()


# --------------------------------------------------------------------------------------------------- locking
_held: dict[str, list] = {}  # lock name -> [descriptor, depth]: a process may nest locks of one output
_held_guard = threading.Lock()


def _lock_name(path: Path) -> Path:
    name = f".{path.name}.lock"
    if len(os.fsencode(name)) > 200:  # keep within NAME_MAX
        name = f".{hashlib.sha1(os.fsencode(path.name)).hexdigest()}.lock"
    return path.with_name(name)


@contextlib.contextmanager
def output_lock(path: str | os.PathLike) -> Iterator[None]:
    """Hold the advisory lock of output ``path`` for the block; refuse at once if another process holds it.

    The lock is ``flock`` on ``.NAME.lock`` beside ``path``, removed on release (a process killed outright leaves
    it behind, unlocked: the next writer takes it). Nested use in one process is allowed.

    Raises
    ------
    OutputBusyError
        If another process is writing ``path`` (the message names it and that process).
    """
    path = Path(path)
    lock = _lock_name(path)
    key = os.path.abspath(lock)
    with _held_guard:
        if key in _held:
            _held[key][1] += 1
            nested = True
        else:
            nested = False
    if nested:
        try:
            yield
        finally:
            with _held_guard:
                _held[key][1] -= 1
        return
    fd = _take_lock(path, lock)
    with _held_guard:
        _held[key] = [fd, 1]
    _sweep_dead_temps(path)
    try:
        yield
    finally:
        with _held_guard:
            _held[key][1] -= 1
            last = _held[key][1] == 0
            if last:
                del _held[key]
        if last:
            with contextlib.suppress(OSError):
                if _same_file(fd, lock):
                    os.unlink(lock)  # while still holding it: a waiter then sees another inode and retries
            os.close(fd)


def _busy(path: Path, fd: int, exc: OSError) -> OutputError:
    holder = ""
    with contextlib.suppress(OSError, ValueError):
        holder = f" (pid {int(os.pread(fd, 32, 0).decode().strip())})"
    if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
        return OutputBusyError(
            f"{path}: another flexdigit process{holder} is writing it; wait for it to finish or choose another file"
        )
    return OutputError(f"{path}: cannot lock it: {exc.strerror or exc}")


def _refuse_if_busy(path: Path) -> None:
    """Raise :class:`OutputBusyError` if another process holds ``path``'s lock; create nothing."""
    lock = _lock_name(path)
    with _held_guard:
        if os.path.abspath(lock) in _held:  # this process holds it (a collection saving its dataset)
            return
    try:
        fd = os.open(lock, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC)
    except OSError:  # no lock file: nobody holds it
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError as exc:
        raise _busy(path, fd, exc) from None
    finally:
        os.close(fd)


def _take_lock(path: Path, lock: Path) -> int:
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            raise OutputError(f"{path}: cannot create its lock file {lock.name}: {exc.strerror or exc}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            error = _busy(path, fd, exc)
            os.close(fd)
            raise error from None
        if _same_file(fd, lock):  # not removed by its last holder between our open and our lock
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
            return fd
        os.close(fd)


# --------------------------------------------------------------------------------------------------- streams
class OutputStream:
    """A file written progressively (a loop log, an MCAP recording, a journal's output), under the output's lock.

    Parameters
    ----------
    path : path-like
        The destination.
    mode : {"new", "append", "replace"}
        ``"new"``: refuse an existing file, write in place (created exclusively; a killed run keeps what it wrote).
        ``"append"``: add to the existing file (or create it). ``"replace"`` (``--force``): write to a temporary
        file beside the old one, which :meth:`close` renames over it only when the run is complete; until then
        the old file is intact.
    binary : bool
        Bytes (``True``) or UTF-8 text.
    hint : str
        Added to the "the file exists" message.

    Attributes
    ----------
    file : file object
        Where to write.
    written : Path
        Where the data ended up (after :meth:`close`: ``path``, or the ``.partial`` file of a stopped run).
    """

    MODES = ("new", "append", "replace")

    def __init__(self, path: str | os.PathLike, mode: str = "new", *, binary: bool = False, hint: str = "") -> None:
        if mode not in self.MODES:
            raise ValueError(f"The 'mode' parameter of OutputStream must be one of {self.MODES}. Got {mode!r}.")
        self.path, self.mode = Path(path), mode
        self._tmp: Path | None = None
        self._closed = False
        self._lock = output_lock(self.path)
        self._lock.__enter__()
        try:
            fd = self._open(hint)
            try:
                self.file = open(fd, "ab" if binary else "a", **({} if binary else {"encoding": "utf-8"}))  # noqa: SIM115
            except BaseException:
                os.close(fd)
                raise
        except BaseException:
            self._cleanup()
            raise
        self.written = self.path if self._tmp is None else self._tmp

    def _open(self, hint: str) -> int:
        path = self.path
        if self.mode == "append" and os.path.lexists(path):
            try:  # non-blocking: a FIFO with no reader must not hang the open
                fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_NONBLOCK | os.O_CLOEXEC)
            except OSError as exc:
                st = _stat(path)  # a FIFO without a reader, a socket, a directory: named
                if st is not None and not stat.S_ISREG(st.st_mode):
                    check_output(path, force=True)
                raise _write_error(path, exc, True) from exc
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                os.close(fd)
                check_output(path, force=True)  # names what is there
            fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
            return fd
        check_output(path, force=self.mode != "new", hint=hint)
        old = _stat(path)
        if self.mode == "replace" and old is not None:
            fd, self._tmp = _new_temp(path, old, "partial")
            return fd
        try:
            return _create(path)
        except FileExistsError:  # appeared since the check (or a symlink, which is never followed)
            raise OutputExistsError(f"{path}: the file exists; pass --force to overwrite it") from None

    def failed(self, exc: BaseException) -> OutputError:
        """The one-line error for a write to this stream that raised ``exc`` (a full disk): it names the file."""
        if isinstance(exc, FlexdigitError):
            return exc
        return _write_error(self.path, exc, self._tmp is not None)

    def close(self, complete: bool = True) -> Path:
        """Flush, fsync and close; return where the data is.

        ``complete``: the run finished, so a ``"replace"`` stream now replaces the old file. A run that stopped
        before its end (a fault, a signal, Ctrl-C: ``complete=False``) leaves the old file intact and its own
        data in ``STEM.partial.SUFFIX`` beside it (numbered if that exists), which the caller names: a stopped
        run's record is evidence, never thrown away, and never silently mistaken for a finished one.
        """
        if self._closed:
            return self.written
        try:
            try:
                self.file.flush()
                os.fsync(self.file.fileno())
                if self._tmp is not None and not _same_file(self.file.fileno(), self._tmp):
                    raise OutputError(f"{self.path}: its temporary file {self._tmp.name} was replaced meanwhile")
            except FlexdigitError:
                raise
            except OSError as exc:
                raise _write_error(self.path, exc, self._tmp is not None) from exc
            self.file.close()
            if self._tmp is not None:
                target = self.path if complete else self._partial_name()
                os.replace(self._tmp, target)
                self._tmp, self.written = None, target
                _fsync_dir(self.path.parent if str(self.path.parent) else Path("."))
        except BaseException:
            self.abandon()
            raise
        self._closed = True
        self._cleanup()
        return self.written

    def _partial_name(self) -> Path:
        stem, suffix = self.path.stem, self.path.suffix
        for n in range(1, 1000):
            candidate = self.path.with_name(f"{stem}.partial{'' if n == 1 else f'-{n}'}{suffix}")
            if not os.path.lexists(candidate):
                return candidate
        raise OutputError(f"{self.path}: 999 partial files of stopped runs beside it; remove some")

    def abandon(self) -> None:
        """Close after a failed write: a ``"replace"`` stream's temporary file is removed (the old file stays); a
        new or appended file keeps the lines that reached it."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(OSError):
            self.file.close()
        self._cleanup()

    def _cleanup(self) -> None:
        if self._tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self._tmp)
            self._tmp = None
        if self._lock is not None:
            lock, self._lock = self._lock, None
            lock.__exit__(None, None, None)

    @property
    def closed(self) -> bool:
        return self._closed


# ---------------------------------------------------------------------------------------------------- inputs
def open_input(path: str | os.PathLike, what: str = "a file", limit: int = SETTINGS_LIMIT) -> BinaryIO:
    """Open ``path`` for reading if it is a regular file of at most ``limit`` bytes; a binary file object.

    Opened non-blocking and ``fstat``-ed before anything is read, so a FIFO never hangs; a FIFO, device
    (``/dev/zero``, a symlink to ``/dev/null``), socket or directory is refused naming it, as is a file over
    ``limit`` (stated). A missing file raises :class:`FileNotFoundError` (the CLI says "no such file: ...").

    Raises
    ------
    DataFileError
        Naming the file, what it is and ``what`` was expected.
    """
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC | getattr(os, "O_NOCTTY", 0))
    except FileNotFoundError:
        raise FileNotFoundError(errno.ENOENT, "No such file", str(path)) from None
    except OSError as exc:
        if exc.errno == errno.ENXIO:  # a socket
            raise DataFileError(f"{path}: is a socket{_through(path)}, not a regular file; expected {what}") from None
        raise
    try:
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            raise DataFileError(f"{path}: is a directory{_through(path)}, not {what}")
        if not stat.S_ISREG(st.st_mode):
            raise DataFileError(f"{path}: is {_kind(st.st_mode)}{_through(path)}, not a regular file; expected {what}")
        if st.st_size > limit:
            raise DataFileError(
                f"{path}: {_size(st.st_size)}, more than the {_size(limit)} flexdigit reads as {what}; "
                "is it the right file?"
            )
        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
        return open(fd, "rb")  # noqa: SIM115 - the caller closes it
    except BaseException:
        os.close(fd)
        raise


def refuse_special(path: str | os.PathLike, what: str = "a file") -> None:
    """Refuse ``path`` naming what it is when it exists and is neither a regular file nor a directory (a FIFO, a
    device, a socket, also through a symlink); for loaders that test ``is_file()`` first, whose "no such file"
    would otherwise misname it. Never opens it."""
    path = Path(path)
    st = _stat(path)
    if st is not None and not stat.S_ISREG(st.st_mode) and not stat.S_ISDIR(st.st_mode):
        raise DataFileError(f"{path}: is {_kind(st.st_mode)}{_through(path)}, not a regular file; expected {what}")


def check_input(path: str | os.PathLike, what: str = "a file", limit: int = RECORDS_LIMIT) -> Path:
    """:func:`open_input`'s checks for a reader that takes a file name (pyarrow, mcap); returns ``path``."""
    open_input(path, what, limit).close()
    return Path(path)


def read_bytes(path: str | os.PathLike, what: str = "a file", limit: int = SETTINGS_LIMIT) -> bytes:
    """The bytes of ``path``, with :func:`open_input`'s checks (a file that grows past ``limit`` meanwhile too)."""
    with open_input(path, what, limit) as fh:
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise DataFileError(f"{path}: more than the {_size(limit)} flexdigit reads as {what}; is it the right file?")
    return data


def count_lines(
    path: str | os.PathLike, what: str, most: int = RECORDS_ROW_LIMIT, *, limit: int = RECORDS_LIMIT
) -> int:
    """Count the lines of ``path`` in bounded memory (1 MiB at a time); refuse it, naming it, past ``most``.

    Lets a reader that holds a table in memory refuse a 10-million-row file in about a second, not after it
    has taken gigabytes.
    """
    lines = 0
    with open_input(path, what, limit) as fh:
        while chunk := fh.read(2**20):
            lines += chunk.count(b"\n")
            if lines > most + 100:  # a header and comment lines are not rows: leave them some room
                raise DataFileError(
                    f"{path}: more than {most:,} lines; flexdigit reads {what} of at most {most:,} rows (17 minutes "
                    "at 1 kHz): cut the part you want into a file of its own"
                )
    if lines >= LARGE_RECORD_LINES:  # reading it takes seconds: say so, on stderr (stdout may be --json)
        print(f"flexdigit: reading {path}: {lines:,} lines", file=sys.stderr, flush=True)
    return lines


def read_text(
    path: str | os.PathLike, what: str = "a text file", limit: int = SETTINGS_LIMIT, *, encoding: str = "utf-8-sig"
) -> str:
    """The text of ``path`` (UTF-8; a byte-order mark, as some Windows editors save one, is skipped), or a
    :class:`~flexdigit.errors.DataFileError` naming the file when it is not a regular file, larger than ``limit``
    bytes, binary or not UTF-8 (Python's own message names neither the file nor what was expected).

    ``what`` says what the file should be (``"a rig parameter TOML"``). A missing file raises
    :class:`FileNotFoundError` (the CLI says "no such file: ...").

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "rig.toml"
    >>> _ = p.write_bytes(b"\\x89PNG\\r\\n")
    >>> read_text(p, "a rig parameter TOML")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    flexdigit.errors.DataFileError: .../rig.toml: not a rig parameter TOML: binary or not UTF-8 (byte 0x89 at offset 0)
    >>> read_text("/dev/zero", "a rig parameter TOML")
    Traceback (most recent call last):
    ...
    flexdigit.errors.DataFileError: /dev/zero: is a character device, not a regular file; expected a rig parameter TOML
    """
    path = Path(path)
    data = read_bytes(path, what, limit)
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as exc:
        raise DataFileError(
            f"{path}: not {what}: binary or not UTF-8 (byte 0x{data[exc.start]:02x} at offset {exc.start})"
        ) from None
    if "\x00" in text:
        raise DataFileError(f"{path}: not {what}: binary (a NUL byte at offset {text.index(chr(0))})")
    return text

"""Output files that are never half-written and never clobber: the one way flexdigit writes a file.

Every output goes to a temporary file beside its destination and is renamed into place only once it is complete
and flushed to disk, so a crash, Ctrl-C or a full disk leaves the destination as it was (absent, or the old file
intact). An existing destination is refused unless ``force=True`` (the ``--force`` flag), and :func:`check_output`
lets a command refuse a bad destination (missing directory, existing file, a directory in the way) *before* any
work starts, not after.

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
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from flexdigit.errors import DataFileError, OutputExistsError

__all__ = ["check_output", "atomic_path", "atomic_write", "read_text"]


def check_output(path: str | os.PathLike, *, force: bool = False, hint: str = "") -> Path:
    """Check that ``path`` can be written before the work that produces it starts; return it as a :class:`Path`.

    Refuses, naming the path: a parent directory that does not exist or is not writable, a directory at the path,
    and an existing file unless ``force`` (``hint`` adds another way out to that message, e.g. ``"or --append
    ..."``).
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"{path}: the directory {parent} does not exist")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory, not a file")
    if path.exists() and not force:
        raise OutputExistsError(f"{path}: the file exists; pass --force to overwrite it" + (f" {hint}" if hint else ""))
    if not os.access(parent, os.W_OK):
        raise PermissionError(f"{path}: the directory {parent} is not writable")
    return path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, force: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; when the block ends cleanly, move it to ``path`` in one step.

    For writers that want a file name (``pyarrow.parquet.write_table``, ``matplotlib``'s ``savefig``). If the block
    raises, the temporary file is removed and ``path`` is untouched. Without ``force`` the final move refuses to
    replace a file that appeared meanwhile (a hard link, which fails if the name exists, where the file system
    allows it).
    """
    path = check_output(path, force=force)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        _fsync(tmp)
        if force:
            os.replace(tmp, path)
        else:
            _publish_no_clobber(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


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
    with atomic_path(path, force=force) as tmp, tmp.open(mode, encoding=encoding, **open_kwargs) as fh:
        yield fh
        fh.flush()


def _fsync(path: Path) -> None:
    with path.open("rb") as fh:
        os.fsync(fh.fileno())


def _publish_no_clobber(tmp: Path, path: Path) -> None:
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise OutputExistsError(f"{path}: the file exists; pass --force to overwrite it") from None
    except OSError:  # no hard links here (some network or FAT file systems): check, then rename
        if path.exists():
            raise OutputExistsError(f"{path}: the file exists; pass --force to overwrite it") from None
        os.replace(tmp, path)


def read_text(path: str | os.PathLike, what: str = "a text file") -> str:
    """The text of ``path`` (UTF-8), or a :class:`~flexdigit.errors.DataFileError` naming the file when it is
    binary or not UTF-8 (Python's own message names neither the file nor what was expected).

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
    """
    path = Path(path)
    if path.is_dir():
        raise DataFileError(f"{path}: is a directory, not {what}")
    data = path.read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataFileError(
            f"{path}: not {what}: binary or not UTF-8 (byte 0x{data[exc.start]:02x} at offset {exc.start})"
        ) from None
    if "\x00" in text:
        raise DataFileError(f"{path}: not {what}: binary (a NUL byte at offset {text.index(chr(0))})")
    return text

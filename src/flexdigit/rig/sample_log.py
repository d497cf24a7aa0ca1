"""The loop's log: one run a JSON-lines file, header, samples and footer, and the reader that checks it (thesis 5.2).

Every sample the loop takes (:func:`flexdigit.rig.loop.run_loop`) is appended as one line and flushed to the OS
at once, so a crash or Ctrl-C loses nothing already written; ``fsync`` policy: the file is fsync'ed every
``fsync_every`` lines (default 50, i.e. one second at 20 ms) and at close, so a power cut loses at most that many
lines. The first line is a header (``format`` :data:`LOG_FORMAT`, the period, backend and controller); the last
line, when the loop ends normally or by a fault, a footer with the stop reason. ``--append`` adds runs after it,
each with its own header. :func:`read_log` reads one run back, refusing a line that is not what the loop writes with
the file, line and field named; the ``replay`` backend and the recordings (:mod:`flexdigit.rig.recording`) read
through it.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from flexdigit._io import check_output
from flexdigit._validation import check_int
from flexdigit.errors import DataFileError, OutputExistsError, RigError

__all__ = [
    "LOG_FORMAT",
    "APPEND_KEYS",
    "LOG_MODES",
    "SampleLog",
    "check_appendable",
    "read_log",
    "read_log_runs",
    "check_sample",
]

LOG_FORMAT = "flexdigit-loop-log/1"
#: Header keys that must agree for a run to be appended to an existing log (``--append``).
APPEND_KEYS = ("controller", "period_s", "rig_settings")
#: How :class:`SampleLog` treats an existing file: refuse it, add a run to it, or replace it (``--force``).
LOG_MODES = ("new", "append", "replace")


class SampleLog:
    """Append-only JSON-lines log of a run, flushed every line (survives a crash or Ctrl-C).

    Parameters
    ----------
    path : path-like
        The log file.
    header : dict
        Written as the run's first line, with ``format``.
    fsync_every : int
        fsync after this many lines (and at close); 0 never fsyncs (the OS still gets every line at once).
    mode : {"new", "append", "replace"}
        What to do with an existing file: ``"new"`` refuses it (:class:`~flexdigit.errors.OutputExistsError`);
        ``"append"`` adds this run after the runs already in it, once it has checked the file is a loop log whose
        first run has the same :data:`APPEND_KEYS` (a torn last line, a crash mid-write, is dropped first);
        ``"replace"`` starts the file afresh (``--force``).
    """

    def __init__(
        self, path: str | os.PathLike, header: dict[str, Any], fsync_every: int = 50, *, mode: str = "new"
    ) -> None:
        from flexdigit._validation import check_choice

        self.path = Path(path)
        self.fsync_every = check_int(fsync_every, "fsync_every", "SampleLog", low=0)
        mode = check_choice(mode, "mode", LOG_MODES, "SampleLog")
        record = {"format": LOG_FORMAT, **header}
        if mode == "append" and self.path.exists():
            check_appendable(self.path, record)
        else:
            check_output(self.path, force=mode == "replace", hint="or --append to add this run to it")
        try:
            if mode == "replace":
                self.path.unlink(missing_ok=True)
            self._file = open(self.path, "a" if mode == "append" else "x", encoding="utf-8")  # noqa: SIM115
        except FileExistsError:  # appeared since the check
            raise OutputExistsError(f"{self.path}: the file exists; pass --force to overwrite it") from None
        except OSError as exc:
            raise RigError(f"cannot open the loop log {self.path}: {exc.strerror or exc}") from exc
        self._since_sync = 0
        self.lines = 0
        self.write(record)

    def write(self, record: dict[str, Any]) -> None:
        self._file.write(json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n")
        self._file.flush()
        self.lines += 1
        self._since_sync += 1
        if self.fsync_every and self._since_sync >= self.fsync_every:
            os.fsync(self._file.fileno())
            self._since_sync = 0

    def close(self) -> None:
        if self._file.closed:
            return
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()

    def abandon(self) -> None:
        """Close without flushing what the OS refused (a full disk): the file keeps the lines already written."""
        try:
            self._file.close()
        except OSError:
            pass


def check_appendable(path: str | os.PathLike, header: dict[str, Any]) -> None:
    """Refuse to append a run with ``header`` to ``path`` unless it is a loop log whose first run agrees on
    :data:`APPEND_KEYS`; drop a torn last line (a crash mid-write) so the new run starts on a line of its own.

    Raises :class:`~flexdigit.errors.DataFileError` naming the file and the first setting that differs.
    """
    path = Path(path)
    with path.open("rb") as fh:
        first = fh.readline()
    try:
        old = json.loads(first.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        old = None
    if not isinstance(old, dict) or old.get("format") != LOG_FORMAT:
        raise DataFileError(
            f"{path}: not a flexdigit loop log ({LOG_FORMAT}); --append only adds a run to a log of the same "
            "format: choose another --log file"
        )
    new = json.loads(json.dumps(header, allow_nan=False))  # compare as they would read back
    for key in APPEND_KEYS:
        if old.get(key) != new.get(key):
            raise DataFileError(
                f"{path}: --append: the log's runs have {key}={old.get(key)!r}, this run {key}={new.get(key)!r}; "
                "log this run to another file"
            )
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with path.open("r+b") as fh:
            fh.truncate(data.rfind(b"\n") + 1)


def read_log(
    path: str | os.PathLike, run: int | None = None
) -> tuple[dict[str, Any], list[dict[str, Any]], dict[str, Any] | None]:
    """Read one run of a loop log: ``(header, samples, footer or None)``; a torn last line (power cut) is ignored.

    A log holds one run, or several added with ``--append`` (each starts with its own header line): ``run``
    (1-based) chooses one; without it a log of several runs is refused naming the lines they start on.

    Raises :class:`~flexdigit.errors.DataFileError` naming the file and line when it is not a loop log.
    """
    path = Path(path)
    runs = read_log_runs(path)
    if run is None:
        if len(runs) > 1:
            starts = ", ".join(str(start) for start, *_ in runs)
            raise DataFileError(
                f"{path}: holds {len(runs)} runs (appended; starting on lines {starts}); line {runs[1][0]} starts a "
                "second run: choose one with read_log(path, run=N) or replay://FILE?run=N"
            )
        run = 1
    from flexdigit._validation import check_int

    index = check_int(run, "run", "read_log", low=1, high=len(runs), error=DataFileError)
    _, header, samples, footer = runs[index - 1]
    return header, samples, footer


def read_log_runs(path: str | os.PathLike) -> list[tuple[int, dict[str, Any], list[dict[str, Any]], dict | None]]:
    """Every run of a loop log as ``(first line number, header, samples, footer or None)``."""
    from flexdigit._io import read_text

    path = Path(path)
    runs: list[tuple[int, dict[str, Any], list[dict[str, Any]], dict | None]] = []
    lines = read_text(path, "a flexdigit loop log").splitlines()
    for number, line in enumerate(lines, 1):
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            if number == len(lines):
                break  # a line cut by a crash mid-write
            raise DataFileError(f"{path}: line {number} is not JSON") from None
        if not isinstance(record, dict):
            raise DataFileError(f"{path}: line {number} is not a JSON object")
        if number == 1 or "format" in record:
            if record.get("format") != LOG_FORMAT:
                raise DataFileError(f"{path}: line {number} is not a flexdigit loop log header (format {LOG_FORMAT})")
            runs.append((number, record, [], None))
        elif runs[-1][3] is not None:
            raise DataFileError(f"{path}: line {number} follows the run's last line (its footer)")
        elif "stop" in record:
            start, header, samples, _ = runs[-1]
            runs[-1] = (start, header, samples, record)
        else:
            runs[-1][2].append(check_sample(record, path, f"line {number}"))
    if not runs:
        raise DataFileError(f"{path}: empty file, expected a flexdigit loop log")
    return runs


def _is_finite(x: int | float) -> bool:
    try:
        return math.isfinite(x)
    except OverflowError:  # an integer of 400 digits: JSON allows it, a float cannot hold it
        return False


def check_sample(record: dict[str, Any], path: Path, where: str) -> dict[str, Any]:
    """A sample as the loop writes it (a log line, a recording's message), or a DataFileError naming the file,
    ``where`` in it (``"line 7"``) and the field."""

    def bad(field: str, expected: str) -> DataFileError:
        got = repr(record.get(field))
        got = got if len(got) <= 60 else got[:57] + "..."
        return DataFileError(f"{path}: {where}: field '{field}' must be {expected}. Got {got}")

    for key in ("t", "setpoint", "y", "pot_v"):
        value = record.get(key)
        if key == "t" and value is None:
            raise bad(key, "a number (the sample's time, s)")
        if value is not None and (isinstance(value, bool) or not isinstance(value, int | float)):
            raise bad(key, "a number or null")
        if value is not None and not _is_finite(value):  # JSON reads NaN, Infinity and 1e999; the loop writes null
            raise bad(key, "a finite number")
    gauges = record.get("gauges_v")
    if not isinstance(gauges, list) or len(gauges) != 3:
        raise bad("gauges_v", "a list of 3 voltages")
    if any(g is not None and (isinstance(g, bool) or not isinstance(g, int | float)) for g in gauges):
        raise bad("gauges_v", "a list of 3 numbers (null for a non-finite reading)")
    if any(g is not None and not _is_finite(g) for g in gauges):
        raise bad("gauges_v", "a list of 3 finite numbers (null for a non-finite reading)")
    command = record.get("command")
    if isinstance(command, bool) or not isinstance(command, int) or not 0 <= command <= 254:
        raise bad("command", "an integer 0..254")
    return record

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

import numpy as np

from flexdigit._io import LOG_LIMIT, OutputStream, check_output, open_input
from flexdigit._validation import check_choice, check_int
from flexdigit.errors import DataFileError
from flexdigit.interrupts import signals_deferred

__all__ = [
    "LOG_FORMAT",
    "APPEND_KEYS",
    "LOG_MODES",
    "SampleLog",
    "check_appendable",
    "read_log",
    "read_log_runs",
    "read_log_columns",
    "SampleColumns",
    "SampleView",
    "check_sample",
    "MAX_LOG_LINE_BYTES",
    "board_log_header",
    "board_log_sample",
]

LOG_FORMAT = "flexdigit-loop-log/1"
#: Header keys that must agree for a run to be appended to an existing log (``--append``).
APPEND_KEYS = ("controller", "period_s", "rig_settings")
#: The longest line of a loop log read, bytes: a sample is under 300, a header with the rig's settings a few kB.
#: Logs are read a line at a time (never whole), so a longer line, a file with a hole of NUL bytes or no line
#: breaks at all, is refused naming it after reading at most this much.
MAX_LOG_LINE_BYTES = 1 << 20
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
        self.path = Path(path)
        #: The log asked for (``path`` becomes ``STEM.partial.jsonl`` when a ``--force`` run stops early) and the mode.
        self.target = self.path
        self.fsync_every = check_int(fsync_every, "fsync_every", "SampleLog", low=0)
        mode = check_choice(mode, "mode", LOG_MODES, "SampleLog")
        self.mode = mode
        record = {"format": LOG_FORMAT, **header}
        if mode != "append" or not self.path.exists():
            check_output(self.path, force=mode == "replace", hint="or --append to add this run to it")
        # under the log's lock (a second run writing it is refused, never mixed); "replace" writes beside the old
        # log, which close(complete=True) replaces (flexdigit._io.OutputStream)
        self._out = OutputStream(self.path, mode, hint="or --append to add this run to it")
        try:
            if mode == "append" and self.path.stat().st_size:
                check_appendable(self.path, record)
        except BaseException:
            self._out.abandon()
            raise
        self._file = self._out.file
        self._since_sync = 0
        self.lines = 0
        self.write(record)

    def write(self, record: dict[str, Any]) -> None:
        line = json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n"
        with signals_deferred():  # a stop signal waits for the line's end: never a torn line
            try:
                self._write(line)
            except OSError as exc:  # a full disk: say which file
                raise self._out.failed(exc) from exc

    def _write(self, line: str) -> None:
        self._file.write(line)
        self._file.flush()
        self.lines += 1
        self._since_sync += 1
        if self.fsync_every and self._since_sync >= self.fsync_every:
            os.fsync(self._file.fileno())
            self._since_sync = 0

    def close(self, complete: bool = True) -> Path:
        """Flush, fsync and close; return where the log is: its path, or (a ``--force`` run that stopped before
        its end, ``complete=False``) ``STEM.partial.jsonl`` beside the old log, which is kept intact."""
        self.path = self._out.close(complete)
        return self.path

    def abandon(self) -> None:
        """Close after a failed write (a full disk): a new or appended log keeps the lines already written; a
        ``--force`` log's new file is removed and the old one kept."""
        self._out.abandon()


def check_appendable(path: str | os.PathLike, header: dict[str, Any]) -> None:
    """Refuse to append a run with ``header`` to ``path`` unless it is a loop log whose first run agrees on
    :data:`APPEND_KEYS`; drop a torn last line (a crash mid-write) so the new run starts on a line of its own.

    Raises :class:`~flexdigit.errors.DataFileError` naming the file and the first setting that differs.
    """
    path = Path(path)
    with open_input(path, "a flexdigit loop log", LOG_LIMIT) as fh:
        first = fh.readline()
    try:
        old = json.loads(first.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):
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
    kept: list[dict[str, Any]] = []
    header, footer = _read_one_run(Path(path), run, kept.append)
    return header, kept, footer


def read_log_columns(
    path: str | os.PathLike, run: int | None = None
) -> tuple[dict[str, Any], dict[str, np.ndarray], dict[str, Any] | None]:
    """:func:`read_log` into columns (:class:`SampleColumns`): ``(header, columns, footer or None)``.

    Streamed: a line at a time into arrays of 64 bytes a sample, where a list of sample dicts takes ten times
    that; what a replay of a long log holds (:class:`~flexdigit.rig.backends.replay_backend.ReplayRig`)."""
    columns = SampleColumns(path)
    header, footer = _read_one_run(Path(path), run, columns.append)
    return header, columns.arrays(), footer


def _read_one_run(path: Path, run: int | None, keep) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """Scan the log once, handing run ``run``'s samples (checked) to ``keep``; its header and footer."""
    want = 1 if run is None else run
    runs = _scan_log(path, lambda index, sample: keep(sample) if index == want else None)
    if run is None and len(runs) > 1:
        starts = ", ".join(str(start) for start, *_ in runs)
        raise DataFileError(
            f"{path}: holds {len(runs)} runs (appended; starting on lines {starts}); line {runs[1][0]} starts a "
            "second run: choose one with read_log(path, run=N) or replay://FILE?run=N"
        )
    index = check_int(want, "run", "read_log", low=1, high=len(runs), error=DataFileError)
    _, header, footer = runs[index - 1]
    return header, footer


def read_log_runs(path: str | os.PathLike) -> list[tuple[int, dict[str, Any], list[dict[str, Any]], dict | None]]:
    """Every run of a loop log as ``(first line number, header, samples, footer or None)``.

    Streamed: read a line at a time (at most :data:`MAX_LOG_LINE_BYTES` each), never the whole file."""
    samples: dict[int, list[dict[str, Any]]] = {}
    runs = _scan_log(Path(path), lambda index, sample: samples.setdefault(index, []).append(sample))
    return [(start, header, samples.get(i, []), footer) for i, (start, header, footer) in enumerate(runs, 1)]


def _scan_log(path: Path, on_sample) -> list[tuple[int, dict[str, Any], dict[str, Any] | None]]:
    """Read a loop log a line at a time: ``(first line, header, footer or None)`` for each run; every sample,
    checked, goes to ``on_sample(run index from 1, sample)`` as it is read (the caller keeps what it needs)."""
    runs: list[list] = []
    with open_input(path, "a flexdigit loop log", LOG_LIMIT) as fh:  # a regular file (a FIFO would hang)
        for number, raw, last in _log_lines(path, fh):
            record = _log_record(path, number, raw, last)
            if record is None:
                break  # a line cut by a crash mid-write
            if number == 1 or "format" in record:
                if record.get("format") != LOG_FORMAT:
                    raise DataFileError(
                        f"{path}: line {number} is not a flexdigit loop log header (format {LOG_FORMAT})"
                    )
                runs.append([number, record, None])
            elif runs[-1][2] is not None:
                raise DataFileError(f"{path}: line {number} follows the run's last line (its footer)")
            elif "stop" in record:
                runs[-1][2] = record
            else:
                on_sample(len(runs), check_sample(record, path, f"line {number}"))
    if not runs:
        raise DataFileError(f"{path}: empty file, expected a flexdigit loop log")
    return [tuple(r) for r in runs]


class SampleColumns:
    """Checked samples (:func:`check_sample`) kept as typed arrays, 64 bytes a sample, not as dicts (about 600).

    :meth:`append` takes a sample dict; :meth:`arrays` gives ``t``, ``gauges_v`` (n x G: the digit's gauges, the
    thesis rig's 3), ``pot_v``, ``setpoint``, ``y`` (float, NaN for null) and ``command`` (int); :class:`SampleView`
    reads them back as dicts, one at a time. Every sample of a run has its first sample's gauge count; another is
    refused naming ``source`` (the file)."""

    _FLOATS = ("t", "pot_v", "setpoint", "y")

    def __init__(self, source: object = "samples") -> None:
        from array import array

        self._array = array
        self._source = source
        self._floats = {name: array("d") for name in self._FLOATS}
        self._gauges: list = []  # one array per gauge, made at the first sample
        self._command = array("h")

    def append(self, sample: dict[str, Any]) -> None:
        f = self._floats
        gauges = sample["gauges_v"]
        if not len(self):
            self._gauges = [self._array("d") for _ in gauges]
        elif len(gauges) != len(self._gauges):
            raise DataFileError(
                f"{self._source}: sample {len(self)}: field 'gauges_v' has {len(gauges)} voltages but the run's first "
                f"sample has {len(self._gauges)} (one per gauge of one digit)"
            )
        f["t"].append(float(sample["t"]))
        for column, g in zip(self._gauges, gauges, strict=True):
            column.append(math.nan if g is None else float(g))
        for name in ("pot_v", "setpoint", "y"):
            value = sample.get(name)
            f[name].append(math.nan if value is None else float(value))
        self._command.append(int(sample["command"]))

    def __len__(self) -> int:
        return len(self._command)

    def arrays(self) -> dict[str, np.ndarray]:
        f = {name: np.frombuffer(a, dtype=float) if len(a) else np.zeros(0) for name, a in self._floats.items()}
        return {
            "t": f["t"],
            "gauges_v": (
                np.column_stack([np.frombuffer(g, dtype=float) for g in self._gauges])
                if len(self)
                else np.zeros((0, 3))
            ),
            "pot_v": f["pot_v"],
            "setpoint": f["setpoint"],
            "y": f["y"],
            "command": np.frombuffer(self._command, dtype=np.int16).astype(int) if len(self) else np.zeros(0, int),
        }


class SampleView:
    """Columns (:meth:`SampleColumns.arrays`) read as a sequence of sample dicts, each made when asked for (null
    for NaN, as the log has it)."""

    def __init__(self, columns: dict[str, np.ndarray]) -> None:
        self._c = columns

    def __len__(self) -> int:
        return len(self._c["t"])

    def __getitem__(self, i: int) -> dict[str, Any]:
        if not -len(self) <= i < len(self):
            raise IndexError(i)
        c = self._c

        def value(x: float) -> float | None:
            return None if math.isnan(x) else float(x)

        return {
            "t": float(c["t"][i]),
            "gauges_v": [value(g) for g in c["gauges_v"][i]],
            "pot_v": value(c["pot_v"][i]),
            "command": int(c["command"][i]),
            "setpoint": value(c["setpoint"][i]),
            "y": value(c["y"][i]),
        }

    def __iter__(self):
        return (self[i] for i in range(len(self)))


def _log_lines(path: Path, fh):
    """``(line number, bytes, is the last line)`` for each line of ``fh``, one line read ahead."""
    number, line = 0, fh.readline(MAX_LOG_LINE_BYTES + 1)
    while line:
        number += 1
        if len(line) > MAX_LOG_LINE_BYTES:
            raise DataFileError(
                f"{path}: line {number} is longer than {MAX_LOG_LINE_BYTES:,} bytes; a loop log's lines are samples "
                "of a few hundred (is it a loop log? a file with a hole of NUL bytes?)"
            )
        following = fh.readline(MAX_LOG_LINE_BYTES + 1)
        yield number, line, not following
        line = following


def _log_record(path: Path, number: int, raw: bytes, last: bool) -> dict[str, Any] | None:
    """One log line as a JSON object; None for a torn last line; a DataFileError naming the line otherwise."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DataFileError(
            f"{path}: not a flexdigit loop log: binary or not UTF-8 (byte 0x{raw[exc.start]:02x} on line {number})"
        ) from None
    if "\x00" in text:
        raise DataFileError(f"{path}: not a flexdigit loop log: binary (a NUL byte on line {number})")
    try:
        record = json.loads(text)
    except json.JSONDecodeError:
        if last:
            return None
        raise DataFileError(f"{path}: line {number} is not JSON") from None
    except RecursionError:  # brackets nested past the parser's depth: no loop log line is
        raise DataFileError(f"{path}: line {number} is not a loop log line (JSON nested too deep)") from None
    if not isinstance(record, dict):
        raise DataFileError(f"{path}: line {number} is not a JSON object")
    return record


def _is_finite(x: int | float) -> bool:
    try:
        return math.isfinite(x)
    except OverflowError:  # an integer of 400 digits: JSON allows it, a float cannot hold it
        return False


#: Most gauges a sample carries (a digit has 1 to 8).
MAX_GAUGES = 8


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
    if not isinstance(gauges, list) or not 1 <= len(gauges) <= MAX_GAUGES:
        raise bad("gauges_v", f"a list of 1 to {MAX_GAUGES} voltages (one per gauge; the thesis rig's 3)")
    if any(g is not None and (isinstance(g, bool) or not isinstance(g, int | float)) for g in gauges):
        raise bad("gauges_v", "a list of numbers (null for a non-finite reading)")
    if any(g is not None and not _is_finite(g) for g in gauges):
        raise bad("gauges_v", "a list of finite numbers (null for a non-finite reading)")
    command = record.get("command")
    if isinstance(command, bool) or not isinstance(command, int) or not 0 <= command <= 254:
        raise bad("command", "an integer 0..254")
    return record


def board_log_header(backend: str, settings: dict, period_s: float, board, setpoint_deg: float, duration_s: float):
    """The header of a run whose loop closed on the board (``flexdigit run --on-board --log``): ``loop`` "board",
    the backend, the image's period and number format (its banner's ``fixed``: ``"fixed"`` or ``"float"``)."""
    fixed = board.banner_value("fixed")
    return {
        "loop": "board",
        "controller": "board",  # the controller exported into the image (APPEND_KEYS)
        "backend": backend,
        "period_s": period_s,
        "duration_s": duration_s,
        "setpoint_deg": setpoint_deg,
        "image_format": None if fixed is None else ("fixed" if fixed == "1" else "float"),
        "rig_settings": settings,
        "estimate": "the board's own: its map's rotation of the streamed gauges minus its tare, as its line carries "
        "it (null from an image that streams none)",
    }


def board_log_sample(
    t: float, setpoint_deg: float, reading, true_deg: float, command: float, estimate_deg: float = math.nan
) -> dict[str, Any]:
    """One watched board period as a loop log's sample: ``y`` the board's streamed rotation estimate (deg; null
    from an image that streams none); ``command`` the board's servo pulse as the nearest serial command (0..254,
    what the log's readers take) and ``board_command`` the pulse itself in commands (Timer1 resolves finer)."""

    def finite(x: float) -> float | None:
        return float(x) if math.isfinite(x) else None

    pulse = finite(float(command))
    return {
        "t": round(float(t), 9),
        "setpoint": float(setpoint_deg),
        "gauges_v": [finite(float(g)) for g in reading.gauges_v],
        "pot_v": finite(float(reading.pot_v)),
        "y": finite(float(estimate_deg)),
        "command": None if pulse is None else min(max(int(round(pulse)), 0), 254),
        "board_command": pulse,
        "true_rotation_deg": finite(float(true_deg)),
    }

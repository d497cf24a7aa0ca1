"""Time series for identification: from a DAQ recording (CSV or Parquet), from the twin, or from arrays.

A recording is a table with a time column and one or more channels, one row per sample. Units are in the
column names, ``<name>_<unit>`` (``time_s``, ``time_ms``, ``t_us``, ``sg1_v``, ``pot_mv``, ``command``) or
``<name> (<unit>)`` / ``<name>[<unit>]`` (``Time (ms)``, ``Pot (V)``, ``t[s]``). A time column with no unit
(``time``, ``t``) needs ``time_unit=`` (``--time-unit`` on the command line); a time unit given for a column that
names another one is refused. A channel is picked by its full column name or its name without the unit (``sg1``
for ``sg1_v``), in any case when that names one column (``sg1`` for ``SG1 (V)``); without one, the first
channel that is not an input (``command``, ``u``) or an unnamed index column (pandas' ``to_csv``) is used. CSV
files may be separated by ``,`` ``;`` tabs or spaces (found from the header and the first rows), with ``#``
comment lines; with a separator other than ``,`` a decimal comma (``0,25``) is read as a decimal point.
Strain-gauge channels answer to either name, ``sgN`` (a DAQ recording, the thesis) or ``gaugeN`` (the twin's
files), when the file has only one of them. An input column, when present, is kept with the series (the servo
command of a step test).
:func:`series_from_table` does the same for a table in memory, such as the twin's experiments
(:mod:`flexdigit.twin.records`).

Every problem with a file raises :class:`~flexdigit.errors.DataFileError` naming the file, the column and the
line (CSV, counting the header as line 1) or row (Parquet) and what was expected: a missing column, a cell that
is not a number, time that does not increase, a run of missing values, irregular sampling, too few samples.

Examples
--------
>>> ts = TimeSeries.from_arrays(np.arange(0, 1, 0.01), np.zeros(100), channel="sg1", unit="V")
>>> ts.n_samples, round(ts.sample_rate_hz, 6)
(100, 100.0)
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexdigit import _io
from flexdigit._io import RECORDS_LIMIT, atomic_write, check_input, count_lines, read_bytes, refuse_special
from flexdigit._repr import summary
from flexdigit._validation import Plausible, check_array
from flexdigit.errors import DataFileError, one_line

__all__ = [
    "SAMPLE_INTERVAL_S",
    "MIN_SAMPLES",
    "TIME_UNITS",
    "TIME_NAMES",
    "CHANNEL_UNITS",
    "INPUT_NAMES",
    "SAMPLING_TOLERANCE",
    "TimeSeries",
    "split_unit",
    "read_timeseries",
    "series_from_table",
    "write_csv",
]

#: The sample interval of a record to identify: the digit rings at ~2 Hz (13 rad/s, table 3.2) and the servo at
#: ~3 Hz, so a record sampled slower than 10 Hz cannot show them; the thesis logged at 1 kHz. A record in ms read as
#: s has a 1 "s" interval, and is named as such.
SAMPLE_INTERVAL_S = Plausible("s", 1e-7, 0.1, "a record of the digit: 10 samples a second or more (the thesis: 1 kHz)")

#: Fewest samples an identification record may have.
MIN_SAMPLES = 20
#: Time units accepted in a column name suffix or ``time_unit``, in seconds.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
#: Other spellings of the time units in a column name (``Time (sec)``, ``t [µs]``).
_TIME_ALIASES = {"sec": "s", "msec": "ms", "µs": "us", "μs": "us", "usec": "us"}
#: Names of a time column (without its unit), case-insensitive.
TIME_NAMES = ("time", "t", "timestamp")
#: Column names of a row index rather than a measurement (pandas ``to_csv`` writes an unnamed one).
_INDEX_NAMES = ("", "index", "unnamed: 0", "sample", "row")
#: Separators tried on a CSV header and its first rows, in this order; then runs of spaces.
_DELIMITERS = ("\t", ";", ",", "|")
#: ``<name> (<unit>)`` or ``<name>[<unit>]``.
_BRACKET_UNIT = re.compile(r"^(?P<stem>.*?)\s*[\(\[]\s*(?P<unit>[^\)\]]*?)\s*[\)\]]$")
#: Unit suffixes recognised in channel names (anything else is kept as part of the name).
CHANNEL_UNITS = {"v": "V", "mv": "mV", "m": "m", "mm": "mm", "rad": "rad", "deg": "deg", "n": "N", "nm": "N m"}
#: Column names (without unit) treated as the experiment's input rather than a measured channel.
INPUT_NAMES = ("command", "cmd", "u", "input")
#: A strain-gauge channel named either way: ``sg1`` (DAQ recordings, the thesis) or ``gauge1`` (the twin's files).
_GAUGE_ALIAS = re.compile(r"^(sg|gauge)(\d+)$", re.IGNORECASE)
#: Largest allowed deviation of one sampling interval from the median interval (fraction of it).
SAMPLING_TOLERANCE = 0.25


@dataclass(frozen=True)
class TimeSeries:
    """One measured channel of an experiment, uniformly sampled.

    Attributes
    ----------
    t_s : ndarray
        Sample times (s), strictly increasing.
    y : ndarray
        The channel (``unit``).
    channel, unit : str
        Channel name and unit (``""`` when unknown).
    source : str
        Where it came from (a file name, ``"twin"``, ``"array"``); used in messages.
    u : ndarray or None
        The input (e.g. servo command) at the same times, when recorded.
    input_name : str
        Name of the input column.
    time_unit : str
        Unit of the time column in the file (``t_s`` is always in seconds); for messages.
    """

    t_s: np.ndarray
    y: np.ndarray
    channel: str = "y"
    unit: str = ""
    source: str = "array"
    u: np.ndarray | None = None
    input_name: str = ""
    time_unit: str = "s"

    @classmethod
    def from_arrays(cls, t_s, y, *, channel: str = "y", unit: str = "", u=None, source: str = "array"):
        """Validate arrays into a series (same checks as a file: increasing time, no NaN, enough samples)."""
        t = check_array(t_s, "t_s", "TimeSeries", ndim=1, finite=False, error=DataFileError)
        yv = check_array(y, "y", "TimeSeries", ndim=1, finite=False, error=DataFileError)
        if yv.shape != t.shape:
            raise DataFileError(f"{source}: time has {t.size} samples but '{channel}' has {yv.size}")
        uv = None
        if u is not None:
            uv = check_array(u, "u", "TimeSeries", ndim=1, shape=(t.size,), error=DataFileError)
        _check_series(t, yv, source, "time", channel, lambda i: f"sample {i}")
        return cls(t, yv, channel, unit, source, uv, "u" if uv is not None else "")

    @property
    def n_samples(self) -> int:
        return int(self.t_s.size)

    @property
    def dt_s(self) -> float:
        """Median sampling interval (s)."""
        return float(np.median(np.diff(self.t_s)))

    @property
    def sample_rate_hz(self) -> float:
        return 1.0 / self.dt_s

    @property
    def name(self) -> str:
        """``source:channel``, for messages and reports."""
        return f"{self.source}:{self.channel}"

    def with_y(self, y) -> TimeSeries:
        """A new series with the same times and a new signal (e.g. filtered)."""
        return TimeSeries(
            self.t_s,
            np.asarray(y, dtype=float),
            self.channel,
            self.unit,
            self.source,
            self.u,
            self.input_name,
            self.time_unit,
        )

    def __repr__(self) -> str:
        return summary(
            self,
            channel=self.channel,
            unit=self.unit,
            samples=len(self.t_s),
            duration_s=float(self.t_s[-1] - self.t_s[0]) if len(self.t_s) else 0.0,
            input=self.input_name if self.u is not None else None,
            source=self.source,
        )


def split_unit(column: str) -> tuple[str, str]:
    """``"sg1_v" -> ("sg1", "V")``, ``"Time (ms)" -> ("Time", "ms")``; a name without a known unit keeps ``""``.

    A unit in brackets or parentheses is always a unit (kept as written unless it is a known one); a suffix after
    the last ``_`` only when it is a known unit (``sg_1_mv`` is ``sg_1`` in mV, ``velocity_knots`` has no unit).

    Examples
    --------
    >>> split_unit("pot_v"), split_unit("time_ms"), split_unit("command")
    (('pot', 'V'), ('time', 'ms'), ('command', ''))
    >>> split_unit("Time (s)"), split_unit("sg2[mV]"), split_unit("force (N)")
    (('Time', 's'), ('sg2', 'mV'), ('force', 'N'))
    """
    name = column.strip()
    m = _BRACKET_UNIT.match(name)
    if m and m.group("stem"):
        unit = m.group("unit")
        return m.group("stem"), _known_unit(unit) or unit
    stem, sep, suffix = name.rpartition("_")
    if sep and stem:
        unit = _known_unit(suffix)
        if unit:
            return stem, unit
    return name, ""


def _known_unit(text: str) -> str:
    """The canonical spelling of a known time or channel unit (``"MS"`` -> ``"ms"``, ``"mv"`` -> ``"mV"``) or ``""``."""
    low = text.strip().lower()
    low = _TIME_ALIASES.get(low, low)
    if low in TIME_UNITS:
        return low
    return CHANNEL_UNITS.get(low, "")


def read_timeseries(
    path: str | Path,
    channel: str | None = None,
    *,
    time_unit: str | None = None,
    time_column: str | None = None,
) -> TimeSeries:
    """Read one channel of a DAQ recording (``.csv`` or ``.parquet``) as a :class:`TimeSeries`.

    Parameters
    ----------
    path : str or Path
        The recording: a header row then one row per sample (CSV; ``#`` lines are comments), or a Parquet table.
    channel : str, optional
        Column to read, by full name (``sg1_v``) or without its unit (``sg1``), in any case when that names one
        column (``sg1`` for ``SG1 (V)``); ``sgN`` and ``gaugeN`` name
        the same gauge when only one of them is in the file (the twin writes ``gauge1_v``). Default: the first
        channel that is not the time or an input column.
    time_unit : {"s", "ms", "us"}, optional
        Unit of a time column whose name carries none (``time``); overrides the name's suffix.
    time_column : str, optional
        Name of the time column (default: the first column named ``time``/``t``, with or without a unit).

    Returns
    -------
    TimeSeries
        Times in seconds; the input column (``command``...) as ``u`` when present.

    Raises
    ------
    DataFileError
        Naming the file, column and line/row: no such file, no header, missing time or channel column, a cell
        that is not a number, time not strictly increasing, NaN runs, irregular sampling, fewer than
        :data:`MIN_SAMPLES` samples.
    """
    p = Path(path)
    refuse_special(p, "a CSV or Parquet record")
    if not p.is_file():
        raise DataFileError(f"{p}: no such file")
    suffix = p.suffix.lower()
    if suffix == ".parquet":
        columns, data = _read_parquet(p)
        where = lambda i: f"row {i + 1}"  # noqa: E731
    elif suffix in (".csv", ".txt", ".tsv"):
        columns, data, lines = _read_csv(p)
        where = lambda i: f"line {lines[i]}" if i < len(lines) else f"line {i + 2}"  # noqa: E731
    else:
        raise DataFileError(f"{p}: unknown file type {p.suffix!r}: expected a .csv or .parquet recording")
    return _series_from_columns(columns, data, str(p), where, channel, time_unit, time_column)


def series_from_table(table, channel: str | None = None, *, source: str = "table", time_unit: str | None = None):
    """One channel of an in-memory table as a :class:`TimeSeries`, with the checks of :func:`read_timeseries`.

    Parameters
    ----------
    table : pyarrow.Table, mapping of column name to array, or an object with a ``table`` attribute
        E.g. the :class:`~flexdigit.twin.records.TwinRecord` of ``release_test`` or ``servo_step_test``
        (its metadata, when present, names the experiment in messages).
    channel, time_unit
        As for :func:`read_timeseries`.
    source : str
        Name used in messages.

    Examples
    --------
    >>> ts = series_from_table({"time_s": np.arange(30) * 0.01, "pot_v": np.ones(30)}, "pot")
    >>> ts.channel, ts.unit, ts.n_samples
    ('pot', 'V', 30)
    """
    meta = getattr(table, "metadata", None)
    if isinstance(meta, dict) and meta.get("experiment"):
        source = f"twin {meta['experiment']}"
    inner = getattr(table, "table", table)
    if hasattr(inner, "column_names"):
        columns = list(inner.column_names)
        data = {c: np.asarray(inner.column(c).to_numpy(zero_copy_only=False), dtype=float) for c in columns}
    else:
        columns = list(inner)
        data = {c: np.asarray(inner[c], dtype=float) for c in columns}
    return _series_from_columns(columns, data, source, lambda i: f"row {i + 1}", channel, time_unit, None)


def _series_from_columns(columns, data, source: str, where, channel, time_unit, time_column) -> TimeSeries:
    """Pick the time, channel and input columns, convert time to seconds and check them."""
    p = source
    tcol = _find_time_column(p, columns, time_column)
    stem, unit_in_name = split_unit(tcol)
    if time_unit is not None and time_unit not in TIME_UNITS:
        raise DataFileError(f"{p}: time unit unknown (--time-unit {time_unit!r}): expected s, ms or us")
    if time_unit is not None and unit_in_name and unit_in_name != time_unit:
        raise DataFileError(
            f"{p}: column {tcol!r} says its time is in {unit_in_name} but --time-unit {time_unit} was given: "
            "drop --time-unit, or rename the column"
        )
    unit = time_unit or unit_in_name
    if unit not in TIME_UNITS:
        got = f"column {tcol!r} has no unit" if not unit_in_name else f"column {tcol!r} is in {unit_in_name!r}"
        raise DataFileError(
            f"{p}: time unit unknown ({got}): name the column time_s, time_ms or time_us, or pass time_unit "
            "(--time-unit) s, ms or us"
        )
    inputs = [c for c in columns if c != tcol and split_unit(c)[0].lower() in INPUT_NAMES]
    channels = [c for c in columns if c != tcol and c not in inputs and c.strip().lower() not in _INDEX_NAMES]
    if channel is None:
        if not channels:
            raise DataFileError(f"{p}: no channel column besides {tcol!r} (columns: {_names(columns)})")
        ycol = channels[0]
    else:
        ycol = _match_channel(p, columns, channel)
    t = data[tcol] * TIME_UNITS[unit]
    y = data[ycol]
    u = data[inputs[0]] if inputs and inputs[0] != ycol else None
    _check_series(t, y, p, tcol, ycol, where)
    if u is not None:
        _check_nan_runs(u, p, inputs[0], where)
    ystem, yunit = split_unit(ycol)
    return TimeSeries(t, y, ystem, yunit, p, u, inputs[0] if u is not None else "", unit)


def _names(columns: list[str]) -> str:
    """Column names for a message, as written; one with a newline or another control character as its repr, so
    the message stays one line."""
    return ", ".join(c if c.isprintable() else repr(c) for c in columns)


def _match_channel(p: str, columns: list[str], channel: str) -> str:
    """The column ``channel`` names: exactly, without its unit, or through the gauge alias ``sgN`` <-> ``gaugeN``;
    then the same ignoring case (``sg1`` for ``SG1 (V)``) when that names one column only."""
    matches = [c for c in columns if c == channel] or [c for c in columns if split_unit(c)[0] == channel]
    if matches:
        return matches[0]
    folded = channel.strip().casefold()
    stem, unit = split_unit(channel)
    for same in (
        lambda c: c.strip().casefold() == folded,
        lambda c: split_unit(c)[0].casefold() == folded,
        lambda c: split_unit(c)[0].casefold() == stem.casefold() and split_unit(c)[1].casefold() == unit.casefold(),
    ):
        matches = [c for c in columns if same(c)]
        if len(matches) == 1:
            return matches[0]
        if len(matches) > 1:
            raise DataFileError(
                f"{p}: channel {channel!r} is ambiguous: it could be any of {_names(matches)}; name the column"
            )
    m = _GAUGE_ALIAS.match(stem)
    if m is not None:
        other = ("gauge" if m.group(1).lower() == "sg" else "sg") + m.group(2)
        matches = [c for c in columns if split_unit(c)[0].lower() == other and (not unit or split_unit(c)[1] == unit)]
        if len(matches) == 1:
            return matches[0]
        if len(matches) > 1:
            raise DataFileError(
                f"{p}: channel {channel!r} is ambiguous: it could be any of {_names(matches)}; name the column"
            )
    raise DataFileError(f"{p}: no column {channel!r} (columns: {_names(columns)})")


def _find_time_column(p: str, columns: list[str], time_column: str | None) -> str:
    if time_column is not None:
        if time_column not in columns:
            raise DataFileError(f"{p}: no time column {time_column!r} (columns: {_names(columns)})")
        return time_column
    for c in columns:
        if split_unit(c)[0].lower() in TIME_NAMES:
            return c
    raise DataFileError(
        f"{p}: no time column: expected one named time_s (or time_ms, time, t) among: {_names(columns)}"
    )


def _read_csv(p: Path) -> tuple[list[str], dict[str, np.ndarray], list[int]]:
    """Columns, float data and the file line of each data row; names the line and column of a bad cell."""
    count_lines(p, "a CSV record")  # a 10-million-row file is refused in a second, not read into gigabytes
    try:
        text = read_bytes(p, "a CSV record", RECORDS_LIMIT).decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataFileError(f"{p}: not a text CSV file (byte {exc.start} is not UTF-8)") from None
    numbered = [
        (lineno, line)
        for lineno, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not numbered:
        raise DataFileError(f"{p}: empty file: expected a header row such as time_s,sg1_v")
    split = _splitter(p, [line for _, line in numbered[:21]])
    header_line, header = numbered[0][0], [c.strip().strip('"') for c in split(numbered[0][1], numbered[0][0])]
    rows: list[list[str]] = []
    lines: list[int] = []
    for lineno, line in numbered[1:]:
        row = split(line, lineno)
        if not "".join(row).strip():
            continue
        if len(row) != len(header):
            raise DataFileError(
                f"{p}: line {lineno} has {len(row)} fields, the header (line {header_line}) has {len(header)}"
            )
        rows.append(row)
        lines.append(lineno)
    if len(set(header)) != len(header):
        raise DataFileError(f"{p}: duplicate column names in the header: {', '.join(header)}")
    decimal_comma = split.delimiter != ","
    data = {}
    for j, c in enumerate(header):
        cells = [row[j] for row in rows]
        data[c] = _parse_column(p, c, cells, lines, decimal_comma)
    return header, data, lines


class _Splitter:
    """Split a CSV line on one delimiter (quotes as in :mod:`csv`), or on runs of spaces (``delimiter=" "``).

    A line :mod:`csv` cannot split (a field past its limit of 131072 characters: a file with a hole of NUL bytes,
    a quote never closed) is a :class:`DataFileError` naming the file and the line, not a ``csv.Error``.
    """

    def __init__(self, delimiter: str, path: Path | None = None):
        self.delimiter, self.path = delimiter, path

    def __call__(self, line: str, lineno: int | None = None) -> list[str]:
        if self.delimiter == " ":
            return [c.strip('"') for c in line.split()]
        try:
            return next(csv.reader([line], delimiter=self.delimiter))
        except csv.Error as exc:
            where = "" if lineno is None else f" line {lineno}:"
            raise DataFileError(
                f"{self.path}:{where} not a CSV row ({exc}; {len(line)} characters on one line): expected numbers "
                f"separated by {self.delimiter!r}"
            ) from None


def _splitter(p: Path, lines: list[str]) -> _Splitter:
    """The delimiter that splits the header and the first rows into the same number (>= 2) of fields.

    Tried in the order tab, ``;``, ``,``, ``|``, then runs of spaces, so ``0,5;1,2`` (a decimal comma) splits on
    ``;``. Without a consistent one, ``,``: the reader then names the first line whose fields do not match.
    """
    for delimiter in (*_DELIMITERS, " "):
        split = _Splitter(delimiter, p)
        try:
            counts = {len(split(line)) for line in lines}
        except DataFileError:
            continue  # not this delimiter; the rows are read (and a bad one named) with the one chosen
        if len(counts) == 1 and counts.pop() >= 2:
            return split
    return _Splitter(",", p)


#: Cells read as a missing value (NaN).
_MISSING = ("", "nan", "na", "null", "none")


def _parse_column(p: Path, name: str, cells: list[str], lines: list[int], decimal_comma: bool) -> np.ndarray:
    """One column's cells as floats (vectorised; cell by cell only to name a bad one)."""
    if decimal_comma:
        cells = [c.replace(",", ".") if "," in c and "." not in c else c for c in cells]
    try:
        return np.array(cells, dtype=float)
    except ValueError:
        pass
    out = np.empty(len(cells))
    for i, cell in enumerate(cells):
        cell = cell.strip()
        if cell.lower() in _MISSING:
            out[i] = math.nan
            continue
        try:
            out[i] = float(cell)
        except ValueError:
            raise DataFileError(f"{p}: line {lines[i]}, column {name!r}: {cell!r} is not a number") from None
    return out


def _read_parquet(p: Path) -> tuple[list[str], dict[str, np.ndarray]]:
    import pyarrow.parquet as pq

    check_input(p, "a Parquet record")
    try:
        with _io.open_input(p, "a Parquet file", _io.RECORDS_LIMIT) as fh:  # any name, even not UTF-8
            table = pq.read_table(fh)
    except Exception as exc:  # pyarrow raises several types for a damaged file; all mean "cannot read it"
        raise DataFileError(f"{p}: not a readable Parquet file ({one_line(exc)})") from None
    try:  # pyarrow decodes the names only when asked: a damaged file's may not be UTF-8
        names = list(table.column_names)
    except UnicodeDecodeError as exc:
        raise DataFileError(f"{p}: a column name is not UTF-8 text ({one_line(exc)})") from None
    data = {}
    for k, name in enumerate(names):
        col = table.column(k)
        try:
            data[name] = np.asarray(col.to_numpy(zero_copy_only=False), dtype=float)
        except (TypeError, ValueError):
            raise DataFileError(f"{p}: column {name!r} is not numeric (type {col.type})") from None
    return names, data


def _check_series(t: np.ndarray, y: np.ndarray, source: str, tcol: str, ycol: str, where) -> None:
    """Enough samples, finite strictly increasing roughly uniform time, no NaN in the channel."""
    if t.size < MIN_SAMPLES:
        raise DataFileError(
            f"{source}: too few samples: {t.size}, an identification record needs at least {MIN_SAMPLES}"
        )
    bad = np.nonzero(~np.isfinite(t))[0]
    if bad.size:
        raise DataFileError(f"{source}: column {tcol!r}, {where(int(bad[0]))}: time is missing or not finite")
    dt = np.diff(t)
    back = np.nonzero(dt <= 0)[0]
    if back.size:
        i = int(back[0]) + 1
        raise DataFileError(
            f"{source}: column {tcol!r}, {where(i)}: time must increase strictly, got {t[i]:g} after {t[i - 1]:g}"
        )
    _check_nan_runs(y, source, ycol, where)
    med = float(np.median(dt))
    if not SAMPLE_INTERVAL_S.satisfied_by(med):
        try:
            SAMPLE_INTERVAL_S.check(med, "sample interval", None, DataFileError)
        except DataFileError as exc:
            raise DataFileError(f"{source}: column {tcol!r}: {str(exc).replace('parameter ', '', 1)}") from None
    off = np.nonzero(np.abs(dt - med) > SAMPLING_TOLERANCE * med)[0]
    if off.size:
        i = int(off[0]) + 1
        raise DataFileError(
            f"{source}: column {tcol!r}, {where(i)}: irregular sampling, a step of {dt[i - 1]:g} where the median "
            f"is {med:g} (dropped samples?); the filters need uniform sampling"
        )


def _check_nan_runs(y: np.ndarray, source: str, col: str, where) -> None:
    nan = ~np.isfinite(y)
    if not nan.any():
        return
    first = int(np.argmax(nan))
    end = first
    while end + 1 < y.size and nan[end + 1]:
        end += 1
    runs = int(np.sum(np.diff(np.concatenate([[0], nan.astype(int)])) == 1))
    more = f" ({runs} runs, {int(nan.sum())} values in all)" if runs > 1 else ""
    span = where(first) if end == first else f"{where(first)} to {where(end)}"
    raise DataFileError(
        f"{source}: column {col!r}, {span}: missing values (NaN run of {end - first + 1}){more}; "
        "cut the record or fill the gap before identifying"
    )


def write_csv(path: str | Path, ts: TimeSeries, *, force: bool = False) -> Path:
    """Write a series as a recording ``time_s,<channel>_<unit>[,command]`` that :func:`read_timeseries` reads
    (atomically; an existing file is refused unless ``force``)."""
    p = Path(path)
    unit = {v: k for k, v in CHANNEL_UNITS.items()}.get(ts.unit, "")
    ycol = f"{ts.channel}_{unit}" if unit else ts.channel
    cols = [ts.t_s, ts.y] + ([ts.u] if ts.u is not None else [])
    header = ["time_s", ycol] + ([ts.input_name or "command"] if ts.u is not None else [])
    with atomic_write(p, "w", force=force) as fh:
        np.savetxt(fh, np.column_stack(cols), delimiter=",", header=",".join(header), comments="", fmt="%.9g")
    return p

"""Tactile datasets: a tidy table of readings, a crash-safe journal, Parquet and CSV files.

One row per reading: the gauge voltages (``gauge1_v`` .. ``gaugeG_v``, one per gauge of the digit, 1 to 8; the
thesis rig's three), the potentiometer voltage, the load (kg), where it hung (from the
tip and from the base, m), the servo command (:data:`~flexdigit.tactile.protocols.RELAXED` when actuation is
disabled), the test and repetition, and the time. The protocol and the rig that produced it travel with it as
metadata, so a dataset cannot silently be mixed up with another experiment.

While collecting, each reading is appended to a JSON-lines *journal* and flushed at once: Ctrl-C or a crash loses
nothing already read, and a partial last line (a crash mid-write) is dropped on resume. When the protocol
completes the journal is compacted to Parquet (pyarrow) and removed.

Examples
--------
>>> import numpy as np
>>> ds = Dataset({c: np.zeros(2, dtype=d) for c, d in COLUMNS.items()}, {"protocol": {"name": "x"}})
>>> len(ds), ds.gauges_v.shape
(2, (2, 3))
"""

from __future__ import annotations

import json
import os
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexdigit import __version__, _io
from flexdigit._io import (
    LOG_LIMIT,
    RECORDS_LIMIT,
    atomic_path,
    atomic_write,
    check_input,
    count_lines,
    read_bytes,
    read_text,
)
from flexdigit.errors import DataFileError, one_line
from flexdigit.interrupts import signals_deferred
from flexdigit.tactile.protocols import RELAXED, Protocol

__all__ = [
    "COLUMNS",
    "GAUGE_COLUMNS",
    "MAX_GAUGES",
    "gauge_columns",
    "dataset_columns",
    "gauge_count_of",
    "JOURNAL_FORMAT",
    "DATASET_FORMAT",
    "Dataset",
    "make_meta",
    "Journal",
    "first_difference",
    "read_journal",
    "save_dataset",
    "export_csv",
    "load_dataset",
]

#: Most gauges a digit carries (:class:`flexdigit.params.Geometry`); a dataset has one column per gauge.
MAX_GAUGES = 8


def gauge_columns(count: int = 3) -> tuple[str, ...]:
    """The gauge columns of a dataset of a digit with ``count`` gauges: ``gauge1_v`` (nearest the clamp) first.

    Examples
    --------
    >>> gauge_columns(4)
    ('gauge1_v', 'gauge2_v', 'gauge3_v', 'gauge4_v')
    """
    return tuple(f"gauge{k}_v" for k in range(1, count + 1))


def dataset_columns(count: int = 3) -> dict[str, type]:
    """Every column of a dataset of a digit with ``count`` gauges, in order, and its numpy dtype."""
    return {
        "sample": np.int64,
        "test": np.int64,
        **dict.fromkeys(gauge_columns(count), np.float64),
        "pot_v": np.float64,
        "load_kg": np.float64,
        "position_index": np.int64,
        "position_from_tip_m": np.float64,
        "position_from_base_m": np.float64,
        "command": np.int64,
        "repetition": np.int64,
        "time_s": np.float64,
    }


#: Every column of a dataset of the thesis rig (three gauges) and its numpy dtype.
COLUMNS: dict[str, type] = dataset_columns(3)
GAUGE_COLUMNS = gauge_columns(3)


def gauge_count_of(meta: dict, where: object = "dataset") -> int:
    """The gauge count a dataset's (or journal's) metadata records: ``gauge_count``, 3 in files written before
    datasets recorded it (the thesis rig's). Anything but an integer 1..:data:`MAX_GAUGES` is refused, naming
    ``where``."""
    value = meta.get("gauge_count", 3) if isinstance(meta, dict) else 3
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= MAX_GAUGES:
        raise DataFileError(f"{where}: metadata 'gauge_count' must be an integer 1..{MAX_GAUGES}. Got {value!r}")
    return value


#: /2: every reading carries a CRC-32 of its canonical JSON (``crc``). A journal of /1 (before it) is still
#: resumed, as legacy: its readings are real measurements that cannot be taken again, and are checked as before
#: (consecutive, inside the protocol's plan) but not against a checksum they never had.
JOURNAL_FORMAT = "flexdigit-tactile-journal/2"
LEGACY_JOURNAL_FORMATS = ("flexdigit-tactile-journal/1",)
DATASET_FORMAT = "flexdigit-tactile-dataset/1"


@dataclass
class Dataset:
    """Readings of one protocol: ``columns`` (name -> 1-D array, see :data:`COLUMNS`) and ``meta``.

    ``meta`` holds ``protocol`` (the protocol as a dict), ``protocol_fingerprint``, ``rig`` (a description of
    the backend), ``digit_length_m`` and ``flexdigit_version``.
    """

    columns: dict[str, np.ndarray]
    meta: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.columns["sample"].shape[0])

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    @property
    def gauge_count(self) -> int:
        """How many gauges the digit has (``meta["gauge_count"]``; 3, the thesis rig's, in older files)."""
        return gauge_count_of(self.meta)

    @property
    def gauge_columns(self) -> tuple[str, ...]:
        """The gauge columns, ``gauge1_v`` .. ``gaugeG_v``."""
        return gauge_columns(self.gauge_count)

    @property
    def gauges_v(self) -> np.ndarray:
        """The gauge voltages as an ``(n, G)`` array (V), gauge 1 (nearest the clamp) first."""
        return np.column_stack([self.columns[c] for c in self.gauge_columns])

    @property
    def contact(self) -> np.ndarray:
        """1 where a load hangs on the digit, 0 for the no-load readings."""
        return (self.columns["load_kg"] > 0).astype(np.int64)

    @property
    def protocol(self) -> Protocol:
        return Protocol.from_dict(self.meta["protocol"])

    def subset(self, mask: np.ndarray) -> Dataset:
        """A new dataset with the rows where ``mask`` is true."""
        return Dataset({k: v[mask] for k, v in self.columns.items()}, dict(self.meta))

    def __repr__(self) -> str:
        name = self.meta.get("protocol", {}).get("name", "?")
        return f"Dataset(protocol={name!r}, samples={len(self)}, rig={self.meta.get('rig', {}).get('url', '?')!r})"


def make_meta(protocol: Protocol, rig: dict, digit_length_m: float, adc_range_v=None, gauge_count: int = 3) -> dict:
    """The metadata stored with a dataset (and in its journal's header); ``adc_range_v`` (V) where it is known
    (the card the readings were taken with; None for imported readings); ``gauge_count``: the digit's gauges."""
    return {
        "gauge_count": int(gauge_count),
        "format": DATASET_FORMAT,
        "protocol": protocol.to_dict(),
        "protocol_fingerprint": protocol.fingerprint,
        "rig": rig,
        "digit_length_m": float(digit_length_m),
        "adc_range_v": None if adc_range_v is None else [float(v) for v in adc_range_v],
        "flexdigit_version": __version__,
    }


# --------------------------------------------------------------------------------------------------- journal
class Journal:
    """Append-only JSON-lines file: a header line, then one line per reading, flushed as written.

    Use :meth:`open` to start or resume; it returns the journal and the readings already in it.
    ``fsync=True`` also forces each line to disk (survives power loss, costs ~ms a reading).
    """

    def __init__(self, path: Path, handle, fsync: bool = False) -> None:
        self.path = path
        self._fh = handle
        self._fsync = fsync

    @classmethod
    def open(cls, path: str | Path, meta: dict, *, fsync: bool = False) -> tuple[Journal, list[dict]]:
        """Open ``path`` for appending; create it with ``meta`` as header, or check the header and resume.

        A new journal's header is written atomically (a crash leaves no journal or a whole header). On resume the
        header's protocol and ``settings`` (the effective settings of the run that started it) must equal
        ``meta``'s; the first difference is named.

        Returns
        -------
        (Journal, list of dict)
            The journal and the readings already recorded, in order (``sample`` 0, 1, ...).

        Raises
        ------
        DataFileError
            If the journal belongs to another protocol or other settings, or its lines are not consecutive
            readings.
        """
        path = Path(path)
        rows: list[dict] = []
        if path.exists():
            header, rows, good_bytes = _read_journal(path)
            if header.get("protocol_fingerprint") != meta["protocol_fingerprint"]:
                raise DataFileError(
                    f"{path}: this journal was written by protocol {header.get('protocol', {}).get('name')!r} "
                    f"(fingerprint {header.get('protocol_fingerprint')}), not {meta['protocol']['name']!r} "
                    f"(fingerprint {meta['protocol_fingerprint']}); remove it or use --out with another file"
                )
            difference = first_difference(header.get("settings"), meta.get("settings"))
            if difference is not None:
                key, was, now = difference
                raise DataFileError(
                    f"{path}: this journal was started with {key}={was!r}; this run has {key}={now!r}. Resume with "
                    "the same settings, or collect into another --out"
                )
            _check_journal_plan(path, rows, header)
            if good_bytes < path.stat().st_size:  # a crash mid-write left a partial line: drop it
                with path.open("r+b") as fh:
                    fh.truncate(good_bytes)
        else:
            with atomic_write(path, "w") as fh:
                fh.write(json.dumps({"journal": JOURNAL_FORMAT, **meta}) + "\n")
        handle = path.open("a", encoding="utf-8")
        return cls(path, handle, fsync), rows

    def append(self, row: dict) -> None:
        """Write one reading with its checksum and flush it (and fsync it if asked); a stop signal waits for the
        line's end."""
        body = {k: v for k, v in row.items() if k != "crc"}
        line = json.dumps({**body, "crc": row_checksum(body)}) + "\n"
        with signals_deferred():
            self._fh.write(line)
            self._fh.flush()
            if self._fsync:
                os.fsync(self._fh.fileno())

    def close(self) -> None:
        self._fh.close()

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def first_difference(was: object, now: object, prefix: str = "") -> tuple[str, object, object] | None:
    """The first (dotted key, old value, new value) where two settings differ, or None when they agree.

    Examples
    --------
    >>> first_difference({"rig": {"seed": 3}, "settle_s": 15.0}, {"rig": {"seed": 4}, "settle_s": 15.0})
    ('rig.seed', 3, 4)
    """
    if isinstance(was, dict) and isinstance(now, dict):
        for key in list(was) + [k for k in now if k not in was]:
            found = first_difference(was.get(key), now.get(key), f"{prefix}{key}.")
            if found is not None:
                return found
        return None
    if was != now:
        return prefix.rstrip(".") or "settings", was, now
    return None


def row_checksum(row: dict) -> str:
    """CRC-32 (8 hex digits) of a journalled reading's canonical JSON, without its own ``crc``.

    Examples
    --------
    >>> row_checksum({"sample": 0, "gauge1_v": 0.5}) == row_checksum({"gauge1_v": 0.5, "sample": 0})
    True
    """
    body = {k: v for k, v in row.items() if k != "crc"}
    return f"{zlib.crc32(json.dumps(body, sort_keys=True, separators=(',', ':')).encode()):08x}"


def _check_journal_plan(path: Path, rows: list[dict], header: dict) -> None:
    """Every journalled reading must be one the protocol of the journal's header takes, where it takes it: a reading
    beyond the plan (an out-of-design row) or whose settings differ from its sample's is refused naming its line."""
    try:
        protocol = Protocol.from_dict(header["protocol"])
        plan = protocol.plan(float(header.get("digit_length_m", 0.270)))
    except (KeyError, TypeError, ValueError) as exc:
        raise DataFileError(f"{path}: line 1: the stored protocol is invalid ({one_line(exc)})") from None
    total = protocol.sample_count
    if len(rows) > total:  # first: rows past the plan say more than any one setting that differs
        raise DataFileError(
            f"{path}: line {total + 2} holds sample {rows[total]['sample']}, beyond the {total} readings protocol "
            f"{protocol.name!r} takes (the journal was edited or mixed with another)"
        )
    for i, row in enumerate(rows):
        number = i + 2
        for name in ("test", "load_kg", "position_index", "command", "repetition", "position_from_tip_m"):
            want, got = plan[name][row["sample"]].item(), row[name]
            same = (got is None and want != want) or (
                got is not None and (got == want or (isinstance(want, float) and abs(got - want) <= 1e-12))
            )
            if not same:
                raise DataFileError(
                    f"{path}: line {number}: sample {row['sample']} has {name} = {got!r}, but protocol "
                    f"{protocol.name!r} takes {want!r} there (the journal was edited or mixed with another)"
                )


def _read_journal(path: Path) -> tuple[dict, list[dict], int]:
    """Header, complete readings, and the byte length of the complete part of a journal."""
    data = read_bytes(path, "a collection journal", LOG_LIMIT)
    lines = data.split(b"\n")
    # Everything after the last newline is a partial line (or empty): it is not counted.
    complete, good_bytes = lines[:-1], data.rfind(b"\n") + 1
    if not complete:
        raise DataFileError(f"{path}: journal has no complete header line")
    try:
        header = json.loads(complete[0])
    except (ValueError, RecursionError):  # not JSON, not UTF-8, or nested past the parser (10^5 brackets)
        raise DataFileError(f"{path}: line 1 is not a journal header (not JSON, or nested too deep)") from None
    if not isinstance(header, dict) or header.get("journal") not in (JOURNAL_FORMAT, *LEGACY_JOURNAL_FORMATS):
        raise DataFileError(f"{path}: line 1 is not a {JOURNAL_FORMAT} header")
    checked = header["journal"] == JOURNAL_FORMAT
    columns = dataset_columns(gauge_count_of(header, f"{path}: line 1"))
    rows = []
    for number, line in enumerate(complete[1:], start=2):
        try:
            row = json.loads(line)
        except (ValueError, RecursionError):  # RecursionError: brackets nested past the parser
            raise DataFileError(f"{path}: line {number} is not valid JSON (or nested too deep)") from None
        if not isinstance(row, dict):
            raise DataFileError(f"{path}: line {number} is not a reading (a JSON object)")
        missing = [c for c in columns if c not in row]
        if missing:
            raise DataFileError(f"{path}: line {number} lacks column '{missing[0]}'")
        for name, dtype in columns.items():
            value = row[name]
            if np.dtype(dtype).kind == "i":
                ok = isinstance(value, int) and not isinstance(value, bool) and abs(value) < 2**63
            else:
                ok = value is None or (isinstance(value, int | float) and not isinstance(value, bool))
            if not ok:
                kind = "an integer" if np.dtype(dtype).kind == "i" else "a number or null"
                raise DataFileError(f"{path}: line {number}: column '{name}' must be {kind}. Got {value!r}")
        if checked and row.get("crc") != row_checksum(row):
            raise DataFileError(
                f"{path}: line {number}: the checksum of sample {row['sample']} does not match its values (the journal "
                "was edited, or a line corrupted); remove this line and the ones after it to take them again"
            )
        if row["sample"] != len(rows):
            raise DataFileError(
                f"{path}: line {number} holds sample {row['sample']}, expected {len(rows)} "
                "(readings must be consecutive; the journal was edited or mixed with another)"
            )
        rows.append(row)
    return header, rows, good_bytes


def read_journal(path: str | Path) -> Dataset:
    """The readings of a journal so far, as a :class:`Dataset` (an interrupted run can still be analysed)."""
    header, rows, _ = _read_journal(Path(path))
    meta = {k: v for k, v in header.items() if k != "journal"}
    return Dataset(_rows_to_columns(rows, dataset_columns(gauge_count_of(meta, path))), meta)


def _rows_to_columns(rows: list[dict], columns: dict[str, type]) -> dict[str, np.ndarray]:
    out = {}
    for name, dtype in columns.items():
        values = [np.nan if r[name] is None else r[name] for r in rows]
        out[name] = np.array(values, dtype=dtype) if values else np.zeros(0, dtype=dtype)
    return out


# ------------------------------------------------------------------------------------------- parquet and csv
def save_dataset(dataset: Dataset, path: str | Path, *, force: bool = False) -> Path:
    """Write ``dataset`` as Parquet (metadata in the schema) or, for a ``.csv`` path, as CSV with a JSON header.

    Atomic (:mod:`flexdigit._io`): a crash never leaves half a file under the real name, a failed write leaves
    the old one; an existing file is refused unless ``force``.
    """
    path = Path(path)
    if path.suffix.lower() == ".csv":
        return export_csv(dataset, path, force=force)
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({name: dataset.columns[name] for name in dataset_columns(dataset.gauge_count)})
    table = table.replace_schema_metadata({"flexdigit": json.dumps(dataset.meta)})
    with atomic_path(path, force=force) as tmp:
        pq.write_table(table, tmp)
    return path


def export_csv(dataset: Dataset, path: str | Path, *, force: bool = False) -> Path:
    """Write ``dataset`` as CSV: a ``# {json metadata}`` first line, a header, one row per reading (atomic)."""
    path = Path(path)
    names = list(dataset_columns(dataset.gauge_count))
    with atomic_write(path, "w", force=force) as fh:
        fh.write("# " + json.dumps(dataset.meta) + "\n")
        fh.write(",".join(names) + "\n")
        cols = [dataset.columns[n] for n in names]
        for i in range(len(dataset)):
            fh.write(",".join(repr(float(c[i])) if c.dtype.kind == "f" else str(int(c[i])) for c in cols) + "\n")
    return path


def load_dataset(path: str | Path, protocol: Protocol | None = None, *, partial: bool | None = None) -> Dataset:
    """Read and validate a dataset (Parquet, CSV export, or an unfinished ``.jsonl`` journal).

    Every reading is checked against the protocol stored with it: its sample number, test, load, position,
    command and repetition must be the protocol's for that sample (an edited load or position is refused), its
    gauge and potentiometer voltages must lie in the ADC range it was read with, and a dataset must hold every
    sample of its protocol (a truncated file is refused) unless ``partial``.

    Parameters
    ----------
    path : path
        The file.
    protocol : Protocol, optional
        If given, the dataset must have been collected with it (same fingerprint).
    partial : bool, optional
        Accept a dataset that holds only the first samples of its protocol. Default: only for a journal.

    Raises
    ------
    DataFileError
        Naming the file and what is wrong: unreadable, a missing column, a wrong dtype, a reading that is not the
        protocol's or out of the ADC range, missing readings, missing metadata, or another protocol.
    FileNotFoundError
        If the file does not exist.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(2, "No such file", str(path))
    suffix = path.suffix.lower()
    if suffix == ".jsonl":
        dataset = read_journal(path)
    elif suffix == ".csv":
        dataset = _load_csv(path)
    else:
        dataset = _load_parquet(path)
    _validate(dataset, path, protocol, partial=suffix == ".jsonl" if partial is None else partial)
    return dataset


def _load_parquet(path: Path) -> Dataset:
    import pyarrow as pa
    import pyarrow.parquet as pq

    check_input(path, "a flexdigit dataset (Parquet)")
    try:
        with _io.open_input(path, "a Parquet file", _io.RECORDS_LIMIT) as fh:  # any name, even not UTF-8
            table = pq.read_table(fh)
    except (pa.ArrowException, OSError) as exc:
        raise DataFileError(f"{path}: not a readable Parquet file ({one_line(exc)})") from None
    try:  # pyarrow decodes the names only when asked: a damaged file's may not be UTF-8
        column_names = table.column_names
    except UnicodeDecodeError as exc:
        raise DataFileError(f"{path}: a column name is not UTF-8 text ({one_line(exc)})") from None
    meta_raw = (table.schema.metadata or {}).get(b"flexdigit")
    if meta_raw is None:
        raise DataFileError(f"{path}: no flexdigit metadata (protocol and rig); not a flexdigit tactile dataset")
    try:
        meta = json.loads(meta_raw)
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
        raise DataFileError(f"{path}: flexdigit metadata is not valid JSON") from None
    expected = dataset_columns(gauge_count_of(meta, path))
    columns = {}
    for name, dtype in expected.items():
        if name not in column_names:
            raise DataFileError(f"{path}: missing column '{name}' (expected columns: {', '.join(expected)})")
        arrow_type = table.schema.field(name).type
        want_float = np.dtype(dtype).kind == "f"
        ok = pa.types.is_floating(arrow_type) if want_float else pa.types.is_integer(arrow_type)
        if not ok:
            raise DataFileError(
                f"{path}: column '{name}' has type {arrow_type}, expected {'float' if want_float else 'integer'}"
            )
        column = table.column(name)
        if column.null_count and not want_float:
            raise DataFileError(f"{path}: column '{name}' has {column.null_count} missing values")
        columns[name] = column.to_numpy(zero_copy_only=False).astype(dtype)
    return Dataset(columns, meta)


def _load_csv(path: Path) -> Dataset:
    from io import StringIO

    count_lines(path, "a flexdigit dataset CSV")
    with StringIO(read_text(path, "a flexdigit dataset CSV", RECORDS_LIMIT)) as fh:
        first = fh.readline()
        if not first.startswith("# "):
            raise DataFileError(f"{path}: line 1 must be '# {{json metadata}}' as written by flexdigit")
        try:
            meta = json.loads(first[2:])
        except (json.JSONDecodeError, RecursionError):
            raise DataFileError(f"{path}: line 1 metadata is not valid JSON") from None
        expected = dataset_columns(gauge_count_of(meta, path))
        header = fh.readline().strip().split(",")
        missing = [c for c in expected if c not in header]
        if missing:
            raise DataFileError(f"{path}: missing column '{missing[0]}' (expected columns: {', '.join(expected)})")
        values: dict[str, list] = {c: [] for c in header}
        for number, line in enumerate(fh, start=3):
            cells = line.rstrip("\n").split(",")
            if len(cells) != len(header):
                raise DataFileError(f"{path}: line {number} has {len(cells)} cells, expected {len(header)}")
            for c, v in zip(header, cells, strict=True):
                values[c].append(v)
    columns = {}
    for name, dtype in expected.items():
        try:
            columns[name] = np.array(values[name], dtype=float)
        except ValueError:
            raise DataFileError(f"{path}: column '{name}' has a value that is not a number") from None
        if np.dtype(dtype).kind == "i":
            col = columns[name]
            if not np.all(np.isfinite(col)) or not np.all(col == np.round(col)):
                raise DataFileError(f"{path}: column '{name}' must hold integers")
        columns[name] = columns[name].astype(dtype)
    return Dataset(columns, meta)


def _validate(dataset: Dataset, path: Path, protocol: Protocol | None, *, partial: bool = False) -> None:
    meta = dataset.meta
    if not isinstance(meta, dict):
        raise DataFileError(f"{path}: the metadata is not a JSON object")
    for key in ("protocol", "protocol_fingerprint", "rig"):
        if key not in meta:
            raise DataFileError(f"{path}: metadata lacks '{key}'")
    try:
        stored = Protocol.from_dict(meta["protocol"])
    except (TypeError, ValueError, AttributeError) as exc:
        raise DataFileError(f"{path}: the stored protocol is invalid ({exc})") from None
    if stored.fingerprint != meta["protocol_fingerprint"]:
        raise DataFileError(f"{path}: the stored protocol does not match its fingerprint (edited metadata?)")
    if protocol is not None and protocol.fingerprint != stored.fingerprint:
        raise DataFileError(
            f"{path}: collected with protocol {stored.name!r} (fingerprint {stored.fingerprint}), "
            f"not {protocol.name!r} (fingerprint {protocol.fingerprint})"
        )
    samples = dataset["sample"]
    if np.unique(samples).size != samples.size:
        raise DataFileError(f"{path}: column 'sample' repeats a sample number (duplicated readings)")
    total = stored.sample_count
    if samples.size and (samples.min() < 0 or samples.max() >= total):
        raise DataFileError(f"{path}: column 'sample' is outside 0..{total - 1} for {stored.name!r}")
    collected = not (isinstance(meta["rig"], dict) and meta["rig"].get("url") == "import")
    if collected:  # taken by the runner in the protocol's order: complete, and each reading where the plan says
        if not partial and samples.size != total:
            missing = sorted(set(range(total)) - set(samples.tolist()))
            raise DataFileError(
                f"{path}: holds {samples.size} of the {total} readings of {stored.name!r} (sample {missing[0]} is "
                "missing): a truncated or cut file; an unfinished collection resumes from its journal"
            )
        _check_against_plan(dataset, path, stored, meta)
    else:  # imported (flexdigit dataset import): its protocol is the set of its settings, in the file's order
        _check_against_settings(dataset, path, stored)
    gauges = dataset.gauges_v
    if gauges.size and not np.all(np.isfinite(gauges)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(gauges), axis=1))[0])
        raise DataFileError(f"{path}: gauge voltage of sample {int(dataset['sample'][bad])} is not finite")
    adc = _adc_range(meta, path)
    for name in (*dataset.gauge_columns, "pot_v") if adc is not None else ():
        values = dataset[name]
        with np.errstate(invalid="ignore"):
            outside = np.flatnonzero((values < adc[0]) | (values > adc[1]))
        if outside.size:
            i = int(outside[0])
            raise DataFileError(
                f"{path}: column '{name}' of sample {int(samples[i])} is {values[i]:g} V, outside the ADC range "
                f"{adc[0]:g}..{adc[1]:g} V it was read with"
            )
    if np.any(np.isinf(dataset["time_s"])):
        raise DataFileError(f"{path}: column 'time_s' must be finite (or NaN where the time is unknown)")


def _adc_range(meta: dict, path: Path) -> tuple[float, float] | None:
    """The ADC range the readings were taken with (metadata; the thesis card's +-5 V for files collected before it
    was recorded; None where it is unknown: imported readings)."""
    value = meta.get("adc_range_v", [-5.0, 5.0])
    if value is None:
        return None
    try:
        low, high = (float(v) for v in value)
    except (TypeError, ValueError):
        raise DataFileError(f"{path}: metadata 'adc_range_v' must be [low, high] in volts. Got {value!r}") from None
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise DataFileError(f"{path}: metadata 'adc_range_v' must be an increasing pair of volts. Got {value!r}")
    return low, high


def _check_against_settings(dataset: Dataset, path: Path, protocol: Protocol) -> None:
    """Each imported reading's load, position and command must be one of its protocol's."""
    allowed = {
        "load_kg": {0.0, *protocol.loads_kg},
        "position_from_tip_m": set(protocol.positions_from_tip_m),
        "command": set(protocol.actuation_commands) or {RELAXED},
    }
    loaded = dataset["load_kg"] > 0
    for name, values in allowed.items():
        column = dataset[name][loaded] if name == "position_from_tip_m" else dataset[name]
        bad = ~np.isin(column, sorted(values))
        if np.any(bad):
            i = int(np.flatnonzero(bad)[0])
            raise DataFileError(
                f"{path}: a reading has {name} = {column[i].item()!r}, not one of protocol {protocol.name!r}'s "
                f"{sorted(values)!r} (an edited or mixed-up file)"
            )


def _check_against_plan(dataset: Dataset, path: Path, protocol: Protocol, meta: dict) -> None:
    """Each reading's setting columns must be what the protocol prescribes for its sample number."""
    try:
        length = float(meta.get("digit_length_m", 0.270))
        plan = protocol.plan(length)
    except (TypeError, ValueError) as exc:
        raise DataFileError(f"{path}: metadata 'digit_length_m' does not fit the protocol ({exc})") from None
    index = dataset["sample"]
    for name in ("test", "load_kg", "position_index", "command", "repetition", "position_from_tip_m"):
        want, got = plan[name][index], dataset[name]
        same = np.isclose(got, want, rtol=1e-12, atol=1e-12, equal_nan=True) if got.dtype.kind == "f" else got == want
        if not np.all(same):
            i = int(np.flatnonzero(~same)[0])
            raise DataFileError(
                f"{path}: sample {int(index[i])} has {name} = {got[i].item()!r}, but protocol {protocol.name!r} takes "
                f"{want[i].item()!r} there (an edited or mixed-up file)"
            )

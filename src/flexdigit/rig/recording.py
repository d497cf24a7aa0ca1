"""Recordings in MCAP: every sample of a run, with JSON schemas, readable by any MCAP tool (Foxglove, Lichtblick,
PlotJuggler, Rerun, the ``mcap`` libraries and CLI).

A recording holds one channel per topic, each with a JSON Schema (``jsonschema`` encoding, ``json`` messages) so
another tool can decode and check it without flexdigit:

- ``/flexdigit/sample``: what the loop logs (:mod:`flexdigit.rig.sample_log`): time, the gauge voltages (one per
  gauge), the pot, the command sent, the setpoint and the measured value;
- channels a caller adds (:meth:`Recording.add_channel`): the live page adds ``/flexdigit/shape`` and
  ``/flexdigit/contact``; this module knows nothing of them (rig is below tactile and live in the import chain).

Metadata records: ``flexdigit.run`` (format, backend, controller, period, start time: the header of a JSON-lines
log), ``flexdigit.rig`` (its repr and parameters), ``flexdigit.calibration`` when a caller gives one, and
``flexdigit.stop`` (why and how the run ended, written by :meth:`Recording.close`). Nested values are stored as
JSON text (MCAP metadata is string to string).

Nothing is lost or clobbered: the file is created exclusively (``--force`` replaces it), and the open chunk is
closed and handed to the operating system at least once a second (``flush_every_s``), so a run that is killed
leaves everything but its last second readable (:func:`read_recording` reads such a file record by record; the summary
section only makes reading faster). A clean close writes the summary and the footer.

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "run.mcap"
>>> with Recording(path, header={"backend": "sim"}) as rec:
...     rec.write_sample({"k": 0, "t": 0.0, "setpoint": 30.0, "gauges_v": [0.1, 0.5, 0.0], "pot_v": None,
...                       "y": 0.0, "command": 8})
>>> header, samples, footer = read_recording(path)
>>> header["backend"], samples[0]["gauges_v"], footer["stop"]
('sim', [0.1, 0.5, 0.0], 'closed')
"""

from __future__ import annotations

import json
import os
import struct
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from flexdigit._io import RECORDS_LIMIT, OutputStream, check_input, check_output, open_input
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.interrupts import signals_deferred, stop_requested
from flexdigit.rig.base import Rig
from flexdigit.rig.sample_log import SampleColumns, check_sample

__all__ = [
    "Recording",
    "read_recording",
    "read_recording_columns",
    "read_metadata",
    "rig_metadata",
    "recording_rig",
    "iter_messages",
    "is_mcap",
    "SAMPLE_TOPIC",
    "MAX_RECORD_BYTES",
    "SAMPLE_SCHEMA",
    "RECORDING_FORMAT",
]

RECORDING_FORMAT = "flexdigit-recording/1"
MCAP_MAGIC = b"\x89MCAP0\r\n"
SAMPLE_TOPIC = "/flexdigit/sample"
#: The largest MCAP record (a chunk, compressed or not, and a chunk's records once decompressed) flexdigit reads,
#: bytes. A chunk is read whole into memory, so this bounds what reading a recording takes (a few times this, not a
#: 1.2 GB chunk's 3.4 GB); flexdigit writes 16 KiB chunks and the mcap tools 1-4 MiB ones. A larger record is
#: refused naming the file (a length claimed past the end of the file is a cut file, read up to there).
MAX_RECORD_BYTES = 64 * 2**20
_NULLABLE = {"type": ["number", "null"]}
#: JSON Schema of a loop sample (the same fields as a JSON-lines loop log line).
SAMPLE_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "flexdigit.Sample",
    "description": "One sample of the rig loop: read, command, log (thesis 5.2). SI units; null where not measured.",
    "type": "object",
    "properties": {
        "k": {"type": "integer", "minimum": 0, "description": "sample index"},
        "t": {"type": "number", "description": "rig time since the start of the run, s"},
        "gauges_v": {
            "type": "array",
            "items": _NULLABLE,
            "minItems": 1,
            "maxItems": 8,
            "description": "gauge voltages 1..G from the base (one per gauge of the digit; the thesis rig's 3), V",
        },
        "pot_v": {**_NULLABLE, "description": "servo potentiometer, V (null: no pot channel)"},
        "command": {"type": "integer", "minimum": 0, "maximum": 254, "description": "servo command sent"},
        "setpoint": {**_NULLABLE, "description": "setpoint, the controller's unit (beam rotation, deg)"},
        "y": {**_NULLABLE, "description": "what the controller measured, its unit (beam rotation, deg)"},
    },
    "required": ["t", "gauges_v", "command"],
    "additionalProperties": True,
}


def is_mcap(path: str | os.PathLike) -> bool:
    """True when the file starts with the MCAP magic bytes."""
    try:  # a FIFO or a device is not one (and is never opened blocking): its reader refuses it by name
        with open_input(path, "an MCAP recording", RECORDS_LIMIT) as fh:
            return fh.read(len(MCAP_MAGIC)) == MCAP_MAGIC
    except (OSError, DataFileError):
        return False


def _metadata_text(values: dict[str, Any]) -> dict[str, str]:
    """MCAP metadata is string to string: strings kept, everything else as JSON text."""
    return {str(k): v if isinstance(v, str) else json.dumps(v, allow_nan=False, default=str) for k, v in values.items()}


def _metadata_values(values: dict[str, str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in values.items():
        try:
            out[k] = json.loads(v)
        except (TypeError, ValueError, RecursionError):  # not JSON (or nested past the parser): kept as text
            out[k] = v
    return out


class Recording:
    """An MCAP recording being written (see the module docstring).

    Parameters
    ----------
    path : path-like
        The ``.mcap`` file; refused if it exists unless ``force``.
    header : dict, optional
        The run's settings (backend, controller, period ...), stored as the ``flexdigit.run`` metadata.
    metadata : dict of dict, optional
        More metadata records, ``{name: {key: value}}`` (e.g. ``flexdigit.rig``, ``flexdigit.calibration``).
    force : bool
        Replace an existing file.
    chunk_size : int
        Bytes per chunk at most.
    flush_every_s : float
        The open chunk is closed and handed to the operating system at least this often (s, wall clock): a run
        killed with ``kill -9`` loses at most that much (:meth:`flush` and :meth:`close` also fsync, for a power
        cut).
    """

    def __init__(
        self,
        path: str | os.PathLike,
        *,
        header: dict[str, Any] | None = None,
        metadata: dict[str, dict[str, Any]] | None = None,
        force: bool = False,
        chunk_size: int = 16 * 1024,
        flush_every_s: float = 1.0,
    ) -> None:
        from mcap.writer import CompressionType, Writer

        self.path = check_output(path, force=force)
        # under the recording's lock; with force, written beside the old file and renamed over it at a complete end
        self._out = OutputStream(self.path, "replace" if force else "new", binary=True)
        self._file = self._out.file
        self._writer = Writer(self._file, chunk_size=chunk_size, compression=CompressionType.NONE)
        self._writer.start(profile="", library=f"flexdigit ({RECORDING_FORMAT})")
        self._channels: dict[str, int] = {}
        self._lock = threading.Lock()  # a live session writes samples and estimates from two threads
        self._sequence = 0
        self._closed = False
        self._flush_every_s = float(flush_every_s)
        self._flushed_at = time.monotonic()
        run = {"format": RECORDING_FORMAT, "started_unix_s": time.time(), **(header or {})}
        self.header = run
        self._writer.add_metadata("flexdigit.run", _metadata_text(run))
        for name, values in (metadata or {}).items():
            self._writer.add_metadata(str(name), _metadata_text(dict(values)))
        self.add_channel(SAMPLE_TOPIC, SAMPLE_SCHEMA)
        self.messages = 0

    def add_channel(self, topic: str, schema: dict[str, Any]) -> None:
        """Add a topic with its JSON Schema (``schema["title"]`` names it); adding it twice is a no-op."""
        if topic in self._channels:
            return
        if not isinstance(topic, str) or not topic.startswith("/"):
            raise ParameterError(f"The 'topic' parameter of Recording.add_channel must start with '/'. Got {topic!r}")
        name = str(schema.get("title", topic.strip("/").replace("/", ".")))
        schema_id = self._writer.register_schema(name, "jsonschema", json.dumps(schema).encode())
        self._channels[topic] = self._writer.register_channel(topic, "json", schema_id)

    def write(self, topic: str, time_s: float, message: dict[str, Any]) -> None:
        """Append one message (a JSON object) on ``topic`` at rig time ``time_s`` (s, >= 0)."""
        channel = self._channels.get(topic)
        if channel is None:
            raise ParameterError(f"Recording.write: unknown topic {topic!r}; add it with add_channel first")
        stamp = max(int(round(float(time_s) * 1e9)), 0)
        if stamp >= 2**64:  # MCAP's times are unsigned 64-bit nanoseconds: 584 years
            raise ParameterError(f"Recording.write: time {time_s!r} s is beyond MCAP's 2**64 ns (584 years)")
        data = json.dumps(message, allow_nan=False, separators=(",", ":")).encode()
        with signals_deferred(), self._lock:  # a stop signal waits for the record's end: never a torn record
            if self._closed:
                raise ParameterError(f"{self.path}: the recording is closed")
            self._writer.add_message(channel, log_time=stamp, data=data, publish_time=stamp, sequence=self._sequence)
            self._sequence += 1
            self.messages += 1
            now = time.monotonic()
            if now - self._flushed_at >= self._flush_every_s:  # close the chunk: a killed run keeps it
                self._flushed_at = now
                try:
                    self._writer.flush()
                except OSError as exc:  # a full disk: say which file
                    raise self._out.failed(exc) from exc

    def write_sample(self, record: dict[str, Any]) -> None:
        """Append a loop sample (:data:`SAMPLE_SCHEMA`) at its time ``record["t"]``."""
        self.write(SAMPLE_TOPIC, float(record["t"]), record)

    def flush(self) -> None:
        """Close the open chunk and push everything written to the disk (fsync)."""
        with self._lock:
            if self._closed:
                return
            try:
                self._writer.flush()
                self._file.flush()
                os.fsync(self._file.fileno())
            except OSError as exc:  # a full disk: say which file
                raise self._out.failed(exc) from exc

    def close(self, stop: dict[str, Any] | None = None) -> None:
        """Write the ``flexdigit.stop`` metadata, the summary and the footer, and close the file. Safe twice.

        Closed plainly (no ``stop`` of the caller's) while a stop signal is being taken (:mod:`flexdigit.interrupts`),
        the stop record says it was interrupted and names the signal."""
        stop = dict(stop or {})
        requested = stop_requested()
        if requested is not None and stop.get("stop", "closed") == "closed":
            stop = {**stop, "stop": "interrupted", "signal": requested.signal_name}
        with signals_deferred(), self._lock:
            self._close(stop)

    def _close(self, stop: dict[str, Any] | None) -> None:
        if self._closed:
            return
        stop = {"stop": "closed", **(stop or {})}
        try:
            self._writer.add_metadata("flexdigit.stop", _metadata_text(stop))
            self._writer.finish()
            # a run that stopped before its end leaves an old recording (--force) intact, itself in STEM.partial.mcap
            self.path = self._out.close(complete=stop["stop"] in ("closed", "completed"))
        except OSError as exc:
            self._out.abandon()
            raise self._out.failed(exc) from exc
        finally:
            self._closed = True
            self._out.abandon()  # no-op once closed

    @property
    def closed(self) -> bool:
        return self._closed

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close({"stop": "error", "message": f"{exc_type.__name__}: {exc}"} if exc_type else None)

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"Recording({str(self.path)!r}, topics={sorted(self._channels)}, messages={self.messages}, {state})"


def rig_metadata(rig) -> dict[str, dict[str, Any]]:
    """``flexdigit.rig`` metadata of an open rig: its repr and parameters (and, on the twin, its calibration)."""
    import dataclasses

    params = dataclasses.asdict(rig.params)
    twin_table = getattr(rig.params, "twin", None)
    if twin_table is not None and twin_table.is_default:  # [twin] left out: the metadata as before the table
        del params["twin"]
    out: dict[str, dict[str, Any]] = {"flexdigit.rig": {"rig": repr(rig), "name": rig.name, "params": params}}
    twin = getattr(rig, "twin", None)
    if twin is not None:
        out["flexdigit.rig"]["twin_calibration"] = twin.calibration.to_dict()
        out["flexdigit.rig"]["twin_seed"] = twin.seed
        out["flexdigit.rig"]["orientation"] = twin.orientation
    return out


class _Records:
    """Every record of an MCAP file in order, tolerating a file cut short by a killed run: iterating stops at the
    first record that cannot be read, and :attr:`stopped` then says why (None when the file was read to its end).

    Streamed: one chunk in memory at a time, each at most :data:`MAX_RECORD_BYTES` read and as much decompressed
    (a chunk claiming more, 2**62 bytes, is refused before anything is allocated)."""

    def __init__(self, path: Path) -> None:
        self.path, self.stopped = path, None

    def __iter__(self) -> Iterator[Any]:
        from mcap.exceptions import McapError
        from mcap.records import Chunk
        from mcap.stream_reader import StreamReader, breakup_chunk

        size = self.path.stat().st_size
        with open_input(self.path, "an MCAP recording", RECORDS_LIMIT) as fh:
            reader = StreamReader(_Bounded(fh, size, self.path), skip_magic=False, emit_chunks=True)
            try:
                for record in reader.records:
                    if isinstance(record, Chunk):
                        yield from breakup_chunk(self._decompressed(record, fh.tell()))
                    else:
                        yield record
            except DataFileError:
                raise  # refused, not cut short
            except (McapError, EOFError, ValueError, OverflowError, struct.error, RuntimeError) as exc:
                # the open chunk of a run that was killed: everything before it is kept (OverflowError: a length
                # inside a chunk damaged past 2**63, which the reader's in-memory stream cannot even ask for;
                # RuntimeError: zstandard's and lz4's errors on damaged compressed data)
                self.stopped = f"{type(exc).__name__}: {exc}"[:200]

    def _decompressed(self, chunk, end: int):
        """``chunk`` with its records decompressed, never more than it claims nor :data:`MAX_RECORD_BYTES`."""
        from mcap.records import Chunk

        at = end - len(chunk.data)
        if chunk.uncompressed_size > MAX_RECORD_BYTES:
            raise DataFileError(
                f"{self.path}: the chunk ending at byte {end:,} claims {chunk.uncompressed_size:,} bytes of records; "
                f"flexdigit reads chunks of at most {MAX_RECORD_BYTES:,} bytes: write it with smaller chunks"
            )
        if chunk.compression == "":
            return chunk
        if chunk.compression == "zstd":
            import zstandard

            # bounded by the claim even when the frame does not say its size (a streaming compressor's)
            try:
                data = zstandard.ZstdDecompressor().decompress(chunk.data, max_output_size=chunk.uncompressed_size)
            except zstandard.ZstdError as exc:  # damaged: read as a cut file
                raise ValueError(f"the zstd chunk near byte {at}: {exc}") from None
        elif chunk.compression == "lz4":
            import lz4.frame

            decompressor = lz4.frame.LZ4FrameDecompressor()
            data = decompressor.decompress(chunk.data, max_length=chunk.uncompressed_size)
            if not decompressor.eof:
                raise ValueError(
                    f"the lz4 chunk near byte {at} holds more than the {chunk.uncompressed_size} it claims"
                )
        else:
            raise DataFileError(
                f"{self.path}: a chunk compressed with {chunk.compression!r}; flexdigit reads none, zstd and lz4"
            )
        if len(data) != chunk.uncompressed_size:
            raise ValueError(
                f"the chunk near byte {at} holds {len(data)} bytes, not the {chunk.uncompressed_size} it claims"
            )
        return Chunk(
            compression="",
            data=data,
            message_start_time=chunk.message_start_time,
            message_end_time=chunk.message_end_time,
            uncompressed_crc=chunk.uncompressed_crc,
            uncompressed_size=chunk.uncompressed_size,
        )


def _records(path: Path) -> Iterator[Any]:
    return iter(_Records(path))


class _Bounded:
    """A binary file whose reads may not ask for more than it holds: a record length damaged into 2**60 would have
    the MCAP reader allocate that much (a MemoryError, found by tests/fuzz); it ends the records as a cut file. Nor
    more than :data:`MAX_RECORD_BYTES` at once: a record that large is refused naming the file."""

    def __init__(self, fh, size: int, path: Path | None = None) -> None:
        self._fh, self._size, self._path = fh, size, path

    def read(self, n: int = -1) -> bytes:
        if n is not None and n > self._size - self._fh.tell():
            raise EOFError("a record runs past the end of the file")
        if n is not None and n > MAX_RECORD_BYTES:
            raise DataFileError(
                f"{self._path}: a record of {n:,} bytes at byte {self._fh.tell():,}; flexdigit reads MCAP records "
                f"(chunks) of at most {MAX_RECORD_BYTES:,} bytes: write it with smaller chunks"
            )
        return self._fh.read(n)

    def __getattr__(self, item):
        return getattr(self._fh, item)


def iter_messages(path: str | os.PathLike, topics=None, *, records=None) -> Iterator[tuple[str, float, dict[str, Any]]]:
    """``(topic, time_s, message)`` for every message in ``path`` (optionally only ``topics``), in file order.

    Messages must be JSON (the channel's ``message_encoding`` "json"); another encoding on a wanted topic is refused
    naming the file and the topic.
    """
    from mcap.records import Channel, Message

    path = check_input(path, "an MCAP recording", RECORDS_LIMIT)  # a FIFO, a device: named, never read
    if not is_mcap(path):
        raise DataFileError(f"{path}: not an MCAP file (no MCAP magic at the start)")
    channels: dict[int, str] = {}
    wanted = None if topics is None else set(topics)
    for record in records if records is not None else _records(path):
        if isinstance(record, Channel):
            channels[record.id] = record.topic
            if (wanted is None or record.topic in wanted) and record.message_encoding != "json":
                raise DataFileError(
                    f"{path}: channel {record.topic} is encoded as {record.message_encoding!r}; "
                    "flexdigit reads JSON messages (message_encoding 'json')"
                )
        elif isinstance(record, Message):
            topic = channels.get(record.channel_id)
            if topic is None:
                raise DataFileError(f"{path}: a message on channel {record.channel_id}, which was never declared")
            if wanted is not None and topic not in wanted:
                continue
            try:
                message = json.loads(record.data)
            except ValueError:
                raise DataFileError(f"{path}: message {record.sequence} on {topic} is not JSON") from None
            except RecursionError:
                raise DataFileError(f"{path}: message {record.sequence} on {topic}: JSON nested too deep") from None
            yield topic, record.log_time * 1e-9, message


def read_metadata(path: str | os.PathLike) -> dict[str, dict[str, Any]]:
    """The metadata records of a recording, ``{name: {key: value}}`` (JSON text decoded)."""
    from mcap.records import Metadata

    return {r.name: _metadata_values(r.metadata) for r in _records(Path(path)) if isinstance(r, Metadata)}


def _check_sample(path: Path, i: int, message: Any, check_sample) -> dict[str, Any]:
    """One ``/flexdigit/sample`` message checked as the loop's logs are
    (:func:`flexdigit.rig.sample_log.check_sample`)."""
    if not isinstance(message, dict) or not {"t", "gauges_v", "command"} <= set(message):
        raise DataFileError(f"{path}: {SAMPLE_TOPIC} message {i} lacks t, gauges_v or command: {message!r:.120}")
    return check_sample(message, path, f"{SAMPLE_TOPIC} message {i}")


def read_recording(path: str | os.PathLike):
    """Read a recording as :func:`~flexdigit.rig.sample_log.read_log` reads a log: ``(header, samples, footer or
    None)``.

    ``header`` is the ``flexdigit.run`` metadata, ``samples`` the ``/flexdigit/sample`` messages (dicts with
    ``t``, ``gauges_v``, ``pot_v``, ``command`` ...), ``footer`` the ``flexdigit.stop`` metadata (None for a run
    that was killed before it closed the file). A recording another program wrote on the documented topic and
    schema (:data:`SAMPLE_SCHEMA`) needs no flexdigit metadata: its header is then ``{"format": None}``. Raises
    :class:`~flexdigit.errors.DataFileError` naming the file when it holds no samples, a sample breaks the schema,
    or its ``flexdigit.run`` metadata is of another format.
    """
    samples: list[dict[str, Any]] = []
    header, footer = _read_samples(Path(path), samples.append)
    return header, samples, footer


def read_recording_columns(path: str | os.PathLike):
    """:func:`read_recording` into columns (:class:`~flexdigit.rig.sample_log.SampleColumns`, 64 bytes a sample):
    ``(header, columns, footer or None)``, streamed a chunk at a time."""
    columns = SampleColumns(path)
    header, footer = _read_samples(Path(path), columns.append)
    return header, columns.arrays(), footer


def _read_samples(path: Path, keep):
    """Stream the recording's samples, checked, to ``keep``; its header and footer (see :func:`read_recording`)."""
    from mcap.records import Metadata

    records = _Records(path)
    meta: dict[str, dict[str, Any]] = {}

    def collecting():
        for record in records:
            if isinstance(record, Metadata):
                meta[record.name] = _metadata_values(record.metadata)
            yield record

    count = 0
    for _, _, message in iter_messages(path, topics=[SAMPLE_TOPIC], records=collecting()):
        count += 1
        keep(_check_sample(path, count, message, check_sample))
    header = meta.get("flexdigit.run")
    if header is not None and header.get("format") != RECORDING_FORMAT:
        raise DataFileError(
            f"{path}: a recording of format {header.get('format')!r}; this flexdigit reads {RECORDING_FORMAT}"
        )
    if not count:
        why = f" (the file is damaged or cut short: {records.stopped})" if records.stopped else ""
        raise DataFileError(f"{path}: no {SAMPLE_TOPIC} messages: not a flexdigit recording{why}")
    return header if header is not None else {"format": None}, meta.get("flexdigit.stop")


#: JSON Schema of what happens to the rig besides its samples (weights hung, lifted, re-hung).
EVENT_TOPIC = "/flexdigit/event"
EVENT_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "flexdigit.Event",
    "description": "A change to the rig that is not a command: a weight hung (kg, m from the base), lifted, re-hung.",
    "type": "object",
    "properties": {
        "t": {"type": "number"},
        "event": {"enum": ["load", "clear", "rehang"]},
        "mass_kg": _NULLABLE,
        "position_from_base_m": _NULLABLE,
    },
    "required": ["t", "event"],
}


def recording_rig(rig, recording: Recording):
    """``rig`` with every reading it returns recorded as a sample, and its loads as events.

    For code that drives a rig without a loop (the tactile protocols' ``collect``): closing the returned rig
    closes ``rig`` (safe command, port) and then the recording.
    """
    recording.add_channel(EVENT_TOPIC, EVENT_SCHEMA)

    class RecordingRig(Rig):
        name = f"{rig.name} (recorded)"

        def __init__(self) -> None:
            super().__init__(rig.params, clock=rig.clock, sleep=rig.wait, operator=lambda message: None)
            self.inner, self.recording, self._k = rig, recording, 0

        def read(self):
            reading = self.inner.read()
            pot = reading.pot_v if reading.pot_v == reading.pot_v else None  # NaN: no pot channel
            gauges = [float(g) if g == g else None for g in reading.gauges_v]
            sample = {"k": self._k, "t": reading.time_s, "gauges_v": gauges, "pot_v": pot, "command": reading.command}
            self.recording.write_sample(sample)
            self._k += 1
            return reading

        def _read(self):  # pragma: no cover - read() is overridden
            raise NotImplementedError

        def _send(self, command: int) -> None:
            self.inner.write_command(command)

        # the wrapped rig's nature and settings are this one's: a collection journals them and compares them on
        # resume, and replays a deterministic rig (tactile.runner)
        accepts_loads = property(lambda self: self.inner.accepts_loads)
        deterministic = property(lambda self: self.inner.deterministic)

        def settings(self):
            return self.inner.settings()

        def _event(self, event: str, mass=None, position=None) -> None:
            self.recording.write(
                EVENT_TOPIC, self.inner.clock(),
                {"t": self.inner.clock(), "event": event, "mass_kg": mass, "position_from_base_m": position},
            )  # fmt: skip

        def _apply_load(self, mass_kg: float, position_from_base_m: float) -> None:
            self.inner.place_load(mass_kg, position_from_base_m)
            self._event("load", mass_kg, position_from_base_m)

        def _remove_loads(self) -> None:
            self.inner.clear_loads()
            self._event("clear")

        def _rehang(self, settle_s: float) -> None:
            self.inner.rehang(settle_s)
            self._event("rehang")

        def _close(self) -> None:
            try:
                self.inner.close()
            finally:
                self.recording.close({"stop": "closed"})

        def __getattr__(self, item):  # the inner rig's extras (the twin, its true rotation)
            if item == "inner":
                raise AttributeError(item)
            return getattr(self.inner, item)

    return RecordingRig()

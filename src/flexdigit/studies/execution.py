"""Running a study's evaluations: serially or on Dask distributed, seeded, resumable, failures kept apart.

A study is a table of rows (parameter values) and a list of metrics. Rows are cut into blocks of ``chunk_size``
rows (a fixed number from the spec, never from the worker count, so the same blocks run whatever the cluster);
each block is evaluated in a fresh process-local context and gives one record per row. On Dask a task evaluates
several consecutive blocks, one after the other (:func:`task_sizes`: fewer tasks, and the values the metrics keep
by their inputs shared between neighbouring blocks as in the process). Randomness inside a block comes only
from generators seeded by the study's seed and the block's key (or the study's seed alone, for the common random
numbers of :mod:`flexdigit.studies.metrics`), so a serial run, a run on 2 workers and a run on 20 give the same
numbers, record for record.

Execution (:func:`run_rows`):

- ``workers=0``: in this process, no Dask (the reference);
- otherwise on Dask distributed: a ``LocalCluster`` on 127.0.0.1 with ``workers`` single-threaded worker
  processes (one per core by default), or an existing cluster's scheduler (``scheduler="tcp://HOST:PORT"``).
  flexdigit runs no process pool of its own.

Every finished task's records are appended to a journal (``journal.jsonl`` in the study's directory: a header line
with the study's fingerprint, then one line per row, flushed and fsynced; each row carries a CRC-32 of its canonical
JSON and the study's fingerprint, so a row edited, renumbered, copied from another study, duplicated or outside
the design is refused naming the file and line, and a line cut short by a
kill is dropped and computed again; a journal of format 1, without checksums, is refused: its rows cannot be
checked, ``--force`` starts over), so a study killed at any point resumes
where it stopped when rerun with the same spec and directory; a journal written by a study with other settings
is refused, never mixed (``--force`` starts over). A row whose evaluation raises is recorded with its error and
its parameters and the study goes on; a task whose worker dies (Dask gives up on it once the workers it ran on
died, ``KilledWorker``) or that could not run is recorded the same way for each of its rows, its error starting
with :data:`TASK_FAILED`: such rows are not results (the rig did not refuse them), so a rerun computes them again,
keeping every other row. A study never waits for ever: a cluster left with no worker for
:data:`NO_WORKER_GRACE_S` (none restarted, or a lost result with no worker to compute it again) ends it in one
line, every finished row journalled, and a rerun resumes. A progress bar goes to stderr.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import sys
import time
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexdigit._io import LOG_LIMIT, atomic_write, output_lock, read_bytes
from flexdigit._system import available_cores, check_workers
from flexdigit.errors import DataFileError, OutputError, ParameterError
from flexdigit.interrupts import raise_if_stopping, signals_deferred
from flexdigit.studies.metrics import MetricContext, evaluate_many

__all__ = [
    "Journal",
    "RowRecord",
    "evaluate_rows",
    "evaluate_blocks",
    "task_sizes",
    "run_rows",
    "run_study",
    "parse_scheduler",
    "check_scheduler_greets",
    "retry_rows",
    "JOURNAL_NAME",
    "TASK_FAILED",
]

JOURNAL_NAME = "journal.jsonl"
#: 2: each row carries its checksum (``crc``); 1 (before it) is refused, its rows cannot be checked.
JOURNAL_FORMAT = 2
#: Memory one local Dask worker process holds, bytes, for the cap on ``workers`` (:func:`flexdigit._system.
#: check_workers`): its imports alone take 120 MB (numpy, scipy, distributed, the twin), a task's models more.
WORKER_BYTES = 512 * 2**20
#: How the error of a row whose task failed (not the row itself: a worker died, the task could not run) begins
TASK_FAILED = "task failed: "


@dataclass(frozen=True)
class RowRecord:
    """One evaluated row: metric values, or the error that stopped it (``values`` then empty)."""

    row: int
    values: dict
    error: str | None = None
    seconds: float = 0.0

    @property
    def done(self) -> bool:
        """A result (values or the row's own error), not a failed task's placeholder to compute again."""
        return not (self.error or "").startswith(TASK_FAILED)

    def to_json(self) -> dict:
        values = {k: (v if math.isfinite(v) else repr(v)) for k, v in self.values.items()}
        return {"row": self.row, "values": values, "error": self.error, "seconds": round(self.seconds, 6)}

    @classmethod
    def from_json(cls, data: dict) -> RowRecord:
        values = {k: float(v) for k, v in data["values"].items()}  # 'inf' / 'nan' round-trip through float()
        return cls(int(data["row"]), values, data.get("error"), float(data.get("seconds", 0.0)))


def evaluate_rows(build, rows, values, metrics, context: MetricContext, task_key: int, seed: int) -> list[RowRecord]:
    """Evaluate rows of a study (the task every worker runs).

    Parameters
    ----------
    build : callable
        ``build(values_row, label) -> ParameterSet`` (e.g. :meth:`StudySpec.parameter_set`).
    rows : sequence of int
        The rows' indices in the study's table.
    values : array_like, shape (len(rows), d)
    metrics : sequence of str
    context : MetricContext
    task_key, seed : int
        The task's key and the study's seed; the only generator a task may use is
        ``numpy.random.default_rng([seed, task_key])`` (handed to ``build`` as ``rng`` when it takes one).
    """
    from threadpoolctl import threadpool_limits

    out: list[RowRecord] = []
    with threadpool_limits(1):  # one core per worker: BLAS threads would fight the other workers
        start = time.perf_counter()
        built, sets = [], []
        for i, row in enumerate(rows):
            try:
                sets.append(build(values[i], f"row {int(row)}"))
                built.append(int(row))
            except Exception as exc:  # noqa: BLE001 - a row the rig refuses is that row's result
                raise_if_stopping(exc)  # (a stop is not)
                out.append(RowRecord(int(row), {}, _message(exc)))
        results = evaluate_many(sets, metrics, context)
        each = (time.perf_counter() - start) / max(1, len(rows))
        for row, res in zip(built, results, strict=True):
            if isinstance(res, Exception):
                out.append(RowRecord(row, {}, _message(res), each))
            else:
                out.append(RowRecord(row, res, None, each))
    return sorted(out, key=lambda r: r.row)


def _message(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


class Journal:
    """The append-only record of a study's finished rows (see the module docstring).

    Parameters
    ----------
    path : Path
    header : dict
        The study's identity (its ``fingerprint`` decides whether an existing journal may be extended).
    force : bool
        Start over: an existing journal is replaced.
    """

    def __init__(self, path: Path, header: dict, *, force: bool = False, design=None) -> None:
        self.path = Path(path)
        self.header = {"flexdigit_study_journal": JOURNAL_FORMAT, **header}
        self.records: dict[int, RowRecord] = {}
        #: The study's rows of parameter values: a journalled row number outside them is refused (None: not checked).
        self.design = None if design is None else np.asarray(design, dtype=float)
        if self.path.exists() and not force:
            self._read()
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # an exclusive, unpredictable temporary file: a symlink planted at a fixed name is never followed
            with atomic_write(self.path, "w", force=True) as fh:
                fh.write(json.dumps(self.header, sort_keys=True) + "\n")

    def _read(self) -> None:
        text = read_bytes(self.path, "a study journal", LOG_LIMIT)
        lines = text.split(b"\n")
        complete, tail = lines[:-1], lines[-1]
        if not complete:
            raise DataFileError(f"{self.path}: not a study journal (no header line)")
        try:
            header = json.loads(complete[0])
        except (json.JSONDecodeError, RecursionError):  # RecursionError: brackets nested past the parser's depth
            raise DataFileError(f"{self.path}: line 1 is not a study journal header") from None
        if isinstance(header, dict) and header.get("flexdigit_study_journal") == 1:
            raise DataFileError(
                f"{self.path}: a study journal of format 1 (written before rows carried checksums): its rows cannot "
                "be checked; --force starts the study over"
            )
        if not isinstance(header, dict) or header.get("flexdigit_study_journal") != JOURNAL_FORMAT:
            raise DataFileError(f"{self.path}: line 1 is not a flexdigit study journal header")
        if header.get("fingerprint") != self.header.get("fingerprint"):
            raise DataFileError(
                f"{self.path}: written by a study with other settings (fingerprint {header.get('fingerprint')}, "
                f"this study {self.header.get('fingerprint')}); use another --out directory, or --force to start over"
            )
        lines: dict[int, int] = {}
        for number, line in enumerate(complete[1:], start=2):
            if not line.strip():
                continue
            try:
                data = json.loads(line)
                record = RowRecord.from_json(data)
                crc = data["crc"]
            except (json.JSONDecodeError, KeyError, TypeError, ValueError, AttributeError, RecursionError):
                raise DataFileError(f"{self.path}: line {number} is not a row record (with its checksum)") from None
            where = f"{self.path}: line {number}"
            if self.design is not None and not 0 <= record.row < len(self.design):
                raise DataFileError(
                    f"{where}: row {record.row} is outside the study's design (rows 0..{len(self.design) - 1}); the "
                    "journal was edited or mixed with another study's"
                )
            if crc != self._checksum(data):
                raise DataFileError(
                    f"{where}: row {record.row}'s checksum does not match its number and values (edited, renumbered "
                    "or copied from another study); --force starts the study over"
                )
            earlier = self.records.get(record.row)
            # a failed task's placeholder may follow any record of its row, and a result may follow a placeholder
            # (the rerun computes the row again); two results for one row are a duplicated line
            if earlier is not None and earlier.done and record.done:
                raise DataFileError(
                    f"{where}: row {record.row} again, already recorded on line {lines[record.row]} (a duplicated "
                    "line); --force starts the study over"
                )
            self.records[record.row] = record
            lines[record.row] = number
        if tail:  # a line cut short by a kill: drop it, the row is computed again
            with self.path.open("r+b") as fh:
                fh.truncate(len(text) - len(tail))

    def _checksum(self, data: dict) -> str:
        """CRC-32 (8 hex digits) of a row record's canonical JSON (without its ``crc``: its row number, values,
        error and time) and the study's fingerprint: a row is valid only as written, in its own study."""
        body = {k: v for k, v in data.items() if k != "crc"}
        text = json.dumps(body, sort_keys=True, separators=(",", ":")) + "|" + str(self.header.get("fingerprint"))
        return f"{zlib.crc32(text.encode()):08x}"

    def append(self, records) -> None:
        """Add finished rows (each with its checksum), flushed and fsynced before returning."""
        lines = ""
        for r in records:
            data = r.to_json()
            if self.design is not None and not 0 <= r.row < len(self.design):
                raise ParameterError(f"row {r.row} is outside the study's design (rows 0..{len(self.design) - 1})")
            lines += json.dumps({**data, "crc": self._checksum(data)}, sort_keys=True) + "\n"
        try:
            with signals_deferred(), self.path.open("a", encoding="utf-8") as fh:  # a stop waits for the rows' end
                fh.write(lines)
                fh.flush()
                os.fsync(fh.fileno())
        except OSError as exc:  # a full disk: say which file, and that a rerun resumes (a torn line is dropped)
            raise OutputError(
                f"{self.path}: cannot write it: {exc.strerror or exc}; the rows before are kept: free some space "
                "and rerun to resume"
            ) from exc
        for r in records:
            self.records[r.row] = r


_SCHEDULER = re.compile(r"^(tcp|tls|inproc|ucx)://[^\s/:]+(:\d{1,5})?$")


def parse_scheduler(url: str) -> str:
    """Check a Dask scheduler address such as ``tcp://127.0.0.1:8786`` and return it."""
    if not isinstance(url, str) or not _SCHEDULER.match(url):
        raise ParameterError(
            f"The 'scheduler' parameter must be a Dask scheduler address such as tcp://127.0.0.1:8786. Got {url!r} "
            "instead."
        )
    return url


#: How long a Dask scheduler has to accept a connection and greet it, s (each; every network wait has one).
SCHEDULER_TIMEOUT_S = 5.0
#: The largest greeting a Dask scheduler sends, bytes (its handshake is under 100 bytes): a longer first frame is
#: not a scheduler's, and distributed itself would allocate whatever length it claims (3 EiB from an HTTP reply).
MAX_GREETING_BYTES = 64 * 1024
#: Dask's default scheduler port, for an address without one.
DASK_PORT = 8786


def check_scheduler_greets(address: str, timeout_s: float = SCHEDULER_TIMEOUT_S) -> None:
    """Raise :class:`OSError` naming ``address`` unless a Dask scheduler answers there within ``timeout_s``.

    distributed's client waits for the scheduler's handshake without a deadline (a server that accepts and stays
    silent hangs it forever, its ``timeout`` covers the connect only) and reads the handshake's 8-byte length
    header unchecked (a server answering HTTP or garbage makes it allocate exabytes). So before a ``Client`` is
    made, this opens a connection of its own, reads the greeting a scheduler sends unasked (distributed's TCP
    framing: a little-endian uint64 length, then a uint64 frame count and one uint64 length per frame, then the
    frames) with a timeout and checks that it is framed so, then closes it. Only ``tcp://`` addresses are checked;
    ``tls://`` and the others are left to distributed.
    """
    import socket
    import struct

    scheme, _, location = address.partition("://")
    if scheme != "tcp":
        return
    host, _, port = location.partition(":")
    port = int(port) if port else DASK_PORT

    def fail(why: str) -> OSError:
        return OSError(f"{address}: not a Dask scheduler: {why}; expected a scheduler's address (dask scheduler)")

    deadline = time.monotonic() + timeout_s

    def receive(sock, n: int) -> bytes:
        data = b""
        while len(data) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise fail(f"no greeting within {timeout_s:g} s of connecting")
            sock.settimeout(left)
            try:
                chunk = sock.recv(n - len(data))
            except TimeoutError:
                raise fail(f"no greeting within {timeout_s:g} s of connecting") from None
            if not chunk:
                raise fail(f"the connection was closed after {len(data)} bytes of its greeting")
            data += chunk
        return data

    try:
        sock = socket.create_connection((host, port), timeout=timeout_s)
    except OSError as exc:
        raise OSError(f"cannot reach the Dask scheduler at {address}: {exc.strerror or exc}") from None
    with sock:
        try:
            (length,) = struct.unpack("<Q", receive(sock, 8))
            if not 16 <= length <= MAX_GREETING_BYTES:
                raise fail(
                    f"its first message claims {length} bytes (a scheduler's greeting is 16..{MAX_GREETING_BYTES})"
                )
            body = receive(sock, length)
        except OSError as exc:
            if str(exc).startswith(address):
                raise
            raise fail(f"{exc.strerror or exc}") from None
    (count,) = struct.unpack_from("<Q", body)
    if (
        not 1 <= count <= (length - 8) // 8
        or 8 * (1 + count) + sum(struct.unpack_from(f"<{count}Q", body, 8)) != length
    ):
        raise fail("its first message is not framed as distributed frames its messages")


@contextlib.contextmanager
def dask_client(scheduler: str | None, workers: int):
    """A Dask ``Client``: on an existing scheduler (checked first: :func:`check_scheduler_greets`), or on a local
    cluster of ``workers`` processes (127.0.0.1)."""
    import dask
    from distributed import Client, LocalCluster

    from flexdigit.studies._warm_worker import DASK_CONFIG

    with _quiet_distributed(), dask.config.set(DASK_CONFIG):
        yield from _client(Client, LocalCluster, scheduler, workers)


@contextlib.contextmanager
def _quiet_distributed():
    """distributed's own log records (a lost connection's traceback, its reconnection attempts) kept off the
    terminal: what went wrong reaches the user as one line of ours."""
    import logging

    loggers = [logging.getLogger(name) for name in ("distributed", "distributed.client", "distributed.comm")]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels, strict=True):
            lg.setLevel(level)


def _client(Client, LocalCluster, scheduler, workers):  # noqa: N803 - the classes, imported by the caller
    if scheduler:
        check_scheduler_greets(parse_scheduler(scheduler))
        try:
            client = Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S:g}s")
        except OSError as exc:
            why = str(exc) or f"{type(exc).__name__}: no answer within {SCHEDULER_TIMEOUT_S:g} s"
            raise OSError(f"cannot reach the Dask scheduler at {scheduler}: {why}") from None
        try:
            yield client
        finally:
            client.close()
        return
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
        silence_logs=40,
    )
    client = Client(cluster)
    try:
        yield client
    finally:
        client.close()
        cluster.close()


def _progress(total: int, done: int, enabled: bool, label: str):
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    progress = Progress(
        TextColumn(f"[bold]{label}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        disable=not enabled,
        transient=False,
    )
    task = progress.add_task(label, total=total, completed=done)
    return progress, task


def run_rows(
    build,
    values,
    metrics,
    context: MetricContext,
    journal: Journal,
    *,
    seed: int,
    chunk_size: int = 8,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    label: str = "study",
) -> dict[int, RowRecord]:
    """Evaluate every row of ``values`` not yet in ``journal``; return all records by row.

    Parameters
    ----------
    build : callable
        ``build(values_row, label) -> ParameterSet``; must pickle (a bound method of a :class:`StudySpec` does).
    values : ndarray, shape (n, d)
    metrics : sequence of str
    context : MetricContext
    journal : Journal
    seed : int
        The study's seed (with each task's key, the seed of the task's generator).
    chunk_size : int
        Rows per task.
    workers : int, optional
        0: in this process; N: a local Dask cluster of N worker processes (default: one per core).
    scheduler : str, optional
        An existing Dask scheduler's address (``tcp://HOST:PORT``); ``workers`` is then ignored.
    progress : bool
        Show a progress bar on stderr.
    """
    values = np.asarray(values, dtype=float)
    n = values.shape[0]
    chunks = [np.arange(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    todo = [(key, rows) for key, rows in enumerate(chunks) if any(not _done(journal, r) for r in rows)]
    if workers is None:
        workers = available_cores()
    if not scheduler:
        check_workers(workers, "workers", WORKER_BYTES)
    bar, task = _progress(n, n - sum(len(r) for _, r in todo), progress and bool(todo), label)
    metrics = list(metrics)
    with bar:
        if not todo:
            return dict(journal.records)
        args = (build, values, metrics, context, journal, todo, seed, bar, task)
        if workers == 0 and not scheduler:
            _run_in_process(*args)
        else:
            _run_on_dask(*args, scheduler=scheduler, workers=workers, label=label)
    return dict(journal.records)


def _run_in_process(build, values, metrics, context, journal: Journal, todo, seed: int, bar, task) -> None:
    """:func:`run_rows`'s tasks one after the other in this process, each journalled as it ends."""
    for key, rows in todo:
        records = evaluate_rows(build, rows, values[rows], metrics, context, key, seed)
        journal.append(_new(journal, records))
        bar.update(task, advance=len(rows))


#: Rows one Dask task evaluates at most (its blocks, :func:`task_sizes`): about 2-4 s of the shipped metrics, so a
#: killed worker loses little and the journal and progress bar move every few seconds.
TASK_ROWS_MAX = 256
#: A Dask task takes at most this share of the blocks still to submit per worker thread (guided self-scheduling):
#: large tasks while much is left, single blocks at the end, so the workers finish within about a block of each
#: other.
TASK_SHARE = 4


def task_sizes(blocks: int, slots: int, chunk_size: int) -> list[int]:
    """How many consecutive blocks each Dask task of a study evaluates, in submission order.

    A task of several blocks keeps, on its worker, the values the metrics keep by their inputs
    (:func:`flexdigit.studies.metrics._kept`) from one block to the next, as the process does: in a Saltelli
    design a row repeats its base sample's row, usually in a neighbouring block, which a worker computed again
    when the blocks alternated between workers (on 2 workers 8-12 % more H-infinity and tactile evaluations than
    in process, shipped tolerances, N = 32). Fewer tasks also wake the client, the scheduler and the workers'
    event loops fewer times. Sizes: ``ceil(left / (TASK_SHARE * slots))`` blocks, at least 1 and at most
    :data:`TASK_ROWS_MAX` rows, so the tasks shrink to single blocks as the study ends. Each block is still
    evaluated alone (:func:`evaluate_blocks`): the numbers are those of the process, whatever the sizes.
    """
    cap = max(1, TASK_ROWS_MAX // max(1, chunk_size))
    sizes, left = [], int(blocks)
    while left > 0:
        size = min(cap, left, max(1, math.ceil(left / (TASK_SHARE * max(1, slots)))))
        sizes.append(size)
        left -= size
    return sizes


def evaluate_blocks(build, blocks, metrics, context: MetricContext, seed: int) -> list[RowRecord]:
    """:func:`evaluate_rows` on each of ``blocks`` (``(task_key, rows, values)``, consecutive blocks of a study)
    in turn, in one process: a Dask task of several blocks."""
    out: list[RowRecord] = []
    for key, rows, values in blocks:
        out += evaluate_rows(build, rows, values, metrics, context, key, seed)
    return out


def _run_on_dask(
    build, values, metrics, context, journal: Journal, todo, seed: int, bar, task, *, scheduler, workers, label
) -> None:
    """:func:`run_rows`'s blocks on a Dask cluster, several consecutive ones a task (:func:`task_sizes`), each
    task journalled as it ends. A task of several blocks that fails is run again block by block, so that only a
    block that fails alone (a worker died running it, or it could not run) journals its rows' failure; the run
    goes on."""
    with dask_client(scheduler, workers) as client:
        # every worker, and any that joins later (one restarted after a kill), warmed before its first task
        from flexdigit.studies._warm_worker import WarmWorker

        client.register_plugin(WarmWorker(build, values[:1], metrics, context), name=WarmWorker.name)
        # an existing cluster may get its workers after the study starts: wait for one, as before; from then on a
        # cluster left with none for NO_WORKER_GRACE_S ends the study (_ended)
        client.wait_for_workers(1)
        # the builder goes with every task (6.6 kB pickled for the shipped spec), neither scattered (scattered data
        # dies with the workers holding it: every task after a worker death would fail) nor a task of its own (the
        # first tasks, submitted while the scheduler saw too few to queue them, all went to the worker holding it)
        prefix = f"{label}-{journal.header.get('fingerprint', '')}"
        slots = sum(client.nthreads().values()) or max(1, workers or 1)

        def submit(blocks, priority):
            payload = [(key, rows, values[rows]) for key, rows in blocks]
            fut = client.submit(evaluate_blocks, build, payload, metrics, context, seed, priority=priority,
                                key=f"{prefix}-{blocks[0][0]}-{len(blocks)}", pure=False, retries=0)  # fmt: skip
            futures[fut] = blocks
            return fut

        futures = {}
        sizes = task_sizes(len(todo), slots, max(len(rows) for _, rows in todo))
        # run in this order (the scheduler's own order of independent tasks is not the submission's): the small
        # tasks last, where they even out the workers' ends
        for i, end in enumerate(np.cumsum(sizes)):
            submit(todo[end - sizes[i] : end], priority=len(sizes) - i)
        while futures:
            for fut in _ended(client, futures, scheduler, journal):
                try:
                    records = fut.result(timeout=WORKER_CHECK_S)
                except Exception as exc:  # noqa: BLE001 - a worker died or the task could not run: keep going
                    if client.status != "running":  # not the task: the scheduler is gone, every task with it
                        _scheduler_lost(client, scheduler, journal)
                    if not fut.done() or (isinstance(exc, TimeoutError) and fut.status == "finished"):
                        continue  # its result died with the worker holding it (Dask computes it again), or is slow
                    blocks = futures.pop(fut)
                    if len(blocks) > 1:  # which block? each alone, again
                        for block in blocks:
                            submit([block], priority=len(sizes) + 1)
                        continue
                    message = f"{TASK_FAILED}{type(exc).__name__}: {exc}".splitlines()[0]
                    records = [RowRecord(int(r), {}, message) for r in blocks[0][1]]
                else:
                    blocks = futures.pop(fut)
                journal.append(_new(journal, records))
                bar.update(task, advance=sum(len(rows) for _, rows in blocks))


#: How long a study waits on its tasks between two looks at its cluster, s: it then checks that the scheduler
#: still has a worker (:func:`_ended`). A task may run for any time; only a cluster with no worker ends a study.
WORKER_CHECK_S = 2.0
#: How long a study's cluster may have no worker at all before the study gives up, s (:func:`_workers_lost`): a
#: nanny restarts a dead worker within seconds, and within tens of seconds on a loaded machine (imports, the warm
#: row); past this none is coming (the nanny could not restart it, or an existing cluster lost every worker), and
#: waiting on would hang the study for ever.
NO_WORKER_GRACE_S = 120.0


def _ended(client, futures, scheduler, journal: Journal) -> list:
    """The futures among ``futures`` that have ended (finished, failed or cancelled), waiting for at least one in
    slices of :data:`WORKER_CHECK_S`; between slices, the study ends with :func:`_scheduler_lost` when the
    scheduler is gone and with :func:`_workers_lost` when it has had no worker for :data:`NO_WORKER_GRACE_S`."""
    from distributed import wait

    alone_since = None
    while True:
        with contextlib.suppress(Exception):  # a slice without an end (TimeoutError), or futures cancelled
            wait(list(futures), timeout=WORKER_CHECK_S, return_when="FIRST_COMPLETED")
        ended = [fut for fut in futures if fut.done()]
        if ended:
            return ended
        if client.status != "running":
            _scheduler_lost(client, scheduler, journal)
        try:
            workers = client.nthreads()
        except OSError:
            _scheduler_lost(client, scheduler, journal)
        if workers:
            alone_since = None
            continue
        alone_since = time.monotonic() if alone_since is None else alone_since
        if time.monotonic() - alone_since >= NO_WORKER_GRACE_S:
            _workers_lost(client, scheduler, journal)


def _scheduler_lost(client, scheduler, journal: Journal):
    """Raise the one line that says the scheduler vanished mid-study (its futures were cancelled: they are not the
    rows' failures, nothing of them is journalled) and that a rerun resumes."""
    address = scheduler or getattr(client.scheduler, "address", "the local cluster")
    done = sum(1 for r in journal.records.values() if r.done)
    raise OSError(
        f"the Dask scheduler at {address} vanished mid-study ({done} rows journalled in {journal.path}); start it "
        "again and rerun the same command to resume"
    ) from None


def _workers_lost(client, scheduler, journal: Journal):
    """Raise the one line that says the study's cluster has had no worker for :data:`NO_WORKER_GRACE_S` (every
    finished row is in the journal, the tasks still out are not the rows' failures) and that a rerun resumes."""
    address = scheduler or getattr(client.scheduler, "address", "the local cluster")
    done = sum(1 for r in journal.records.values() if r.done)
    raise OSError(
        f"the Dask cluster at {address} has had no worker for {NO_WORKER_GRACE_S:g} s: its workers died and none "
        f"came back ({done} rows journalled in {journal.path}); start workers (or check the machine's memory) and "
        "rerun the same command to resume"
    ) from None


def _new(journal: Journal, records) -> list[RowRecord]:
    """The records of a task whose rows are not yet done: a task retried for one failed row evaluates its whole
    chunk again (the same numbers, seeded by the task's key), but a row already done is recorded once."""
    return [r for r in records if not _done(journal, r.row)]


def _done(journal: Journal, row) -> bool:
    record = journal.records.get(int(row))
    return record is not None and record.done


def retry_rows(out_dir) -> int:
    """How many rows of the study journaled in ``out_dir`` a rerun would compute again (their task failed); 0 when
    there is no journal."""
    path = Path(out_dir) / JOURNAL_NAME
    if not path.is_file():
        return 0
    failed = set()
    for line in path.read_bytes().split(b"\n")[1:]:
        with contextlib.suppress(json.JSONDecodeError, KeyError, TypeError, ValueError, AttributeError, RecursionError):
            record = RowRecord.from_json(json.loads(line))
            (failed.discard if record.done else failed.add)(record.row)
    return len(failed)


def run_study(
    build,
    values,
    metrics,
    context,
    out_dir,
    header: dict,
    *,
    seed: int,
    chunk_size: int,
    workers=None,
    scheduler=None,
    force: bool = False,
    progress: bool = True,
    label: str = "study",
):
    """:func:`run_rows` with the study's journal in ``out_dir``; returns ``(outputs, errors)``: per metric an array
    over the rows (NaN where a row failed) and per row its error or None."""
    Path(out_dir).mkdir(parents=True, exist_ok=True)  # the lock file lives beside the journal
    with output_lock(Path(out_dir) / JOURNAL_NAME):  # one study writes a journal at a time: never mixed
        journal = Journal(Path(out_dir) / JOURNAL_NAME, header, force=force, design=values)
        records = run_rows(
            build,
            values,
            metrics,
            context,
            journal,
            seed=seed,
            chunk_size=chunk_size,
            workers=workers,
            scheduler=scheduler,
            progress=progress,
            label=label,
        )
    n = len(values)
    outputs = {m: np.array([records[i].values.get(m, math.nan) for i in range(n)]) for m in metrics}
    return outputs, [records[i].error for i in range(n)]


def warn(message: str) -> None:
    """One line on stderr (failed rows, unconverged indices): the result is kept, the user is told."""
    print(f"flexdigit study: {message}", file=sys.stderr)

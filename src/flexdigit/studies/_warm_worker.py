"""The Dask worker plugin that warms and tunes a study's workers (imported only when a study runs on Dask:
distributed is a heavy import the in-process path never pays)."""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys

import numpy as np
from distributed.diagnostics.plugin import WorkerPlugin
from threadpoolctl import threadpool_limits

from flexdigit.studies.metrics import evaluate_many

__all__ = [
    "WarmWorker",
    "tune_worker",
    "tuning_state",
    "DASK_CONFIG",
    "WORKER_INTERVALS_S",
    "MALLOC_THRESHOLDS_BYTES",
]

#: The longest period, s, of a worker's housekeeping callbacks during a study (distributed's defaults: the event
#: loop's health tick 20 ms, the system monitor 500 ms, the memory monitor 100 ms). Each wakes the worker's event
#: loop, which takes the GIL from the task's thread: on 320 rows of the shipped spec one worker spent 5.65 s of CPU
#: with the defaults and 5.11 s with these, the process 4.85 s (2 cores, one run each; 2,845 voluntary context
#: switches against 816). A study's tasks hold kilobytes, so a memory check a second is ample.
WORKER_INTERVALS_S = {"tick": 1.0, "monitor": 5.0, "memory_monitor": 1.0}
#: glibc's mmap and trim thresholds, bytes, set on a worker whose nanny fixed ``MALLOC_TRIM_THRESHOLD_`` (its
#: default 65536, distributed's ``nanny.pre-spawn-environ``). Setting it at all freezes glibc's mmap threshold at
#: 128 KiB, so every array above that is mapped and unmapped afresh: 102,000 page faults on 160 rows against 760,
#: and 3.24 s of CPU against 2.80 s (one worker, one run each). These are glibc's own ceilings for its dynamic
#: thresholds on 64-bit (``DEFAULT_MMAP_THRESHOLD_MAX`` 32 MiB, the trim threshold twice the mmap one).
MALLOC_THRESHOLDS_BYTES = {"mmap": 32 * 2**20, "trim": 64 * 2**20}
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # mallopt's parameters (glibc's malloc.h)
#: distributed's settings for the local cluster a study starts (:func:`flexdigit.studies.execution.dask_client`:
#: its scheduler and nannies in the study's process, its workers spawned with them): no ``MALLOC_TRIM_THRESHOLD_``
#: from the nanny (:data:`MALLOC_THRESHOLDS_BYTES` says why), no sampling profiler, housekeeping at
#: :data:`WORKER_INTERVALS_S`. The workers of an existing cluster are tuned the same way as they are warmed.
DASK_CONFIG = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": f"{WORKER_INTERVALS_S['tick']:g}s",
    "distributed.admin.system-monitor.interval": f"{WORKER_INTERVALS_S['monitor']:g}s",
    "distributed.worker.memory.monitor-interval": f"{WORKER_INTERVALS_S['memory_monitor']:g}s",
}


class WarmWorker(WorkerPlugin):
    """As a worker starts (and any that joins later: one restarted after a kill), evaluate one row of the study,
    not journalled, so that its imports, the compiled kernels' caches, the baseline controller and a user metric's
    module are loaded before its first task; before it, a worker's first tasks ran several times slower than the
    process's. It also tunes the worker for numeric tasks (:func:`tune_worker`), however it was started. A row
    that fails here is left for its task to report. The row's values leave no trace in the study's numbers
    (:func:`flexdigit.studies.metrics.evaluate_many` starts every block afresh)."""

    name = "flexdigit-warm-worker"

    def __init__(self, build, row, metrics, context) -> None:
        self.build, self.row, self.metrics, self.context = build, np.asarray(row, dtype=float), list(metrics), context

    def setup(self, worker=None) -> None:
        tune_worker(worker)
        with threadpool_limits(1), contextlib.suppress(Exception):
            if self.row.size:
                evaluate_many([self.build(self.row[0], "warm-up")], self.metrics, self.context)


def tune_worker(dask_worker) -> dict:
    """Make a running worker spend its CPU on the study's tasks; return what was changed (for the tests).

    - distributed's sampling profiler (every 10 ms) stopped: 1 s of a worker's 6.5 s of CPU on 320 rows, where the
      process spent 4.8 s (a study's tasks are numeric loops, their profile tells no one more);
    - its housekeeping callbacks slowed to :data:`WORKER_INTERVALS_S` (never sped up);
    - glibc's malloc thresholds set to :data:`MALLOC_THRESHOLDS_BYTES` when the nanny set
      ``MALLOC_TRIM_THRESHOLD_`` (Linux with glibc only; elsewhere nothing).

    A worker started by :func:`flexdigit.studies.execution.dask_client` has all three from its configuration
    already (:data:`DASK_CONFIG`); ``dask worker`` processes get them here.
    """
    changed = {}
    callbacks = getattr(dask_worker, "periodic_callbacks", {})
    for name in ("profile", "profile-cycle"):
        callback = callbacks.pop(name, None)
        if callback is not None:
            callback.stop()
            changed[name] = None
    for name, period_s in WORKER_INTERVALS_S.items():
        callback = callbacks.get(name)
        if callback is not None and callback.callback_time < 1e3 * period_s:
            callback.callback_time = 1e3 * period_s  # tornado reads it when it schedules the next call
            changed[name] = period_s
    if os.environ.get("MALLOC_TRIM_THRESHOLD_") and sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):  # not glibc (musl has no mallopt): left as it is
            libc = ctypes.CDLL("libc.so.6")
            if libc.mallopt(_M_MMAP_THRESHOLD, MALLOC_THRESHOLDS_BYTES["mmap"]) and libc.mallopt(
                _M_TRIM_THRESHOLD, MALLOC_THRESHOLDS_BYTES["trim"]
            ):
                changed["malloc"] = dict(MALLOC_THRESHOLDS_BYTES)
    return changed


def tuning_state(dask_worker=None) -> dict:
    """What :func:`tune_worker` left on a worker (run it there: ``client.run(tuning_state)``): the periods of its
    housekeeping callbacks, ms; whether its sampling profiler runs; the nanny's ``MALLOC_TRIM_THRESHOLD_``; and
    the minor page faults of allocating, filling and freeing a 1 MiB array 64 times (about 16,000 when each is
    mapped afresh, a handful when the heap keeps them: Linux counts them; None elsewhere)."""
    import resource

    callbacks = getattr(dask_worker, "periodic_callbacks", {})
    faults = None
    with contextlib.suppress(AttributeError, OSError):
        before = resource.getrusage(resource.RUSAGE_THREAD).ru_minflt
        for _ in range(64):
            np.ones(2**17)  # 1 MiB of float64, written (a page faults when first written), then freed
        faults = resource.getrusage(resource.RUSAGE_THREAD).ru_minflt - before
    return {
        "periods_ms": {name: callbacks[name].callback_time for name in WORKER_INTERVALS_S if name in callbacks},
        "profiling": "profile" in callbacks,
        "malloc_trim_threshold": os.environ.get("MALLOC_TRIM_THRESHOLD_"),
        "page_faults": faults,
    }

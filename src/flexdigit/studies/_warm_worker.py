"""The Dask worker plugin that warms a study's workers (imported only when a study runs on Dask: distributed is
a heavy import the in-process path never pays)."""

from __future__ import annotations

import contextlib

import numpy as np
from distributed.diagnostics.plugin import WorkerPlugin
from threadpoolctl import threadpool_limits

from flexdigit.studies.metrics import evaluate_many

__all__ = ["WarmWorker"]


class WarmWorker(WorkerPlugin):
    """As a worker starts (and any that joins later: one restarted after a kill), evaluate one row of the study,
    not journalled, so that its imports, the compiled kernels' caches, the baseline controller and a user metric's
    module are loaded before its first task; before it, a worker's first tasks ran several times slower than the
    process's. It also stops the worker's sampling profiler. A row that fails here is left for its task to report.
    The row's values leave no trace in the study's numbers (:func:`flexdigit.studies.metrics.evaluate_many` starts
    every block afresh)."""

    name = "flexdigit-warm-worker"

    def __init__(self, build, row, metrics, context) -> None:
        self.build, self.row, self.metrics, self.context = build, np.asarray(row, dtype=float), list(metrics), context

    def setup(self, worker=None) -> None:
        # distributed's sampling profiler looks at the task's stack every 10 ms: 14 % more CPU for the same rows
        # on a worker than in process, measured (a study's tasks are numeric loops, its profile tells no one more)
        for name in ("profile", "profile-cycle"):
            callback = getattr(worker, "periodic_callbacks", {}).pop(name, None)
            if callback is not None:
                callback.stop()
        with threadpool_limits(1), contextlib.suppress(Exception):
            if self.row.size:
                evaluate_many([self.build(self.row[0], "warm-up")], self.metrics, self.context)

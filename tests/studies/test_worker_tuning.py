"""A study's Dask workers spend their CPU on its rows (issue 27): distributed's profiler off, its housekeeping
slowed, glibc's malloc left to keep arrays in the heap. What each costs, measured, is in
:mod:`flexdigit.studies._warm_worker`; the speed-up is in ``benchmarks/bench_dask.py`` (no timing here)."""

from types import SimpleNamespace

import pytest

from flexdigit.studies._warm_worker import WORKER_INTERVALS_S, tune_worker, tuning_state
from flexdigit.studies.execution import dask_client

#: See tests/studies/test_cluster.py: 64 arrays of 1 MiB mapped afresh fault 16,384 pages; kept in the heap ~220.
TUNED_PAGE_FAULTS = 4096


class Callback:
    def __init__(self, period_ms: float) -> None:
        self.callback_time, self.stopped = period_ms, False

    def stop(self) -> None:
        self.stopped = True


def test_tune_worker_stops_the_profiler_and_only_slows_housekeeping(monkeypatch):
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)  # no mallopt in the test's own process
    profile, tick, monitor = Callback(10), Callback(20), Callback(60_000)
    worker = SimpleNamespace(periodic_callbacks={"profile": profile, "tick": tick, "monitor": monitor})
    changed = tune_worker(worker)
    assert profile.stopped
    assert "profile" not in worker.periodic_callbacks
    assert tick.callback_time == 1e3 * WORKER_INTERVALS_S["tick"]
    assert monitor.callback_time == 60_000  # already slower than asked: left
    assert changed == {"profile": None, "tick": WORKER_INTERVALS_S["tick"]}


@pytest.mark.slow
def test_a_local_clusters_workers_start_tuned():
    with dask_client(None, 1) as client:
        (state,) = client.run(tuning_state).values()
    assert state["malloc_trim_threshold"] is None  # the nanny's MALLOC_TRIM_THRESHOLD_ not set
    assert state["page_faults"] < TUNED_PAGE_FAULTS
    assert not state["profiling"]
    assert state["periods_ms"] == {name: 1e3 * s for name, s in WORKER_INTERVALS_S.items()}

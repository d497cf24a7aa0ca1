"""A one-gauge linear digit with a drifting gauge and a thesis-6.1-like run of it: the drift tests' shared pieces
(tests/tactile/test_bayes_drift.py, tests/tactile/test_drift_limit.py)."""

from __future__ import annotations

import numpy as np

from flexdigit.tactile.dataset import Dataset, dataset_columns, make_meta
from flexdigit.tactile.protocols import Protocol


class Linear:
    """One gauge reading ``slope * m * a`` volts, white noise ``noise_v``, random-walk drift ``drift`` V/sqrt(s)."""

    def __init__(self, slope: float, noise_v: float, drift: float = 0.0) -> None:
        self.slope = slope
        self.noise_v = np.array([noise_v])
        self.drift_v_per_sqrt_s = np.array([drift])

    def gauges_v(self, a, m, command):
        a, m = np.broadcast_arrays(np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(m, float)))
        return (self.slope * m * a)[:, None]


def _run(tests: int = 2, positions: int = 6, reps: int = 5, no_load: int = 10, settle_s: float = 15.0) -> Dataset:
    """A thesis-6.1-like run on one gauge: per test a no-load block at its start, then ``positions`` positions
    each read ``reps`` times 20 ms apart after ``settle_s``; 1 kg at 0.05..0.15 m."""
    tips = tuple(np.round(np.linspace(0.05, 0.15, positions), 6))
    protocol = Protocol("run", (1.0,) * 1, tips, (), repetitions=reps, no_load_repetitions=no_load, settle_s=settle_s)
    rows, clock = [], 0.0
    for test in range(tests):
        clock += settle_s
        for _ in range(no_load):
            rows.append((test, 0.0, np.nan, clock))
            clock += 0.02
        for tip in tips:
            clock += settle_s
            for _ in range(reps):
                rows.append((test, 1.0, 0.2 - tip, clock))
                clock += 0.02
    test, load, base, time = (np.array(c) for c in zip(*rows, strict=True))
    cols = {c: np.zeros(test.size, dtype=d) for c, d in dataset_columns(1).items()}
    cols.update(sample=np.arange(test.size), test=test, load_kg=load, position_from_base_m=base, time_s=time)
    cols.update(position_from_tip_m=0.2 - base, command=np.full(test.size, -1))
    return Dataset(cols, make_meta(protocol, {}, 0.2, gauge_count=1))

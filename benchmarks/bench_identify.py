"""Identification benchmarks: a long record read and identified, step finding included.

- ``read``: :func:`read_timeseries` of a 30 s record at 2 kHz (60,000 CSV rows, 2 columns).
- ``identify step`` / ``identify release``: :func:`identify` (default lsq method: hum removal, spike search, the
  instant found from the signal, robust fit with drift, quality checks) on the same length of record: the
  servo's step (3.2.4: 20.53 rad/s, 0.5629) and the digit's release (3.1.2: 13.10 rad/s, 0.068), both with 1 %
  noise, 20 spikes, 50 Hz hum and a drift. Issue 11: "well under a second". Best of 3.
"""

from __future__ import annotations

import tempfile
import timeit
from pathlib import Path

import numpy as np


def _record(kind: str, wn: float, zeta: float, seed: int):
    from flexdigit.identify.fit import second_order_response

    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 30.0, 1 / 2000)
    y = second_order_response(t, kind, wn, zeta, 0.9, 0.4, 0.3) + 0.01 * t / 30
    y += 0.02 * np.sin(2 * np.pi * 50.0 * t + 0.3) + rng.normal(0.0, 0.004, t.size)
    y[rng.choice(t.size, 20, replace=False)] += 0.15
    return t, y


def run() -> list[dict]:
    from flexdigit.identify.identification import identify
    from flexdigit.identify.timeseries import TimeSeries, read_timeseries

    rows = []
    t, y = _record("step", 20.53, 0.5629, 0)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "long.csv"
        np.savetxt(path, np.column_stack([t, y]), delimiter=",", header="time_s,pot_v", comments="", fmt="%.9g")
        best = min(timeit.repeat(lambda: read_timeseries(path), number=1, repeat=3))
    rows.append(
        {"name": "read a 30 s record at 2 kHz (60,000 CSV rows)", "value": best, "unit": "s", "goal": "", "note": ""}
    )
    for kind, wn, zeta in (("step", 20.53, 0.5629), ("release", 13.0995, 0.06791)):
        series = TimeSeries.from_arrays(*_record(kind, wn, zeta, 1))
        result = identify(series, kind)
        best = min(timeit.repeat(lambda s=series, k=kind: identify(s, k), number=1, repeat=3))
        rows.append(
            {
                "name": f"identify {kind}, 30 s at 2 kHz (instant found, robust fit, checks)",
                "value": best,
                "unit": "s",
                "goal": "< 1",
                "note": f"wn {100 * (result.wn_rad_s / wn - 1):+.2f} %, zeta {100 * (result.zeta / zeta - 1):+.2f} %",
            }
        )
    return rows

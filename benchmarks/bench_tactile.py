"""Tactile benchmarks: collecting table 6.1 on the twin, the thesis's full network sweep, prediction latency.

- Collection: the 1275-reading protocol ``thesis-6.1`` on the ``sim`` rig (virtual time, the twin's 20 ms step),
  journal and Parquet included. The protocol settles 15 s after every one of its 51 settings (the twin's digit
  rings that long), so the twin integrates ~790 s of motion; also with the sim backend's 2 ms step, for
  information.
- Full sweep: coarse (5-60 step 5), fine (+-5 step 1) and learning-gradient (1e-1..1e-9) sweeps plus the final
  network, 50 epochs of 50 SCG iterations each, on both experiments' twin data (thesis-6.1, thesis-7.1 loaded).
- One network, side by side in this run: the thesis's 24-node network (50 epochs of 50 SCG iterations) trained by
  the numpy reference (NETLAB's scg on mlp_error/mlp_grad, :mod:`flexdigit.tactile.netlab`) and by the compiled
  kernel :class:`~flexdigit.tactile.netlab.MLP` uses (:mod:`flexdigit.tactile._scg_kernel`, compile excluded).
- Latency: a trained 24-node network (with its normalisers) predicting 100,000 readings in one call, per reading;
  and one reading per call, for information.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np


def run() -> list[dict]:
    from flexdigit.tactile.pipeline import ThesisNetwork, features, run_pipeline, targets
    from flexdigit.tactile.protocols import load_protocol
    from flexdigit.tactile.thesis_experiments import collect_on_twin

    rows = []
    tmp = Path(tempfile.mkdtemp())
    p61 = load_protocol("thesis-6.1")
    collect_on_twin(p61, tmp / "warm.parquet", settle_s=0.1)  # imports and the twin's model cache, not timed
    start = time.perf_counter()
    ds6 = collect_on_twin(p61, tmp / "d6.parquet")
    seconds = time.perf_counter() - start
    rows.append(
        {
            "name": f"collect thesis-6.1 on the twin ({len(ds6)} readings, 15 s settle)",
            "value": seconds,
            "unit": "s",
            "goal": "<= 10 s",
            "note": "the twin integrates ~790 s of a ringing digit (51 settings x 15 s settle) at its 20 ms step",
        }
    )
    from flexdigit.rig.base import open_rig
    from flexdigit.tactile.runner import collect

    rig = open_rig("sim", seed=0, orientation="horizontal", cable=False, dt_s=0.002)
    start = time.perf_counter()
    collect(p61, rig, tmp / "d6-2ms.parquet")
    rows.append(
        {
            "name": "collect thesis-6.1 on the twin at a 2 ms step",
            "value": time.perf_counter() - start,
            "unit": "s",
            "goal": "",
            "note": "the sim backend's default step (kept for the control loop); same settled readings to 0.1 mV",
        }
    )
    ds7 = collect_on_twin(load_protocol("thesis-7.1"), tmp / "d7.parquet")
    start = time.perf_counter()
    trainings = 0
    for ds in (ds6, ds7):
        sub = ds.subset(ds["load_kg"] > 0)
        _, y = targets(sub, "position_index")
        r = run_pipeline(features(sub), y, seed=0)
        trainings += len(r.coarse) + len(r.fine) + len(r.gradient) + 2
    rows.append(
        {
            "name": f"full thesis sweep, both experiments ({trainings} networks)",
            "value": time.perf_counter() - start,
            "unit": "s",
            "goal": "",
            "note": "coarse 5-60, fine +-5, gradient 1e-1..1e-9; 50 epochs x 50 SCG iterations each, early stopping",
        }
    )
    rows += _one_network_side_by_side(ds6)
    rng = np.random.default_rng(0)
    x = ds6.gauges_v
    net = ThesisNetwork(hidden=24, epochs=5).fit(x, rng.normal(size=len(x)))
    batch = x[rng.integers(0, len(x), 100_000)]
    net.predict(batch[:10])
    start = time.perf_counter()
    for _ in range(5):
        net.predict(batch)
    per = (time.perf_counter() - start) / (5 * len(batch))
    rows.append(
        {
            "name": "prediction latency, 24-node network, batched",
            "value": per * 1e6,
            "unit": "us/reading",
            "goal": "<= 20 us",
            "note": "100,000 readings per call, normalisation included",
        }
    )
    start = time.perf_counter()
    for i in range(2000):
        net.predict(batch[i : i + 1])
    rows.append(
        {
            "name": "prediction latency, one reading per call",
            "value": (time.perf_counter() - start) / 2000 * 1e6,
            "unit": "us/reading",
            "goal": "",
            "note": "input validation and numpy call overhead dominate",
        }
    )
    return rows


def _one_network_side_by_side(dataset) -> list[dict]:
    from flexdigit.tactile.netlab import MLP, mlp_error, mlp_grad, mlp_init, scg
    from flexdigit.tactile.pipeline import Normaliser, features, targets, thesis_split

    sub = dataset.subset(dataset["load_kg"] > 0)
    _, y = targets(sub, "position_index")
    x = features(sub)
    split = thesis_split(len(y), 0)
    xn = Normaliser().fit(x[split.train]).transform(x[split.train])
    t = Normaliser().fit(y[split.train][:, None]).transform(y[split.train][:, None])  # E 6.1, as the pipeline does
    MLP(hidden=24, epochs=1, iterations_per_epoch=5).fit(xn, t)  # compile (cached per machine), not timed
    start = time.perf_counter()
    MLP(hidden=24, tol=1e-7, epochs=50, iterations_per_epoch=50, random_state=0).fit(xn, t)
    compiled = time.perf_counter() - start
    w = mlp_init(3, 24, 1, np.random.default_rng(0))
    start = time.perf_counter()
    for _ in range(50):
        w, converged = scg(lambda v: mlp_error(v, xn, t, 24), lambda v: mlp_grad(v, xn, t, 24), w, 50, 1e-7, 1e-7)
        if converged:
            break
    reference = time.perf_counter() - start
    note = f"{len(t)} training readings, 2,500 SCG iterations"
    return [
        {
            "name": "one 24-node network, numpy reference (netlab.scg)",
            "value": reference,
            "unit": "s",
            "goal": "",
            "note": note,
        },
        {
            "name": "one 24-node network, compiled (MLP.fit)",
            "value": compiled,
            "unit": "s",
            "goal": "",
            "note": f"{reference / compiled:.1f}x the reference",
        },
    ]


if __name__ == "__main__":
    for row in run():
        print(row)

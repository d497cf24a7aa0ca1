"""Palpation benchmarks (issue 13): an estimate's latency and a full scan's time on the twin.

- Latency of one contact estimate from one reading (three gauges and the command): position, force and their
  standard deviations (point hypothesis, what force control runs every 20 ms frame), and with the point /
  distributed decision (the slower of a point reading and a line load's, whose standard deviations it adds); best
  of 5 runs of 200 calls, wall and CPU, tables built beforehand (not timed; their build is its own row).
- A full scan on the twin through the 20 ms loop: the nodule phantom at 9 offsets 10 mm apart, each a sweep of 12
  plateaus (2.5 s settle, 20 readings), the twin integrating at 10 ms; then the local fits and the inclusion fit.
  Also the same scan's analysis on the twin's statics (:func:`flexdigit.palpation.palpation.simulate_sweep`), which
  is what the report runs.
- One palpation sweep (23 plateaus) through the loop and its fit; 10 s of force control at the twin's 5 ms step.
"""

from __future__ import annotations

import time

import numpy as np


def _best(fn, number: int = 200, repeat: int = 5) -> tuple[float, float]:
    """Best wall and best CPU time per call (s) over ``repeat`` runs of ``number`` calls."""
    best, best_cpu = np.inf, np.inf
    for _ in range(repeat):
        start, cpu = time.perf_counter(), time.process_time()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - start) / number)
        best_cpu = min(best_cpu, (time.process_time() - cpu) / number)
    return best, best_cpu


def run() -> list[dict]:
    from flexdigit.palpation.contact_estimation import ContactEstimator, ContactGaugeModel
    from flexdigit.palpation.palpation import PalpationProtocol, hold_force, palpate, run_sweep, scan, simulate_sweep
    from flexdigit.palpation.palpation_files import load_palpation_protocol, load_tissue
    from flexdigit.rig.base import open_rig

    rows = []
    model = ContactGaugeModel()
    start = time.perf_counter()
    point = ContactEstimator(model, commands=[20], classify=False).fit()
    table_s = time.perf_counter() - start
    start = time.perf_counter()
    both = ContactEstimator(model, commands=[20]).fit()
    line_s = time.perf_counter() - start
    noise = model.noise_v * np.random.default_rng(0).standard_normal((1, 3))
    reading = model.point_v([0.2], [-0.1], 20) + noise
    line = model.line_v([0.2], [0.08], [-0.3], 20) + noise
    both.predict(reading, 20)  # loads the compiled kernels (numba's cache), not timed
    # a line entry's derivatives are computed the first time a reading is declared there (timed here, not below)
    start = time.perf_counter()
    assert both.predict(line, 20).kind[0] == "distributed"
    derivative_s = time.perf_counter() - start
    wall, cpu = _best(lambda: point.predict(reading, 20))
    rows.append(
        {
            "name": "contact estimate, one reading (position, force, sds)",
            "value": 1e3 * wall,
            "unit": "ms",
            "goal": "<= 1 ms",
            "note": f"ContactEstimator(classify=False).predict: 271-point profile, refinement, Fisher sds; "
            f"CPU {1e3 * cpu:.2f} ms",
        }
    )
    wall, cpu = _best(lambda: both.predict(reading, 20))
    wall_line, cpu_line = _best(lambda: both.predict(line, 20))
    rows.append(
        {
            "name": "contact estimate with point vs distributed, one reading",
            "value": 1e3 * max(wall, wall_line),
            "unit": "ms",
            "goal": "<= 1 ms",
            "note": f"adds the line-load profile (~800 centres x extents) and the Bayes factor: a point reading "
            f"{1e3 * wall:.2f} ms (CPU {1e3 * cpu:.2f}), a line load's with its sds {1e3 * wall_line:.2f} ms "
            f"(CPU {1e3 * cpu_line:.2f})",
        }
    )
    rng = np.random.default_rng(1)
    batch = model.point_v(rng.uniform(0.15, 0.26, 1000), -rng.uniform(0.05, 0.5, 1000), 20)
    batch = batch + model.noise_v * rng.standard_normal(batch.shape)
    wall, cpu = _best(lambda: point.predict(batch, 20), number=1, repeat=3)
    wall_both, cpu_both = _best(lambda: both.predict(batch, 20), number=1, repeat=3)
    rows.append(
        {
            "name": "contact estimate per reading in a batch of 1000 (point contacts), point / with the decision",
            "value": wall,
            "unit": "ms",
            "goal": "",
            "note": f"with point vs distributed {wall_both:.2f} ms; CPU {cpu:.2f} / {cpu_both:.2f} ms",
        }
    )
    rows.append(
        {
            "name": "estimator tables for one command, point / point and line",
            "value": table_s,
            "unit": "s",
            "goal": "",
            "note": f"point and line loads: {line_s:.2f} s; a line entry's derivatives at its first declaration "
            f"(the first estimate there): {1e3 * derivative_s:.1f} ms",
        }
    )

    tissue, _ = load_tissue("nodule-phantom")
    plan = load_palpation_protocol("scan")
    placed = tissue.replace(inclusions=())
    rig = open_rig("sim", seed=0, dt_s=0.01)
    start = time.perf_counter()
    records = []
    for d in plan.scan["offsets_m"]:
        rig.place_tissue(tissue.moved(d))
        records.append(run_sweep(rig, plan.sweep))
    loop_s = time.perf_counter() - start
    start = time.perf_counter()
    result = scan(records, placed, plan.scan["offsets_m"], plan.sweep, model=model)
    fit_s = time.perf_counter() - start
    rig.close()
    sim_s = len(plan.scan["offsets_m"]) * plan.sweep.duration_s
    rows.append(
        {
            "name": f"full scan on the twin, 9 offsets x {len(plan.sweep.commands)} plateaus, through the loop",
            "value": loop_s + fit_s,
            "unit": "s",
            "goal": "",
            "note": f"{sim_s:.0f} s of rig time: loop {loop_s:.1f} s, fits {fit_s:.1f} s; inclusion "
            f"{1000 * (result.inclusion['centre_m'] - 0.1):+.1f} mm off, ratio {result.inclusion['ratio']:.2f} (3)",
        }
    )
    start = time.perf_counter()
    statics = [simulate_sweep(model, tissue.moved(d), plan.sweep, seed=j) for j, d in enumerate(plan.scan["offsets_m"])]
    scan(statics, placed, plan.scan["offsets_m"], plan.sweep, model=model)
    rows.append(
        {
            "name": "the same scan on the twin's statics (what the report runs)",
            "value": time.perf_counter() - start,
            "unit": "s",
            "goal": "",
            "note": "simulate_sweep + scan",
        }
    )

    soft, _ = load_tissue("soft-block")
    rig = open_rig("sim", seed=0, dt_s=0.01)
    start = time.perf_counter()
    res = palpate(rig, soft, PalpationProtocol(), model=model)
    rows.append(
        {
            "name": "one palpation sweep (23 plateaus) through the loop and its fit",
            "value": time.perf_counter() - start,
            "unit": "s",
            "goal": "",
            "note": f"{PalpationProtocol().duration_s:.0f} s of rig time; modulus "
            f"{res.fit.modulus_n_m2:.0f} N/m^2 (1000)",
        }
    )
    rig.close()
    rig = open_rig("sim", seed=0, dt_s=0.005)
    rig.place_tissue(soft)
    start = time.perf_counter()
    held = hold_force(rig, 0.1, duration_s=10.0, region_m=(0.15, 0.27), model=model)
    rows.append(
        {
            "name": "10 s of force control (0.1 N) on the twin",
            "value": time.perf_counter() - start,
            "unit": "s",
            "goal": "",
            "note": f"steady {held.steady_error:+.1%}, overshoot {held.overshoot:.1%}",
        }
    )
    rig.close()
    return rows

"""Studies benchmarks: what one evaluation of each metric costs (the batched forms against the exact ones) and the
batched twin's real-time factor (the Dask speed-up and per-task overhead: :mod:`benchmarks.bench_dask`).

- Per evaluation: each of the ten sensitivity metrics alone, one row at a time, and all ten on blocks of 8 rows as
  a study evaluates them (CPU time in one thread, rows of the shipped tolerances, seeded); the tactile limits'
  exact forms (``protocol_limits``, ``identifiability_map``: what every row cost before issue 27) in the same run.
- Batched twin: N = 1000 parameter sets (E and the housing stiffness drawn, seeded), a 0 -> 30 deg command step
  (the first 2 s include the halved steps of the transient) and 2 s of quiet following; aggregate real-time
  factor = N x simulated time / wall time, and per CPU second of all threads (less sensitive to other jobs), and
  per CPU second in one thread (what one core does; two quiet cores give about twice it). The
  kernel's compile time (once per machine: numba caches it) is measured apart in a fresh process with an empty
  cache. The scalar twin's real-time factor in the same run, for comparison.
"""

from __future__ import annotations

import tempfile
import time
import warnings

import numpy as np

_COMPILE_SCRIPT = """
import time
from flexdigit.params import RigParams
from flexdigit.twin.batched import BatchedTwin
twin = BatchedTwin(RigParams())
twin.command([30])
start = time.process_time()
twin.advance(0.02)
print(time.process_time() - start)
"""


def _study_rows(n_base: int):
    import dataclasses

    from flexdigit.studies.metrics import SENSITIVITY_METRICS, MetricContext
    from flexdigit.studies.sensitivity import SensitivitySettings, sensitivity_design
    from flexdigit.studies.spec import load_spec

    spec = dataclasses.replace(load_spec("thesis-tolerances"), metrics=SENSITIVITY_METRICS)
    u, _ = sensitivity_design(spec, SensitivitySettings(morris_trajectories=0, sobol_n=n_base))
    return spec, spec.values_from_unit(u), MetricContext(baseline=spec.baseline)


def _compile_seconds() -> float:
    """CPU time of the kernel's first call with an empty numba cache, in a fresh process (what a new machine pays
    once; later processes load the compiled code from the cache)."""
    import os
    import subprocess
    import sys

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = subprocess.run(
            [sys.executable, "-c", _COMPILE_SCRIPT], env=env, capture_output=True, text=True, check=True
        )
    return float(out.stdout.split()[-1])


def _batched_rows() -> list[dict]:
    from flexdigit.params import Material, RigParams
    from flexdigit.twin import Twin
    from flexdigit.twin.batched import BatchedTwin
    from flexdigit.twin.calibration import default_calibration

    compile_s = _compile_seconds()
    warm = BatchedTwin(RigParams())  # loads the compiled kernel from the cache: not timed
    warm.command([30])
    warm.advance(0.1)
    cal = default_calibration()
    rng = np.random.default_rng(0)
    n = 1000
    params = [RigParams(material=Material(youngs_modulus_pa=float(e))) for e in rng.uniform(195e9, 215e9, n)]
    cals = [cal.replace(housing_ei_n_m2=tuple(np.array(cal.housing_ei_n_m2) * f)) for f in rng.uniform(0.8, 1.2, n)]
    start = time.perf_counter()
    twins = BatchedTwin(params, cals)
    build = time.perf_counter() - start
    twins.command(np.full(n, 30))
    cpu = time.process_time()
    start = time.perf_counter()
    twins.advance(2.0)
    step = time.perf_counter() - start
    start = time.perf_counter()
    twins.advance(2.0)
    quiet = time.perf_counter() - start
    cpu = time.process_time() - cpu
    one = BatchedTwin(params, cals)  # the same in one thread: CPU time per rig and ROS2 step, less load-sensitive
    one.threads = 1
    one.command(np.full(n, 30))
    cpu_one = time.process_time()
    one.advance(4.0)
    cpu_one = time.process_time() - cpu_one
    single = Twin(params[0], cals[0])
    single.command(30)
    start = time.perf_counter()
    single.advance(4.0)
    scalar = time.perf_counter() - start
    threads = len(twins._blocks())
    return [
        {
            "name": "batched twin, N = 1000: aggregate real-time factor, 4 s (step + quiet)",
            "value": n * 4.0 / (step + quiet),
            "unit": "x",
            "goal": ">= 10,000",
            "note": f"step 2 s: {n * 2.0 / step:.0f} x, quiet 2 s: {n * 2.0 / quiet:.0f} x; {threads} threads; "
            f"per CPU second (all threads): {n * 4.0 / cpu:.0f} x",
        },
        {
            "name": "batched twin, N = 1000, one thread: real-time factor per CPU second",
            "value": n * 4.0 / cpu_one,
            "unit": "x",
            "goal": "",
            "note": f"{1e6 * cpu_one / one.substeps.sum():.2f} us CPU per rig and ROS2 step "
            f"({one.substeps.sum()} steps, halved ones included)",
        },
        {"name": "batched twin, N = 1000: build (1000 chains)", "value": build, "unit": "s", "goal": "", "note": ""},
        {
            "name": "batched twin: kernel compile, once per machine (numba cache)",
            "value": compile_s,
            "unit": "s",
            "goal": "",
            "note": "CPU time of the first call with an empty cache; excluded from the figures above",
        },
        {
            "name": "scalar twin, same 4 s, one rig",
            "value": 4.0 / scalar,
            "unit": "x",
            "goal": "",
            "note": "real-time factor of one Twin in the same run",
        },
    ]


def _metric_rows() -> list[dict]:
    from threadpoolctl import threadpool_limits

    from flexdigit.studies.metrics import (
        SENSITIVITY_METRICS,
        MetricContext,
        _bayes_exact,
        _blind_zone_exact,
        _forget_kept,
        evaluate_many,
    )
    from flexdigit.studies.spec import load_spec

    spec = load_spec("thesis-tolerances")
    ctx = MetricContext(baseline=spec.baseline)
    unit = np.random.default_rng(1).random((41, len(spec.parameters)))
    sets = [spec.parameter_set(v) for v in spec.values_from_unit(unit)]
    rows = []

    def cpu_ms(func, count: int) -> float:
        start = time.process_time()
        func()
        return 1e3 * (time.process_time() - start) / count

    with threadpool_limits(1):  # as a study's worker runs them
        evaluate_many(sets[:1], SENSITIVITY_METRICS, ctx)  # warm: the baseline controller, kernels, tables
        for name in SENSITIVITY_METRICS:
            _forget_kept()  # each metric from scratch (the loop's three share one computation in a study)
            value = cpu_ms(lambda name=name: [evaluate_many([p], [name], ctx) for p in sets[1:9]], 8)
            rows.append({"name": f"metric {name}, one evaluation", "value": value, "unit": "ms", "goal": "",
                         "note": "CPU, one thread, one row at a time"})  # fmt: skip
        blocks = [sets[i : i + 8] for i in range(9, 41, 8)]
        _forget_kept()
        value = cpu_ms(lambda: [evaluate_many(b, SENSITIVITY_METRICS, ctx) for b in blocks], 32)
        rows.append({"name": "all ten metrics, per row, in blocks of 8 rows", "value": value, "unit": "ms",
                     "goal": "", "note": "CPU, one thread: independent random rows (nothing repeats)"})  # fmt: skip
        # a study's rows: Saltelli's, where most rows move one parameter and share the values that do not read it
        study_spec, values, _ = _study_rows(16)
        study = [study_spec.parameter_set(v) for v in values[:320]]
        _forget_kept()
        value = cpu_ms(
            lambda: [evaluate_many(study[i : i + 8], SENSITIVITY_METRICS, ctx) for i in range(0, 320, 8)], 320
        )
        rows.append({"name": "all ten metrics, per row, a Saltelli design in blocks of 8 rows", "value": value,
                     "unit": "ms", "goal": "", "note": "CPU, one thread: the first 320 rows of a study's "
                     "design (16 base samples, 18 parameters), what a study's row costs"})  # fmt: skip
        for name, exact in (("bayes_position_limit_mm", _bayes_exact), ("blind_zone_mm", _blind_zone_exact)):
            value = cpu_ms(lambda exact=exact: [exact(p, ctx) for p in sets[1:5]], 4)
            note = "tactile.bounds / tactile.localisation per row, CPU, one thread"
            rows.append({"name": f"metric {name}, exact form (before issue 27)", "value": value, "unit": "ms",
                         "goal": "", "note": note})  # fmt: skip
    return rows


def run() -> list[dict]:
    warnings.simplefilter("ignore")
    return _metric_rows() + _batched_rows()

"""A tendon robot's sensing, experiments and study rows: what ``tdcr shape|contact``, ``simulate --robot`` and a
robot study cost (issue 26's commands), and the accuracy each reaches, in one run.

- Shape from gauges (rao2021, 3 stations a segment, 36 gauges, a 50 mN tip force and a microstrain of noise):
  one estimate from readings (``estimate_shape``), and its tip error against the twin.
- Contact (rao2021 under 2,0,0,0,1,0 N, 48 gauges, 18 mN pressed at 270 mm): one location from readings
  (``locate_contact``), and its place and force errors.
- Release test (rao2021, 3 periods at 200 steps a period): one first frequency, and the 40-element cantilever's
  against Euler-Bernoulli.
- A robot study's rows: tip metrics (one statics each) and the first frequency (one release each) per second.

Run: ``python -m benchmarks bench_tdcrcli``.
"""

from __future__ import annotations

import math
import time

import numpy as np


def _best_time(func, repeats: int, rounds: int = 5) -> float:
    func()
    best = math.inf
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(repeats):
            func()
        best = min(best, (time.perf_counter() - start) / repeats)
    return best


def bench_sensing() -> list[dict]:
    from flexdigit.tdcr import ROBOTS, estimate_shape, locate_contact, sense_contact, sense_shape

    robot = ROBOTS["rao2021"]
    shape = sense_shape(robot, tensions_n=[4, 0, 0, 0, 2, 0], tip_force_n=[0.05, 0, 0], noise_std=1e-6, seed=0)
    shape_s = _best_time(lambda: estimate_shape(robot, shape.layout, shape.strains), 20)
    contact = sense_contact(robot, [2, 0, 0, 0, 1, 0], contact_s_m=0.27, contact_force_n=[-0.01, 0.015, 0.0])
    contact_s = _best_time(lambda: locate_contact(robot, contact.layout, contact.strains, contact.free), 5)
    return [
        {
            "name": "tdcr shape: one estimate from 36 gauges (rao2021)",
            "value": shape_s * 1e3,
            "unit": "ms",
            "goal": "",
            "note": f"tip error {shape.tip_error_m * 1e3:.3f} mm, {shape.tip_angle_error_deg:.3f} deg against the "
            "twin (50 mN tip force, 1 microstrain noise); best of 5 x 20",
        },
        {
            "name": "tdcr contact: one location from 48 gauges (rao2021)",
            "value": contact_s * 1e3,
            "unit": "ms",
            "goal": "",
            "note": f"place error {contact.place_error_m * 1e3:.2f} mm, force error "
            f"{contact.force_error_n / math.hypot(0.01, 0.015) * 100:.1f} % of 18 mN; best of 5 x 5",
        },
    ]


def bench_release() -> list[dict]:
    from flexdigit.tdcr import ROBOTS, Robot, Segment, release_test

    robot = ROBOTS["rao2021"]
    release_s = _best_time(lambda: release_test(robot, [4, 0, 0, 0, 2, 0]), 2)
    rao = release_test(robot, [4, 0, 0, 0, 2, 0])
    rod = release_test(Robot(name="rod", segments=(Segment(0.4, 40),)))
    return [
        {
            "name": "simulate release --robot rao2021: one first frequency",
            "value": release_s * 1e3,
            "unit": "ms",
            "goal": "",
            "note": f"{rao.first_frequency_hz:.4f} Hz under 4,0,0,0,2,0 N ({rao.motion.t_s.size - 1} steps); a "
            f"40-element cantilever {100 * (rod.first_frequency_hz / rod.euler_bernoulli_hz - 1):+.3f} % from "
            "Euler-Bernoulli",
        },
    ]


def bench_study_rows() -> list[dict]:
    from flexdigit.studies.metrics import MetricContext, evaluate_many
    from flexdigit.studies.robot_study import load_robot_spec

    spec = load_robot_spec("rao2021-tolerances")
    rng = np.random.default_rng(0)
    values = spec.values_from_unit(rng.uniform(size=(64, len(spec.parameters))))
    rows = []
    for metrics, label in ((("tip_lateral_m", "tip_angle_deg"), "tip metrics"), (("first_frequency_hz",), "freq")):
        context = MetricContext(user_metrics=spec.user_metrics)
        start = time.perf_counter()
        cases = [spec.parameter_set(v) for v in values]
        evaluate_many(cases, metrics, context)
        per = (time.perf_counter() - start) / len(cases)
        rows.append(
            {
                "name": f"robot study rows ({label}), rao2021-tolerances",
                "value": 1.0 / per,
                "unit": "rows/s",
                "goal": "",
                "note": f"{len(cases)} rows of {', '.join(metrics)}, one process",
            }
        )
    return rows


def run() -> list[dict]:
    """The robot commands' costs (``python -m benchmarks bench_tdcrcli``), BLAS on one thread as a study's
    workers run (on a loaded 2-core machine its spinning threads made single SVDs take a second)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        return [*bench_sensing(), *bench_release(), *bench_study_rows()]


if __name__ == "__main__":
    for row in run():
        print(row)

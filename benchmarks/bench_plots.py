"""What ``--plot FILE`` adds to a command (issue 28): drawing and saving each figure, best of 3 (goal <= 1 s each).

The data are computed once, untimed (the command computes them anyway); only ``<domain>_figure(...)`` and
``flexdigit._plot.save_plot`` (PNG, the report's DPI) are timed. ``python -m benchmarks plots``.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

REPEATS = 3
GOAL_S = 1.0


def _inputs() -> dict:
    """name -> a function drawing that figure from data computed here, untimed."""
    import numpy as np

    from flexdigit.calibrate.residual_plot import residual_figure
    from flexdigit.calibrate.targets import CalibrationTargets
    from flexdigit.calibrate.twin_fit import calibrate
    from flexdigit.control.design_plot import design_figure
    from flexdigit.control.thesis_designs import thesis_design
    from flexdigit.identify.fit_plot import fit_figure
    from flexdigit.identify.identification import identify
    from flexdigit.identify.timeseries import series_from_table
    from flexdigit.models.plant import build_plant
    from flexdigit.shape.shape import ShapeEstimator
    from flexdigit.shape.shape_plot import shape_figure
    from flexdigit.tactile.prediction_plot import prediction_figure
    from flexdigit.tdcr import ROBOTS, backbone_figure, contact_figure, experiment_figure, sense_contact, sense_shape
    from flexdigit.tdcr import step_test as robot_step_test
    from flexdigit.twin.record_plot import record_figure
    from flexdigit.twin.records import actuation_sweep, servo_step_test

    step = servo_step_test(seed=0)  # 1.5 s at 1 kHz, as `flexdigit simulate step`
    series = series_from_table(step, "pot")
    fit = identify(series, "step")
    plant = build_plant("printed").tf
    controller = thesis_design(39.0, plant).controller
    sweep = actuation_sweep([8, 22, 36, 43], settle_s=1.0, samples=3, seed=0)
    targets = CalibrationTargets.from_records(sweep=_sweep_table(sweep))
    calibration = calibrate(targets)
    rng = np.random.default_rng(0)
    actual = rng.uniform(0.0, 0.24, 1000)  # a thesis-sized test set: 1000 readings, m from the tip
    estimate = ShapeEstimator().estimate([0.0085, 0.765, 0.151], command=22)
    robot, pulls = ROBOTS["rao2021"], [2.0, 0, 0, 1.0, 0, 0]
    robot_step = robot_step_test(robot, pulls, duration_s=1.0, dt_s=1e-3)  # 1 s at 1 kHz, as `simulate --robot`
    robot_shape = sense_shape(robot, tensions_n=pulls, noise_std=1e-6, seed=0)
    robot_contact = sense_contact(robot, pulls, contact_s_m=0.3, contact_force_n=[0.0, 0.05, 0.0])
    return {
        "simulate step: record": lambda: record_figure(step),
        "identify step: fit over the record": lambda: fit_figure(series, fit),
        "design hinf: step and Bode": lambda: design_figure(plant, controller),
        "predict: predicted vs actual (1000 readings)": lambda: prediction_figure(
            actual, actual + rng.normal(0, 0.01, actual.size), "position"
        ),
        "calibrate: residuals per target": lambda: residual_figure(calibration),
        "shape: centre line": lambda: shape_figure(estimate),
        "simulate step --robot: the tip's path (1001 samples)": lambda: experiment_figure(robot_step),
        "tdcr shape: backbone beside the twin's": lambda: backbone_figure(robot_shape, robot),
        "tdcr contact: the contact on the backbone": lambda: contact_figure(robot_contact, robot),
    }


def _sweep_table(record):
    from flexdigit.calibrate.record_files import read_sweep

    with tempfile.TemporaryDirectory() as tmp:
        path = record.save(Path(tmp) / "sweep.csv")
        return read_sweep(path)


def run() -> list[dict]:
    with tempfile.TemporaryDirectory() as tmp:
        return time_figures(_inputs(), Path(tmp))


def time_figures(inputs: dict, tmp: Path) -> list[dict]:
    """Each figure of ``inputs`` (name -> a function drawing it) drawn and saved to ``tmp``: best of REPEATS."""
    from flexdigit._plot import save_plot

    rows = []
    for name, draw in inputs.items():
        best = float("inf")
        for _ in range(REPEATS):
            start = time.perf_counter()
            save_plot(draw(), tmp / "figure.png", force=True)
            best = min(best, time.perf_counter() - start)
        note = f"best of {REPEATS}"
        rows.append({"name": name, "value": best, "unit": "s", "goal": f"<= {GOAL_S:g} s", "note": note})
    return rows

"""What ``--plot FILE`` adds to the commands that drew nothing before (``design 20ms|sweep``, ``collect``, ``study``,
``tdcr statics|dynamics``): drawing and saving each figure, best of 3 (goal <= 1 s each, as ``bench_plots``).

The data are computed once, untimed (the command computes them anyway); only the ``*_figure(...)`` call and
:func:`flexdigit._plot.save_plot` (PNG, the report's DPI) are timed. ``python -m benchmarks plots2``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from benchmarks.bench_plots import time_figures


def _dataset(readings: int = 1275):
    """A dataset the size of table 6.1's (1275 readings, three gauges), its voltages drawn at random."""
    import numpy as np

    from flexdigit.tactile.dataset import COLUMNS, Dataset

    rng = np.random.default_rng(0)
    columns = {c: np.zeros(readings, dtype=d) for c, d in COLUMNS.items()}
    columns["sample"] = np.arange(readings)
    columns["time_s"] = np.arange(readings) * 15.0
    columns["load_kg"] = rng.choice([0.0, 0.01, 0.02, 0.05], readings)
    columns["position_from_tip_m"] = rng.choice(np.arange(0.0, 0.25, 0.0125), readings)
    for k in (1, 2, 3):
        columns[f"gauge{k}_v"] = rng.normal(0.0, 0.3, readings)
    return Dataset(columns, {"protocol": {"name": "table-6.1-sized"}})


def _sensitivity(tmp: Path):
    """A small robot sensitivity study (two metrics, N = 8), run in process."""
    from flexdigit.studies.robot_study import robot_spec_from_toml, run_robot_sensitivity
    from flexdigit.studies.sensitivity import SensitivitySettings

    spec = robot_spec_from_toml(
        '[study]\nrobot = "rao2021"\ntensions_n = [1, 0, 0, 0, 0, 0]\nmetrics = ["tip_angle_deg", "tip_z_m"]\n'
        '[parameters.backbone.youngs_modulus_pa]\ndistribution = "uniform"\nrelative = 0.1\n'
        '[parameters.loads.tensions_n.0]\ndistribution = "uniform"\nrelative = 0.1\n'
    )
    settings = SensitivitySettings(morris_trajectories=0, sobol_n=8)
    return run_robot_sensitivity(spec, tmp / "study", settings=settings, workers=0, progress=False)


def _inputs(tmp: Path) -> dict:
    """name -> a function drawing that figure from data computed here, untimed."""
    from flexdigit.control.design20ms import design_20ms
    from flexdigit.control.design_plot import sweep_figure, twenty_ms_figure
    from flexdigit.studies.figures import sensitivity_figure
    from flexdigit.tactile.dataset_plot import dataset_figure
    from flexdigit.tdcr import ROBOTS, simulate, solve_statics, statics_figure, trajectory_figure

    robot = ROBOTS["rao2021"]
    pulled = solve_statics(robot, [2.0, 0, 0, 1.0, 0, 0])
    motion = simulate(robot, solve_statics(robot, [0.0] * 6), 1.0, dt_s=1e-3, tensions_n=[2.0, 0, 0, 0, 0, 0])
    design = design_20ms()
    dataset = _dataset()
    study = _sensitivity(tmp)
    sweep = ([0.5, 5.0, 39.0, 50.0], [108.5, 97.8, -15.6, 24.0], [0.335, 1.15, 5.4e5, 5626], [0.78, 0.85, 22.48, 2.6])
    return {
        "design 20ms: step and loop frequency response": lambda: twenty_ms_figure(design),
        "design sweep: tolerance per cut-off (4 filters)": lambda: sweep_figure(*sweep),
        "collect: gauges against place and time (1275 readings)": lambda: dataset_figure(dataset),
        "study sensitivity: total-index map (2 metrics)": lambda: sensitivity_figure(study),
        "tdcr statics: backbone from three sides": lambda: statics_figure(pulled, robot),
        "tdcr dynamics: the tip's path (1001 samples)": lambda: trajectory_figure(motion, robot),
    }


def run() -> list[dict]:
    with tempfile.TemporaryDirectory() as tmp:
        return time_figures(_inputs(Path(tmp)), Path(tmp))

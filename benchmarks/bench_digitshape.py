"""The shape estimate's cost with its global search (issue 24), on the thesis rig and on a digit that sags far.

A cold :meth:`~flexdigit.shape.shape.ShapeEstimator.estimate` (what ``flexdigit shape`` runs once; ``shape
--accuracy`` and the report's chapter 8 run it on batches) now settles every candidate load position of a coarse
grid on its own shape wherever a load is found. Timed in the same run:

- one reading, 25 g at 200 mm on the thesis rig lying horizontal (command 20), and 10 g at the tip of campaign
  digit 2 (one 389 mm section of 0.25 mm phosphor bronze, 7 gauges, cable detached: 84 deg of sag), ms per
  estimate, best of 5;
- a batch: the thesis rig's 27 load positions x 6 commands (``shape_accuracy``'s weight cases), readings per
  second;
- the live page's warm-started estimate (no global search: the last frame's shape is the start), ms.

``python -m benchmarks digitshape``
"""

from __future__ import annotations

import time

import numpy as np

#: Campaign digit 2 of tests/digit_campaign.py (``campaign_digit(2)``), written out (benchmarks do not import the
#: tests).
SAGGING_DIGIT = {
    "geometry": {
        "section_count": 1,
        "section_length_m": 0.3893,
        "strip_length_m": 0.3893,
        "digit_length_m": 0.404,
        "strip_thickness_m": 0.00025,
        "strip_width_m": 0.0132,
        "cable_eccentricity_m": 0.00318,
        "gauge_positions_m": [0.0374, 0.0388, 0.0837, 0.0982, 0.1916, 0.2682, 0.3749],
    },
    "material": {"youngs_modulus_pa": 110e9, "strip_density_kg_m3": 8860.0},
    "sensors": {
        "bridge": "quarter",
        "gauge_bridges": ["quarter", "half", "full", "half", "half", "quarter", "quarter"],
        "gauge_factors": [1.74, 1.38, 1.12, 0.89, 0.87, 2.09, 1.52],
        "amplifier_gains_v_per_v": [7838.0, 3618.0, 3929.0, 4440.0, 13840.0, 20000.0, 20000.0],
        "adc_bits": 16,
        "adc_range_v": [-2.5, 2.5],
        "adc_channels": [6, 2, 7, 3, 0, 1, 4],
    },
    "actuator": {"gear_ratio": 1.88},
    "cables": {"count": 1, "pretension_n": 0.0, "guide_friction_ratio": 0.0163},
}


def _best_ms(call, repeats: int = 5) -> float:
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best * 1e3


def run() -> list[dict]:
    from flexdigit.params import RigParams
    from flexdigit.shape.shape import ACCURACY_POSITIONS_M, ShapeEstimator
    from flexdigit.twin import static_gauges_v
    from flexdigit.twin.digit_calibration import twin_calibration

    thesis = ShapeEstimator(orientation="horizontal")
    volts = static_gauges_v([0.025], [0.20], [20])
    thesis.estimate(volts, command=20)  # set-up once
    thesis_ms = _best_ms(lambda: thesis.estimate(volts, command=20))

    params = RigParams.from_dict(SAGGING_DIGIT)
    cal = twin_calibration(params, None)
    length = params.geometry.digit_length_m
    sag_volts = static_gauges_v([0.010], [length], None, params=params, calibration=cal, cells_per_section=27)
    sagging = ShapeEstimator(params, cal, orientation="horizontal", cable=False)
    sagging.estimate(sag_volts)
    sag_ms = _best_ms(lambda: sagging.estimate(sag_volts))

    commands, positions = np.meshgrid(np.arange(8, 44, 7), ACCURACY_POSITIONS_M, indexing="ij")
    batch = static_gauges_v(np.full(commands.size, 0.025), positions.ravel(), commands.ravel(), seed=0)
    start = time.perf_counter()
    thesis.estimate(batch, command=commands.ravel())
    per_s = commands.size / (time.perf_counter() - start)

    previous = thesis.estimate(volts, command=20)
    warm_ms = _best_ms(lambda: thesis.estimate(volts, command=20, start=previous), repeats=20)
    return [
        {"name": "shape estimate, cold, thesis rig (25 g at 200 mm)", "value": thesis_ms, "unit": "ms", "goal": "",
         "note": "flexdigit shape's one reading, the global search included"},
        {"name": "shape estimate, cold, 0.40 m digit sagging 84 deg", "value": sag_ms, "unit": "ms", "goal": "",
         "note": "campaign digit 2, 10 g at the tip, 7 gauges, cable detached"},
        {"name": "shape estimates, batch of 162 (thesis rig)", "value": per_s, "unit": "readings/s", "goal": "",
         "note": "shape_accuracy's weight cases at 6 commands"},
        {"name": "shape estimate, warm start (thesis rig)", "value": warm_ms, "unit": "ms", "goal": "",
         "note": "the live page's: no global search"},
    ]  # fmt: skip

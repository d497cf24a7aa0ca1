"""Force control between two commands (issue 24, forcecal): what one estimate of the loop's hot path costs
(``ForceController.estimate``, once a 20 ms sample) on ``random_digit(10)`` of tests/digits.py (4 quarter bridges,
a cable pair, 1.1:1) as before (the same reading at both commands, its own place) and now (the reading moved to each
command's free shape, the force read at the contact's held place: two more force profiles a sample), and what a
10 s hold of 0.1 N on its twin costs. Best of 3.

``python -m benchmarks forcecal``
"""

from __future__ import annotations

import numpy as np

from benchmarks._common import RANDOM_DIGIT_10, best_of


def _hold(params) -> None:
    from flexdigit.palpation.palpation import hold_force
    from flexdigit.rig.base import open_rig
    from flexdigit.twin.contact import Tissue

    length = params.geometry.digit_length_m
    with open_rig("sim", params, seed=2, dt_s=0.005) as rig:
        rig.place_tissue(Tissue(0.55 * length, length + 0.08, 0.1 * length, 1000.0))
        hold_force(rig, 0.1, duration_s=10.0, region_m=(0.55 * length, length))


def _estimate_us(model, free_step: bool, place_readings: int, command: int) -> float:
    from flexdigit.palpation.contact_estimation import ContactEstimator
    from flexdigit.palpation.palpation import ForceController

    length = model.length_m
    estimator = ContactEstimator(model, classify=False, region_m=(0.55 * length, length)).fit()
    controller = ForceController(
        estimator, np.zeros(len(model.noise_v)), free_step=free_step, place_readings=place_readings, high=254
    )
    controller.reset(command)
    controller.touching = True
    reading = model.point_v([0.97 * length], [-0.1], command)[0]

    class Reading:
        gauges_v = reading

    controller.step(0.1, Reading())  # the tables of both commands, once
    return 1e6 * best_of(lambda: [controller.step(0.1, Reading()) for _ in range(200)]) / 200


def run() -> list[dict]:
    from flexdigit.palpation.contact_estimation import ContactGaugeModel
    from flexdigit.palpation.palpation import PLACE_READINGS
    from flexdigit.params import RigParams
    from flexdigit.twin.digit_calibration import twin_calibration

    params = RigParams.from_dict(RANDOM_DIGIT_10)
    model = ContactGaugeModel(params, twin_calibration(params))
    command = int(params.actuator.equilibrium_command) + 11
    rows = []
    for label, free_step, place in (("as before", False, 0), ("free step, held place", True, PLACE_READINGS)):
        rows.append(
            {
                "name": f"force loop sample, random_digit(10), {label}",
                "value": _estimate_us(model, free_step, place, command),
                "unit": "us",
                "goal": "< 20 ms loop",
                "note": "ForceController.step once touching: the estimate (and the held place from its readings)",
            }
        )
    rows.append(
        {
            "name": "force hold 10 s of 0.1 N, random_digit(10)",
            "value": best_of(lambda: _hold(params)),
            "unit": "s",
            "goal": "",
            "note": "wall time of hold_force on the twin (5 ms step, seed 2), tare and tables included",
        }
    )
    return rows

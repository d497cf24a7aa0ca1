"""Force control (issue 24): what a 10 s hold of 0.1 N costs in CPU on the twin, and what one estimate costs the
loop's hot path (``ForceController.estimate``, once a 20 ms sample): the thesis rig (each reading alone, point
hypothesis), the thesis rig with a classifying estimator (point or line load: what a digit whose point hypothesis
misreads a stretch of contact would run), and the one-section test digit (each estimate on the mean of 14 readings).
Best of 3.

``python -m benchmarks force``
"""

from __future__ import annotations

import numpy as np

from benchmarks._common import ONE_SECTION, best_of


def _hold(params) -> None:
    from flexdigit.palpation.palpation import hold_force
    from flexdigit.rig.base import open_rig
    from flexdigit.twin.contact import Tissue
    from flexdigit.twin.digit_calibration import twin_calibration

    length = params.geometry.digit_length_m
    with open_rig("sim", params, seed=0, dt_s=0.005, calibration=twin_calibration(params)) as rig:
        rig.place_tissue(Tissue(0.55 * length, length + 0.08, 0.1 * length, 1000.0))
        hold_force(rig, 0.1, duration_s=10.0, region_m=(0.55 * length, length))


def _estimate_us(model, classify: bool, readings: int, command: int) -> float:
    from flexdigit.palpation.contact_estimation import ContactEstimator
    from flexdigit.palpation.palpation import ForceController

    length = model.length_m
    estimator = ContactEstimator(model, classify=classify, region_m=(0.55 * length, length), n_readings=readings)
    controller = ForceController(estimator.fit(), np.zeros(len(model.noise_v)), average_readings=readings)
    controller.reset(command)
    reading = model.point_v([0.95 * length], [-0.1], command)[0]
    controller.estimate(reading, command + 0.3)  # the tables of both commands, once
    return 1e6 * best_of(lambda: [controller.estimate(reading, command + 0.3) for _ in range(200)]) / 200


def run() -> list[dict]:
    from flexdigit.palpation.contact_estimation import ContactGaugeModel
    from flexdigit.params import RigParams
    from flexdigit.twin.digit_calibration import twin_calibration

    one = RigParams.from_dict(ONE_SECTION)
    rows = []
    for label, params in (("thesis rig", RigParams()), ("one-section digit", one)):
        rows.append(
            {
                "name": f"force hold 10 s of 0.1 N, {label}",
                "value": best_of(lambda params=params: _hold(params)),
                "unit": "s",
                "goal": "",
                "note": "wall time of hold_force on the twin (5 ms step), tare and tables included",
            }
        )
    thesis = ContactGaugeModel()
    cases = (
        ("thesis rig, point", thesis, False, 1, 20),
        ("thesis rig, point or line load", thesis, True, 1, 20),
        ("one-section digit, mean of 14", ContactGaugeModel(one, twin_calibration(one)), False, 14, 12),
    )
    for label, model, classify, readings, command in cases:
        rows.append(
            {
                "name": f"force estimate, {label}",
                "value": _estimate_us(model, classify, readings, command),
                "unit": "us",
                "goal": "< 20 ms loop",
                "note": "ForceController.estimate, once a sample: two commands interpolated, as the decision says",
            }
        )
    return rows

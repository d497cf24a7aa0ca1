"""The rotation map of a digit (issue 24): what the referenced sweep (straight before, between and after the
commands) costs against the plain one, in CPU and in the rig's own time (twice the settles), and what the quadratic
term costs the loop's hot path (``RotationEstimator.predict_one``, once a sample). The one-section test digit's twin
(one quarter bridge) and ``random_digit(20)`` (4 quarter bridges on a pair: the curved map). Best of 3.

``python -m benchmarks map``
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks._common import ONE_SECTION, RANDOM_DIGIT_20, best_of


def _sweep(params, sweep: str) -> tuple[float, float]:
    """CPU time (s) and rig time (s) of one sweep of ``params``' twin."""
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation

    rig = open_rig("sim", params, seed=1)
    start = time.perf_counter()
    calibrate_rotation(rig, sweep=sweep)
    return time.perf_counter() - start, rig.clock()


def run() -> list[dict]:
    from flexdigit.params import RigParams
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation

    digit = RigParams.from_dict(ONE_SECTION)
    rows = []
    times = {}
    for sweep in ("plain", "referenced"):
        cpu = min(_sweep(digit, sweep)[0] for _ in range(3))
        times[sweep] = cpu
        rows.append(
            {
                "name": f"map sweep, one-section digit, {sweep}",
                "value": cpu,
                "unit": "s",
                "goal": "",
                "note": f"CPU of calibrate_rotation on its twin; rig time {_sweep(digit, sweep)[1]:.1f} s",
            }
        )
    curved = calibrate_rotation(open_rig("sim", RigParams.from_dict(RANDOM_DIGIT_20), seed=1))
    readings = np.asarray(curved.gauges_v_)
    for label, est in (("affine", calibrate_rotation(open_rig("sim", digit, seed=1))), ("curved", curved)):
        g = readings[:, : est.coef_.size]
        per = best_of(lambda est=est, g=g: [est.predict_one(row) for _ in range(200) for row in g]) / (200 * len(g))
        rows.append(
            {
                "name": f"map reading (predict_one), {label} (degree {est.degree})",
                "value": per * 1e6,
                "unit": "us",
                "goal": "< 20 ms loop",
                "note": f"{est.coef_.size} gauge(s), once a sample",
            }
        )
    return rows

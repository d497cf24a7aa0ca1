"""What the Bayes floor of the network's split costs (issue 24, trial 2 items 10 and 12): the limits by prior of
the design study's table 6.1 settings as ``train`` computes them (``studies.metrics.bayes_limits_by_prior``, what
``study design --export K`` now adds to an exported file's header), for the thesis rig and a six-gauge front
design, beside the study's own ``bayes_position_limit_mm``: wall time of one call each, and the figures.

``python -m benchmarks bayes2``
"""

from __future__ import annotations

import time
from pathlib import Path

FRONT39 = Path(__file__).resolve().parents[1] / "tests" / "data" / "handmade_digits2" / "study_front39.toml"


def run() -> list[dict]:
    from flexdigit.params import RigParams, load_params
    from flexdigit.studies.metrics import MetricContext, _forget_kept, bayes_limits_by_prior, bayes_position_limit_mm
    from flexdigit.studies.spec import ParameterSet
    from flexdigit.twin.digit_calibration import twin_calibration

    ctx = MetricContext()
    out = []
    for label, params in (("thesis rig", RigParams()), ("front design 39 (6 gauges)", load_params(FRONT39))):
        ps = ParameterSet(params, twin_calibration(params))
        _forget_kept()
        start = time.perf_counter()
        metric = bayes_position_limit_mm(ps, ctx)
        metric_s = time.perf_counter() - start
        start = time.perf_counter()
        limits = bayes_limits_by_prior(ps, ctx)
        seconds = time.perf_counter() - start
        shown = ", ".join(f"{k} {'-' if v is None else f'{v:.3f}'} mm" for k, v in limits.items())
        out.append(
            {
                "name": f"Bayes limits by prior (settings and span), {label}, table 6.1",
                "value": round(seconds, 2),
                "unit": "s",
                "goal": "",
                "note": f"{shown}; the study's metric {metric:.3f} mm in {metric_s:.2f} s",
            }
        )
    return out

"""What counting the gauges' drift costs the localisation Bayes limit of ``flexdigit train --bayes-limit`` (issue
24): the thesis rig's twin collects thesis-6.1 (1275 readings over a 774 s run, seed 0), and the limit on the
loaded readings is computed with the drift each reading carries (``drift=True``, ``tactile.localisation.
drift_variance_v2``) beside the white-noise floor (the default): wall time of one call each at the train
command's 4000 samples, and both limits.

``python -m benchmarks netfix``
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path


def run() -> list[dict]:
    import numpy as np

    from flexdigit.params import RigParams
    from flexdigit.tactile.localisation import position_bayes_rmse_m, readings_gauge_model
    from flexdigit.tactile.protocols import load_protocol
    from flexdigit.tactile.runner import collect_on
    from flexdigit.twin.digit_calibration import twin_calibration

    params = RigParams()
    with tempfile.TemporaryDirectory() as tmp:
        dataset = collect_on("sim", load_protocol("thesis-6.1", params), Path(tmp) / "data.parquet", seed=0)
    rows = np.flatnonzero(dataset["load_kg"] > 0)
    model = readings_gauge_model(params, twin_calibration(params))
    out = []
    for label, drift in (("with the drift", True), ("white noise only (the floor)", False)):
        start = time.perf_counter()
        limit = position_bayes_rmse_m(model, dataset, rows, drift=drift)
        seconds = time.perf_counter() - start
        out.append(
            {
                "name": f"Bayes limit, span prior, {label}, thesis rig on thesis-6.1 (collected)",
                "value": round(seconds, 2),
                "unit": "s",
                "goal": "",
                "note": f"limit {1e3 * limit:.2f} mm on {rows.size} loaded readings",
            }
        )
    return out

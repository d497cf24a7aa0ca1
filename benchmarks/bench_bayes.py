"""What the localisation Bayes limit of ``flexdigit train --bayes-limit`` costs (issue 24): the thesis rig's twin
on thesis-6.1's settings (28 positions x 3 loads, one reading each), the span prior (the default: positions
continuous within half the protocol's step of each, ``tactile.localisation.position_bayes_rmse_m``) beside the
settings prior (``protocol_limits``, chapter 6's), wall time of one call each at the train command's 4000 samples.

``python -m benchmarks bayes``
"""

from __future__ import annotations

import time


def _dataset():
    import numpy as np

    from flexdigit.params import RigParams
    from flexdigit.tactile.dataset import Dataset, dataset_columns, make_meta
    from flexdigit.tactile.protocols import load_protocol

    protocol = load_protocol("thesis-6.1")
    length = RigParams().geometry.digit_length_m
    tips = np.repeat(np.asarray(protocol.positions_from_tip_m), len(protocol.loads_kg))
    loads = np.tile(np.asarray(protocol.loads_kg), len(protocol.positions_from_tip_m))
    cols = {c: np.zeros(tips.size, dtype=d) for c, d in dataset_columns(3).items()}
    cols.update(load_kg=loads, position_from_tip_m=tips, position_from_base_m=length - tips)
    cols["command"][:] = -1
    cols["sample"] = np.arange(tips.size)
    return Dataset(cols, make_meta(protocol, {}, length))


def run() -> list[dict]:
    import numpy as np

    from flexdigit.params import RigParams
    from flexdigit.tactile.localisation import position_bayes_rmse_m, readings_gauge_model
    from flexdigit.twin.digit_calibration import twin_calibration

    params = RigParams()
    model = readings_gauge_model(params, twin_calibration(params))
    dataset = _dataset()
    rows = np.arange(len(dataset))
    out = []
    for prior in ("span", "settings"):
        start = time.perf_counter()
        limit = position_bayes_rmse_m(model, dataset, rows, prior=prior)
        seconds = time.perf_counter() - start
        out.append(
            {
                "name": f"Bayes limit, {prior} prior, thesis rig on thesis-6.1",
                "value": round(seconds, 2),
                "unit": "s",
                "goal": "",
                "note": f"limit {1e3 * limit:.2f} mm, 4000 samples a setting",
            }
        )
    return out

"""A digit with an antagonistic pair and its cables detached (the tactile chapter's relaxed servo, ``cable=False``):
neither cable pulls, so its twin is the same digit with one detached cable, reading for reading. (Before, the
second cable's stretch came out at ``p + inf`` and the dynamics diverged at the first step.)"""

from __future__ import annotations

import numpy as np

from digits import write_digit
from flexdigit.params import load_params
from flexdigit.rig.base import open_rig
from flexdigit.twin.digit_calibration import twin_calibration


def test_a_detached_pair_is_a_detached_single_cable(tmp_path):
    pair = load_params(write_digit("four-sections-two-cables", tmp_path))
    single = pair.replace(cables=pair.cables.__class__(count=1, pretension_n=0.0))
    readings = []
    for params in (pair, single):
        options = dict(calibration=twin_calibration(params), cable=False, orientation="horizontal", seed=0)
        with open_rig("sim", params, dt_s=0.02, **options) as rig:
            rig.place_load(0.01, 0.3)
            rig.wait(2.0)
            readings.append(rig.read().gauges_v)
    assert np.all(np.isfinite(readings[0]))
    np.testing.assert_array_equal(readings[0], readings[1])

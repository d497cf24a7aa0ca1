"""The damping law's cost (issue 24): :func:`flexdigit.twin.digit_calibration.calibration_for` now runs the chain's
linear modal analysis of the digit (and, once, the thesis rig's) to match the materials' loss factors at the
digit's first mode; every twin of a described digit built without a calibration file pays it. Timed beside the
thesis rig's (the same call, its modal factor exactly 1), caches cleared each time. Best of 5.

``python -m benchmarks damping``
"""

from __future__ import annotations

from benchmarks._common import FIVE_SECTIONS_EIGHT_GAUGES, best_of


def run() -> list[dict]:
    from flexdigit.params import RigParams
    from flexdigit.twin.digit_calibration import calibration_for, first_mode_rad_s

    def derived(params):
        first_mode_rad_s.cache_clear()
        return calibration_for(params)

    digit = RigParams.from_dict(FIVE_SECTIONS_EIGHT_GAUGES)
    return [
        {
            "name": "calibration_for, thesis rig (two modal analyses, 9 springs)",
            "value": best_of(lambda: derived(RigParams()), 5) * 1e3,
            "unit": "ms",
            "goal": "",
            "note": "twin_calibration gives the thesis rig its packaged one",
        },
        {
            "name": "calibration_for, 0.5 m 8-gauge digit (9 + 15 springs)",
            "value": best_of(lambda: derived(digit), 5) * 1e3,
            "unit": "ms",
            "goal": "",
            "note": "per twin of a digit without a calibration file (uncached)",
        },
    ]

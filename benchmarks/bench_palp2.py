"""Palpation on any digit (issue 24, trial 2): what the sweep's additions cost. The staircase's rail watch runs once
a 20 ms sample (every gauge against the ADC's rails, :class:`~flexdigit.palpation.palpation._Staircase`); the
plateau noise with the ADC's quantisation bias (a 1000-term Fourier series per gauge) once a fit and once its
Cramer-Rao bound. The thesis rig's 3 gauges beside an 8-gauge digit. Best of 3.

``python -m benchmarks palp2``
"""

from __future__ import annotations

import math

import numpy as np

from benchmarks._common import FIVE_SECTIONS_EIGHT_GAUGES, best_of

#: samples of the staircase timed per repeat: the built-in sweep's 25 plateaus of 2.5 s at 20 ms
SAMPLES = 3125


def _staircase_us(gauges: int) -> float:
    from flexdigit.palpation.palpation import _Staircase
    from flexdigit.rig.base import Reading

    commands = [8, *range(8, 31), 8]
    reading = Reading(time_s=0.0, gauges_v=np.full(gauges, 0.5), pot_v=math.nan, command=8)
    times = np.arange(SAMPLES) * 0.02

    def sweep():
        stairs = _Staircase(commands, 2.5, adc_range_v=(-5.0, 5.0))
        for t in times:
            stairs.step(t, reading)

    return 1e6 * best_of(sweep) / SAMPLES


def _sigma_ms(params) -> float:
    from flexdigit.palpation.contact_estimation import ContactGaugeModel
    from flexdigit.palpation.palpation import plateau_sigma_v

    model = ContactGaugeModel(params)
    return 1e3 * best_of(lambda: [plateau_sigma_v(model, 20) for _ in range(10)]) / 10


def run() -> list[dict]:
    from flexdigit.params import RigParams

    rows = []
    for gauges in (3, 8):
        rows.append(
            {
                "name": f"sweep staircase with the rail watch, {gauges} gauges",
                "value": _staircase_us(gauges),
                "unit": "us",
                "goal": "< 20 ms loop",
                "note": "_Staircase.step once a sample: the schedule and every gauge against the ADC's rails",
            }
        )
    for label, params in (("thesis rig", RigParams()), ("8 gauges", RigParams.from_dict(FIVE_SECTIONS_EIGHT_GAUGES))):
        rows.append(
            {
                "name": f"plateau noise with the quantisation bias, {label}",
                "value": _sigma_ms(params),
                "unit": "ms",
                "goal": "",
                "note": "plateau_sigma_v: once a fit and once its Cramer-Rao bound",
            }
        )
    return rows

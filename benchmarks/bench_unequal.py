"""Sections of unequal lengths beside equal ones (issue 24): the twin's real-time factor and its static load cases
per second for the thesis rig and for the digit of ``tests/digits.py`` with 60/100/80 mm sections and 10/12/10 mm
supports, timed in the same run, with the measures of :mod:`benchmarks.bench_digits`. The layout is computed once
per chain (``Geometry.section_bounds_m``), so the two should run alike: same section count, same cells.

``python -m benchmarks unequal``
"""

from __future__ import annotations

from benchmarks.bench_digits import speed_rows

#: The test digit "unequal-sections" of tests/digits.py, written out (benchmarks do not import the tests).
UNEQUAL_SECTIONS = {
    "geometry": {
        "section_count": 3,
        "section_length_m": [0.06, 0.10, 0.08],
        "support_lengths_m": [0.01, 0.012, 0.01],
        "strip_length_m": 0.24,
        "digit_length_m": 0.272,
        "gauge_positions_m": [0.035, 0.125, 0.227],
    },
}
DIGITS = {
    "thesis rig (3 x 80 mm)": ({}, "vertical"),
    "unequal sections (60/100/80 mm)": (UNEQUAL_SECTIONS, "vertical"),
}


def run() -> list[dict]:
    return speed_rows(DIGITS)

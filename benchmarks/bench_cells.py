"""The cost of the twin's default resolution (issue 24, ``flexdigit.twin.digit.default_cells``): the run twin's
real-time factor of long digits at the old 3 cells per section and at the default (cells no longer than
``MAX_CELL_LENGTH_M``), timed in the same run as :func:`benchmarks._common.realtime_factor` times them (2 ms
step, read every 20 ms frame, a slow ramp, 10 simulated s, best of 3; the long digits hang tip down).

- One 0.39 m section (the campaign's digit 2, ``tests/digit_campaign.py``, written out: benchmarks do not import
  the tests): 3 springs before, 15 now.
- 5 sections of 90 mm, 8 gauges, 0.5 m (``tests/digits.py``): 15 springs before, 25 now.
- The thesis rig: 9 springs either way (the same chain).

``python -m benchmarks bench_cells``
"""

from __future__ import annotations

from benchmarks._common import FIVE_SECTIONS_EIGHT_GAUGES, ONE_LONG_SECTION, realtime_factor

DIGITS = {
    "thesis rig": ({}, "vertical"),
    "one 0.39 m section": (ONE_LONG_SECTION, "hanging"),
    "5 sections, 8 gauges, 0.5 m": (FIVE_SECTIONS_EIGHT_GAUGES, "hanging"),
}


def run() -> list[dict]:
    rows = []
    for name, (description, orientation) in DIGITS.items():
        for label, cells in (("3 cells per section (before)", 3), ("default cells (now)", None)):
            factor, springs, elapsed = realtime_factor(description, orientation, cells)
            rows.append(
                {
                    "name": f"run twin real-time factor, {name}, {label}",
                    "value": factor,
                    "unit": "x",
                    "goal": ">= 1 (the loop)",
                    "note": f"{springs} springs, {orientation}; 10 s in {elapsed:.3f} s (best of 3)",
                }
            )
    return rows

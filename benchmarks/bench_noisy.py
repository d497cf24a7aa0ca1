"""A coarse map's 20 ms design (issue 24): what the quieter observers of the weights search cost.

Where no candidate of the search's grid qualifies (:data:`flexdigit.control.design20ms.QUIET_R_FACTORS`), the
search goes on over the quieter ones: ``random_digit(8)`` of ``tests/digits.py`` (one 0.38 m section, 3 quarter
bridges, a pair; 0.67 deg of noise a reading) is searched over 120 candidates instead of 48. Timed beside the
one-section test digit, whose grid qualifies (48), in the same run; best of 3.

``python -m benchmarks noisy``
"""

from __future__ import annotations

from benchmarks._common import ONE_SECTION, RANDOM_DIGIT_8, best_of


def run() -> list[dict]:
    from flexdigit.control.design20ms import digit_design_20ms
    from flexdigit.params import RigParams

    rows = []
    for name, data in (("random_digit(8), quieter observers", RANDOM_DIGIT_8), ("one-section, grid", ONE_SECTION)):
        params = RigParams.from_dict(data)
        design = digit_design_20ms(params)
        seconds = best_of(lambda params=params: digit_design_20ms(params))
        rows.append(
            {
                "name": f"20 ms design, {name}",
                "value": seconds,
                "unit": "s",
                "goal": "",
                "note": f"{design.choice.candidates} candidates searched",
            }
        )
    return rows

"""A described digit's 20 ms design (issue 24): the time ``flexdigit design 20ms --params`` and every
``flexdigit run --params`` spend designing, beside the thesis rig's chapter-5 design, timed in the same run.

The digit's design linearises its twin's chain, truncates its modes and searches the weights on that model
(:func:`flexdigit.control.design20ms.digit_weights`: 96 candidates, each designed and scored by three linear steps
and two Lyapunov solves); the thesis rig's is one design. Best of 3, the 0.5 m 8-gauge digit hung.

``python -m benchmarks digitctl2``
"""

from __future__ import annotations

from benchmarks._common import FIVE_SECTIONS_EIGHT_GAUGES, best_of


def run() -> list[dict]:
    from flexdigit.control.design20ms import digit_design_20ms
    from flexdigit.params import RigParams

    digit = RigParams.from_dict(FIVE_SECTIONS_EIGHT_GAUGES)
    thesis_s = best_of(lambda: digit_design_20ms(RigParams()))
    digit_s = best_of(lambda: digit_design_20ms(digit, orientation="hanging"))
    return [
        {"name": "20 ms design, thesis rig", "value": thesis_s, "unit": "s", "goal": "", "note": "chapter 5's"},
        {
            "name": "20 ms design, 0.5 m 8-gauge digit (model + weights search)",
            "value": digit_s,
            "unit": "s",
            "goal": "",
            "note": "what each run --params spends before the loop",
        },
    ]

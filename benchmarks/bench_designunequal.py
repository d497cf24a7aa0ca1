"""A kept 20 ms design (issue 24): what ``flexdigit run --params D.toml`` spends designing the digit's controller
with the weights searched (as every run did) and with a design kept by ``flexdigit design 20ms --out ctrl.json``
(``run --controller ctrl.json``: the file read and checked, the model linearised, one design), timed in the same
run on the 0.5 m 8-gauge digit hung. Best of 3.

``python -m benchmarks designunequal``
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from benchmarks._common import FIVE_SECTIONS_EIGHT_GAUGES, best_of


def run() -> list[dict]:
    from flexdigit.control.design20ms import digit_design_20ms
    from flexdigit.control.kept_design import keep_design, read_kept_design, write_kept_design
    from flexdigit.params import RigParams

    digit = RigParams.from_dict(FIVE_SECTIONS_EIGHT_GAUGES)
    searched_s = best_of(lambda: digit_design_20ms(digit, orientation="hanging"))
    with tempfile.TemporaryDirectory() as tmp:
        path = write_kept_design(keep_design(digit, orientation="hanging"), Path(tmp) / "ctrl.json")

        def kept():
            design = read_kept_design(path)
            design.check(digit, None, orientation="hanging", period_s=0.02)
            return digit_design_20ms(digit, orientation="hanging", weights=design.weights)

        kept_s = best_of(kept)
    return [
        {
            "name": "20 ms design, 0.5 m 8-gauge digit, weights searched",
            "value": searched_s,
            "unit": "s",
            "goal": "",
            "note": "what run --params spends before the loop without a kept design",
        },
        {
            "name": "20 ms design, 0.5 m 8-gauge digit, kept design file",
            "value": kept_s,
            "unit": "s",
            "goal": "",
            "note": f"file read and checked, model, one design: {searched_s / kept_s:.0f}x less",
        },
    ]

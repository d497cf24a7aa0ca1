"""The coarse-step check of a digit's 20 ms design (issue 24): what ``frame_pulse_deg`` adds to every design.

Every described digit's design computes the tip's peak after one frame of one command on its model
(:func:`flexdigit.control.design20ms.frame_pulse_deg`: 3 s on a 1 ms grid) and says when it reaches the 2 % band.
Timed on the one-section test digit's model (2 states of servo, one mode) and on the campaign's seed 3 (three modes
kept), beside the one-section digit's whole design; best of 3.

``python -m benchmarks stepfix``
"""

from __future__ import annotations

from benchmarks._common import CAMPAIGN_3, ONE_SECTION, best_of


def run() -> list[dict]:
    import warnings

    from flexdigit.control.design20ms import digit_design_20ms, frame_pulse_deg
    from flexdigit.control.digit_model import digit_model
    from flexdigit.errors import DesignWarning
    from flexdigit.params import RigParams

    rows = []
    for name, data in (("one-section", ONE_SECTION), ("campaign seed 3", CAMPAIGN_3)):
        params = RigParams.from_dict(data)
        model = digit_model(params)
        pulse = frame_pulse_deg(model.plant, params.actuator.serial_period_s)
        seconds = best_of(lambda model=model, params=params: frame_pulse_deg(model.plant, 0.02))
        rows.append(
            {
                "name": f"coarse-step check (frame_pulse_deg), {name}",
                "value": seconds,
                "unit": "s",
                "goal": "",
                "note": f"{model.plant.nstates} states; one frame of one command: {pulse:.2f} deg at the tip",
            }
        )
    params = RigParams.from_dict(ONE_SECTION)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DesignWarning)
        design = best_of(lambda: digit_design_20ms(params))
    rows.append(
        {"name": "20 ms design, one-section (check included)", "value": design, "unit": "s", "goal": "", "note": ""}
    )
    return rows


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:.4f} {row['unit']} {row['note']}")

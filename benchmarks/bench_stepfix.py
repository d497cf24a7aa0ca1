"""The coarse-step check of a digit's 20 ms design (issue 24): what ``frame_pulse_deg`` adds to every design.

Every described digit's design computes the tip's peak after one frame of one command on its model
(:func:`flexdigit.control.design20ms.frame_pulse_deg`: 3 s on a 1 ms grid) and says when it reaches the 2 % band.
Timed on the one-section test digit's model (2 states of servo, one mode) and on the campaign's seed 3 (three modes
kept), beside the one-section digit's whole design; best of 3.

``python -m benchmarks stepfix``
"""

from __future__ import annotations

from benchmarks.bench_digitctl2 import best_of
from benchmarks.bench_noisy import ONE_SECTION

#: tests/digit_campaign.py's campaign_digit(3) (3.1 deg a command; the benchmarks do not import the tests).
CAMPAIGN_3 = {
    "geometry": {
        "section_count": 3,
        "section_length_m": 0.1401,
        "strip_length_m": 0.4203,
        "digit_length_m": 0.444,
        "strip_thickness_m": 0.0005,
        "strip_width_m": 0.0199,
        "cable_eccentricity_m": 0.00305,
        "gauge_positions_m": [0.0555, 0.1598, 0.1676],
    },
    "material": {"youngs_modulus_pa": 110e9, "strip_density_kg_m3": 8860.0},
    "sensors": {
        "bridge": "half",
        "gauge_bridges": ["half", "half", "full"],
        "gauge_factors": [0.99, 1.28, 1.4],
        "amplifier_gains_v_per_v": [20000.0, 20000.0, 14674.0],
        "adc_bits": 16,
        "adc_range_v": [-2.5, 2.5],
        "adc_channels": [3, 4, 2],
    },
    "cables": {"count": 2, "pretension_n": 3.2, "guide_friction_ratio": 0.0805},
}


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

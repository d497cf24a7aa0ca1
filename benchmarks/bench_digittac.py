"""What reading a drawn digit steady and tared costs (issue 24): one collection of the campaign's protocol on the
drawn digit of ``tests/digit_campaign.py`` seed 0 (6 sections of 0.2 mm strip, 0.166 m, a cable pair: it still
rang 10 s after each load), with the thesis's fixed settle, read steady, and read steady and tared before each
position (a protocol TOML's default): wall time of ``tactile.collect`` on the twin and the run's virtual length.

``python -m benchmarks digittac``
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import replace
from pathlib import Path

#: tests/digit_campaign.py's seed 0, written out (benchmarks do not import the tests).
DIGIT = {
    "geometry": {
        "section_count": 6,
        "section_length_m": 0.023267,
        "strip_length_m": 0.139602,
        "digit_length_m": 0.166,
        "strip_thickness_m": 0.0002,
        "strip_width_m": 0.0069,
        "cable_eccentricity_m": 0.00323,
        "gauge_positions_m": [0.023, 0.0316, 0.0406, 0.0466],
    },
    "material": {"youngs_modulus_pa": 205e9, "strip_density_kg_m3": 7850.0},
    "sensors": {
        "bridge": "full",
        "gauge_bridges": ["full", "full", "full", "half"],
        "gauge_factors": [0.96, 1.7, 1.47, 1.98],
        "amplifier_gains_v_per_v": [20000.0, 12445.0, 18844.0, 20000.0],
        "adc_bits": 12,
        "adc_range_v": [-5.0, 5.0],
        "adc_channels": [7, 2, 4, 0],
    },
    "actuator": {"gear_ratio": 1.0},
    "cables": {"count": 2, "pretension_n": 6.6, "guide_friction_ratio": 0.0311},
}
#: The campaign's protocol for that digit: 19 places 0.5 mm apart from the tip, 40 readings, 10 no-load, 10 s.
PROTOCOL = (
    'name = "campaign"\nloads_g = [10.0]\npositions_from_tip_cm = '
    + str([round(0.05 * k, 2) for k in range(19)])
    + "\nrepetitions = 40\nno_load_repetitions = 10\nsettle_s = 10.0\n"
)


def run() -> list[dict]:
    from flexdigit.params import RigParams
    from flexdigit.tactile.protocols import protocol_from_toml
    from flexdigit.tactile.runner import collect

    params = RigParams.from_dict(DIGIT)
    default = protocol_from_toml(PROTOCOL)
    cases = {
        "fixed 10 s settle": replace(default, wait_until_steady=False, tare_each_position=False),
        "read steady": replace(default, tare_each_position=False),
        "read steady and tared (default)": default,
    }
    rows = []
    for label, protocol in cases.items():
        with tempfile.TemporaryDirectory() as directory:
            start = time.perf_counter()
            dataset = collect(protocol, out=Path(directory) / "d.parquet", params=params, seed=0)
            wall = time.perf_counter() - start
        virtual = float(dataset["time_s"].max())
        rows.append(
            {
                "name": f"collect, drawn digit (campaign seed 0), {label}",
                "value": wall,
                "unit": "s",
                "goal": "",
                "note": f"{len(dataset)} readings over {virtual:.0f} s of the twin's time",
            }
        )
    return rows

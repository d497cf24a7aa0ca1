"""The test digits of issue 24: planar digits other than (and including) the thesis rig, as parameter-file tables.

Each is a consistent description (``flexdigit params FILE`` accepts it): together they cover 1, 2, 3, 4 and 5
sections (one of unequal lengths); 1, 2, 3, 4, 6 and 8 gauges; quarter, half and full bridges; one cable and an
antagonistic pair; a geared servo; digits 0.15 to 0.5 m long. ``write_digit`` writes one as a TOML file, as a
user would.
"""

from __future__ import annotations

from pathlib import Path

import tomli_w

from flexdigit.params import Geometry, RigParams, Sensors


def _equal(count: int, length: float) -> list[float]:
    """Gauge ``k`` of ``count`` at ``(k + 1/2) L / count``, rounded to 0.1 mm (a file a user would write)."""
    return [round((k + 0.5) * length / count, 4) for k in range(count)]


DIGITS: dict[str, dict] = {
    "thesis": {},
    # one 150 mm section, one quarter-bridge gauge: 0.16 m
    "one-section": {
        "geometry": {
            "section_count": 1,
            "section_length_m": 0.15,
            "strip_length_m": 0.15,
            "digit_length_m": 0.16,
            "gauge_positions_m": [0.06],
        },
        "sensors": {"bridge": "quarter", "adc_channels": [0]},
    },
    # two 100 mm sections, two full-bridge gauges midway
    "two-sections": {
        "geometry": {
            "section_count": 2,
            "section_length_m": 0.10,
            "strip_length_m": 0.20,
            "digit_length_m": 0.22,
            "gauge_positions_m": [0.055, 0.165],
        },
        "sensors": {"bridge": "full", "adc_channels": [0, 1]},
    },
    # the 4 x 80 mm digit, described consistently, 4 gauges and the antagonistic pair
    "four-sections-two-cables": {
        "geometry": {
            "section_count": 4,
            "section_length_m": 0.08,
            "strip_length_m": 0.32,
            "digit_length_m": 0.36,
            "gauge_positions_m": [0.045, 0.135, 0.225, 0.315],
        },
        "sensors": {"adc_channels": [0, 1, 2, 3]},
        "cables": {"count": 2, "pretension_n": 5.0},
    },
    # five 90 mm sections, 0.5 m long, 8 full-bridge gauges two per section's strip
    "five-sections-eight-gauges": {
        "geometry": {
            "section_count": 5,
            "section_length_m": 0.09,
            "strip_length_m": 0.45,
            "digit_length_m": 0.50,
            "gauge_positions_m": [0.03, 0.07, 0.13, 0.17, 0.23, 0.27, 0.33, 0.37],
        },
        "sensors": {"bridge": "full", "adc_channels": list(range(8))},
    },
    # the thesis geometry with 6 equally spaced quarter-bridge gauges and a 4:1 reduction on the servo
    "six-gauges-geared": {
        "geometry": {"gauge_positions_m": _equal(6, 0.27)},
        "sensors": {"bridge": "quarter", "adc_channels": list(range(6))},
        "actuator": {"gear_ratio": 4.0},
    },
    # a short digit: three 45 mm sections, 0.15 m, two gauges
    "short": {
        "geometry": {
            "section_count": 3,
            "section_length_m": 0.045,
            "strip_length_m": 0.135,
            "digit_length_m": 0.15,
            "gauge_positions_m": [0.025, 0.125],
        },
        "sensors": {"adc_channels": [0, 1]},
    },
    # sections of unequal lengths (60, 100, 80 mm from the base) and supports (10, 12, 10 mm: half the first at
    # the clamp, the last one's centre at the tip), 0.272 m, a gauge midway on each section's strip
    "unequal-sections": {
        "geometry": {
            "section_count": 3,
            "section_length_m": [0.06, 0.10, 0.08],
            "support_lengths_m": [0.01, 0.012, 0.01],
            "strip_length_m": 0.24,
            "digit_length_m": 0.272,
            "gauge_positions_m": [0.035, 0.125, 0.227],
        },
    },
}


def newcomer_digit():
    """The newcomer's digit of issue 28's trial, as RigParams: 2 x 0.10 m sections of a 0.3 x 12 mm strip, 4
    half-bridge gauges, one cable."""
    geometry = Geometry(
        section_count=2,
        section_length_m=0.10,
        strip_length_m=0.20,
        digit_length_m=0.22,
        strip_thickness_m=0.0003,
        strip_width_m=0.012,
        gauge_positions_m=(0.03, 0.07, 0.13, 0.17),
    )
    return RigParams(geometry=geometry, sensors=Sensors(adc_channels=(0, 1, 2, 3)))


def write_digit(name: str, directory: Path, **changes: dict) -> Path:
    """Write digit ``name`` (with some sections' keys changed) as ``directory/name.toml``."""
    data = {section: dict(values) for section, values in DIGITS[name].items()}
    for section, values in changes.items():
        data.setdefault(section, {}).update(values)
    path = Path(directory) / f"{name}.toml"
    path.write_text(tomli_w.dumps(data))
    return path


def random_digit(seed: int) -> dict:
    """A consistent planar digit drawn with ``seed`` (1-8 sections, 1-8 gauges on the free strip, 0.15-0.5 m, any
    bridge, one or two cables, a gear ratio 1-4): a digit nobody wrote by hand, for the general case.

    Supports are 10 mm (half a support at the clamp and the tip, as :func:`flexdigit.params.digit_inconsistencies`
    lays them out); gauges sit at distinct 0.1 mm places at least 2 mm inside a section's free strip.
    """
    import numpy as np

    rng = np.random.default_rng([24, seed])
    sections = int(rng.integers(1, 9))
    length = round(float(rng.uniform(0.15, 0.5)), 3)
    support = 0.010
    pitch = length / sections
    section = round(pitch - support, 6)
    count = int(rng.integers(1, 9))
    places: set[float] = set()
    while len(places) < count:  # a section's free strip runs from k pitch + support / 2 to (k + 1) pitch - support / 2
        k = int(rng.integers(0, sections))
        x = k * pitch + support / 2 + 0.002 + float(rng.uniform(0, section - 0.004))
        places.add(round(x, 4))
    bridge = str(rng.choice(["quarter", "half", "full"]))
    data: dict = {
        "geometry": {
            "section_count": sections,
            "section_length_m": section,
            "strip_length_m": round(sections * section, 6),
            "digit_length_m": length,
            "gauge_positions_m": sorted(places),
        },
        "sensors": {"bridge": bridge, "adc_channels": list(range(count))},
    }
    if rng.random() < 0.5:
        data["cables"] = {"count": 2, "pretension_n": round(float(rng.uniform(1.0, 8.0)), 2)}
    if rng.random() < 0.5:
        data["actuator"] = {"gear_ratio": round(float(rng.uniform(1.0, 4.0)), 2)}
    return data

"""What the benchmarks share: :func:`best_of`, :func:`realtime_factor`, and the test digits they time, written out
once here (benchmarks do not import the tests: each says which tests/digits.py or tests/digit_campaign.py digit it
copies)."""

from __future__ import annotations

import time

__all__ = [
    "best_of",
    "realtime_factor",
    "ONE_SECTION",
    "FIVE_SECTIONS_EIGHT_GAUGES",
    "RANDOM_DIGIT_8",
    "RANDOM_DIGIT_10",
    "RANDOM_DIGIT_20",
    "CAMPAIGN_3",
    "ONE_LONG_SECTION",
]


def best_of(function, repeats: int = 3) -> float:
    """The shortest of ``repeats`` wall times of ``function()``, s."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def realtime_factor(description: dict, orientation: str, cells=None, sim_seconds: float = 10.0, repeats: int = 3):
    """Simulated seconds per wall-clock second of the run twin of a digit, ``(factor, springs, elapsed)``: the ``sim``
    backend's 2 ms step read every 20 ms serial frame, a command every 5th frame of a slow ramp over 30 commands from
    the straight one, ``sim_seconds`` on fresh twins, best of ``repeats``; ``cells`` per section (None: the
    description's own resolution)."""
    from flexdigit.params import RigParams
    from flexdigit.rig.backends.sim_backend import DEFAULT_TWIN_DT_S
    from flexdigit.twin.twin import Twin

    params = RigParams.from_dict(description)
    straight = params.actuator.equilibrium_command
    ramp = list(range(straight, straight + 31)) + list(range(straight + 29, straight, -1))

    def once() -> tuple[float, int]:
        twin = Twin(params, seed=0, orientation=orientation, dt_s=DEFAULT_TWIN_DT_S, cells_per_section=cells)
        frame = params.actuator.serial_period_s
        start = time.perf_counter()
        for k in range(int(round(sim_seconds / frame))):
            if k % 5 == 0:
                twin.command(ramp[(k // 5) % len(ramp)])
            twin.advance(frame)
            twin.read()
        return time.perf_counter() - start, twin.chain.n

    elapsed, springs = min(once() for _ in range(repeats))
    return sim_seconds / elapsed, springs, elapsed


#: tests/digits.py's one-section digit: one 0.15 m section, one quarter bridge.
ONE_SECTION = {
    "geometry": {
        "section_count": 1,
        "section_length_m": 0.15,
        "strip_length_m": 0.15,
        "digit_length_m": 0.16,
        "gauge_positions_m": [0.06],
    },
    "sensors": {"bridge": "quarter", "adc_channels": [0]},
}
#: Issue 24's long digit of tests/digits.py ("five-sections-eight-gauges"): 5 sections of 90 mm (0.5 m), 8 full
#: bridges.
FIVE_SECTIONS_EIGHT_GAUGES = {
    "geometry": {
        "section_count": 5,
        "section_length_m": 0.09,
        "strip_length_m": 0.45,
        "digit_length_m": 0.50,
        "gauge_positions_m": [0.03, 0.07, 0.13, 0.17, 0.23, 0.27, 0.33, 0.37],
    },
    "sensors": {"bridge": "full", "adc_channels": list(range(8))},
}
#: tests/digits.py's random_digit(8), as its TOML reads: one 0.384 m section, 3 quarter bridges, a pair.
RANDOM_DIGIT_8 = {
    "geometry": {
        "section_count": 1,
        "section_length_m": 0.384,
        "strip_length_m": 0.384,
        "digit_length_m": 0.394,
        "gauge_positions_m": [0.0421, 0.2229, 0.3831],
    },
    "sensors": {"bridge": "quarter", "adc_channels": [0, 1, 2]},
    "cables": {"count": 2, "pretension_n": 6.85},
}
#: tests/digits.py's random_digit(10): 4 quarter bridges, a cable pair, 1.1:1.
RANDOM_DIGIT_10 = {
    "geometry": {
        "section_count": 3,
        "section_length_m": 0.086,
        "strip_length_m": 0.258,
        "digit_length_m": 0.288,
        "gauge_positions_m": [0.0577, 0.082, 0.2507, 0.2749],
    },
    "sensors": {"bridge": "quarter", "adc_channels": [0, 1, 2, 3]},
    "cables": {"count": 2, "pretension_n": 4.24},
    "actuator": {"gear_ratio": 1.1},
}
#: tests/digits.py's random_digit(20): 6 sections, 4 quarter bridges on a pair (the curved map).
RANDOM_DIGIT_20 = {
    "geometry": {
        "section_count": 6,
        "section_length_m": 0.018833,
        "strip_length_m": 0.112998,
        "digit_length_m": 0.173,
        "gauge_positions_m": [0.0458, 0.1301, 0.1563, 0.1659],
    },
    "sensors": {"bridge": "quarter", "adc_channels": [0, 1, 2, 3]},
    "cables": {"count": 2, "pretension_n": 1.48},
}
#: tests/digit_campaign.py's campaign_digit(3): 3.1 deg a command (the coarse step).
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
#: tests/digit_campaign.py's campaign_digit(2), its mechanics (the sensor chain does not change the twin's
#: cost): one 0.39 m section.
ONE_LONG_SECTION = {
    "actuator": {"gear_ratio": 1.88},
    "cables": {"count": 1, "guide_friction_ratio": 0.0163, "pretension_n": 0.0},
    "geometry": {
        "cable_eccentricity_m": 0.00318,
        "digit_length_m": 0.404,
        "gauge_positions_m": [0.0374, 0.0388, 0.0837, 0.0982, 0.1916, 0.2682, 0.3749],
        "section_count": 1,
        "section_length_m": 0.3893,
        "strip_length_m": 0.3893,
        "strip_thickness_m": 0.00025,
        "strip_width_m": 0.0132,
    },
    "material": {"strip_density_kg_m3": 8860.0, "youngs_modulus_pa": 110e9},
    "sensors": {"adc_channels": list(range(7))},
}
